//! The four kernels of a ReSTIR DI frame (glsl/restir/): candidates, temporal reuse, spatial
//! reuse, shading, each a typed wrapper with its push constants; and the per-render reservoir
//! buffers they share.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::{bind, Binding, Buffer, Commands, Context, GpuResult};
use crate::methods::accumulation::Accumulation;
use crate::methods::gbuffer::GBuffer;
use crate::methods::scene_kernel::SceneKernel;
use crate::sampling::pcg;
use crate::scene::gpu::{GpuLight, GpuMaterial, GpuScene};

use super::Combination;

/// Each pass's seed is the render's hashed with its own tag ("cand", "temp", "spat"), so their
/// random streams are apart whatever dimensions they use (docs/DESIGN.md "Determinism").
fn pass_seed(seed: u32, tag: u32) -> u32 {
    pcg::hash(&[seed, tag])
}

/// One reservoir (glsl/include/restir.glsl `Reservoir`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Reservoir {
    pub sample_point: Vec4,
    pub weights: Vec4,
}

/// A pixel's surface of the previous frame (`RestirSurface`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct RestirSurface {
    pub position: Vec4,
    pub normal: Vec4,
    pub side: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CandidateParams {
    frame: u32,
    seed: u32,
    light_candidates: u32,
    bsdf_candidates: u32,
    streams: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TemporalParams {
    previous_camera_position: Vec4,
    previous_camera_forward: Vec4,
    previous_camera_right: Vec4,
    previous_camera_up: Vec4,
    frame: u32,
    seed: u32,
    cap: f32,
    combination: u32,
    previous_env_base: u32,
    history: u32,
    normal_cos: f32,
    depth_tolerance: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SpatialParams {
    frame: u32,
    seed: u32,
    neighbours: u32,
    radius: f32,
    combination: u32,
    normal_cos: f32,
    depth_tolerance: f32,
    _pad: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(Reservoir as "Reservoir" { sample_point, weights }),
        gpu_layout!(RestirSurface as "RestirSurface" { position, normal, side }),
        gpu_layout!(CandidateParams in ["generate_restir_candidates"] {
            frame,
            seed,
            light_candidates,
            bsdf_candidates,
            streams,
        }),
        gpu_layout!(TemporalParams in ["reuse_restir_temporal"] {
            previous_camera_position,
            previous_camera_forward,
            previous_camera_right,
            previous_camera_up,
            frame,
            seed,
            cap,
            combination,
            previous_env_base,
            history,
            normal_cos,
            depth_tolerance,
        }),
        gpu_layout!(SpatialParams in ["reuse_restir_spatial"] {
            frame,
            seed,
            neighbours,
            radius,
            combination,
            normal_cos,
            depth_tolerance,
            _pad,
        }),
    ]
};

/// Spatial reuse takes a neighbour whose normal is within about 25 degrees of the pixel's...
pub const NORMAL_COS: f32 = 0.906;
/// ...and whose camera distance is within 10% of it (Bitterli et al. 2020, Section 6).
pub const DEPTH_TOLERANCE: f32 = 0.1;

/// Temporal reuse takes a previous frame's surface whose shading normal is within 60 degrees
/// of the pixel's...
pub const TEMPORAL_NORMAL_COS: f32 = 0.5;
/// ...and whose distance from the previous camera is within 10% of the pixel's point's (RTXDI's
/// defaults, DI/TemporalResampling.hlsli).
pub const TEMPORAL_DEPTH_TOLERANCE: f32 = 0.1;

/// The render's reservoirs: this frame's (candidates, then after temporal reuse), the final
/// ones (after spatial reuse; what the next frame reuses) and the surfaces they belong to.
pub struct ReservoirBuffers {
    current: Buffer<Reservoir>,
    last: Buffer<Reservoir>,
    surfaces: Buffer<RestirSurface>,
    /// EntryTranslation's placeholder where no translation is read.
    no_translation: Buffer<u32>,
}

impl ReservoirBuffers {
    /// The last frame's final reservoirs (the spatial pass's), read back.
    pub fn read_final(&self) -> GpuResult<Vec<Reservoir>> {
        self.last.read()
    }

    /// Zeroed: no previous frame (M = 0, an invalid surface is written by frame 0's spatial
    /// pass before any temporal pass reads it).
    pub fn new(ctx: &Context, pixels: usize) -> GpuResult<Self> {
        let invalid = RestirSurface {
            position: Vec4::new(0.0, 0.0, 0.0, f32::from_bits(u32::MAX)),
            ..RestirSurface::zeroed()
        };
        Ok(ReservoirBuffers {
            current: Buffer::zeroed(ctx, "Reservoirs", pixels)?,
            last: Buffer::zeroed(ctx, "FinalReservoirs", pixels)?,
            surfaces: Buffer::from_slice(ctx, "PreviousSurfaces", &vec![invalid; pixels])?,
            no_translation: Buffer::from_slice(ctx, "EntryTranslation", &[u32::MAX])?,
        })
    }

    fn bindings(&self) -> [Binding<'_>; 3] {
        [
            bind("Reservoirs", &self.current),
            bind("FinalReservoirs", &self.last),
            bind("PreviousSurfaces", &self.surfaces),
        ]
    }
}

/// What every pass of one frame needs.
pub struct FrameInputs<'a> {
    pub scene: &'a GpuScene,
    pub gbuffer: &'a GBuffer,
    pub reservoirs: &'a ReservoirBuffers,
    pub frame: u32,
    pub seed: u32,
}

impl<'a> FrameInputs<'a> {
    fn bindings(&self, traces: bool) -> Vec<Binding<'a>> {
        let mut b = if traces {
            self.scene.bindings()
        } else {
            self.scene.scene_bindings()
        };
        b.push(bind("GBuffer", &self.gbuffer.texels));
        b.extend(self.reservoirs.bindings());
        b
    }
}

/// glsl/restir/generate_restir_candidates.comp, specialized to the light sampler (its
/// constant LIGHT_BVH).
pub struct GenerateCandidates(SceneKernel);

/// The candidates a pixel draws each frame: M light and B BSDF candidates, the light ones
/// through the light BVH or the power table, dealt into `shadow_rays` shadow-tested streams.
#[derive(Clone, Copy)]
pub struct CandidateCounts {
    pub light: u32,
    pub bsdf: u32,
    pub shadow_rays: u32,
    pub light_bvh: bool,
}

impl GenerateCandidates {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(GenerateCandidates(SceneKernel::new(
            ctx,
            "generate_restir_candidates",
        )?))
    }

    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        inputs: &FrameInputs<'a>,
        counts: CandidateCounts,
        accumulation: &'a Accumulation,
    ) -> GpuResult<()> {
        let kernel = self.0.get_with(inputs.scene.features, counts.light_bvh)?;
        let mut bindings = inputs.bindings(true);
        bindings.extend(inputs.scene.light_bvh_bindings());
        // For the count of reservoirs dropped with non-finite weights.
        bindings.extend(accumulation.bindings());
        let params = CandidateParams {
            frame: inputs.frame,
            seed: pass_seed(inputs.seed, 0x63616e64),
            light_candidates: counts.light,
            bsdf_candidates: counts.bsdf,
            streams: counts.shadow_rays,
        };
        kernel.dispatch(cmd, &bindings, &params, inputs.scene.image_workgroups())
    }
}

/// The previous frame as the temporal pass sees it: which one (glsl's HISTORY_*), its camera,
/// and the light it was lit by.
pub enum History<'a> {
    /// None: the render's first frame with nothing carried over.
    None,
    /// This render's previous frame (its camera, lights and table).
    Render,
    /// The previous animation frame, its lights and map uploaded by the method.
    Animation(&'a PreviousLighting),
}

/// The previous animation frame's camera and light, for the temporal pass of a render's first
/// frame: its materials (their emission), analytic lights and map as it had them, and each of
/// its light-table entries' entry in this frame's table (u32::MAX where the light is gone).
pub struct PreviousLighting {
    pub camera: [Vec4; 4],
    pub materials: Buffer<GpuMaterial>,
    pub lights: Buffer<GpuLight>,
    pub env_texels: Buffer<Vec4>,
    pub translation: Buffer<u32>,
}

/// How the temporal pass finds and reuses the previous frame's reservoirs.
#[derive(Clone, Copy)]
pub struct TemporalOptions {
    /// The previous reservoir's M at most this times the frame's.
    pub cap: u32,
    pub combination: Combination,
    /// The surface test: shading normals' cosine at least this...
    pub normal_cos: f32,
    /// ...and distances from the previous camera within this fraction.
    pub depth_tolerance: f32,
}

/// glsl/restir/reuse_restir_temporal.comp.
pub struct ReuseTemporal(SceneKernel);

impl ReuseTemporal {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ReuseTemporal(SceneKernel::new(
            ctx,
            "reuse_restir_temporal",
        )?))
    }

    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        inputs: &FrameInputs<'a>,
        history: History<'a>,
        options: TemporalOptions,
        accumulation: &'a Accumulation,
    ) -> GpuResult<()> {
        let kernel = self.0.get(inputs.scene.features)?;
        let scene = inputs.scene;
        let mut bindings = inputs.bindings(true);
        let (code, camera, previous_env_base) = match history {
            History::Animation(previous) => {
                bindings.push(bind("PreviousEnvTexels", &previous.env_texels));
                bindings.push(bind("PreviousMaterials", &previous.materials));
                bindings.push(bind("PreviousLights", &previous.lights));
                bindings.push(bind("EntryTranslation", &previous.translation));
                (2, previous.camera, 0)
            }
            History::None | History::Render => {
                // Within a render the previous frame's map is the sequence's frame before
                // (restir.glsl "Frames"); frame 0 has none, so which map it binds does not
                // matter. Its camera, emission and lights are this frame's; no translation.
                let (previous_env, base) =
                    scene.environment_texels_of(inputs.frame.saturating_sub(1));
                bindings.push(bind("PreviousEnvTexels", previous_env));
                bindings.push(bind("PreviousMaterials", &scene.materials));
                bindings.push(bind("PreviousLights", &scene.lights));
                bindings.push(bind("EntryTranslation", &inputs.reservoirs.no_translation));
                let code = if matches!(history, History::None) {
                    0
                } else {
                    1
                };
                (code, scene.camera, base)
            }
        };
        let params = TemporalParams {
            previous_camera_position: camera[0],
            previous_camera_forward: camera[1],
            previous_camera_right: camera[2],
            previous_camera_up: camera[3],
            frame: inputs.frame,
            seed: pass_seed(inputs.seed, 0x74656d70),
            cap: options.cap as f32,
            combination: options.combination.gpu_code(),
            previous_env_base,
            history: code,
            normal_cos: options.normal_cos,
            depth_tolerance: options.depth_tolerance,
        };
        bindings.extend(accumulation.bindings());
        kernel.dispatch(cmd, &bindings, &params, inputs.scene.image_workgroups())
    }
}

/// glsl/restir/reuse_restir_spatial.comp.
pub struct ReuseSpatial(SceneKernel);

impl ReuseSpatial {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ReuseSpatial(SceneKernel::new(ctx, "reuse_restir_spatial")?))
    }

    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        inputs: &FrameInputs<'a>,
        neighbours: u32,
        radius: u32,
        combination: Combination,
        accumulation: &'a Accumulation,
    ) -> GpuResult<()> {
        let kernel = self.0.get(inputs.scene.features)?;
        let params = SpatialParams {
            frame: inputs.frame,
            seed: pass_seed(inputs.seed, 0x73706174),
            neighbours,
            radius: radius as f32,
            combination: combination.gpu_code(),
            normal_cos: NORMAL_COS,
            depth_tolerance: DEPTH_TOLERANCE,
            _pad: 0,
        };
        let mut bindings = inputs.bindings(true);
        // For the count of reservoirs dropped with non-finite weights.
        bindings.extend(accumulation.bindings());
        kernel.dispatch(cmd, &bindings, &params, inputs.scene.image_workgroups())
    }
}

/// glsl/restir/shade_restir.comp.
pub struct ShadeRestir(SceneKernel);

impl ShadeRestir {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ShadeRestir(SceneKernel::new(ctx, "shade_restir")?))
    }

    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        inputs: &FrameInputs<'a>,
        accumulation: &'a Accumulation,
    ) -> GpuResult<()> {
        let kernel = self.0.get(inputs.scene.features)?;
        let mut bindings = inputs.bindings(false);
        bindings.extend(accumulation.bindings());
        kernel.dispatch(cmd, &bindings, &(), inputs.scene.image_workgroups())
    }
}
