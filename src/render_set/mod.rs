//! The files a render writes into its output directory (docs/design.md "Interfaces"), as one set:
//! the range image, the labels before shadowing, the previews and `labels.json` (labels.rs).
//! It sits above `io` (the formats) and `scene` (what the labels stand for).

mod labels;

pub use labels::{label_map, write_label_map, LabelEntry};

use crate::error::Result;
use crate::io::{
    write_label_image, write_label_preview, write_range_image, write_range_preview, RangeImage, StagedSet,
};
use crate::render_output::RenderOutput;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The files a render writes, in the order [`write_render_directory`] returns them.
pub const RENDER_FILES: [&str; 6] =
    ["range.exr", "label_unshadowed.exr", "labels.json", "range.png", "label.png", "label_unshadowed.png"];

/// The set a render writes into `dir` ([`write_render_set`]); refuses at once what its commit
/// would refuse, so a command can ask before it renders.
pub fn render_set(dir: &Path) -> Result<StagedSet> {
    StagedSet::new(dir, &RENDER_FILES, &[])
}

/// Writes range.exr, label_unshadowed.exr, labels.json and the PNG previews (range.png,
/// label.png, label_unshadowed.png) into `dir`, creating it, as one set (io/atomic.rs): the
/// directory holds either its previous files or all of the new ones. Returns the paths written.
pub fn write_render_directory(dir: &Path, scene: &Scene, out: &RenderOutput) -> Result<Vec<PathBuf>> {
    write_render_set(render_set(dir)?, scene, out)
}

/// Writes a render's files into `set` ([`render_set`]) and commits it.
pub fn write_render_set(set: StagedSet, scene: &Scene, out: &RenderOutput) -> Result<Vec<PathBuf>> {
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
    set.commit()
}
