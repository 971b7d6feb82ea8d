//! Converged references, stored in the repository beside their scene: for scenes whose cached
//! reference (references.rs: a few thousand samples, rendered in minutes) is too noisy to judge
//! a run's outliers or a small relMSE, `irad bench references` renders one reference once, to a
//! net relMSE of at most 0.01, in chunks it can stop and resume, and the suite uses it in place
//! of the cache whenever the scene and the reference's settings match.
//!
//! Layout: `<scene folder>/converged/<W>x<H>-<key hash>/` holds `reference.json` (the record)
//! and `halves-<chunks>.exr`, the two independent halves A (top) and B (bottom) stacked in one
//! float32 image, each the mean of its samples. Chunk i renders `chunk_spp` samples with seed
//! `SEED_BASE + i` into the half with fewer samples, so the halves stay independent and within
//! one chunk of each other; the reference is their weighted mean and its own relMSE is
//! estimated from their difference (`references::combine`). Every chunk is saved at once: the
//! new halves under a new name, then the record that names them (write, then rename), then
//! the old halves are removed, so an interrupted run never leaves a record that names
//! anything but complete halves, and at most one chunk is lost. One process extends a
//! reference at a time: the folder is locked (`crate::lock::HolderLock`) while it does.
//!
//! An animated scene has one converged reference per animation frame (`extend_frame`,
//! `lookup_frame`): the frame's scene as `Scene::at_frame` gives it, in its own folder
//! `<W>x<H>-frame<NNNN>-<key hash>/`, keyed by the file's content hash and the frame (the hash
//! is the file's, the same for every frame), its chunks seeded apart from every other frame's
//! (`chunk_seed`). Each frame is resumable on its own, so a batch scheduler can split the
//! frames among jobs (`irad bench references --shard I/N`).
//!
//! The key is what changes the expected image: the scene (its content hash), the resolution
//! and every reference parameter but the sample count, the seed and the light sampler. Unlike the cache's key, it
//! leaves out the hashes of the kernels and of the Rust sources: a converged reference is an
//! estimate of the scene's expected image, which a correct path tracer does not change (the
//! tests keep it unbiased), and one that went stale at every edit of the renderer could never
//! be kept in the repository. The record names the device, driver and commit of each session
//! that added to it.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::{bail, Context as _, Result};
use serde::{Deserialize, Serialize};

use crate::gpu::Context;
use crate::image::{exr, Image};
use crate::lock::HolderLock;
use crate::methods::reference::Reference;
use crate::methods::{Method, Renderers};
use crate::scene::gpu::GpuScene;
use crate::scene::hash::fnv1a64;
use crate::scene::Scene;

use super::references::{combine, rename, samples_of, unique_suffix};

/// The folder, beside a scene file, that holds its converged references.
pub const FOLDER: &str = "converged";

/// Chunk i's seed is `SEED_BASE + i`: far from the small seeds runs use and from the cache's
/// `REFERENCE_SEED`, so no run or cached reference shares random numbers with a chunk.
pub const SEED_BASE: u32 = 0x5851_f42d;

/// Frame f's chunk i uses seed `SEED_BASE + f * FRAME_SEED_STRIDE + i`: each frame's
/// reference has its own random numbers (a frame sharing its noise with the next would hide
/// part of a run's flicker against them), and a still scene's (frame None) are as before.
/// Distinct for 4096 frames of up to 2^20 chunks each (u32 wraps there: frames f and f + 4096
/// share seeds, which only a suite scoring both would see).
pub const FRAME_SEED_STRIDE: u32 = 1 << 20;

/// The seed of chunk `chunk` of the reference of `frame` (None: a still scene).
pub fn chunk_seed(frame: Option<u32>, chunk: u32) -> u32 {
    SEED_BASE
        .wrapping_add(frame.unwrap_or(0).wrapping_mul(FRAME_SEED_STRIDE))
        .wrapping_add(chunk)
}

/// The net relMSE a converged reference is rendered to: low enough that a run's outliers and a
/// relMSE of 0.1 are judged against the scene rather than the reference's noise.
pub const TARGET_REL_MSE: f64 = 0.01;

/// What a converged reference estimates; equal keys mean the same expected image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConvergedKey {
    pub scene: String,
    pub scene_hash: String,
    pub resolution: [u32; 2],
    /// The reference method's parameters but its sample count and seed.
    pub parameters: BTreeMap<String, serde_json::Value>,
    /// The animation frame, for a reference of one frame of an animated scene: its content
    /// hash is the file's, the same for every frame (`Scene::at_frame` changes lights, camera
    /// and emission, not the hash), so the frame is part of the key. Left out for a still
    /// scene, so the keys (and folders) of still scenes' references are as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<u32>,
}

impl ConvergedKey {
    pub fn new(scene: &Scene, reference: &Method) -> ConvergedKey {
        let mut parameters = reference.parameters();
        parameters.remove(reference.count_key());
        // How next-event estimation picks its light changes the noise, not the expected image
        // (tests/light_bvh.rs: the path tracer is unbiased with either).
        parameters.remove("light_sampler");
        ConvergedKey {
            scene: scene.name.clone(),
            scene_hash: format!("{:016x}", scene.content_hash),
            resolution: [scene.camera.width, scene.camera.height],
            parameters,
            frame: None,
        }
    }

    /// The key of frame `frame` of an animated scene (`scene` is the animated scene or its
    /// frame: both have the file's hash).
    pub fn of_frame(scene: &Scene, reference: &Method, frame: u32) -> ConvergedKey {
        ConvergedKey {
            frame: Some(frame),
            ..ConvergedKey::new(scene, reference)
        }
    }

    /// The key of `scene` (`frame` None: a still scene) or of one frame of it.
    pub fn of(scene: &Scene, reference: &Method, frame: Option<u32>) -> ConvergedKey {
        match frame {
            Some(f) => ConvergedKey::of_frame(scene, reference, f),
            None => ConvergedKey::new(scene, reference),
        }
    }

    /// The entry's folder under a scene's `converged/` folder.
    pub fn dir(&self, scene_folder: &Path) -> PathBuf {
        let text = serde_json::to_string(self).expect("a key serializes");
        let [w, h] = self.resolution;
        let hash = fnv1a64(text.as_bytes()) >> 32;
        let name = match self.frame {
            Some(f) => format!("{w}x{h}-frame{f:04}-{hash:08x}"),
            None => format!("{w}x{h}-{hash:08x}"),
        };
        scene_folder.join(FOLDER).join(name)
    }
}

/// One run of `irad bench references` that added chunks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Session {
    pub device: String,
    pub driver: String,
    /// `git describe --always --dirty` of the checkout the scene is in, when it is one.
    pub commit: String,
    /// Seconds since 1970 when the session started.
    pub started_unix: u64,
    pub chunks: u32,
    pub spp: u64,
    /// GPU time of the session's chunks (the device's timestamps; on a CPU device such as
    /// lavapipe, wall time of the kernels on a machine that may have been busy).
    pub gpu_ms: f64,
    pub wall_ms: f64,
}

/// The record beside a converged reference's halves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConvergedRecord {
    pub key: ConvergedKey,
    /// The stacked halves' file, in the same folder.
    pub halves: String,
    /// Samples per pixel in half A and half B.
    pub spp: [u64; 2],
    /// Chunks rendered; chunk i used seed `SEED_BASE + i`.
    pub chunks: u32,
    /// The reference's own relMSE, from its halves; None before both halves have samples.
    pub rel_mse: Option<f64>,
    pub gpu_ms: f64,
    pub wall_ms: f64,
    pub nonfinite_estimates: u64,
    pub sessions: Vec<Session>,
}

impl ConvergedRecord {
    pub fn total_spp(&self) -> u64 {
        self.spp[0] + self.spp[1]
    }
}

/// A converged reference: its record and halves.
#[derive(Clone, Debug)]
pub struct Converged {
    pub dir: PathBuf,
    pub record: ConvergedRecord,
    pub halves: [Image; 2],
}

impl Converged {
    /// The reference image (the halves' weighted mean) and its own relMSE.
    pub fn image(&self) -> (Image, f64) {
        let [a, b] = &self.halves;
        combine(a, b, self.record.spp[0], self.record.spp[1])
    }

    /// The halves' file.
    pub fn halves_path(&self) -> PathBuf {
        self.dir.join(&self.record.halves)
    }
}

/// The folder a scene's converged references live under: its file's folder; None for a scene
/// built in code.
pub fn scene_folder(scene: &Scene) -> Option<&Path> {
    scene.source.as_deref()?.parent()
}

/// The converged reference in `dir`, if one is there; an error when one is there but does not
/// read back whole (a damaged entry is reported, not silently replaced).
pub fn load(dir: &Path) -> Result<Option<Converged>> {
    let record_path = dir.join("reference.json");
    if !record_path.exists() {
        return Ok(None);
    }
    let text = fs::read_to_string(&record_path)
        .with_context(|| format!("reading {}", record_path.display()))?;
    let record: ConvergedRecord = serde_json::from_str(&text)
        .with_context(|| format!("parsing {} as a converged reference", record_path.display()))?;
    check_samples(&record, &record_path)?;
    let path = dir.join(&record.halves);
    let stacked = exr::read(&path)?;
    let [w, h] = record.key.resolution;
    if [stacked.width, stacked.height] != [w, 2 * h] {
        bail!(
            "{}: {}x{}, but {} names a {w}x{h} image, whose two halves stack to {w}x{}",
            path.display(),
            stacked.width,
            stacked.height,
            record_path.display(),
            2 * h
        );
    }
    if let Some(i) = stacked
        .pixels
        .iter()
        .position(|p| !p.iter().all(|v| v.is_finite()))
    {
        bail!(
            "{}: pixel ({}, {}) is not finite",
            path.display(),
            i as u32 % w,
            i as u32 / w
        );
    }
    let n = (w * h) as usize;
    let half = |k: usize| Image {
        width: w,
        height: h,
        pixels: stacked.pixels[k * n..(k + 1) * n].to_vec(),
    };
    Ok(Some(Converged {
        dir: dir.to_path_buf(),
        halves: [half(0), half(1)],
        record,
    }))
}

/// Refuses a record whose samples per half are not those its chunks put there: the halves'
/// weights in the reference and its relMSE come from `spp`, so a wrong count (a hand edit)
/// would skew both without a sign. `extend` sends chunk i to the half with fewer samples
/// (A on a tie), and every chunk of a session has the session's samples, so replaying the
/// sessions gives the counts.
fn check_samples(record: &ConvergedRecord, path: &Path) -> Result<()> {
    let chunks: u64 = record.sessions.iter().map(|s| u64::from(s.chunks)).sum();
    if chunks != u64::from(record.chunks) {
        bail!(
            "{}: `chunks` = {}, but its sessions add up to {chunks} chunks: the record is damaged or was edited; move its folder away to start again",
            path.display(),
            record.chunks
        );
    }
    let mut spp = [0u128; 2];
    let mut sizes = Vec::new();
    for (i, s) in record.sessions.iter().enumerate() {
        let per_chunk = match u64::from(s.chunks) {
            0 => 0,
            n => s.spp / n,
        };
        if s.chunks == 0 || per_chunk == 0 || per_chunk * u64::from(s.chunks) != s.spp {
            bail!(
                "{}: sessions[{i}] has `spp` = {} over `chunks` = {}, not a whole number of samples per chunk: the record is damaged or was edited; move its folder away to start again",
                path.display(),
                s.spp,
                s.chunks
            );
        }
        replay(&mut spp, u128::from(per_chunk), u64::from(s.chunks));
        sizes.push(format!("{} of {per_chunk}", s.chunks));
    }
    if spp != record.spp.map(u128::from) {
        bail!(
            "{}: `spp` = [{}, {}], but its {} chunks ({} spp) put [{}, {}] in its halves: the record is damaged or was edited, and its halves would be weighted wrongly; move its folder away to start again",
            path.display(),
            record.spp[0],
            record.spp[1],
            record.chunks,
            sizes.join(", then "),
            spp[0],
            spp[1]
        );
    }
    Ok(())
}

/// Adds `chunks` chunks of `per_chunk` samples to the halves `spp` as `extend` does.
fn replay(spp: &mut [u128; 2], per_chunk: u128, mut chunks: u64) {
    let step = |spp: &mut [u128; 2]| spp[usize::from(spp[1] < spp[0])] += per_chunk;
    while chunks > 0 {
        let before = *spp;
        step(spp);
        chunks -= 1;
        if chunks == 0 {
            break;
        }
        step(spp);
        chunks -= 1;
        // Which half a chunk goes to depends only on the halves' difference; once a pair of
        // chunks brings it back, every later pair does the same, so they are added at once.
        if spp[0] - before[0] == per_chunk && spp[1] - before[1] == per_chunk {
            let pairs = chunks / 2;
            spp[0] += u128::from(pairs) * per_chunk;
            spp[1] += u128::from(pairs) * per_chunk;
            chunks -= 2 * pairs;
        }
    }
}

/// The converged reference for `scene` and `reference` (a reference method) when one is stored
/// beside the scene with a matching key and at least as many samples as `reference` asks for.
pub fn lookup(scene: &Scene, reference: &Method) -> Result<Option<Converged>> {
    lookup_frame(scene, reference, None)
}

/// `lookup` for frame `frame` of an animated scene (`scene` the animated scene or that frame's
/// `Scene::at_frame`); `frame` None: a still scene.
pub fn lookup_frame(
    scene: &Scene,
    reference: &Method,
    frame: Option<u32>,
) -> Result<Option<Converged>> {
    let Some(folder) = scene_folder(scene) else {
        return Ok(None);
    };
    let key = ConvergedKey::of(scene, reference, frame);
    let Some(found) = load(&key.dir(folder))? else {
        return Ok(None);
    };
    if found.record.key != key || found.record.rel_mse.is_none() {
        return Ok(None);
    }
    Ok((found.record.total_spp() >= reference.samples()).then_some(found))
}

/// When `extend` stops adding chunks.
pub struct ExtendOptions<'a> {
    /// Stop once the net relMSE is at most this.
    pub target_rel_mse: f64,
    /// Stop after the chunk that ends past this instant.
    pub deadline: Option<Instant>,
    /// Samples per pixel of one chunk.
    pub chunk_spp: u32,
    /// Stop after the chunk under way once this is set (Ctrl-C).
    pub stop: Option<&'a AtomicBool>,
}

/// What `extend` reports.
pub enum Progress<'a> {
    /// `done` of the chunk's `total` samples rendered.
    Rendering { done: u32, total: u32 },
    /// A chunk is saved; `ms_per_spp` is this session's GPU time per sample so far.
    Saved {
        record: &'a ConvergedRecord,
        ms_per_spp: f64,
    },
    /// The reference's folder `dir` was locked by a process that is gone (`holder`); it was
    /// taken over.
    StaleLock { dir: &'a Path, holder: String },
}

/// Extends (or starts) the converged reference of `scene` (a still scene) with `reference`'s
/// settings, chunk by chunk, until its net relMSE reaches the target, the deadline passes or
/// `stop` is set.
pub fn extend(
    ctx: &Context,
    renderers: &Renderers,
    scene: &Scene,
    gpu_scene: &GpuScene,
    reference: &Method,
    options: &ExtendOptions,
    on: impl FnMut(Progress),
) -> Result<Converged> {
    if let Some(animation) = &scene.animation {
        bail!(
            "{} is animated ({} frames): its converged references are one per frame (`extend_frame`)",
            scene.name,
            animation.frames
        );
    }
    extend_key(
        ctx, renderers, scene, None, gpu_scene, reference, options, on,
    )
}

/// `extend` for frame `frame` of the animated scene `animated`: the frame's scene
/// (`Scene::at_frame`) is uploaded and rendered, keyed by the file's hash and the frame
/// (`ConvergedKey::of_frame`), in the same chunks, halves, lock and record as a still scene's.
pub fn extend_frame(
    ctx: &Context,
    renderers: &Renderers,
    animated: &Scene,
    frame: u32,
    reference: &Method,
    options: &ExtendOptions,
    on: impl FnMut(Progress),
) -> Result<Converged> {
    let Some(animation) = &animated.animation else {
        bail!(
            "{} is not animated: its converged reference is one image (`extend`)",
            animated.name
        );
    };
    if frame >= animation.frames {
        bail!(
            "{}: frame {frame} is past the animation's {} frames",
            animated.name,
            animation.frames
        );
    }
    let still = animated.at_frame(frame)?;
    let gpu_scene = GpuScene::upload(ctx, &still)
        .with_context(|| format!("uploading frame {frame} of {}", animated.name))?;
    extend_key(
        ctx,
        renderers,
        &still,
        Some(frame),
        &gpu_scene,
        reference,
        options,
        on,
    )
}

#[allow(clippy::too_many_arguments)]
fn extend_key(
    ctx: &Context,
    renderers: &Renderers,
    scene: &Scene,
    frame: Option<u32>,
    gpu_scene: &GpuScene,
    reference: &Method,
    options: &ExtendOptions,
    mut on: impl FnMut(Progress),
) -> Result<Converged> {
    let Some(settings) = reference.settings_of::<Reference>() else {
        bail!(
            "a reference is rendered by the reference method, not {}",
            reference.name()
        );
    };
    let Some(folder) = scene_folder(scene) else {
        bail!(
            "{} is built into irad, not read from a file: a converged reference is stored beside its scene file",
            scene.name
        );
    };
    let key = ConvergedKey::of(scene, reference, frame);
    let dir = key.dir(folder);
    // One writer at a time: two writers would render the same chunks, and the last record
    // written would drop the other's session and leave its halves behind.
    fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let acquired = HolderLock::acquire_or(
        &dir,
        "wait for it to finish (or stop it); it extends the same converged reference",
    )?;
    let _lock = RecordOrNothing {
        lock: Some(acquired.lock),
        dir: &dir,
    };
    if let Some(holder) = acquired.stale {
        on(Progress::StaleLock { dir: &dir, holder });
    }
    let mut current = match load(&dir)? {
        Some(found) if found.record.key == key => found,
        Some(found) => bail!(
            "{} holds a converged reference of other settings ({}); move it away to start a new one",
            dir.display(),
            serde_json::to_string(&found.record.key).unwrap_or_default()
        ),
        None => {
            let [w, h] = key.resolution;
            Converged {
                dir: dir.clone(),
                record: ConvergedRecord {
                    key: key.clone(),
                    halves: String::new(),
                    spp: [0, 0],
                    chunks: 0,
                    rel_mse: None,
                    gpu_ms: 0.0,
                    wall_ms: 0.0,
                    nonfinite_estimates: 0,
                    sessions: Vec::new(),
                },
                halves: [Image::new(w, h), Image::new(w, h)],
            }
        }
    };
    let info = ctx.info();
    let session = Session {
        device: info.name.clone(),
        driver: info.driver.clone(),
        commit: commit_of(folder),
        started_unix: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs()),
        chunks: 0,
        spp: 0,
        gpu_ms: 0.0,
        wall_ms: 0.0,
    };
    let mut session_index = None;
    let stopped = || options.stop.is_some_and(|s| s.load(Ordering::SeqCst));
    let past_deadline = || options.deadline.is_some_and(|d| Instant::now() >= d);
    let converged = |r: &ConvergedRecord| r.rel_mse.is_some_and(|e| e <= options.target_rel_mse);
    while !converged(&current.record) && !stopped() && !past_deadline() {
        let record = &mut current.record;
        let half = usize::from(record.spp[1] < record.spp[0]);
        let seed = chunk_seed(frame, record.chunks);
        let chunk = options.chunk_spp;
        let method = samples_of(scene, settings, chunk, seed);
        let out = renderers
            .run(ctx, &method, scene, gpu_scene, |done, total| {
                on(Progress::Rendering { done, total })
            })
            .with_context(|| match frame {
                Some(f) => format!(
                    "rendering chunk {} of {} frame {f}",
                    record.chunks, scene.name
                ),
                None => format!("rendering chunk {} of {}", record.chunks, scene.name),
            })?;
        // The half's mean over its old and new samples, kept as f32 in memory exactly as on
        // disk, so a resumed run adds to the same bits an uninterrupted one would.
        let n = record.spp[half] as f64;
        let k = chunk as f64;
        for (m, x) in current.halves[half]
            .pixels
            .iter_mut()
            .zip(&out.image.pixels)
        {
            for c in 0..3 {
                m[c] = ((n * m[c] as f64 + k * x[c] as f64) / (n + k)) as f32;
            }
        }
        let gpu_ms = out.passes.total_gpu_ms().unwrap_or(out.wall_ms);
        record.spp[half] += chunk as u64;
        record.chunks += 1;
        record.gpu_ms += gpu_ms;
        record.wall_ms += out.wall_ms;
        record.nonfinite_estimates += out.nonfinite_estimates as u64;
        let i = *session_index.get_or_insert_with(|| {
            record.sessions.push(session.clone());
            record.sessions.len() - 1
        });
        let s = &mut record.sessions[i];
        s.chunks += 1;
        s.spp += chunk as u64;
        s.gpu_ms += gpu_ms;
        s.wall_ms += out.wall_ms;
        let ms_per_spp = s.gpu_ms / s.spp as f64;
        if record.spp[0] > 0 && record.spp[1] > 0 {
            let [a, b] = &current.halves;
            record.rel_mse = Some(combine(a, b, record.spp[0], record.spp[1]).1);
        }
        save(&mut current)?;
        on(Progress::Saved {
            record: &current.record,
            ms_per_spp,
        });
    }
    Ok(current)
}

/// The lock `extend` holds on a reference's folder; on drop, whatever the exit (a failed
/// first chunk, a stop before one), the folder is removed when it holds no record (and
/// `converged/` when it is left empty), so no folder without `reference.json` is left among
/// the references kept beside their scene (and walked, as the tests do). Its other files then belong to no record: halves saved just
/// before an interruption stopped their record.
struct RecordOrNothing<'a> {
    lock: Option<HolderLock>,
    dir: &'a Path,
}

impl Drop for RecordOrNothing<'_> {
    fn drop(&mut self) {
        let lock = self.lock.take();
        if self.dir.join("reference.json").exists() {
            return;
        }
        // Removed while the lock is held, so no other writer's file goes, then the lock file
        // (the lock's drop), then the folder, which `remove_dir` leaves if another process
        // has just put its lock file there.
        if let Ok(entries) = fs::read_dir(self.dir) {
            for entry in entries.flatten() {
                if entry.file_name() != crate::lock::LOCK_FILE {
                    let _ = fs::remove_file(entry.path());
                }
            }
        }
        drop(lock);
        let _ = fs::remove_dir(self.dir);
        // And `converged/` when this was its only reference.
        if let Some(parent) = self.dir.parent() {
            let _ = fs::remove_dir(parent);
        }
    }
}

/// Writes the halves under a new name, then the record naming them, then removes the old
/// halves (module doc).
fn save(current: &mut Converged) -> Result<()> {
    let dir = &current.dir;
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let [a, b] = &current.halves;
    let mut stacked = Image::new(a.width, 2 * a.height);
    stacked.pixels = a.pixels.iter().chain(&b.pixels).copied().collect();
    let name = format!("halves-{:06}.exr", current.record.chunks);
    let unique = unique_suffix();
    let tmp = dir.join(format!("{name}.{unique}.exr"));
    exr::write(&tmp, &stacked)?;
    rename(&tmp, &dir.join(&name))?;
    let old = std::mem::replace(&mut current.record.halves, name);
    let mut text = serde_json::to_string_pretty(&current.record)?;
    text.push('\n');
    let json_tmp = dir.join(format!("reference.json.{unique}"));
    fs::write(&json_tmp, text).with_context(|| format!("writing {}", json_tmp.display()))?;
    rename(&json_tmp, &dir.join("reference.json"))?;
    if !old.is_empty() && old != current.record.halves {
        let _ = fs::remove_file(dir.join(old));
    }
    Ok(())
}

/// `git describe --always --dirty` in `folder`, or why there is none.
fn commit_of(folder: &Path) -> String {
    std::process::Command::new("git")
        .arg("-C")
        .arg(folder)
        .args(["describe", "--always", "--dirty", "--abbrev=12"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|| "unknown (not a git checkout)".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No two (frame, chunk) pairs of 4096 frames share a seed, and a still scene's chunks are
    /// frame 0's.
    #[test]
    fn chunk_seeds_differ_between_frames_and_chunks() {
        let mut seen = std::collections::HashSet::new();
        for f in (0..4096).step_by(7).chain([4094]) {
            for c in [0, 1, 2, 255, FRAME_SEED_STRIDE - 1] {
                assert!(seen.insert(chunk_seed(Some(f), c)), "frame {f} chunk {c}");
            }
        }
        assert_eq!(chunk_seed(None, 3), chunk_seed(Some(0), 3));
        assert_ne!(chunk_seed(Some(1), 0), chunk_seed(Some(0), 1));
    }
}
