//! The arena figure, the paper's Fig. 8: the arena seen from above, in metres at equal aspect
//! ratio, with every robot's trajectory and its outline at a few instants
//! ([`Outline`]).
//!
//! * **Colours.** Robots take the ten-colour "tab10" palette by index, cycled for larger
//!   swarms.
//! * **Paths** are thinned only below one pixel, which changes no pixel's meaning but keeps a
//!   100-robot, 10 000-step figure fast.
//! * **Snapshot times** are told apart by fill strength: the earliest outline is faintest, the
//!   latest strongest; the legend maps each strength to its time. A filled triangle inside each
//!   outline points along the heading.

// Figures may use the host's f64 functions: a PNG is not promised byte-identical across
// machines (clippy.toml, docs/limits-and-failures.md).
#![allow(clippy::disallowed_methods)]

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use swarm::experiment::Outline;

use super::canvas::{FONT_FAMILY, INK, check_png_name, register_font, write_png};
use super::{MAX_ABS_COORD_M, PlotError, ROBOT_PALETTE, draw_error, tick_label};

/// Colour of arena walls.
const WALL_COLOUR: RGBColor = RGBColor(40, 40, 40);

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

#[cfg(test)]
mod tests {
    use super::*;

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
