//! The two rasterizers of a view, and what both read: the graphics pipeline's draws
//! (draw.rs, whose `DrawConstants` the compute rasterizer reads as well) and pipelines
//! (graphics.rs), and the compute rasterizer (compute.rs), which `Raster` chooses between per
//! view.

pub(crate) mod compute;
pub(crate) mod draw;
pub(crate) mod graphics;
