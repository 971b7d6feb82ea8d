//! glsl/shared/draw_bsdf_samples.comp: the BSDF sampler (bsdf.glsl) and the cosine sampler on their
//! own, for one material, shading normal and outgoing direction: `count` draws of each with
//! their pdfs, and `count` uniform probes of bsdf_pdf, so tests can check them against the
//! pdf they report (env's `brdf` and `cosine` strategies, and every method's BSDF sampling).

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::scene::gpu::{phong_probability, GpuScene};
use crate::scene::Material;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct DrawParams {
    kd: Vec4,
    ks: Vec4,
    n: Vec4,
    wo: Vec4,
    count: u32,
    seed: u32,
    pad: [u32; 2],
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(DrawParams in ["draw_bsdf_samples"] { kd, ks, n, wo, count, seed, pad => pad })]
};

pub struct BsdfDraws {
    kernel: Kernel,
    /// (direction, bsdf_pdf) per draw; all zero where the material reflects nothing.
    pub draws: Buffer<[f32; 4]>,
    /// (cosine-weighted direction about n, cos / pi) per draw.
    pub cosine: Buffer<[f32; 4]>,
    /// (uniform direction, bsdf_pdf) per probe.
    pub probes: Buffer<[f32; 4]>,
    count: u32,
}

impl BsdfDraws {
    pub fn new(ctx: &Context, count: u32) -> GpuResult<Self> {
        let len = count.max(1) as usize;
        Ok(BsdfDraws {
            kernel: Kernel::new(ctx, "draw_bsdf_samples")?,
            draws: Buffer::zeroed(ctx, "BsdfDraws", len)?,
            cosine: Buffer::zeroed(ctx, "CosineDraws", len)?,
            probes: Buffer::zeroed(ctx, "BsdfProbes", len)?,
            count,
        })
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        material: &Material,
        n: Vec3,
        wo: Vec3,
        seed: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("BsdfDraws", &self.draws));
        bindings.push(bind("CosineDraws", &self.cosine));
        bindings.push(bind("BsdfProbes", &self.probes));
        let params = DrawParams {
            kd: material.kd.extend(phong_probability(material)),
            ks: material.ks.extend(material.ns),
            n: n.extend(0.0),
            wo: wo.extend(0.0),
            count: self.count,
            seed,
            pad: [0; 2],
        };
        self.kernel
            .dispatch_threads(cmd, &bindings, &params, [self.count, 1, 1])
    }
}
