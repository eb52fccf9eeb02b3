//! PNG previews for people: the range image as shaded grey (brighter is closer to the sensor,
//! times Lambert shading from normals estimated by finite differences of z), labels in
//! distinct colours, and each lost pixel in its reason's colour ([`reason_colour`], fully
//! saturated, outside the label palette). Pixels without a surface are black.

use super::write_atomically;
use crate::effects::Reason;
use crate::error::{Error, Result};
use std::path::Path;

/// Colour of shadowed pixels in label previews: full magenta.
pub const SHADOW_COLOUR: [u8; 3] = [255, 0, 255];

/// The colour of a pixel lost for `reason` in label previews (the README's legend).
pub fn reason_colour(reason: Reason) -> [u8; 3] {
    match reason {
        Reason::Valid | Reason::NoSurface => [0, 0, 0],
        Reason::Shadow => SHADOW_COLOUR,
        Reason::Grazing => [255, 128, 0],
        Reason::OutOfRange => [0, 0, 255],
        Reason::Dark => [96, 48, 0],
        Reason::Edge => [255, 255, 0],
        Reason::Dropout => [0, 255, 255],
    }
}

/// Range preview of heights `z` (larger is closer). `valid[i]` says whether pixel i has data;
/// `pitch` is dx, dy (model units a pixel spans).
pub fn write_range_preview(
    path: &Path,
    width: u32,
    height: u32,
    z: &[f32],
    valid: &[bool],
    pitch: [f64; 2],
) -> Result<()> {
    let (w, h) = (width as usize, height as usize);
    let light = glam::DVec3::new(-1.0, 1.0, 2.0).normalize();
    let at = |c: usize, r: usize| valid[r * w + c].then(|| f64::from(z[r * w + c]));
    let slope = |here: f64, before: Option<f64>, after: Option<f64>, step: f64| match (before, after) {
        (Some(b), Some(a)) => (a - b) / (2.0 * step),
        (Some(b), None) => (here - b) / step,
        (None, Some(a)) => (a - here) / step,
        (None, None) => 0.0,
    };
    let (z_lo, z_hi) = (0..w * h)
        .filter(|&i| valid[i])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| (lo.min(f64::from(z[i])), hi.max(f64::from(z[i]))));
    let mut pixels = vec![0u8; w * h * 3];
    for r in 0..h {
        for c in 0..w {
            let Some(here) = at(c, r) else { continue };
            let dzdx = slope(
                here,
                c.checked_sub(1).and_then(|c| at(c, r)),
                (c + 1 < w).then(|| at(c + 1, r)).flatten(),
                pitch[0],
            );
            // Rows go down in y.
            let dzdy = -slope(
                here,
                r.checked_sub(1).and_then(|r| at(c, r)),
                (r + 1 < h).then(|| at(c, r + 1)).flatten(),
                pitch[1],
            );
            let normal = glam::DVec3::new(-dzdx, -dzdy, 1.0).normalize();
            let height = if z_hi > z_lo { (here - z_lo) / (z_hi - z_lo) } else { 1.0 };
            let grey = (0.3 + 0.7 * height) * (0.35 + 0.65 * normal.dot(light).max(0.0)) * 255.0;
            pixels[(r * w + c) * 3..][..3].fill(grey.round() as u8);
        }
    }
    write_rgb(path, width, height, &pixels)
}

/// Label preview; a pixel without a label has its reason's colour ([`reason_colour`]), or
/// black where no reasons are given.
pub fn write_label_preview(
    path: &Path,
    width: u32,
    height: u32,
    label: &[u32],
    reason: Option<&[Reason]>,
) -> Result<()> {
    let pixels_given = |n: usize| n == (width as usize) * (height as usize);
    if !pixels_given(label.len()) || !reason.is_none_or(|r| pixels_given(r.len())) {
        return Err(Error::file(
            path,
            format!("a {width}×{height} preview needs {} labels and reasons", u64::from(width) * u64::from(height)),
        ));
    }
    let pixels: Vec<u8> = (0..label.len())
        .flat_map(|i| match label[i] {
            0 => reason_colour(reason.map_or(Reason::NoSurface, |r| r[i])),
            l => label_colour(l),
        })
        .collect();
    write_rgb(path, width, height, &pixels)
}

/// Distinct colours for neighbouring labels: hues a golden angle apart, moderate saturation.
fn label_colour(label: u32) -> [u8; 3] {
    let hue = (f64::from(label) * 0.618_033_988_749_895).fract() * 6.0;
    let (s, v) = (0.55, 0.95);
    let f = hue.fract();
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    let (r, g, b) = match hue as u32 {
        0 => (v, t, p),
        1 => (q, v, p),
        2 => (p, v, t),
        3 => (p, q, v),
        4 => (t, p, v),
        _ => (v, p, q),
    };
    [r, g, b].map(|x| (x * 255.0).round() as u8)
}

pub(crate) fn write_rgb(path: &Path, width: u32, height: u32, pixels: &[u8]) -> Result<()> {
    write_atomically(path, |file| {
        // Unbuffered: the encoder writes whole chunks, and an error on a buffered flush at drop
        // would be lost.
        let mut encoder = png::Encoder::new(file, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| Error::file(path, e))?;
        writer.write_image_data(pixels).map_err(|e| Error::file(path, e))?;
        writer.finish().map_err(|e| Error::file(path, e))
    })
}
