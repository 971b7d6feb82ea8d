//! Bias-compensated clamping of the VPL gather (Kollig and Keller 2004, "Illumination in the
//! presence of weak singularities"), shared by ir and bir. The gather clamps the geometry term
//! at b, which removes the spikes next to VPLs; short camera-side paths add back exactly what
//! the clamp removed (glsl/include/compensation.glsl), so the estimate stays unbiased:
//!
//! - glsl/shared/trace_compensation_paths.comp: level l's vertices, BSDF-sampled from level l - 1
//!   (the G-buffer for l = 1), kept where G(x, y) > b, with next-event estimation at each;
//! - glsl/shared/gather_compensation_vpls.comp: the frame's VPLs at level l's vertices, clamped at b
//!   except at the last level, DEPTH, whose gather is unclamped and ends the recursion
//!   without bias.
//!
//! b comes from the scene by default (`auto_clamp`): the geometry term at the radius inside
//! which a shading point expects a few (pi) of the frame's VPLs. A method resolves its
//! settings into a `FrameClamp` once per render and records its pass after each gather.

use std::ops::Range;

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult};
use crate::methods::scene_kernel::SceneKernel;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use super::accumulation::Accumulation;
use super::gbuffer::GBuffer;
use super::ir::gather::SLOTS_PER_DISPATCH;
use super::ir::walk::Vpl;

/// How a VPL gather treats the geometry term's singularity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VplClamp {
    /// b from the scene and the frame's VPL count (`auto_clamp`).
    Auto,
    /// This b; 0 leaves the geometry term unclamped.
    Fixed(f32),
}

/// The clamp of a VPL gather and whether its bias is compensated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClampSettings {
    pub clamp: VplClamp,
    /// Add back what the clamp removed (unbiased); off: the plain, biased clamp.
    pub compensate: bool,
}

impl Default for ClampSettings {
    fn default() -> Self {
        ClampSettings {
            clamp: VplClamp::Auto,
            compensate: true,
        }
    }
}

impl ClampSettings {
    /// The b a frame of `vpls` surface VPLs gathers with in `scene` (0: unclamped).
    pub fn resolve(&self, scene: &Scene, vpls: u32) -> f32 {
        match self.clamp {
            VplClamp::Auto => auto_clamp(scene, vpls),
            VplClamp::Fixed(b) => b,
        }
    }

    /// b for a render whose frames shade `vpls` surface VPLs, with the compensation's buffers
    /// when it is compensated (and b > 0).
    pub fn prepare(
        &self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        vpls: u32,
    ) -> GpuResult<FrameClamp> {
        let g_clamp = self.resolve(scene, vpls);
        let buffers = if self.compensate && g_clamp > 0.0 {
            Some(CompensationBuffers::new(ctx, gpu_scene)?)
        } else {
            None
        };
        Ok(FrameClamp { g_clamp, buffers })
    }

    /// The record's value of `clamp`: "auto" or the number.
    pub fn clamp_param(&self) -> serde_json::Value {
        match self.clamp {
            VplClamp::Auto => serde_json::json!("auto"),
            VplClamp::Fixed(b) => serde_json::json!(b),
        }
    }
}

/// Compensation levels per frame: the last one's gather is unclamped, so its vertices can
/// spike again; enough levels keep them rare even at a small b. Measured on the corner light at
/// 32x32 (bir, 256 VPLs x 64 frames, b = 0.35: 16%, 5%, 2%, 0.9%, 0.4%, 0.2% of pixels reach
/// levels 1-6): with 3 levels the image mean's standard deviation over seeds was 16%, with 6 it
/// was 3.2%; an empty level costs one dispatch whose workgroups exit at once.
pub const DEPTH: u32 = 6;

/// The automatic clamp's constant: b = AUTO_CLAMP_SCALE N / A for N surface VPLs spread over
/// the scene's area A. At G = b a shading point sees, within the radius r = 1 / sqrt(b) about
/// it, about one of the N VPLs (N pi r^2 / A = pi / AUTO_CLAMP_SCALE), so the clamp acts only
/// where single VPLs dominate a pixel.
pub const AUTO_CLAMP_SCALE: f64 = 1.0;

/// b for `vpls` surface VPLs per frame in `scene`: AUTO_CLAMP_SCALE vpls / (total triangle area).
pub fn auto_clamp(scene: &Scene, vpls: u32) -> f32 {
    let area: f64 = scene.triangles.iter().map(|t| t.area()).sum();
    if area > 0.0 {
        (AUTO_CLAMP_SCALE * vpls.max(1) as f64 / area) as f32
    } else {
        0.0
    }
}

/// One vertex as glsl/include/compensation.glsl lays it out.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct CompensationVertex {
    pub position: Vec4,
    pub normal: Vec4,
    pub side: Vec4,
    pub wo: Vec4,
    pub beta: Vec4,
}

/// The two vertex lists levels alternate between and the per-level counts.
struct CompensationBuffers {
    lists: [Buffer<CompensationVertex>; 2],
    /// counts[l]: level l's vertices this frame (counts[0] unused).
    counts: Buffer<u32>,
}

impl CompensationBuffers {
    fn new(ctx: &Context, scene: &GpuScene) -> GpuResult<Self> {
        let n = scene.pixel_count().max(1);
        Ok(CompensationBuffers {
            lists: [
                Buffer::zeroed(ctx, "CompensationList0", n)?,
                Buffer::zeroed(ctx, "CompensationList1", n)?,
            ],
            counts: Buffer::zeroed(ctx, "CompensationCounts", DEPTH as usize + 1)?,
        })
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TraceParams {
    level: u32,
    frame: u32,
    seed: u32,
    g_clamp: f32,
    direct_weight: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GatherParams {
    level: u32,
    vpl_begin: u32,
    vpl_end: u32,
    g_clamp: f32,
    weight: f32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(CompensationVertex as "CompensationVertex" { position, normal, side, wo, beta }),
        gpu_layout!(TraceParams in ["trace_compensation_paths"] {
            level,
            frame,
            seed,
            g_clamp,
            direct_weight,
        }),
        gpu_layout!(GatherParams in ["gather_compensation_vpls"] {
            level,
            vpl_begin,
            vpl_end,
            g_clamp,
            weight,
        }),
    ]
};

/// A set of VPLs a frame gathers: slots of a buffer, each contribution times a weight.
pub struct VplSource<'a> {
    pub vpls: &'a Buffer<Vpl>,
    pub slots: Range<u32>,
    pub weight: f32,
}

pub struct ClampCompensation {
    trace: SceneKernel,
    gather: SceneKernel,
}

impl ClampCompensation {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ClampCompensation {
            trace: SceneKernel::new(ctx, "trace_compensation_paths")?,
            gather: SceneKernel::new(ctx, "gather_compensation_vpls")?,
        })
    }

    /// Records the compensation of a gather of `sources` clamped at `g_clamp` (> 0) for the
    /// frame's G-buffer: DEPTH levels of paths, each level's VPL light added into
    /// `accumulation`.
    #[allow(clippy::too_many_arguments)]
    fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        accumulation: &'a Accumulation,
        buffers: &'a CompensationBuffers,
        sources: &[VplSource<'a>],
        g_clamp: f32,
        direct_weight: f32,
        frame: u32,
        seed: u32,
    ) -> GpuResult<()> {
        cmd.fill_zero(&buffers.counts);
        let threads = [scene.pixel_count() as u32, 1, 1];
        for level in 1..=DEPTH {
            let input = &buffers.lists[(level as usize + 1) % 2];
            let output = &buffers.lists[level as usize % 2];
            let mut bindings = scene.bindings();
            bindings.push(bind("GBuffer", &gbuffer.texels));
            bindings.extend(accumulation.bindings());
            bindings.push(bind("CompensationIn", input));
            bindings.push(bind("CompensationOut", output));
            bindings.push(bind("CompensationCounts", &buffers.counts));
            let params = TraceParams {
                level,
                frame,
                seed,
                g_clamp,
                direct_weight,
            };
            self.trace
                .get(scene.features)?
                .dispatch_threads(cmd, &bindings, &params, threads)?;

            // The last level's gather is unclamped: nothing is left to compensate.
            let clamp = if level == DEPTH { 0.0 } else { g_clamp };
            for source in sources {
                let mut bindings = scene.bindings();
                bindings.extend(accumulation.bindings());
                bindings.push(bind("Vpls", source.vpls));
                bindings.push(bind("CompensationIn", output));
                bindings.push(bind("CompensationCounts", &buffers.counts));
                // Split as the pixel gather is (lavapipe's loop budget; gather.rs).
                let mut begin = source.slots.start;
                while begin < source.slots.end {
                    let end = source.slots.end.min(begin + SLOTS_PER_DISPATCH);
                    let params = GatherParams {
                        level,
                        vpl_begin: begin,
                        vpl_end: end,
                        g_clamp: clamp,
                        weight: source.weight,
                    };
                    self.gather
                        .get(scene.features)?
                        .dispatch_threads(cmd, &bindings, &params, threads)?;
                    begin = end;
                }
            }
        }
        Ok(())
    }
}

/// A render's clamp: the b its gathers use and, compensated, the buffers of the compensation.
pub struct FrameClamp {
    pub g_clamp: f32,
    buffers: Option<CompensationBuffers>,
}

impl FrameClamp {
    /// Records pass "clamp compensation" after a gather of `sources` at `g_clamp`, or nothing
    /// when the clamp is off or not compensated. `direct_weight` is the share of the frame's
    /// estimate this gather is (the weight of the next-event term at the paths' vertices,
    /// which the sources' weights do not carry: 1 for one gather per frame). `seed` keys the
    /// paths' random numbers.
    #[allow(clippy::too_many_arguments)]
    pub fn record_compensation<'a>(
        &'a self,
        kernels: &'a ClampCompensation,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        accumulation: &'a Accumulation,
        sources: &[VplSource<'a>],
        direct_weight: f32,
        frame: u32,
        seed: u32,
    ) -> GpuResult<()> {
        let Some(buffers) = &self.buffers else {
            return Ok(());
        };
        cmd.pass("clamp compensation", |cmd| {
            kernels.record(
                cmd,
                scene,
                gbuffer,
                accumulation,
                buffers,
                sources,
                self.g_clamp,
                direct_weight,
                frame,
                seed,
            )
        })
    }

    /// `vpl_clamp` (the b used) and, compensated, the last frame's compensation vertices per
    /// pixel at each level (how much of the image the clamp touched).
    pub fn stats(&self, scene: &GpuScene) -> GpuResult<Vec<(String, f64)>> {
        let mut stats = vec![("vpl_clamp".to_string(), self.g_clamp as f64)];
        if let Some(buffers) = &self.buffers {
            let counts = buffers.counts.read()?;
            let pixels = scene.pixel_count().max(1) as f64;
            for (level, &count) in counts.iter().enumerate().skip(1) {
                stats.push((
                    format!("compensation_vertices_per_pixel_level_{level}"),
                    count as f64 / pixels,
                ));
            }
        }
        Ok(stats)
    }
}
