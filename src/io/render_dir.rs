//! The files a render writes into its output directory (DESIGN.md "Interfaces").

use super::{
    write_label_image, write_label_map, write_label_preview, write_range_image, write_range_preview, RangeImage,
};
use crate::error::{Error, Result};
use crate::render::RenderOutput;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// Writes range.exr, label_unshadowed.exr, labels.json and the PNG previews (range.png,
/// label.png, label_unshadowed.png) into `dir`, creating it. Returns the paths written.
pub fn write_render_directory(dir: &Path, scene: &Scene, out: &RenderOutput) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let (w, h) = (out.width(), out.height());
    let path = |name: &str| dir.join(name);
    let written = vec![
        path("range.exr"),
        path("label_unshadowed.exr"),
        path("labels.json"),
        path("range.png"),
        path("label.png"),
        path("label_unshadowed.png"),
    ];
    write_range_image(&written[0], &RangeImage::from(out))?;
    write_label_image(&written[1], w, h, &out.label_unshadowed)?;
    write_label_map(&written[2], scene)?;
    let valid: Vec<bool> = out.label.iter().map(|&l| l != 0).collect();
    write_range_preview(&written[3], w, h, &out.z, &valid, out.sensor.pitch)?;
    write_label_preview(&written[4], w, h, &out.label, &out.label_unshadowed)?;
    write_label_preview(&written[5], w, h, &out.label_unshadowed, &out.label_unshadowed)?;
    Ok(written)
}
