//! The reference cache: a scene's reference image, rendered on demand by the reference method
//! and kept under `<cache>/<scene name>-<scene content hash>/<settings key>/`, where the
//! settings key hashes everything that changes the image: the reference parameters and seed,
//! the resolution, the SPIR-V of the reference kernels and a hash of the Rust sources the
//! image depends on (build.rs, `IRAD_REFERENCE_CODE_HASH`). An entry is reused only when its
//! record matches all of these again (so an edited scene, other settings, a rebuilt kernel or
//! a changed loader never reuse a stale image) and its EXR reads back at the right size and
//! finite. Files are written under temporary names unique to the host and process, then
//! renamed, record last, so an interrupted or concurrent writer (shards sharing a cache on a
//! network file system) never leaves an entry that passes the check.
//!
//! A reference of N samples is rendered as two halves, N/2 samples with seed s and the rest
//! with seed s + 1, and their weighted mean is the reference. The halves' difference measures
//! the reference's own error: with n_a + n_b = N, E[(A - B)^2] = var_1 (1/n_a + 1/n_b), and
//! the mean's variance is var_1 / N, so the reference's relMSE is about
//! mean((A - B)^2 / (r^2 + 0.01)) n_a n_b / N^2. No run's relMSE can be measured much below
//! it.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use serde::{Deserialize, Serialize};

use crate::gpu::Context;
use crate::image::metrics::REL_MSE_EPSILON;
use crate::image::{exr, Image};
use crate::methods::lightfield::{Lightfield, LightfieldSettings, Strategy as LightfieldStrategy};
use crate::methods::reference::{Reference, ReferenceSettings};
use crate::methods::{reference, Method, Renderers};
use crate::scene::gpu::GpuScene;
use crate::scene::hash::fnv1a64;
use crate::scene::Scene;

use super::file::file_safe;

/// What a cached reference was rendered from; equal keys mean the same image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceKey {
    pub scene: String,
    pub scene_hash: String,
    pub resolution: [u32; 2],
    pub parameters: std::collections::BTreeMap<String, serde_json::Value>,
    pub seed: u32,
    pub kernel_hash: String,
    pub code_hash: String,
    /// The animation frame, for one frame of an animated scene (whose content hash is the
    /// file's, the same for every frame); left out for a still scene, whose keys are as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<u32>,
}

/// The record beside a cached reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceRecord {
    pub key: ReferenceKey,
    pub device: String,
    pub driver: String,
    pub gpu_ms: Option<f64>,
    pub wall_ms: f64,
    pub nonfinite_estimates: u32,
    /// The reference's own relMSE, from its halves; None for a 1-sample reference.
    pub rel_mse: Option<f64>,
}

impl ReferenceKey {
    pub fn new(scene: &Scene, method: &Method) -> ReferenceKey {
        ReferenceKey {
            scene: scene.name.clone(),
            scene_hash: format!("{:016x}", scene.content_hash),
            resolution: [scene.camera.width, scene.camera.height],
            parameters: method.parameters(),
            seed: method.seed(),
            kernel_hash: format!("{:016x}", reference::kernel_hash()),
            code_hash: env!("IRAD_REFERENCE_CODE_HASH").into(),
            frame: None,
        }
    }

    /// The key of frame `frame` of an animated scene (None: a still scene).
    pub fn of(scene: &Scene, method: &Method, frame: Option<u32>) -> ReferenceKey {
        ReferenceKey {
            frame,
            ..ReferenceKey::new(scene, method)
        }
    }

    /// The entry's folder under the cache root.
    pub fn dir(&self, root: &Path) -> PathBuf {
        let text = serde_json::to_string(self).expect("a key serializes");
        root.join(format!("{}-{}", file_safe(&self.scene), self.scene_hash))
            .join(format!("{:016x}", fnv1a64(text.as_bytes())))
    }
}

/// A reference image and where it came from.
pub struct CachedReference {
    pub image: Image,
    pub record: ReferenceRecord,
    pub exr: PathBuf,
    /// False when it was rendered now.
    pub reused: bool,
}

/// The cached reference for `key`, if a valid one is there.
pub fn lookup(root: &Path, key: &ReferenceKey) -> Option<CachedReference> {
    let dir = key.dir(root);
    let text = fs::read_to_string(dir.join("reference.json")).ok()?;
    let record: ReferenceRecord = serde_json::from_str(&text).ok()?;
    if record.key != *key {
        return None;
    }
    let exr_path = dir.join("reference.exr");
    let image = exr::read(&exr_path).ok()?;
    let finite = image.pixels.iter().flatten().all(|v| v.is_finite());
    if [image.width, image.height] != key.resolution || !finite {
        return None;
    }
    Some(CachedReference {
        image,
        record,
        exr: exr_path,
        reused: true,
    })
}

/// The reference for `scene` with `method` (a reference method): from the cache when valid,
/// else rendered now and stored.
pub fn get_or_render(
    ctx: &Context,
    renderers: &Renderers,
    root: &Path,
    scene: &Scene,
    gpu_scene: &GpuScene,
    method: &Method,
    progress: impl FnMut(u32, u32),
) -> Result<CachedReference> {
    get_or_render_frame(
        ctx, renderers, root, scene, None, gpu_scene, method, progress,
    )
}

/// `get_or_render` for frame `frame` of an animated scene: `scene` is that frame's scene
/// (`Scene::at_frame`), keyed with the frame (`ReferenceKey::of`); None: a still scene.
#[allow(clippy::too_many_arguments)]
pub fn get_or_render_frame(
    ctx: &Context,
    renderers: &Renderers,
    root: &Path,
    scene: &Scene,
    frame: Option<u32>,
    gpu_scene: &GpuScene,
    method: &Method,
    mut progress: impl FnMut(u32, u32),
) -> Result<CachedReference> {
    let key = ReferenceKey::of(scene, method, frame);
    if let Some(found) = lookup(root, &key) {
        return Ok(found);
    }
    let Some(settings) = method.settings_of::<Reference>() else {
        anyhow::bail!(
            "a reference is rendered by the reference method, not {}",
            method.name()
        );
    };
    let total = settings.spp;
    let n_a = (total / 2).max(1);
    let n_b = total - n_a;
    let context = || format!("rendering the reference of {}", scene.name);
    let half = |spp: u32, seed: u32| samples_of(scene, settings, spp, seed);
    // Each frame's halves their own random numbers, as a converged reference's chunks.
    let seed = settings.seed.wrapping_add(
        frame
            .unwrap_or(0)
            .wrapping_mul(super::converged::FRAME_SEED_STRIDE),
    );
    let a = renderers
        .run(ctx, &half(n_a, seed), scene, gpu_scene, |d, _| {
            progress(d, total)
        })
        .with_context(context)?;
    let (image, rel_mse, gpu_ms, wall_ms, nonfinite) = if n_b == 0 {
        let gpu = a.passes.total_gpu_ms();
        (a.image, None, gpu, a.wall_ms, a.nonfinite_estimates)
    } else {
        let b = renderers
            .run(
                ctx,
                &half(n_b, seed.wrapping_add(1)),
                scene,
                gpu_scene,
                |d, _| progress(n_a + d, total),
            )
            .with_context(context)?;
        let (image, rel_mse) = combine(&a.image, &b.image, n_a as u64, n_b as u64);
        let gpu = a
            .passes
            .total_gpu_ms()
            .zip(b.passes.total_gpu_ms())
            .map(|(x, y)| x + y);
        let nonfinite = a.nonfinite_estimates + b.nonfinite_estimates;
        (image, Some(rel_mse), gpu, a.wall_ms + b.wall_ms, nonfinite)
    };
    let info = ctx.info();
    let record = ReferenceRecord {
        key: key.clone(),
        device: info.name.clone(),
        driver: info.driver.clone(),
        gpu_ms,
        wall_ms,
        nonfinite_estimates: nonfinite,
        rel_mse,
    };
    let dir = key.dir(root);
    fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let unique = unique_suffix();
    let exr_path = dir.join("reference.exr");
    let exr_tmp = dir.join(format!("reference.exr.{unique}.exr"));
    exr::write(&exr_tmp, &image)?;
    rename(&exr_tmp, &exr_path)?;
    let json_tmp = dir.join(format!("reference.json.{unique}"));
    let mut text = serde_json::to_string_pretty(&record)?;
    text.push('\n');
    fs::write(&json_tmp, text).with_context(|| format!("writing {}", json_tmp.display()))?;
    rename(&json_tmp, &dir.join("reference.json"))?;
    Ok(CachedReference {
        image,
        record,
        exr: exr_path,
        reused: false,
    })
}

/// The method that renders `spp` reference samples of `scene` with `seed`: the path tracer
/// with `settings`, or, for a scene that places light-field luminaires (which the path tracer
/// does not model), lightfield's restricted strategy (unbiased, tested against the brute force
/// in tests/lightfield.rs) with 64 samples per image and frame on average and no K_max, one
/// frame per reference sample. The brute force (uniform over every whole image plane) is
/// unbiased too but, where a point sees a small window of each image, wastes nearly every
/// sample: its error at equal samples was 50x and more on the faceted headlights.
pub fn samples_of(scene: &Scene, settings: &ReferenceSettings, spp: u32, seed: u32) -> Method {
    let luminaire_images = scene
        .luminaires
        .iter()
        .map(|l| l.luminaire.images.len() as u32)
        .max();
    match luminaire_images {
        Some(images) => Method::new::<Lightfield>(LightfieldSettings {
            spp: 64 * images,
            frames: spp,
            k_max: 64 * images,
            strategy: LightfieldStrategy::Restricted,
            seed,
            pixels: settings.pixels,
            ..Default::default()
        }),
        None => {
            let mut s = *settings;
            s.spp = spp;
            s.seed = seed;
            Method::new::<Reference>(s)
        }
    }
}

/// The weighted mean of halves `a` (n_a samples) and `b` (n_b samples), and the estimate of
/// its own relMSE from their difference (module doc).
pub fn combine(a: &Image, b: &Image, n_a: u64, n_b: u64) -> (Image, f64) {
    let n = (n_a + n_b) as f64;
    let (wa, wb) = (n_a as f64 / n, n_b as f64 / n);
    let mut image = Image::new(a.width, a.height);
    let mut sum = 0.0f64;
    for ((out, pa), pb) in image.pixels.iter_mut().zip(&a.pixels).zip(&b.pixels) {
        for c in 0..3 {
            let (x, y) = (pa[c] as f64, pb[c] as f64);
            let r = wa * x + wb * y;
            out[c] = r as f32;
            sum += (x - y) * (x - y) / (r * r + REL_MSE_EPSILON);
        }
    }
    let rel_mse = sum / (3 * a.pixels.len()).max(1) as f64 * wa * wb;
    (image, rel_mse)
}

/// Host name, process id and time: unique across the machines sharing a cache.
pub(super) fn unique_suffix() -> String {
    let host = host_name();
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    format!("{host}.{}.{nanos}.tmp", std::process::id())
}

/// This machine's name as `unique_suffix` writes it.
pub(super) fn host_name() -> String {
    fs::read_to_string("/proc/sys/kernel/hostname")
        .or_else(|_| fs::read_to_string("/etc/hostname"))
        .map(|h| file_safe(h.trim()))
        .unwrap_or_else(|_| "host".into())
}

pub(super) fn rename(from: &Path, to: &Path) -> Result<()> {
    fs::rename(from, to).with_context(|| format!("renaming {} to {}", from.display(), to.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Halves made of n_a and n_b samples of a per-pixel uniform noise around a known truth:
    /// the estimate from the halves matches the combined image's actual relMSE against the
    /// truth, once the known second-order term is taken out: the estimate divides by the noisy
    /// r^2 instead of the truth's, and E[1 / r^2] is about (1 + 3 relMSE) / t^2 (a slight
    /// overestimate, the safe side for a floor).
    #[test]
    fn halves_estimate_the_references_own_relmse() {
        let (w, h) = (128u32, 128u32);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let truth: Vec<f64> = (0..w * h).map(|i| 0.2 + (i % 7) as f64 * 0.3).collect();
        let mut half = |n: u32| {
            let mut im = Image::new(w, h);
            for (p, t) in im.pixels.iter_mut().zip(&truth) {
                for c in p.iter_mut() {
                    let mean: f64 = (0..n).map(|_| 2.0 * t * uniform()).sum::<f64>() / n as f64;
                    *c = mean as f32;
                }
            }
            im
        };
        let (n_a, n_b) = (4, 12);
        let (a, b) = (half(n_a), half(n_b));
        let (r, estimate) = combine(&a, &b, n_a as u64, n_b as u64);
        let actual: f64 = r
            .pixels
            .iter()
            .zip(&truth)
            .flat_map(|(p, t)| {
                p.iter()
                    .map(move |&x| (x as f64 - t).powi(2) / (t * t + REL_MSE_EPSILON))
            })
            .sum::<f64>()
            / (3 * w * h) as f64;
        let corrected = estimate / (1.0 + 3.0 * estimate);
        assert!(
            (corrected / actual - 1.0).abs() < 0.03,
            "{estimate} ({corrected}) vs {actual}"
        );
    }
}
