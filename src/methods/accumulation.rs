//! The radiance accumulation buffer (glsl/include/radiance.glsl): per-pixel f32 sums of the
//! frames of one submission on the GPU, folded after each submission into f64 sums on the host
//! (so a 100k-sample render does not lose small samples to f32 rounding), and the count of
//! non-finite estimates the kernels dropped.

use std::cell::RefCell;

use glam::Vec4;

use crate::gpu::{bind, Binding, Buffer, Commands, Context, GpuResult};
use crate::image::Image;

pub struct Accumulation {
    pub radiance: Buffer<Vec4>,
    pub diagnostics: Buffer<u32>,
    pub width: u32,
    pub height: u32,
    sums: RefCell<Vec<[f64; 3]>>,
}

impl Accumulation {
    pub fn new(ctx: &Context, width: u32, height: u32) -> GpuResult<Accumulation> {
        let pixels = width as usize * height as usize;
        Ok(Accumulation {
            radiance: Buffer::zeroed(ctx, "Radiance", pixels)?,
            diagnostics: Buffer::zeroed(ctx, "Diagnostics", 1)?,
            width,
            height,
            sums: RefCell::new(vec![[0.0; 3]; pixels]),
        })
    }

    pub fn bindings(&self) -> [Binding<'_>; 2] {
        [
            bind("Radiance", &self.radiance),
            bind("Diagnostics", &self.diagnostics),
        ]
    }

    /// Records the clear that starts a submission's sums.
    pub fn begin_submission<'a>(&'a self, cmd: &mut Commands<'a>) {
        cmd.fill_zero(&self.radiance);
    }

    /// Adds the finished submission's sums into the host's f64 sums.
    pub fn collect(&self) -> GpuResult<()> {
        let mut sums = self.sums.borrow_mut();
        for (sum, s) in sums.iter_mut().zip(self.radiance.read()?) {
            sum[0] += s.x as f64;
            sum[1] += s.y as f64;
            sum[2] += s.z as f64;
        }
        Ok(())
    }

    /// The mean over `frames` frames of everything collected.
    pub fn resolve(&self, frames: u32) -> Image {
        let scale = 1.0 / frames.max(1) as f64;
        Image {
            width: self.width,
            height: self.height,
            pixels: self
                .sums
                .borrow()
                .iter()
                .map(|s| s.map(|v| (v * scale) as f32))
                .collect(),
        }
    }

    /// How many per-pixel estimates were NaN or Inf and dropped.
    pub fn nonfinite_estimates(&self) -> GpuResult<u32> {
        Ok(self.diagnostics.read()?[0])
    }
}
