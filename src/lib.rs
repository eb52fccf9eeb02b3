//! rangesynth: realistic range images (triangulation shadows included) for verifying 3D
//! object hypotheses, rendered with explicit Vulkan. See README.md and DESIGN.md.

pub mod accuracy;
pub mod effects;
pub mod error;
pub mod exact;
mod exact_array;
pub mod experiment;
pub mod gpu;
pub mod io;
pub mod limits;
pub mod mesh;
mod plot;
pub mod pose;
pub mod raster_choice;
pub mod render;
pub mod render_output;
pub mod render_set;
pub mod scene;
pub mod sensor;
pub mod shader_contract;
pub mod shadow;
pub mod untrusted;
pub mod verify;

pub use error::{Error, Result};
pub use render::{RenderOutput, Renderer};
pub use scene::Scene;
