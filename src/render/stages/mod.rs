//! The stages of a job between its rasterization and its sink, each a compute pass (or a
//! copy) over the range view: the shadow mask (and the list its depth test's second pass walks
//! from), the sensor effects, and in shadow mode
//! `exact` the host's image copied in where the rasterizers would have drawn. The pass list
//! (passes.rs) records them in order.

pub(crate) mod effects;
pub(crate) mod host_view;
pub(crate) mod mask_pipelines;
pub(crate) mod shadow_mask;
pub(crate) mod walk_list;
