//! Files: range images as OpenEXR (f32 points, u32 labels, the sensor settings in the
//! header), PNG previews, and the text formats' parsers. Inputs are read only from regular
//! files within the memory budget (input_file.rs); outputs are written atomically,
//! only over regular files, and sets of them replace their directory whole (atomic.rs).

mod atomic;
mod depth_png;
mod exr_file;
mod input_file;
mod preview;
mod range_image;
mod text_formats;

pub use atomic::{refuse_overwriting_inputs, write_atomically, PendingFile, StagedSet};
pub use depth_png::{check_depth_scale, depth_png_values, read_depth_png, write_depth_png, DepthPng};
pub use exr_file::{parse_range_image, read_label_image, read_range_image, write_label_image, write_range_image};
pub use input_file::{read_identified_file, read_input_file, read_input_text};
#[cfg(feature = "tools")]
pub(crate) use preview::write_rgb;
pub use preview::{reason_colour, write_label_preview, write_range_preview, SHADOW_COLOUR};
pub use range_image::RangeImage;
pub use text_formats::{parse_json, parse_toml};

/// What a file type is, in words: how a refused input or output is described.
pub(crate) fn file_kind(t: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_file() {
        "a regular file"
    } else if t.is_dir() {
        "a directory"
    } else if t.is_symlink() {
        "a symbolic link"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else {
        "of an unknown file type"
    }
}

/// A fresh, empty directory for one unit test's files.
#[cfg(test)]
pub(crate) fn scratch_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("rangesynth-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
