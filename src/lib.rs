//! rangesynth: realistic range images (triangulation shadows included) for verifying 3D
//! object hypotheses, rendered with explicit Vulkan. See README.md and the book in docs/
//! (docs/design.md for the design).
//!
//! The feature `tools` (on by default) adds the accuracy sweep, the paper's experiment and
//! their plots, and the command line that runs them; an embedder that needs neither (the
//! Python package) leaves it out and does not compile them or their plotting crate.

#[cfg(feature = "tools")]
pub mod accuracy;
pub mod bop;
pub mod effects;
pub mod error;
pub mod exact;
mod exact_array;
#[cfg(feature = "tools")]
pub mod experiment;
pub mod gpu;
pub mod io;
pub mod limits;
pub mod mesh;
#[cfg(feature = "tools")]
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

/// The code of the README and of every page of the book (docs/), compiled and run by `cargo
/// test` as doc tests, so that the examples stay true to the library. Blocks that are not
/// Rust are marked with their language (`sh`, `toml`, `json`, `text`).
#[cfg(doctest)]
mod book {
    #[doc = include_str!("../README.md")]
    struct Readme;
    #[doc = include_str!("../docs/README.md")]
    struct BookIndex;
    #[doc = include_str!("../docs/sensors-and-shadows.md")]
    struct SensorsAndShadows;
    #[doc = include_str!("../docs/effects.md")]
    struct Effects;
    #[doc = include_str!("../docs/verification.md")]
    struct Verification;
    #[doc = include_str!("../docs/rasterizers.md")]
    struct Rasterizers;
    #[doc = include_str!("../docs/limits.md")]
    struct Limits;
    #[doc = include_str!("../docs/performance.md")]
    struct Performance;
    #[doc = include_str!("../docs/accuracy.md")]
    struct Accuracy;
    #[doc = include_str!("../docs/experiment.md")]
    struct Experiment;
    #[doc = include_str!("../docs/design.md")]
    struct Design;
    #[doc = include_str!("../docs/testing.md")]
    struct Testing;
    #[doc = include_str!("../docs/performance-history.md")]
    struct PerformanceHistory;
    #[doc = include_str!("../docs/compute-rasterizer.md")]
    struct ComputeRasterizer;
}
