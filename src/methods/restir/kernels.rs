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
use crate::scene::gpu::GpuScene;

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
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TemporalParams {
    frame: u32,
    seed: u32,
    cap: f32,
    combination: u32,
    previous_env_base: u32,
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
        }),
        gpu_layout!(TemporalParams in ["reuse_restir_temporal"] {
            frame,
            seed,
            cap,
            combination,
            previous_env_base,
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

/// The render's reservoirs: this frame's (candidates, then after temporal reuse), the final
/// ones (after spatial reuse; what the next frame reuses) and the surfaces they belong to.
pub struct ReservoirBuffers {
    current: Buffer<Reservoir>,
    last: Buffer<Reservoir>,
    surfaces: Buffer<RestirSurface>,
}

impl ReservoirBuffers {
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
        light_candidates: u32,
        bsdf_candidates: u32,
        light_bvh: bool,
        accumulation: &'a Accumulation,
    ) -> GpuResult<()> {
        let kernel = self.0.get_with(inputs.scene.features, light_bvh)?;
        let mut bindings = inputs.bindings(true);
        bindings.extend(inputs.scene.light_bvh_bindings());
        // For the count of reservoirs dropped with non-finite weights.
        bindings.extend(accumulation.bindings());
        let params = CandidateParams {
            frame: inputs.frame,
            seed: pass_seed(inputs.seed, 0x63616e64),
            light_candidates,
            bsdf_candidates,
        };
        kernel.dispatch(cmd, &bindings, &params, inputs.scene.image_workgroups())
    }
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
        cap: u32,
        combination: Combination,
        accumulation: &'a Accumulation,
    ) -> GpuResult<()> {
        let kernel = self.0.get(inputs.scene.features)?;
        // The previous frame's reservoirs were resampled under its map (restir.glsl "Frames");
        // frame 0 has none (M = 0), so which map it binds does not matter.
        let (previous_env, previous_env_base) = inputs
            .scene
            .environment_texels_of(inputs.frame.saturating_sub(1));
        let params = TemporalParams {
            frame: inputs.frame,
            seed: pass_seed(inputs.seed, 0x74656d70),
            cap: cap as f32,
            combination: combination.gpu_code(),
            previous_env_base,
        };
        let mut bindings = inputs.bindings(true);
        bindings.push(bind("PreviousEnvTexels", previous_env));
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
