//! The radiance accumulation buffer (glsl/include/radiance.glsl): per-pixel sums of every
//! frame's estimate, and the count of non-finite estimates the kernels dropped.

use glam::Vec4;

use crate::gpu::{bind, Binding, Buffer, Context, GpuResult};
use crate::image::Image;

pub struct Accumulation {
    pub radiance: Buffer<Vec4>,
    pub diagnostics: Buffer<u32>,
    pub width: u32,
    pub height: u32,
}

impl Accumulation {
    pub fn new(ctx: &Context, width: u32, height: u32) -> GpuResult<Accumulation> {
        Ok(Accumulation {
            radiance: Buffer::zeroed(ctx, "Radiance", width as usize * height as usize)?,
            diagnostics: Buffer::zeroed(ctx, "Diagnostics", 1)?,
            width,
            height,
        })
    }

    pub fn bindings(&self) -> [Binding<'_>; 2] {
        [
            bind("Radiance", &self.radiance),
            bind("Diagnostics", &self.diagnostics),
        ]
    }

    /// The mean over `frames` frames.
    pub fn resolve(&self, frames: u32) -> GpuResult<Image> {
        let sums = self.radiance.read()?;
        let scale = 1.0 / frames.max(1) as f32;
        Ok(Image {
            width: self.width,
            height: self.height,
            pixels: sums
                .iter()
                .map(|s| [s.x * scale, s.y * scale, s.z * scale])
                .collect(),
        })
    }

    /// How many per-pixel estimates were NaN or Inf and dropped.
    pub fn nonfinite_estimates(&self) -> GpuResult<u32> {
        Ok(self.diagnostics.read()?[0])
    }
}
