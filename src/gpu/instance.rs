//! The Vulkan loader, the instance and, when asked for, the Khronos validation layer with a
//! debug messenger whose messages go to the `log` facade (target "vulkan") and are kept in a [`ValidationLog`].

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::{ext::debug_utils, vk};

use super::error::{GpuError, GpuResult, VkContext};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Every warning and error the validation layer reported, in order. Shared with the debug
/// messenger, so it stays readable after the context is dropped (leaks are reported then).
#[derive(Clone, Default, Debug)]
pub struct ValidationLog(Arc<Mutex<Vec<String>>>);

impl ValidationLog {
    pub fn messages(&self) -> Vec<String> {
        self.0.lock().map(|m| m.clone()).unwrap_or_default()
    }
    fn push(&self, message: String) {
        if let Ok(mut m) = self.0.lock() {
            m.push(message);
        }
    }
}

/// Whether to enable the validation layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Validation {
    Off,
    On,
}

impl Validation {
    /// `IRAD_VALIDATE=1` (or true, yes) turns validation on; unset, empty, 0, false or no
    /// leave it off; any other value is an error naming the variable.
    pub fn from_env() -> GpuResult<Self> {
        Ok(if super::env_switch::read("IRAD_VALIDATE")? {
            Validation::On
        } else {
            Validation::Off
        })
    }
}

pub(crate) struct Instance {
    /// Keeps the loader library loaded while the instance lives.
    _entry: ash::Entry,
    pub(crate) raw: ash::Instance,
    debug: Option<Debug>,
    pub(crate) log: ValidationLog,
}

struct Debug {
    loader: debug_utils::Instance,
    messenger: vk::DebugUtilsMessengerEXT,
    user_data: *mut ValidationLog,
}

// The raw pointer is only handed to the messenger and freed after it is destroyed.
unsafe impl Send for Debug {}
unsafe impl Sync for Debug {}

/// Loads the system Vulkan loader, or the library IRAD_VULKAN_LIBRARY names.
pub(crate) fn load_entry() -> GpuResult<ash::Entry> {
    let loaded = match std::env::var_os("IRAD_VULKAN_LIBRARY") {
        Some(path) => unsafe { ash::Entry::load_from(&path) }.map_err(|e| {
            GpuError::LoaderMissing(format!(
                "IRAD_VULKAN_LIBRARY={}: {e}",
                path.to_string_lossy()
            ))
        }),
        None => unsafe { ash::Entry::load() }.map_err(|e| GpuError::LoaderMissing(e.to_string())),
    };
    loaded
}

/// Whether the Khronos validation layer is installed where the loader finds it.
pub fn validation_layer_available() -> bool {
    let Ok(entry) = load_entry() else {
        return false;
    };
    layer_present(&entry)
}

fn layer_present(entry: &ash::Entry) -> bool {
    unsafe { entry.enumerate_instance_layer_properties() }
        .map(|layers| {
            layers
                .iter()
                .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER))
        })
        .unwrap_or(false)
}

impl Instance {
    pub(crate) fn new(validation: Validation) -> GpuResult<Arc<Self>> {
        let entry = load_entry()?;
        let validate = validation == Validation::On;
        if validate && !layer_present(&entry) {
            return Err(GpuError::ValidationLayerMissing);
        }
        let available: Vec<String> = unsafe { entry.enumerate_instance_extension_properties(None) }
            .vk("vkEnumerateInstanceExtensionProperties")?
            .iter()
            .filter_map(|e| {
                e.extension_name_as_c_str()
                    .ok()
                    .map(|s| s.to_string_lossy().into_owned())
            })
            .collect();
        let has = |name: &CStr| available.iter().any(|a| a.as_bytes() == name.to_bytes());

        let mut extensions = Vec::new();
        if validate {
            extensions.push(debug_utils::NAME.as_ptr());
        }
        let mut flags = vk::InstanceCreateFlags::empty();
        if has(ash::khr::portability_enumeration::NAME) {
            extensions.push(ash::khr::portability_enumeration::NAME.as_ptr());
            flags |= vk::InstanceCreateFlags::ENUMERATE_PORTABILITY_KHR;
        }
        let layers = if validate {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let app = vk::ApplicationInfo::default()
            .application_name(c"irad")
            .engine_name(c"irad")
            .api_version(vk::API_VERSION_1_2);
        let log = ValidationLog::default();
        let user_data = Box::into_raw(Box::new(log.clone()));
        let mut messenger_info = messenger_create_info(user_data);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_extension_names(&extensions)
            .enabled_layer_names(&layers)
            .flags(flags);
        if validate {
            // Also reports problems in vkCreateInstance / vkDestroyInstance themselves.
            info = info.push_next(&mut messenger_info);
        }
        let raw = match unsafe { entry.create_instance(&info, None) } {
            Ok(raw) => raw,
            Err(result) => {
                drop(unsafe { Box::from_raw(user_data) });
                return Err(match result {
                    vk::Result::ERROR_INCOMPATIBLE_DRIVER
                    | vk::Result::ERROR_INITIALIZATION_FAILED => GpuError::NoDevice,
                    vk::Result::ERROR_LAYER_NOT_PRESENT => GpuError::ValidationLayerMissing,
                    result => GpuError::Vulkan {
                        call: "vkCreateInstance",
                        result,
                    },
                });
            }
        };
        let debug = if validate {
            let loader = debug_utils::Instance::new(&entry, &raw);
            let info = messenger_create_info(user_data);
            match unsafe { loader.create_debug_utils_messenger(&info, None) } {
                Ok(messenger) => Some(Debug {
                    loader,
                    messenger,
                    user_data,
                }),
                Err(result) => {
                    unsafe { raw.destroy_instance(None) };
                    drop(unsafe { Box::from_raw(user_data) });
                    return Err(GpuError::Vulkan {
                        call: "vkCreateDebugUtilsMessengerEXT",
                        result,
                    });
                }
            }
        } else {
            drop(unsafe { Box::from_raw(user_data) });
            None
        };
        Ok(Arc::new(Instance {
            _entry: entry,
            raw,
            debug,
            log,
        }))
    }

    pub(crate) fn validating(&self) -> bool {
        self.debug.is_some()
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        unsafe {
            if let Some(debug) = self.debug.take() {
                debug
                    .loader
                    .destroy_debug_utils_messenger(debug.messenger, None);
                self.raw.destroy_instance(None);
                drop(Box::from_raw(debug.user_data));
            } else {
                self.raw.destroy_instance(None);
            }
        }
    }
}

fn messenger_create_info<'a>(
    user_data: *mut ValidationLog,
) -> vk::DebugUtilsMessengerCreateInfoEXT<'a> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(on_validation_message))
        .user_data(user_data.cast())
}

unsafe extern "system" fn on_validation_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    let text = if data.is_null() {
        String::from("(no message)")
    } else {
        unsafe { (*data).message_as_c_str() }
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let line = format!("[vulkan {severity:?} {kind:?}] {text}");
    // Through the log facade (target "vulkan"), so a library user routes it; the binary's
    // logger prints the line as it is, and never panics (nor may anything across FFI).
    match severity {
        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR => log::error!(target: "vulkan", "{line}"),
        _ => log::warn!(target: "vulkan", "{line}"),
    }
    if !user_data.is_null() {
        unsafe { &*(user_data as *const ValidationLog) }.push(line);
    }
    vk::FALSE
}
