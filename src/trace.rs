//! glsl/gpu/trace_rays.comp: a buffer of rays traced through the BVH (glsl/include/bvh.glsl), closest
//! hit or any hit. The kernel the BVH test and `irad bench rays` run.
//!
//! The wrapper only records; once the submission has completed, `GpuBvh::check_loop_cuts`
//! says whether the device's loop limit cut a traversal short (the hits are then wrong).

use glam::Vec3;

use crate::bvh::GpuBvh;
use crate::gpu::{bind, Buffer, Commands, Context, GpuError, GpuResult, Kernel};

/// BVH_NO_TRIANGLE of bvh.glsl: a miss.
pub const NO_TRIANGLE: u32 = u32::MAX;
/// TRACE_ANY_HIT of trace_rays.comp: an any-hit query hit something.
pub const ANY_HIT: u32 = u32::MAX - 1;

/// A ray as trace_rays.comp reads it: hits need `0 < t < t_max`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TraceRay {
    pub origin: [f32; 3],
    pub t_max: f32,
    /// Any length (t is measured in multiples of it).
    pub direction: [f32; 3],
    pub _pad: f32,
}

impl TraceRay {
    pub fn new(origin: Vec3, direction: Vec3, t_max: f32) -> Self {
        TraceRay {
            origin: origin.to_array(),
            t_max,
            direction: direction.to_array(),
            _pad: 0.0,
        }
    }

    pub fn origin(&self) -> Vec3 {
        Vec3::from_array(self.origin)
    }

    pub fn direction(&self) -> Vec3 {
        Vec3::from_array(self.direction)
    }
}

/// What trace_rays.comp writes per ray. Closest hit: t, the GPU triangle index and the
/// barycentrics (u, v) of v1 and v2, or `triangle == NO_TRIANGLE` (and zeros) on a miss.
/// Any hit: `triangle` is `ANY_HIT` or `NO_TRIANGLE`, the rest zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TraceHit {
    pub t: f32,
    pub triangle: u32,
    pub barycentrics: [f32; 2],
}

impl TraceHit {
    pub fn is_hit(&self) -> bool {
        self.triangle != NO_TRIANGLE
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceMode {
    Closest,
    Any,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TraceParams {
    ray_count: u32,
    mode: u32,
    repeat: u32,
    _pad: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(TraceRay as "TraceRay" {
            origin => "origin_t_max",
            t_max => "origin_t_max" + 12,
            direction,
            _pad => pad,
        }),
        gpu_layout!(TraceHit as "TraceHit" { t, triangle, barycentrics }),
        gpu_layout!(TraceParams in ["trace_rays"] { ray_count, mode, repeat, _pad => "_pad1" }),
    ]
};

pub struct TraceRays(Kernel);

impl TraceRays {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(TraceRays(Kernel::new(ctx, "trace_rays")?))
    }

    /// Records the tracing of every ray of `rays` into the same index of `hits`.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        bvh: &'a GpuBvh,
        rays: &'a Buffer<TraceRay>,
        hits: &'a Buffer<TraceHit>,
        mode: TraceMode,
    ) -> GpuResult<()> {
        self.record_repeated(cmd, bvh, rays, hits, mode, 1)
    }

    /// As `record`, each ray traced `repeat` times (0 counts as 1) by its invocation, the
    /// same hit each time: enough repeats spend lavapipe's loop budget within one invocation
    /// (tests/bvh.rs checks that the cut is reported).
    pub fn record_repeated<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        bvh: &'a GpuBvh,
        rays: &'a Buffer<TraceRay>,
        hits: &'a Buffer<TraceHit>,
        mode: TraceMode,
        repeat: u32,
    ) -> GpuResult<()> {
        if hits.len() != rays.len() {
            return Err(GpuError::BufferLength {
                name: "trace hits".into(),
                expected: rays.len(),
                given: hits.len(),
            });
        }
        let ray_count = u32::try_from(rays.len()).map_err(|_| GpuError::BufferLength {
            name: "trace rays".into(),
            expected: u32::MAX as usize,
            given: rays.len(),
        })?;
        let [nodes, triangles, loop_cuts] = bvh.bindings();
        let bindings = [
            nodes,
            triangles,
            loop_cuts,
            bind("Rays", rays),
            bind("Hits", hits),
        ];
        let params = TraceParams {
            ray_count,
            mode: match mode {
                TraceMode::Closest => 0,
                TraceMode::Any => 1,
            },
            repeat,
            _pad: 0,
        };
        // A 2D grid (trace_rays.comp folds y into the ray index): x at most 65535 groups.
        let groups = ray_count.div_ceil(self.0.workgroup_size()[0]).max(1);
        let x = groups.min(65535);
        self.0
            .dispatch(cmd, &bindings, &params, [x, groups.div_ceil(x), 1])
    }
}
