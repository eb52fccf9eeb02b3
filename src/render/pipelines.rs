//! The compiled pipelines one `Renderer` owns and reuses: the range-view and shadow-view
//! rasterization pipelines (dynamic rendering into each view's attachments, targets.rs) and
//! the shadow-mask compute pipelines; and the effect and compute-raster pipelines, built the
//! first time a call needs them.

use crate::error::{Error, Result, VkResultExt};
use crate::gpu::shaders::{self, ShaderModule};
use crate::gpu::{GpuContext, DEPTH_FORMAT};
use crate::render::built_once::built_once;
use crate::render::raster::compute::{self, ComputeRasterPipelines};
use crate::render::raster::draw::{DrawConstants, ViewPipelines};
use crate::render::stages::effects::EffectPipelines;
use crate::render::stages::shadow_mask::{MaskPipelines, MaskVariant};
use crate::render::targets::{check_formats, ViewKind};
use ash::vk;
use std::sync::{Arc, OnceLock};

pub struct Pipelines {
    ctx: Arc<GpuContext>,
    pub raster_layout: vk::PipelineLayout,
    pub range: ViewPipelines,
    pub shadow: ViewPipelines,
    pub mask: MaskPipelines,
    effects: OnceLock<EffectPipelines>,
    compute_raster: OnceLock<ComputeRasterPipelines>,
}

impl Pipelines {
    pub fn new(ctx: &Arc<GpuContext>) -> Result<Self> {
        check_formats(ctx)?;
        let d = &ctx.device;
        let mask = MaskPipelines::new(ctx, MaskVariant::Attachments)?;
        let mut p = Self {
            ctx: ctx.clone(),
            raster_layout: vk::PipelineLayout::null(),
            range: ViewPipelines::default(),
            shadow: ViewPipelines::default(),
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
        let vert = ShaderModule::new(ctx, shaders::RASTER_VERT, "raster.vert")?;
        for kind in [ViewKind::Range, ViewKind::Shadow] {
            let (frag, ties_frag, name) = match kind {
                ViewKind::Range => (shaders::RASTER_RANGE_FRAG, shaders::RASTER_RANGE_TIES_FRAG, "range view"),
                ViewKind::Shadow => (shaders::RASTER_SHADOW_FRAG, shaders::RASTER_SHADOW_TIES_FRAG, "shadow view"),
            };
            let frag = ShaderModule::new(ctx, frag, &format!("raster.frag ({name})"))?;
            let ties_frag = ShaderModule::new(ctx, ties_frag, &format!("raster.frag ({name}, ties)"))?;
            let formats = kind.colour_formats();
            let pipeline = |frag, depth, what: &str| {
                raster_pipeline(ctx, p.raster_layout, &vert, frag, &formats, depth, &format!("{name}{what}"))
            };
            let view = match kind {
                ViewKind::Range => &mut p.range,
                ViewKind::Shadow => &mut p.shadow,
            };
            view.nearest = pipeline(Some(&frag), Depth::Nearest, "")?;
            view.depth_only = pipeline(None, Depth::Nearest, " (depth)")?;
            view.ties = pipeline(Some(&ties_frag), Depth::Tie, " (ties)")?;
        }
        Ok(p)
    }
}

impl Pipelines {
    /// The effect pipelines, built on first use: a renderer that never meets an effect never
    /// compiles them.
    pub fn effects(&self) -> Result<&EffectPipelines> {
        built_once(&self.effects, || EffectPipelines::new(&self.ctx))
    }

    /// The compute rasterizer's pipelines, built on first use; an error on a device without
    /// 64-bit buffer atomics.
    pub fn compute_raster(&self) -> Result<&ComputeRasterPipelines> {
        built_once(&self.compute_raster, || {
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
            for view in [&self.range, &self.shadow] {
                for pipeline in [view.nearest, view.depth_only, view.ties] {
                    d.destroy_pipeline(pipeline, None);
                }
            }
            d.destroy_pipeline_layout(self.raster_layout, None);
        }
    }
}

/// How a raster pipeline uses the depth buffer.
#[derive(Clone, Copy)]
enum Depth {
    /// The nearest fragment wins: depth test LESS, depth written. Without a fragment shader,
    /// a depth-only pass (colour writes masked).
    Nearest,
    /// After a depth-only pass of the same draws: every fragment whose depth, less the tie
    /// tolerance (the fragment shader writes it), reaches the nearest passes (LESS_OR_EQUAL,
    /// depth not written), so among coincident faces the last drawn wins. The range view draws
    /// in descending label order, so the lowest label wins a tie whatever the scene's order.
    Tie,
}

fn raster_pipeline(
    ctx: &GpuContext,
    layout: vk::PipelineLayout,
    vert: &ShaderModule,
    frag: Option<&ShaderModule>,
    color_formats: &[vk::Format],
    depth_use: Depth,
    name: &str,
) -> Result<vk::Pipeline> {
    let vertex_stage =
        vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vert.raw).name(c"main");
    let fragment_stage = frag.map(|frag| {
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(frag.raw)
            .name(c"main")
    });
    let stages: Vec<_> = std::iter::once(vertex_stage).chain(fragment_stage).collect();
    let bindings = [vk::VertexInputBindingDescription::default().stride(12).input_rate(vk::VertexInputRate::VERTEX)];
    let attributes = [vk::VertexInputAttributeDescription::default().format(vk::Format::R32G32B32_SFLOAT)];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
        .vertex_binding_descriptions(&bindings)
        .vertex_attribute_descriptions(&attributes);
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
    // The cull mode is set per draw (draw.rs): only a solid's triangles facing away are culled.
    // Counter-clockwise in the view's xy (y up, camera along −z) faces the camera; the viewport
    // turns y down, and Vulkan's counter-clockwise accounts for that.
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample =
        vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
    // Larger z is closer and maps to smaller depth (sensor.rs), so the nearest surface wins with LESS.
    let (compare, write) = match depth_use {
        Depth::Nearest => (vk::CompareOp::LESS, true),
        Depth::Tie => (vk::CompareOp::LESS_OR_EQUAL, false),
    };
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(true)
        .depth_write_enable(write)
        .depth_compare_op(compare);
    let write_mask = if frag.is_some() { vk::ColorComponentFlags::RGBA } else { vk::ColorComponentFlags::empty() };
    let blend_attachments: Vec<_> = color_formats
        .iter()
        .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(write_mask))
        .collect();
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR, vk::DynamicState::CULL_MODE];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(color_formats)
        .depth_attachment_format(DEPTH_FORMAT);
    let info = [vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering)];
    // SAFETY: all referenced state outlives the call.
    let pipeline = unsafe { ctx.device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) }
        .map(|p| p[0])
        .map_err(|(_, e)| Error::vulkan(&format!("creating the {name} pipeline"), e))?;
    ctx.name_object(pipeline, name);
    Ok(pipeline)
}
