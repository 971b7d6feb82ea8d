//! What irad needs to know of a physical device (the limits `irad info` prints), and the choice
//! of device: discrete GPU, then integrated, then virtual, then CPU (lavapipe), unless
//! `--device <index|name substring>` says otherwise.

use std::fmt;

use ash::vk;

use super::error::{GpuError, GpuResult, VkContext};

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum DeviceKind {
    Discrete,
    Integrated,
    Virtual,
    Cpu,
    Other,
}

impl DeviceKind {
    fn from_vk(t: vk::PhysicalDeviceType) -> Self {
        match t {
            vk::PhysicalDeviceType::DISCRETE_GPU => DeviceKind::Discrete,
            vk::PhysicalDeviceType::INTEGRATED_GPU => DeviceKind::Integrated,
            vk::PhysicalDeviceType::VIRTUAL_GPU => DeviceKind::Virtual,
            vk::PhysicalDeviceType::CPU => DeviceKind::Cpu,
            _ => DeviceKind::Other,
        }
    }
}

impl fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DeviceKind::Discrete => "discrete GPU",
            DeviceKind::Integrated => "integrated GPU",
            DeviceKind::Virtual => "virtual GPU",
            DeviceKind::Cpu => "CPU",
            DeviceKind::Other => "other",
        })
    }
}

/// A physical device as irad sees it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// Position in the loader's enumeration: what `--device <index>` means.
    pub index: usize,
    pub name: String,
    pub kind: DeviceKind,
    pub api_version: (u32, u32, u32),
    /// Driver name and version string (VkPhysicalDeviceDriverProperties).
    pub driver: String,
    pub max_storage_buffer_range: u64,
    pub max_compute_shared_memory: u32,
    pub max_workgroup_invocations: u32,
    pub max_workgroup_size: [u32; 3],
    pub max_workgroup_count: [u32; 3],
    pub max_push_constants: u32,
    pub subgroup_size: u32,
    /// Subgroup arithmetic (subgroupInclusiveAdd, ...) in compute shaders: the scans need it.
    pub subgroup_arithmetic: bool,
    /// VK_EXT_shader_atomic_float with shaderBufferFloat32AtomicAdd.
    pub float_atomic_add: bool,
    /// The queue family irad would use: the first with compute, preferring one with timestamps.
    pub compute_queue_family: Option<u32>,
    /// Valid bits of that family's timestamps; 0 means no timestamps.
    pub timestamp_valid_bits: u32,
    pub timestamp_period_ns: f32,
    /// Largest device-local memory heap.
    pub device_local_heap: u64,
}

impl DeviceInfo {
    pub fn timestamps(&self) -> bool {
        self.timestamp_valid_bits > 0
    }
}

pub(crate) fn enumerate(
    instance: &ash::Instance,
) -> GpuResult<Vec<(vk::PhysicalDevice, DeviceInfo)>> {
    let devices = match unsafe { instance.enumerate_physical_devices() } {
        Ok(d) => d,
        Err(vk::Result::ERROR_INITIALIZATION_FAILED) => return Err(GpuError::NoDevice),
        Err(result) => {
            return Err(GpuError::Vulkan {
                call: "vkEnumeratePhysicalDevices",
                result,
            })
        }
    };
    devices
        .into_iter()
        .enumerate()
        .map(|(index, pd)| Ok((pd, describe(instance, pd, index)?)))
        .collect()
}

fn describe(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    index: usize,
) -> GpuResult<DeviceInfo> {
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let api = props.api_version;
    let has_1_1 = vk::api_version_minor(api) >= 1 || vk::api_version_major(api) > 1;
    let has_1_2 = vk::api_version_minor(api) >= 2 || vk::api_version_major(api) > 1;

    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
    if has_1_2 {
        props2 = props2.push_next(&mut driver);
    }
    if has_1_1 {
        unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    }
    let limits = props.limits;

    let extensions = unsafe { instance.enumerate_device_extension_properties(pd) }
        .vk("vkEnumerateDeviceExtensionProperties")?;
    let has_atomic_float = extensions
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::shader_atomic_float::NAME));
    let mut float_atomic_add = false;
    if has_atomic_float {
        let mut atomics = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut atomics);
        unsafe { instance.get_physical_device_features2(pd, &mut features2) };
        float_atomic_add = atomics.shader_buffer_float32_atomic_add == vk::TRUE;
    }

    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let compute: Vec<(u32, &vk::QueueFamilyProperties)> = families
        .iter()
        .enumerate()
        .filter(|(_, f)| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
        .map(|(i, f)| (i as u32, f))
        .collect();
    let family = compute
        .iter()
        .find(|(_, f)| f.timestamp_valid_bits > 0)
        .or(compute.first());

    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let device_local_heap = memory.memory_heaps[..memory.memory_heap_count as usize]
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0);

    let driver = if has_1_2 {
        let name = driver
            .driver_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let info = driver
            .driver_info_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        format!("{name} {info}").trim().to_string()
    } else {
        format!("driver version {:#x}", props.driver_version)
    };

    Ok(DeviceInfo {
        index,
        name: props
            .device_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        kind: DeviceKind::from_vk(props.device_type),
        api_version: (
            vk::api_version_major(api),
            vk::api_version_minor(api),
            vk::api_version_patch(api),
        ),
        driver,
        max_storage_buffer_range: limits.max_storage_buffer_range as u64,
        max_compute_shared_memory: limits.max_compute_shared_memory_size,
        max_workgroup_invocations: limits.max_compute_work_group_invocations,
        max_workgroup_size: limits.max_compute_work_group_size,
        max_workgroup_count: limits.max_compute_work_group_count,
        max_push_constants: limits.max_push_constants_size,
        subgroup_size: subgroup.subgroup_size,
        subgroup_arithmetic: subgroup
            .supported_stages
            .contains(vk::ShaderStageFlags::COMPUTE)
            && subgroup
                .supported_operations
                .contains(vk::SubgroupFeatureFlags::BASIC | vk::SubgroupFeatureFlags::ARITHMETIC),
        float_atomic_add,
        compute_queue_family: family.map(|(i, _)| *i),
        timestamp_valid_bits: family.map(|(_, f)| f.timestamp_valid_bits).unwrap_or(0),
        timestamp_period_ns: limits.timestamp_period,
        device_local_heap,
    })
}

/// `--device` or IRAD_DEVICE: an index into `irad info`'s list, or a case-insensitive
/// substring of a name, with where the user gave it (for messages).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceSelector {
    pub by: DeviceBy,
    /// Given as the `--device` flag or the IRAD_DEVICE variable.
    pub origin: SelectorOrigin,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceBy {
    Index(usize),
    Name(String),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SelectorOrigin {
    Flag,
    Environment,
}

/// The variable that stands for `--device` when the flag is not given.
pub const DEVICE_VARIABLE: &str = "IRAD_DEVICE";

impl DeviceSelector {
    /// IRAD_DEVICE's selector: None where it is unset or blank, an error naming the variable
    /// where it is not a selector.
    pub fn from_env() -> Result<Option<DeviceSelector>, String> {
        match std::env::var(DEVICE_VARIABLE) {
            Ok(v) if !v.trim().is_empty() => v
                .parse::<DeviceSelector>()
                .map(|s| {
                    Some(DeviceSelector {
                        origin: SelectorOrigin::Environment,
                        ..s
                    })
                })
                .map_err(|e| format!("{DEVICE_VARIABLE}={v}: {e}")),
            Ok(_) | Err(std::env::VarError::NotPresent) => Ok(None),
            Err(std::env::VarError::NotUnicode(v)) => Err(format!(
                "{DEVICE_VARIABLE}={}: not valid UTF-8",
                v.to_string_lossy()
            )),
        }
    }

    /// As the user wrote it: `--device 7` or `IRAD_DEVICE=7`.
    pub fn shown(&self) -> String {
        match self.origin {
            SelectorOrigin::Flag => format!("--device {self}"),
            SelectorOrigin::Environment => format!("{DEVICE_VARIABLE}={self}"),
        }
    }
}

/// Parses a `--device` value (origin `Flag`).
impl std::str::FromStr for DeviceSelector {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        if s.is_empty() {
            return Err(
                "empty device selector: give an index or part of a device name (see `irad info`)"
                    .into(),
            );
        }
        let by = match s.parse::<usize>() {
            Ok(i) => DeviceBy::Index(i),
            Err(_) => DeviceBy::Name(s.to_string()),
        };
        Ok(DeviceSelector {
            by,
            origin: SelectorOrigin::Flag,
        })
    }
}

impl fmt::Display for DeviceSelector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.by {
            DeviceBy::Index(i) => write!(f, "{i}"),
            DeviceBy::Name(n) => write!(f, "{n}"),
        }
    }
}

/// Picks the device to run on among `devices` (in enumeration order).
pub fn choose(devices: &[DeviceInfo], selector: Option<&DeviceSelector>) -> GpuResult<usize> {
    let usable = |d: &DeviceInfo| d.compute_queue_family.is_some() && d.subgroup_arithmetic;
    let available = || {
        if devices.is_empty() {
            return "none".to_string();
        }
        devices
            .iter()
            .map(|d| format!("{}: {} ({})", d.index, d.name, d.kind))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let bad = |value: &DeviceSelector, reason: &str| GpuError::BadDeviceSelector {
        value: value.shown(),
        reason: reason.to_string(),
        available: available(),
    };
    match selector {
        None => devices
            .iter()
            .filter(|d| usable(d))
            .min_by_key(|d| (d.kind, d.index))
            .map(|d| d.index)
            .ok_or(GpuError::NoDevice),
        Some(
            sel @ DeviceSelector {
                by: DeviceBy::Index(i),
                ..
            },
        ) => match devices.get(*i) {
            None => Err(bad(sel, "no device has that index")),
            Some(d) if !usable(d) => Err(bad(
                sel,
                "that device lacks a compute queue or subgroup arithmetic",
            )),
            Some(d) => Ok(d.index),
        },
        Some(
            sel @ DeviceSelector {
                by: DeviceBy::Name(name),
                ..
            },
        ) => {
            let needle = name.to_lowercase();
            let matches: Vec<&DeviceInfo> = devices
                .iter()
                .filter(|d| usable(d) && d.name.to_lowercase().contains(&needle))
                .collect();
            match matches.as_slice() {
                [] => Err(bad(sel, "no device name contains it")),
                [d] => Ok(d.index),
                _ => Err(bad(sel, "several device names contain it; give an index")),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dev(index: usize, name: &str, kind: DeviceKind) -> DeviceInfo {
        DeviceInfo {
            index,
            name: name.into(),
            kind,
            api_version: (1, 3, 0),
            driver: String::new(),
            max_storage_buffer_range: 1 << 27,
            max_compute_shared_memory: 32768,
            max_workgroup_invocations: 1024,
            max_workgroup_size: [1024; 3],
            max_workgroup_count: [65535; 3],
            max_push_constants: 128,
            subgroup_size: 8,
            subgroup_arithmetic: true,
            float_atomic_add: true,
            compute_queue_family: Some(0),
            timestamp_valid_bits: 64,
            timestamp_period_ns: 1.0,
            device_local_heap: 1 << 30,
        }
    }

    #[test]
    fn prefers_discrete_then_integrated_then_cpu() {
        let d = [
            dev(0, "llvmpipe", DeviceKind::Cpu),
            dev(1, "Intel UHD", DeviceKind::Integrated),
            dev(2, "H100", DeviceKind::Discrete),
        ];
        assert_eq!(choose(&d, None).unwrap(), 2);
        assert_eq!(choose(&d[..2], None).unwrap(), 1);
        assert_eq!(choose(&d[..1], None).unwrap(), 0);
        assert!(matches!(choose(&[], None), Err(GpuError::NoDevice)));
    }

    #[test]
    fn selector_by_index_and_name() {
        let d = [
            dev(0, "llvmpipe (LLVM 15)", DeviceKind::Cpu),
            dev(1, "NVIDIA H100", DeviceKind::Discrete),
        ];
        assert_eq!(choose(&d, Some(&"0".parse().unwrap())).unwrap(), 0);
        assert_eq!(choose(&d, Some(&"llvm".parse().unwrap())).unwrap(), 0);
        assert_eq!(choose(&d, Some(&"h100".parse().unwrap())).unwrap(), 1);
        let err = choose(&d, Some(&"7".parse().unwrap()))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("--device 7") && err.contains("llvmpipe"),
            "{err}"
        );
        let err = choose(&d, Some(&"radeon".parse().unwrap()))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("radeon") && err.contains("NVIDIA H100"),
            "{err}"
        );
        assert!("  ".parse::<DeviceSelector>().is_err());
        // A selector from IRAD_DEVICE is named as the variable, not as the flag.
        let from_env = DeviceSelector {
            origin: SelectorOrigin::Environment,
            ..("99".parse().unwrap())
        };
        let err = choose(&d, Some(&from_env)).unwrap_err().to_string();
        assert!(
            err.contains("IRAD_DEVICE=99:") && !err.contains("--device"),
            "{err}"
        );
    }
}
