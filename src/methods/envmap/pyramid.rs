//! The `hierarchical` sampler's luminance pyramid (glsl/include/env_pyramid.glsl reads it),
//! rebuilt on the GPU from the scene's map: glsl/envmap/weigh_env_pyramid.comp (each leaf's
//! conservative luminance times its solid angle), then glsl/envmap/reduce_env_pyramid.comp once per
//! level (2x2 sums) up to the 2 x 1 top. No CDF and no scan: a draw descends the levels.

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind, Binding, Buffer, Commands, Context, GpuResult, Kernel};
use crate::scene::gpu::GpuScene;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReduceParams {
    level: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct DrawParams {
    count: u32,
    seed: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(ReduceParams in ["reduce_env_pyramid"] { level }),
        gpu_layout!(DrawParams in ["draw_env_pyramid_samples"] { count, seed }),
    ]
};

/// H', the pyramid's leaf rows for a map `height` texels high (the power of two at or
/// above); the leaves are 2 H' wide.
pub fn leaf_rows(height: u32) -> u32 {
    height.max(1).next_power_of_two()
}

/// Levels, finest first: (columns, rows, offset into the buffer).
pub fn levels(height: u32) -> Vec<(u32, u32, usize)> {
    let mut rows = leaf_rows(height);
    let mut offset = 0usize;
    let mut out = vec![];
    loop {
        out.push((2 * rows, rows, offset));
        offset += 2 * (rows as usize) * (rows as usize);
        if rows == 1 {
            return out;
        }
        rows /= 2;
    }
}

/// The pyramid, or, for a scene without a map or when not asked for, a placeholder binding.
pub struct EnvPyramid {
    kernels: Option<(Kernel, Kernel)>,
    levels: Vec<(u32, u32, usize)>,
    pub weights: Buffer<f32>,
}

impl EnvPyramid {
    pub fn new(ctx: &Context, scene: &GpuScene, build: bool) -> GpuResult<Self> {
        let size = scene.environment_size.filter(|_| build);
        let levels = size.map_or(vec![], |[_, h]| levels(h));
        let len = levels
            .last()
            .map_or(1, |&(w, h, offset)| offset + (w * h) as usize);
        let kernels = match size {
            Some(_) => Some((
                Kernel::new(ctx, "weigh_env_pyramid")?,
                Kernel::new(ctx, "reduce_env_pyramid")?,
            )),
            None => None,
        };
        Ok(EnvPyramid {
            kernels,
            levels,
            weights: Buffer::zeroed(ctx, "EnvPyramid", len)?,
        })
    }

    pub fn is_built(&self) -> bool {
        self.kernels.is_some()
    }

    pub fn levels(&self) -> &[(u32, u32, usize)] {
        &self.levels
    }

    pub fn binding(&self) -> Binding<'_> {
        bind("EnvPyramid", &self.weights)
    }

    /// Pass "pyramid": the leaves from the map, then every level above.
    pub fn record<'a>(&'a self, cmd: &mut Commands<'a>, scene: &'a GpuScene) -> GpuResult<()> {
        let Some((weigh, reduce)) = &self.kernels else {
            return Ok(());
        };
        let mut bindings = scene.bindings();
        bindings.push(self.binding());
        let (w, h, _) = self.levels[0];
        weigh.dispatch_threads(cmd, &bindings, &(), [w, h, 1])?;
        for (level, &(w, h, _)) in self.levels.iter().enumerate().skip(1) {
            let params = ReduceParams {
                level: level as u32 - 1,
            };
            reduce.dispatch_threads(cmd, &bindings, &params, [w, h, 1])?;
        }
        Ok(())
    }
}

/// glsl/envmap/draw_env_pyramid_samples.comp: `count` draws from the pyramid (direction, reported
/// density) and `count` uniform probes of its density (direction, density).
pub struct PyramidDraws {
    kernel: Kernel,
    pub draws: Buffer<[f32; 4]>,
    pub probes: Buffer<[f32; 4]>,
    count: u32,
}

impl PyramidDraws {
    pub fn new(ctx: &Context, count: u32) -> GpuResult<Self> {
        Ok(PyramidDraws {
            kernel: Kernel::new(ctx, "draw_env_pyramid_samples")?,
            draws: Buffer::zeroed(ctx, "PyramidDraws", count.max(1) as usize)?,
            probes: Buffer::zeroed(ctx, "PyramidProbes", count.max(1) as usize)?,
            count,
        })
    }

    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        pyramid: &'a EnvPyramid,
        seed: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(pyramid.binding());
        bindings.push(bind("PyramidDraws", &self.draws));
        bindings.push(bind("PyramidProbes", &self.probes));
        let params = DrawParams {
            count: self.count,
            seed,
        };
        self.kernel
            .dispatch_threads(cmd, &bindings, &params, [self.count, 1, 1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_run_from_the_leaves_to_the_two_by_one_top() {
        assert_eq!(levels(1), vec![(2, 1, 0)]);
        assert_eq!(levels(3), vec![(8, 4, 0), (4, 2, 32), (2, 1, 40)]);
        let l = levels(1024);
        assert_eq!(l.len(), 11);
        assert_eq!(l[0], (2048, 1024, 0));
        for k in 1..l.len() {
            let (w, h, offset) = l[k - 1];
            assert_eq!(l[k], (w / 2, h / 2, offset + (w * h) as usize));
        }
        assert_eq!((l[10].0, l[10].1), (2, 1));
    }
}
