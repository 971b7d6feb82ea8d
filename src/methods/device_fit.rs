//! Sizes a device cannot hold, refused before any rendering and said in the user's words: the
//! setting, scene field or file at fault and the largest value that fits this device. Without
//! these checks the same values fail later, when a buffer is created, by the buffer's internal
//! name (`CubeWeights`, `GBuffer`, `EnvTexels`, `BundleHits`, `Vpls`) and without the file.
//!
//! Every storage buffer a kernel binds must fit the device's maxStorageBufferRange (128 MiB on
//! lavapipe, the Vulkan minimum; about 4 GiB on desktop GPUs). The checks below compute, for
//! each size a user controls, the largest buffer it makes, with the element types and counts
//! of the code that allocates it, and search the largest value under the limit.

use std::mem::size_of;

use glam::Vec4;

use crate::methods::bir::Split;
use crate::methods::bundles::light_vertices::{LightSelection, LightVertex};
use crate::methods::bundles::ray_bundles::BundleHit;
use crate::methods::bundles::Bundles;
use crate::methods::compensation::{CompensationVertex, VplClamp};
use crate::methods::gbuffer::GBufferTexel;
use crate::methods::ir::schedule::{mean_albedo, Absorption, Schedule};
use crate::methods::ir::walk::Vpl;
use crate::methods::ir::InstantRadiosity;
use crate::methods::Method;
use crate::scene::Scene;

/// Bytes a pixel takes in the largest per-pixel buffer every method binds (the G-buffer; a
/// unit test checks it is the largest per-pixel element but the compensation's).
pub const PIXEL_BYTES: u64 = size_of::<GBufferTexel>() as u64;
/// Bytes a pixel takes in the clamp compensation's vertex lists (ir, bir, bundles).
pub const COMPENSATION_PIXEL_BYTES: u64 = size_of::<CompensationVertex>() as u64;

/// The largest `v` in `1..=max` with `bytes(v) <= limit` (bytes increasing in v), or 0.
pub fn largest_fitting(max: u64, limit: u64, bytes: impl Fn(u64) -> u64) -> u64 {
    let (mut lo, mut hi) = (0, max);
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if bytes(mid) <= limit {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    lo
}

fn over(bytes: u64, limit: u64) -> String {
    format!(
        "would take {bytes} bytes in one buffer, over this device's maxStorageBufferRange of \
         {limit} bytes (`irad info`)"
    )
}

/// The scene's image size and environment maps against `limit` (maxStorageBufferRange).
pub fn check_scene(scene: &Scene, limit: u64) -> Result<(), String> {
    check_pixels(scene, PIXEL_BYTES, "", limit)?;
    let file = scene_file(scene);
    if let Some(env) = &scene.environment {
        // EnvTexels (one Vec4 a texel), and for a sequence every map's texels in one buffer.
        let maps = scene.environment_sequence.len().max(1) as u64;
        let texels = env.width as u64 * env.height as u64;
        let texel_bytes = size_of::<Vec4>() as u64;
        let bytes = maps * texels * texel_bytes;
        if bytes > limit {
            let most = limit / (maps * texel_bytes);
            let what = if maps > 1 {
                format!("{maps} maps of {}x{}", env.width, env.height)
            } else {
                format!("{}x{}", env.width, env.height)
            };
            return Err(format!(
                "{file}: environment map {}: {what} texels {}; this device holds at most \
                 {most} texels a map{}",
                env.source.display(),
                over(bytes, limit),
                if maps > 1 {
                    " in a sequence this long"
                } else {
                    ""
                }
            ));
        }
    }
    Ok(())
}

/// The image's pixels at `pixel_bytes` each against `limit`.
/// `what` names the buffer's use where it is not every method's G-buffer.
fn check_pixels(scene: &Scene, pixel_bytes: u64, what: &str, limit: u64) -> Result<(), String> {
    let (w, h) = (scene.camera.width as u64, scene.camera.height as u64);
    let bytes = (w * h).saturating_mul(pixel_bytes);
    if bytes <= limit {
        return Ok(());
    }
    let pixels = limit / pixel_bytes;
    // The same aspect ratio at the most pixels that fit.
    let scale = (pixels as f64 / (w * h) as f64).sqrt();
    let (fw, fh) = (
        ((w as f64 * scale) as u64).max(1),
        ((h as f64 * scale) as u64).max(1),
    );
    Err(format!(
        "{}: the image size {w}x{h} (camera.resolution, or the suite's or flag's size): {} \
         pixels at {pixel_bytes} bytes a pixel{what} {}; this device holds at most {pixels} \
         pixels, e.g. {fw}x{fh}",
        scene_file(scene),
        w * h,
        over(bytes, limit)
    ))
}

fn scene_file(scene: &Scene) -> String {
    scene.source.as_ref().map_or_else(
        || format!("embedded:{}", scene.name),
        |p| p.display().to_string(),
    )
}

/// The method's settings against `limit` on `scene` (which `check_scene` passed).
pub fn check_method(method: &Method, scene: &Scene, limit: u64) -> Result<(), String> {
    let pixels = scene.camera.width as u64 * scene.camera.height as u64;
    // ir's and bir's clamp compensation keeps per-pixel vertex lists (compensation.rs:
    // allocated where it compensates a clamp other than 0).
    let clamp = match method {
        Method::Ir(s) => Some(s.clamp),
        Method::Bir(s) => Some(s.clamp),
        _ => None,
    };
    if let Some(c) = clamp {
        if c.compensate && c.clamp != VplClamp::Fixed(0.0) {
            check_pixels(
                scene,
                COMPENSATION_PIXEL_BYTES,
                " in the clamp's compensation (compensate = false avoids it)",
                limit,
            )?;
        }
    }
    match method {
        Method::Env(s) => {
            // CubeWeights and CubeRowCdf: 6 R^2 f32s (envmap/cube.rs).
            let bytes = |r: u64| 6 * r * r * size_of::<f32>() as u64;
            let r = s.face_resolution as u64;
            if bytes(r) > limit {
                let largest = largest_fitting(r, limit, bytes);
                return Err(format!(
                    "env: face_resolution = {r} (--face-resolution): the cube map's table {}; \
                     the largest that fits is {largest}",
                    over(bytes(r), limit)
                ));
            }
            // The strategies' light samples are bounded by MAX_WINDOWED_SAMPLES whatever
            // spp is.
        }
        Method::Ir(s) => {
            // Vpls: one slot per VPL of every path level (ir/walk.rs).
            let bytes = |paths: u64| {
                let settings = crate::methods::ir::IrSettings {
                    paths: paths as u32,
                    ..*s
                };
                InstantRadiosity::schedule(scene, &settings).slot_count as u64
                    * size_of::<Vpl>() as u64
            };
            let paths = s.paths as u64;
            if bytes(paths) > limit {
                let largest = largest_fitting(paths, limit, bytes);
                return Err(format!(
                    "ir: vpls = {paths} (--vpls): the VPLs {}; the largest that fits is {largest}",
                    over(bytes(paths), limit)
                ));
            }
        }
        Method::Bundles(s) => {
            // BundleHits: a chunk of iterations' hits per pixel (bundles/mod.rs); the frame's
            // light vertices: iterations x slots (bundles/light_vertices.rs).
            let slots = match s.lights {
                LightSelection::All => scene.lights.len().max(1) as u64,
                LightSelection::Roulette => 1,
            };
            let bytes = |iterations: u64| {
                let hits = Bundles::chunk_size(iterations as u32, pixels as usize) as u64
                    * pixels
                    * size_of::<BundleHit>() as u64;
                hits.max(iterations * slots * size_of::<LightVertex>() as u64)
            };
            let n = s.iterations as u64;
            if bytes(n) > limit {
                let largest = largest_fitting(n, limit, bytes);
                return Err(format!(
                    "bundles: iterations = {n} (--iterations): the bundles' hits at {}x{} pixels \
                     {}; the largest that fits is {largest}",
                    scene.camera.width,
                    scene.camera.height,
                    over(bytes(n), limit)
                ));
            }
        }
        Method::Bir(s) => {
            // Vpls: the standard walk's slots for a batch's light paths (bir/mod.rs).
            let bytes = |vpls: u64| {
                let vpls_per_frame = (vpls as u32).max(2);
                let batch = if s.batch == 0 {
                    vpls_per_frame
                } else {
                    s.batch.clamp(2, vpls_per_frame)
                };
                let rho = mean_albedo(scene);
                let split = Split::new(s.strategy, batch, rho);
                Schedule::new(split.light_paths, rho, Absorption::Fractional).slot_count as u64
                    * size_of::<Vpl>() as u64
            };
            let vpls = s.vpls as u64;
            if bytes(vpls) > limit {
                let largest = largest_fitting(vpls, limit, bytes);
                return Err(format!(
                    "bir: vpls = {vpls} (--vpls): the standard VPLs {}; the largest that fits is \
                     {largest} (or a smaller batch)",
                    over(bytes(vpls), limit)
                ));
            }
        }
        Method::Reference(_) | Method::Lightfield(_) => {}
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_largest_fitting_value_is_found() {
        let bytes = |r: u64| 6 * r * r * 4;
        assert_eq!(largest_fitting(4096, 134_217_728, bytes), 2364);
        assert_eq!(largest_fitting(100, 134_217_728, bytes), 100);
        assert_eq!(largest_fitting(100, 1, bytes), 0);
    }

    #[test]
    fn an_environment_map_too_large_is_named_by_its_file() {
        let mut scene = crate::scene::default_scene();
        scene.environment = Some(crate::scene::Environment {
            width: 8192,
            height: 4096,
            texels: Vec::new(),
            source: "maps/sky.exr".into(),
        });
        let e = check_scene(&scene, 134_217_728).unwrap_err();
        assert!(
            e.contains("environment map maps/sky.exr: 8192x4096 texels")
                && e.contains("at most 8388608 texels")
                && !e.contains("EnvTexels"),
            "{e}"
        );
        scene.environment.as_mut().unwrap().height = 1024;
        assert_eq!(check_scene(&scene, 134_217_728), Ok(()));
    }

    #[test]
    fn the_g_buffer_is_the_largest_per_pixel_element() {
        // Radiance, EnvSampleCounts, EnvAlpha, LuminaireSampleCounts, CompensationList*,
        // DirectAlphaState, VplRadiance: per-pixel buffers besides the G-buffer.
        for other in [
            size_of::<[f32; 4]>(),
            size_of::<[f32; 2]>(),
            size_of::<[f32; 4]>(),
            size_of::<Vpl>(),
        ] {
            assert!(other as u64 <= PIXEL_BYTES, "{other} > {PIXEL_BYTES}");
        }
    }
}
