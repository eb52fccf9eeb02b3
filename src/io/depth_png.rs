//! Depth images as the BOP format stores them: a 16-bit greyscale PNG whose value is the depth
//! along a pinhole view's optical axis divided by a scale (BOP: depth in mm = value ×
//! `depth_scale`), 0 where there is no measurement.

use super::{read_input_file, write_atomically};
use crate::error::{guard_parser, Error, Result};
use crate::limits::Ledger;
use std::path::Path;

/// A depth image as read: its values row by row (0: no measurement).
#[derive(Debug, Clone, PartialEq)]
pub struct DepthPng {
    pub width: u32,
    pub height: u32,
    pub values: Vec<u16>,
}

/// Reads a 16-bit greyscale PNG (the regular file at `path`, within the run's budget: the
/// decoded image is charged before it is made). Any other PNG is refused, naming what it is.
pub fn read_depth_png(path: &Path, ledger: &Ledger) -> Result<DepthPng> {
    let bytes = read_input_file(path, "depth image", ledger)?;
    guard_parser("the depth image", "the png decoder", || {
        let bad = |e: png::DecodingError| Error::file(path, format!("not a readable PNG: {e}"));
        let mut decoder = png::Decoder::new(std::io::Cursor::new(&bytes));
        // No expansion of palettes or 16-bit samples: a depth image is read as stored.
        decoder.set_transformations(png::Transformations::IDENTITY);
        let mut reader = decoder.read_info().map_err(bad)?;
        let info = reader.info();
        let (width, height) = (info.width, info.height);
        if (info.color_type, info.bit_depth) != (png::ColorType::Grayscale, png::BitDepth::Sixteen) {
            return Err(Error::file(
                path,
                format!(
                    "a depth image must be a 16-bit greyscale PNG; this one is {:?} at {:?} bits",
                    info.color_type, info.bit_depth
                ),
            ));
        }
        // The decoded bytes and the values made from them, both held at once.
        let samples = u64::from(width) * u64::from(height);
        ledger.charge(format_args!("decoding the {width}×{height} depth image {}", path.display()), samples * 4)?;
        let mut buffer = vec![0u8; reader.output_buffer_size()];
        let frame = reader.next_frame(&mut buffer).map_err(bad)?;
        let values = buffer[..frame.buffer_size()].chunks_exact(2).map(|b| u16::from_be_bytes([b[0], b[1]])).collect();
        Ok(DepthPng { width, height, values })
    })
}

/// The value of each pixel: `depth / scale` rounded to the nearest integer where `valid`, else
/// 0. A depth whose value does not fit 1 to 65535 is refused (a value of 0 would read as no
/// measurement, and a clamped one as another depth), naming the scale that would hold it.
pub fn depth_png_values(depth: &[f32], valid: &[bool], scale: f64) -> Result<Vec<u16>> {
    check_depth_scale(scale)?;
    depth
        .iter()
        .zip(valid)
        .map(|(&z, &valid)| {
            if !valid {
                return Ok(0);
            }
            let value = (f64::from(z) / scale).round();
            match (1.0..=f64::from(u16::MAX)).contains(&value) {
                true => Ok(value as u16),
                false => Err(Error::Scene(format!(
                    "depth {z} at scale {scale} is {value}, outside a depth PNG's 1 to 65535: use a scale between \
                     {:e} and {:e}",
                    f64::from(z) / f64::from(u16::MAX),
                    f64::from(z) / 0.5
                ))),
            }
        })
        .collect()
}

/// Refuses a scale that is not positive and finite.
pub fn check_depth_scale(scale: f64) -> Result<()> {
    match scale.is_finite() && scale > 0.0 {
        true => Ok(()),
        false => Err(Error::Scene(format!("the depth PNG's scale {scale} must be positive and finite"))),
    }
}

/// Writes `values` (row-major) as a 16-bit greyscale PNG, atomically.
pub fn write_depth_png(path: &Path, width: u32, height: u32, values: &[u16]) -> Result<()> {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    write_atomically(path, |file| {
        let mut encoder = png::Encoder::new(file, width, height);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Sixteen);
        let mut writer = encoder.write_header().map_err(|e| Error::file(path, e))?;
        writer.write_image_data(&bytes).map_err(|e| Error::file(path, e))?;
        writer.finish().map_err(|e| Error::file(path, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1.9 m at 0.1 mm is 19000; 0 where invalid; a depth whose value would be 0 or beyond
    /// 65535 is refused.
    #[test]
    fn depths_become_integers_of_the_scale_or_zero() {
        assert_eq!(depth_png_values(&[1.9, 1.0, 6.0], &[true, false, true], 1e-4).unwrap(), [19000, 0, 60000]);
        for depth in [7.0, 1e-5, f32::NAN] {
            let e = depth_png_values(&[depth], &[true], 1e-4).unwrap_err().to_string();
            assert!(e.contains("outside a depth PNG's 1 to 65535"), "{depth}: {e}");
        }
        assert!(depth_png_values(&[1.0], &[true], 0.0).is_err());
    }
}
