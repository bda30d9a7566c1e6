//! A sweep's table: every point's claims and first/last-window statistics, collected from the
//! points' folders and staged with its figures (`merge_into`); `h8swarm sweep merge`
//! ([`super::merge`]) commits a map's and its confirmation's together.
//!
//! Written to `DIR/merged/` (or `--out`):
//! * `sweep.csv`: one row per planned point, in order, finished or not. Columns: `index`,
//!   `id`, `status` (`ok`, `failed`, `missing`: never run or still running, `broken`: a folder
//!   that is neither finished nor failed), one column per swept key, `seed`; then for every
//!   condition and window of the points' summary.json the mean and 95 % interval of each
//!   statistic (`learning.last.collisions_per_m.mean`, `….lo`, `….hi`) and of each condition's
//!   robots (`learning.robots.ending_held_percent.mean`, `learning.robots.ending_held`, …);
//!   then for every claim (column names from its text, `claim.<words>.…`): `outcome` (`holds`,
//!   `unsure`, `fails`, `undecided`), `means_agree`, `apart` (intervals apart), `a` and `b`
//!   (the two means compared, in the order the claim's words name them), `effect` (their
//!   difference, positive when the means agree with the claim), and the repeat-by-repeat counts `for`, `against`, `tied`,
//!   `undefined` with the sign test's `p`; last `error`. A point that did not finish has empty
//!   cells.
//! * `sweep.json`: the same rows (objects keyed by column), the column order, the claims' full
//!   texts (with whether each is one of the paper's), the lists of failed, missing and broken
//!   points, and the figures it drew (`figures`: the next merge into the same folder replaces
//!   exactly those).
//! * `plots/`: a map of every claim over the swept keys, and the region where the paper's
//!   text claims hold together (see [`super::figures`]). Merge never clears a folder: a user's
//!   own files in `OUT` or `OUT/plots` stay.
//!
//! The table is a pure function of the points' folders: the same bytes however the points were
//! split into tasks or where they ran.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::Path;

use serde_json::{Map, Value, json};

use super::SweepError;
use super::figures::{ClaimSeries, PointClaim, cell_values, claim_figures, region};
use super::plan::read_plan;
use super::points::{PointState, host_name, is_dead_leftover, point_state, read_summary};
use swarm::terminal_text::printable;

/// The statistics of a window in the order the table lists them (others follow, sorted).
const STAT_ORDER: [&str; 14] = [
    "mean_d",
    "collisions_per_robot",
    "collisions_per_net_m",
    "collisions_per_m",
    "contact_percent",
    "held_percent",
    "shuttling_percent",
    "circling_percent",
    "exploring_percent",
    "net_mm",
    "moved_mm",
    "fresh_cells_per_100_steps",
    "gap_cv",
    "touching_percent",
];

/// A claim's words as a column name: lower case, runs of anything but letters and digits as
/// one `_`, at most 72 characters.
#[must_use]
pub fn claim_slug(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars().flat_map(char::to_lowercase) {
        if c.is_ascii_alphanumeric() {
            out.push(c);
        } else if !out.is_empty() && !out.ends_with('_') {
            out.push('_');
        }
    }
    let mut out: String = out.chars().take(72).collect();
    while out.ends_with('_') {
        out.pop();
    }
    if out.is_empty() { "claim".into() } else { out }
}

/// Columns in order of first appearance.
#[derive(Default)]
struct Columns {
    order: Vec<String>,
    seen: BTreeSet<String>,
}

impl Columns {
    fn add(&mut self, c: &str) {
        if self.seen.insert(c.to_string()) {
            self.order.push(c.to_string());
        }
    }
}

fn toml_to_json(v: &toml::Value) -> Value {
    serde_json::to_value(v).unwrap_or(Value::Null)
}

fn num(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

/// A cell as CSV text.
fn csv_cell(v: Option<&Value>) -> String {
    match v {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => other.to_string(),
    }
}

/// What `merge` found.
#[derive(Debug, Default)]
pub struct Merged {
    /// Column names in order.
    pub columns: Vec<String>,
    /// One row per point.
    pub rows: Vec<Map<String, Value>>,
    /// Points that ran and failed, with why.
    pub failed: Vec<(String, String)>,
    /// Points with no folder.
    pub missing: Vec<String>,
    /// Points whose folder is neither finished nor failed, with why.
    pub broken: Vec<(String, String)>,
    /// The claims: column slug, full text and whether it is one of the paper's, in order of
    /// first appearance.
    pub claims: Vec<(String, String, bool)>,
}

/// Reads every point of the sweep in `dir` into the table.
///
/// # Errors
/// Not a sweep folder (input). A finished point whose summary.json cannot be read is listed
/// as broken, not an error.
pub fn collect(
    dir: &Path,
) -> Result<(super::plan::Plan, Vec<super::plan::PlanLine>, Merged), SweepError> {
    let (plan, lines) = read_plan(dir)?;
    let points = dir.join("points");
    let mut cols = Columns::default();
    for c in ["index", "id", "status"] {
        cols.add(c);
    }
    for a in &plan.axes {
        for k in &a.keys {
            cols.add(k);
        }
    }
    cols.add("seed");
    let mut m = Merged::default();
    let mut stat_cols = Columns::default();
    let mut claims = Claims::default();
    let mut claim_cols = Columns::default();
    for line in &lines {
        let mut row = Map::new();
        row.insert("index".into(), json!(line.index));
        row.insert("id".into(), json!(line.id));
        for (a, &c) in plan.axes.iter().zip(&line.coords) {
            for (k, v) in a.keys.iter().zip(a.values.get(c).into_iter().flatten()) {
                row.insert(k.clone(), toml_to_json(v));
            }
        }
        row.insert("seed".into(), json!(line.seed));
        let status = match point_state(&points, line) {
            PointState::Ok => "ok",
            PointState::Missing => {
                m.missing.push(line.id.clone());
                "missing"
            }
            PointState::Failed(why) => {
                row.insert("error".into(), json!(why));
                m.failed.push((line.id.clone(), why));
                "failed"
            }
            PointState::Broken(why) => {
                row.insert("error".into(), json!(why));
                m.broken.push((line.id.clone(), why));
                "broken"
            }
        };
        row.insert("status".into(), json!(status));
        let summary = if status == "ok" {
            let path = points.join(&line.id).join("summary.json");
            match read_summary(&path) {
                Ok(v) => Some(v),
                Err(why) => {
                    // A finished point whose summary cannot be read: listed, not fatal.
                    row.insert("status".into(), json!("broken"));
                    row.insert("error".into(), json!(why));
                    m.broken.push((line.id.clone(), why));
                    None
                }
            }
        } else {
            None
        };
        if let Some(summary) = summary {
            condition_cells(&summary, &mut row, &mut stat_cols);
            claim_cells(&summary, &mut row, &mut claims, &mut claim_cols);
        }
        m.rows.push(row);
    }
    for c in stat_cols.order.iter().chain(&claim_cols.order) {
        cols.add(c);
    }
    cols.add("error");
    m.columns = cols.order;
    m.claims = claims.order;
    Ok((plan, lines, m))
}

/// Leftover temporary folders under `points/` (tasks running now, or killed).
fn temporaries(points: &Path) -> Vec<String> {
    let mut out: Vec<String> = std::fs::read_dir(points)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".tmp-") || n.starts_with("..tmp-"))
        .collect();
    out.sort();
    out
}

/// The figures an earlier merge into `out` wrote (the `figures` of its sweep.json): names
/// `plots/NAME.png` only, so nothing outside `out/plots` can be named.
pub(super) fn earlier_figures(out: &Path) -> Vec<String> {
    let Ok(text) = std::fs::read_to_string(out.join("sweep.json")) else {
        return Vec::new();
    };
    let Ok(doc) = serde_json::from_str::<Value>(&text) else {
        return Vec::new();
    };
    doc["figures"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .filter(|n| {
            n.strip_prefix("plots/").is_some_and(|f| {
                f.ends_with(".png") && !f.starts_with('.') && !f.contains(['/', '\\'])
            })
        })
        .map(str::to_string)
        .collect()
}

/// What one merge staged ([`merge_into`]): the text to print, whether every point finished,
/// and the staged files, merge's earlier files to remove and the folders, as the stage's
/// commit takes them.
pub(super) struct Staged {
    /// What to print.
    pub text: String,
    /// Whether every point finished.
    pub complete: bool,
    /// Staged files, relative to the output folder.
    pub files: Vec<String>,
    /// Merge's files of an earlier merge that go when not written again.
    pub ours: Vec<String>,
    /// Folders that exist after the commit.
    pub folders: Vec<String>,
}

/// Merges the sweep in `dir` into the staging folder `stage` under `prefix` (`""` for the
/// output folder itself, `"confirm/"` for the confirmation's sub-folder): `sweep.csv`,
/// `sweep.json` and the figures in `plots/`. Nothing is committed.
///
/// # Errors
/// Not a sweep folder (input); a file that cannot be written (tool).
pub(super) fn merge_into(
    dir: &Path,
    stage: &crate::stage::Stage,
    prefix: &str,
) -> Result<Staged, SweepError> {
    let (plan, lines, m) = collect(dir)?;
    let out = stage.out().join(prefix);
    let plots = out.join("plots");
    // Every file is written into the staging folder and moved into place in one commit
    // (crate::stage): a failure (a full disk) leaves `out` as it was. Only merge's own files
    // are replaced: the figures of an earlier merge into `out` (its sweep.json lists them) that
    // this one does not draw again are removed; anything else in `out` or `out/plots` is the
    // user's and stays.
    let earlier: Vec<String> = earlier_figures(&out)
        .into_iter()
        .map(|f| format!("{prefix}{f}"))
        .collect();
    let staged_plots = stage.path(&format!("{prefix}plots"));
    std::fs::create_dir_all(&staged_plots).map_err(|e| {
        SweepError::tool(format!("cannot create `{}`: {e}", staged_plots.display()))
    })?;

    write_csv(&m, &stage.path(&format!("{prefix}sweep.csv")))?;
    let csv_path = out.join("sweep.csv");

    let series = claim_series(&m);
    let coords: Vec<Vec<usize>> = lines.iter().map(|l| l.coords.clone()).collect();
    let paper: Vec<&ClaimSeries> = series.iter().filter(|s| s.paper).collect();
    let (inside, with_data) = region(&plan.axes, &coords, &paper);
    let ok = m.rows.iter().filter(|r| r["status"] == "ok").count();
    let doc = json!({
        "sweep": plan.sweep,
        "points": plan.points,
        "ok": ok,
        "failed": m.failed.iter().map(|(id, why)| json!({"id": id, "error": why})).collect::<Vec<_>>(),
        "missing": m.missing,
        "broken": m.broken.iter().map(|(id, why)| json!({"id": id, "why": why})).collect::<Vec<_>>(),
        "axes": plan.axes.iter().map(|a| json!({
            "keys": a.keys,
            "values": a.values.iter().map(|v| v.iter().map(toml_to_json).collect::<Vec<_>>()).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "seeds": plan.seeds,
        "claims": m.claims.iter().map(|(slug, text, paper)| json!({"column": format!("claim.{slug}"), "claim": text, "paper": paper})).collect::<Vec<_>>(),
        "region": inside.iter().map(|&i| cell_values(&plan.axes, i).into_iter().map(|(k, v)| (k, Value::String(v))).collect::<Map<String, Value>>()).collect::<Vec<_>>(),
        "columns": m.columns,
        "rows": m.rows,
    });
    let figures = claim_figures(&plan.axes, &coords, &series, &staged_plots)?;
    let figure_names: Vec<String> = figures
        .iter()
        .filter_map(|p| p.file_name())
        .map(|n| format!("plots/{}", n.to_string_lossy()))
        .collect();
    let mut doc = doc;
    doc["figures"] = json!(figure_names);
    let json_path = out.join("sweep.json");
    let text = serde_json::to_string_pretty(&doc)
        .map_err(|e| SweepError::tool(format!("writing sweep.json: {e}")))?
        + "\n";
    std::fs::write(stage.path(&format!("{prefix}sweep.json")), text.as_bytes())
        .map_err(|e| SweepError::tool(format!("cannot write `{}`: {e}", json_path.display())))?;
    let mut files = vec![format!("{prefix}sweep.csv"), format!("{prefix}sweep.json")];
    files.extend(figure_names.iter().map(|f| format!("{prefix}{f}")));

    let mut t = String::new();
    let _ = writeln!(
        t,
        "h8swarm sweep merge `{}`: {} points, {} ok, {} failed, {} missing, {} broken",
        plan.sweep,
        plan.points,
        ok,
        m.failed.len(),
        m.missing.len(),
        m.broken.len()
    );
    render_points(&mut t, &m, dir);
    render_repeat_warning(&mut t, &plan, &lines);
    for (slug, text, _) in &m.claims {
        let col = format!("claim.{slug}.outcome");
        let with: Vec<&str> = m
            .rows
            .iter()
            .filter_map(|r| r.get(&col).and_then(Value::as_str))
            .collect();
        let _ = writeln!(
            t,
            "holds in {:>3} of {:>3} points: {}",
            with.iter().filter(|h| **h == "holds").count(),
            with.len(),
            printable(text)
        );
    }
    render_power(&mut t, &plan, &coords, &paper);
    if !paper.is_empty() {
        let cells: usize = plan.axes.iter().map(|a| a.values.len()).product();
        let _ = writeln!(
            t,
            "the paper's {} text claims hold together (pooled over seeds) in {} of {} cells ({} with data for all):",
            paper.len(),
            inside.len(),
            cells,
            with_data
        );
        for &i in &inside {
            let v: Vec<String> = cell_values(&plan.axes, i)
                .into_iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect();
            let _ = writeln!(t, "  {}", v.join(", "));
        }
    }
    let _ = writeln!(
        t,
        "wrote {} ({} rows x {} columns) and {}; {} figures in {}",
        printable(&csv_path.display().to_string()),
        m.rows.len(),
        m.columns.len(),
        printable(&json_path.display().to_string()),
        figures.len(),
        printable(&plots.display().to_string())
    );
    if !plan.axes.is_empty() && figures.is_empty() && ok > 0 {
        let _ = writeln!(t, "(no claim had values to draw)");
    }
    let complete = m.failed.is_empty() && m.missing.is_empty() && m.broken.is_empty();
    let folders = if prefix.is_empty() {
        vec!["plots".to_string()]
    } else {
        vec![
            prefix.trim_end_matches('/').to_string(),
            format!("{prefix}plots"),
        ]
    };
    Ok(Staged {
        text: t,
        complete,
        files,
        ours: earlier,
        folders,
    })
}

/// Writes the merged table to `path` (rendered in memory, then written in one step).
fn write_csv(m: &Merged, path: &Path) -> Result<(), SweepError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| SweepError::tool(format!("writing sweep.csv: {e}"));
    w.write_record(&m.columns).map_err(csv_err)?;
    for row in &m.rows {
        w.write_record(m.columns.iter().map(|c| csv_cell(row.get(c))))
            .map_err(csv_err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| SweepError::tool(format!("writing sweep.csv: {e}")))?;
    std::fs::write(path, &bytes)
        .map_err(|e| SweepError::tool(format!("cannot write `sweep.csv`: {e}")))
}

/// Each claim's result per point (its repeats for, against and tied, and its effect), for the
/// figures.
pub(super) fn claim_series(m: &Merged) -> Vec<ClaimSeries> {
    m.claims
        .iter()
        .map(|(slug, text, paper)| ClaimSeries {
            slug: slug.clone(),
            text: text.clone(),
            paper: *paper,
            per_point: m
                .rows
                .iter()
                .map(|r| {
                    let n = |part: &str| {
                        r.get(&format!("claim.{slug}.{part}"))
                            .and_then(Value::as_u64)
                            .map(|v| v as u32)
                    };
                    let (f, a, t) = (n("for")?, n("against")?, n("tied")?);
                    Some(PointClaim {
                        for_: f,
                        against: a,
                        defined: f + a + t,
                        effect: r
                            .get(&format!("claim.{slug}.effect"))
                            .and_then(Value::as_f64),
                    })
                })
                .collect(),
        })
        .collect()
}

/// Fewest repeats a one-sided sign test at [`swarm::summary::SIGNIFICANCE`] can decide on:
/// 5 repeats all going one way give p = 1/32.
const MIN_DECIDING_REPEATS: i64 = 5;

/// The warning `h8swarm run` gives when a run's repeats cannot reach p < 0.05 (in the same
/// words, `tests/sweep.rs` holds them together), for the points of the plan with the fewest
/// repeats; and whether a cell of the maps, which pools its seeds, can.
fn render_repeat_warning(
    t: &mut String,
    plan: &super::plan::Plan,
    lines: &[super::plan::PlanLine],
) {
    let repeats: Vec<i64> = lines
        .iter()
        .filter_map(|l| l.scenario.get("repeats").and_then(toml::Value::as_integer))
        .collect();
    let (Some(&fewest), Some(&most)) = (repeats.iter().min(), repeats.iter().max()) else {
        return;
    };
    if fewest >= MIN_DECIDING_REPEATS {
        return;
    }
    let in_a_point = if fewest == most {
        "in a point".to_string()
    } else {
        format!("in a point of {fewest}")
    };
    let head = if fewest < 2 {
        format!(
            "one repeat: no intervals and no paired test {in_a_point} (set repeats = {MIN_DECIDING_REPEATS} or more)"
        )
    } else {
        format!(
            "{fewest} repeats: a one-sided sign test needs at least {MIN_DECIDING_REPEATS} repeats all going one way to reach p < 0.05, so no claim can hold {in_a_point}"
        )
    };
    let seeds = plan.seeds.len() as i64;
    let pooled = fewest * seeds;
    let _ = writeln!(
        t,
        "WARNING {head}; a cell of the maps pools its {seeds} seed{} ({pooled} repeat{}), {}",
        if seeds == 1 { "" } else { "s" },
        if pooled == 1 { "" } else { "s" },
        if pooled >= MIN_DECIDING_REPEATS {
            "which can reach p < 0.05"
        } else {
            "too few to reach p < 0.05"
        }
    );
}

/// Per claim of the paper's, its cells by pooled outcome, and the repeats a cell would need at
/// the effect it shows where it is not yet decided (the median over those cells).
fn render_power(
    t: &mut String,
    plan: &super::plan::Plan,
    coords: &[Vec<usize>],
    paper: &[&ClaimSeries],
) {
    use super::figures::{CellOutcome, cells};
    for s in paper {
        let cs = cells(&plan.axes, coords, s);
        let count = |o: CellOutcome| cs.iter().filter(|c| c.outcome() == o).count();
        let mut needed: Vec<u32> = cs
            .iter()
            .filter(|c| c.outcome() == CellOutcome::Unsure)
            .filter_map(|c| {
                let untied = c.for_ + c.against;
                swarm::summary::Power::of(&swarm::summary::Paired {
                    for_: c.for_,
                    against: c.against,
                    tied: c.defined - untied,
                    undefined: 0,
                    p: swarm::summary::sign_test_p(c.for_, untied),
                    p_opposite: swarm::summary::sign_test_p(c.against, untied),
                })
                .repeats_needed
            })
            .collect();
        needed.sort_unstable();
        let unsure = count(CellOutcome::Unsure);
        let need = match needed.get(needed.len() / 2) {
            Some(n) if unsure > 0 => format!(
                " (at the effect they show, a median of {n} repeats a cell would decide them)"
            ),
            _ => String::new(),
        };
        let words = s.text.split(':').next().unwrap_or(&s.text);
        let _ = writeln!(
            t,
            "cells (pooled over seeds): {} holds in {}, unsure in {unsure}{need}, fails in {}, the opposite in {}, no data in {}",
            printable(words),
            count(CellOutcome::Holds),
            count(CellOutcome::Fails),
            count(CellOutcome::Opposite),
            count(CellOutcome::NoData)
        );
    }
}

/// The report's lines on the points that did not finish: failed, missing, broken, and the
/// temporary folders under `dir/points` (a task at work, or a killed task's leftovers).
fn render_points(t: &mut String, m: &Merged, dir: &Path) {
    for (id, why) in &m.failed {
        let _ = writeln!(t, "FAILED  {id}: {}", printable(why));
    }
    for id in &m.missing {
        let _ = writeln!(t, "MISSING {id}");
    }
    for (id, why) in &m.broken {
        let _ = writeln!(
            t,
            "BROKEN  {id}: {} (the next `sweep run` redoes it)",
            printable(why)
        );
    }
    let host = host_name();
    for tmp in temporaries(&dir.join("points")) {
        let _ = if is_dead_leftover(&tmp, &host) {
            writeln!(
                t,
                "LEFTOVER points/{} (its task was killed; the next `sweep run` removes it)",
                printable(&tmp)
            )
        } else {
            writeln!(
                t,
                "RUNNING points/{} (a task at work, or left by a killed one)",
                printable(&tmp)
            )
        };
    }
}

/// The claims met so far over the points: each claim's text with its column slug, and the
/// claims (slug, text, whether it is the paper's) in the order they were first met.
#[derive(Default)]
struct Claims {
    slugs: BTreeMap<String, String>,
    order: Vec<(String, String, bool)>,
}

/// A finished point's window statistics into `row`: every condition's per-robot figures and
/// its first and last windows' estimates (mean, lo, hi), their columns added to `cols`.
fn condition_cells(summary: &Value, row: &mut Map<String, Value>, cols: &mut Columns) {
    for c in summary["conditions"].as_array().into_iter().flatten() {
        let cond = c["condition"].as_str().unwrap_or("condition");
        if let Some(robots) = c["robots"].as_object() {
            for (k, v) in robots {
                if let Some(est) = v.as_object() {
                    for part in ["mean", "lo", "hi"] {
                        let col = format!("{cond}.robots.{k}.{part}");
                        cols.add(&col);
                        row.insert(col, est.get(part).cloned().unwrap_or(Value::Null));
                    }
                } else {
                    let col = format!("{cond}.robots.{k}");
                    cols.add(&col);
                    row.insert(col, v.clone());
                }
            }
        }
        for w in ["first", "last"] {
            let Some(win) = c[w].as_object() else {
                continue;
            };
            let mut keys: Vec<&String> = STAT_ORDER
                .iter()
                .filter_map(|k| win.get_key_value(*k).map(|(k, _)| k))
                .collect();
            let mut rest: Vec<&String> = win
                .keys()
                .filter(|k| !STAT_ORDER.contains(&k.as_str()))
                .collect();
            rest.sort();
            keys.extend(rest);
            for k in keys {
                let Some(est) = win[k].as_object() else {
                    continue;
                };
                if !est.contains_key("mean") {
                    continue;
                }
                for part in ["mean", "lo", "hi"] {
                    let col = format!("{cond}.{w}.{k}.{part}");
                    cols.add(&col);
                    row.insert(col, est.get(part).cloned().unwrap_or(Value::Null));
                }
            }
        }
    }
}

/// A claim's effect: the difference of its two values (in the order its words name them),
/// positive when the means agree with the claim, whichever way it goes ("a below b" or
/// "a above b").
fn effect(a: Option<f64>, b: Option<f64>, means_agree: Option<bool>) -> Value {
    match (a, b, means_agree) {
        (Some(a), Some(b), Some(agree)) => {
            let d = (b - a).abs();
            num(if agree || d == 0.0 { d } else { -d })
        }
        _ => Value::Null,
    }
}

/// A finished point's claims into `row`: outcome, values, effect and repeats per claim, under
/// a column slug of the claim's (new claims added to `claims`, their columns to `cols`).
fn claim_cells(
    summary: &Value,
    row: &mut Map<String, Value>,
    claims: &mut Claims,
    cols: &mut Columns,
) {
    for c in summary["claims"].as_array().into_iter().flatten() {
        let text = c["claim"].as_str().unwrap_or_default().to_string();
        let slug = match claims.slugs.get(&text) {
            Some(s) => s.clone(),
            None => {
                let base = claim_slug(&text);
                let mut slug = base.clone();
                let mut n = 2;
                while claims.slugs.values().any(|s| *s == slug) {
                    slug = format!("{base}_{n}");
                    n += 1;
                }
                claims.slugs.insert(text.clone(), slug.clone());
                let paper = c["paper"].as_bool().unwrap_or(false);
                claims.order.push((slug.clone(), text.clone(), paper));
                slug
            }
        };
        let a = c["values"][0].as_f64();
        let b = c["values"][1].as_f64();
        let r = &c["repeats"];
        let cells = [
            ("outcome", c["outcome"].clone()),
            ("means_agree", c["means_agree"].clone()),
            ("apart", c["apart"].clone()),
            ("a", a.map_or(Value::Null, num)),
            ("b", b.map_or(Value::Null, num)),
            ("effect", effect(a, b, c["means_agree"].as_bool())),
            ("for", r["for"].clone()),
            ("against", r["against"].clone()),
            ("tied", r["tied"].clone()),
            ("undefined", r["undefined"].clone()),
            ("p", r["p"].clone()),
            ("towards", c["power"]["towards"].clone()),
            ("repeats_needed", c["power"]["repeats_needed"].clone()),
        ];
        for (part, v) in cells {
            let col = format!("claim.{slug}.{part}");
            cols.add(&col);
            row.insert(col, v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::MIN_DECIDING_REPEATS;
    use swarm::summary::{SIGNIFICANCE, sign_test_p};

    #[test]
    fn the_fewest_deciding_repeats_are_those_of_the_sign_test() {
        let n = MIN_DECIDING_REPEATS as u32;
        assert!(sign_test_p(n, n) < SIGNIFICANCE);
        assert!(sign_test_p(n - 1, n - 1) >= SIGNIFICANCE);
    }
}
