//! glsl/ir/trace_vpls.comp: the quasi-random walk from the lights that writes one frame's VPLs
//! (Keller 97 Section 3.2), and the VPL buffer it writes.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult};
use crate::methods::scene_kernel::SceneKernel;
use crate::scene::gpu::{GpuScene, LightEntry};

use super::schedule::Schedule;

/// One VPL as glsl/include/vpl.glsl lays it out.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Vpl {
    /// w: kind (u32 bits): 0 none, 1 surface, 2 area-light point, 3 point light, 4 spot light.
    pub position: Vec4,
    pub normal: Vec4,
    pub power: Vec4,
    pub incident: Vec4,
}

pub const VPL_NONE: u32 = 0;
pub const VPL_SURFACE: u32 = 1;

impl Vpl {
    pub fn kind(&self) -> u32 {
        self.position.w.to_bits()
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct WalkParams {
    path_count: u32,
    vertex_count: u32,
    seed: u32,
    survival: f32,
    path_stride: u32,
    path_phase: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(Vpl as "Vpl" { position, normal, power, incident }),
        gpu_layout!(WalkParams in ["trace_vpls"] {
            path_count, vertex_count, seed, survival, path_stride, path_phase
        }),
    ]
};

/// The VPL slots of one frame and the schedule that lays them out.
pub struct VplBuffers {
    pub vpls: Buffer<Vpl>,
    pub schedule: Buffer<[u32; 4]>,
    pub layout: Schedule,
}

impl VplBuffers {
    pub fn new(ctx: &Context, layout: Schedule) -> GpuResult<VplBuffers> {
        Ok(VplBuffers {
            vpls: Buffer::zeroed(ctx, "Vpls", layout.slot_count.max(1) as usize)?,
            schedule: Buffer::from_slice(ctx, "VplSchedule", &layout.levels)?,
            layout,
        })
    }
}

/// Which of a frame's paths a walk traces: i = phase (mod stride).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathClass {
    pub stride: u32,
    pub phase: u32,
}

impl PathClass {
    pub const ALL: PathClass = PathClass {
        stride: 1,
        phase: 0,
    };
}

pub struct TraceVpls(SceneKernel);

impl TraceVpls {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(TraceVpls(SceneKernel::new(ctx, "trace_vpls")?))
    }

    /// Walks every path (each clears its slots first: a path that ends early leaves its later
    /// slots empty), choosing lights by `entries` when given (bir's camera-driven table)
    /// instead of the scene's power-based one.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        buffers: &'a VplBuffers,
        seed: u32,
        entries: Option<&'a Buffer<LightEntry>>,
    ) -> GpuResult<()> {
        self.record_paths(cmd, scene, buffers, seed, entries, PathClass::ALL)
    }

    /// Walks only the paths of `class` (i = class.phase mod class.stride) and leaves the
    /// other paths' slots as they are (ir's reuse across frames, src/methods/ir/reuse.rs).
    pub fn record_paths<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        buffers: &'a VplBuffers,
        seed: u32,
        entries: Option<&'a Buffer<LightEntry>>,
        class: PathClass,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        if let Some(entries) = entries {
            for b in bindings.iter_mut() {
                if b.name == "LightEntries" {
                    *b = bind("LightEntries", entries);
                }
            }
        }
        bindings.push(bind("Vpls", &buffers.vpls));
        bindings.push(bind("VplSchedule", &buffers.schedule));
        let params = WalkParams {
            path_count: buffers.layout.path_count,
            vertex_count: buffers.layout.levels.len() as u32,
            seed,
            survival: buffers.layout.mean_albedo as f32,
            path_stride: class.stride.max(1),
            path_phase: class.phase,
        };
        let walked = buffers
            .layout
            .path_count
            .saturating_sub(class.phase)
            .div_ceil(class.stride.max(1));
        self.0.get(scene.features)?.dispatch(
            cmd,
            &bindings,
            &params,
            [walked.div_ceil(64).max(1), 1, 1],
        )
    }
}
