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

use crate::methods::compensation::{ClampSettings, CompensationVertex, VplClamp};
use crate::methods::gbuffer::GBufferTexel;
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

/// "would take BYTES bytes in one buffer, over this device's maxStorageBufferRange".
pub fn over(bytes: u64, limit: u64) -> String {
    format!(
        "would take {bytes} bytes in one buffer, over this device's maxStorageBufferRange of \
         {limit} bytes (`irad info`)"
    )
}

/// The scene's image size, triangles, lights, albedo textures and environment maps against `limit`
/// (maxStorageBufferRange).
pub fn check_scene(scene: &Scene, limit: u64) -> Result<(), String> {
    check_pixels(scene, PIXEL_BYTES, "", limit)?;
    let file = scene_file(scene);
    // ShadingTriangles, the largest buffer with an element per triangle (BvhTriangles 48 bytes,
    // EmitterTriangles 64): found by scaling the many-light hall (docs/many-lights-scale.md),
    // where 2^20 emissive quads made 2.2 million triangles, 136.1 MiB of shading data against
    // lavapipe's 128 MiB. The light BVH's nodes (2L - 1 of 32 bytes for L lights) are checked
    // after it.
    let triangle_bytes = size_of::<crate::scene::gpu::ShadingTriangle>() as u64;
    let triangles = scene.triangles.len() as u64;
    if triangles * triangle_bytes > limit {
        let emissive = emissive_triangles(scene);
        return Err(format!(
            "{file}: {triangles} triangles ({emissive} of them emissive) {}; this device holds \
             at most {} triangles a scene (64 bytes of shading data each)",
            over(triangles * triangle_bytes, limit),
            limit / triangle_bytes
        ));
    }
    let lights = emissive_triangles(scene) + scene.lights.len() as u64;
    let node_bytes = size_of::<crate::sampling::light_bvh::LightNode>() as u64;
    let nodes = (2 * lights).saturating_sub(1);
    if nodes * node_bytes > limit {
        return Err(format!(
            "{file}: {lights} lights (emissive triangles, point and spot lights): their light \
             BVH {}; this device holds at most {} lights a scene",
            over(nodes * node_bytes, limit),
            (limit / node_bytes).div_ceil(2)
        ));
    }
    // A scene built in code may name a texture it lacks, or give one the wrong texel count: the
    // kernels would read another texture's texels.
    for m in &scene.materials {
        if let Some(k) = m.albedo_texture {
            let Some(t) = scene.textures.get(k as usize) else {
                return Err(format!(
                    "{file}: material `{}` names albedo texture {k}, but the scene has {}",
                    m.name,
                    scene.textures.len()
                ));
            };
            if t.texels.len() as u64 != t.width as u64 * t.height as u64 || t.width == 0 {
                return Err(format!(
                    "{file}: albedo texture {} is {}x{} but holds {} texels",
                    t.source.display(),
                    t.width,
                    t.height,
                    t.texels.len()
                ));
            }
        }
    }
    // Texels: every albedo texture's texels in one buffer, 8 bytes a texel (half RGB).
    let texel_bytes = crate::scene::texture_upload::texel_bytes(scene);
    if texel_bytes > limit {
        let mut largest: Vec<&crate::scene::Texture> = scene.textures.iter().collect();
        largest.sort_by_key(|t| std::cmp::Reverse(t.width as u64 * t.height as u64));
        let named: Vec<String> = largest
            .iter()
            .take(3)
            .map(|t| format!("{} ({}x{})", t.source.display(), t.width, t.height))
            .collect();
        return Err(format!(
            "{file}: {} albedo textures {}; this device holds at most {} texels of texture a \
             scene (8 bytes each): scale the largest down ({})",
            scene.textures.len(),
            over(texel_bytes, limit),
            limit / 8,
            named.join(", ")
        ));
    }
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

fn emissive_triangles(scene: &Scene) -> u64 {
    scene
        .triangles
        .iter()
        .filter(|t| scene.materials[t.material as usize].is_emissive())
        .count() as u64
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

/// Refuses `value` where `bytes(value)` (increasing in the value) passes `limit`: the error is
/// `message(over, largest)`, with `over` the bytes against the limit in words (`over`) and
/// `largest` the largest value that fits.
pub fn check_size(
    value: u64,
    limit: u64,
    bytes: impl Fn(u64) -> u64,
    message: impl FnOnce(String, u64) -> String,
) -> Result<(), String> {
    let b = bytes(value);
    if b <= limit {
        return Ok(());
    }
    let largest = largest_fitting(value, limit, &bytes);
    Err(message(over(b, limit), largest))
}

/// The clamp compensation's per-pixel vertex lists (ir, bir: compensation.rs allocates them
/// where it compensates a clamp other than 0) against `limit`.
pub fn check_compensation(clamp: &ClampSettings, scene: &Scene, limit: u64) -> Result<(), String> {
    if clamp.compensate && clamp.clamp != VplClamp::Fixed(0.0) {
        check_pixels(
            scene,
            COMPENSATION_PIXEL_BYTES,
            " in the clamp's compensation (compensate = false avoids it)",
            limit,
        )?;
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
    fn textures_over_the_limit_are_refused_naming_the_largest() {
        let mut scene = crate::scene::default_scene();
        (scene.camera.width, scene.camera.height) = (1, 1);
        let texture = |name: &str, side: u32| crate::scene::Texture {
            width: side,
            height: side,
            texels: vec![glam::Vec3::ONE; (side * side) as usize],
            wrap: [crate::scene::Wrap::Repeat; 2],
            source: name.into(),
        };
        scene.textures = vec![texture("small.png", 4), texture("wall.jpg", 64)];
        let limit = (64 * scene.triangles.len() as u64).max(8 * (64 * 64 + 16));
        assert_eq!(check_scene(&scene, limit), Ok(()));
        scene.textures.push(texture("more.png", 8));
        let e = check_scene(&scene, limit).unwrap_err();
        assert!(
            e.contains("3 albedo textures")
                && e.contains(&format!("at most {} texels", limit / 8))
                && e.contains("wall.jpg (64x64), more.png (8x8), small.png (4x4)"),
            "{e}"
        );
    }

    #[test]
    fn a_scene_of_too_many_triangles_is_refused_in_triangles() {
        let mut scene = crate::scene::default_scene();
        // One pixel, so that the G-buffer fits whatever the limit.
        (scene.camera.width, scene.camera.height) = (1, 1);
        let limit = 64 * scene.triangles.len() as u64;
        assert_eq!(check_scene(&scene, limit), Ok(()));
        let t = scene.triangles[0];
        scene.triangles.push(t);
        let e = check_scene(&scene, limit).unwrap_err();
        assert!(
            e.contains(&format!("{} triangles", scene.triangles.len()))
                && e.contains(&format!("at most {} triangles", limit / 64)),
            "{e}"
        );
        for bytes in [
            size_of::<crate::bvh::BvhTriangle>(),
            size_of::<crate::scene::gpu::EmitterTriangle>(),
        ] {
            assert!(bytes <= size_of::<crate::scene::gpu::ShadingTriangle>());
        }
    }

    #[test]
    fn the_g_buffer_is_the_largest_per_pixel_element() {
        // Radiance, EnvSampleCounts, EnvAlpha, LuminaireSampleCounts, CompensationList*,
        // DirectAlphaState, VplRadiance: per-pixel buffers besides the G-buffer.
        for other in [
            size_of::<[f32; 4]>(),
            size_of::<[f32; 2]>(),
            size_of::<[f32; 4]>(),
            size_of::<crate::methods::ir::walk::Vpl>(),
        ] {
            assert!(other as u64 <= PIXEL_BYTES, "{other} > {PIXEL_BYTES}");
        }
    }
}
