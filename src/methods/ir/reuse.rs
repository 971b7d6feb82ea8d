//! ir's VPL reuse across animation frames (`--reuse K`; glsl/ir/reweigh_vpls.comp has the
//! estimator). The walk's paths fall into K classes (path i in class i mod K); a sequence's
//! frame walks one class afresh and keeps the other K - 1 from the frames before, each path
//! re-weighed for this frame's light positions by multiple importance sampling over the
//! classes, so every frame stays an unbiased estimate (Laine et al. 07's incremental instant
//! radiosity, which keeps the VPLs still visible from a moving light; Keller 97's Russian
//! roulette "for animation"). A still render, a sequence's first frame and every frame after
//! the first of a render walk all classes, so `--reuse` changes nothing there.
//!
//! What crosses frames: the walk's slots (`History::base`), and per class the walk seed and the
//! analytic lights of the frame that walked it. It is kept only while the light table is the
//! same (same lights, intensities and emission: a point or spot light may move and turn) and
//! the schedule, path count and K are the same.

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult};
use crate::methods::across_frames::{Carried, Change};
use crate::methods::scene_kernel::SceneKernel;
use crate::sampling::pcg;
use crate::scene::gpu::{GpuLight, GpuScene, LightEntry};
use crate::scene::{Light, Scene};

use super::walk::{Vpl, VplBuffers};

/// Most classes (reweigh_vpls.comp's MAX_CLASSES).
pub const MAX_CLASSES: u32 = 16;

pub const CARRIED: Carried = Carried {
    state: "with --reuse K above 1, the light paths of the last K frames (each frame walks \
            1/K of them afresh), re-weighed for where the point and spot lights are now (a \
            change of intensity, cone or light set walks them all)",
    invalidated_by: &[Change::Emission],
};

/// What an ir render leaves for the next animation frame.
pub struct History {
    /// The animation frame the slots were last used for and its scene's content hash.
    pub frame: u32,
    pub content_hash: u64,
    pub base: VplBuffers,
    pub classes: Classes,
    /// The light table the paths were chosen from (kept only while it is the same).
    pub entries: Vec<LightEntry>,
}

/// Per class: the seed of the walk that made it and the analytic lights of its frame.
#[derive(Clone)]
pub struct Classes {
    pub seeds: Vec<u32>,
    pub lights: Vec<Vec<GpuLight>>,
}

impl Classes {
    /// Every class walked in one frame (walk seed `seed`) under `lights`.
    pub fn walked(count: u32, seed: u32, lights: &[GpuLight]) -> Classes {
        Classes {
            seeds: (0..count).map(|k| class_seed(seed, k, count)).collect(),
            lights: vec![lights.to_vec(); count as usize],
        }
    }
}

/// The seed class `class` of `classes` walks with in a frame whose walk seed is `seed` (the
/// walk's own with one class).
pub fn class_seed(seed: u32, class: u32, classes: u32) -> u32 {
    match classes {
        0 | 1 => seed,
        _ => pcg::hash(&[seed, class, 0x636c6173]),
    }
}

/// Whether `this` frame's lights are `previous`'s moved or turned: the same lights with the
/// same kinds, intensities and cones (so the same light table), positions and spot axes free.
pub fn lights_moved_only(previous: &Scene, this: &Scene) -> bool {
    previous.lights.len() == this.lights.len()
        && previous
            .lights
            .iter()
            .zip(&this.lights)
            .all(|(a, b)| match (a, b) {
                (Light::Point { intensity: ia, .. }, Light::Point { intensity: ib, .. }) => {
                    ia == ib
                }
                (
                    Light::Spot {
                        intensity: ia,
                        cone_angle: ca,
                        falloff_angle: fa,
                        ..
                    },
                    Light::Spot {
                        intensity: ib,
                        cone_angle: cb,
                        falloff_angle: fb,
                        ..
                    },
                ) => ia == ib && ca == cb && fa == fb,
                _ => false,
            })
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReweighParams {
    path_count: u32,
    vertex_count: u32,
    classes: u32,
    light_count: u32,
    fresh: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(ReweighParams in ["reweigh_vpls"] {
        path_count, vertex_count, classes, light_count, fresh
    })]
};

/// One frame's class data on the device: ClassLights (K x analytic lights) and ClassSeeds.
pub struct ClassBuffers {
    lights: Buffer<GpuLight>,
    seeds: Buffer<u32>,
    class_count: u32,
    light_count: u32,
}

impl ClassBuffers {
    pub fn new(ctx: &Context, classes: &Classes) -> GpuResult<ClassBuffers> {
        let light_count = classes.lights.first().map_or(0, |l| l.len()) as u32;
        let mut lights: Vec<GpuLight> = classes.lights.concat();
        // A binding cannot be an empty buffer.
        lights.push(GpuLight::zeroed());
        Ok(ClassBuffers {
            lights: Buffer::from_slice(ctx, "ClassLights", &lights)?,
            seeds: Buffer::from_slice(ctx, "ClassSeeds", &classes.seeds)?,
            class_count: classes.seeds.len() as u32,
            light_count,
        })
    }
}

/// glsl/ir/reweigh_vpls.comp.
pub struct ReweighVpls(SceneKernel);

impl ReweighVpls {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ReweighVpls(SceneKernel::new(ctx, "reweigh_vpls")?))
    }

    /// Writes `frame_vpls` from `base`'s slots, each path re-weighed for this frame's lights;
    /// class `fresh` was walked this frame.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        base: &'a VplBuffers,
        frame_vpls: &'a Buffer<Vpl>,
        classes: &'a ClassBuffers,
        fresh: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("Vpls", frame_vpls));
        bindings.push(bind("VplSchedule", &base.schedule));
        bindings.push(bind("BaseVpls", &base.vpls));
        bindings.push(bind("ClassLights", &classes.lights));
        bindings.push(bind("ClassSeeds", &classes.seeds));
        let params = ReweighParams {
            path_count: base.layout.path_count,
            vertex_count: base.layout.levels.len() as u32,
            classes: classes.class_count,
            light_count: classes.light_count,
            fresh,
        };
        self.0.get(scene.features)?.dispatch(
            cmd,
            &bindings,
            &params,
            [base.layout.path_count.div_ceil(64), 1, 1],
        )
    }
}
