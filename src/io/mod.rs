//! Files: range images as OpenEXR (f32 points, u32 labels, the sensor settings in the
//! header), PNG previews, and the label map `labels.json`.

mod exr_file;
mod labels;
mod preview;
mod range_image;
mod render_dir;

pub use exr_file::{read_label_image, read_range_image, write_label_image, write_range_image};
pub use labels::{label_map, write_label_map, LabelEntry};
pub use preview::{write_label_preview, write_range_preview, SHADOW_COLOUR};
pub use range_image::RangeImage;
pub use render_dir::write_render_directory;
