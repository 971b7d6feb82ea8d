//! glsl/bundles/trace_light_vertices.comp: each iteration's VPLs from the point and spot lights,
//! sampled by their emission pdf (Tokuyoshi 12 Section 4.1), one per light or one light by
//! Russian roulette, and the iteration's bundle direction; and the buffer of one frame's light
//! vertices.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult};
use crate::methods::scene_kernel::SceneKernel;
use crate::scene::gpu::{GpuScene, LIGHT_ENVIRONMENT, LIGHT_POINT, LIGHT_SPOT};

use super::directions::BundleDirections;

/// One light vertex as glsl/include/bundles.glsl lays it out.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightVertex {
    /// x0; w: light index (u32 bits).
    pub light: Vec4,
    /// rgb: I(w01) / (P_l p_e(w01)); w: P_l (0: no light in this slot).
    pub power: Vec4,
    /// x1; w: 1 when the ray hit a surface.
    pub position: Vec4,
    pub normal: Vec4,
    /// w: the area density of x1, p_e |cos| / d^2.
    pub side: Vec4,
    /// The iteration's bundle direction w_k; w: p_r(w_k).
    pub bundle: Vec4,
}

/// How each iteration picks the lights its VPLs leave from (Section 4.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightSelection {
    /// One VPL from every point and spot light (the paper's default).
    All,
    /// One VPL from one light chosen by power ("Russian roulette if desired", for many lights).
    Roulette,
}

crate::methods::settings::named_choices!(LightSelection {
    All => "all",
    Roulette => "roulette",
});

/// One frame's light vertices: `slots` per iteration, iteration-major.
pub struct FrameLightVertices {
    pub buffer: Buffer<LightVertex>,
    pub slots: u32,
    /// Point and spot light entries (LightEntries' first).
    pub lights: u32,
}

impl FrameLightVertices {
    pub fn new(
        ctx: &Context,
        scene: &GpuScene,
        iterations: u32,
        selection: LightSelection,
    ) -> GpuResult<Self> {
        let lights = point_and_spot_entries(scene);
        let slots = match selection {
            LightSelection::All => lights.max(1),
            LightSelection::Roulette => 1,
        };
        Ok(FrameLightVertices {
            buffer: Buffer::zeroed(ctx, "LightVertices", (iterations.max(1) * slots) as usize)?,
            slots,
            lights,
        })
    }
}

/// The point and spot lights' entries, which lead LightEntries (bundles declines emissive
/// triangles, and the environment's entry comes last).
fn point_and_spot_entries(scene: &GpuScene) -> u32 {
    let entries = &scene.light_table.entries;
    let n = entries
        .iter()
        .take_while(|e| e.kind == LIGHT_POINT || e.kind == LIGHT_SPOT)
        .count();
    debug_assert!(entries[n..].iter().all(|e| e.kind == LIGHT_ENVIRONMENT));
    n as u32
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LightVertexParams {
    first_iteration: u32,
    count: u32,
    seed: u32,
    lights: u32,
    slots: u32,
    directions: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(LightVertex as "LightVertex" { light, power, position, normal, side, bundle }),
        gpu_layout!(LightVertexParams in ["trace_light_vertices"] {
            first_iteration,
            count,
            seed,
            lights,
            slots,
            directions,
        }),
    ]
};

pub struct TraceLightVertices(SceneKernel);

impl TraceLightVertices {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(TraceLightVertices(SceneKernel::new(
            ctx,
            "trace_light_vertices",
        )?))
    }

    /// Writes the light vertices of iterations first_iteration.. first_iteration + I.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        vertices: &'a FrameLightVertices,
        directions: &'a BundleDirections,
        first_iteration: u32,
        seed: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("LightVertices", &vertices.buffer));
        bindings.extend(directions.bindings());
        let total = vertices.buffer.len() as u32;
        let params = LightVertexParams {
            first_iteration,
            count: total / vertices.slots,
            seed,
            lights: vertices.lights,
            slots: vertices.slots,
            directions: directions.mode_code(),
        };
        self.0
            .get(scene.features)?
            .dispatch_threads(cmd, &bindings, &params, [total, 1, 1])
    }
}
