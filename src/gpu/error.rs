//! Errors of the GPU layer: each says what is missing or wrong and what to install or pass.

use ash::vk;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum GpuError {
    #[error(
        "no Vulkan loader could be loaded ({0}): install it with `apt-get install libvulkan1 mesa-vulkan-drivers`, or point IRAD_VULKAN_LIBRARY at a libvulkan.so.1"
    )]
    LoaderMissing(String),

    #[error(
        "no Vulkan device with a compute queue was found: install a GPU driver, or lavapipe (a CPU Vulkan driver) with `apt-get install mesa-vulkan-drivers`"
    )]
    NoDevice,

    #[error(
        "validation was asked for (IRAD_VALIDATE=1) but the Khronos validation layer is not installed: `apt-get install vulkan-validationlayers`, or unset IRAD_VALIDATE"
    )]
    ValidationLayerMissing,

    #[error("{name}={value}: expected 1, true or yes (on) or 0, false, no or empty (off)")]
    EnvSwitch { name: String, value: String },

    /// A size the user chose that this device cannot hold, said in the user's words
    /// (methods/device_fit.rs).
    #[error("{0}")]
    DoesNotFit(String),

    /// An environment variable's value that is not what it takes (the message names it).
    #[error("{0}")]
    Environment(String),

    /// `value` as the user gave it: `--device 7` or `IRAD_DEVICE=7`.
    #[error("{value}: {reason}; the devices are: {available} (see `irad info`)")]
    BadDeviceSelector {
        value: String,
        reason: String,
        available: String,
    },

    #[error("device `{device}` lacks {feature}, which irad needs")]
    MissingFeature { device: String, feature: String },

    #[error("Vulkan call {call} failed: {result}")]
    Vulkan {
        call: &'static str,
        result: vk::Result,
    },

    #[error(
        "device `{device}` numbers a workgroup's subgroup lanes in another order than its invocations ({detail}); irad's scans (glsl/include/workgroup_scan.glsl) need the two orders to agree: please report the device and driver"
    )]
    SubgroupLayout { device: String, detail: String },

    #[error(
        "kernel {kernel}: buffer `{binding}` of {bytes} bytes is bound as a uniform block, over the {limit} bytes every Vulkan device allows (maxUniformBufferRange's minimum)"
    )]
    UniformBlockTooLarge {
        kernel: String,
        binding: String,
        bytes: u64,
        limit: u64,
    },

    #[error(
        "buffer `{name}`: {bytes} bytes asked for, over the device's {limit_name} of {limit} bytes"
    )]
    BufferTooLarge {
        name: String,
        bytes: u64,
        limit_name: &'static str,
        limit: u64,
    },

    #[error("buffer `{name}`: {expected} elements expected, {given} given")]
    BufferLength {
        name: String,
        expected: usize,
        given: usize,
    },

    #[error("kernel `{kernel}`: no SPIR-V module of that name is embedded (rebuild spv/ with `irad shaders`)")]
    KernelNotEmbedded { kernel: String },

    #[error("kernel `{kernel}`: reflection failed: {reason}")]
    Reflection { kernel: String, reason: String },

    #[error("kernel `{kernel}` declares no binding `{binding}` (it declares: {declared})")]
    UnknownBinding {
        kernel: String,
        binding: String,
        declared: String,
    },

    #[error("kernel `{kernel}`: binding `{binding}` (set 0, binding {index}) was not bound")]
    MissingBinding {
        kernel: String,
        binding: String,
        index: u32,
    },

    #[error(
        "the BVH is {depth} levels deep, over the {limit} the GPU traversal stack holds (degenerate geometry: many coincident or nested triangles?)"
    )]
    BvhTooDeep { depth: usize, limit: usize },

    /// A kernel loop the device's loop limit broke out of (bvh.glsl's LoopCuts): a BVH
    /// traversal left unfinished, or weigh_env_cube's footprint past its proven bound.
    #[error(
        "the device's loop limit (lavapipe: 65535 loop iterations a group of lanes) cut a kernel's loop short in this render (a ray's BVH traversal left unfinished, or a table's search past its bound), so the image would be wrong: render this scene on a GPU driver without the limit, or simplify the scene"
    )]
    TraversalCut,

    #[error("kernel `{kernel}`: binding `{binding}` bound twice")]
    DuplicateBinding { kernel: String, binding: String },

    #[error(
        "kernel `{kernel}`: push constants of {given} bytes given, the shader declares {expected}"
    )]
    PushConstantSize {
        kernel: String,
        expected: u32,
        given: usize,
    },

    #[error("kernel `{kernel}`: {groups:?} workgroups asked for, over the device's maxComputeWorkGroupCount {limit:?}")]
    TooManyWorkgroups {
        kernel: String,
        groups: [u32; 3],
        limit: [u32; 3],
    },

    #[error("pass `{pass}`: {reason}")]
    Pass { pass: String, reason: String },
}

pub type GpuResult<T> = Result<T, GpuError>;

/// Maps a raw Vulkan result to [`GpuError::Vulkan`] naming the call.
pub(crate) trait VkContext<T> {
    fn vk(self, call: &'static str) -> GpuResult<T>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> GpuResult<T> {
        self.map_err(|result| GpuError::Vulkan { call, result })
    }
}
