//! The reference cache: a scene's reference image, rendered on demand by the reference method
//! and kept under `<cache>/<scene name>-<scene content hash>/<settings key>/`, where the
//! settings key hashes everything that changes the image: the reference parameters and seed,
//! the resolution, and the SPIR-V of the reference kernels. An entry is reused only when its
//! record matches all of these again (so an edited scene, other settings or a rebuilt kernel
//! never reuse a stale image) and its EXR reads back at the right size and finite. Files are
//! written under temporary names and renamed, record last, so an interrupted or concurrent
//! writer (two shards sharing a cache) never leaves an entry that passes the check.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use serde::{Deserialize, Serialize};

use crate::gpu::Context;
use crate::image::{exr, Image};
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
    let key = ReferenceKey::new(scene, method);
    if let Some(found) = lookup(root, &key) {
        return Ok(found);
    }
    let output = renderers
        .run(ctx, method, scene, gpu_scene, progress)
        .with_context(|| format!("rendering the reference of {}", scene.name))?;
    let info = ctx.info();
    let record = ReferenceRecord {
        key: key.clone(),
        device: info.name.clone(),
        driver: info.driver.clone(),
        gpu_ms: output.passes.total_gpu_ms(),
        wall_ms: output.wall_ms,
        nonfinite_estimates: output.nonfinite_estimates,
    };
    let dir = key.dir(root);
    fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let unique = format!("{}.tmp", std::process::id());
    let exr_path = dir.join("reference.exr");
    let exr_tmp = dir.join(format!("reference.exr.{unique}.exr"));
    exr::write(&exr_tmp, &output.image)?;
    rename(&exr_tmp, &exr_path)?;
    let json_tmp = dir.join(format!("reference.json.{unique}"));
    let mut text = serde_json::to_string_pretty(&record)?;
    text.push('\n');
    fs::write(&json_tmp, text).with_context(|| format!("writing {}", json_tmp.display()))?;
    rename(&json_tmp, &dir.join("reference.json"))?;
    Ok(CachedReference {
        image: output.image,
        record,
        exr: exr_path,
        reused: false,
    })
}

fn rename(from: &Path, to: &Path) -> Result<()> {
    fs::rename(from, to).with_context(|| format!("renaming {} to {}", from.display(), to.display()))
}
