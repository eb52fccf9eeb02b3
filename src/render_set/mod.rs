//! The files a render writes into its output directory (docs/design.md "Interfaces"), as one set:
//! the range image, the labels before shadowing, the previews and `labels.json` (labels.rs).
//! It sits above `io` (the formats) and `scene` (what the labels stand for).

mod labels;

pub use labels::{label_map, write_label_map, LabelEntry};

use crate::error::{Error, Result};
use crate::io::{
    check_depth_scale, depth_png_values, write_depth_png, write_label_image, write_label_preview, write_range_image,
    write_range_preview, RangeImage, StagedSet,
};
use crate::render_output::RenderOutput;
use crate::scene::Scene;
use crate::sensor::View;
use std::path::{Path, PathBuf};

/// The files a render writes, in the order [`write_render_directory`] returns them.
pub const RENDER_FILES: [&str; 6] =
    ["range.exr", "label_unshadowed.exr", "labels.json", "range.png", "label.png", "label_unshadowed.png"];

/// The BOP-style depth image a render of a pinhole reference view writes where asked
/// (`render --depth-png SCALE`).
pub const DEPTH_PNG: &str = "depth.png";

/// The files of a render's set: [`RENDER_FILES`], and [`DEPTH_PNG`] where asked.
pub fn render_files(depth_png: bool) -> Vec<&'static str> {
    RENDER_FILES.iter().copied().chain(depth_png.then_some(DEPTH_PNG)).collect()
}

/// The set a render writes into `dir` ([`write_render_set`]), with a depth PNG where
/// `depth_png`; refuses at once what its commit would refuse, so a command can ask before it
/// renders.
pub fn render_set(dir: &Path, depth_png: bool) -> Result<StagedSet> {
    StagedSet::new(dir, &render_files(depth_png), &[])
}

/// Writes range.exr, label_unshadowed.exr, labels.json and the PNG previews (range.png,
/// label.png, label_unshadowed.png) into `dir`, creating it, as one set (io/atomic.rs): the
/// directory holds either its previous files or all of the new ones. Returns the paths written.
pub fn write_render_directory(dir: &Path, scene: &Scene, out: &RenderOutput) -> Result<Vec<PathBuf>> {
    write_render_set(render_set(dir, false)?, scene, out, None)
}

/// Refuses a depth PNG (`render --depth-png SCALE`) for a sensor whose reference view is not a
/// pinhole camera: its depth is along an optical axis.
pub fn check_depth_png(scene: &Scene, scale: f64) -> Result<()> {
    check_depth_scale(scale)?;
    match scene.sensor.reference {
        View::Pinhole(_) => Ok(()),
        View::Orthographic(_) => Err(Error::Scene(
            "--depth-png writes depth along a pinhole reference view's optical axis; this scene's sensor is \
             orthographic"
                .into(),
        )),
    }
}

/// Writes a render's files into `set` ([`render_set`]) and commits it: with `depth_scale`, the
/// depth PNG too (each valid pixel's depth / scale; [`check_depth_png`]).
pub fn write_render_set(
    set: StagedSet,
    scene: &Scene,
    out: &RenderOutput,
    depth_scale: Option<f64>,
) -> Result<Vec<PathBuf>> {
    let (w, h) = (out.width(), out.height());
    let [range, unshadowed, labels, range_png, label_png, unshadowed_png] = RENDER_FILES.map(|name| set.staged(name));
    write_range_image(&range, &RangeImage::from(out))?;
    write_label_image(&unshadowed, w, h, &out.label_unshadowed)?;
    write_label_map(&labels, scene)?;
    let valid: Vec<bool> = out.label.iter().map(|&l| l != 0).collect();
    let (heights, pitch) = out.relief();
    write_range_preview(&range_png, w, h, &heights, &valid, pitch)?;
    write_label_preview(&label_png, w, h, &out.label, Some(&out.reason))?;
    write_label_preview(&unshadowed_png, w, h, &out.label_unshadowed, None)?;
    if let Some(scale) = depth_scale {
        check_depth_png(scene, scale)?;
        write_depth_png(&set.staged(DEPTH_PNG), w, h, &depth_png_values(&out.z, &valid, scale)?)?;
    }
    set.commit()
}
