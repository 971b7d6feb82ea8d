//! `irad bench rays`: rays per second of the GPU traversal (glsl/include/bvh.glsl through
//! trace_rays.comp), closest hit and any hit, for coherent (camera) and incoherent (random)
//! rays, next to obvhs's CWBVH traversal of the same rays over the same tree on the CPU using
//! every core, and the ratio GPU/CPU.
//!
//! GPU: median of the pass's timestamp time over the repeats, after a warm-up submission.
//! CPU: median wall clock of the same rays split over `available_parallelism` threads (chunks
//! taken from a shared counter), triangles in leaf order so no index lookup is timed, with
//! obvhs's own `Triangle::intersect`. Both count hits, as a cross-check that they traced the
//! same thing.

use std::hint::black_box;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::Result;
use glam::{Vec3, Vec3A};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;

use super::median;
use crate::bvh::{build_cwbvh, obvhs_triangles, Bvh, GpuBvh};
use crate::gpu::{Buffer, Commands, Context};
use crate::trace::{TraceHit, TraceMode, TraceRay, TraceRays};

/// One ray set traced one way.
pub struct RaysRow {
    pub set: &'static str,
    pub mode: TraceMode,
    pub rays: usize,
    pub gpu_ms: f64,
    pub cpu_ms: f64,
    pub gpu_hits: usize,
    pub cpu_hits: usize,
}

impl RaysRow {
    pub fn gpu_rays_per_s(&self) -> f64 {
        self.rays as f64 / (self.gpu_ms * 1e-3)
    }
    pub fn cpu_rays_per_s(&self) -> f64 {
        self.rays as f64 / (self.cpu_ms * 1e-3)
    }
    pub fn ratio(&self) -> f64 {
        self.cpu_ms / self.gpu_ms
    }
}

pub struct RaysReport {
    pub triangles: usize,
    pub nodes: usize,
    pub depth: usize,
    pub build_ms: f64,
    pub cpu_threads: usize,
    pub repeats: usize,
    pub rows: Vec<RaysRow>,
}

/// Traces `camera_rays` (coherent) and `random_rays` (incoherent) over `triangles`, closest hit
/// and any hit, `repeats` timed times each after one warm-up.
pub fn run(
    ctx: &Context,
    triangles: &[[Vec3; 3]],
    camera_rays: &[TraceRay],
    random_rays: &[TraceRay],
    repeats: usize,
) -> Result<RaysReport> {
    let repeats = repeats.max(1);
    let start = Instant::now();
    let cwbvh = build_cwbvh(triangles);
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let bvh = Bvh::from_cwbvh(&cwbvh, triangles);
    // The CPU traverses the same tree, with triangles in leaf order as on the GPU.
    let leaf_triangles: Vec<Triangle> = {
        let all = obvhs_triangles(triangles);
        cwbvh
            .primitive_indices
            .iter()
            .map(|&i| all[i as usize])
            .collect()
    };
    let gpu_bvh = GpuBvh::upload(ctx, &bvh)?;
    let trace = TraceRays::new(ctx)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());

    let mut rows = Vec::new();
    for (set, rays) in [("camera", camera_rays), ("random", random_rays)] {
        if rays.is_empty() {
            continue;
        }
        let ray_buffer = Buffer::from_slice(ctx, &format!("{set} rays"), rays)?;
        let hits = Buffer::<TraceHit>::zeroed(ctx, &format!("{set} hits"), rays.len())?;
        for mode in [TraceMode::Closest, TraceMode::Any] {
            let mut gpu_ms = Vec::new();
            for i in 0..repeats + 1 {
                let mut cmd = Commands::new(ctx)?;
                cmd.pass("trace", |cmd| {
                    trace.record(cmd, &gpu_bvh, &ray_buffer, &hits, mode)
                })?;
                let t = cmd.submit_and_wait()?;
                gpu_bvh.check_loop_cuts()?;
                if i > 0 {
                    gpu_ms.push(t.gpu_ms("trace").unwrap_or(t.wall_ms));
                }
            }
            let gpu_hits = hits.read()?.iter().filter(|h| h.is_hit()).count();
            let mut cpu_ms = Vec::new();
            let mut cpu_hits = 0;
            for i in 0..repeats + 1 {
                let start = Instant::now();
                cpu_hits = trace_cpu(&cwbvh, &leaf_triangles, rays, mode, threads);
                if i > 0 {
                    cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
                }
            }
            rows.push(RaysRow {
                set,
                mode,
                rays: rays.len(),
                gpu_ms: median(&mut gpu_ms),
                cpu_ms: median(&mut cpu_ms),
                gpu_hits,
                cpu_hits,
            });
        }
    }
    Ok(RaysReport {
        triangles: triangles.len(),
        nodes: bvh.nodes.len(),
        depth: bvh.depth(),
        build_ms,
        cpu_threads: threads,
        repeats,
        rows,
    })
}

/// obvhs's CWBVH traversal of every ray on `threads` threads; returns the number of hits.
pub fn trace_cpu(
    bvh: &CwBvh,
    leaf_triangles: &[Triangle],
    rays: &[TraceRay],
    mode: TraceMode,
    threads: usize,
) -> usize {
    const CHUNK: usize = 1024;
    let next = AtomicUsize::new(0);
    let hits = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| {
                let mut local = 0;
                loop {
                    let first = next.fetch_add(CHUNK, Ordering::Relaxed);
                    if first >= rays.len() {
                        break;
                    }
                    for r in &rays[first..(first + CHUNK).min(rays.len())] {
                        let ray = Ray::new(
                            Vec3A::from_array(r.origin),
                            Vec3A::from_array(r.direction),
                            0.0,
                            r.t_max,
                        );
                        let intersect = |ray: &Ray, id: usize| leaf_triangles[id].intersect(ray);
                        let hit = match mode {
                            TraceMode::Closest => {
                                let mut hit = RayHit::none();
                                bvh.ray_traverse(ray, &mut hit, intersect)
                            }
                            TraceMode::Any => !bvh.ray_traverse_miss(ray, intersect),
                        };
                        local += usize::from(black_box(hit));
                    }
                }
                hits.fetch_add(local, Ordering::Relaxed);
            });
        }
    });
    hits.into_inner()
}

pub fn print_table(device: &str, report: &RaysReport) {
    println!(
        "BVH traversal on {device}: {} triangles, CWBVH of {} nodes, depth {}, built in {:.0} ms",
        report.triangles, report.nodes, report.depth, report.build_ms
    );
    println!(
        "GPU: median pass time of {} runs; CPU: obvhs CWBVH on {} threads, median wall clock",
        report.repeats, report.cpu_threads
    );
    println!(
        "{:>7} {:>8} {:>9} {:>12} {:>12} {:>8} {:>9} {:>9}",
        "rays", "query", "count", "GPU Mrays/s", "CPU Mrays/s", "GPU/CPU", "GPU hits", "CPU hits"
    );
    for r in &report.rows {
        println!(
            "{:>7} {:>8} {:>9} {:>12.2} {:>12.2} {:>8.2} {:>9} {:>9}",
            r.set,
            match r.mode {
                TraceMode::Closest => "closest",
                TraceMode::Any => "any",
            },
            r.rays,
            r.gpu_rays_per_s() * 1e-6,
            r.cpu_rays_per_s() * 1e-6,
            r.ratio(),
            r.gpu_hits,
            r.cpu_hits
        );
    }
    println!("target on lavapipe: GPU/CPU >= 0.7 on random rays");
}
