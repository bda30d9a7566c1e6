//! The sweep's figures: each claim's effect against the swept keys, drawn with `plotters`.
//!
//! A claim says "a below b"; its **effect** at a point is b − a, positive where the claim
//! holds (the table's `claim.….effect`). Seeds, and the axes a figure does not show, are
//! averaged over.
//! * One axis: the effect at each value, every point as a grey dot and the mean as a line, a
//!   line at 0 (`plots/CLAIM.png`).
//! * Two axes: a heat map (`plots/CLAIM.png`), the first axis down, the second across; each
//!   cell coloured by its mean effect (blue where the claim holds, vermillion where it fails,
//!   stronger with the size of the effect against the figure's largest) and labelled with the
//!   mean and how many of its points the claim holds in (`holds 2/3`); a cell with no finished
//!   point is grey and says so.
//! * Three axes or more: a heat map for every pair of axes (`plots/CLAIM--A--B.png`).
//!
//! Like the run's own figures, the bytes are a pure function of the table (the embedded DejaVu
//! Sans font; no clock).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::SweepError;
use super::spec::{Axis, sanitize};

/// The font family the run's figures register (DejaVu Sans, embedded).
const FONT: &str = "sans-serif";
/// Text and axes.
const INK: RGBColor = RGBColor(34, 34, 34);
/// Where a claim holds (Okabe–Ito blue).
const HOLDS: RGBColor = RGBColor(0, 114, 178);
/// Where a claim fails (Okabe–Ito vermillion).
const FAILS: RGBColor = RGBColor(213, 94, 0);
/// A cell without data.
const NO_DATA: RGBColor = RGBColor(215, 215, 215);

/// One claim's values over the points, in point order.
#[derive(Clone, Debug, PartialEq)]
pub struct ClaimSeries {
    /// The claim's column name (`claim.SLUG.…`), also its figure's file name.
    pub slug: String,
    /// The claim's text (the figure's title).
    pub text: String,
    /// Per point: its effect (b − a) and whether the claim holds, or nothing when the point
    /// did not finish.
    pub per_point: Vec<Option<(f64, bool)>>,
}

/// The points of one cell of a figure.
#[derive(Clone, Debug, Default)]
struct Cell {
    /// Effects of its finished points.
    effects: Vec<f64>,
    /// How many of them the claim holds in.
    holds: usize,
    /// Points planned in the cell.
    planned: usize,
}

impl Cell {
    fn mean(&self) -> Option<f64> {
        (!self.effects.is_empty())
            .then(|| self.effects.iter().sum::<f64>() / self.effects.len() as f64)
    }
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

/// Draws every claim's figures into `dir`; returns the files written.
///
/// # Errors
/// A figure that cannot be drawn or written (tool).
pub fn claim_figures(
    axes: &[Axis],
    coords: &[Vec<usize>],
    series: &[ClaimSeries],
    dir: &Path,
) -> Result<Vec<PathBuf>, SweepError> {
    crate::plot::register_font().map_err(|e| tool(dir, e))?;
    let mut written = Vec::new();
    for s in series {
        if s.per_point.iter().all(Option::is_none) {
            continue;
        }
        match axes.len() {
            0 => {}
            1 => {
                let path = dir.join(format!("{}.png", s.slug));
                line_figure(&axes[0], coords, s, &path)?;
                written.push(path);
            }
            2 => {
                let path = dir.join(format!("{}.png", s.slug));
                heat_map(axes, (0, 1), coords, s, &path)?;
                written.push(path);
            }
            n => {
                for i in 0..n {
                    for j in i + 1..n {
                        let path = dir.join(format!(
                            "{}--{}--{}.png",
                            s.slug,
                            sanitize(&axes[i].name(), 40),
                            sanitize(&axes[j].name(), 40)
                        ));
                        heat_map(axes, (i, j), coords, s, &path)?;
                        written.push(path);
                    }
                }
            }
        }
    }
    Ok(written)
}

/// Renders `draw` into an RGB buffer of `size`, then writes it as PNG.
fn render(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), String>,
) -> Result<(), SweepError> {
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| tool(path, e))?;
        draw(&root).map_err(|e| tool(path, e))?;
        root.present().map_err(|e| tool(path, e))?;
    }
    crate::plot::write_png(path, size, &rgb).map_err(|e| tool(path, e))
}

fn title_lines(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    text: &str,
    width_px: u32,
) -> Result<i32, String> {
    let font = (FONT, 20).into_font().color(&INK);
    let mut y = 16;
    for l in wrap(text, (width_px as usize / 11).max(30)) {
        root.draw_text(&l, &font, (20, y))
            .map_err(|e| e.to_string())?;
        y += 26;
    }
    Ok(y)
}

fn line_figure(
    axis: &Axis,
    coords: &[Vec<usize>],
    s: &ClaimSeries,
    path: &Path,
) -> Result<(), SweepError> {
    let n = axis.values.len();
    let mut cells = vec![Cell::default(); n];
    for (c, v) in coords.iter().zip(&s.per_point) {
        let cell = &mut cells[c[0]];
        cell.planned += 1;
        if let Some((e, h)) = v {
            cell.effects.push(*e);
            cell.holds += usize::from(*h);
        }
    }
    let all: Vec<f64> = cells
        .iter()
        .flat_map(|c| c.effects.iter().copied())
        .collect();
    let lo = all.iter().copied().fold(0.0f64, f64::min);
    let hi = all.iter().copied().fold(0.0f64, f64::max);
    let pad = ((hi - lo) * 0.08).max(1e-9);
    let (lo, hi) = (lo - pad, hi + pad);
    let labels: Vec<String> = (0..n).map(|i| axis.label(i)).collect();
    let size = (1000, 700);
    render(path, size, |root| {
        let top = title_lines(root, &s.text, size.0)?;
        let (_, body) = root.split_vertically(top + 4);
        let mut chart = ChartBuilder::on(&body)
            .margin(20)
            .x_label_area_size(60)
            .y_label_area_size(90)
            .build_cartesian_2d((0..n as i32).into_segmented(), lo..hi)
            .map_err(|e| e.to_string())?;
        let label_of = |v: &SegmentValue<i32>| match v {
            SegmentValue::CenterOf(i) => labels.get(*i as usize).cloned().unwrap_or_default(),
            _ => String::new(),
        };
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n)
            .x_label_formatter(&label_of)
            .x_desc(axis.name())
            .y_desc("effect b - a (> 0: the claim holds)")
            .label_style((FONT, 16).into_font().color(&INK))
            .axis_desc_style((FONT, 18).into_font().color(&INK))
            .draw()
            .map_err(|e| e.to_string())?;
        // The zero line across the plotting area.
        let (x0, _) = chart.backend_coord(&(SegmentValue::CenterOf(0), 0.0));
        let (x1, y0) = chart.backend_coord(&(SegmentValue::CenterOf(n as i32 - 1), 0.0));
        body.draw(&PathElement::new(
            vec![(x0 - 40, y0), (x1 + 40, y0)],
            RGBColor(120, 120, 120).stroke_width(1),
        ))
        .map_err(|e| e.to_string())?;
        let dots = cells.iter().enumerate().flat_map(|(i, c)| {
            c.effects.iter().map(move |&e| {
                Circle::new(
                    (SegmentValue::CenterOf(i as i32), e),
                    4,
                    RGBColor(150, 150, 150).filled(),
                )
            })
        });
        chart.draw_series(dots).map_err(|e| e.to_string())?;
        let means: Vec<(SegmentValue<i32>, f64)> = cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.mean().map(|m| (SegmentValue::CenterOf(i as i32), m)))
            .collect();
        chart
            .draw_series(LineSeries::new(means.clone(), HOLDS.stroke_width(3)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(
                means
                    .iter()
                    .map(|p| Circle::new(p.clone(), 6, HOLDS.filled())),
            )
            .map_err(|e| e.to_string())?;
        // How often it holds, above each value.
        let font = (FONT, 15)
            .into_font()
            .color(&INK)
            .pos(Pos::new(HPos::Center, VPos::Bottom));
        for (i, c) in cells.iter().enumerate() {
            let (x, _) = chart.backend_coord(&(SegmentValue::CenterOf(i as i32), 0.0));
            let (_, y) = chart.backend_coord(&(SegmentValue::CenterOf(i as i32), hi));
            let text = if c.effects.is_empty() {
                "no data".to_string()
            } else if c.effects.len() < c.planned {
                format!("holds {}/{} of {}", c.holds, c.effects.len(), c.planned)
            } else {
                format!("holds {}/{}", c.holds, c.effects.len())
            };
            body.draw_text(&text, &font, (x, y + 18))
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    })
}

fn heat_map(
    axes: &[Axis],
    (ay, ax): (usize, usize),
    coords: &[Vec<usize>],
    s: &ClaimSeries,
    path: &Path,
) -> Result<(), SweepError> {
    let (ny, nx) = (axes[ay].values.len(), axes[ax].values.len());
    let mut cells = vec![Cell::default(); nx * ny];
    for (c, v) in coords.iter().zip(&s.per_point) {
        let cell = &mut cells[c[ay] * nx + c[ax]];
        cell.planned += 1;
        if let Some((e, h)) = v {
            cell.effects.push(*e);
            cell.holds += usize::from(*h);
        }
    }
    let max_abs = cells
        .iter()
        .filter_map(Cell::mean)
        .map(f64::abs)
        .fold(0.0f64, f64::max);
    let cell_w = (760 / nx as u32).clamp(48, 170);
    let cell_h = (520 / ny as u32).clamp(34, 110);
    let (left, right, top_pad, bottom) = (230u32, 170u32, 30u32, 90u32);
    let width = (left + nx as u32 * cell_w + right).max(900);
    let title_h = 16 + 26 * wrap(&s.text, (width as usize / 11).max(30)).len() as u32;
    let top = title_h + top_pad;
    let size = (width, top + ny as u32 * cell_h + bottom);
    let x_labels: Vec<String> = (0..nx).map(|i| axes[ax].label(i)).collect();
    let y_labels: Vec<String> = (0..ny).map(|i| axes[ay].label(i)).collect();
    render(path, size, |root| {
        title_lines(root, &s.text, size.0)?;
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        for j in 0..ny {
            for i in 0..nx {
                let c = &cells[j * nx + i];
                let x0 = (left + i as u32 * cell_w) as i32;
                let y0 = (top + j as u32 * cell_h) as i32;
                let (fill, strong) = match c.mean() {
                    None => (NO_DATA, false),
                    Some(m) => {
                        let t = if max_abs > 0.0 {
                            (m / max_abs).clamp(-1.0, 1.0)
                        } else {
                            0.0
                        };
                        let base = if t >= 0.0 { HOLDS } else { FAILS };
                        let a = t.abs();
                        let mix = |w: u8, b: u8| {
                            (f64::from(w) * (1.0 - a) + f64::from(b) * a).round() as u8
                        };
                        (
                            RGBColor(mix(255, base.0), mix(255, base.1), mix(255, base.2)),
                            a > 0.55,
                        )
                    }
                };
                root.draw(&Rectangle::new(
                    [(x0, y0), (x0 + cell_w as i32, y0 + cell_h as i32)],
                    fill.filled(),
                ))
                .map_err(e)?;
                root.draw(&Rectangle::new(
                    [(x0, y0), (x0 + cell_w as i32, y0 + cell_h as i32)],
                    WHITE.stroke_width(2),
                ))
                .map_err(e)?;
                let ink = if strong { WHITE } else { INK };
                let centred = (FONT, 15)
                    .into_font()
                    .color(&ink)
                    .pos(Pos::new(HPos::Center, VPos::Center));
                let (cx, cy) = (x0 + cell_w as i32 / 2, y0 + cell_h as i32 / 2);
                let (first, second) = match c.mean() {
                    None => ("no data".to_string(), String::new()),
                    Some(m) => (
                        fmt_effect(m),
                        if c.effects.len() < c.planned {
                            format!("{}/{} of {}", c.holds, c.effects.len(), c.planned)
                        } else {
                            format!("holds {}/{}", c.holds, c.effects.len())
                        },
                    ),
                };
                if cell_h >= 44 && !second.is_empty() {
                    root.draw_text(&first, &centred, (cx, cy - 10)).map_err(e)?;
                    root.draw_text(&second, &centred, (cx, cy + 10))
                        .map_err(e)?;
                } else {
                    root.draw_text(&first, &centred, (cx, cy)).map_err(e)?;
                }
            }
        }
        let label = (FONT, 16).into_font().color(&INK);
        let right_of = label.pos(Pos::new(HPos::Right, VPos::Center));
        for (j, l) in y_labels.iter().enumerate() {
            let y = (top + j as u32 * cell_h + cell_h / 2) as i32;
            root.draw_text(l, &right_of, (left as i32 - 10, y))
                .map_err(e)?;
        }
        let below = label.pos(Pos::new(HPos::Center, VPos::Top));
        for (i, l) in x_labels.iter().enumerate() {
            let x = (left + i as u32 * cell_w + cell_w / 2) as i32;
            root.draw_text(l, &below, (x, (top + ny as u32 * cell_h + 8) as i32))
                .map_err(e)?;
        }
        let desc = (FONT, 18).into_font().color(&INK);
        root.draw_text(
            &format!("{} (across)", axes[ax].name()),
            &desc.pos(Pos::new(HPos::Center, VPos::Top)),
            (
                (left + nx as u32 * cell_w / 2) as i32,
                (top + ny as u32 * cell_h + 40) as i32,
            ),
        )
        .map_err(e)?;
        root.draw_text(
            &format!("{} (down)", axes[ay].name()),
            &desc.pos(Pos::new(HPos::Right, VPos::Bottom)),
            (left as i32 - 10, top as i32 - 6),
        )
        .map_err(e)?;
        // The colour key.
        let kx = (left + nx as u32 * cell_w + 40) as i32;
        let kh = (ny as u32 * cell_h).max(120) as i32;
        let steps = 40;
        for k in 0..steps {
            let t = 1.0 - 2.0 * (f64::from(k) + 0.5) / f64::from(steps);
            let base = if t >= 0.0 { HOLDS } else { FAILS };
            let a = t.abs();
            let mix = |w: u8, b: u8| (f64::from(w) * (1.0 - a) + f64::from(b) * a).round() as u8;
            let y0 = top as i32 + kh * k / steps;
            let y1 = top as i32 + kh * (k + 1) / steps;
            root.draw(&Rectangle::new(
                [(kx, y0), (kx + 24, y1)],
                RGBColor(mix(255, base.0), mix(255, base.1), mix(255, base.2)).filled(),
            ))
            .map_err(e)?;
        }
        let small = (FONT, 14).into_font().color(&INK);
        let key_text = small.pos(Pos::new(HPos::Left, VPos::Center));
        root.draw_text(&fmt_effect(max_abs), &key_text, (kx + 30, top as i32 + 6))
            .map_err(e)?;
        root.draw_text("holds", &key_text, (kx + 30, top as i32 + 24))
            .map_err(e)?;
        root.draw_text("0", &key_text, (kx + 30, top as i32 + kh / 2))
            .map_err(e)?;
        root.draw_text("fails", &key_text, (kx + 30, top as i32 + kh - 24))
            .map_err(e)?;
        root.draw_text(
            &fmt_effect(-max_abs),
            &key_text,
            (kx + 30, top as i32 + kh - 6),
        )
        .map_err(e)?;
        root.draw_text(
            "each cell: the mean over its points of the effect b - a (> 0 where the claim holds) and how many it holds in",
            &small.pos(Pos::new(HPos::Left, VPos::Top)),
            (20, (size.1 - 28) as i32),
        )
        .map_err(e)?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effects_keep_three_digits_and_a_sign() {
        assert_eq!(fmt_effect(0.012345), "+0.0123");
        assert_eq!(fmt_effect(-12.345), "-12.3");
        assert_eq!(fmt_effect(1234.5), "+1234");
        assert_eq!(fmt_effect(0.0), "0");
    }

    #[test]
    fn titles_wrap_at_spaces() {
        assert_eq!(wrap("aa bb cc", 5), vec!["aa bb", "cc"]);
        assert_eq!(wrap("", 5), vec![""]);
    }
}
