//! glsl/trace_light_vertices.comp: one VPL per iteration from a point or spot light sampled by
//! its emission pdf (Tokuyoshi 12 Section 4.1) and the iteration's bundle direction, and the
//! buffer of one frame's light vertices.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::scene::gpu::GpuScene;

/// One iteration's light vertex as glsl/include/bundles.glsl lays it out.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightVertex {
    /// x0; w: light index (u32 bits).
    pub light: Vec4,
    /// rgb: I(w01) / (P_l p_e(w01)); w: P_l.
    pub power: Vec4,
    /// x1; w: 1 when the ray hit a surface.
    pub position: Vec4,
    pub normal: Vec4,
    /// w: the area density of x1, p_e |cos| / d^2.
    pub side: Vec4,
    /// The iteration's bundle direction w_k.
    pub bundle: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LightVertexParams {
    first_iteration: u32,
    count: u32,
    seed: u32,
}

pub struct TraceLightVertices(Kernel);

impl TraceLightVertices {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(TraceLightVertices(Kernel::new(
            ctx,
            "trace_light_vertices",
        )?))
    }

    /// Writes iterations first_iteration.. first_iteration + vertices.len() into `vertices`.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        vertices: &'a Buffer<LightVertex>,
        first_iteration: u32,
        seed: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("LightVertices", vertices));
        let params = LightVertexParams {
            first_iteration,
            count: vertices.len() as u32,
            seed,
        };
        self.0
            .dispatch_threads(cmd, &bindings, &params, [vertices.len() as u32, 1, 1])
    }
}
