//! The sweep's figures, drawn with `plotters`: a **claim map** for every claim and a **region**
//! figure for the paper's text claims together.
//!
//! A claim says "a below b" (or "a above b"), checked in every point repeat by repeat ([`swarm::summary`]). A
//! map's cell is one combination of the swept values; it pools the points that differ only in
//! their master seed: their repeats' counts for and against the claim are added and judged by
//! the same one-sided exact sign test at the same level, so a cell of 5 seeds × 10 repeats is
//! judged on 50 paired repeats. The cell is coloured by that pooled outcome ([`CellOutcome`])
//! and labelled with it, the repeats for it out of those with a value, and the mean over its
//! points of the effect (positive where the means agree with the claim).
//!
//! Layout: the first swept axis runs down a panel, the second across; every combination of the
//! further axes gets a panel of its own, in a grid (one axis alone: one row of cells). The
//! region figure has the same layout; a cell shows which of the paper's text claims hold
//! there, and the cells where all of them hold are drawn strong.
//!
//! Like the run's own figures, the bytes are a pure function of the table (the embedded DejaVu
//! Sans font; no clock).

// Figures may use the host's f64 functions: a PNG is not promised byte-identical across
// machines (clippy.toml, docs/limits-and-failures.md).
#![allow(clippy::disallowed_methods)]

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::SweepError;
use super::spec::Axis;
use crate::plot::canvas::{FONT_FAMILY, INK, register_font, write_png};
use swarm::summary::{SIGNIFICANCE, sign_test_p};

/// Where a claim holds (Okabe–Ito blue).
const HOLDS: RGBColor = RGBColor(0, 114, 178);
/// Where more repeats go the claimed way, not enough to say so.
const UNSURE: RGBColor = RGBColor(158, 202, 230);
/// Where as many or more repeats go the other way.
const FAILS: RGBColor = RGBColor(245, 196, 160);
/// Where the opposite holds (Okabe–Ito vermillion).
const OPPOSITE: RGBColor = RGBColor(213, 94, 0);
/// A cell without data.
const NO_DATA: RGBColor = RGBColor(215, 215, 215);

/// One point's result for one claim.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointClaim {
    /// Repeats for the claim.
    pub for_: u32,
    /// Repeats against it.
    pub against: u32,
    /// Repeats with a value on both sides.
    pub defined: u32,
    /// The difference of the point's two means, positive when they agree with the claim, when
    /// both have one.
    pub effect: Option<f64>,
}

/// One claim's results over the points, in point order.
#[derive(Clone, Debug, PartialEq)]
pub struct ClaimSeries {
    /// The claim's column name (`claim.SLUG.…`), also its figure's file name.
    pub slug: String,
    /// The claim's text (the figure's title).
    pub text: String,
    /// Whether it is one of the paper's own text claims.
    pub paper: bool,
    /// Per point, its result, or nothing when the point did not finish.
    pub per_point: Vec<Option<PointClaim>>,
}

/// A cell's pooled outcome.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellOutcome {
    /// The pooled sign test says so.
    Holds,
    /// More repeats for than against, not enough to say so.
    Unsure,
    /// As many or more against.
    Fails,
    /// The pooled sign test says the opposite.
    Opposite,
    /// No finished point, or no repeat with a value on both sides.
    NoData,
}

impl CellOutcome {
    fn colour(self) -> RGBColor {
        match self {
            CellOutcome::Holds => HOLDS,
            CellOutcome::Unsure => UNSURE,
            CellOutcome::Fails => FAILS,
            CellOutcome::Opposite => OPPOSITE,
            CellOutcome::NoData => NO_DATA,
        }
    }

    fn word(self) -> &'static str {
        match self {
            CellOutcome::Holds => "holds",
            CellOutcome::Unsure => "unsure",
            CellOutcome::Fails => "fails",
            CellOutcome::Opposite => "opposite",
            CellOutcome::NoData => "no data",
        }
    }
}

/// The points of one cell of a map.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cell {
    /// Repeats for the claim, over the cell's points.
    pub for_: u32,
    /// Repeats against it.
    pub against: u32,
    /// Repeats with a value on both sides.
    pub defined: u32,
    /// Effects of its points that have one.
    pub effects: Vec<f64>,
    /// Points finished.
    pub finished: usize,
    /// Points planned.
    pub planned: usize,
}

impl Cell {
    /// The pooled outcome.
    #[must_use]
    pub fn outcome(&self) -> CellOutcome {
        let n = self.for_ + self.against;
        if self.defined == 0 {
            CellOutcome::NoData
        } else if sign_test_p(self.for_, n) < SIGNIFICANCE {
            CellOutcome::Holds
        } else if sign_test_p(self.against, n) < SIGNIFICANCE {
            CellOutcome::Opposite
        } else if self.for_ > self.against {
            CellOutcome::Unsure
        } else {
            CellOutcome::Fails
        }
    }

    fn mean_effect(&self) -> Option<f64> {
        (!self.effects.is_empty())
            .then(|| self.effects.iter().sum::<f64>() / self.effects.len() as f64)
    }
}

/// The cells of a claim: one per combination of the axes' values, in the order of
/// [`cell_index`].
#[must_use]
pub fn cells(axes: &[Axis], coords: &[Vec<usize>], s: &ClaimSeries) -> Vec<Cell> {
    let n: usize = axes.iter().map(|a| a.values.len()).product();
    let mut out = vec![Cell::default(); n.max(1)];
    for (c, v) in coords.iter().zip(&s.per_point) {
        let cell = &mut out[cell_index(axes, c)];
        cell.planned += 1;
        if let Some(p) = v {
            cell.finished += 1;
            cell.for_ += p.for_;
            cell.against += p.against;
            cell.defined += p.defined;
            if let Some(e) = p.effect {
                cell.effects.push(e);
            }
        }
    }
    out
}

/// The cell of a point's coordinates: the first axis varies slowest.
#[must_use]
pub fn cell_index(axes: &[Axis], coords: &[usize]) -> usize {
    axes.iter()
        .zip(coords)
        .fold(0, |i, (a, &c)| i * a.values.len() + c)
}

/// The values of cell `index`: (axis name, value label) per axis.
#[must_use]
pub fn cell_values(axes: &[Axis], mut index: usize) -> Vec<(String, String)> {
    let mut out = Vec::with_capacity(axes.len());
    for a in axes.iter().rev() {
        let n = a.values.len().max(1);
        out.push((a.name(), a.label(index % n)));
        index /= n;
    }
    out.reverse();
    out
}

/// The region: the cells where every one of `paper` holds (pooled over seeds), and how many
/// cells have data for all of them. Empty without claims.
#[must_use]
pub fn region(axes: &[Axis], coords: &[Vec<usize>], paper: &[&ClaimSeries]) -> (Vec<usize>, usize) {
    if paper.is_empty() {
        return (Vec::new(), 0);
    }
    let per_claim: Vec<Vec<Cell>> = paper.iter().map(|s| cells(axes, coords, s)).collect();
    let n = per_claim[0].len();
    let all =
        |i: usize, o: &dyn Fn(CellOutcome) -> bool| per_claim.iter().all(|c| o(c[i].outcome()));
    let inside = (0..n)
        .filter(|&i| all(i, &|o| o == CellOutcome::Holds))
        .collect();
    let with_data = (0..n)
        .filter(|&i| all(i, &|o| o != CellOutcome::NoData))
        .count();
    (inside, with_data)
}

fn tool(path: &Path, e: impl std::fmt::Display) -> SweepError {
    SweepError::tool(format!("drawing `{}`: {e}", path.display()))
}

/// An effect with three significant digits and its sign.
fn fmt_effect(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:+.digits$}")
}

/// Splits a title into lines of at most `width` characters at spaces.
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for word in text.split_whitespace() {
        let last = lines.last_mut().map_or(0, |l| l.len());
        if last > 0 && last + 1 + word.len() > width {
            lines.push(String::new());
        }
        if let Some(l) = lines.last_mut() {
            if !l.is_empty() {
                l.push(' ');
            }
            l.push_str(word);
        }
    }
    lines
}

/// Draws every claim's map, and the region of the paper's text claims when there are any,
/// into `dir`; returns the files written.
///
/// # Errors
/// A figure that cannot be drawn or written (tool).
pub fn claim_figures(
    axes: &[Axis],
    coords: &[Vec<usize>],
    series: &[ClaimSeries],
    dir: &Path,
) -> Result<Vec<PathBuf>, SweepError> {
    register_font().map_err(|e| tool(dir, e))?;
    let mut written = Vec::new();
    if axes.is_empty() {
        return Ok(written);
    }
    let grid = Grid::new(axes);
    for s in series {
        if s.per_point.iter().all(Option::is_none) {
            continue;
        }
        let path = dir.join(format!("{}.png", s.slug));
        draw_map(&path, &grid, &claim_map(&s.text, &cells(axes, coords, s)))?;
        written.push(path);
    }
    let paper: Vec<&ClaimSeries> = series.iter().filter(|s| s.paper).collect();
    if !paper.is_empty()
        && paper
            .iter()
            .any(|s| s.per_point.iter().any(Option::is_some))
    {
        let path = dir.join("region.png");
        let per_claim: Vec<Vec<Cell>> = paper.iter().map(|s| cells(axes, coords, s)).collect();
        draw_map(&path, &grid, &region_map(&paper, &per_claim))?;
        written.push(path);
    }
    Ok(written)
}

/// What a map shows: its title, each cell's three lines of label and its fill (a colour, and
/// whether the label is drawn on it in white), the key and the note under it.
struct Map<'a> {
    title: String,
    labels: Vec<[String; 3]>,
    fills: Vec<(RGBColor, bool)>,
    key: Vec<(RGBColor, &'a str)>,
    note: &'a str,
}

/// One claim's map: each cell's outcome, its repeats for the claim of those with a value, and
/// the mean effect.
fn claim_map(text: &str, cells: &[Cell]) -> Map<'static> {
    let labels: Vec<[String; 3]> = cells
        .iter()
        .map(|c| {
            let o = c.outcome();
            if o == CellOutcome::NoData {
                return [
                    "no data".into(),
                    format!("{}/{} points", c.finished, c.planned),
                    String::new(),
                ];
            }
            [
                o.word().to_string(),
                format!("{}/{}", c.for_, c.defined),
                c.mean_effect().map_or_else(String::new, fmt_effect),
            ]
        })
        .collect();
    let fills: Vec<(RGBColor, bool)> = cells
        .iter()
        .map(|c| {
            let o = c.outcome();
            (
                o.colour(),
                matches!(o, CellOutcome::Holds | CellOutcome::Opposite),
            )
        })
        .collect();
    let note = "each cell pools its seeds: outcome of the one-sided sign test on all their repeats (holds, unsure, fails, opposite), repeats for the claim / repeats with a value, mean effect over its points (positive: the means agree with the claim)";
    let key: Vec<(RGBColor, &str)> = [
        CellOutcome::Holds,
        CellOutcome::Unsure,
        CellOutcome::Fails,
        CellOutcome::Opposite,
        CellOutcome::NoData,
    ]
    .iter()
    .map(|o| (o.colour(), o.word()))
    .collect();
    Map {
        title: text.to_string(),
        labels,
        fills,
        key,
        note,
    }
}

/// The map of where the paper's text claims (`paper`, their cells `per_claim`) hold together:
/// in each cell, how many hold and which.
fn region_map(paper: &[&ClaimSeries], per_claim: &[Vec<Cell>]) -> Map<'static> {
    let k = paper.len();
    let n = per_claim[0].len();
    let mut labels = Vec::with_capacity(n);
    let mut fills = Vec::with_capacity(n);
    let outcomes = |i: usize| per_claim.iter().map(move |c| c[i].outcome());
    for i in 0..n {
        let holding: Vec<usize> = outcomes(i)
            .enumerate()
            .filter(|(_, o)| *o == CellOutcome::Holds)
            .map(|(j, _)| j)
            .collect();
        let data = outcomes(i).any(|o| o != CellOutcome::NoData);
        let all = holding.len() == k;
        let names: Vec<String> = holding.iter().map(|j| (j + 1).to_string()).collect();
        labels.push([
            if all {
                "ALL HOLD".to_string()
            } else if data {
                format!("{} of {k}", holding.len())
            } else {
                "no data".to_string()
            },
            if names.is_empty() {
                "-".into()
            } else {
                names.join(" ")
            },
            String::new(),
        ]);
        let shade = |t: f64| {
            let mix = |w: u8, b: u8| (f64::from(w) * (1.0 - t) + f64::from(b) * t).round() as u8;
            RGBColor(mix(255, UNSURE.0), mix(255, UNSURE.1), mix(255, UNSURE.2))
        };
        fills.push(if all {
            (HOLDS, true)
        } else if !data {
            (NO_DATA, false)
        } else {
            (shade(holding.len() as f64 / k as f64), false)
        });
    }
    let mut title = "Where the paper's text claims hold together (pooled over seeds):".to_string();
    for (j, s) in paper.iter().enumerate() {
        let short = s.text.split(':').next().unwrap_or(&s.text);
        title.push_str(&format!(" {} {short};", j + 1));
    }
    title.pop();
    let key = vec![
        (HOLDS, "all hold"),
        (UNSURE, "some hold"),
        (RGBColor(255, 255, 255), "none holds"),
        (NO_DATA, "no data"),
    ];
    let note = "each cell: how many of the claims hold there (pooled sign test at p < 0.05) and which (their numbers)";
    Map {
        title,
        labels,
        fills,
        key,
        note,
    }
}

/// The layout of a map: cells in panels, panels in a grid.
struct Grid {
    /// (axis, label) down a panel.
    rows: (String, Vec<String>),
    /// (axis, label) across a panel.
    cols: (String, Vec<String>),
    /// One title per panel, in the order of the cells (the further axes' combinations).
    panels: Vec<String>,
    /// Panels per row of the grid.
    per_row: usize,
}

impl Grid {
    fn new(axes: &[Axis]) -> Self {
        let labels = |a: &Axis| (0..a.values.len()).map(|i| a.label(i)).collect::<Vec<_>>();
        let (rows, cols) = match axes.len() {
            1 => (
                (String::new(), vec![String::new()]),
                (axes[0].name(), labels(&axes[0])),
            ),
            _ => (
                (axes[0].name(), labels(&axes[0])),
                (axes[1].name(), labels(&axes[1])),
            ),
        };
        let further = if axes.len() > 2 { &axes[2..] } else { &[][..] };
        let mut panels = vec![String::new()];
        for a in further {
            let mut next = Vec::new();
            for p in &panels {
                for i in 0..a.values.len() {
                    let sep = if p.is_empty() { "" } else { ", " };
                    next.push(format!("{p}{sep}{} = {}", short_name(a), a.label(i)));
                }
            }
            panels = next;
        }
        let per_row = further.last().map_or(1, |a| a.values.len()).clamp(1, 4);
        Self {
            rows,
            cols,
            panels,
            per_row,
        }
    }
}

/// An axis' name without its keys' table prefixes (`world.mu_wall` → `mu_wall`).
fn short_name(a: &Axis) -> String {
    a.keys
        .iter()
        .map(|k| k.rsplit('.').next().unwrap_or(k))
        .collect::<Vec<_>>()
        .join("+")
}

/// Cell size, pixels.
const CELL_W: i32 = 104;
const CELL_H: i32 = 62;
/// Room for the row labels left of a panel and the panel's title above it.
const PANEL_LEFT: i32 = 96;
const PANEL_TOP: i32 = 50;
/// Space between panels.
const PANEL_GAP: i32 = 26;

/// Draws `map` on the grid `g` into the PNG file `path`, sized to hold its panels.
fn draw_map(path: &Path, g: &Grid, map: &Map<'_>) -> Result<(), SweepError> {
    let (nr, nc) = (g.rows.1.len() as i32, g.cols.1.len() as i32);
    let panel_w = PANEL_LEFT + nc * CELL_W;
    let panel_h = PANEL_TOP + nr * CELL_H + 30;
    let per_row = g.per_row as i32;
    let grid_rows = (g.panels.len() as i32 + per_row - 1) / per_row;
    let width = (40 + per_row * (panel_w + PANEL_GAP)).max(1000);
    let title_lines = wrap(&map.title, (width as usize / 11).max(40));
    let top = 20 + 26 * title_lines.len() as i32 + 60;
    let height = top + grid_rows * (panel_h + PANEL_GAP) + 70;
    let size = (width as u32, height as u32);
    let mut rgb = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_map_on(&root, g, &title_lines, map, top).map_err(|e| tool(path, e))?;
        root.present().map_err(|e| tool(path, e))?;
    }
    write_png(path, size, &rgb).map_err(|e| tool(path, e))
}

/// Draws `map` on `root`: the title's lines, the key, the panels from `top` down, the note.
fn draw_map_on(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    g: &Grid,
    title_lines: &[String],
    map: &Map<'_>,
    top: i32,
) -> Result<(), String> {
    let (labels, fills, key, note) = (&map.labels, &map.fills, &map.key, map.note);
    let e = |e: DrawingAreaErrorKind<_>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let title_font = (FONT_FAMILY, 20).into_font().color(&INK);
    for (i, l) in title_lines.iter().enumerate() {
        root.draw_text(l, &title_font, (20, 16 + 26 * i as i32))
            .map_err(e)?;
    }
    let small = (FONT_FAMILY, 14).into_font().color(&INK);
    let left_text = small.pos(Pos::new(HPos::Left, VPos::Center));
    // The key, and which axis runs where.
    let mut kx = 20;
    let ky = top - 44;
    for (c, word) in key {
        root.draw(&Rectangle::new(
            [(kx, ky - 9), (kx + 22, ky + 9)],
            c.filled(),
        ))
        .map_err(e)?;
        root.draw(&Rectangle::new(
            [(kx, ky - 9), (kx + 22, ky + 9)],
            INK.mix(0.4),
        ))
        .map_err(e)?;
        root.draw_text(word, &left_text, (kx + 28, ky)).map_err(e)?;
        kx += 40 + 9 * word.len() as i32;
    }
    let axes_text = if g.rows.0.is_empty() {
        format!("across: {}", g.cols.0)
    } else {
        format!("down: {}; across: {}", g.rows.0, g.cols.0)
    };
    root.draw_text(&axes_text, &left_text, (kx + 30, ky))
        .map_err(e)?;

    let (nr, nc) = (g.rows.1.len(), g.cols.1.len());
    let panel_w = PANEL_LEFT + nc as i32 * CELL_W;
    let panel_h = PANEL_TOP + nr as i32 * CELL_H + 30;
    let centred = |ink: &RGBColor, px: i32| {
        (FONT_FAMILY, px)
            .into_font()
            .color(ink)
            .pos(Pos::new(HPos::Center, VPos::Center))
    };
    for (p, name) in g.panels.iter().enumerate() {
        let px = 20 + (p % g.per_row) as i32 * (panel_w + PANEL_GAP);
        let py = top + (p / g.per_row) as i32 * (panel_h + PANEL_GAP);
        let panel_font = (FONT_FAMILY, 14).into_font().color(&INK);
        for (k, l) in wrap(name, (panel_w as usize / 8).max(20))
            .iter()
            .take(2)
            .enumerate()
        {
            root.draw_text(l, &panel_font, (px, py + 2 + 18 * k as i32))
                .map_err(e)?;
        }
        let x0 = px + PANEL_LEFT;
        let y0 = py + PANEL_TOP;
        for (r, label) in g.rows.1.iter().enumerate() {
            let y = y0 + r as i32 * CELL_H + CELL_H / 2;
            root.draw_text(
                label,
                &small.pos(Pos::new(HPos::Right, VPos::Center)),
                (x0 - 8, y),
            )
            .map_err(e)?;
        }
        for (c, label) in g.cols.1.iter().enumerate() {
            let x = x0 + c as i32 * CELL_W + CELL_W / 2;
            root.draw_text(
                label,
                &small.pos(Pos::new(HPos::Center, VPos::Top)),
                (x, y0 + nr as i32 * CELL_H + 6),
            )
            .map_err(e)?;
        }
        for r in 0..nr {
            for c in 0..nc {
                // The further axes vary fastest in a cell's index.
                let i = (r * nc + c) * g.panels.len() + p;
                let (Some((fill, strong)), Some(text)) = (fills.get(i), labels.get(i)) else {
                    continue;
                };
                let cx0 = x0 + c as i32 * CELL_W;
                let cy0 = y0 + r as i32 * CELL_H;
                let rect = [(cx0, cy0), (cx0 + CELL_W, cy0 + CELL_H)];
                root.draw(&Rectangle::new(rect, fill.filled())).map_err(e)?;
                root.draw(&Rectangle::new(rect, INK.mix(0.25))).map_err(e)?;
                let ink = if *strong { WHITE } else { INK };
                let (mx, my) = (cx0 + CELL_W / 2, cy0 + CELL_H / 2);
                let lines: Vec<&String> = text.iter().filter(|t| !t.is_empty()).collect();
                let step = 17;
                let y_first = my - step * (lines.len() as i32 - 1) / 2;
                for (k, t) in lines.iter().enumerate() {
                    let size = if k == 0 { 15 } else { 13 };
                    root.draw_text(t, &centred(&ink, size), (mx, y_first + step * k as i32))
                        .map_err(e)?;
                }
            }
        }
    }
    let (w, h) = root.dim_in_pixel();
    let lines = wrap(note, (w as usize / 8).max(40));
    for (i, l) in lines.iter().enumerate() {
        let y = h as i32 - 14 - 18 * (lines.len() - i) as i32;
        root.draw_text(l, &small, (20, y)).map_err(e)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effects_keep_three_digits_and_a_sign() {
        assert_eq!(fmt_effect(0.012345), "+0.0123");
        assert_eq!(fmt_effect(-123.45), "-123");
        assert_eq!(fmt_effect(0.0), "0");
    }

    #[test]
    fn titles_wrap_at_spaces() {
        assert_eq!(wrap("aa bb cc", 5), vec!["aa bb", "cc"]);
    }

    fn axis(n: usize) -> Axis {
        Axis {
            keys: vec!["k".into()],
            values: (0..n)
                .map(|i| vec![toml::Value::Integer(i as i64)])
                .collect(),
        }
    }

    #[test]
    fn cells_pool_their_seeds_and_judge_all_their_repeats() {
        let axes = [axis(2), axis(3)];
        // Two seeds per cell; cell (1, 2) gets 4 + 5 of 10 + 10 repeats for: 9 of 20 does not
        // hold; cell (0, 0) gets 9 + 8 of 10 + 10: 17 of 20 holds (p = 0.0013).
        let coords = vec![vec![0, 0], vec![0, 0], vec![1, 2], vec![1, 2], vec![0, 1]];
        let pc = |f: u32, e: f64| {
            Some(PointClaim {
                for_: f,
                against: 10 - f,
                defined: 10,
                effect: Some(e),
            })
        };
        let s = ClaimSeries {
            slug: "x".into(),
            text: "x".into(),
            paper: true,
            per_point: vec![pc(9, 1.0), pc(8, 3.0), pc(4, -1.0), pc(5, 0.0), None],
        };
        let c = cells(&axes, &coords, &s);
        assert_eq!(c.len(), 6);
        let a = &c[cell_index(&axes, &[0, 0])];
        assert_eq!((a.for_, a.against, a.defined, a.finished), (17, 3, 20, 2));
        assert_eq!(a.outcome(), CellOutcome::Holds);
        assert_eq!(a.mean_effect(), Some(2.0));
        let b = &c[cell_index(&axes, &[1, 2])];
        assert_eq!(b.outcome(), CellOutcome::Fails);
        let none = &c[cell_index(&axes, &[0, 1])];
        assert_eq!((none.planned, none.finished), (1, 0));
        assert_eq!(none.outcome(), CellOutcome::NoData);
        // 2 for, 18 against: the opposite holds.
        let opposite = Cell {
            for_: 2,
            against: 18,
            defined: 20,
            ..Cell::default()
        };
        assert_eq!(opposite.outcome(), CellOutcome::Opposite);
    }

    #[test]
    fn cell_indices_run_the_first_axis_slowest() {
        let axes = [axis(2), axis(3), axis(4)];
        assert_eq!(cell_index(&axes, &[0, 0, 1]), 1);
        assert_eq!(cell_index(&axes, &[0, 1, 0]), 4);
        assert_eq!(cell_index(&axes, &[1, 0, 0]), 12);
        assert_eq!(cell_index(&axes, &[1, 2, 3]), 23);
    }
}
