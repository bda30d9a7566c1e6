//! The experiment's figures, drawn with `plotters`.
//!
//! * [`learning_figure`]: the paper's Fig. 6/7 — left panel the mean over robots of the summed
//!   sensor distance D (du), right panel the collisions per robot, both per window of learning
//!   steps, as a PNG and an SVG of the same drawing. Each [`Series`] is a mean over repeats with a
//!   band `[lo, hi]`; the learning run is drawn solid over a translucent band, the controls the
//!   paper lacks (learning off, random walk) dashed.
//! * [`arena_figure`]: the paper's Fig. 8 — the arena seen from above, in metres at equal aspect
//!   ratio, with every robot's trajectory and its outline at a few instants ([`Outline`](swarm::experiment::Outline)).
//!
//! Choices where the spec is silent (docs/design.md §5 names the metrics, not the drawing):
//! * **Font.** DejaVu Sans 2.37 (`assets/DejaVuSans.ttf`, licence in
//!   `assets/DejaVuSans-LICENSE.txt`) is compiled into the binary and registered in plotters'
//!   `ab_glyph` font table as `"sans-serif"`, so figures render identically on a machine without
//!   system fonts. The SVG names the family `sans-serif`; a viewer draws it with its own sans face,
//!   laid out with DejaVu's metrics.
//! * **Colours.** Learning curves take the Okabe–Ito colour-blind-safe palette by *label*, in
//!   order of first appearance (so a label has one colour in both panels and in the legend);
//!   robots take the ten-colour "tab10" palette by index, cycled for larger swarms.
//! * **Data are drawn as given.** Nothing is smoothed. Axis ranges cover every mean and band
//!   value; a panel whose values are all ≥ 0 (collisions, D) starts at 0 only when that costs
//!   little room (the lowest value is within 30 % of the span from 0). Arena paths are thinned
//!   only below one pixel, which changes no pixel's meaning but keeps a 100-robot,
//!   10 000-step figure fast.
//! * **Snapshot times** are told apart by fill strength: the earliest outline is faintest, the
//!   latest strongest; the legend maps each strength to its time. A filled triangle inside each
//!   outline points along the heading.
//! * **Robustness.** Every input is checked before anything is drawn: an empty or non-finite
//!   series, mismatched lengths, x not strictly increasing, an outline of a robot that has no
//!   path, a zero heading: each is a [`PlotError`] naming the series or item, and no file is
//!   written. A drawing is rendered in memory first, so a failure never leaves half a file.
//!   Parent folders are not created: that is the caller's job.
//! * **Determinism.** The bytes written are a pure function of the input (no clock, no
//!   randomness, no hash-map order).

// Figures may use the host's f64 functions: a PNG is not promised byte-identical across
// machines (clippy.toml, docs/limits-and-failures.md).
#![allow(clippy::disallowed_methods)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use swarm::experiment::Outline;

/// Size in pixels of the learning figure (PNG and SVG): two panels side by side, with a
/// one-row legend under them. Each further legend row (many or long labels) adds
/// [`LEGEND_ROW_PX`] to the height.
pub const LEARNING_SIZE_PX: (u32, u32) = (1600, 700);

/// Height of one row of the learning figure's legend, pixels.
pub const LEGEND_ROW_PX: u32 = 36;

/// Largest magnitude accepted for a learning-figure value (x, mean, lo, hi). Larger finite
/// values would overflow the axis arithmetic of plotters 0.3.7 (it panics or loops on an
/// infinite span); no step count, D or collision rate comes near it.
pub const MAX_ABS_VALUE: f64 = 1e12;

/// Largest magnitude accepted for an arena coordinate, metres (1 000 km).
pub const MAX_ABS_COORD_M: f64 = 1e6;

/// DejaVu Sans 2.37 from Debian's fonts-dejavu-core; licence in assets/DejaVuSans-LICENSE.txt.
static DEJAVU_SANS_TTF: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Family name under which the embedded font is registered (plotters' default family).
const FONT_FAMILY: &str = "sans-serif";

/// Okabe & Ito (2008) colour-blind-safe palette, without its yellow (too pale on white).
const CURVE_PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(0, 0, 0),       // black
];

/// The ten-colour "tab10" categorical palette (Tableau 10), cycled over robots.
const ROBOT_PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Colour of text and axes: a soft black.
const INK: RGBColor = RGBColor(34, 34, 34);
/// Colour of arena walls.
const WALL_COLOUR: RGBColor = RGBColor(40, 40, 40);

/// One curve with a band: x = step (window centre), mean over repeats, band = `[lo, hi]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text, e.g. `"learning (3 robots)"`, `"learning off"`, `"random walk"`.
    pub label: String,
    /// Draw the line dashed (the controls) instead of solid (the learning runs).
    pub dashed: bool,
    /// Window centres in learning steps; strictly increasing.
    pub x: Vec<f64>,
    /// Mean over repeats at each x.
    pub mean: Vec<f64>,
    /// Lower edge of the band at each x (e.g. the minimum over repeats).
    pub lo: Vec<f64>,
    /// Upper edge of the band at each x (e.g. the maximum over repeats).
    pub hi: Vec<f64>,
    /// How many repeats each point rests on (empty: all of them, [`Series::repeats`]). A point
    /// resting on fewer is drawn as an open circle with its count beside it, and no band is
    /// drawn through it.
    pub n: Vec<usize>,
    /// The repeats the series' condition ran (0: not said).
    pub repeats: usize,
}

impl Series {
    /// Whether point `i` rests on every repeat.
    #[must_use]
    pub fn full(&self, i: usize) -> bool {
        self.n.get(i).is_none_or(|&n| n >= self.repeats)
    }
}

/// The paper's Fig. 6/7: left panel mean D per window (du), right panel collisions per robot per
/// window.
#[derive(Debug, Clone, PartialEq)]
pub struct LearningFigure {
    /// Title over both panels, e.g. `"Arena, 3 robots, 5 repeats (paper Fig. 7)"`.
    pub title: String,
    /// Label of both x axes, e.g. `"learning step"`.
    pub x_label: String,
    /// Series of the left panel: mean over robots of the summed sensor distance D, in du.
    pub d: Vec<Series>,
    /// Series of the right panel: collisions per robot per window.
    pub collisions: Vec<Series>,
    /// Further panels (at most eight, e.g. collisions per net metre, net progress, contact
    /// time and the corridor's gap CV), drawn two to a row under the first two; none keeps the
    /// paper's two-panel figure.
    pub more: Vec<Panel>,
    /// The share of held robot-steps per condition (percent, labels as in the panels), drawn
    /// dotted on a right-hand axis of 0–100 % in the collisions panel and in every further
    /// panel that asks for it, so a falling collision curve is read beside the robots held in
    /// place; none draws no overlay.
    pub held: Vec<Series>,
    /// Mark every point (a run with few windows, whose lines are no trend).
    pub markers: bool,
}

/// A further panel of the learning figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Caption over the panel.
    pub caption: String,
    /// Label of its y axis.
    pub y_label: String,
    /// Its series (checked like the first two panels').
    pub series: Vec<Series>,
    /// Draw [`LearningFigure::held`] on a right-hand axis.
    pub held_overlay: bool,
}

/// The paper's Fig. 8: the arena from above with every robot's trajectory and its outline at a
/// few instants. All coordinates are in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct ArenaFigure {
    /// Title over the arena, e.g. `"Arena, 3 robots, seed 1"`.
    pub title: String,
    /// Wall segments, each from one end to the other, in metres.
    pub walls: Vec<[(f64, f64); 2]>,
    /// One trajectory per robot (index = robot number), in metres; a path may be empty.
    pub paths: Vec<Vec<(f64, f64)>>,
    /// Robot outlines at chosen instants.
    pub outlines: Vec<Outline>,
}

/// The corridor seen over time: each robot's position along the corridor against the learning
/// step, its body drawn as a band (its centre ± half its length), so the gaps between
/// neighbours are the white space between the bands and an even spacing shows as parallel
/// bands.
#[derive(Debug, Clone, PartialEq)]
pub struct SpaceTimeFigure {
    /// Title.
    pub title: String,
    /// The corridor's length, metres (the y axis runs from 0 to it).
    pub length_m: f64,
    /// A robot's length along the corridor, metres (the band's width).
    pub body_m: f64,
    /// One path per robot: (learning step, position along the corridor in metres), steps
    /// increasing.
    pub paths: Vec<Vec<(f64, f64)>>,
}

/// Why a figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A panel of the learning figure has no series.
    #[error("the {panel} panel has no series; give at least one")]
    NoSeries {
        /// `"D"` or `"collisions"`.
        panel: &'static str,
    },
    /// A series has no points.
    #[error("{panel} series {index} ({label:?}) has no points; give at least one")]
    EmptySeries {
        /// `"D"` or `"collisions"`.
        panel: &'static str,
        /// Position of the series in its panel's list.
        index: usize,
        /// The series' label.
        label: String,
    },
    /// The four vectors of a series differ in length.
    #[error(
        "{panel} series {index} ({label:?}): x has {x} points, mean {mean}, lo {lo}, hi {hi}; \
         all four must have the same length"
    )]
    LengthMismatch {
        /// `"D"` or `"collisions"`.
        panel: &'static str,
        /// Position of the series in its panel's list.
        index: usize,
        /// The series' label.
        label: String,
        /// Length of `x`.
        x: usize,
        /// Length of `mean`.
        mean: usize,
        /// Length of `lo`.
        lo: usize,
        /// Length of `hi`.
        hi: usize,
    },
    /// A series' repeat counts do not match its points.
    #[error(
        "{panel} series {index} ({label:?}): x has {x} points but n has {n} counts; give one \
         per point or none"
    )]
    CountMismatch {
        /// The panel.
        panel: &'static str,
        /// Position of the series in its panel's list.
        index: usize,
        /// The series' label.
        label: String,
        /// Length of `x`.
        x: usize,
        /// Length of `n`.
        n: usize,
    },
    /// A value of a series is NaN, infinite or beyond ±[`MAX_ABS_VALUE`].
    #[error(
        "{panel} series {index} ({label:?}): {field}[{at}] is {value}; every value must be \
         finite and within ±{MAX_ABS_VALUE:e}"
    )]
    BadValue {
        /// `"D"` or `"collisions"`.
        panel: &'static str,
        /// Position of the series in its panel's list.
        index: usize,
        /// The series' label.
        label: String,
        /// `"x"`, `"mean"`, `"lo"` or `"hi"`.
        field: &'static str,
        /// Index of the bad value.
        at: usize,
        /// The bad value.
        value: f64,
    },
    /// The x values of a series do not increase strictly.
    #[error(
        "{panel} series {index} ({label:?}): x[{at}] = {value} does not exceed the x before it \
         ({previous}); x must increase strictly"
    )]
    NotIncreasing {
        /// `"D"` or `"collisions"`.
        panel: &'static str,
        /// Position of the series in its panel's list.
        index: usize,
        /// The series' label.
        label: String,
        /// Index of the offending x.
        at: usize,
        /// The offending x.
        value: f64,
        /// The x before it.
        previous: f64,
    },
    /// A coordinate, time or heading of the arena figure is NaN or infinite, or a coordinate
    /// lies beyond ±[`MAX_ABS_COORD_M`].
    #[error(
        "arena figure: {item} is {value}; every number must be finite and every coordinate \
         within ±{MAX_ABS_COORD_M:e} m"
    )]
    ArenaBadValue {
        /// Which item, e.g. `"path of robot 2, point 17"`.
        item: String,
        /// The bad value.
        value: f64,
    },
    /// An outline names a robot that has no entry in `paths`.
    #[error(
        "arena figure: outline {index} is of robot {robot}, but there are {robots} paths \
         (robots 0..{robots}); give one path, possibly empty, per robot"
    )]
    UnknownRobot {
        /// Position of the outline in the list.
        index: usize,
        /// The robot it names.
        robot: usize,
        /// Number of paths given.
        robots: usize,
    },
    /// An outline's heading is the zero vector.
    #[error("arena figure: outline {index} has heading (0, 0); give a unit vector")]
    ZeroHeading {
        /// Position of the outline in the list.
        index: usize,
    },
    /// The arena figure has no wall, no path point and no outline.
    #[error("arena figure: nothing to draw (no walls, no path points, no outlines)")]
    NothingToDraw,
    /// A PNG output path does not end in `.png`.
    #[error("{}: a PNG figure's file name must end in .png", path.display())]
    NotPng {
        /// The path given.
        path: PathBuf,
    },
    /// An output file could not be written.
    #[error("could not write {}: {reason}", path.display())]
    Write {
        /// The file that could not be written.
        path: PathBuf,
        /// What the system said.
        reason: String,
    },
    /// Drawing failed (in practice: text could not be laid out).
    #[error("drawing {} failed: {reason}", path.display())]
    Draw {
        /// The file being drawn.
        path: PathBuf,
        /// What plotters said.
        reason: String,
    },
    /// The embedded font could not be parsed (a corrupt build).
    #[error("the embedded DejaVu Sans font could not be loaded")]
    Font,
}

// ---------------------------------------------------------------------------------------------
// Learning figure
// ---------------------------------------------------------------------------------------------

/// Height of the title strip of the learning figure, pixels.
const LEARNING_TITLE_PX: u32 = 56;
/// Length of a legend's line sample, pixels.
const LEGEND_SAMPLE_PX: i32 = 56;
/// Stroke width of a curve, pixels.
const CURVE_WIDTH_PX: u32 = 3;

/// Draws the learning figure (paper Fig. 6/7) into `png` and `svg`.
///
/// Both files show the same drawing, [`LEARNING_SIZE_PX`] pixels (taller by [`LEGEND_ROW_PX`]
/// per extra legend row). Colours go by label, so a label has the same colour in both panels;
/// the palette has 7 colours and repeats after that. `png` must end in `.png`. Nothing is
/// written unless every series is valid.
pub fn learning_figure(fig: &LearningFigure, png: &Path, svg: &Path) -> Result<(), PlotError> {
    validate_panel("D", &fig.d)?;
    validate_panel("collisions", &fig.collisions)?;
    for p in fig.more.iter().take(MAX_MORE_PANELS) {
        validate_panel("further", &p.series)?;
    }
    if !fig.held.is_empty() {
        validate_panel("held", &fig.held)?;
    }
    check_png_name(png)?;
    register_font()?;
    let styles = CurveStyles::new(fig);
    let (w, mut h) = LEARNING_SIZE_PX;
    h += more_rows(fig) * (LEARNING_SIZE_PX.1 - LEARNING_TITLE_PX - 60);
    let rows = legend_rows(&styles, w as i32 - 60).map_err(|e| draw_error(png, e))?;
    let extra_rows = rows.len().saturating_sub(1) as u32 + u32::from(has_partial_points(fig));
    let size = (w, h + extra_rows * LEGEND_ROW_PX);

    let mut rgb = vec![0u8; (size.0 as usize) * (size.1 as usize) * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_learning(&root, fig, &styles, &rows).map_err(|e| draw_error(png, e))?;
        root.present().map_err(|e| draw_error(png, e))?;
    }
    write_png(png, size, &rgb)?;

    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw_learning(&root, fig, &styles, &rows).map_err(|e| draw_error(svg, e))?;
        root.present().map_err(|e| draw_error(svg, e))?;
    }
    std::fs::write(svg, text.as_bytes()).map_err(|e| write_error(svg, e))
}

/// Most further panels of the learning figure (four rows of two).
const MAX_MORE_PANELS: usize = 8;

/// Whether a panel's point rests on fewer than all repeats (the legend then says what its
/// open circle means).
fn has_partial_points(fig: &LearningFigure) -> bool {
    fig.d
        .iter()
        .chain(&fig.collisions)
        .chain(
            fig.more
                .iter()
                .take(MAX_MORE_PANELS)
                .flat_map(|p| &p.series),
        )
        .any(|s| (0..s.x.len()).any(|i| !s.full(i)))
}

/// Rows of further panels under the first two.
fn more_rows(fig: &LearningFigure) -> u32 {
    fig.more.len().min(MAX_MORE_PANELS).div_ceil(2) as u32
}

/// Checks one panel's series: present, non-empty, equal lengths, finite, x strictly increasing.
fn validate_panel(panel: &'static str, series: &[Series]) -> Result<(), PlotError> {
    if series.is_empty() {
        return Err(PlotError::NoSeries { panel });
    }
    for (index, s) in series.iter().enumerate() {
        let label = || s.label.clone();
        if s.x.is_empty() {
            return Err(PlotError::EmptySeries {
                panel,
                index,
                label: label(),
            });
        }
        let n = s.x.len();
        if s.mean.len() != n || s.lo.len() != n || s.hi.len() != n {
            return Err(PlotError::LengthMismatch {
                panel,
                index,
                label: label(),
                x: n,
                mean: s.mean.len(),
                lo: s.lo.len(),
                hi: s.hi.len(),
            });
        }
        for (field, values) in [("x", &s.x), ("mean", &s.mean), ("lo", &s.lo), ("hi", &s.hi)] {
            let bad = |v: &f64| !v.is_finite() || v.abs() > MAX_ABS_VALUE;
            if let Some((at, &value)) = values.iter().enumerate().find(|(_, v)| bad(v)) {
                return Err(PlotError::BadValue {
                    panel,
                    index,
                    label: label(),
                    field,
                    at,
                    value,
                });
            }
        }
        if !s.n.is_empty() && s.n.len() != n {
            return Err(PlotError::CountMismatch {
                panel,
                index,
                label: label(),
                x: n,
                n: s.n.len(),
            });
        }
        if let Some(at) = (1..n).find(|&i| s.x[i] <= s.x[i - 1]) {
            return Err(PlotError::NotIncreasing {
                panel,
                index,
                label: label(),
                at,
                value: s.x[at],
                previous: s.x[at - 1],
            });
        }
    }
    Ok(())
}

/// Colour and dash of each distinct label, in order of first appearance (left panel first).
struct CurveStyles {
    /// (label, colour, dashed) per distinct label.
    entries: Vec<(String, RGBColor, bool)>,
}

impl CurveStyles {
    fn new(fig: &LearningFigure) -> Self {
        let mut entries: Vec<(String, RGBColor, bool)> = Vec::new();
        let more = fig
            .more
            .iter()
            .take(MAX_MORE_PANELS)
            .flat_map(|p| p.series.iter());
        for s in fig.d.iter().chain(&fig.collisions).chain(more) {
            if !entries.iter().any(|(l, _, _)| *l == s.label) {
                let colour = CURVE_PALETTE[entries.len() % CURVE_PALETTE.len()];
                entries.push((s.label.clone(), colour, s.dashed));
            }
        }
        Self { entries }
    }

    fn colour(&self, label: &str) -> RGBColor {
        self.entries
            .iter()
            .find(|(l, _, _)| l == label)
            .map_or(INK, |(_, c, _)| *c)
    }
}

/// One row of the learning figure's legend: (entry index, width in pixels) per entry.
type LegendRow = Vec<(usize, i32)>;

/// Font size of the learning figure's legend, pixels.
const LEGEND_FONT_PX: f64 = 18.0;

/// Legend rows: entry indices per row, so that each row fits the figure's width.
fn legend_rows(styles: &CurveStyles, max_width: i32) -> Result<Vec<LegendRow>, String> {
    let font = FontDesc::new(
        FontFamily::Name(FONT_FAMILY),
        LEGEND_FONT_PX,
        FontStyle::Normal,
    );
    let mut rows: Vec<LegendRow> = vec![Vec::new()];
    let mut width: i32 = 0;
    for (i, (label, _, _)) in styles.entries.iter().enumerate() {
        let (tw, _) = font.box_size(label).map_err(|e| e.to_string())?;
        let entry = LEGEND_SAMPLE_PX + 10 + tw.min(i32::MAX as u32 / 2) as i32 + 40;
        if width.saturating_add(entry) > max_width && !rows.last().is_some_and(Vec::is_empty) {
            rows.push(Vec::new());
            width = 0;
        }
        width = width.saturating_add(entry);
        if let Some(row) = rows.last_mut() {
            row.push((i, entry));
        }
    }
    Ok(rows)
}

fn draw_learning<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &LearningFigure,
    styles: &CurveStyles,
    rows: &[LegendRow],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (w, h) = root.dim_in_pixel();
    let legend_font = (FONT_FAMILY, LEGEND_FONT_PX).into_font().color(&INK);
    let partial = has_partial_points(fig);
    let legend_px = (rows.len() as u32 + u32::from(partial)) * LEGEND_ROW_PX + 14;

    let (title_area, rest) = root.split_vertically(LEARNING_TITLE_PX);
    let (panels, legend_area) =
        rest.split_vertically(h.saturating_sub(LEARNING_TITLE_PX + legend_px));
    let title_font = (FONT_FAMILY, 27)
        .into_font()
        .color(&INK)
        .pos(Pos::new(HPos::Center, VPos::Center));
    title_area.draw_text(
        &fig.title,
        &title_font,
        ((w / 2) as i32, (LEARNING_TITLE_PX / 2) as i32 + 4),
    )?;

    let rows_of_panels = 1 + more_rows(fig);
    let areas = panels.split_evenly((rows_of_panels as usize, 2));
    let held = (!fig.held.is_empty()).then_some(fig.held.as_slice());
    let first = [
        Panel {
            caption: "Mean summed sensor distance D".into(),
            y_label: "mean summed distance D (du)".into(),
            series: fig.d.clone(),
            held_overlay: false,
        },
        Panel {
            caption: "Collisions".into(),
            y_label: "collisions per robot per window".into(),
            series: fig.collisions.clone(),
            held_overlay: true,
        },
    ];
    let all = first.iter().chain(fig.more.iter().take(MAX_MORE_PANELS));
    for (area, p) in areas.iter().zip(all) {
        draw_panel(
            area,
            p,
            &fig.x_label,
            held.filter(|_| p.held_overlay),
            fig.markers,
            styles,
        )?;
    }
    draw_curve_legend(&legend_area, styles, rows, &legend_font, partial)
}

/// Axis range of one panel: every mean and band value, padded; starts at 0 when the values are
/// all ≥ 0 and 0 is close (within 30 % of the span below the lowest value).
fn value_range(series: &[Series]) -> (f64, f64) {
    let values = series
        .iter()
        .flat_map(|s| s.mean.iter().chain(&s.lo).chain(&s.hi))
        .copied();
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    padded_range(lo, hi, lo >= 0.0 && lo <= 0.3 * (hi - lo))
}

/// `[lo, hi]` widened by 6 % of the span at both ends (1 unit, or 10 % of the value, if the span
/// is 0); the lower end is 0 when `from_zero`, and never below 0 when the data are ≥ 0.
fn padded_range(lo: f64, hi: f64, from_zero: bool) -> (f64, f64) {
    let span = hi - lo;
    let pad = if span > 0.0 {
        0.06 * span
    } else {
        (0.1 * lo.abs()).max(1.0)
    };
    let bottom = if from_zero {
        0.0
    } else if lo >= 0.0 {
        (lo - pad).max(0.0)
    } else {
        lo - pad
    };
    (bottom, hi + pad)
}

/// Range of x over a panel's series, widened to round numbers: window centres such as
/// 50..9 950 give an axis from 0 to 10 000. A single x is widened by ±0.5.
fn x_range(series: &[Series]) -> (f64, f64) {
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.x.iter().copied())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if hi <= lo {
        return (lo - 0.5, hi + 0.5);
    }
    let span = hi - lo;
    // A tenth of the span's decade: at most ~10 % of the span is added at either end.
    let unit = 10f64.powf(span.log10().floor() - 1.0);
    let start = if lo >= 0.0 && lo <= 0.1 * span {
        0.0
    } else {
        (lo / unit).floor() * unit
    };
    (start, (hi / unit).ceil() * unit)
}

/// A tick label with as many decimals as the axis span calls for.
fn tick_label(value: f64, span: f64) -> String {
    let decimals = if span >= 50.0 {
        0
    } else if span >= 5.0 {
        1
    } else if span >= 0.5 {
        2
    } else {
        3
    };
    // `-0` would look odd at the origin.
    let v = if value.abs() < 0.5 * 10f64.powi(-decimals) {
        0.0
    } else {
        value
    };
    format!("{v:.prec$}", prec = decimals as usize)
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    x_label: &str,
    held: Option<&[Series]>,
    markers: bool,
    styles: &CurveStyles,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let series = &panel.series;
    let (x0, x1) = match held {
        Some(st) => {
            let (a, b) = x_range(series);
            let (c, d) = x_range(st);
            (a.min(c), b.max(d))
        }
        None => x_range(series),
    };
    let (y0, y1) = value_range(series);
    // The right-hand axis' title is drawn inside its label area, which ends a margin short of
    // the panel's edge, so it never reaches into the next panel's y-axis title.
    let mut chart = ChartBuilder::on(area)
        .margin_left(14)
        .margin_right(if held.is_some() { 26 } else { 34 })
        .margin_top(6)
        .margin_bottom(4)
        .caption(&panel.caption, (FONT_FAMILY, 22).into_font().color(&INK))
        .x_label_area_size(62)
        .y_label_area_size(92)
        .right_y_label_area_size(if held.is_some() { 84 } else { 0 })
        .build_cartesian_2d(x0..x1, y0..y1)?
        .set_secondary_coord(x0..x1, 0.0..100.0);
    let y_label = panel.y_label.as_str();
    let x_fmt = |v: &f64| tick_label(*v, x1 - x0);
    let y_fmt = |v: &f64| tick_label(*v, y1 - y0);
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style((FONT_FAMILY, 16).into_font().color(&INK))
        .axis_desc_style((FONT_FAMILY, 19).into_font().color(&INK))
        .axis_style(INK.mix(0.7))
        .bold_line_style(INK.mix(0.12))
        .max_light_lines(0)
        .x_labels(9)
        .y_labels(8)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .draw()?;
    if let Some(st) = held {
        chart
            .configure_secondary_axes()
            .y_desc("held robot-steps (%), dotted")
            .label_style((FONT_FAMILY, 16).into_font().color(&INK))
            .axis_desc_style((FONT_FAMILY, 19).into_font().color(&INK))
            .axis_style(INK.mix(0.7))
            .y_labels(6)
            .draw()?;
        for s in st {
            let colour = styles.colour(&s.label);
            let points: Vec<(f64, f64)> = s.x.iter().copied().zip(s.mean.iter().copied()).collect();
            chart.draw_secondary_series(DashedLineSeries::new(
                points.clone(),
                3,
                6,
                colour.mix(0.8).stroke_width(2),
            ))?;
            if markers || points.len() == 1 {
                chart.draw_secondary_series(
                    points
                        .into_iter()
                        .map(|p| Circle::new(p, 4, colour.mix(0.8).stroke_width(2))),
                )?;
            }
        }
    }

    // Bands first, then dashed lines, then solid lines, so the learning runs lie on top. A
    // band is drawn over each run of points that rest on every repeat (a point that rests on
    // fewer has no band: its interval would be of a part of the repeats only).
    for s in series {
        let alpha = if s.dashed { 0.11 } else { 0.22 };
        let mut i = 0;
        while i < s.x.len() {
            if !s.full(i) {
                i += 1;
                continue;
            }
            let start = i;
            while i < s.x.len() && s.full(i) {
                i += 1;
            }
            let run = start..i;
            if s.lo[run.clone()]
                .iter()
                .zip(&s.hi[run.clone()])
                .all(|(l, h)| l == h)
            {
                continue;
            }
            let outline: Vec<(f64, f64)> = run
                .clone()
                .map(|k| (s.x[k], s.hi[k]))
                .chain(run.rev().map(|k| (s.x[k], s.lo[k])))
                .collect();
            chart.draw_series(std::iter::once(Polygon::new(
                outline,
                styles.colour(&s.label).mix(alpha).filled(),
            )))?;
        }
    }
    for dashed in [true, false] {
        for s in series.iter().filter(|s| s.dashed == dashed) {
            let colour = styles.colour(&s.label);
            let points: Vec<(f64, f64)> = s.x.iter().copied().zip(s.mean.iter().copied()).collect();
            if markers || points.len() == 1 {
                chart.draw_series(
                    points
                        .iter()
                        .enumerate()
                        .filter(|&(i, _)| s.full(i))
                        .map(|(_, &p)| Circle::new(p, 6, colour.filled())),
                )?;
            }
            // Points resting on fewer than all repeats: an open circle, the count beside it.
            let count_font = (FONT_FAMILY, 15)
                .into_font()
                .color(&colour)
                .pos(Pos::new(HPos::Left, VPos::Bottom));
            for (i, &p) in points.iter().enumerate().filter(|&(i, _)| !s.full(i)) {
                chart.draw_series(std::iter::once(Circle::new(p, 7, WHITE.filled())))?;
                chart.draw_series(std::iter::once(Circle::new(p, 7, colour.stroke_width(2))))?;
                chart.draw_series(std::iter::once(
                    EmptyElement::at(p)
                        + Text::new(format!("{}", s.n[i]), (8, -6), count_font.clone()),
                ))?;
            }
            if points.len() > 1 && dashed {
                chart.draw_series(DashedLineSeries::new(
                    points,
                    12,
                    8,
                    colour.stroke_width(CURVE_WIDTH_PX),
                ))?;
            } else if points.len() > 1 {
                chart.draw_series(LineSeries::new(points, colour.stroke_width(CURVE_WIDTH_PX)))?;
            }
        }
    }
    Ok(())
}

/// The shared legend under the panels: a line sample over a band swatch, then the label; with
/// `partial`, a note on the points that rest on fewer repeats.
fn draw_curve_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    styles: &CurveStyles,
    rows: &[LegendRow],
    font: &TextStyle,
    partial: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (w, _) = area.dim_in_pixel();
    let text = font.pos(Pos::new(HPos::Left, VPos::Center));
    for (r, row) in rows.iter().enumerate() {
        let row_width: i32 = row.iter().map(|(_, width)| width).sum::<i32>() - 40;
        let mut x = (w as i32 - row_width) / 2;
        let y = r as i32 * LEGEND_ROW_PX as i32 + LEGEND_ROW_PX as i32 / 2 + 4;
        for &(i, width) in row {
            let (label, colour, dashed) = &styles.entries[i];
            let alpha = if *dashed { 0.11 } else { 0.22 };
            area.draw(&Rectangle::new(
                [(x, y - 9), (x + LEGEND_SAMPLE_PX, y + 9)],
                colour.mix(alpha).filled(),
            ))?;
            let line = [(x, y), (x + LEGEND_SAMPLE_PX, y)];
            let style = colour.stroke_width(CURVE_WIDTH_PX);
            if *dashed {
                area.draw(&DashedPathElement::new(line, 12, 8, style))?;
            } else {
                area.draw(&PathElement::new(line, style))?;
            }
            area.draw_text(label, &text, (x + LEGEND_SAMPLE_PX + 10, y))?;
            x += width;
        }
    }
    if partial {
        let y = rows.len() as i32 * LEGEND_ROW_PX as i32 + 6;
        let note = font.pos(Pos::new(HPos::Center, VPos::Center));
        area.draw_text(
            "open circle: a window in which fewer repeats have a value (their number beside it); no band there",
            &note,
            (w as i32 / 2, y),
        )?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Arena figure
// ---------------------------------------------------------------------------------------------

/// Largest width of the arena's plotting area, pixels.
const ARENA_MAX_W_PX: f64 = 1000.0;
/// Largest height of the arena's plotting area, pixels.
const ARENA_MAX_H_PX: f64 = 900.0;
/// Smallest width of the arena's plotting area, pixels (a narrow corridor stays readable).
const ARENA_MIN_W_PX: f64 = 260.0;
/// Smallest height of the arena's plotting area, pixels.
const ARENA_MIN_H_PX: f64 = 160.0;
/// Height of the arena figure's title strip, pixels.
const ARENA_TITLE_PX: u32 = 52;
/// Width of the arena figure's legend column, pixels.
const ARENA_LEGEND_W_PX: u32 = 250;
/// Height of one legend entry of the arena figure, pixels.
const ARENA_ENTRY_PX: i32 = 26;
/// Chart margins and label areas around the arena's plotting area, pixels.
const ARENA_MARGIN_PX: (u32, u32, u32, u32) = (10, 10, 14, 26); // top, bottom, left, right
/// Width of the y-label area of the arena chart, pixels.
const ARENA_Y_LABELS_PX: u32 = 72;
/// Height of the x-label area of the arena chart, pixels.
const ARENA_X_LABELS_PX: u32 = 58;
/// Most robots listed one by one in the arena legend.
const ARENA_LISTED_ROBOTS: usize = 12;
/// Most snapshot times listed in the arena legend; beyond that an evenly spread selection.
const ARENA_LISTED_TIMES: usize = 12;

/// Draws the arena figure (paper Fig. 8) into `png`, which must end in `.png`.
///
/// The image's size follows the arena's shape (equal aspect ratio); a 1.8 m square arena gives
/// about 1 300 × 1 050 pixels. Nothing is written unless the figure is valid.
pub fn arena_figure(fig: &ArenaFigure, png: &Path) -> Result<(), PlotError> {
    check_png_name(png)?;
    let (size, rgb) = render_arena(fig).map_err(|e| match e {
        PlotError::Draw { reason, .. } => draw_error(png, reason),
        other => other,
    })?;
    write_png(png, size, &rgb)
}

/// The arena figure's pixels: its size and its RGB bytes, row by row (what [`arena_figure`]
/// writes).
///
/// # Errors
/// Invalid data, or a drawing that fails.
pub fn render_arena(fig: &ArenaFigure) -> Result<((u32, u32), Vec<u8>), PlotError> {
    let headings = validate_arena(fig)?;
    register_font()?;
    let layout = ArenaLayout::new(fig, &headings);
    let size = layout.size_px;
    let mut rgb = vec![0u8; (size.0 as usize) * (size.1 as usize) * 3];
    {
        let here = Path::new("arena figure");
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_arena(&root, fig, &layout).map_err(|e| draw_error(here, e))?;
        root.present().map_err(|e| draw_error(here, e))?;
    }
    Ok((size, rgb))
}

/// Draws several arena figures side by side into one `png` (e.g. the paths of early and of
/// late learning, each with its own title and legend), their tops aligned, on white.
pub fn arena_figure_panels(figs: &[ArenaFigure], png: &Path) -> Result<(), PlotError> {
    if figs.is_empty() {
        return Err(PlotError::NothingToDraw);
    }
    check_png_name(png)?;
    register_font()?;
    let mut images = Vec::with_capacity(figs.len());
    for fig in figs {
        let headings = validate_arena(fig)?;
        let layout = ArenaLayout::new(fig, &headings);
        let size = layout.size_px;
        let mut rgb = vec![0u8; (size.0 as usize) * (size.1 as usize) * 3];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
            draw_arena(&root, fig, &layout).map_err(|e| draw_error(png, e))?;
            root.present().map_err(|e| draw_error(png, e))?;
        }
        images.push((size, rgb));
    }
    let width: u32 = images.iter().map(|(s, _)| s.0).sum();
    let height: u32 = images.iter().map(|(s, _)| s.1).max().unwrap_or(1);
    let mut out = vec![255u8; width as usize * height as usize * 3];
    let mut x0 = 0usize;
    for ((w, h), rgb) in &images {
        let (w, h) = (*w as usize, *h as usize);
        for row in 0..h {
            let dst = (row * width as usize + x0) * 3;
            out[dst..dst + w * 3].copy_from_slice(&rgb[row * w * 3..(row + 1) * w * 3]);
        }
        x0 += w;
    }
    write_png(png, (width, height), &out)
}

/// Size of the space-time figure, pixels.
pub const SPACETIME_SIZE_PX: (u32, u32) = (1500, 760);

/// Draws the corridor's space-time figure into `png` (which must end in `.png`).
pub fn spacetime_figure(fig: &SpaceTimeFigure, png: &Path) -> Result<(), PlotError> {
    let bad = |item: String, value: f64| PlotError::ArenaBadValue { item, value };
    for (name, v) in [("length_m", fig.length_m), ("body_m", fig.body_m)] {
        if !v.is_finite() || v <= 0.0 || v > MAX_ABS_COORD_M {
            return Err(bad(format!("space-time figure, {name}"), v));
        }
    }
    for (r, path) in fig.paths.iter().enumerate() {
        for (i, &(t, x)) in path.iter().enumerate() {
            if let Some(v) = [t, x]
                .into_iter()
                .find(|v| !v.is_finite() || v.abs() > MAX_ABS_VALUE)
            {
                return Err(bad(format!("path of robot {r}, point {i}"), v));
            }
        }
    }
    if fig.paths.iter().all(Vec::is_empty) {
        return Err(PlotError::NothingToDraw);
    }
    check_png_name(png)?;
    register_font()?;
    let size = SPACETIME_SIZE_PX;
    let mut rgb = vec![0u8; (size.0 as usize) * (size.1 as usize) * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_spacetime(&root, fig).map_err(|e| draw_error(png, e))?;
        root.present().map_err(|e| draw_error(png, e))?;
    }
    write_png(png, size, &rgb)
}

fn draw_spacetime<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &SpaceTimeFigure,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (t0, t1) = fig
        .paths
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &(t, _)| {
            (a.min(t), b.max(t))
        });
    let (t0, t1) = if t1 > t0 {
        (t0, t1)
    } else {
        (t0 - 0.5, t0 + 0.5)
    };
    let mut chart = ChartBuilder::on(root)
        .margin(20)
        .caption(&fig.title, (FONT_FAMILY, 24).into_font().color(&INK))
        .x_label_area_size(60)
        .y_label_area_size(90)
        .build_cartesian_2d(t0..t1, 0.0..fig.length_m)?;
    let x_fmt = |v: &f64| tick_label(*v, t1 - t0);
    let y_fmt = |v: &f64| tick_label(*v, fig.length_m);
    chart
        .configure_mesh()
        .x_desc("learning step")
        .y_desc("position along the corridor (m)")
        .label_style((FONT_FAMILY, 16).into_font().color(&INK))
        .axis_desc_style((FONT_FAMILY, 19).into_font().color(&INK))
        .axis_style(INK.mix(0.7))
        .bold_line_style(INK.mix(0.10))
        .max_light_lines(0)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .draw()?;
    let half = 0.5 * fig.body_m;
    for (r, path) in fig.paths.iter().enumerate() {
        if path.is_empty() {
            continue;
        }
        let c = ROBOT_PALETTE[r % ROBOT_PALETTE.len()];
        let band: Vec<(f64, f64)> = path
            .iter()
            .map(|&(t, x)| (t, (x + half).min(fig.length_m)))
            .chain(path.iter().rev().map(|&(t, x)| (t, (x - half).max(0.0))))
            .collect();
        chart.draw_series(std::iter::once(Polygon::new(band, c.mix(0.25).filled())))?;
        chart
            .draw_series(
                path.windows(2)
                    .map(|w| PathElement::new(vec![w[0], w[1]], c.stroke_width(2))),
            )?
            .label(format!("robot {r}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT_FAMILY, 16).into_font().color(&INK))
        .background_style(WHITE.mix(0.85))
        .border_style(INK.mix(0.4))
        .draw()?;
    Ok(())
}

/// Checks the arena figure; returns each outline's heading normalised to unit length.
fn validate_arena(fig: &ArenaFigure) -> Result<Vec<(f64, f64)>, PlotError> {
    let bad = |item: String, value: f64| PlotError::ArenaBadValue { item, value };
    let first_bad = |p: &[(f64, f64)]| {
        p.iter()
            .enumerate()
            .flat_map(|(i, &(x, y))| [(i, x), (i, y)])
            .find(|(_, v)| !v.is_finite() || v.abs() > MAX_ABS_COORD_M)
    };
    for (w, wall) in fig.walls.iter().enumerate() {
        if let Some((end, v)) = first_bad(wall) {
            return Err(bad(format!("wall {w}, end {end}"), v));
        }
    }
    for (r, path) in fig.paths.iter().enumerate() {
        if let Some((i, v)) = first_bad(path) {
            return Err(bad(format!("path of robot {r}, point {i}"), v));
        }
    }
    let mut headings = Vec::with_capacity(fig.outlines.len());
    for (index, o) in fig.outlines.iter().enumerate() {
        if o.robot >= fig.paths.len() {
            return Err(PlotError::UnknownRobot {
                index,
                robot: o.robot,
                robots: fig.paths.len(),
            });
        }
        if !o.time_s.is_finite() {
            return Err(bad(format!("outline {index}, time_s"), o.time_s));
        }
        if let Some((c, v)) = first_bad(&o.corners) {
            return Err(bad(format!("outline {index}, corner {c}"), v));
        }
        if let Some(v) = [o.heading.0, o.heading.1]
            .into_iter()
            .find(|v| !v.is_finite())
        {
            return Err(bad(format!("outline {index}, heading"), v));
        }
        let len = o.heading.0.hypot(o.heading.1);
        if len == 0.0 || !len.is_finite() {
            return Err(PlotError::ZeroHeading { index });
        }
        headings.push((o.heading.0 / len, o.heading.1 / len));
    }
    let any_point = !fig.walls.is_empty()
        || fig.paths.iter().any(|p| !p.is_empty())
        || !fig.outlines.is_empty();
    if !any_point {
        return Err(PlotError::NothingToDraw);
    }
    Ok(headings)
}

/// Everything the arena drawing needs that does not depend on the backend.
struct ArenaLayout {
    /// Image size, pixels.
    size_px: (u32, u32),
    /// Width of the chart part (left of the legend), pixels.
    chart_w_px: u32,
    /// Height of the chart part, pixels (the legend may be taller).
    chart_h_px: u32,
    /// Stroke width (pixels) and opacity of the trajectories.
    path_style: (u32, f64),
    /// Bounding box of everything drawn, padded: (x0, x1, y0, y1) in metres.
    bbox_m: (f64, f64, f64, f64),
    /// Distinct snapshot times, ascending.
    times_s: Vec<f64>,
    /// Unit heading of each outline.
    headings: Vec<(f64, f64)>,
}

impl ArenaLayout {
    fn new(fig: &ArenaFigure, headings: &[(f64, f64)]) -> Self {
        let points = fig
            .walls
            .iter()
            .flat_map(|w| w.iter().copied())
            .chain(fig.paths.iter().flatten().copied())
            .chain(fig.outlines.iter().flat_map(|o| o.corners.iter().copied()));
        let (mut x0, mut x1, mut y0, mut y1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for (x, y) in points {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        let pad = (0.04 * (x1 - x0).max(y1 - y0)).max(0.02);
        let bbox_m = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
        let (w_m, h_m) = (bbox_m.1 - bbox_m.0, bbox_m.3 - bbox_m.2);
        let px_per_m = (ARENA_MAX_W_PX / w_m).min(ARENA_MAX_H_PX / h_m);
        let plot_w = (w_m * px_per_m).round().max(ARENA_MIN_W_PX) as u32;
        let plot_h = (h_m * px_per_m).round().max(ARENA_MIN_H_PX) as u32;
        let (mt, mb, ml, mr) = ARENA_MARGIN_PX;
        let chart_w_px = plot_w + ARENA_Y_LABELS_PX + ml + mr;
        let chart_h_px = plot_h + ARENA_X_LABELS_PX + mt + mb;
        let length_m: f64 = fig
            .paths
            .iter()
            .flat_map(|p| p.windows(2))
            .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
            .sum();
        let ink = length_m * px_per_m / (f64::from(plot_w) * f64::from(plot_h));

        let mut times_s: Vec<f64> = fig.outlines.iter().map(|o| o.time_s).collect();
        times_s.sort_by(f64::total_cmp);
        times_s.dedup();
        let legend_h = legend_height(fig.paths.len(), times_s.len());
        let size_px = (
            chart_w_px + ARENA_LEGEND_W_PX,
            ARENA_TITLE_PX + chart_h_px.max(legend_h),
        );
        Self {
            size_px,
            chart_w_px,
            chart_h_px,
            path_style: path_style(ink),
            bbox_m,
            times_s,
            headings: headings.to_vec(),
        }
    }

    /// Fill strength of an outline taken at `time_s`: faint for the earliest, strong for the
    /// latest.
    fn fill_alpha(&self, time_s: f64) -> f64 {
        let k = self.times_s.len();
        if k <= 1 {
            return 0.45;
        }
        let rank = self.times_s.partition_point(|&t| t < time_s);
        0.10 + 0.60 * rank as f64 / (k - 1) as f64
    }
}

/// Pixel height of the arena legend for `robots` robots and `times` snapshot times.
fn legend_height(robots: usize, times: usize) -> u32 {
    let robot_rows = if robots <= ARENA_LISTED_ROBOTS {
        robots
    } else {
        2
    };
    let time_rows = match times {
        0 => 0,
        t if t <= ARENA_LISTED_TIMES => 2 + t + 1,
        _ => 2 + ARENA_LISTED_TIMES + 1 + 1,
    };
    let rows = 1 + robot_rows + 1 + time_rows;
    (rows as i32 * ARENA_ENTRY_PX + 40) as u32
}

/// Stroke width (pixels) and opacity of trajectories from their ink: the fraction of the
/// plotting area a 1-pixel line of their total length would cover. Sparse paths are drawn 2 px
/// wide and strong; dense ones (long runs, big swarms) 1 px and fainter, so outlines stay
/// readable on top.
fn path_style(ink: f64) -> (u32, f64) {
    if ink < 0.25 {
        (2, 0.85)
    } else {
        (1, (0.85 - 0.15 * ink).clamp(0.3, 0.85))
    }
}

/// Keeps the first and last point and every point at least `min_step` from the last kept one.
fn thin_path(path: &[(f64, f64)], min_step: f64) -> Vec<(f64, f64)> {
    let mut kept: Vec<(f64, f64)> = Vec::with_capacity(path.len().min(4096));
    for (i, &p) in path.iter().enumerate() {
        let far = kept
            .last()
            .is_none_or(|&(x, y)| (p.0 - x).hypot(p.1 - y) >= min_step);
        if far || i + 1 == path.len() {
            kept.push(p);
        }
    }
    kept
}

/// A darker shade of `c` (for the heading marks).
fn darker(c: RGBColor) -> RGBColor {
    let f = |v: u8| (f64::from(v) * 0.55).round() as u8;
    RGBColor(f(c.0), f(c.1), f(c.2))
}

/// Heading triangle inside an outline: tip near the front edge, base across the middle.
fn heading_triangle(corners: &[(f64, f64); 4], h: (f64, f64)) -> [(f64, f64); 3] {
    let c = (
        corners.iter().map(|p| p.0).sum::<f64>() / 4.0,
        corners.iter().map(|p| p.1).sum::<f64>() / 4.0,
    );
    let side = (-h.1, h.0);
    let along = |p: &(f64, f64)| (p.0 - c.0) * h.0 + (p.1 - c.1) * h.1;
    let across = |p: &(f64, f64)| ((p.0 - c.0) * side.0 + (p.1 - c.1) * side.1).abs();
    let front = corners.iter().map(along).fold(0.0, f64::max);
    let half_w = corners.iter().map(across).fold(0.0, f64::max);
    let at = |a: f64, s: f64| (c.0 + h.0 * a + side.0 * s, c.1 + h.1 * a + side.1 * s);
    [
        at(0.8 * front, 0.0),
        at(0.0, 0.38 * half_w),
        at(0.0, -0.38 * half_w),
    ]
}

/// `t = 12.5 s`, without trailing zeros (`t = 1.5e9 s` for times beyond a few months).
fn time_label(time_s: f64) -> String {
    if time_s.abs() >= 1e7 {
        return format!("t = {time_s:.3e} s");
    }
    let mut s = format!("{time_s:.2}");
    while s.ends_with('0') {
        s.pop();
    }
    if s.ends_with('.') {
        s.pop();
    }
    if s == "-0" {
        s = "0".to_string();
    }
    format!("t = {s} s")
}

/// The chart of an arena figure: metres on both axes.
type ArenaChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws the arena figure: the title, the chart (the paths, the outlines, the walls) and the
/// legend beside it.
fn draw_arena<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &ArenaFigure,
    layout: &ArenaLayout,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (title_area, body) = root.split_vertically(ARENA_TITLE_PX);
    let title_font = (FONT_FAMILY, 26)
        .into_font()
        .color(&INK)
        .pos(Pos::new(HPos::Center, VPos::Center));
    title_area.draw_text(
        &fig.title,
        &title_font,
        (
            (layout.size_px.0 / 2) as i32,
            (ARENA_TITLE_PX / 2) as i32 + 4,
        ),
    )?;
    let (chart_column, legend_area) = body.split_horizontally(layout.chart_w_px);
    // When the legend is taller than the chart (a long corridor), centre the chart beside it.
    let (_, column_h) = chart_column.dim_in_pixel();
    let above = column_h.saturating_sub(layout.chart_h_px) / 2;
    let chart_area = chart_column.margin(
        above,
        column_h.saturating_sub(above + layout.chart_h_px),
        0,
        0,
    );
    let (mut chart, m_per_px) = arena_chart(&chart_area, layout)?;
    draw_paths(&mut chart, fig, layout, m_per_px)?;
    draw_outlines(&mut chart, fig, layout)?;
    for wall in &fig.walls {
        chart.draw_series(std::iter::once(PathElement::new(
            wall.to_vec(),
            WALL_COLOUR.stroke_width(5),
        )))?;
    }
    draw_arena_legend(&legend_area, fig.paths.len(), layout)
}

/// The arena's chart on `area`, its mesh drawn, with an equal aspect ratio; and the metres a
/// pixel spans.
fn arena_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    layout: &ArenaLayout,
) -> Result<(ArenaChart<'a, DB>, f64), DrawingAreaErrorKind<DB::ErrorType>> {
    // Equal aspect ratio: measure the plotting area, then widen one range so a metre spans as
    // many pixels across as up.
    let (mt, mb, ml, mr) = ARENA_MARGIN_PX;
    let build = |x: std::ops::Range<f64>, y: std::ops::Range<f64>| {
        ChartBuilder::on(area)
            .margin_top(mt)
            .margin_bottom(mb)
            .margin_left(ml)
            .margin_right(mr)
            .x_label_area_size(ARENA_X_LABELS_PX)
            .y_label_area_size(ARENA_Y_LABELS_PX)
            .build_cartesian_2d(x, y)
    };
    let (pw, ph) = build(0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
    let (bx0, bx1, by0, by1) = layout.bbox_m;
    let m_per_px = ((bx1 - bx0) / f64::from(pw.max(1))).max((by1 - by0) / f64::from(ph.max(1)));
    let (cx, cy) = (0.5 * (bx0 + bx1), 0.5 * (by0 + by1));
    let (hw, hh) = (
        0.5 * m_per_px * f64::from(pw),
        0.5 * m_per_px * f64::from(ph),
    );
    let mut chart = build(cx - hw..cx + hw, cy - hh..cy + hh)?;
    let span = (2.0 * hw).max(2.0 * hh);
    let fmt = |v: &f64| tick_label(*v, span);
    chart
        .configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style((FONT_FAMILY, 16).into_font().color(&INK))
        .axis_desc_style((FONT_FAMILY, 18).into_font().color(&INK))
        .axis_style(INK.mix(0.7))
        .bold_line_style(INK.mix(0.10))
        .max_light_lines(0)
        .x_labels((pw / 90).max(2) as usize)
        .y_labels((ph / 55).max(2) as usize)
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .draw()?;
    Ok((chart, m_per_px))
}

/// The robots' colours, repeating past the palette.
fn robot_colour(r: usize) -> RGBColor {
    ROBOT_PALETTE[r % ROBOT_PALETTE.len()]
}

/// Each robot's path (thinned to what `m_per_px` shows) and a circle at its start.
fn draw_paths<DB: DrawingBackend>(
    chart: &mut ArenaChart<'_, DB>,
    fig: &ArenaFigure,
    layout: &ArenaLayout,
    m_per_px: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (path_px, path_alpha) = layout.path_style;
    // Each step of a path is a segment of its own: plotters joins a wide polyline's segments
    // with mitres, and where a robot reverses (backward after forward) the two segments meet
    // at almost 180° and the mitre becomes a long thin spike far past the path.
    for (r, path) in fig.paths.iter().enumerate() {
        let thin = thin_path(path, 0.75 * m_per_px);
        let style = robot_colour(r).mix(path_alpha).stroke_width(path_px);
        chart.draw_series(
            thin.windows(2)
                .map(|w| PathElement::new(vec![w[0], w[1]], style)),
        )?;
    }
    for (r, path) in fig.paths.iter().enumerate() {
        if let Some(&start) = path.first() {
            chart.draw_series(std::iter::once(Circle::new(
                start,
                5,
                robot_colour(r).stroke_width(2),
            )))?;
        }
    }
    Ok(())
}

/// The robots' outlines at the snapshots, each filled by its time, bordered, with its heading.
fn draw_outlines<DB: DrawingBackend>(
    chart: &mut ArenaChart<'_, DB>,
    fig: &ArenaFigure,
    layout: &ArenaLayout,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    // Outlines from the earliest snapshot to the latest, so the latest lie on top.
    let border_px = if fig.paths.len() <= 30 { 2 } else { 1 };
    let mut order: Vec<usize> = (0..fig.outlines.len()).collect();
    order.sort_by(|&a, &b| fig.outlines[a].time_s.total_cmp(&fig.outlines[b].time_s));
    for i in order {
        let o = &fig.outlines[i];
        let c = robot_colour(o.robot);
        let corners: Vec<(f64, f64)> = o.corners.to_vec();
        chart.draw_series(std::iter::once(Polygon::new(
            corners.clone(),
            c.mix(layout.fill_alpha(o.time_s)).filled(),
        )))?;
        let mut closed = corners;
        closed.push(o.corners[0]);
        chart.draw_series(std::iter::once(PathElement::new(
            closed,
            c.stroke_width(border_px),
        )))?;
        let tri = heading_triangle(&o.corners, layout.headings[i]);
        chart.draw_series(std::iter::once(Polygon::new(
            tri.to_vec(),
            darker(c).filled(),
        )))?;
    }
    Ok(())
}

/// The legend beside the arena: the robots' colours, the start marker, the snapshots' times
/// and the heading marker.
fn draw_arena_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    robots: usize,
    layout: &ArenaLayout,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let head = (FONT_FAMILY, 19)
        .into_font()
        .color(&INK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let text = (FONT_FAMILY, 16)
        .into_font()
        .color(&INK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let x = 8;
    let text_x = x + 44;
    let mut y = 28;
    let step = ARENA_ENTRY_PX;

    area.draw_text("robots", &head, (x, y))?;
    y += step;
    if robots <= ARENA_LISTED_ROBOTS {
        for r in 0..robots {
            let c = ROBOT_PALETTE[r % ROBOT_PALETTE.len()];
            area.draw(&PathElement::new(
                [(x, y), (x + 34, y)],
                c.stroke_width(layout.path_style.0 + 1),
            ))?;
            area.draw_text(&format!("robot {r}"), &text, (text_x, y))?;
            y += step;
        }
    } else {
        for (i, c) in ROBOT_PALETTE.iter().enumerate() {
            let sx = x + 20 * i as i32;
            area.draw(&Rectangle::new([(sx, y - 7), (sx + 16, y + 7)], c.filled()))?;
        }
        y += step;
        area.draw_text(&format!("{robots} robots; colours repeat"), &text, (x, y))?;
        y += step;
    }
    area.draw(&Circle::new((x + 17, y), 5, INK.stroke_width(2)))?;
    area.draw_text("start of path", &text, (text_x, y))?;
    y += step;

    if layout.times_s.is_empty() {
        return Ok(());
    }
    y += step / 2;
    area.draw_text("snapshots", &head, (x, y))?;
    y += step;
    let k = layout.times_s.len();
    let listed: Vec<f64> = if k <= ARENA_LISTED_TIMES {
        layout.times_s.clone()
    } else {
        (0..ARENA_LISTED_TIMES)
            .map(|i| layout.times_s[i * (k - 1) / (ARENA_LISTED_TIMES - 1)])
            .collect()
    };
    for &t in &listed {
        area.draw(&Rectangle::new(
            [(x + 6, y - 9), (x + 28, y + 9)],
            INK.mix(layout.fill_alpha(t)).filled(),
        ))?;
        area.draw(&Rectangle::new(
            [(x + 6, y - 9), (x + 28, y + 9)],
            INK.stroke_width(1),
        ))?;
        area.draw_text(&time_label(t), &text, (text_x, y))?;
        y += step;
    }
    if listed.len() < k {
        area.draw_text(&format!("({k} times in all)"), &text, (text_x, y))?;
        y += step;
    }
    let tri = [(x + 30, y), (x + 8, y - 8), (x + 8, y + 8)];
    area.draw(&Polygon::new(tri, INK.filled()))?;
    area.draw_text("heading", &text, (text_x, y))?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Shared helpers
// ---------------------------------------------------------------------------------------------

/// Registers the embedded font once per process (the sweep's figures use it too).
pub(crate) fn register_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, DEJAVU_SANS_TTF).is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// The PNG encoder picks the format from the file name, so insist on `.png`.
fn check_png_name(path: &Path) -> Result<(), PlotError> {
    let is_png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if is_png {
        Ok(())
    } else {
        Err(PlotError::NotPng {
            path: path.to_path_buf(),
        })
    }
}

/// Encodes an RGB buffer drawn in memory into `path` as PNG.
pub(crate) fn write_png(path: &Path, size: (u32, u32), rgb: &[u8]) -> Result<(), PlotError> {
    // Open the file ourselves first: the encoder reports I/O failures only as debug text.
    std::fs::File::create(path).map_err(|e| write_error(path, e))?;
    let mut file = BitMapBackend::new(path, size);
    file.blit_bitmap((0, 0), size, rgb)
        .map_err(|e| draw_error(path, e))?;
    file.present().map_err(|e| PlotError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

fn draw_error(path: &Path, e: impl std::fmt::Display) -> PlotError {
    PlotError::Draw {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

fn write_error(path: &Path, e: std::io::Error) -> PlotError {
    PlotError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_take_decimals_from_the_span() {
        assert_eq!(tick_label(2500.0, 10_000.0), "2500");
        assert_eq!(tick_label(12.25, 20.0), "12.2");
        assert_eq!(tick_label(0.126, 1.0), "0.13");
        assert_eq!(tick_label(0.0125, 0.1), "0.013");
        assert_eq!(tick_label(-0.0001, 1.0), "0.00");
    }

    #[test]
    fn ranges_pad_and_anchor_at_zero() {
        assert_eq!(padded_range(10.0, 110.0, false), (4.0, 116.0));
        assert_eq!(padded_range(1.0, 101.0, false), (0.0, 107.0));
        assert_eq!(padded_range(-10.0, 90.0, false), (-16.0, 96.0));
        assert_eq!(padded_range(5.0, 5.0, false), (4.0, 6.0));
        let s = |lo: f64, hi: f64| Series {
            label: String::new(),
            dashed: false,
            x: vec![0.0],
            mean: vec![lo],
            lo: vec![lo],
            hi: vec![hi],
            n: Vec::new(),
            repeats: 0,
        };
        // Close to 0 (within 30 % of the span): the axis starts at 0.
        assert_eq!(value_range(&[s(0.2, 1.0)]).0, 0.0);
        // Far from 0: the axis hugs the data.
        assert!(value_range(&[s(300.0, 400.0)]).0 > 250.0);
    }

    #[test]
    fn thinning_keeps_ends_and_drops_sub_pixel_steps() {
        let path: Vec<(f64, f64)> = (0..=100).map(|i| (f64::from(i) * 0.001, 0.0)).collect();
        let thin = thin_path(&path, 0.01);
        assert_eq!(thin.first(), path.first());
        assert_eq!(thin.last(), path.last());
        assert_eq!(thin.len(), 11);
        assert!(thin_path(&[], 0.01).is_empty());
        assert_eq!(thin_path(&[(1.0, 2.0)], 0.01), vec![(1.0, 2.0)]);
    }

    #[test]
    fn time_labels_drop_trailing_zeros() {
        assert_eq!(time_label(0.0), "t = 0 s");
        assert_eq!(time_label(1125.0), "t = 1125 s");
        assert_eq!(time_label(4.5), "t = 4.5 s");
        assert_eq!(time_label(0.126), "t = 0.13 s");
        assert_eq!(time_label(1.5e300), "t = 1.500e300 s");
    }

    #[test]
    fn heading_triangle_points_along_the_heading() {
        let corners = [
            (-0.115, -0.09),
            (0.115, -0.09),
            (0.115, 0.09),
            (-0.115, 0.09),
        ];
        let tri = heading_triangle(&corners, (1.0, 0.0));
        assert!((tri[0].0 - 0.8 * 0.115).abs() < 1e-12 && tri[0].1.abs() < 1e-12);
        assert!(tri[1].0.abs() < 1e-12 && tri[2].0.abs() < 1e-12);
        assert!(tri[1].1 > 0.0 && tri[2].1 < 0.0);
        let tri = heading_triangle(&corners, (0.0, -1.0));
        assert!(tri[0].1 < -0.05, "tip should point down: {tri:?}");
    }

    #[test]
    fn later_snapshots_are_filled_more_strongly() {
        let fig = ArenaFigure {
            title: String::new(),
            walls: vec![[(0.0, 0.0), (1.0, 0.0)]],
            paths: vec![vec![]],
            outlines: [30.0, 0.0, 10.0]
                .iter()
                .map(|&t| Outline {
                    robot: 0,
                    time_s: t,
                    corners: [(0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1)],
                    heading: (1.0, 0.0),
                })
                .collect(),
        };
        let layout = ArenaLayout::new(&fig, &[(1.0, 0.0); 3]);
        assert_eq!(layout.times_s, vec![0.0, 10.0, 30.0]);
        assert!(layout.fill_alpha(0.0) < layout.fill_alpha(10.0));
        assert!(layout.fill_alpha(10.0) < layout.fill_alpha(30.0));
    }
}
