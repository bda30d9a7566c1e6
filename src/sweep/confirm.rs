//! `h8swarm sweep confirm DIR`: the confirmation stage. A claim map is drawn on its own
//! (discovery) seeds; the cells chosen from it are run again on master seeds the map never
//! used, and `sweep merge DIR` reports the map and the confirmation side by side, with the
//! default a stated rule takes from the confirmed cells.
//!
//! * `sweep confirm DIR` reads the `[confirm]` section of the sweep file (the copy in
//!   `DIR/sweep.toml`; [`super::spec::Confirm`]) and the finished map, picks the cells (the
//!   region where the paper's text claims all hold, pooled over the map's seeds; that and its
//!   neighbours; or the cells listed) and plans them on the confirmation's seeds into
//!   `DIR/confirm/`, a sweep folder like any (`plan.json`, `points.jsonl`, `sweep.sbatch`) with
//!   the same axes, so its points sit in the map's cells; `confirm.json` records the choice.
//!   Each point is the map's point of that cell with the seed (and, if asked, the repeats)
//!   changed, so nothing else differs. Planning again is allowed for the same run list only.
//! * `sweep run DIR/confirm` (or `sbatch DIR/confirm/sweep.sbatch`) runs it.
//! * `sweep merge DIR` merges the map into `DIR/merged/`, the confirmation into
//!   `DIR/merged/confirm/`, and writes `DIR/merged/confirmation.csv` and `.json`: per chosen
//!   cell the map's and the confirmation's pooled outcome of every one of the paper's text
//!   claims, whether the confirmation holds them all (*confirmed*), its neighbours in the map's
//!   region, its margin, and the repeats a decision would need at each claim's observed
//!   effect ([`swarm::summary::Power`]).
//!
//! **The rule** for a default (docs/claims.md): only a confirmed cell can be one; among them,
//! the one with the most neighbours (one step along one axis) in the map's region, then the
//! widest margin (the smallest, over the paper's text claims, of (for − against) / (for +
//! against) in the confirmation), then the first in the grid. No confirmed cell: no default.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::figures::{Cell, CellOutcome, ClaimSeries, cell_index, cell_values, cells, region};
use super::plan::{Plan, PlanLine, PointCost, requests, sbatch_script};
use super::spec::{Axis, CellChoice, Confirm, SlurmSpec, confirm_section, point_id, slurm_section};
use super::{SweepError, write_atomic};
use swarm::summary::{Paired, Power, sign_test_p};
use swarm::terminal_text::printable;

/// The confirmation's folder inside the map's.
pub const CONFIRM_DIR: &str = "confirm";

/// `confirm.json`: what the confirmation re-runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConfirmRecord {
    /// The map's sweep.
    pub map: String,
    /// How the cells were chosen.
    pub choice: CellChoice,
    /// The cells (their index in the map's grid, the first axis slowest), in order.
    pub cells: Vec<usize>,
    /// The confirmation's master seeds.
    pub seeds: Vec<u64>,
    /// Repeats per point, when not the map's.
    pub repeats: Option<u32>,
}

/// The cells one step along one axis from cell `coords`.
fn neighbours(axes: &[Axis], coords: &[usize]) -> Vec<usize> {
    let mut out = Vec::new();
    for (a, axis) in axes.iter().enumerate() {
        for next in [coords[a].checked_sub(1), Some(coords[a] + 1)]
            .into_iter()
            .flatten()
            .filter(|&c| c < axis.values.len())
        {
            let mut c = coords.to_vec();
            c[a] = next;
            out.push(cell_index(axes, &c));
        }
    }
    out
}

/// The coordinates of cell `index`.
fn coords_of(axes: &[Axis], mut index: usize) -> Vec<usize> {
    let mut out = vec![0; axes.len()];
    for (c, a) in out.iter_mut().zip(axes).rev() {
        let n = a.values.len().max(1);
        *c = index % n;
        index /= n;
    }
    out
}

/// A finished map: its plan, run list, the paper's claims over its points, and its region.
type Map = (Plan, Vec<PlanLine>, Vec<ClaimSeries>, Vec<usize>);

/// The map's paper-claim series and its region (cells where they all hold, pooled).
fn map_region(dir: &Path) -> Result<Map, SweepError> {
    let (plan, lines, m) = super::table::collect(dir)?;
    let not_ok = m.failed.len() + m.missing.len() + m.broken.len();
    if not_ok > 0 {
        return Err(SweepError::input(format!(
            "the map in `{}` is not complete ({not_ok} of {} points not ok): run it to the end and merge it before confirming",
            dir.display(),
            plan.points
        )));
    }
    let series: Vec<ClaimSeries> = super::table::claim_series(&m)
        .into_iter()
        .filter(|s| s.paper)
        .collect();
    let coords: Vec<Vec<usize>> = lines.iter().map(|l| l.coords.clone()).collect();
    let paper: Vec<&ClaimSeries> = series.iter().collect();
    let (inside, _) = region(&plan.axes, &coords, &paper);
    Ok((plan, lines, series, inside))
}

/// Plans the confirmation of the map in `dir` into `dir/confirm`; returns what to print.
///
/// # Errors
/// Not a sweep folder, no `[confirm]` section, a map that is not complete, a folder holding
/// another confirmation (input); a folder that cannot be written (tool).
pub fn plan_confirmation(dir: &Path, bin: Option<&Path>) -> Result<String, SweepError> {
    let file = dir.join("sweep.toml");
    let text = std::fs::read_to_string(&file).map_err(|e| {
        SweepError::input(format!(
            "`{}` is not a sweep folder (sweep.toml: {e}): make one with `h8swarm sweep plan`",
            dir.display()
        ))
    })?;
    let (plan, lines, _, inside) = map_region(dir)?;
    let confirm = confirm_section(&text, &file, &plan.axes, &plan.seeds)?.ok_or_else(|| {
        SweepError::input(format!(
            "`{}` has no [confirm] section: add one to the sweep file (seeds = [21, 22, 23, 24, 25], cells = \"region\") and plan it again into the same folder",
            file.display()
        ))
    })?;
    let chosen = choose_cells(&plan.axes, &confirm, &inside);
    let mut t = String::new();
    let seeds_text = seed_list(&confirm.seeds);
    if chosen.is_empty() {
        let _ = writeln!(
            t,
            "h8swarm sweep confirm `{}`: no cell of the map holds the paper's text claims together, so there is nothing to confirm (cells = {})",
            plan.sweep,
            choice_words(&confirm.cells)
        );
        return Ok(t);
    }
    let slurm = slurm_section(&text);
    let (cplan, clines) = confirmation_plan(&plan, &lines, &confirm, &chosen, &slurm)?;
    let out = super::plan::plan_folder(&dir.join(CONFIRM_DIR))?;
    let bin: PathBuf = match bin {
        Some(b) => b.to_path_buf(),
        None => std::env::current_exe()
            .map_err(|e| SweepError::tool(format!("cannot find this program's path: {e}")))?,
    };
    let script = sbatch_script(&cplan, &slurm, &out, &bin)?;
    let list_path = out.join("points.jsonl");
    let tmp = out.join(format!(".points.jsonl.tmp-{}", std::process::id()));
    let mut list = String::new();
    for l in &clines {
        let line = serde_json::to_string(l)
            .map_err(|e| SweepError::tool(format!("writing the run list: {e}")))?;
        list.push_str(&line);
        list.push('\n');
    }
    write_atomic(&tmp, list.as_bytes())?;
    if list_path.exists() && !super::plan::same_file_bytes(&list_path, &tmp)? {
        let _ = std::fs::remove_file(&tmp);
        return Err(SweepError::input(format!(
            "`{}` already holds a different confirmation (its points.jsonl differs): remove it to plan another",
            out.display()
        )));
    }
    std::fs::rename(&tmp, &list_path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        SweepError::tool(format!("cannot write `{}`: {e}", list_path.display()))
    })?;
    for sub in ["points", "logs"] {
        let p = out.join(sub);
        std::fs::create_dir_all(&p)
            .map_err(|e| SweepError::tool(format!("cannot create `{}`: {e}", p.display())))?;
    }
    let record = ConfirmRecord {
        map: plan.sweep.clone(),
        choice: confirm.cells.clone(),
        cells: chosen.clone(),
        seeds: confirm.seeds.clone(),
        repeats: confirm.repeats,
    };
    write_atomic(&out.join("confirm.json"), pretty(&record)?.as_bytes())?;
    write_atomic(&out.join("plan.json"), pretty(&cplan)?.as_bytes())?;
    write_atomic(&out.join("sweep.sbatch"), script.as_bytes())?;
    write_atomic(&out.join("sweep.toml"), text.as_bytes())?;
    let out_text = printable(&out.display().to_string());
    let _ = writeln!(
        t,
        "h8swarm sweep confirm `{}`: {} cells (cells = {}) on seeds {seeds_text}: {} points in {} tasks of up to {}",
        plan.sweep,
        chosen.len(),
        choice_words(&confirm.cells),
        cplan.points,
        cplan.tasks,
        cplan.points_per_task
    );
    for &c in &chosen {
        let _ = writeln!(t, "  {}", cell_words(&plan.axes, c));
    }
    let _ = writeln!(
        t,
        "each task asks for {} CPUs, {} MB, {}",
        cplan.requests.cpus_per_task, cplan.requests.mem_mb, cplan.requests.time
    );
    let _ = writeln!(
        t,
        "wrote {out_text} (plan.json, points.jsonl, sweep.sbatch, confirm.json)"
    );
    let _ = writeln!(t, "on a cluster: sbatch {out_text}/sweep.sbatch");
    let _ = writeln!(t, "on this machine: h8swarm sweep run {out_text}");
    let _ = writeln!(
        t,
        "then: h8swarm sweep merge {} (the map and the confirmation)",
        printable(&dir.display().to_string())
    );
    Ok(t)
}

/// `v` as pretty JSON with a final newline.
fn pretty<T: Serialize>(v: &T) -> Result<String, SweepError> {
    serde_json::to_string_pretty(v)
        .map(|s| s + "\n")
        .map_err(|e| SweepError::tool(format!("writing JSON: {e}")))
}

/// The cells a confirmation re-runs, in grid order.
fn choose_cells(axes: &[Axis], confirm: &Confirm, inside: &[usize]) -> Vec<usize> {
    let mut chosen: Vec<usize> = match &confirm.cells {
        CellChoice::Region => inside.to_vec(),
        CellChoice::RegionAndNeighbours => inside
            .iter()
            .flat_map(|&c| {
                let mut v = neighbours(axes, &coords_of(axes, c));
                v.push(c);
                v
            })
            .collect(),
        CellChoice::Listed(list) => list.iter().map(|c| cell_index(axes, c)).collect(),
    };
    chosen.sort_unstable();
    chosen.dedup();
    chosen
}

/// The confirmation's plan and run list: each chosen cell's map point (its first seed) with the
/// confirmation's seeds and repeats.
fn confirmation_plan(
    plan: &Plan,
    lines: &[PlanLine],
    confirm: &Confirm,
    chosen: &[usize],
    slurm: &SlurmSpec,
) -> Result<(Plan, Vec<PlanLine>), SweepError> {
    let per_seed = plan.seeds.len().max(1);
    let count = chosen.len() * confirm.seeds.len();
    let per_task = plan.points_per_task.max(1);
    let mut out = Vec::with_capacity(count);
    let mut costs = Vec::with_capacity(count);
    for (ci, &cell) in chosen.iter().enumerate() {
        let src = lines
            .iter()
            .skip(cell * per_seed)
            .find(|l| cell_index(&plan.axes, &l.coords) == cell)
            .ok_or_else(|| SweepError::input(format!("the map has no point in cell {cell}")))?;
        for (si, &seed) in confirm.seeds.iter().enumerate() {
            let index = ci * confirm.seeds.len() + si;
            let id = point_id(index, count, &plan.axes, &src.coords, seed);
            let mut scenario = src.scenario.clone();
            scenario.insert("name".into(), toml::Value::String(id.clone()));
            scenario.insert(
                "seed".into(),
                toml::Value::Integer(i64::try_from(seed).unwrap_or(i64::MAX)),
            );
            if let Some(r) = confirm.repeats {
                scenario.insert("repeats".into(), toml::Value::Integer(i64::from(r)));
            }
            let line = PlanLine {
                index,
                id,
                task: index / per_task,
                coords: src.coords.clone(),
                seed,
                scenario,
            };
            let s = line.point().resolve()?;
            costs.push(PointCost::of(&s));
            out.push(line);
        }
    }
    let tasks = count.div_ceil(per_task);
    let max_array = slurm
        .max_array_size
        .unwrap_or(super::plan::DEFAULT_MAX_ARRAY_SIZE);
    if tasks > max_array {
        return Err(SweepError::input(format!(
            "the confirmation's {count} points at {per_task} a task make {tasks} array tasks, more than Slurm's MaxArraySize of {max_array}: give the sweep a larger `slurm.points_per_task`"
        )));
    }
    let cplan = Plan {
        h8swarm_version: env!("CARGO_PKG_VERSION").to_string(),
        sweep: format!("{}-confirm", plan.sweep),
        axes: plan.axes.clone(),
        seeds: confirm.seeds.clone(),
        points: count,
        cells: Some(chosen.to_vec()),
        points_per_task: per_task,
        tasks,
        max_parallel: plan.max_parallel,
        requests: requests(&costs, slurm, per_task)?,
    };
    Ok((cplan, out))
}

/// Seeds as text: `21-25` for a run of consecutive seeds, else listed.
fn seed_list(seeds: &[u64]) -> String {
    let consecutive = seeds.windows(2).all(|w| w[1] == w[0] + 1);
    match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if consecutive && seeds.len() > 2 => format!("{a}-{b}"),
        _ => seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", "),
    }
}

fn choice_words(c: &CellChoice) -> String {
    match c {
        CellChoice::Region => "\"region\"".into(),
        CellChoice::RegionAndNeighbours => "\"region+neighbours\"".into(),
        CellChoice::Listed(l) => format!("{} listed", l.len()),
    }
}

/// A cell's values in words: `learner.eta = 0.03, world.mu_wall = 0.1`.
fn cell_words(axes: &[Axis], cell: usize) -> String {
    cell_values(axes, cell)
        .into_iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// One chosen cell's verdict.
#[derive(Clone, Debug, PartialEq)]
struct Row {
    cell: usize,
    in_region: bool,
    neighbours: usize,
    neighbours_in_region: usize,
    map: Vec<Cell>,
    confirmation: Vec<Cell>,
    confirmed: bool,
    margin: Option<f64>,
    finished: usize,
    planned: usize,
}

/// A pooled cell's repeats as a paired count (no repeat without a value: the cells do not
/// keep them).
fn paired(c: &Cell) -> Paired {
    let untied = c.for_ + c.against;
    Paired {
        for_: c.for_,
        against: c.against,
        tied: c.defined - untied,
        undefined: 0,
        p: sign_test_p(c.for_, untied),
        p_opposite: sign_test_p(c.against, untied),
    }
}

/// The word of a pooled outcome with its repeats: `holds 36/50`.
fn outcome_words(c: &Cell) -> String {
    let word = match c.outcome() {
        CellOutcome::Holds => "holds",
        CellOutcome::Unsure => "unsure",
        CellOutcome::Fails => "fails",
        CellOutcome::Opposite => "the opposite",
        CellOutcome::NoData => return "no data".into(),
    };
    format!("{word} {}/{}", c.for_, c.defined)
}

/// Merges the confirmation of the map in `dir` (its folder exists) into the merge's staging
/// folder: the confirmation's own merge under `confirm/`, the side-by-side table beside the
/// map's. Returns what it staged; the caller commits it with the map's merge.
///
/// # Errors
/// A damaged folder (input); an output that cannot be written (tool).
pub(super) fn merge_confirmation(
    dir: &Path,
    stage: &crate::stage::Stage,
) -> Result<super::table::Staged, SweepError> {
    let cdir = dir.join(CONFIRM_DIR);
    let mut staged = super::table::merge_into(&cdir, stage, &format!("{CONFIRM_DIR}/"))?;
    let t = &mut staged.text;
    let record: ConfirmRecord = std::fs::read_to_string(cdir.join("confirm.json"))
        .ok()
        .and_then(|s| serde_json::from_str(&s).ok())
        .ok_or_else(|| {
            SweepError::input(format!(
                "`{}` has no readable confirm.json: plan it with `h8swarm sweep confirm {}`",
                cdir.display(),
                dir.display()
            ))
        })?;
    let (plan, lines, series, inside) = match map_region(dir) {
        Ok(v) => v,
        Err(e) => {
            let _ = writeln!(t, "the confirmation cannot be judged: {e}");
            staged.complete = false;
            return Ok(staged);
        }
    };
    let grid: usize = plan.axes.iter().map(|a| a.values.len()).product();
    if let Some(c) = record.cells.iter().find(|&&c| c >= grid.max(1)) {
        return Err(SweepError::input(format!(
            "`{}` names cell {c}, but the map has {grid} cells: plan the confirmation again with `h8swarm sweep confirm {}`",
            cdir.join("confirm.json").display(),
            dir.display()
        )));
    }
    let (cplan, clines, cm) = super::table::collect(&cdir)?;
    if clines.iter().any(|l| {
        l.coords.len() != plan.axes.len()
            || l.coords
                .iter()
                .zip(&plan.axes)
                .any(|(&c, a)| c >= a.values.len())
    }) {
        return Err(SweepError::input(format!(
            "`{}` holds a point outside the map's grid: plan the confirmation again with `h8swarm sweep confirm {}`",
            cdir.join("points.jsonl").display(),
            dir.display()
        )));
    }
    let cseries = super::table::claim_series(&cm);
    let ccoords: Vec<Vec<usize>> = clines.iter().map(|l| l.coords.clone()).collect();
    let coords: Vec<Vec<usize>> = lines.iter().map(|l| l.coords.clone()).collect();
    let axes = &plan.axes;
    // The paper's claims, matched by their words.
    let pairs: Vec<(&ClaimSeries, Option<&ClaimSeries>)> = series
        .iter()
        .map(|s| (s, cseries.iter().find(|c| c.text == s.text)))
        .collect();
    let map_cells: Vec<Vec<Cell>> = series.iter().map(|s| cells(axes, &coords, s)).collect();
    let conf_cells: Vec<Vec<Cell>> = pairs
        .iter()
        .map(|(s, c)| match c {
            Some(c) => cells(axes, &ccoords, c),
            None => cells(
                axes,
                &ccoords,
                &ClaimSeries {
                    per_point: vec![None; ccoords.len()],
                    ..(*s).clone()
                },
            ),
        })
        .collect();
    let mut rows: Vec<Row> = record
        .cells
        .iter()
        .map(|&cell| {
            let nb = neighbours(axes, &coords_of(axes, cell));
            let map: Vec<Cell> = map_cells.iter().map(|c| c[cell].clone()).collect();
            let confirmation: Vec<Cell> = conf_cells.iter().map(|c| c[cell].clone()).collect();
            let confirmed = !confirmation.is_empty()
                && confirmation
                    .iter()
                    .all(|c| c.outcome() == CellOutcome::Holds);
            let margin = confirmation
                .iter()
                .map(|c| {
                    let n = c.for_ + c.against;
                    if n == 0 {
                        -1.0
                    } else {
                        (f64::from(c.for_) - f64::from(c.against)) / f64::from(n)
                    }
                })
                .reduce(f64::min);
            let (finished, planned) = confirmation
                .first()
                .map_or((0, 0), |c| (c.finished, c.planned));
            Row {
                cell,
                in_region: inside.contains(&cell),
                neighbours: nb.len(),
                neighbours_in_region: nb.iter().filter(|n| inside.contains(n)).count(),
                map,
                confirmation,
                confirmed,
                margin,
                finished,
                planned,
            }
        })
        .collect();
    // The rule: confirmed first, then most neighbours in the map's region, then the widest
    // margin, then grid order.
    rows.sort_by(|a, b| {
        b.confirmed
            .cmp(&a.confirmed)
            .then(b.neighbours_in_region.cmp(&a.neighbours_in_region))
            .then(
                b.margin
                    .unwrap_or(-1.0)
                    .total_cmp(&a.margin.unwrap_or(-1.0)),
            )
            .then(a.cell.cmp(&b.cell))
    });
    let default = rows.first().filter(|r| r.confirmed).map(|r| r.cell);
    write_table(stage.dir(), axes, &series, &rows, default, &record)?;
    staged.files.extend(
        ["confirmation.csv", "confirmation.json"]
            .into_iter()
            .map(str::to_string),
    );
    render(t, axes, &series, &rows, default, &record, &cplan);
    Ok(staged)
}

/// Writes `confirmation.csv` and `confirmation.json` into `out` (the merge's staging folder).
fn write_table(
    out: &Path,
    axes: &[Axis],
    series: &[ClaimSeries],
    rows: &[Row],
    default: Option<usize>,
    record: &ConfirmRecord,
) -> Result<(), SweepError> {
    let mut columns: Vec<String> = vec!["rank".into(), "cell".into()];
    columns.extend(axes.iter().map(Axis::name));
    for c in [
        "in_map_region",
        "neighbours",
        "neighbours_in_map_region",
        "confirmation_points",
        "confirmation_points_ok",
    ] {
        columns.push(c.into());
    }
    for s in series {
        for stage in ["map", "confirmation"] {
            for part in [
                "outcome",
                "for",
                "against",
                "defined",
                "towards",
                "repeats_needed",
            ] {
                columns.push(format!("{stage}.{}.{part}", s.slug));
            }
        }
    }
    for c in ["confirmed", "margin", "default"] {
        columns.push(c.into());
    }
    let mut json_rows = Vec::new();
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| SweepError::tool(format!("writing confirmation.csv: {e}"));
    w.write_record(&columns).map_err(csv_err)?;
    for (rank, r) in rows.iter().enumerate() {
        let mut cells_text: Vec<String> = vec![(rank + 1).to_string(), r.cell.to_string()];
        cells_text.extend(cell_values(axes, r.cell).into_iter().map(|(_, v)| v));
        cells_text.extend([
            r.in_region.to_string(),
            r.neighbours.to_string(),
            r.neighbours_in_region.to_string(),
            r.planned.to_string(),
            r.finished.to_string(),
        ]);
        for (m, c) in r.map.iter().zip(&r.confirmation) {
            for cell in [m, c] {
                let o = match cell.outcome() {
                    CellOutcome::Holds => "holds",
                    CellOutcome::Unsure => "unsure",
                    CellOutcome::Fails => "fails",
                    CellOutcome::Opposite => "opposite",
                    CellOutcome::NoData => "no-data",
                };
                let power = Power::of(&paired(cell));
                cells_text.extend([
                    o.to_string(),
                    cell.for_.to_string(),
                    cell.against.to_string(),
                    cell.defined.to_string(),
                    power.towards.to_string(),
                    power
                        .repeats_needed
                        .map(|n| n.to_string())
                        .unwrap_or_default(),
                ]);
            }
        }
        cells_text.extend([
            r.confirmed.to_string(),
            r.margin.map(|m| format!("{m}")).unwrap_or_default(),
            (default == Some(r.cell)).to_string(),
        ]);
        let obj: serde_json::Map<String, Value> = columns
            .iter()
            .cloned()
            .zip(cells_text.iter().map(|v| json!(v)))
            .collect();
        json_rows.push(Value::Object(obj));
        w.write_record(&cells_text).map_err(csv_err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| SweepError::tool(format!("writing confirmation.csv: {e}")))?;
    write_staged(&out.join("confirmation.csv"), &bytes)?;
    let doc = json!({
        "map": record.map,
        "choice": record.choice,
        "seeds": record.seeds,
        "repeats": record.repeats,
        "claims": series.iter().map(|s| json!({"slug": s.slug, "claim": s.text})).collect::<Vec<_>>(),
        "rule": "a default only from confirmed cells (every one of the paper's text claims holds on the confirmation's seeds, pooled); among them the most neighbours in the map's region, then the widest margin (the smallest over the claims of (for - against) / (for + against)), then grid order",
        "default": default.map(|c| cell_values(axes, c).into_iter().map(|(k, v)| (k, Value::String(v))).collect::<serde_json::Map<_, _>>()),
        "columns": columns,
        "rows": json_rows,
    });
    let text = serde_json::to_string_pretty(&doc)
        .map_err(|e| SweepError::tool(format!("writing confirmation.json: {e}")))?
        + "\n";
    write_staged(&out.join("confirmation.json"), text.as_bytes())
}

/// Writes a file into the merge's staging folder (moved into place by its commit).
fn write_staged(path: &Path, bytes: &[u8]) -> Result<(), SweepError> {
    std::fs::write(path, bytes)
        .map_err(|e| SweepError::tool(format!("cannot write `{}`: {e}", path.display())))
}

/// The printed side-by-side table and the default.
fn render(
    t: &mut String,
    axes: &[Axis],
    series: &[ClaimSeries],
    rows: &[Row],
    default: Option<usize>,
    record: &ConfirmRecord,
    cplan: &Plan,
) {
    let _ = writeln!(
        t,
        "confirmation of `{}` on seeds {} ({} cells, {} points): the paper's text claims, map then confirmation (repeats for the claim / with a value, pooled over the seeds)",
        record.map,
        seed_list(&record.seeds),
        record.cells.len(),
        cplan.points
    );
    for (rank, r) in rows.iter().enumerate() {
        let verdict = if r.finished < r.planned {
            format!("INCOMPLETE ({} of {} points)", r.finished, r.planned)
        } else if r.confirmed {
            "CONFIRMED".into()
        } else {
            "not confirmed".into()
        };
        let _ = writeln!(
            t,
            "{}. {}: {verdict}; {} of {} neighbours in the map's region{}; margin {}",
            rank + 1,
            cell_words(axes, r.cell),
            r.neighbours_in_region,
            r.neighbours,
            if r.in_region {
                ""
            } else {
                " (not itself in it)"
            },
            r.margin
                .map_or_else(|| "none".into(), |m| format!("{m:+.2}"))
        );
        for ((s, m), c) in series.iter().zip(&r.map).zip(&r.confirmation) {
            let words: String = s.text.split(':').next().unwrap_or(&s.text).to_string();
            let power = Power::of(&paired(c));
            let need = if c.outcome() == CellOutcome::Holds {
                String::new()
            } else {
                format!(" ({})", power.words())
            };
            let _ = writeln!(
                t,
                "     {:<28} map {:<18} confirmation {}{need}",
                printable(&words),
                outcome_words(m),
                outcome_words(c)
            );
        }
    }
    match default {
        Some(c) => {
            let _ = writeln!(
                t,
                "the rule's default (docs/claims.md: confirmed, most neighbours in the map's region, widest margin): {}",
                cell_words(axes, c)
            );
        }
        None => {
            let _ = writeln!(
                t,
                "no cell is confirmed: the rule takes no default from this map"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axes() -> Vec<Axis> {
        let ax = |k: &str, n: usize| Axis {
            keys: vec![k.into()],
            values: (0..n)
                .map(|i| vec![toml::Value::Integer(i as i64)])
                .collect(),
        };
        vec![ax("a", 3), ax("b", 2)]
    }

    #[test]
    fn neighbours_are_one_step_along_one_axis() {
        let a = axes();
        // Cell (1, 0): (0, 0), (2, 0), (1, 1).
        let mut n = neighbours(&a, &[1, 0]);
        n.sort_unstable();
        assert_eq!(
            n,
            vec![
                cell_index(&a, &[0, 0]),
                cell_index(&a, &[1, 1]),
                cell_index(&a, &[2, 0])
            ]
        );
        assert_eq!(coords_of(&a, cell_index(&a, &[2, 1])), vec![2, 1]);
        let c = Confirm {
            seeds: vec![21],
            cells: CellChoice::RegionAndNeighbours,
            repeats: None,
        };
        assert_eq!(
            choose_cells(&a, &c, &[cell_index(&a, &[0, 0])]),
            vec![0, 1, 2]
        );
        assert_eq!(seed_list(&[21, 22, 23]), "21-23");
        assert_eq!(seed_list(&[6, 9]), "6, 9");
    }
}
