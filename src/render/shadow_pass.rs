//! The compute pass that applies the shadow test (shaders/shadow_mask.comp, src/shadow.rs)
//! to the range view, reading both views' attachments and writing the shadowed labels.

use super::pipelines::Pipelines;
use super::targets::ViewTargets;
use crate::error::{Result, VkResultExt};
use crate::gpu::{Buffer, GpuContext};
use crate::sensor::{Sensor, ViewGrid};
use crate::shadow::{ShadowMode, DEPTH_BIAS_PIXELS, DEPTH_BIAS_RELATIVE};
use ash::vk;
use std::sync::Arc;

/// Push constants of the mask pass; matches `shaders/shadow_mask.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MaskConstants {
    range_grid: [f32; 4],
    shadow_grid: [f32; 4],
    sizes: [i32; 4],
    cos_theta: f32,
    sin_theta: f32,
    bias_pitch: f32,
    bias_relative: f32,
    mode: u32,
    _pad: [u32; 3],
}

impl MaskConstants {
    pub fn new(sensor: &Sensor, mode: ShadowMode, range: &ViewGrid, shadow: &ViewGrid) -> Self {
        let grid = |g: &ViewGrid| [g.origin[0] as f32, g.origin[1] as f32, g.pitch[0] as f32, g.pitch[1] as f32];
        Self {
            range_grid: grid(range),
            shadow_grid: grid(shadow),
            sizes: [range.width as i32, range.height as i32, shadow.width as i32, shadow.height as i32],
            cos_theta: sensor.theta().cos() as f32,
            sin_theta: sensor.theta().sin() as f32,
            bias_pitch: (DEPTH_BIAS_PIXELS * sensor.pitch[0]) as f32,
            bias_relative: DEPTH_BIAS_RELATIVE as f32,
            mode: mode.shader_code(),
            _pad: [0; 3],
        }
    }
}

/// The descriptor set binding both views' attachments and the output labels.
pub struct MaskBindings {
    ctx: Arc<GpuContext>,
    pool: vk::DescriptorPool,
    pub set: vk::DescriptorSet,
}

impl MaskBindings {
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &Pipelines,
        range: &ViewTargets,
        shadow: &ViewTargets,
        masked: &Buffer,
    ) -> Result<Self> {
        let d = &ctx.device;
        let sizes = [
            vk::DescriptorPoolSize { ty: vk::DescriptorType::STORAGE_IMAGE, descriptor_count: 5 },
            vk::DescriptorPoolSize { ty: vk::DescriptorType::STORAGE_BUFFER, descriptor_count: 1 },
        ];
        // SAFETY: valid device.
        let pool = unsafe { d.create_descriptor_pool(&vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes), None) }
            .vk("creating the shadow-mask descriptor pool")?;
        let mut bindings = Self { ctx: ctx.clone(), pool, set: vk::DescriptorSet::null() };
        let layouts = [pipelines.mask_set_layout];
        // SAFETY: the pool has room for one set of this layout.
        bindings.set = unsafe { d.allocate_descriptor_sets(&vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts)) }
            .vk("allocating the shadow-mask descriptor set")?[0];
        let slope = shadow.slope.as_ref().unwrap_or(&shadow.z);
        let images: Vec<[vk::DescriptorImageInfo; 1]> = [&range.label, &range.z, &shadow.label, &shadow.z, slope]
            .iter()
            .map(|i| [vk::DescriptorImageInfo::default().image_view(i.view).image_layout(vk::ImageLayout::GENERAL)])
            .collect();
        let buffer = [vk::DescriptorBufferInfo::default().buffer(masked.raw).range(vk::WHOLE_SIZE)];
        let mut writes: Vec<_> = images
            .iter()
            .enumerate()
            .map(|(b, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(bindings.set)
                    .dst_binding(b as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                    .image_info(info)
            })
            .collect();
        writes.push(
            vk::WriteDescriptorSet::default()
                .dst_set(bindings.set)
                .dst_binding(5)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&buffer),
        );
        // SAFETY: the set, views and buffer are alive.
        unsafe { d.update_descriptor_sets(&writes, &[]) };
        Ok(bindings)
    }

    pub fn record(&self, cmd: vk::CommandBuffer, pipelines: &Pipelines, constants: &MaskConstants) {
        let d = &self.ctx.device;
        let groups = |n: i32| (n as u32).div_ceil(8);
        // SAFETY: cmd is recording; the set's resources are in GENERAL layout by now.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipelines.mask);
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, pipelines.mask_layout, 0, &[self.set], &[]);
            d.cmd_push_constants(cmd, pipelines.mask_layout, vk::ShaderStageFlags::COMPUTE, 0, bytemuck::bytes_of(constants));
            d.cmd_dispatch(cmd, groups(constants.sizes[0]), groups(constants.sizes[1]), 1);
        }
    }
}

impl Drop for MaskBindings {
    fn drop(&mut self) {
        // SAFETY: owned; the submission using the set has completed.
        unsafe { self.ctx.device.destroy_descriptor_pool(self.pool, None) };
    }
}
