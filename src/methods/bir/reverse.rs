//! glsl/trace_reverse_vpls.comp, glsl/shade_reverse_vpls.comp and glsl/find_uncovered_vpls.comp:
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
}

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
        let params = ReverseParams {
            count,
            pool: pool.max(1),
            seed,
            pixels: scene.pixel_count() as u32,
        };
        self.0
            .dispatch(cmd, &bindings, &params, [count.div_ceil(64), 1, 1])
    }
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
    /// all), times `weight`.
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
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("Vpls", vpls));
        bindings.push(bind("ReverseVpls", reverse));
        let count = reverse.len() as u32;
        let params = ShadeParams {
            count,
            light_samples,
            vpl_begin: slots.start,
            vpl_end: slots.end,
            seed,
            weight,
            connections,
            depth: depth.max(1),
        };
        self.0
            .get(scene.features)?
            .dispatch(cmd, &bindings, &params, [count.div_ceil(64), 1, 1])
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
        let params = CoverParams {
            vpl_begin: slots.start,
            vpl_end: slots.end,
            pool: pool.max(1),
            seed,
            pixels: scene.pixel_count() as u32,
            uncovered_scale,
        };
        self.0
            .dispatch(cmd, &bindings, &params, [count.div_ceil(64), 1, 1])
    }
}
