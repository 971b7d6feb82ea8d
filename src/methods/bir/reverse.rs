//! glsl/bir/trace_reverse_vpls.comp, glsl/bir/shade_reverse_vpls.comp and glsl/bir/find_uncovered_vpls.comp:
//! bir's reverse VPLs (the ends of length-2 camera paths, Segovia 06 Section 3.1), their exact
//! density over the batch's pool of camera points (Eq. 7), their outgoing radiance (diffuse
//! approximation, lit by the lights and the batch's standard VPLs), and the standard VPLs no
//! reverse VPL could reach (weight 1 under `both`).

use std::ops::Range;

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::methods::gbuffer::GBuffer;
use crate::methods::ir::walk::Vpl;
use crate::methods::scene_kernel::SceneKernel;
use crate::scene::gpu::GpuScene;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReverseParams {
    count: u32,
    pool: u32,
    seed: u32,
    pixels: u32,
    pool_begin: u32,
    pool_end: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ShadeParams {
    count: u32,
    light_samples: u32,
    vpl_begin: u32,
    vpl_end: u32,
    seed: u32,
    weight: f32,
    connections: u32,
    depth: u32,
    sample_begin: u32,
    sample_end: u32,
    connection_begin: u32,
    connection_end: u32,
    vpl_weight: f32,
    history: u32,
}

/// Shadow and closest-hit rays per invocation in one dispatch of bir's per-VPL kernels.
/// lavapipe stops an invocation's loops silently after 65535 iterations in all (docs/DESIGN.md
/// "The loop budget"), and each ray is a traversal loop of tens of iterations in the shipped
/// scenes: as ir's gather, which shades 512 VPL slots per dispatch, one shadow ray each.
pub const RAYS_PER_DISPATCH: u32 = 512;

/// The ranges `0..count` cut into pieces of at most `per` (at least one piece, maybe empty).
pub fn pieces(count: u32, per: u32) -> impl Iterator<Item = (u32, u32)> {
    let per = per.max(1);
    (0..count.div_ceil(per).max(1)).map(move |i| (i * per, count.min((i + 1) * per)))
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CoverParams {
    vpl_begin: u32,
    vpl_end: u32,
    pool: u32,
    seed: u32,
    pixels: u32,
    uncovered_scale: f32,
    pool_begin: u32,
    pool_end: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(ReverseParams in ["trace_reverse_vpls"] {
            count,
            pool,
            seed,
            pixels,
            pool_begin,
            pool_end,
        }),
        gpu_layout!(ShadeParams in ["shade_reverse_vpls"] {
            count,
            light_samples,
            vpl_begin,
            vpl_end,
            seed,
            weight,
            connections,
            depth,
            sample_begin,
            sample_end,
            connection_begin,
            connection_end,
            vpl_weight,
            history,
        }),
        gpu_layout!(CoverParams in ["find_uncovered_vpls"] {
            vpl_begin,
            vpl_end,
            pool,
            seed,
            pixels,
            uncovered_scale,
            pool_begin,
            pool_end,
        }),
    ]
};

pub struct TraceReverseVpls(Kernel);

impl TraceReverseVpls {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(TraceReverseVpls(Kernel::new(ctx, "trace_reverse_vpls")?))
    }

    /// Writes `reverse.len()` reverse VPLs drawn from a pool of `pool` camera points of
    /// `gbuffer`, with their densities.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        reverse: &'a Buffer<Vpl>,
        pool: u32,
        seed: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.push(bind("ReverseVpls", reverse));
        let count = reverse.len() as u32;
        let mut params = ReverseParams {
            count,
            pool: pool.max(1),
            seed,
            pixels: scene.pixel_count() as u32,
            pool_begin: 0,
            pool_end: 0,
        };
        // x2's ray and a shadow ray per pool point.
        for (begin, end) in pieces(params.pool, RAYS_PER_DISPATCH - 1) {
            params.pool_begin = begin;
            params.pool_end = end;
            self.0
                .dispatch(cmd, &bindings, &params, [count.div_ceil(64), 1, 1])?;
        }
        Ok(())
    }
}

/// Which standard VPL set a reverse radiance dispatch connects to, and its weight.
#[derive(Clone, Copy, Debug)]
pub struct StandardSet {
    /// 1 / the number of sets the reverse VPLs connect to.
    pub weight: f32,
    /// An earlier batch's set: connections only, added.
    pub history: bool,
}

pub struct ShadeReverseVpls(SceneKernel);

impl ShadeReverseVpls {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ShadeReverseVpls(SceneKernel::new(
            ctx,
            "shade_reverse_vpls",
        )?))
    }

    /// Sets each reverse VPL's power from its radiance, lit by `light_samples` next-event
    /// samples and `connections` of the standard VPL slots `slots` of `vpls` per bounce (0:
    /// all), times `weight`; the connections weigh `set.weight`. With `set.history`, `vpls` is
    /// an earlier batch's set and only its connections are added.
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        reverse: &'a Buffer<Vpl>,
        vpls: &'a Buffer<Vpl>,
        slots: Range<u32>,
        light_samples: u32,
        connections: u32,
        depth: u32,
        seed: u32,
        weight: f32,
        set: StandardSet,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("Vpls", vpls));
        bindings.push(bind("ReverseVpls", reverse));
        let count = reverse.len() as u32;
        let depth = depth.max(1);
        let samples = light_samples.max(1);
        let slot_count = slots.end - slots.start;
        let connection_count = if connections == 0 || connections >= slot_count {
            slot_count
        } else {
            connections
        };
        let mut params = ShadeParams {
            count,
            light_samples,
            vpl_begin: slots.start,
            vpl_end: slots.end,
            seed,
            weight,
            connections,
            depth,
            sample_begin: 0,
            sample_end: 0,
            connection_begin: 0,
            connection_end: 0,
            vpl_weight: set.weight,
            history: u32::from(set.history),
        };
        // A sample's path casts a next-event ray at x2 and two rays per vertex, then one per
        // connection: whole samples per dispatch where they fit, else one sample per
        // dispatch with its connections in pieces (its path traced again for each).
        let path_rays = 1 + 2 * depth;
        let (samples_per, connections_per) =
            if path_rays.saturating_add(connection_count) <= RAYS_PER_DISPATCH {
                (
                    RAYS_PER_DISPATCH / (path_rays + connection_count),
                    connection_count,
                )
            } else {
                (1, RAYS_PER_DISPATCH.saturating_sub(path_rays).max(64))
            };
        let kernel = self.0.get(scene.features)?;
        for (sample_begin, sample_end) in pieces(samples, samples_per) {
            for (connection_begin, connection_end) in pieces(connection_count, connections_per) {
                params.sample_begin = sample_begin;
                params.sample_end = sample_end;
                params.connection_begin = connection_begin;
                params.connection_end = connection_end;
                kernel.dispatch(cmd, &bindings, &params, [count.div_ceil(64), 1, 1])?;
            }
        }
        Ok(())
    }
}

pub struct FindUncoveredVpls(Kernel);

impl FindUncoveredVpls {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(FindUncoveredVpls(Kernel::new(ctx, "find_uncovered_vpls")?))
    }

    /// Marks the standard VPL slots `slots` of `vpls` that no point of the pool `pool`, `seed`
    /// (the batch's reverse VPLs') reaches, and multiplies their power by `uncovered_scale`.
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        vpls: &'a Buffer<Vpl>,
        slots: Range<u32>,
        pool: u32,
        seed: u32,
        uncovered_scale: f32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.push(bind("Vpls", vpls));
        let count = slots.end - slots.start;
        let mut params = CoverParams {
            vpl_begin: slots.start,
            vpl_end: slots.end,
            pool: pool.max(1),
            seed,
            pixels: scene.pixel_count() as u32,
            uncovered_scale,
            pool_begin: 0,
            pool_end: 0,
        };
        // A shadow ray per pool point.
        for (begin, end) in pieces(params.pool, RAYS_PER_DISPATCH) {
            params.pool_begin = begin;
            params.pool_end = end;
            self.0
                .dispatch(cmd, &bindings, &params, [count.div_ceil(64), 1, 1])?;
        }
        Ok(())
    }
}
