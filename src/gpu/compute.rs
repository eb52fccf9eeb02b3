//! A compute pipeline with its descriptor-set layout (one binding per resource, compute stage)
//! and push constants, owning all three: what each compute pass of the product is built on;
//! and the one way a pass is recorded, with a [`StorageSet`] bound.

use super::descriptors::{SetShape, StorageSet};
use super::shaders::ShaderModule;
use super::Buffer;
use super::GpuContext;
use crate::error::{Error, Result, VkResultExt};
use ash::vk;
use std::sync::Arc;

pub struct ComputePipeline {
    ctx: Arc<GpuContext>,
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pub pipeline: vk::Pipeline,
}

impl ComputePipeline {
    /// A compute pipeline whose set 0 binds the resources of `shape`, from binding 0 (compute
    /// stage; the order a [`StorageSet`](super::StorageSet) writes them in), whose push
    /// constants are `push_size` bytes, and whose specialization constants take the values of
    /// `constants`, (constant_id, 32-bit value) pairs, the ids as reflection found them in the
    /// shader (`shaders::layout::spec`): codes the host defines once (such as the shadow tests)
    /// reach the shader from that one definition, by name.
    pub fn new(
        ctx: &Arc<GpuContext>,
        shape: SetShape,
        push_size: usize,
        spirv: &[u8],
        constants: &[(u32, u32)],
        name: &str,
    ) -> Result<Self> {
        shape.check_fits(push_size, &ctx.limits, name)?;
        let d = &ctx.device;
        let bindings: Vec<_> = shape
            .types()
            .enumerate()
            .map(|(b, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b as u32)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // SAFETY: valid device.
        let set_layout = unsafe {
            d.create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings), None)
        }
        .vk(&format!("creating the {name} descriptor layout"))?;
        // A shader without push constants (push_size 0) declares no range: a range may not be empty.
        let push_range =
            vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::COMPUTE).size(push_size as u32);
        let push = if push_size == 0 { Vec::new() } else { vec![push_range] };
        let set_layouts = [set_layout];
        // SAFETY: valid device and set layout.
        let layout = unsafe {
            d.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&push),
                None,
            )
        };
        let layout = match layout {
            Ok(l) => l,
            Err(e) => {
                // SAFETY: unused layout.
                unsafe { d.destroy_descriptor_set_layout(set_layout, None) };
                return Err(Error::vulkan(&format!("creating the {name} pipeline layout"), e));
            }
        };
        let made = ShaderModule::new(ctx, spirv, name).and_then(|module| {
            let entries: Vec<_> = (0..)
                .zip(constants)
                .map(|(i, &(constant_id, _))| vk::SpecializationMapEntry { constant_id, offset: 4 * i, size: 4 })
                .collect();
            let values: Vec<u32> = constants.iter().map(|&(_, value)| value).collect();
            let specialization =
                vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(&values));
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module.raw)
                .name(c"main")
                .specialization_info(&specialization);
            let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
            // SAFETY: valid layout and module.
            unsafe { d.create_compute_pipelines(ctx.pipeline_cache(), &info, None) }
                .map(|p| p[0])
                .map_err(|(_, e)| Error::vulkan(&format!("creating the {name} pipeline"), e))
        });
        match made {
            Ok(pipeline) => {
                ctx.name_object(pipeline, name);
                Ok(Self { ctx: ctx.clone(), set_layout, layout, pipeline })
            }
            Err(e) => {
                // SAFETY: unused layouts.
                unsafe {
                    d.destroy_pipeline_layout(layout, None);
                    d.destroy_descriptor_set_layout(set_layout, None);
                }
                Err(e)
            }
        }
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        let d = &self.ctx.device;
        // SAFETY: owned handles; no submission uses them once their owner is dropped.
        unsafe {
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

impl StorageSet {
    /// Records a compute dispatch of `groups` workgroups with this set bound as set 0 and
    /// `constants` pushed at offset 0 (none where empty). The set's resources must already be
    /// in GENERAL layout.
    pub fn dispatch(&self, cmd: vk::CommandBuffer, pipeline: &ComputePipeline, constants: &[u8], groups: [u32; 2]) {
        self.dispatch_slices(cmd, pipeline, constants, groups, 1);
    }

    /// As [`StorageSet::dispatch`], `slices` times over: `groups` workgroups for each z.
    pub fn dispatch_slices(
        &self,
        cmd: vk::CommandBuffer,
        pipeline: &ComputePipeline,
        constants: &[u8],
        groups: [u32; 2],
        slices: u32,
    ) {
        self.bind(cmd, pipeline, constants);
        // SAFETY: cmd is recording with the pipeline and set bound.
        unsafe { self.ctx.device.cmd_dispatch(cmd, groups[0], groups[1], slices) };
    }

    /// As [`StorageSet::dispatch`], with the workgroup counts read from `args` (a
    /// `VkDispatchIndirectCommand` at offset 0) when the dispatch runs.
    pub fn dispatch_indirect(
        &self,
        cmd: vk::CommandBuffer,
        pipeline: &ComputePipeline,
        constants: &[u8],
        args: &Buffer,
    ) {
        self.dispatch_indirect_at(cmd, pipeline, constants, (args, 0));
    }

    /// As [`StorageSet::dispatch_indirect`], the command at `offset` in `args` (a multiple
    /// of 4 within it).
    pub fn dispatch_indirect_at(
        &self,
        cmd: vk::CommandBuffer,
        pipeline: &ComputePipeline,
        constants: &[u8],
        (args, offset): (&Buffer, u64),
    ) {
        self.bind(cmd, pipeline, constants);
        // SAFETY: cmd is recording with the pipeline and set bound; args holds the command at
        // offset.
        unsafe { self.ctx.device.cmd_dispatch_indirect(cmd, args.raw, offset) };
    }

    fn bind(&self, cmd: vk::CommandBuffer, pipeline: &ComputePipeline, constants: &[u8]) {
        let (layout, pipeline) = (pipeline.layout, pipeline.pipeline);
        let d = &self.ctx.device;
        // SAFETY: cmd is recording; pipeline and layout match the set's layout; the set's
        // resources outlive the submission.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, layout, 0, &[self.set], &[]);
            if !constants.is_empty() {
                d.cmd_push_constants(cmd, layout, vk::ShaderStageFlags::COMPUTE, 0, constants);
            }
        }
    }
}
