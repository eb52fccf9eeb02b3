//! SPIR-V compiled by `build.rs` from `shaders/`, embedded in the binary.
//! `include_bytes!` is not 4-byte aligned, so words are decoded with `ash::util::read_spv`.

use super::GpuContext;
use crate::error::{Error, Result, VkResultExt};
use ash::vk;

pub const RASTER_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster.vert.spv"));
pub const RASTER_RANGE_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster_range.frag.spv"));
pub const RASTER_RANGE_TIES_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster_range_ties.frag.spv"));
pub const RASTER_SHADOW_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster_shadow.frag.spv"));
pub const RASTER_SHADOW_TIES_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster_shadow_ties.frag.spv"));
pub const RASTER_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster.comp.spv"));
pub const RASTER_LARGE_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster_large.comp.spv"));
pub const RASTER_TIES_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster_ties.comp.spv"));
pub const RASTER_LARGE_TIES_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster_large_ties.comp.spv"));
pub const RASTER_RESOLVE_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/raster_resolve.comp.spv"));
pub const RASTER_RESOLVE_SHADOW_COMP: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/raster_resolve_shadow.comp.spv"));
pub const SHADOW_MASK_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/shadow_mask.comp.spv"));
pub const SHADOW_MASK_WORDS_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/shadow_mask_words.comp.spv"));
pub const SCORE_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/score.comp.spv"));
pub const EFFECT_GRAZING_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/effect_grazing.comp.spv"));
pub const EFFECT_WORKING_VOLUME_COMP: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/effect_working_volume.comp.spv"));
pub const EFFECT_REFLECTIVITY_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/effect_reflectivity.comp.spv"));
pub const EFFECT_EDGES_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/effect_edges.comp.spv"));
pub const EFFECT_DROPOUT_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/effect_dropout.comp.spv"));
pub const EFFECT_NOISE_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/effect_noise.comp.spv"));
pub const EFFECT_QUANTIZE_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/effect_quantize.comp.spv"));

/// A shader module that lives only as long as pipeline creation needs it.
pub struct ShaderModule<'a> {
    ctx: &'a GpuContext,
    pub raw: vk::ShaderModule,
}

impl<'a> ShaderModule<'a> {
    pub fn new(ctx: &'a GpuContext, spirv: &[u8], name: &str) -> Result<Self> {
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .map_err(|e| Error::Unsupported(format!("embedded SPIR-V {name} is malformed: {e}")))?;
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: valid SPIR-V from shaderc.
        let raw = unsafe { ctx.device.create_shader_module(&info, None) }.vk(name)?;
        ctx.name_object(raw, name);
        Ok(Self { ctx, raw })
    }
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        // SAFETY: modules are not needed once pipelines are created.
        unsafe { self.ctx.device.destroy_shader_module(self.raw, None) };
    }
}
