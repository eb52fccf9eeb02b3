//! Plots of the measured sweeps (`rangesynth accuracy`, `rangesynth experiment`): plotters
//! draws into an RGB buffer, which is written as a PNG atomically like every other output.
//! The font is embedded (DejaVu Sans Mono, under the Bitstream Vera licence beside it in
//! `DejaVu-LICENSE`), so a plot needs no system fonts and looks the same on every machine.

use crate::error::{Error, Result};
use crate::io::write_rgb;
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;
use plotters::style::register_font;
use std::path::Path;
use std::sync::Once;

/// The font family plots name.
pub(crate) const FONT: &str = "sans-serif";

static FONT_BYTES: &[u8] = include_bytes!("DejaVuSansMono.ttf");

/// The area a plot draws on.
pub(crate) type PlotArea<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Draws the series' legend at `position`, in the plots' one style.
pub(crate) fn draw_legend<'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, CT>,
    position: SeriesLabelPosition,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, 14))
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()?;
    Ok(())
}

/// Draws a `width`×`height` plot with `draw` and writes it to `path` as a PNG.
pub(crate) fn write_plot(
    path: &Path,
    (width, height): (u32, u32),
    draw: impl FnOnce(&PlotArea) -> std::result::Result<(), Box<dyn std::error::Error>>,
) -> Result<()> {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // The bytes are the embedded font, which parses: nothing to report.
        let _ = register_font(FONT, FontStyle::Normal, FONT_BYTES);
    });
    let mut pixels = vec![0u8; width as usize * height as usize * 3];
    {
        let area = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        area.fill(&WHITE).map_err(|e| Error::file(path, e))?;
        draw(&area).map_err(|e| Error::file(path, e))?;
        area.present().map_err(|e| Error::file(path, e))?;
    }
    write_rgb(path, width, height, &pixels)
}
