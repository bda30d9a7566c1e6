//! The sweep file and the points it expands to.
//!
//! ```toml
//! name = "eta-history"          # optional; default: the file's name without .toml
//! base = "arena"                # `arena`, `corridor` or a scenario file (relative to this file)
//! seeds = [1, 2, 3]             # master seeds (or a count: `seeds = 3` is [1, 2, 3])
//!
//! [set]                         # fixed changes to the base, for every point
//! steps = 2000
//! repeats = 5
//!
//! [grid]                        # one axis per key: every combination is a point
//! "learner.eta" = [0.001, 0.01]
//! learner.history = [0, 1, 2]   # dotted keys may also be written as TOML tables
//!
//! [[zip]]                       # one axis whose keys move together (equal-length lists)
//! steps = [1000, 2000]
//! window = [100, 200]
//!
//! [slurm]                       # all optional: see `SlurmSpec`
//! points_per_task = 2
//! max_parallel = 50
//!
//! [confirm]                     # optional: what `h8swarm sweep confirm` re-runs (see
//! seeds = [21, 22, 23]          # `Confirm`): cells of the map on seeds it never used
//! cells = "region"
//! ```
//!
//! Keys are the scenario's own (`robots`, `steps`, `learner.eta`, `world.substep_s`, …, as
//! `h8swarm run`'s summary.json lists them under `scenario`); `name`, `base` and `seed` are
//! the sweep's. Points are the Cartesian product of the axes (the first axis varies slowest)
//! with the seeds innermost, numbered from 0 in that order. A point's id is its number and its
//! values, reduced to the characters `[A-Za-z0-9.+-]`, so no value can reach outside the sweep
//! folder. Points are made one at a time ([`Sweep::point`]), never all held at once. Every
//! point's scenario is checked as `h8swarm run` checks a scenario file
//! ([`Sweep::check_points`], which `sweep plan` runs), before
//! anything is written.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::Path;

use serde::{Deserialize, Serialize};

use swarm::scenario::{Scenario, ScenarioFile};
use swarm::terminal_text::{one_line, toml_error};

use super::SweepError;

/// The most points a sweep may have (a Slurm array's size is bounded by the cluster's
/// `MaxArraySize`, 1 001 by default, but several points may share a task).
pub const MAX_POINTS: usize = 1_000_000;

/// Longest id, characters (the number, then the values shortened).
pub const MAX_ID_CHARS: usize = 96;

/// Slurm settings of a sweep (all optional).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SlurmSpec {
    /// Points run one after the other by one array task (default 1).
    pub points_per_task: Option<usize>,
    /// At most this many array tasks at once: the `%L` of `--array=0-K%L` (default 100).
    pub max_parallel: Option<usize>,
    /// CPUs per task (default: computed from the points, at most `max_cpus`).
    pub cpus_per_task: Option<usize>,
    /// Upper bound of the computed CPUs per task (default 8).
    pub max_cpus: Option<usize>,
    /// Memory per task in MB (default: computed from the points' robots and steps).
    pub mem_mb: Option<u64>,
    /// Time limit per task, as Slurm writes it (`MM`, `HH:MM:SS`, `D-HH`); default: computed.
    pub time: Option<String>,
    /// Partition (`--partition`).
    pub partition: Option<String>,
    /// Account (`--account`).
    pub account: Option<String>,
    /// Further `sbatch` options, one per entry (e.g. `"--qos=long"`): long options of
    /// letters, digits and `-_.,:=@/+`, each written as one `#SBATCH` line; not the options
    /// the plan writes itself (see [`super::plan::PLAN_OPTIONS`]).
    pub extra: Option<Vec<String>>,
    /// The cluster's `MaxArraySize` (default 1 001, Slurm's default: array indices 0 to
    /// 1 000); a plan needing more array tasks is refused.
    pub max_array_size: Option<usize>,
}

/// The sweep file as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    name: Option<String>,
    base: Option<String>,
    seeds: Option<toml::Value>,
    set: Option<toml::Table>,
    grid: Option<toml::Table>,
    zip: Option<Vec<toml::Table>>,
    slurm: Option<SlurmSpec>,
    confirm: Option<toml::Table>,
}

/// Master seeds kept for checks made from outside the project: a confirmation never runs on
/// them (a count skips them, a list naming one is refused). The project's own tests, maps and
/// confirmations never use them; an outside check brings its own sweep.
pub const RESERVED_SEEDS: std::ops::RangeInclusive<u64> = 11..=20;

/// The `[confirm]` section as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ConfirmFile {
    seeds: Option<toml::Value>,
    cells: Option<toml::Value>,
    repeats: Option<i64>,
}

/// Which cells of the map a confirmation re-runs.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CellChoice {
    /// The cells where the paper's text claims all hold on the map (pooled over its seeds).
    Region,
    /// Those and their neighbours (one step along one axis), so that the confirmation judges
    /// how robust the region is too.
    RegionAndNeighbours,
    /// The cells listed, by their position on each axis.
    Listed(Vec<Vec<usize>>),
}

/// What `h8swarm sweep confirm` re-runs: cells of the map on master seeds the map never used.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Confirm {
    /// The confirmation's master seeds (none of the map's; none of [`RESERVED_SEEDS`] unless
    /// allowed).
    pub seeds: Vec<u64>,
    /// The cells.
    pub cells: CellChoice,
    /// Repeats per point, when not the map's.
    pub repeats: Option<u32>,
}

/// One axis of the grid: one key (a `[grid]` entry) or several that move together (a `[[zip]]`
/// table).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// The dotted scenario keys.
    pub keys: Vec<String>,
    /// The axis' values: for each position, one value per key.
    pub values: Vec<Vec<toml::Value>>,
}

impl Axis {
    /// The axis' name: its keys joined by `+`.
    #[must_use]
    pub fn name(&self) -> String {
        self.keys.join("+")
    }

    /// The label of position `i`: its values (joined by `, ` for a zipped axis).
    #[must_use]
    pub fn label(&self, i: usize) -> String {
        self.values[i]
            .iter()
            .map(value_text)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// A parsed, checked sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// The sweep's name (safe for file names).
    pub name: String,
    /// The axes, in order (the first varies slowest).
    pub axes: Vec<Axis>,
    /// The master seeds (innermost).
    pub seeds: Vec<u64>,
    /// The Slurm settings.
    pub slurm: SlurmSpec,
    /// The confirmation stage, when the file has a `[confirm]` section.
    pub confirm: Option<Confirm>,
    /// How many points: the seeds times every axis' length.
    pub count: usize,
    /// The base scenario with the `[set]` changes, as a table: every point starts from it.
    table: toml::Table,
    /// Whether a point that sets `steps` gets its window cut to it (no `window` set or swept).
    clamp_window: bool,
    /// Where the sweep came from, for messages (`sweep file `PATH``).
    where_: String,
}

impl Sweep {
    /// Point `index` (0 to [`Sweep::count`] − 1): its position on each axis, its seed and its
    /// full scenario. Points are made one at a time, so a plan of a million points never holds
    /// them all.
    ///
    /// # Errors
    /// A key that cannot be set (a value where a table is needed).
    pub fn point(&self, index: usize) -> Result<Point, SweepError> {
        let where_ = &self.where_;
        let mut coords = vec![0usize; self.axes.len()];
        let mut rest = index / self.seeds.len();
        for (c, a) in coords.iter_mut().zip(&self.axes).rev() {
            *c = rest % a.values.len();
            rest /= a.values.len();
        }
        let seed = self.seeds[index % self.seeds.len()];
        let mut t = self.table.clone();
        for (a, &c) in self.axes.iter().zip(&coords) {
            for (k, v) in a.keys.iter().zip(&a.values[c]) {
                set_key(&mut t, k, v.clone())
                    .map_err(|e| SweepError::input(format!("{where_}: `{k}`: {e}")))?;
            }
        }
        if self.clamp_window {
            clamp_window(&mut t);
        }
        let id = point_id(index, self.count, &self.axes, &coords, seed);
        t.insert("name".into(), toml::Value::String(id.clone()));
        t.insert(
            "seed".into(),
            toml::Value::Integer(i64::try_from(seed).unwrap_or(i64::MAX)),
        );
        Ok(Point {
            index,
            id,
            coords,
            seed,
            scenario: t,
        })
    }

    /// Every point in order, one at a time.
    pub fn points(&self) -> impl Iterator<Item = Result<Point, SweepError>> + '_ {
        (0..self.count).map(|i| self.point(i))
    }

    /// Checks every point's scenario as `h8swarm run` checks a scenario file, calling `each`
    /// with each point and its scenario (in order, one at a time).
    ///
    /// # Errors
    /// The first point whose scenario is out of range (naming the point and the key), or
    /// `each`'s error.
    pub fn check_points(
        &self,
        mut each: impl FnMut(&Point, &Scenario) -> Result<(), SweepError>,
    ) -> Result<(), SweepError> {
        for p in self.points() {
            let p = p?;
            let s = p
                .resolve()
                .map_err(|e| SweepError::input(format!("{}: {e}", self.where_)))?;
            each(&p, &s)?;
        }
        Ok(())
    }
}

/// One point of a sweep: a full scenario.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// Its number, from 0.
    pub index: usize,
    /// Its id: the number and the values, safe as a folder name.
    pub id: String,
    /// Its position on each axis.
    pub coords: Vec<usize>,
    /// Its master seed.
    pub seed: u64,
    /// The full scenario, as a TOML table (what `scenario.toml` in its folder holds).
    pub scenario: toml::Table,
}

impl Point {
    /// The scenario as TOML text.
    ///
    /// # Errors
    /// A table TOML cannot write (not for one built by [`parse`]).
    pub fn scenario_toml(&self) -> Result<String, SweepError> {
        toml::to_string(&self.scenario)
            .map_err(|e| SweepError::tool(format!("writing point {}'s scenario: {e}", self.id)))
    }

    /// The checked scenario.
    ///
    /// # Errors
    /// A value out of range (naming the key).
    pub fn resolve(&self) -> Result<Scenario, SweepError> {
        Scenario::from_table(&self.scenario).map_err(|e| {
            SweepError::input(format!(
                "point {} ({}): {}",
                self.index,
                self.id,
                one_line(&format!("{e:#}"))
            ))
        })
    }
}

/// A point's id: `p` and its number (at least four digits, as many as the largest of
/// `count` points needs), then its values on the axes and its seed, reduced to
/// `[A-Za-z0-9.+-]` and at most [`MAX_ID_CHARS`] characters.
#[must_use]
pub fn point_id(index: usize, count: usize, axes: &[Axis], coords: &[usize], seed: u64) -> String {
    let digits = count.saturating_sub(1).to_string().len().max(4);
    let mut slug = String::new();
    for (a, &c) in axes.iter().zip(coords) {
        for (k, v) in a.keys.iter().zip(&a.values[c]) {
            let short = k.rsplit('.').next().unwrap_or(k);
            let _ = write!(slug, "-{short}{}", value_text(v));
        }
    }
    let _ = write!(slug, "-s{seed}");
    let prefix = format!("p{index:0digits$}");
    let id = format!(
        "{prefix}{}",
        sanitize(&slug, MAX_ID_CHARS.saturating_sub(prefix.len()))
    );
    // `sanitize` never starts with `.` or `_`, so put the dash back when it trimmed it.
    if id.len() > prefix.len() && !id[prefix.len()..].starts_with('-') {
        format!("{prefix}-{}", &id[prefix.len()..])
    } else {
        id
    }
}

/// The `[slurm]` section of a sweep file's text (the defaults when it has none or cannot be
/// read: `sweep plan` checked it).
#[must_use]
pub fn slurm_section(text: &str) -> SlurmSpec {
    toml::from_str::<SweepFile>(text)
        .ok()
        .and_then(|f| f.slurm)
        .unwrap_or_default()
}

/// Cuts a point's `window` to its `steps` (a point that shortens the run without naming a
/// window gets one window of the whole run, as a scenario file does).
fn clamp_window(t: &mut toml::Table) {
    if let (Some(toml::Value::Integer(steps)), Some(toml::Value::Integer(window))) =
        (t.get("steps"), t.get("window"))
        && window > steps
    {
        let steps = *steps;
        t.insert("window".into(), toml::Value::Integer(steps));
    }
}

/// A value as a label: strings bare, everything else as TOML writes it.
#[must_use]
pub fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        toml::Value::Array(a) => format!(
            "[{}]",
            a.iter().map(value_text).collect::<Vec<_>>().join(", ")
        ),
        other => other.to_string(),
    }
}

/// `text` reduced to `[A-Za-z0-9.+-]` (others become `_`; runs of `_` or of `.` become one),
/// at most `max` characters; never empty, never starting with `.` or `_`, never holding `..`.
#[must_use]
pub fn sanitize(text: &str, max: usize) -> String {
    let mut out = String::new();
    for c in text.chars() {
        let c = if c.is_ascii_alphanumeric() || matches!(c, '.' | '+' | '-') {
            c
        } else {
            '_'
        };
        // Runs of `_` become one, and of `.` one (so no `..` survives).
        if (c == '_' || c == '.') && out.ends_with(c) {
            continue;
        }
        if out.len() >= max {
            break;
        }
        out.push(c);
    }
    let out = out.trim_start_matches(['.', '_']).to_string();
    if out.is_empty() { "x".to_string() } else { out }
}

/// Flattens nested tables into dotted keys, keeping the leaves (non-table values).
fn flatten(prefix: &str, t: &toml::Table, out: &mut Vec<(String, toml::Value)>) {
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(inner) => flatten(&key, inner, out),
            other => out.push((key, other.clone())),
        }
    }
}

/// Sets `key` (dotted) in `table`, creating tables on the way.
fn set_key(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let mut parts: Vec<&str> = key.split('.').collect();
    let last = parts.pop().unwrap_or_default();
    let mut t = table;
    for p in parts {
        let entry = t
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = match entry {
            toml::Value::Table(inner) => inner,
            _ => return Err(format!("`{p}` is a value, not a table")),
        };
    }
    t.insert(last.to_string(), value);
    Ok(())
}

fn get_key<'a>(table: &'a toml::Table, key: &str) -> Option<&'a toml::Value> {
    let mut parts = key.split('.').peekable();
    let mut t = table;
    while let Some(p) = parts.next() {
        let v = t.get(p)?;
        if parts.peek().is_none() {
            return Some(v);
        }
        t = v.as_table()?;
    }
    None
}

/// The keys a point may set, checked against the scenario: the base's own leaves, or an
/// optional key the scenario file format accepts (e.g. `controller.image`).
struct Keys {
    base: toml::Table,
    leaves: Vec<String>,
}

impl Keys {
    fn new(base: &Scenario) -> Result<Self, SweepError> {
        let table = toml::Table::try_from(base)
            .map_err(|e| SweepError::tool(format!("the base scenario as TOML: {e}")))?;
        let mut leaves = Vec::new();
        flatten("", &table, &mut leaves);
        let mut leaves: Vec<String> = leaves.into_iter().map(|(k, _)| k).collect();
        leaves.retain(|k| k != "name" && k != "seed");
        Ok(Self {
            base: table,
            leaves,
        })
    }

    /// Checks `key` (from `where_`); a sweep's own key or an unknown one is an error.
    fn check(&self, key: &str, where_: &str) -> Result<(), SweepError> {
        let valid = || {
            format!(
                "valid keys are {} (and the optional controller.image, controller.symbols, controller.robots, world.solver)",
                self.leaves.join(", ")
            )
        };
        if key == "seed" {
            return Err(SweepError::input(format!(
                "{where_}: `seed` is the sweep's own axis: give the master seeds as `seeds = [..]` at the top of the sweep file"
            )));
        }
        let head = key.split('.').next().unwrap_or(key);
        if ["name", "base", "seeds", "slurm", "set", "grid", "zip"].contains(&head) {
            return Err(SweepError::input(format!(
                "{where_}: `{key}` is a key of the sweep file itself: give it before the first [table] (TOML puts every key after a [table] header into that table), not in a grid or set"
            )));
        }
        if key.is_empty() || key.split('.').any(str::is_empty) {
            return Err(SweepError::input(format!(
                "{where_}: `{key}` is not a key: {}",
                valid()
            )));
        }
        if self.leaves.iter().any(|k| k == key) {
            return Ok(());
        }
        // Not in the base's table: an optional key (absent when unset) is still valid if the
        // scenario file format accepts it.
        let mut probe = toml::Table::new();
        let known = set_key(&mut probe, key, toml::Value::Boolean(false)).is_ok()
            && match toml::to_string(&probe) {
                Ok(text) => match toml::from_str::<ScenarioFile>(&text) {
                    Ok(_) => true,
                    Err(e) => !e.to_string().contains("unknown field"),
                },
                Err(_) => false,
            };
        if known {
            Ok(())
        } else {
            Err(SweepError::input(format!(
                "{where_}: unknown key `{key}`: {}",
                valid()
            )))
        }
    }

    /// `v` for `key`, with an integer given for a real-valued key taken as that real (`eta =
    /// 0` for `eta = 0.0`).
    fn coerce(&self, key: &str, v: toml::Value) -> toml::Value {
        match (get_key(&self.base, key), v) {
            (Some(toml::Value::Float(_)), toml::Value::Integer(i)) => toml::Value::Float(i as f64),
            (_, v) => v,
        }
    }
}

fn list<'a>(v: &'a toml::Value, where_: &str) -> Result<&'a Vec<toml::Value>, SweepError> {
    match v {
        toml::Value::Array(a) if !a.is_empty() => Ok(a),
        toml::Value::Array(_) => Err(SweepError::input(format!(
            "{where_} is an empty list: give at least one value, like [0.001, 0.01]"
        ))),
        other => Err(SweepError::input(format!(
            "{where_} = {other} is not a list: give the values to sweep as a list, like [0.001, 0.01]"
        ))),
    }
}

/// Parses and checks a sweep file's text; `file` names it in messages and anchors a relative
/// `base` path.
///
/// The points themselves are checked by [`Sweep::check_points`].
///
/// # Errors
/// Bad TOML, an unknown or misplaced key, an empty or unequal list, a bad seed, too many
/// points: each naming the file, the key, and what is valid.
pub fn parse(text: &str, file: &Path) -> Result<Sweep, SweepError> {
    let where_ = format!("sweep file `{}`", file.display());
    let f: SweepFile = toml::from_str(text)
        .map_err(|e| SweepError::input(format!("{where_}, {}", toml_error(text, &e))))?;
    let base = load_base(f.base.as_deref(), file, &where_)?;
    let keys = Keys::new(&base)?;

    let name = f.name.clone().unwrap_or_else(|| {
        file.file_stem()
            .map_or_else(|| "sweep".to_string(), |s| s.to_string_lossy().into_owned())
    });
    let name = sanitize(&name, 48);

    let mut table = keys.base.clone();
    let window_given = apply_set(&keys, &mut table, f.set.as_ref(), &where_)?;

    let mut axes = grid_axes(&keys, f.grid.as_ref(), &where_)?;
    for (z, t) in f.zip.iter().flatten().enumerate() {
        axes.push(zip_axis(
            &keys,
            t,
            &format!("{where_}, [[zip]] number {}", z + 1),
        )?);
    }
    let swept = swept_once(&axes, &where_)?;
    let seeds = seeds(f.seeds.as_ref(), base.seed, &where_)?;
    let confirm = confirm_of(f.confirm.as_ref(), &axes, &seeds, &where_)?;

    let mut count: usize = seeds.len();
    for a in &axes {
        count = count.saturating_mul(a.values.len());
    }
    if count > MAX_POINTS {
        return Err(SweepError::input(format!(
            "{where_}: the grid has {count} points: at most {MAX_POINTS} are allowed"
        )));
    }

    Ok(Sweep {
        name,
        axes,
        seeds,
        slurm: f.slurm.unwrap_or_default(),
        confirm,
        count,
        clamp_window: !window_given && !swept.contains("window"),
        table,
        where_,
    })
}

/// The sweep's base scenario: `arena` (the default), `corridor`, or a scenario file (a
/// relative path is taken from the sweep file's folder).
fn load_base(base: Option<&str>, file: &Path, where_: &str) -> Result<Scenario, SweepError> {
    let base_name = base.unwrap_or("arena");
    if base_name == "arena" || base_name == "corridor" {
        Scenario::builtin(base_name)
    } else {
        let p = Path::new(base_name);
        let p = if p.is_relative() {
            file.parent().unwrap_or(Path::new("")).join(p)
        } else {
            p.to_path_buf()
        };
        Scenario::load(&p.display().to_string())
    }
    .map_err(|e| SweepError::input(format!("{where_}: key `base` = \"{base_name}\": {e:#}")))
}

/// Applies the fixed changes of `[set]` to `table`; returns whether they set `window` (as in a
/// scenario file, `steps` set without `window` cuts the base's window to the run).
fn apply_set(
    keys: &Keys,
    table: &mut toml::Table,
    set: Option<&toml::Table>,
    where_: &str,
) -> Result<bool, SweepError> {
    let mut entries = Vec::new();
    if let Some(t) = set {
        flatten("", t, &mut entries);
    }
    let window_given = entries.iter().any(|(k, _)| k == "window");
    for (k, v) in entries {
        keys.check(&k, &format!("{where_}, [set]"))?;
        let v = keys.coerce(&k, v);
        set_key(table, &k, v)
            .map_err(|e| SweepError::input(format!("{where_}, [set] `{k}`: {e}")))?;
    }
    Ok(window_given)
}

/// The axes of `[grid]`: one per key, in the file's order.
fn grid_axes(
    keys: &Keys,
    grid: Option<&toml::Table>,
    where_: &str,
) -> Result<Vec<Axis>, SweepError> {
    let mut entries = Vec::new();
    if let Some(t) = grid {
        flatten("", t, &mut entries);
    }
    let mut axes = Vec::new();
    for (k, v) in &entries {
        let at = format!("{where_}, [grid] `{k}`");
        keys.check(k, &at)?;
        let values = list(v, &at)?;
        axes.push(Axis {
            keys: vec![k.clone()],
            values: values
                .iter()
                .map(|v| vec![keys.coerce(k, v.clone())])
                .collect(),
        });
    }
    Ok(axes)
}

/// The axis of one `[[zip]]` table (named `at` in messages): its keys move together, so their
/// lists must be of equal length.
fn zip_axis(keys: &Keys, t: &toml::Table, at: &str) -> Result<Axis, SweepError> {
    let mut entries = Vec::new();
    flatten("", t, &mut entries);
    if entries.is_empty() {
        return Err(SweepError::input(format!(
            "{at} is empty: give two or more keys with lists of equal length"
        )));
    }
    let mut lists = Vec::new();
    for (k, v) in &entries {
        let at_k = format!("{at}, `{k}`");
        keys.check(k, &at_k)?;
        lists.push(list(v, &at_k)?);
    }
    let n = lists[0].len();
    if let Some((i, l)) = lists.iter().enumerate().find(|(_, l)| l.len() != n) {
        return Err(SweepError::input(format!(
            "{at}: `{}` has {} values but `{}` has {n}: zipped lists must be of equal length",
            entries[i].0,
            l.len(),
            entries[0].0
        )));
    }
    Ok(Axis {
        keys: entries.iter().map(|(k, _)| k.clone()).collect(),
        values: (0..n)
            .map(|i| {
                entries
                    .iter()
                    .zip(&lists)
                    .map(|((k, _), l)| keys.coerce(k, l[i].clone()))
                    .collect()
            })
            .collect(),
    })
}

/// The keys the axes sweep, each swept once.
///
/// # Errors
/// A key in two axes.
fn swept_once(axes: &[Axis], where_: &str) -> Result<BTreeSet<String>, SweepError> {
    let mut seen = BTreeSet::new();
    for a in axes {
        for k in &a.keys {
            if !seen.insert(k.clone()) {
                return Err(SweepError::input(format!(
                    "{where_}: key `{k}` is swept twice (in [grid] and [[zip]], or in two [[zip]] tables): give it once"
                )));
            }
        }
    }
    Ok(seen)
}

/// The `[confirm]` section of a sweep file's text (`file` names it in messages), checked
/// against the map's axes and seeds; none without one. `sweep confirm` reads it from the copy
/// `sweep plan` keeps.
///
/// # Errors
/// Malformed TOML, or a bad `[confirm]` section (see [`parse`]'s errors).
pub fn confirm_section(
    text: &str,
    file: &Path,
    axes: &[Axis],
    map_seeds: &[u64],
) -> Result<Option<Confirm>, SweepError> {
    let where_ = format!("sweep file `{}`", file.display());
    let f: SweepFile = toml::from_str(text)
        .map_err(|e| SweepError::input(format!("{where_}, {}", toml_error(text, &e))))?;
    confirm_of(f.confirm.as_ref(), axes, map_seeds, &where_)
}

/// The confirmation of a `[confirm]` table: its seeds (a list, or a count: the first that the
/// map did not use, skipping [`RESERVED_SEEDS`]), its cells (`"region"`,
/// `"region+neighbours"`, or a list of tables giving every swept key a value of its axis) and
/// its repeats.
fn confirm_of(
    t: Option<&toml::Table>,
    axes: &[Axis],
    map_seeds: &[u64],
    where_: &str,
) -> Result<Option<Confirm>, SweepError> {
    let Some(t) = t else {
        return Ok(None);
    };
    let at = format!("{where_}, [confirm]");
    let f: ConfirmFile =
        toml::Value::Table(t.clone())
            .try_into()
            .map_err(|e: toml::de::Error| {
                SweepError::input(format!("{at}: {}", one_line(e.message())))
            })?;
    let seeds = match &f.seeds {
        None => {
            return Err(SweepError::input(format!(
                "{at}: no `seeds`: give the confirmation's master seeds, seeds the map did not use (e.g. seeds = [21, 22, 23, 24, 25]), or a count"
            )));
        }
        Some(toml::Value::Integer(n)) if (1..=1000).contains(n) => (1u64..)
            .filter(|s| !map_seeds.contains(s) && !RESERVED_SEEDS.contains(s))
            .take(*n as usize)
            .collect(),
        Some(toml::Value::Array(_)) => {
            let list = seeds(f.seeds.as_ref(), 0, &at)?;
            if let Some(s) = list.iter().find(|s| map_seeds.contains(s)) {
                return Err(SweepError::input(format!(
                    "{at}: seed {s} is one of the map's seeds: a confirmation runs on seeds the map never used"
                )));
            }
            if let Some(s) = list.iter().find(|&&s| RESERVED_SEEDS.contains(&s)) {
                return Err(SweepError::input(format!(
                    "{at}: seed {s}: master seeds {}-{} are reserved for checks from outside the project; choose others (e.g. 21 on)",
                    RESERVED_SEEDS.start(),
                    RESERVED_SEEDS.end()
                )));
            }
            list
        }
        Some(other) => {
            return Err(SweepError::input(format!(
                "{at}: `seeds` = {other}: give a list of master seeds the map did not use, like [21, 22, 23], or a count from 1 to 1000"
            )));
        }
    };
    let cells = match &f.cells {
        None => CellChoice::Region,
        Some(toml::Value::String(s)) if s == "region" => CellChoice::Region,
        Some(toml::Value::String(s)) if s == "region+neighbours" => CellChoice::RegionAndNeighbours,
        Some(toml::Value::Array(list)) if !list.is_empty() => {
            let mut out = Vec::new();
            for (i, c) in list.iter().enumerate() {
                out.push(listed_cell(c, axes, &format!("{at}, cell {}", i + 1))?);
            }
            CellChoice::Listed(out)
        }
        Some(other) => {
            return Err(SweepError::input(format!(
                "{at}: `cells` = {other}: give \"region\", \"region+neighbours\" or a list of cells like [{{ \"learner.eta\" = 0.03, \"learner.threshold\" = 10 }}]"
            )));
        }
    };
    let repeats = match f.repeats {
        None => None,
        Some(r) if (1..=100_000).contains(&r) => Some(r as u32),
        Some(r) => {
            return Err(SweepError::input(format!(
                "{at}: `repeats` = {r} is out of range: valid is 1 to 100000"
            )));
        }
    };
    Ok(Some(Confirm {
        seeds,
        cells,
        repeats,
    }))
}

/// Whether two values of a key are the same (a whole number equals the same real).
fn same_value(a: &toml::Value, b: &toml::Value) -> bool {
    match (a, b) {
        (toml::Value::Integer(x), toml::Value::Float(y))
        | (toml::Value::Float(y), toml::Value::Integer(x)) => (*x as f64) == *y,
        _ => a == b,
    }
}

/// The position on each axis of a listed cell: a table that gives every swept key one of its
/// axis' values.
fn listed_cell(c: &toml::Value, axes: &[Axis], at: &str) -> Result<Vec<usize>, SweepError> {
    let toml::Value::Table(t) = c else {
        return Err(SweepError::input(format!(
            "{at} is {c}: give a table of the swept keys' values"
        )));
    };
    let mut given = Vec::new();
    flatten("", t, &mut given);
    let swept: Vec<&String> = axes.iter().flat_map(|a| &a.keys).collect();
    if let Some((k, _)) = given.iter().find(|(k, _)| !swept.contains(&k)) {
        return Err(SweepError::input(format!(
            "{at}: `{k}` is not a swept key: the cell's keys are {}",
            swept
                .iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let mut coords = Vec::new();
    for a in axes {
        let vals: Vec<&toml::Value> = a
            .keys
            .iter()
            .map(|k| {
                given
                    .iter()
                    .find(|(g, _)| g == k)
                    .map(|(_, v)| v)
                    .ok_or_else(|| {
                        SweepError::input(format!("{at}: no value for the swept key `{k}`"))
                    })
            })
            .collect::<Result<_, _>>()?;
        let pos = a
            .values
            .iter()
            .position(|vs| vs.iter().zip(&vals).all(|(v, g)| same_value(v, g)))
            .ok_or_else(|| {
                SweepError::input(format!(
                    "{at}: {} = {} is not a value of the map's axis (valid: {})",
                    a.name(),
                    vals.iter()
                        .map(|v| value_text(v))
                        .collect::<Vec<_>>()
                        .join(", "),
                    (0..a.values.len())
                        .map(|i| a.label(i))
                        .collect::<Vec<_>>()
                        .join("; ")
                ))
            })?;
        coords.push(pos);
    }
    Ok(coords)
}

/// The master seeds: the base's when `seeds` is absent, 1 to n for a count n, else the listed
/// ones (whole numbers, each once).
fn seeds(
    seeds: Option<&toml::Value>,
    base_seed: u64,
    where_: &str,
) -> Result<Vec<u64>, SweepError> {
    match seeds {
        None => Ok(vec![base_seed]),
        Some(toml::Value::Integer(n)) if (1..=100_000).contains(n) => Ok((1..=*n as u64).collect()),
        Some(list @ toml::Value::Array(a)) if !a.is_empty() => {
            let mut out = Vec::new();
            for v in a {
                match v {
                    toml::Value::Integer(s) if *s >= 0 => out.push(*s as u64),
                    other => {
                        return Err(SweepError::input(format!(
                            "{where_}: `seeds` holds {other}: every seed must be a whole number >= 0"
                        )));
                    }
                }
            }
            let distinct: BTreeSet<u64> = out.iter().copied().collect();
            if distinct.len() != out.len() {
                return Err(SweepError::input(format!(
                    "{where_}: `seeds` = {list}: a seed is listed twice"
                )));
            }
            Ok(out)
        }
        Some(other) => Err(SweepError::input(format!(
            "{where_}: `seeds` = {other}: give a list of master seeds like [1, 2, 3], or a count from 1 to 100000"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parses and checks every point, as `sweep plan` does.
    fn sweep(text: &str) -> Result<Sweep, String> {
        let s = parse(text, Path::new("t.toml")).map_err(|e| e.to_string())?;
        s.check_points(|_, _| Ok(())).map_err(|e| e.to_string())?;
        Ok(s)
    }

    fn points(s: &Sweep) -> Vec<Point> {
        s.points().collect::<Result<_, _>>().unwrap()
    }

    #[test]
    fn a_grid_expands_with_seeds_innermost() {
        let s = sweep(
            "seeds = [4, 5]\n[set]\nsteps = 50\n[grid]\n\"learner.eta\" = [0, 0.01]\nlearner.history = [0, 1, 2]\n",
        )
        .unwrap();
        assert_eq!(s.count, 12);
        assert_eq!(s.name, "t");
        let all = points(&s);
        let p = &all[7];
        let sc = p.resolve().unwrap();
        assert_eq!(sc.steps, 50);
        assert_eq!(p.seed, 5);
        assert_eq!(sc.seed, 5);
        // Both axes' values reach the scenario (0 taken as 0.0 for the real-valued eta).
        let (eta_axis, hist_axis) = if s.axes[0].keys[0] == "learner.eta" {
            (0, 1)
        } else {
            (1, 0)
        };
        let eta = [0.0, 0.01][p.coords[eta_axis]];
        assert_eq!(sc.learner.eta, eta);
        assert_eq!(sc.learner.history, p.coords[hist_axis]);
        assert!(p.id.starts_with("p0007-"), "{}", p.id);
        assert!(p.id.ends_with("-s5"), "{}", p.id);
        let ids: BTreeSet<&str> = all.iter().map(|p| p.id.as_str()).collect();
        assert_eq!(ids.len(), 12);
    }

    #[test]
    fn zipped_keys_move_together() {
        let s = sweep("[[zip]]\nsteps = [40, 80]\nwindow = [10, 20]\n[grid]\nrobots = [3, 4]\n")
            .unwrap();
        assert_eq!(s.count, 4);
        for p in &points(&s) {
            let sc = p.resolve().unwrap();
            assert_eq!(sc.window * 4, sc.steps);
        }
        assert_eq!(s.seeds, vec![1]);
    }

    #[test]
    fn bad_files_say_what_and_where() {
        let e = sweep("[grid]\n\"learner.etaa\" = [1]\n").unwrap_err();
        assert!(
            e.contains("unknown key `learner.etaa`") && e.contains("learner.eta"),
            "{e}"
        );
        let e = sweep("[grid]\nrobots = []\n").unwrap_err();
        assert!(e.contains("empty list") && e.contains("robots"), "{e}");
        let e = sweep("[grid]\nrobots = 3\n").unwrap_err();
        assert!(e.contains("not a list"), "{e}");
        let e = sweep("[[zip]]\nsteps = [40, 80]\nwindow = [10]\n").unwrap_err();
        assert!(e.contains("equal length"), "{e}");
        let e = sweep("[grid]\nseed = [1, 2]\n").unwrap_err();
        assert!(e.contains("seeds = "), "{e}");
        let e = sweep("seeds = [1, 1]\n").unwrap_err();
        assert!(e.contains("twice"), "{e}");
        let e = sweep("seeds = \"x\"\n").unwrap_err();
        assert!(e.contains("seeds"), "{e}");
        let e = sweep("grids = 1\n").unwrap_err();
        assert!(e.contains("grids") && e.contains("t.toml"), "{e}");
        // A key the base's table leaves out while it has its default is named among the
        // valid ones.
        let e = sweep("[grid]\n\"world.solverr\" = [\"capped\"]\n").unwrap_err();
        assert!(
            e.contains("unknown key") && e.contains("world.solver)"),
            "{e}"
        );
        let e = sweep("[grid]\n\"learner.eta\" = [0.5, 2.0]\n").unwrap_err();
        assert!(e.contains("learner.eta") && e.contains("point 1"), "{e}");
        // A value the scenario cannot read names the point, the key and the value, not a line
        // of the point's generated scenario.
        let e = sweep("[grid]\n\"world.solver\" = [\"capped\", \"fast\"]\n").unwrap_err();
        assert!(
            e.contains("point 1")
                && e.contains("unknown variant `fast`")
                && e.contains("in `world.solver`"),
            "{e}"
        );
        assert!(!e.contains("line ") && !e.contains("column"), "{e}");
        let e = sweep("base = \"moon\"\n").unwrap_err();
        assert!(e.contains("base") && e.contains("moon"), "{e}");
        let e = sweep("[grid]\nrobots = [3]\n[[zip]]\nrobots = [4]\n").unwrap_err();
        assert!(e.contains("twice"), "{e}");
    }

    #[test]
    fn ids_cannot_leave_the_folder() {
        let s =
            sweep("[grid]\n\"controller.symbols\" = [\"../../etc/passwd\", \"/x y\"]\n").unwrap();
        for p in &points(&s) {
            assert!(
                !p.id.contains('/') && !p.id.contains(' ') && !p.id.contains(".."),
                "{}",
                p.id
            );
        }
        for bad in ["../../etc/passwd", "/abs", "..", "a/b\\c", "\n", ""] {
            let id = sanitize(bad, 40);
            assert!(!id.contains('/') && !id.contains('\\') && !id.starts_with('.'));
            assert!(!id.is_empty() && id != "..");
        }
        assert_eq!(sanitize("eta0.001", 40), "eta0.001");
        assert_eq!(sanitize("a b//c", 40), "a_b_c");
    }

    #[test]
    fn a_confirmation_runs_on_seeds_the_map_never_used_and_never_on_the_reserved_ones() {
        let base = "seeds = [1, 2]\n[set]\nsteps = 50\n[grid]\n\"learner.eta\" = [0.01, 0.03]\n";
        let with = |confirm: &str| sweep(&format!("{base}[confirm]\n{confirm}\n"));
        let c = with("seeds = [21, 22]\ncells = \"region+neighbours\"")
            .unwrap()
            .confirm
            .unwrap();
        assert_eq!(c.seeds, vec![21, 22]);
        assert_eq!(c.cells, CellChoice::RegionAndNeighbours);
        // A count takes the first seeds the map did not use, skipping 11-20.
        let c = with("seeds = 3").unwrap().confirm.unwrap();
        assert_eq!(c.seeds, vec![3, 4, 5]);
        assert_eq!(c.cells, CellChoice::Region);
        let axes = vec![Axis {
            keys: vec!["learner.eta".into()],
            values: vec![vec![toml::Value::Float(0.01)]],
        }];
        let ten: Vec<u64> = (1..=10).collect();
        let c = confirm_section("[confirm]\nseeds = 3\n", Path::new("t.toml"), &axes, &ten)
            .unwrap()
            .unwrap();
        assert_eq!(c.seeds, vec![21, 22, 23]);
        // A list naming a reserved seed is refused (nothing runs: the plan is refused), and no
        // key lets a confirmation take one.
        let e = with("seeds = [21, 15]").unwrap_err();
        assert!(
            e.contains("seed 15") && e.contains("11-20") && e.contains("reserved"),
            "{e}"
        );
        let e = with("seeds = [21]\nallow_reserved_seeds = true").unwrap_err();
        assert!(e.contains("allow_reserved_seeds"), "{e}");
        // The map's own seeds are refused.
        let e = with("seeds = [2, 21]").unwrap_err();
        assert!(e.contains("seed 2") && e.contains("never used"), "{e}");
        // Listed cells name a value of every axis.
        let c = with("seeds = [21]\ncells = [{ \"learner.eta\" = 0.03 }]")
            .unwrap()
            .confirm
            .unwrap();
        assert_eq!(c.cells, CellChoice::Listed(vec![vec![1]]));
        let e = with("seeds = [21]\ncells = [{ \"learner.eta\" = 0.5 }]").unwrap_err();
        assert!(e.contains("not a value") && e.contains("0.01; 0.03"), "{e}");
        let e = with("seeds = [21]\ncells = [{ \"learner.threshold\" = 10 }]").unwrap_err();
        assert!(e.contains("not a swept key"), "{e}");
        let e = with("seeds = [21]\ncells = \"everywhere\"").unwrap_err();
        assert!(e.contains("region"), "{e}");
        let e = with("cells = \"region\"").unwrap_err();
        assert!(e.contains("no `seeds`"), "{e}");
        let e = with("seeds = [21]\nrepeat = 3").unwrap_err();
        assert!(e.contains("repeat"), "{e}");
    }
}
