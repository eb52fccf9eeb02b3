//! Buffers and images that own their memory. Each holds an `Arc<GpuContext>` and frees its
//! allocation and handle in `Drop`, so nothing can be destroyed twice or outlive the device.
//! Every object and allocation carries a name for validation messages.

use super::GpuContext;
use crate::error::{Error, Result, VkResultExt};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

#[derive(Debug, Clone, Copy)]
pub struct BufferDesc {
    pub size: u64,
    pub usage: vk::BufferUsageFlags,
    pub location: MemoryLocation,
}

impl BufferDesc {
    /// Written by the host, read by shaders (through a device address) or as vertex/index data.
    pub fn upload(size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self { size, usage: usage | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS, location: MemoryLocation::CpuToGpu }
    }

    /// Device-local scratch that shaders read and write through its device address, and that
    /// transfers can fill or copy from.
    pub fn gpu_storage(size: u64) -> Self {
        Self {
            size,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
                | vk::BufferUsageFlags::TRANSFER_SRC
                | vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuOnly,
        }
    }

    /// Written by the GPU (copies or storage writes), read by the host.
    pub fn readback(size: u64) -> Self {
        Self {
            size,
            usage: vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::GpuToCpu,
        }
    }
}

pub struct Buffer {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    pub(crate) size: u64,
}

impl Buffer {
    pub fn new(ctx: &Arc<GpuContext>, desc: BufferDesc, name: &str) -> Result<Self> {
        let d = &ctx.device;
        let info = vk::BufferCreateInfo::default().size(desc.size.max(4)).usage(desc.usage);
        // SAFETY: valid device and create info.
        let raw = unsafe { d.create_buffer(&info, None) }.vk(name)?;
        // SAFETY: raw was just created.
        let requirements = unsafe { d.get_buffer_memory_requirements(raw) };
        let allocation = ctx.allocator.lock().unwrap_or_else(|p| p.into_inner()).allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: desc.location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: unbound, unused buffer.
                unsafe { d.destroy_buffer(raw, None) };
                return Err(Error::from(e).context_for(name));
            }
        };
        let buffer = Self { ctx: ctx.clone(), raw, allocation: Some(allocation), size: desc.size };
        let a = buffer.allocation.as_ref().expect("just set");
        // SAFETY: memory from the allocator matches the requirements.
        unsafe { d.bind_buffer_memory(raw, a.memory(), a.offset()) }.vk(name)?;
        ctx.name_object(raw, name);
        Ok(buffer)
    }

    /// A host-visible buffer filled with `data`.
    pub fn with_data<T: bytemuck::Pod>(
        ctx: &Arc<GpuContext>,
        usage: vk::BufferUsageFlags,
        data: &[T],
        name: &str,
    ) -> Result<Self> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut buffer = Self::new(ctx, BufferDesc::upload(bytes.len() as u64, usage), name)?;
        buffer.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        Ok(buffer)
    }

    pub fn device_address(&self) -> u64 {
        let info = vk::BufferDeviceAddressInfo::default().buffer(self.raw);
        // SAFETY: created with SHADER_DEVICE_ADDRESS (BufferDesc::upload) on a device with the feature.
        unsafe { self.ctx.device.get_buffer_device_address(&info) }
    }

    /// The device address as the (low, high) words shaders take (GL_EXT_buffer_reference_uvec2).
    pub fn address_words(&self) -> [u32; 2] {
        let address = self.device_address();
        [address as u32, (address >> 32) as u32]
    }

    fn mapped_mut(&mut self) -> Result<&mut [u8]> {
        let size = self.size as usize;
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .map(|s| &mut s[..size])
            .ok_or_else(|| Error::Unsupported("a host-visible buffer was not mapped".into()))
    }

    /// The buffer's contents as `T`s. The caller has waited for the GPU writes and issued a
    /// host-read barrier; the memory is coherent (gpu-allocator's GpuToCpu).
    pub fn read<T: bytemuck::Pod>(&self) -> Result<Vec<T>> {
        let size = self.size as usize;
        let bytes = self
            .allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .map(|s| &s[..size])
            .ok_or_else(|| Error::Unsupported("a readback buffer was not mapped".into()))?;
        Ok(bytemuck::pod_collect_to_vec(bytes))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator.lock().unwrap_or_else(|p| p.into_inner()).free(a);
        }
        // SAFETY: owned handle; users wait for the GPU before dropping.
        unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
    }
}

#[derive(Debug, Clone, Copy)]
pub struct ImageDesc {
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub usage: vk::ImageUsageFlags,
}

impl ImageDesc {
    /// A colour attachment that compute passes read as a storage image and that can be
    /// copied out.
    pub fn attachment(format: vk::Format, extent: vk::Extent2D) -> Self {
        Self {
            format,
            extent,
            usage: vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST,
        }
    }

    pub fn depth(extent: vk::Extent2D) -> Self {
        Self { format: DEPTH_FORMAT, extent, usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT }
    }

    pub fn aspect(&self) -> vk::ImageAspectFlags {
        if self.format == DEPTH_FORMAT {
            vk::ImageAspectFlags::DEPTH
        } else {
            vk::ImageAspectFlags::COLOR
        }
    }
}

pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct Image {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::Image,
    pub(crate) view: vk::ImageView,
    allocation: Option<Allocation>,
    pub(crate) desc: ImageDesc,
}

impl Image {
    pub fn new(ctx: &Arc<GpuContext>, desc: ImageDesc, name: &str) -> Result<Self> {
        let d = &ctx.device;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.extent.width, height: desc.extent.height, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device and create info.
        let raw = unsafe { d.create_image(&info, None) }.vk(name)?;
        // SAFETY: raw was just created.
        let requirements = unsafe { d.get_image_memory_requirements(raw) };
        let allocation = ctx.allocator.lock().unwrap_or_else(|p| p.into_inner()).allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: unbound, unused image.
                unsafe { d.destroy_image(raw, None) };
                return Err(Error::from(e).context_for(name));
            }
        };
        let mut image = Self { ctx: ctx.clone(), raw, view: vk::ImageView::null(), allocation: Some(allocation), desc };
        let a = image.allocation.as_ref().expect("just set");
        // SAFETY: memory from the allocator matches the requirements.
        unsafe { d.bind_image_memory(raw, a.memory(), a.offset()) }.vk(name)?;
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(desc.format)
            .subresource_range(subresource_range(desc.aspect()));
        // SAFETY: bound image.
        image.view = unsafe { d.create_image_view(&view_info, None) }.vk(name)?;
        ctx.name_object(raw, name);
        ctx.name_object(image.view, name);
        Ok(image)
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.desc.extent
    }

    /// Records a copy of the image's top-left `width`×`height` pixels into the start of
    /// `buffer`, row after row. The image must be in TRANSFER_SRC layout and the buffer hold
    /// them.
    pub fn record_copy_to_buffer(&self, cmd: vk::CommandBuffer, buffer: &Buffer, (width, height): (u32, u32)) {
        let region = [vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
            )
            .image_extent(vk::Extent3D { width, height, depth: 1 })];
        // SAFETY: cmd is recording; the caller's barrier put the image in TRANSFER_SRC layout
        // and the region lies inside both.
        unsafe {
            self.ctx.device.cmd_copy_image_to_buffer(
                cmd,
                self.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &region,
            )
        };
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: owned handles; users wait for the GPU before dropping.
        unsafe {
            if self.view != vk::ImageView::null() {
                self.ctx.device.destroy_image_view(self.view, None);
            }
            self.ctx.device.destroy_image(self.raw, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator.lock().unwrap_or_else(|p| p.into_inner()).free(a);
        }
    }
}

pub(crate) fn subresource_range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1)
}

impl Error {
    fn context_for(self, name: &str) -> Self {
        match self {
            Error::OutOfMemory(what) => Error::OutOfMemory(format!("{what} for {name}")),
            other => other,
        }
    }
}
