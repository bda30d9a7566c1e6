//! The corridor's space-time figure: each robot's position along the corridor against the
//! learning step, its body drawn as a band, so the gaps between neighbours are the white space
//! between the bands.

// Figures may use the host's f64 functions: a PNG is not promised byte-identical across
// machines (clippy.toml, docs/limits-and-failures.md).
#![allow(clippy::disallowed_methods)]

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::canvas::{FONT_FAMILY, INK, check_png_name, register_font, write_png};
use super::{MAX_ABS_COORD_M, MAX_ABS_VALUE, PlotError, ROBOT_PALETTE, draw_error, tick_label};

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
