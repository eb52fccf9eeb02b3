//! The graphics pipelines that draw a view into its attachments (targets.rs) by dynamic
//! rendering: three for each kind of view and projection (draw.rs, `ViewPipelines`), built by
//! the renderer's pipelines (src/render/pipelines.rs) and a rig's (src/render/pinhole/).

use super::draw::{DepthOrder, Projection, ViewPipelines};
use crate::error::{Error, Result};
use crate::gpu::shaders::{self, ShaderModule};
use crate::gpu::{GpuContext, DEPTH_FORMAT};
use crate::render::targets::ViewKind;
use ash::vk;

/// The three raster pipelines of one kind of view (draw.rs, `ViewPipelines`).
pub fn view_pipelines(
    ctx: &GpuContext,
    layout: vk::PipelineLayout,
    kind: ViewKind,
    projection: Projection,
) -> Result<ViewPipelines> {
    use Projection::{Orthographic, Pinhole};
    let (vert, frag, ties_frag, name) = match (projection, kind) {
        (Orthographic, ViewKind::Range) => {
            (shaders::RASTER_VERT, shaders::RASTER_RANGE_FRAG, shaders::RASTER_RANGE_TIES_FRAG, "range view")
        }
        (Orthographic, ViewKind::Shadow) => {
            (shaders::RASTER_VERT, shaders::RASTER_SHADOW_FRAG, shaders::RASTER_SHADOW_TIES_FRAG, "shadow view")
        }
        (Pinhole, ViewKind::Range) => (
            shaders::RASTER_PINHOLE_VERT,
            shaders::RASTER_PINHOLE_RANGE_FRAG,
            shaders::RASTER_PINHOLE_RANGE_TIES_FRAG,
            "pinhole reference view",
        ),
        (Pinhole, ViewKind::Shadow) => (
            shaders::RASTER_PINHOLE_VERT,
            shaders::RASTER_PINHOLE_SHADOW_FRAG,
            shaders::RASTER_PINHOLE_SHADOW_TIES_FRAG,
            "pinhole witness views",
        ),
    };
    let order = match projection {
        Orthographic => DepthOrder::NearestLeast,
        Pinhole => DepthOrder::NearestGreatest,
    };
    let vert = ShaderModule::new(ctx, vert, &format!("raster.vert ({name})"))?;
    let frag = ShaderModule::new(ctx, frag, &format!("raster.frag ({name})"))?;
    let ties_frag = ShaderModule::new(ctx, ties_frag, &format!("raster.frag ({name}, ties)"))?;
    let formats = kind.colour_formats();
    let pipeline = |frag, depth, what: &str| {
        raster_pipeline(ctx, layout, &vert, frag, &formats, (depth, order), &format!("{name}{what}"))
    };
    let mut view = ViewPipelines { order, ..ViewPipelines::NULL };
    // Each handle is kept as soon as it is made, so that a failure further on destroys it.
    let built = (|| {
        view.nearest = pipeline(Some(&frag), Depth::Nearest, "")?;
        view.depth_only = pipeline(None, Depth::Nearest, " (depth)")?;
        view.ties = pipeline(Some(&ties_frag), Depth::Tie, " (ties)")?;
        Ok(())
    })();
    match built {
        Ok(()) => Ok(view),
        Err(e) => {
            view.destroy(ctx);
            Err(e)
        }
    }
}

/// How a raster pipeline uses the depth buffer.
#[derive(Clone, Copy)]
enum Depth {
    /// The nearest fragment wins: depth test LESS (GREATER in a pinhole view), depth written.
    /// Without a fragment shader, a depth-only pass (colour writes masked).
    Nearest,
    /// After a depth-only pass of the same draws: every fragment whose depth, moved nearer by
    /// the tie tolerance (the fragment shader writes it), reaches the nearest passes
    /// (LESS_OR_EQUAL, or GREATER_OR_EQUAL, depth not written), so among coincident faces the last drawn wins. The range view draws
    /// in descending label order, so the lowest label wins a tie whatever the scene's order.
    Tie,
}

fn raster_pipeline(
    ctx: &GpuContext,
    layout: vk::PipelineLayout,
    vert: &ShaderModule,
    frag: Option<&ShaderModule>,
    color_formats: &[vk::Format],
    (depth_use, order): (Depth, DepthOrder),
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
    // An orthographic view's larger z is closer and maps to smaller depth (sensor.rs), so the
    // nearest surface wins with LESS; a pinhole view's nearest has the greatest depth.
    let (compare, write) = match (depth_use, order) {
        (Depth::Nearest, DepthOrder::NearestLeast) => (vk::CompareOp::LESS, true),
        (Depth::Tie, DepthOrder::NearestLeast) => (vk::CompareOp::LESS_OR_EQUAL, false),
        (Depth::Nearest, DepthOrder::NearestGreatest) => (vk::CompareOp::GREATER, true),
        (Depth::Tie, DepthOrder::NearestGreatest) => (vk::CompareOp::GREATER_OR_EQUAL, false),
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
    let pipeline = unsafe { ctx.device.create_graphics_pipelines(ctx.pipeline_cache(), &info, None) }
        .map(|p| p[0])
        .map_err(|(_, e)| Error::vulkan(&format!("creating the {name} pipeline"), e))?;
    ctx.name_object(pipeline, name);
    Ok(pipeline)
}
