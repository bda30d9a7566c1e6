//! The experiment's figures, drawn with `plotters`, one file per figure:
//!
//! * [`learning`]: the paper's Fig. 6/7, [`learning_figure`] (PNG and SVG).
//! * [`arena`]: the paper's Fig. 8, [`arena_figure`], [`render_arena`] and
//!   [`arena_figure_panels`].
//! * [`spacetime`]: the corridor's space-time figure, [`spacetime_figure`].
//! * [`canvas`]: what every figure, the sweep's too, draws with: the embedded font, the ink,
//!   the PNG writer.
//!
//! What they share:
//! * **Data are drawn as given.** Nothing is smoothed; axis ranges cover every value.
//! * **Robustness.** Every input is checked before anything is drawn; a bad value is a
//!   [`PlotError`] naming the series or item, and no file is written. A drawing is rendered in
//!   memory first, so a failure never leaves half a file. Parent folders are not created: that
//!   is the caller's job.
//! * **Determinism.** The bytes written are a pure function of the input (no clock, no
//!   randomness, no hash-map order).
//!
//! Why a figure looks as it does (palette, axes, snapshot shading) is told in its own module;
//! the font in [`canvas`].

// Figures may use the host's f64 functions: a PNG is not promised byte-identical across
// machines (clippy.toml, docs/limits-and-failures.md).
#![allow(clippy::disallowed_methods)]

use std::path::{Path, PathBuf};

use plotters::prelude::RGBColor;

pub mod arena;
pub mod canvas;
pub mod learning;
pub mod spacetime;

pub use arena::{ArenaFigure, arena_figure, arena_figure_panels, render_arena};
pub use learning::{
    LEARNING_SIZE_PX, LEGEND_ROW_PX, LearningFigure, Panel, Series, learning_figure,
};
pub use spacetime::{SPACETIME_SIZE_PX, SpaceTimeFigure, spacetime_figure};

/// Largest magnitude accepted for a learning-figure value (x, mean, lo, hi). Larger finite
/// values would overflow the axis arithmetic of plotters 0.3.7 (it panics or loops on an
/// infinite span); no step count, D or collision rate comes near it.
pub const MAX_ABS_VALUE: f64 = 1e12;

/// Largest magnitude accepted for an arena coordinate, metres (1 000 km).
pub const MAX_ABS_COORD_M: f64 = 1e6;

/// The ten-colour "tab10" categorical palette (Tableau 10), cycled over robots.
pub(crate) const ROBOT_PALETTE: [RGBColor; 10] = [
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

/// A tick label with as many decimals as the axis span calls for.
pub(crate) fn tick_label(value: f64, span: f64) -> String {
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

pub(crate) fn draw_error(path: &Path, e: impl std::fmt::Display) -> PlotError {
    PlotError::Draw {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

pub(crate) fn write_error(path: &Path, e: std::io::Error) -> PlotError {
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
}
