//! The GPU context: one logical device with one compute queue on the chosen physical device.
//! Everything created from it (buffers, kernels, command recordings) holds it alive, so
//! teardown always runs in the right order and destroys every object.

use std::sync::{Arc, Mutex};

use ash::vk;

use super::device_info::{self, DeviceInfo, DeviceSelector};
use super::error::{GpuError, GpuResult, VkContext};
use super::instance::{Instance, Validation, ValidationLog};

#[derive(Clone, Debug)]
pub struct ContextOptions {
    pub device: Option<DeviceSelector>,
    pub validation: Validation,
    /// Every buffer device-local only, written and read through staging buffers, as on a
    /// discrete GPU, even where device memory is host-visible (lavapipe, integrated GPUs): so
    /// the staging path runs in CI. IRAD_FORCE_STAGING=1.
    pub force_staging: bool,
}

impl ContextOptions {
    /// Whether IRAD_FORCE_STAGING asks for forced staging (1, true or yes; an error naming
    /// the variable for a value that is neither on nor off).
    pub fn force_staging_from_env() -> GpuResult<bool> {
        super::env_switch::read("IRAD_FORCE_STAGING")
    }

    /// The options the environment asks for: IRAD_DEVICE, IRAD_VALIDATE and
    /// IRAD_FORCE_STAGING, each checked (an error names a variable whose value is not one).
    pub fn from_env() -> GpuResult<Self> {
        Ok(ContextOptions {
            device: DeviceSelector::from_env().map_err(GpuError::Environment)?,
            validation: Validation::from_env()?,
            force_staging: Self::force_staging_from_env()?,
        })
    }
}

impl Default for ContextOptions {
    /// The best device, no validation, no forced staging (`from_env` reads the environment).
    fn default() -> Self {
        ContextOptions {
            device: None,
            validation: Validation::Off,
            force_staging: false,
        }
    }
}

/// Lists every device the loader sees, in `--device` index order.
pub fn list_devices() -> GpuResult<Vec<DeviceInfo>> {
    let instance = Instance::new(Validation::Off)?;
    Ok(device_info::enumerate(&instance.raw)?
        .into_iter()
        .map(|(_, info)| info)
        .collect())
}

/// A cheap handle; clones share the device.
#[derive(Clone)]
pub struct Context {
    pub(crate) shared: Arc<Shared>,
}

pub(crate) struct Shared {
    pub(crate) device: ash::Device,
    pub(crate) queue: Mutex<vk::Queue>,
    pub(crate) command_pool: Mutex<vk::CommandPool>,
    pub(crate) memory: vk::PhysicalDeviceMemoryProperties,
    pub(crate) info: DeviceInfo,
    pub(crate) force_staging: bool,
    /// The verdict of src/gpu/subgroup_layout.rs, probed at the first scan.
    pub(crate) subgroup_layout: std::sync::OnceLock<Result<(), String>>,
    pub(crate) debug_names: Option<ash::ext::debug_utils::Device>,
    // Dropped last: the device must go before the instance.
    pub(crate) instance: Arc<Instance>,
}

impl Context {
    pub fn new(options: &ContextOptions) -> GpuResult<Self> {
        let instance = Instance::new(options.validation)?;
        let devices = device_info::enumerate(&instance.raw)?;
        let infos: Vec<DeviceInfo> = devices.iter().map(|(_, i)| i.clone()).collect();
        let chosen = device_info::choose(&infos, options.device.as_ref())?;
        let (physical, info) = devices[chosen].clone();
        if !info.subgroup_arithmetic {
            return Err(GpuError::MissingFeature {
                device: info.name.clone(),
                feature: "subgroup arithmetic in compute shaders (Vulkan 1.1)".into(),
            });
        }
        let family = info.compute_queue_family.ok_or(GpuError::NoDevice)?;

        let priorities = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let mut extensions = Vec::new();
        let device_extensions =
            unsafe { instance.raw.enumerate_device_extension_properties(physical) }
                .vk("vkEnumerateDeviceExtensionProperties")?;
        if device_extensions
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(ash::khr::portability_subset::NAME))
        {
            // Required wherever a device lists it (MoltenVK).
            extensions.push(ash::khr::portability_subset::NAME.as_ptr());
        }
        let mut atomics = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        if info.float_atomic_add {
            // Enabled explicitly: lavapipe runs float atomics without it, but that is invalid usage.
            extensions.push(ash::ext::shader_atomic_float::NAME.as_ptr());
            atomics = atomics
                .shader_buffer_float32_atomics(true)
                .shader_buffer_float32_atomic_add(true);
        }
        let mut create = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&extensions);
        if info.float_atomic_add {
            create = create.push_next(&mut atomics);
        }
        let device =
            unsafe { instance.raw.create_device(physical, &create, None) }.vk("vkCreateDevice")?;
        let queue = unsafe { device.get_device_queue(family, 0) };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(family)
            .flags(
                vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER
                    | vk::CommandPoolCreateFlags::TRANSIENT,
            );
        let command_pool = match unsafe { device.create_command_pool(&pool_info, None) } {
            Ok(p) => p,
            Err(result) => {
                unsafe { device.destroy_device(None) };
                return Err(GpuError::Vulkan {
                    call: "vkCreateCommandPool",
                    result,
                });
            }
        };
        let memory = unsafe { instance.raw.get_physical_device_memory_properties(physical) };
        let debug_names = instance
            .validating()
            .then(|| ash::ext::debug_utils::Device::new(&instance.raw, &device));
        Ok(Context {
            shared: Arc::new(Shared {
                device,
                queue: Mutex::new(queue),
                command_pool: Mutex::new(command_pool),
                memory,
                info,
                force_staging: options.force_staging,
                subgroup_layout: std::sync::OnceLock::new(),
                debug_names,
                instance,
            }),
        })
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }

    /// Whether buffers are forced behind staging copies (ContextOptions::force_staging).
    pub fn force_staging(&self) -> bool {
        self.shared.force_staging
    }

    /// Checks, once per context, that subgroup lanes follow the invocation order the scans
    /// rely on (src/gpu/subgroup_layout.rs).
    pub fn check_subgroup_layout(&self) -> GpuResult<()> {
        if let Some(verdict) = self.shared.subgroup_layout.get() {
            return verdict.clone().map_err(|detail| GpuError::SubgroupLayout {
                device: self.info().name.clone(),
                detail,
            });
        }
        let result = super::subgroup_layout::probe(self);
        let verdict = match &result {
            Ok(()) => Ok(()),
            Err(GpuError::SubgroupLayout { detail, .. }) => Err(detail.clone()),
            // A failure to run the probe is reported, not cached.
            Err(_) => return result,
        };
        let _ = self.shared.subgroup_layout.set(verdict);
        result
    }

    /// Whether the validation layer is on for this context.
    pub fn validating(&self) -> bool {
        self.shared.instance.validating()
    }

    /// The validation layer's messages so far; the log outlives the context, so dropping every
    /// handle and then reading it also catches objects leaked at teardown.
    pub fn validation_log(&self) -> ValidationLog {
        self.shared.instance.log.clone()
    }

    pub(crate) fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    /// Records `record` into a fresh command buffer, submits it and waits for it.
    pub(crate) fn one_shot(&self, record: impl FnOnce(vk::CommandBuffer)) -> GpuResult<()> {
        let cb = self.allocate_command_buffer()?;
        let result = (|| {
            let begin = vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            unsafe { self.device().begin_command_buffer(cb, &begin) }.vk("vkBeginCommandBuffer")?;
            record(cb);
            unsafe { self.device().end_command_buffer(cb) }.vk("vkEndCommandBuffer")?;
            self.submit_and_wait(cb)
        })();
        self.free_command_buffer(cb);
        result
    }

    pub(crate) fn allocate_command_buffer(&self) -> GpuResult<vk::CommandBuffer> {
        let pool = self.shared.command_pool.lock().expect("command pool lock");
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(*pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        Ok(unsafe { self.device().allocate_command_buffers(&info) }
            .vk("vkAllocateCommandBuffers")?[0])
    }

    pub(crate) fn free_command_buffer(&self, cb: vk::CommandBuffer) {
        let pool = self.shared.command_pool.lock().expect("command pool lock");
        unsafe { self.device().free_command_buffers(*pool, &[cb]) };
    }

    pub(crate) fn submit_and_wait(&self, cb: vk::CommandBuffer) -> GpuResult<()> {
        let device = self.device();
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }
            .vk("vkCreateFence")?;
        let cbs = [cb];
        let submit = [vk::SubmitInfo::default().command_buffers(&cbs)];
        let result = {
            let queue = self.shared.queue.lock().expect("queue lock");
            unsafe { device.queue_submit(*queue, &submit, fence) }.vk("vkQueueSubmit")
        }
        .and_then(|_| {
            unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")
        });
        unsafe { device.destroy_fence(fence, None) };
        result
    }

    /// The index of a memory type allowed by `type_bits` with all of `required`, preferring one
    /// that also has `preferred`.
    pub(crate) fn memory_type(
        &self,
        type_bits: u32,
        required: vk::MemoryPropertyFlags,
        preferred: vk::MemoryPropertyFlags,
    ) -> Option<u32> {
        let mem = &self.shared.memory;
        let candidates = || {
            (0..mem.memory_type_count).filter(move |&i| {
                type_bits & (1 << i) != 0
                    && mem.memory_types[i as usize]
                        .property_flags
                        .contains(required)
            })
        };
        candidates()
            .find(|&i| {
                mem.memory_types[i as usize]
                    .property_flags
                    .contains(preferred)
            })
            .or_else(|| candidates().next())
    }

    pub(crate) fn memory_flags(&self, index: u32) -> vk::MemoryPropertyFlags {
        self.shared.memory.memory_types[index as usize].property_flags
    }

    pub(crate) fn heap_size(&self, index: u32) -> u64 {
        let heap = self.shared.memory.memory_types[index as usize].heap_index;
        self.shared.memory.memory_heaps[heap as usize].size
    }

    /// Names an object for the validation layer's messages (only when validating).
    pub(crate) fn name_object<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(names) = &self.shared.debug_names {
            if let Ok(cname) = std::ffi::CString::new(name) {
                let info = vk::DebugUtilsObjectNameInfoEXT::default()
                    .object_handle(handle)
                    .object_name(&cname);
                let _ = unsafe { names.set_debug_utils_object_name(&info) };
            }
        }
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            if let Ok(pool) = self.command_pool.lock() {
                self.device.destroy_command_pool(*pool, None);
            }
            self.device.destroy_device(None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::instance::validation_layer_available;

    /// The log the tests rely on does catch what the layer reports at teardown: a leaked fence.
    #[test]
    fn validation_log_reports_objects_leaked_at_teardown() {
        if !validation_layer_available() {
            eprintln!("note: validation layer not installed; skipping");
            return;
        }
        let ctx = Context::new(&ContextOptions {
            device: None,
            validation: Validation::On,
            force_staging: false,
        })
        .unwrap();
        let log = ctx.validation_log();
        unsafe {
            ctx.device()
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }
        .unwrap();
        assert!(log.messages().is_empty());
        drop(ctx);
        let messages = log.messages();
        assert!(
            messages.iter().any(|m| m.contains("VkFence")),
            "no leak reported: {messages:?}"
        );
    }
}
