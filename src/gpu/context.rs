//! The headless Vulkan instance and device that every GPU resource belongs to.
//!
//! Device choice: the device named by [`ContextOptions::device`] (a case-insensitive
//! substring of its name), else the first discrete GPU, else the first device. Validation
//! (the Khronos layer with synchronization validation) is on when asked; its messages are
//! collected, not printed, so tests can fail on any of them and the CLI can show them.
//!
//! Resources hold an `Arc<GpuContext>`, so the context (allocator, then device, then
//! instance) is torn down only after the last of them.
//!
//! Dynamic rendering, synchronization2 and a dynamic cull mode are core in Vulkan 1.3; on a
//! 1.2 device they come from VK_KHR_dynamic_rendering, VK_KHR_synchronization2 and
//! VK_EXT_extended_dynamic_state, whose entry points differ but whose semantics do not. The
//! context picks one set at creation and every caller goes through it
//! ([`GpuContext::cmd_pipeline_barrier2`] and its siblings).

use super::devices::device_uuid;
use super::pipeline_cache::{default_cache_dir, PipelineCache, PipelineCacheReport};
use crate::error::{Error, Result, VkResultExt};
use ash::{ext, khr, vk};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_void, CStr, CString};
use std::mem::ManuallyDrop;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

/// Environment variable naming the device to use (substring of its name).
pub const DEVICE_ENV: &str = "RANGESYNTH_DEVICE";
/// Environment variable turning validation on (`1`).
pub const VALIDATION_ENV: &str = "RANGESYNTH_VALIDATION";
/// Environment variable capping the Vulkan version used (`1.2` or `1.3`).
pub const MAX_VULKAN_ENV: &str = "RANGESYNTH_MAX_VULKAN";

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

#[derive(Debug, Clone, Default)]
pub struct ContextOptions {
    /// Khronos validation with synchronization validation.
    pub validation: bool,
    /// Pick the device whose name contains this (case-insensitive), or whose UUID or index
    /// (in the loader's order) it is (`list_devices`).
    pub device: Option<String>,
    /// Use at most this Vulkan version (`vk::API_VERSION_1_2` takes the extension path even
    /// on a 1.3 device, which is how the tests cover it); `None` uses what the device has.
    pub max_vulkan_version: Option<u32>,
    /// Where the driver's compiled pipelines are kept between runs (pipeline_cache.rs); `None`
    /// keeps them for this context only.
    pub pipeline_cache_dir: Option<PathBuf>,
}

impl ContextOptions {
    /// Options from `RANGESYNTH_VALIDATION`, `RANGESYNTH_DEVICE` and `RANGESYNTH_MAX_VULKAN`
    /// (an unreadable version is ignored), and the pipeline cache in its usual place
    /// ([`default_cache_dir`]).
    pub fn from_env() -> Self {
        Self {
            validation: std::env::var(VALIDATION_ENV).is_ok_and(|v| v == "1"),
            device: std::env::var(DEVICE_ENV).ok().filter(|d| !d.is_empty()),
            max_vulkan_version: std::env::var(MAX_VULKAN_ENV).ok().and_then(|v| match v.trim() {
                "1.2" => Some(vk::API_VERSION_1_2),
                "1.3" => Some(vk::API_VERSION_1_3),
                _ => None,
            }),
            pipeline_cache_dir: default_cache_dir(),
        }
    }
}

pub struct GpuContext {
    /// Keeps the Vulkan loader library loaded for as long as the instance lives.
    _entry: ash::Entry,
    instance: ash::Instance,
    debug: Option<DebugMessenger>,
    pub(crate) physical_device: vk::PhysicalDevice,
    pub(crate) device: ash::Device,
    debug_names: Option<ext::debug_utils::Device>,
    commands: Vulkan13Commands,
    queue: Mutex<vk::Queue>,
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Every pipeline is built through it, and it is written back to disk after each build
    /// ([`GpuContext::save_pipeline_cache`]).
    pipeline_cache: PipelineCache,
    pub(crate) limits: vk::PhysicalDeviceLimits,
    /// Nanoseconds per timestamp tick; `None` when the queue has no timestamps.
    pub(crate) timestamp_period: Option<f64>,
    device_name: String,
    /// Whether the device is a CPU (a software rasterizer such as lavapipe), not a GPU.
    is_cpu: bool,
    /// Whether shaders may use 64-bit integers and 64-bit atomics on storage buffers (the
    /// compute rasterizer needs both).
    int64_atomics: bool,
    /// Command pools, buffers and fences of finished submissions, reused by the next.
    recorders: Mutex<Vec<Recorder>>,
    /// Pipeline barriers recorded so far ([`GpuContext::barriers_recorded`]).
    barriers: AtomicU64,
    /// Submissions whose wait is not over, and the most there have been at once
    /// ([`GpuContext::most_submissions_in_flight`]).
    in_flight: AtomicU64,
    most_in_flight: AtomicU64,
    /// Nanoseconds spent recording command buffers ([`GpuContext::recording_time`]).
    recording_nanos: AtomicU64,
}

/// What one submission records into and waits on; one per submission in flight.
struct Recorder {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

/// Where the Vulkan 1.3 commands rangesynth uses come from.
enum Vulkan13Commands {
    Core,
    Extensions {
        rendering: khr::dynamic_rendering::Device,
        sync2: khr::synchronization2::Device,
        dynamic_state: ext::extended_dynamic_state::Device,
    },
}

struct DebugMessenger {
    loader: ext::debug_utils::Instance,
    messenger: vk::DebugUtilsMessengerEXT,
    messages: ValidationLog,
}

/// The messages validation reported on one context, oldest first: a handle that outlives the
/// context, so that what the layer reports while the context is destroyed (objects left
/// alive) can still be read.
#[derive(Clone, Default)]
pub struct ValidationLog(Arc<Mutex<Vec<String>>>);

impl ValidationLog {
    /// The messages so far; taking them empties the log.
    pub fn take(&self) -> Vec<String> {
        std::mem::take(&mut *self.0.lock().unwrap_or_else(|p| p.into_inner()))
    }

    /// Whether the context it was made for is gone (no messenger writes to it any more).
    pub fn is_closed(&self) -> bool {
        Arc::strong_count(&self.0) == 1
    }
}

// SAFETY: the raw pointer is a Box owned by the messenger, only read through its Mutex.
unsafe impl Send for DebugMessenger {}
unsafe impl Sync for DebugMessenger {}

impl GpuContext {
    pub fn new(options: &ContextOptions) -> Result<Arc<Self>> {
        // SAFETY: loading the system Vulkan loader; no other Vulkan state exists yet.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| Error::VulkanUnavailable(e.to_string()))?;
        let validation = options.validation && validation_available(&entry)?;
        if options.validation && !validation {
            return Err(Error::Unsupported(
                "validation was requested but VK_LAYER_KHRONOS_validation is not installed \
                 (Debian: vulkan-validationlayers)"
                    .into(),
            ));
        }
        let app = vk::ApplicationInfo::default().application_name(c"rangesynth").api_version(vk::API_VERSION_1_3);
        let layers = if validation { vec![VALIDATION_LAYER.as_ptr()] } else { vec![] };
        let extensions = if validation {
            vec![ext::debug_utils::NAME.as_ptr(), ext::validation_features::NAME.as_ptr()]
        } else {
            vec![]
        };
        let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation {
            info = info.push_next(&mut features);
        }
        // SAFETY: every pointer in `info` outlives the call.
        let instance = unsafe { entry.create_instance(&info, None) }.vk("creating the Vulkan instance")?;
        let debug = if validation { Some(DebugMessenger::new(&entry, &instance)?) } else { None };

        let cap = options.max_vulkan_version.unwrap_or(vk::API_VERSION_1_3);
        let chosen = choose_device(&instance, options.device.as_deref(), cap);
        let (physical_device, queue_family, core_1_3) = match chosen {
            Ok(found) => found,
            Err(e) => {
                drop(debug);
                // SAFETY: nothing else was created from the instance.
                unsafe { instance.destroy_instance(None) };
                return Err(e);
            }
        };
        // SAFETY: physical_device came from this instance.
        let properties = unsafe { instance.get_physical_device_properties(physical_device) };
        let device_name = properties.device_name_as_c_str().unwrap_or(c"?").to_string_lossy().into_owned();

        let priorities = [1.0];
        let queue_info =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        let int64_atomics = supports_int64_atomics(&instance, physical_device);
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default()
            .buffer_device_address(true)
            .shader_buffer_int64_atomics(int64_atomics);
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true);
        let mut rendering = vk::PhysicalDeviceDynamicRenderingFeatures::default().dynamic_rendering(true);
        let mut sync2 = vk::PhysicalDeviceSynchronization2Features::default().synchronization2(true);
        let mut dynamic_state =
            vk::PhysicalDeviceExtendedDynamicStateFeaturesEXT::default().extended_dynamic_state(true);
        // gl_PrimitiveID in a fragment shader needs geometryShader.
        let base = vk::PhysicalDeviceFeatures::default().geometry_shader(true).shader_int64(int64_atomics);
        let extensions = if core_1_3 { vec![] } else { EXTENSIONS_1_2.iter().map(|e| e.as_ptr()).collect() };
        let mut device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_features(&base)
            .enabled_extension_names(&extensions)
            .push_next(&mut v12);
        device_info = if core_1_3 {
            device_info.push_next(&mut v13)
        } else {
            device_info.push_next(&mut rendering).push_next(&mut sync2).push_next(&mut dynamic_state)
        };
        // SAFETY: the features were checked by choose_device; pointers outlive the call.
        let device =
            unsafe { instance.create_device(physical_device, &device_info, None) }.vk("creating the device")?;
        // SAFETY: family and index 0 were requested above.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        // SAFETY: valid physical device.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        let timestamp_period = (families[queue_family as usize].timestamp_valid_bits > 0)
            .then_some(f64::from(properties.limits.timestamp_period));
        let uuid = device_uuid(&instance, physical_device, &properties);
        let pipeline_cache = PipelineCache::open(&device, &properties, &uuid, options.pipeline_cache_dir.as_deref());
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: true,
            allocation_sizes: Default::default(),
        })?;
        let debug_names = debug.as_ref().map(|_| ext::debug_utils::Device::new(&instance, &device));
        let commands = match core_1_3 {
            true => Vulkan13Commands::Core,
            false => Vulkan13Commands::Extensions {
                rendering: khr::dynamic_rendering::Device::new(&instance, &device),
                sync2: khr::synchronization2::Device::new(&instance, &device),
                dynamic_state: ext::extended_dynamic_state::Device::new(&instance, &device),
            },
        };
        Ok(Arc::new(Self {
            _entry: entry,
            instance,
            debug,
            physical_device,
            device,
            debug_names,
            commands,
            queue: Mutex::new(queue),
            queue_family,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            pipeline_cache,
            limits: properties.limits,
            timestamp_period,
            device_name,
            is_cpu: properties.device_type == vk::PhysicalDeviceType::CPU,
            int64_atomics,
            recorders: Mutex::new(Vec::new()),
            barriers: AtomicU64::new(0),
            in_flight: AtomicU64::new(0),
            most_in_flight: AtomicU64::new(0),
            recording_nanos: AtomicU64::new(0),
        }))
    }

    /// Whether the device has 64-bit integers and 64-bit buffer atomics in shaders (enabled
    /// where it has them).
    pub fn has_int64_atomics(&self) -> bool {
        self.int64_atomics
    }

    /// The most bytes the device binds as one storage buffer (maxStorageBufferRange): it bounds
    /// the pixels of an image (a word a pixel) and of a compute-rasterized view (8 bytes).
    pub fn max_storage_buffer_range(&self) -> u64 {
        u64::from(self.limits.max_storage_buffer_range)
    }

    /// Half the side of the square viewport through which the graphics pipeline draws every
    /// view (src/render/raster/draw.rs, `ViewportFrame`): half the largest power of two within the
    /// device's viewport dimensions (maxViewportDimensions: 16,384 on lavapipe, so 8,192).
    pub fn viewport_half_side(&self) -> f32 {
        let [width, height] = self.limits.max_viewport_dimensions;
        (1u32 << width.min(height).max(1).ilog2()) as f32 / 2.0
    }

    /// The most pixels a view may have on a side: an image the device can create, inside the
    /// viewport.
    pub fn max_view_side(&self) -> u32 {
        self.limits.max_image_dimension2_d.min(2 * self.viewport_half_side() as u32)
    }

    /// Whether the device runs the core Vulkan 1.3 path (else the 1.2 extensions).
    pub fn core_vulkan_1_3(&self) -> bool {
        matches!(self.commands, Vulkan13Commands::Core)
    }

    /// `vkCmdBeginRendering`, core or KHR.
    ///
    /// # Safety
    /// As for the Vulkan command: `cmd` is recording and everything `info` names is alive.
    pub(crate) unsafe fn cmd_begin_rendering(&self, cmd: vk::CommandBuffer, info: &vk::RenderingInfo) {
        // SAFETY: forwarded from the caller.
        unsafe {
            match &self.commands {
                Vulkan13Commands::Core => self.device.cmd_begin_rendering(cmd, info),
                Vulkan13Commands::Extensions { rendering, .. } => rendering.cmd_begin_rendering(cmd, info),
            }
        }
    }

    /// `vkCmdEndRendering`, core or KHR.
    ///
    /// # Safety
    /// `cmd` is recording inside a render pass begun with [`Self::cmd_begin_rendering`].
    pub(crate) unsafe fn cmd_end_rendering(&self, cmd: vk::CommandBuffer) {
        // SAFETY: forwarded from the caller.
        unsafe {
            match &self.commands {
                Vulkan13Commands::Core => self.device.cmd_end_rendering(cmd),
                Vulkan13Commands::Extensions { rendering, .. } => rendering.cmd_end_rendering(cmd),
            }
        }
    }

    /// `vkCmdSetCullMode`, core or EXT.
    ///
    /// # Safety
    /// `cmd` is recording with a pipeline bound whose cull mode is dynamic.
    pub(crate) unsafe fn cmd_set_cull_mode(&self, cmd: vk::CommandBuffer, mode: vk::CullModeFlags) {
        // SAFETY: forwarded from the caller.
        unsafe {
            match &self.commands {
                Vulkan13Commands::Core => self.device.cmd_set_cull_mode(cmd, mode),
                Vulkan13Commands::Extensions { dynamic_state, .. } => dynamic_state.cmd_set_cull_mode(cmd, mode),
            }
        }
    }

    /// `vkCmdPipelineBarrier2`, core or KHR.
    ///
    /// # Safety
    /// `cmd` is recording; every handle in `info` is alive.
    pub(crate) unsafe fn cmd_pipeline_barrier2(&self, cmd: vk::CommandBuffer, info: &vk::DependencyInfo) {
        self.barriers.fetch_add(1, Ordering::Relaxed);
        // SAFETY: forwarded from the caller.
        unsafe {
            match &self.commands {
                Vulkan13Commands::Core => self.device.cmd_pipeline_barrier2(cmd, info),
                Vulkan13Commands::Extensions { sync2, .. } => sync2.cmd_pipeline_barrier2(cmd, info),
            }
        }
    }

    /// `vkCmdWriteTimestamp2`, core or KHR.
    ///
    /// # Safety
    /// `cmd` is recording; `query` is within `pool` and was reset.
    pub(crate) unsafe fn cmd_write_timestamp2(
        &self,
        cmd: vk::CommandBuffer,
        stage: vk::PipelineStageFlags2,
        pool: vk::QueryPool,
        query: u32,
    ) {
        // SAFETY: forwarded from the caller.
        unsafe {
            match &self.commands {
                Vulkan13Commands::Core => self.device.cmd_write_timestamp2(cmd, stage, pool, query),
                Vulkan13Commands::Extensions { sync2, .. } => sync2.cmd_write_timestamp2(cmd, stage, pool, query),
            }
        }
    }

    /// # Safety
    /// The queue is externally synchronized; the command buffers are complete.
    unsafe fn queue_submit2(
        &self,
        queue: vk::Queue,
        submits: &[vk::SubmitInfo2],
        fence: vk::Fence,
    ) -> ash::prelude::VkResult<()> {
        // SAFETY: forwarded from the caller.
        unsafe {
            match &self.commands {
                Vulkan13Commands::Core => self.device.queue_submit2(queue, submits, fence),
                Vulkan13Commands::Extensions { sync2, .. } => sync2.queue_submit2(queue, submits, fence),
            }
        }
    }

    pub(crate) fn instance(&self) -> &ash::Instance {
        &self.instance
    }

    /// Size of the smallest device-local memory heap, in bytes: what a batch may plan against.
    pub fn device_local_heap_size(&self) -> u64 {
        // SAFETY: valid physical device of a live instance.
        let memory = unsafe { self.instance.get_physical_device_memory_properties(self.physical_device) };
        memory.memory_heaps[..memory.memory_heap_count as usize]
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .min()
            .unwrap_or(0)
    }

    /// The cache every pipeline is built through.
    pub(crate) fn pipeline_cache(&self) -> vk::PipelineCache {
        self.pipeline_cache.raw
    }

    /// Writes the pipeline cache back to disk where pipelines were built since it was last
    /// read or written; a failure is noted in [`GpuContext::pipeline_cache_report`], never
    /// returned. Called after each set of pipelines is built, and when the context ends.
    pub fn save_pipeline_cache(&self) {
        self.pipeline_cache.save(&self.device);
    }

    /// Where the pipeline cache is, what was found there, and how its last write went.
    pub fn pipeline_cache_report(&self) -> PipelineCacheReport {
        self.pipeline_cache.report()
    }

    pub fn device_name(&self) -> &str {
        &self.device_name
    }

    /// Pipeline barriers recorded through this context so far, in every command buffer. Each
    /// makes a GPU finish the work before it before starting the work after it, so a batch
    /// should take them per run of hypotheses, not per hypothesis (verify/batch.rs; tests and
    /// bench_verify count them).
    pub fn barriers_recorded(&self) -> u64 {
        self.barriers.load(Ordering::Relaxed)
    }

    /// The most submissions this context has had in flight at once (submitted, their wait not
    /// yet over): 2 where a verification recorded a chunk while the device ran another
    /// (verify/lanes.rs; tests/verify.rs reads it).
    pub fn most_submissions_in_flight(&self) -> u64 {
        self.most_in_flight.load(Ordering::Relaxed)
    }

    /// Host time spent recording command buffers through this context so far, in every
    /// thread: the host's share of a verification, which several chunks in flight overlap with
    /// the device's work (verify/lanes.rs; bench_verify prints it a hypothesis).
    pub fn recording_time(&self) -> std::time::Duration {
        std::time::Duration::from_nanos(self.recording_nanos.load(Ordering::Relaxed))
    }

    /// Whether the device is a CPU (a software rasterizer such as lavapipe), not a GPU.
    pub fn is_cpu(&self) -> bool {
        self.is_cpu
    }

    pub fn validation_enabled(&self) -> bool {
        self.debug.is_some()
    }

    /// Validation messages (warnings and errors) collected so far, oldest first; taking
    /// them empties the log.
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.debug.as_ref().map(|d| d.messages.take()).unwrap_or_default()
    }

    /// The log of this context's validation messages, which stays readable after the context
    /// is dropped; `None` where validation is off.
    pub fn validation_log(&self) -> Option<ValidationLog> {
        self.debug.as_ref().map(|d| d.messages.clone())
    }

    /// Gives a Vulkan object a name that validation messages will show.
    pub(crate) fn name_object<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(names) = &self.debug_names {
            let name = CString::new(name.replace('\0', " ")).unwrap_or_default();
            let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
            // SAFETY: the handle belongs to this device; naming is best-effort.
            let _ = unsafe { names.set_debug_utils_object_name(&info) };
        }
    }

    /// Records commands into a command buffer, submits it and waits for it to finish. Each
    /// call takes its own recorder (command pool, buffer and fence) from the free list, or
    /// makes one, so several threads may submit at once; a recorder goes back to the list
    /// after a submission that finished, is destroyed when recording failed, and is given up
    /// (never waited for) when the GPU did not finish.
    pub(crate) fn submit_and_wait(
        &self,
        name: &str,
        record: impl FnOnce(vk::CommandBuffer) -> Result<()>,
    ) -> Result<()> {
        let d = &self.device;
        let free = self.recorders.lock().unwrap_or_else(|p| p.into_inner()).pop();
        let recorder = match free {
            Some(r) => r,
            None => self.new_recorder()?,
        };
        let mut submitted = false;
        let result = (|| {
            let cmd = recorder.cmd;
            self.name_object(cmd, name);
            // SAFETY: the pool's only buffer is not in use (its last submission was waited on).
            unsafe { d.reset_command_pool(recorder.pool, vk::CommandPoolResetFlags::empty()) }
                .vk("resetting a command pool")?;
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            let recording = std::time::Instant::now();
            // SAFETY: a reset command buffer.
            unsafe { d.begin_command_buffer(cmd, &begin) }.vk("beginning a command buffer")?;
            record(cmd)?;
            // SAFETY: recording started above.
            unsafe { d.end_command_buffer(cmd) }.vk("ending a command buffer")?;
            let nanos = u64::try_from(recording.elapsed().as_nanos()).unwrap_or(u64::MAX);
            self.recording_nanos.fetch_add(nanos, Ordering::Relaxed);
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
            {
                let queue = self.queue.lock().unwrap_or_else(|p| p.into_inner());
                // SAFETY: the command buffer is complete; the queue is externally synchronized by the Mutex.
                unsafe { self.queue_submit2(*queue, &submit, recorder.fence) }.vk(name)?;
                submitted = true;
            }
            let now = self.in_flight.fetch_add(1, Ordering::Relaxed) + 1;
            self.most_in_flight.fetch_max(now, Ordering::Relaxed);
            // SAFETY: the fence was just submitted.
            let waited = unsafe { d.wait_for_fences(&[recorder.fence], true, SUBMIT_TIMEOUT_NS) }.vk(name);
            self.in_flight.fetch_sub(1, Ordering::Relaxed);
            match waited {
                Err(Error::Vulkan { result: vk::Result::TIMEOUT, .. }) => Err(Error::DeviceLost(format!(
                    "{name}: the GPU did not finish within {} s",
                    SUBMIT_TIMEOUT_NS / 1_000_000_000
                ))),
                // SAFETY: the fence is signalled; nothing waits on it now.
                Ok(()) => unsafe { d.reset_fences(&[recorder.fence]) }.vk("resetting a fence"),
                other => other,
            }
        })();
        match (&result, submitted) {
            (Ok(()), _) => self.recorders.lock().unwrap_or_else(|p| p.into_inner()).push(recorder),
            // SAFETY: nothing was submitted, so nothing uses the recorder.
            (Err(_), false) => unsafe { self.destroy_recorder(recorder) },
            // Submitted but not seen to finish (a hung or lost device): the GPU may still use
            // it, and waiting could block for ever, so it is left to the device's end.
            (Err(_), true) => {}
        }
        result
    }

    fn new_recorder(&self) -> Result<Recorder> {
        let d = &self.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid device and family.
        let pool = unsafe { d.create_command_pool(&pool_info, None) }.vk("creating a command pool")?;
        let alloc = vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1);
        // SAFETY: the pool is valid.
        let cmd = unsafe { d.allocate_command_buffers(&alloc) }.map(|c| c[0]);
        // SAFETY: valid device.
        let fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) };
        match (cmd, fence) {
            (Ok(cmd), Ok(fence)) => Ok(Recorder { pool, cmd, fence }),
            (cmd, fence) => {
                // SAFETY: unused objects of this device.
                unsafe {
                    if let Ok(fence) = fence {
                        d.destroy_fence(fence, None);
                    }
                    d.destroy_command_pool(pool, None);
                }
                Err(Error::vulkan("making a command buffer and fence", cmd.err().or(fence.err()).unwrap_or_default()))
            }
        }
    }

    /// # Safety
    /// Nothing may use the recorder any more.
    unsafe fn destroy_recorder(&self, recorder: Recorder) {
        // SAFETY: the caller's promise; the pool frees its buffer.
        unsafe {
            self.device.destroy_fence(recorder.fence, None);
            self.device.destroy_command_pool(recorder.pool, None);
        }
    }
}

/// How long one submission may run before it is treated as a lost device.
const SUBMIT_TIMEOUT_NS: u64 = 600_000_000_000;

impl Drop for GpuContext {
    fn drop(&mut self) {
        // SAFETY: every resource holds an Arc to this context, so none is left; the
        // allocator goes before the device, the device before the instance.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.pipeline_cache.save(&self.device);
            self.pipeline_cache.destroy(&self.device);
            for recorder in std::mem::take(self.recorders.get_mut().unwrap_or_else(|p| p.into_inner())) {
                self.destroy_recorder(recorder);
            }
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            drop(self.debug.take());
            self.instance.destroy_instance(None);
        }
    }
}

fn validation_available(entry: &ash::Entry) -> Result<bool> {
    // SAFETY: plain enumeration.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }.vk("listing Vulkan layers")?;
    Ok(layers.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)))
}

impl DebugMessenger {
    fn new(entry: &ash::Entry, instance: &ash::Instance) -> Result<Self> {
        let loader = ext::debug_utils::Instance::new(entry, instance);
        let messages = ValidationLog::default();
        let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(collect_message))
            .user_data(Arc::as_ptr(&messages.0).cast_mut().cast());
        // SAFETY: the messenger holds `messages` (an Arc) until it is destroyed in Drop.
        let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
            .map_err(|e| Error::vulkan("creating the validation messenger", e))?;
        Ok(Self { loader, messenger, messages })
    }
}

impl Drop for DebugMessenger {
    fn drop(&mut self) {
        // SAFETY: the instance is still alive (its owner drops the messenger first); the log
        // the messenger writes to lives until after it is destroyed (a field, dropped after
        // this).
        unsafe { self.loader.destroy_debug_utils_messenger(self.messenger, None) };
    }
}

unsafe extern "system" fn collect_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data; `user` is the Mutex inside the messenger's
    // ValidationLog, alive while the messenger is.
    unsafe {
        let message = (*data).message_as_c_str().map(|m| m.to_string_lossy().into_owned()).unwrap_or_default();
        let log = &*(user as *const Mutex<Vec<String>>);
        log.lock().unwrap_or_else(|p| p.into_inner()).push(format!("{severity:?}: {message}"));
    }
    vk::FALSE
}

/// Device extensions that stand in for Vulkan 1.3 on a 1.2 device.
const EXTENSIONS_1_2: [&CStr; 3] =
    [khr::dynamic_rendering::NAME, khr::synchronization2::NAME, ext::extended_dynamic_state::NAME];

/// The requested, else first discrete, else first device that has what rangesynth needs,
/// with a queue family doing graphics and compute; and whether it takes the core 1.3 path
/// (its version, capped at `cap`, is 1.3 or later).
fn choose_device(instance: &ash::Instance, wanted: Option<&str>, cap: u32) -> Result<(vk::PhysicalDevice, u32, bool)> {
    // SAFETY: plain enumeration.
    let devices = unsafe { instance.enumerate_physical_devices() }.vk("listing Vulkan devices")?;
    let mut candidates = Vec::new();
    let mut rejected = Vec::new();
    for (index, pd) in devices.into_iter().enumerate() {
        // SAFETY: pd came from the instance.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = props.device_name_as_c_str().unwrap_or(c"?").to_string_lossy().into_owned();
        if let Some(w) = wanted {
            // A number is an index alone: "1" must not pick a card whose name holds a 1.
            let chosen = match w.trim().parse::<usize>() {
                Ok(wanted_index) => wanted_index == index,
                Err(_) => {
                    // NVIDIA's tools (nvidia-smi, NVIDIA_VISIBLE_DEVICES) write the same UUID
                    // with a "GPU-" before it.
                    let w = w.trim();
                    let uuid = if w.get(..4).is_some_and(|p| p.eq_ignore_ascii_case("GPU-")) { &w[4..] } else { w };
                    super::devices::device_uuid(instance, pd, &props).eq_ignore_ascii_case(uuid)
                        || name.to_lowercase().contains(&w.to_lowercase())
                }
            };
            if !chosen {
                rejected.push(format!("{name} (not named {w:?})"));
                continue;
            }
        }
        let core_1_3 = props.api_version.min(cap) >= vk::API_VERSION_1_3;
        match suitability(instance, pd, &props, core_1_3) {
            Ok(family) => {
                candidates.push((pd, family, props.device_type == vk::PhysicalDeviceType::DISCRETE_GPU, core_1_3))
            }
            Err(why) => rejected.push(format!("{name} ({why})")),
        }
    }
    candidates
        .iter()
        .find(|c| c.2)
        .or(candidates.first())
        .map(|&(pd, family, _, core_1_3)| (pd, family, core_1_3))
        .ok_or_else(|| {
            Error::NoDevice(if rejected.is_empty() {
                "the Vulkan loader found no device (Debian: install mesa-vulkan-drivers for lavapipe)".into()
            } else {
                format!("none fits: {}", rejected.join("; "))
            })
        })
}

fn suitability(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
    core_1_3: bool,
) -> Result<u32, String> {
    if props.api_version < vk::API_VERSION_1_2 {
        return Err("needs Vulkan 1.2".into());
    }
    if !core_1_3 {
        // SAFETY: valid physical device.
        let available = unsafe { instance.enumerate_device_extension_properties(pd) }.map_err(|e| e.to_string())?;
        let has = |name: &CStr| available.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
        if let Some(missing) = EXTENSIONS_1_2.iter().find(|&&name| !has(name)) {
            return Err(format!("a Vulkan 1.2 device needs {}", missing.to_string_lossy()));
        }
    }
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    // The extension feature structs are the 1.3 ones under their KHR names; querying them
    // answers for either path.
    let mut rendering = vk::PhysicalDeviceDynamicRenderingFeatures::default();
    let mut sync2 = vk::PhysicalDeviceSynchronization2Features::default();
    // Core in 1.3 without a feature to ask for; the 1.2 path needs the extension's.
    let mut dynamic_state = vk::PhysicalDeviceExtendedDynamicStateFeaturesEXT::default();
    let mut features =
        vk::PhysicalDeviceFeatures2::default().push_next(&mut v12).push_next(&mut rendering).push_next(&mut sync2);
    if !core_1_3 {
        features = features.push_next(&mut dynamic_state);
    }
    // SAFETY: valid physical device; the chain outlives the call.
    unsafe { instance.get_physical_device_features2(pd, &mut features) };
    let geometry_shader = features.features.geometry_shader;
    let dynamic_cull_mode = if core_1_3 { vk::TRUE } else { dynamic_state.extended_dynamic_state };
    let missing: Vec<&str> = [
        (geometry_shader, "geometryShader"),
        (v12.buffer_device_address, "bufferDeviceAddress"),
        (rendering.dynamic_rendering, "dynamicRendering"),
        (sync2.synchronization2, "synchronization2"),
        (dynamic_cull_mode, "extendedDynamicState"),
    ]
    .iter()
    .filter(|(on, _)| *on == vk::FALSE)
    .map(|(_, n)| *n)
    .collect();
    if !missing.is_empty() {
        return Err(format!("lacks {}", missing.join(", ")));
    }
    // SAFETY: valid physical device.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
        .map(|i| i as u32)
        .ok_or_else(|| "no queue family with graphics and compute".into())
}

/// Whether the device has `shaderInt64` and `shaderBufferInt64Atomics`.
fn supports_int64_atomics(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut v12);
    // SAFETY: valid physical device; the chain outlives the call.
    unsafe { instance.get_physical_device_features2(pd, &mut features) };
    features.features.shader_int64 == vk::TRUE && v12.shader_buffer_int64_atomics == vk::TRUE
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tests' guarantee that "any validation message fails the test" is only as good as
    /// the capture: a real violation must show up in the log.
    #[test]
    fn validation_messages_are_captured() {
        let ctx = GpuContext::new(&ContextOptions { validation: true, ..Default::default() })
            .expect("a Vulkan device with validation");
        assert!(ctx.take_validation_messages().is_empty());
        // VUID-VkBufferCreateInfo-size-00912: size must be greater than 0.
        let info = vk::BufferCreateInfo::default().size(0).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
        // SAFETY: deliberately invalid create info; the layer reports it and the result is discarded.
        if let Ok(buffer) = unsafe { ctx.device.create_buffer(&info, None) } {
            // SAFETY: the buffer is unused.
            unsafe { ctx.device.destroy_buffer(buffer, None) };
        }
        let messages = ctx.take_validation_messages();
        assert!(messages.iter().any(|m| m.contains("00912")), "{messages:?}");
    }

    /// What validation reports while a context is destroyed (here, a buffer left alive) is
    /// read from its log after the context is gone.
    #[test]
    fn the_log_outlives_its_context() {
        let ctx = GpuContext::new(&ContextOptions { validation: true, ..Default::default() })
            .expect("a Vulkan device with validation");
        let log = ctx.validation_log().expect("validation is on");
        let info = vk::BufferCreateInfo::default().size(16).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
        // SAFETY: a valid buffer, deliberately never destroyed, so that destroying the device
        // reports it.
        unsafe { ctx.device.create_buffer(&info, None) }.expect("a buffer");
        assert!(!log.is_closed());
        drop(ctx);
        assert!(log.is_closed());
        let messages = log.take();
        assert!(messages.iter().any(|m| m.contains("vkDestroyDevice")), "{messages:?}");
    }
}
