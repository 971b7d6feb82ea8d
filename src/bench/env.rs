//! `irad bench env`: the per-frame cost of env's sampling table (Lu 14 Alg. 1 lines 5-10) at
//! several cube-face resolutions, next to the time to copy the map once (the bandwidth bound:
//! building the table must at least read the map), and the latitude-longitude table's build
//! (env's latlong strategy, bundles' directions) for comparison. All GPU times are medians of
//! the timed repetitions, measured in one submission per repetition. Then the frame time of
//! env's strategies against samples per pixel, with and without shadow rays (the thesis's
//! timings leave visibility out).

use anyhow::Result;
use glam::Vec3;

use super::median;
use crate::gpu::{copy::CopyValues, Buffer, Commands, Context};
use crate::methods::envmap::cube::CubeTable;
use crate::methods::envmap::{Env, EnvSettings, Strategy};
use crate::methods::equirect_table::EquirectTable;
use crate::methods::interface::{self, Renderer};
use crate::methods::rebuild::TableRebuild;
use crate::scene::gpu::GpuScene;
use crate::scene::{Environment, Scene};

pub struct EnvTableResult {
    pub face_resolution: u32,
    pub cube_ms: f64,
    pub cdf_ms: f64,
    pub samples_ms: f64,
    pub latlong_ms: f64,
    pub copy_ms: f64,
}

impl EnvTableResult {
    pub fn table_ms(&self) -> f64 {
        self.cube_ms + self.cdf_ms + self.samples_ms
    }
}

/// A synthetic sky of `width` x `height` for the benchmark: a gradient and a sun of a few
/// texels (the content does not change the work, only the map's size does).
pub fn synthetic_sky(width: u32, height: u32) -> Environment {
    let mut texels = Vec::with_capacity((width * height) as usize);
    for j in 0..height {
        let up = 1.0 - j as f32 / height as f32;
        for _ in 0..width {
            texels.push(Vec3::new(0.3, 0.45, 0.9) * up + Vec3::splat(0.05));
        }
    }
    let (si, sj) = (width / 3, height / 4);
    for j in sj..(sj + (height / 128).max(1)) {
        for i in si..(si + (width / 128).max(1)) {
            texels[(j * width + i) as usize] = Vec3::splat(5000.0);
        }
    }
    Environment {
        width,
        height,
        texels,
        source: format!("synthetic {width}x{height}").into(),
    }
}

/// Median GPU times of the table's passes at each face resolution, `samples_per_face` light
/// samples per face (N_s / 2), after `warmup` untimed repetitions.
pub fn run(
    ctx: &Context,
    scene: &Scene,
    faces: &[u32],
    samples_per_face: u32,
    warmup: usize,
    repeats: usize,
    mut progress: impl FnMut(u32),
) -> Result<Vec<EnvTableResult>> {
    let env = scene
        .environment
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("bench env: the scene has no environment map"))?;
    let gpu = GpuScene::upload(ctx, scene)?;
    let floats: Vec<f32> = env
        .texels
        .iter()
        .flat_map(|t| [t.x, t.y, t.z, 0.0])
        .collect();
    let source = Buffer::from_slice(ctx, "bench map", &floats)?;
    let destination = Buffer::<f32>::zeroed(ctx, "bench map copy", floats.len())?;
    let copy = CopyValues::new(ctx)?;
    let latlong = EquirectTable::new(ctx, &gpu, 0.0, true)?;
    let mut results = Vec::new();
    for &r in faces {
        progress(r);
        let cube = CubeTable::new(ctx, r, samples_per_face, 1, 1)?;
        let mut times: [Vec<f64>; 5] = Default::default();
        for i in 0..warmup + repeats {
            let mut cmd = Commands::new(ctx)?;
            cmd.pass("cube map", |cmd| cube.record_weights(cmd, &gpu))?;
            cmd.pass("cdf", |cmd| cube.record_cdf(cmd))?;
            cmd.pass("light samples", |cmd| cube.record_samples(cmd, 0, 0, 1))?;
            cmd.pass("latlong table", |cmd| latlong.record(cmd, &gpu))?;
            cmd.pass("copy", |cmd| copy.record(cmd, &source, &destination))?;
            let t = cmd.submit_and_wait()?;
            if i >= warmup {
                for (k, pass) in ["cube map", "cdf", "light samples", "latlong table", "copy"]
                    .iter()
                    .enumerate()
                {
                    times[k].push(t.gpu_ms(pass).unwrap_or(t.wall_ms));
                }
            }
        }
        let [cube_ms, cdf_ms, samples_ms, latlong_ms, copy_ms] = times.map(|mut v| median(&mut v));
        results.push(EnvTableResult {
            face_resolution: r,
            cube_ms,
            cdf_ms,
            samples_ms,
            latlong_ms,
            copy_ms,
        });
    }
    Ok(results)
}

pub fn print_table(
    device: &str,
    map: &Environment,
    samples_per_face: u32,
    results: &[EnvTableResult],
) {
    println!(
        "env sampling table per frame on {device}: map {}x{}, {samples_per_face} light samples per face (median GPU ms)",
        map.width, map.height
    );
    println!(
        "{:>6} {:>10} {:>9} {:>9} {:>10} {:>10} {:>10} {:>10}",
        "face R", "cube map", "cdf", "samples", "table", "latlong", "copy map", "table/copy"
    );
    for r in results {
        println!(
            "{:>6} {:>10.3} {:>9.3} {:>9.3} {:>10.3} {:>10.3} {:>10.3} {:>9.1}x",
            r.face_resolution,
            r.cube_ms,
            r.cdf_ms,
            r.samples_ms,
            r.table_ms(),
            r.latlong_ms,
            r.copy_ms,
            r.table_ms() / r.copy_ms
        );
    }
}

/// One row of the shading table: a strategy at N_s samples per pixel, with or without shadow
/// rays, per frame (GPU ms, means over the timed frames).
pub struct EnvShadingResult {
    pub strategy: Strategy,
    pub spp: u32,
    pub shadows: bool,
    /// The "shade" pass.
    pub shade_ms: f64,
    /// Every pass of the frame (G-buffer, the map seen by the camera, tables, shading).
    pub frame_ms: f64,
}

/// env's frame time against samples per pixel: for each strategy, N_s and shadow setting, one
/// warm-up render of a frame, then `frames` timed frames of the scene at its resolution.
pub fn run_shading(
    ctx: &Context,
    scene: &Scene,
    strategies: &[Strategy],
    spps: &[u32],
    face_resolution: u32,
    frames: u32,
    mut progress: impl FnMut(Strategy, u32, bool),
) -> Result<Vec<EnvShadingResult>> {
    if let Some(e) = interface::declines::<Env>(scene) {
        anyhow::bail!("bench env: {e}");
    }
    let gpu = GpuScene::upload(ctx, scene)?;
    let env = Renderer::<Env>::new(ctx)?;
    let mut results = vec![];
    for &strategy in strategies {
        for &spp in spps {
            for shadows in [true, false] {
                progress(strategy, spp, shadows);
                let settings = |frames| EnvSettings {
                    spp,
                    frames,
                    strategy,
                    face_resolution,
                    shadows,
                    // Lu's dynamic frame: the tables rebuilt every frame, as for a moving map.
                    rebuild: TableRebuild::EveryFrame,
                    ..Default::default()
                };
                env.render(ctx, scene, &gpu, &settings(1), |_, _| {})?;
                let out = env.render(ctx, scene, &gpu, &settings(frames.max(1)), |_, _| {})?;
                let per_frame = |ms: Option<f64>| ms.unwrap_or(f64::NAN) / frames.max(1) as f64;
                let shade = out.passes.passes.iter().find(|p| p.0 == "shade");
                results.push(EnvShadingResult {
                    strategy,
                    spp,
                    shadows,
                    shade_ms: per_frame(shade.and_then(|p| p.1)),
                    frame_ms: per_frame(out.passes.total_gpu_ms()),
                });
            }
        }
    }
    Ok(results)
}

pub fn print_shading(device: &str, scene: &Scene, results: &[EnvShadingResult]) {
    println!(
        "env shading per frame on {device}: {}x{} (mean GPU ms over the timed frames)",
        scene.camera.width, scene.camera.height
    );
    println!(
        "{:>13} {:>6} {:>11} {:>11} {:>8} {:>13} {:>13} {:>10}",
        "strategy", "N_s", "shade", "frame", "fps", "shade no-vis", "frame no-vis", "fps no-vis"
    );
    for pair in results.chunks(2) {
        let [with, without] = pair else { continue };
        println!(
            "{:>13} {:>6} {:>11.3} {:>11.3} {:>8.1} {:>13.3} {:>13.3} {:>10.1}",
            with.strategy.name(),
            with.spp,
            with.shade_ms,
            with.frame_ms,
            1e3 / with.frame_ms,
            without.shade_ms,
            without.frame_ms,
            1e3 / without.frame_ms
        );
    }
}
