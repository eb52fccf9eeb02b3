//! The compiled pipelines one `Renderer` owns and reuses: the range-view and shadow-view
//! rasterization pipelines (dynamic rendering into each view's attachments, targets.rs) and
//! the shadow-mask compute pipelines; and the effect, compute-raster and pinhole-rig
//! pipelines, built the first time a call needs them.

use crate::error::{Error, Result, VkResultExt};
use crate::gpu::GpuContext;
use crate::render::built_once::built_once;
use crate::render::pinhole::PinholePipelines;
use crate::render::raster::compute::{self, ComputeRasterPipelines};
use crate::render::raster::draw::Projection;
use crate::render::raster::draw::{DrawConstants, ViewPipelines};
use crate::render::raster::graphics::view_pipelines;
use crate::render::stages::effects::EffectPipelines;
use crate::render::stages::mask_pipelines::MaskPipelines;
use crate::render::stages::shadow_mask::{mask_pipelines, MaskVariant};
use crate::render::targets::{check_formats, ViewKind};
use ash::vk;
use std::sync::{Arc, OnceLock};

pub struct Pipelines {
    ctx: Arc<GpuContext>,
    pub raster_layout: vk::PipelineLayout,
    pub range: ViewPipelines,
    pub shadow: ViewPipelines,
    pub mask: MaskPipelines,
    pinhole: OnceLock<PinholePipelines>,
    effects: OnceLock<EffectPipelines>,
    compute_raster: OnceLock<ComputeRasterPipelines>,
}

impl Pipelines {
    pub fn new(ctx: &Arc<GpuContext>) -> Result<Self> {
        check_formats(ctx)?;
        let d = &ctx.device;
        let mask = mask_pipelines(ctx, MaskVariant::Attachments)?;
        let mut p = Self {
            ctx: ctx.clone(),
            raster_layout: vk::PipelineLayout::null(),
            range: ViewPipelines::NULL,
            shadow: ViewPipelines::NULL,
            pinhole: OnceLock::new(),
            mask,
            effects: OnceLock::new(),
            compute_raster: OnceLock::new(),
        };
        let raster_push = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT)
            .size(size_of::<DrawConstants>() as u32)];
        // SAFETY: valid device; p's Drop destroys whatever was created if a later step fails.
        p.raster_layout = unsafe {
            d.create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&raster_push), None)
        }
        .vk("creating the raster pipeline layout")?;
        p.range = view_pipelines(ctx, p.raster_layout, ViewKind::Range, Projection::Orthographic)?;
        p.shadow = view_pipelines(ctx, p.raster_layout, ViewKind::Shadow, Projection::Orthographic)?;
        Ok(p)
    }
}

impl Pipelines {
    /// A rig's pinhole pipelines, built on first use: a renderer that never meets a pinhole
    /// view never compiles them.
    pub fn pinhole(&self) -> Result<&PinholePipelines> {
        built_once(&self.ctx, &self.pinhole, || PinholePipelines::new(&self.ctx, self.raster_layout))
    }

    /// The effect pipelines, built on first use: a renderer that never meets an effect never
    /// compiles them.
    pub fn effects(&self) -> Result<&EffectPipelines> {
        built_once(&self.ctx, &self.effects, || EffectPipelines::new(&self.ctx))
    }

    /// The compute rasterizer's pipelines, built on first use; an error on a device without
    /// 64-bit buffer atomics.
    pub fn compute_raster(&self) -> Result<&ComputeRasterPipelines> {
        built_once(&self.ctx, &self.compute_raster, || {
            if !compute::device_supports(&self.ctx) {
                return Err(Error::Unsupported(format!(
                    "the compute rasterizer needs shaderInt64 and shaderBufferInt64Atomics, which {} lacks; \
                     use the graphics rasterizer",
                    self.ctx.device_name()
                )));
            }
            ComputeRasterPipelines::new(&self.ctx)
        })
    }
}

impl Drop for Pipelines {
    fn drop(&mut self) {
        let d = &self.ctx.device;
        // SAFETY: owned handles (null ones are ignored by Vulkan); no submission uses them
        // once the renderer is dropped.
        unsafe {
            self.range.destroy(&self.ctx);
            self.shadow.destroy(&self.ctx);
            // The pinhole pipelines go before the layout they were built with.
            drop(self.pinhole.take());
            d.destroy_pipeline_layout(self.raster_layout, None);
        }
    }
}
