//! glsl/gpu/copy_values.comp: a plain float copy, the memory-bandwidth yardstick for the scans.

use super::buffer::{Buffer, GpuBuffer};
use super::commands::Commands;
use super::context::Context;
use super::error::{GpuError, GpuResult};
use super::kernel::{bind, Kernel};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CopyParams {
    vec4_count: u32,
    _pad: [u32; 3],
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(CopyParams in ["copy_values"] { vec4_count, _pad => "_pad0" })]
};

pub struct CopyValues(Kernel);

impl CopyValues {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(CopyValues(Kernel::new(ctx, "copy_values")?))
    }

    /// Copies `source` into `destination`; both hold the same number of floats, a multiple of 4.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        source: &'a Buffer<f32>,
        destination: &'a Buffer<f32>,
    ) -> GpuResult<()> {
        let n = source.len();
        if destination.len() != n || n % 4 != 0 {
            return Err(GpuError::BufferLength {
                name: destination.name().to_string(),
                expected: n.next_multiple_of(4),
                given: destination.len(),
            });
        }
        let vec4_count = (n / 4) as u32;
        let groups = vec4_count
            .div_ceil(self.0.workgroup_size()[0])
            .clamp(1, 65535);
        let bindings = [bind("Source", source), bind("Destination", destination)];
        self.0.dispatch(
            cmd,
            &bindings,
            &CopyParams {
                vec4_count,
                _pad: [0; 3],
            },
            [groups, 1, 1],
        )
    }
}
