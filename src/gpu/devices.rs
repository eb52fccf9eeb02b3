//! The Vulkan devices this machine offers, for a caller choosing one: each one's index in the
//! loader's order, name, UUID (which tells apart two cards of one model, and is what CUDA
//! tools print, where `CUDA_VISIBLE_DEVICES` does not filter Vulkan devices) and kind.

use crate::error::{Error, Result, VkResultExt};
use ash::vk;

/// One device as the loader lists it.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    /// The device's UUID, as 8-4-4-4-12 lowercase hex digits (empty for a Vulkan 1.0 device).
    pub uuid: String,
    /// "discrete", "integrated", "virtual", "cpu" or "other".
    pub kind: &'static str,
}

/// A device's UUID in the usual text form; empty for a Vulkan 1.0 device, which cannot say it
/// (and which rangesynth cannot use).
pub(crate) fn device_uuid(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
) -> String {
    if props.api_version < vk::API_VERSION_1_1 {
        return String::new();
    }
    let mut id = vk::PhysicalDeviceIDProperties::default();
    let mut properties = vk::PhysicalDeviceProperties2::default().push_next(&mut id);
    // SAFETY: pd came from the instance (Vulkan 1.1 or later, which rangesynth's devices are).
    unsafe { instance.get_physical_device_properties2(pd, &mut properties) };
    let hex: String = id.device_uuid.iter().map(|b| format!("{b:02x}")).collect();
    format!("{}-{}-{}-{}-{}", &hex[0..8], &hex[8..12], &hex[12..16], &hex[16..20], &hex[20..32])
}

fn kind_of(device_type: vk::PhysicalDeviceType) -> &'static str {
    match device_type {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual",
        vk::PhysicalDeviceType::CPU => "cpu",
        _ => "other",
    }
}

/// Every device the Vulkan loader lists, whether or not rangesynth can use it (creating a
/// renderer on one it cannot says why).
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    // SAFETY: loading the system Vulkan loader.
    let entry = unsafe { ash::Entry::load() }.map_err(|e| Error::VulkanUnavailable(e.to_string()))?;
    let app = vk::ApplicationInfo::default().application_name(c"rangesynth").api_version(vk::API_VERSION_1_3);
    let info = vk::InstanceCreateInfo::default().application_info(&app);
    // SAFETY: every pointer in `info` outlives the call.
    let instance = unsafe { entry.create_instance(&info, None) }.vk("creating the Vulkan instance")?;
    // SAFETY: plain enumeration.
    let listed = unsafe { instance.enumerate_physical_devices() }.vk("listing Vulkan devices");
    let devices = listed.map(|devices| {
        devices
            .into_iter()
            .enumerate()
            .map(|(index, pd)| {
                // SAFETY: pd came from the instance.
                let props = unsafe { instance.get_physical_device_properties(pd) };
                DeviceInfo {
                    index,
                    name: props.device_name_as_c_str().unwrap_or(c"?").to_string_lossy().into_owned(),
                    uuid: device_uuid(&instance, pd, &props),
                    kind: kind_of(props.device_type),
                }
            })
            .collect()
    });
    // SAFETY: nothing else was created from the instance.
    unsafe { instance.destroy_instance(None) };
    devices
}
