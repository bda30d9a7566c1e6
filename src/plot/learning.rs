//! The learning figure, the paper's Fig. 6/7: left panel the mean over robots of the summed
//! sensor distance D (du), right panel the collisions per robot, both per window of learning
//! steps, as a PNG and an SVG of the same drawing; further panels two to a row under them. Each
//! [`Series`] is a mean over repeats with a band `[lo, hi]`; the learning run is drawn solid
//! over a translucent band, the controls the paper lacks (learning off, random walk) dashed.
//!
//! * **Colours.** Curves take the Okabe–Ito colour-blind-safe palette by *label*, in order of
//!   first appearance (so a label has one colour in every panel and in the legend).
//! * **Axes.** A panel's range covers every mean and band value; a panel whose values are all
//!   ≥ 0 (collisions, D) starts at 0 only when that costs little room (the lowest value is
//!   within 30 % of the span from 0).

// Figures may use the host's f64 functions: a PNG is not promised byte-identical across
// machines (clippy.toml, docs/limits-and-failures.md).
#![allow(clippy::disallowed_methods)]

use std::path::Path;

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{FONT_FAMILY, INK, check_png_name, register_font, write_png};
use super::{MAX_ABS_VALUE, PlotError, draw_error, tick_label, write_error};

/// Size in pixels of the learning figure (PNG and SVG): two panels side by side, with a
/// one-row legend under them. Each further legend row (many or long labels) adds
/// [`LEGEND_ROW_PX`] to the height.
pub const LEARNING_SIZE_PX: (u32, u32) = (1600, 700);

/// Height of one row of the learning figure's legend, pixels.
pub const LEGEND_ROW_PX: u32 = 36;

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
