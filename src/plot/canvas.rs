//! What a figure draws with, the sweep's figures too: the embedded font under
//! [`FONT_FAMILY`], the [`INK`] of text and axes, and [`write_png`], which encodes an RGB buffer
//! drawn in memory (with `plotters`' `BitMapBackend::with_buffer`) into a PNG file.
//!
//! **Font.** DejaVu Sans 2.37 (`assets/DejaVuSans.ttf`, licence in
//! `assets/DejaVuSans-LICENSE.txt`) is compiled into the binary and registered in plotters'
//! `ab_glyph` font table as `"sans-serif"` by [`register_font`], so figures render identically
//! on a machine without system fonts. An SVG names the family `sans-serif`; a viewer draws it
//! with its own sans face, laid out with DejaVu's metrics.
//!
//! A figure calls [`register_font`] before it lays out any text, draws into a buffer, and
//! writes it with [`write_png`] only once the drawing succeeded.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use super::{PlotError, draw_error, write_error};

/// DejaVu Sans 2.37 from Debian's fonts-dejavu-core; licence in assets/DejaVuSans-LICENSE.txt.
static DEJAVU_SANS_TTF: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Family name under which the embedded font is registered (plotters' default family).
pub const FONT_FAMILY: &str = "sans-serif";

/// Colour of text and axes: a soft black.
pub const INK: RGBColor = RGBColor(34, 34, 34);

/// Registers the embedded font under [`FONT_FAMILY`], once per process; call it before
/// laying out any text.
///
/// # Errors
/// [`PlotError::Font`] if the embedded font cannot be parsed (a corrupt build).
pub fn register_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, DEJAVU_SANS_TTF).is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// The PNG encoder picks the format from the file name, so insist on `.png`.
pub(crate) fn check_png_name(path: &Path) -> Result<(), PlotError> {
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

/// Encodes an RGB buffer drawn in memory (`size.0 × size.1` pixels, 3 bytes each, row by row)
/// into `path` as PNG.
///
/// # Errors
/// [`PlotError::Write`] if the file cannot be created or written, [`PlotError::Draw`] if the
/// buffer cannot be copied into the image.
pub fn write_png(path: &Path, size: (u32, u32), rgb: &[u8]) -> Result<(), PlotError> {
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
