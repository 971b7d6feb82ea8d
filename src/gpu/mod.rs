//! The ash compute core: instance and validation, device choice, context, typed buffers,
//! kernels with reflected layouts, command recording with per-pass GPU timestamps, and the
//! kernels every method shares (prefix sum).

pub mod buffer;
pub mod commands;
pub mod context;
#[cfg(test)]
pub(crate) mod contracts;
pub mod copy;
pub mod device_info;
pub mod env_switch;
pub mod error;
pub mod instance;
pub mod kernel;
pub mod prefix_sum;
pub mod reflect;
pub mod spirv;
pub mod subgroup_layout;
pub mod timing;

pub use buffer::{Buffer, GpuBuffer};
pub use commands::Commands;
pub use context::{list_devices, Context, ContextOptions};
pub use device_info::{DeviceBy, DeviceInfo, DeviceKind, DeviceSelector, SelectorOrigin};
pub use error::{GpuError, GpuResult};
pub use instance::{validation_layer_available, Validation, ValidationLog};
pub use kernel::{bind, Binding, Kernel};
pub use timing::{PassTime, PassTotals, Timings};
