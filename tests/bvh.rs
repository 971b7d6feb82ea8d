//! The GPU BVH traversal (glsl/include/bvh.glsl through trace_rays.comp) against obvhs's own CPU
//! traversal of an independently built BVH2: over 100k rays on a mesh of over
//! 50k triangles, the same triangle (mapped back to input order), t within 1e-4 relative, the
//! same misses; any-hit agrees with closest-hit on every ray. Both sides intersect triangles with
//! the same Moller-Trumbore arithmetic (BvhTriangle::intersect mirrors the GLSL), so the
//! comparison tests the tree, its GPU layout and the traversal, not two triangle tests.
//!
//! Tolerance: a ray through a shared edge or vertex hits two triangles at the same t, and f32
//! rounding (FMA contraction differs between LLVM on lavapipe and rustc) can pick either, or
//! let the ray slip between them. Such rays are counted, must be genuine (the GPU's triangle
//! hit within 1e-4 of the CPU's t on the CPU too, or the hit within 1e-5 of an edge in
//! barycentric terms), and may be at most 1e-4 of the rays.

use crate::common;

use glam::Vec3;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::BvhBuildParams;

use irad::bvh::procedural::{self, Random};
use irad::bvh::{obvhs_triangles, Bvh, BvhTriangle, GpuBvh, GPU_STACK_SIZE};
use irad::gpu::{Buffer, Commands, Context, GpuError, GpuResult};
use irad::trace::{TraceHit, TraceMode, TraceRay, TraceRays, ANY_HIT, NO_TRIANGLE};

const T_TOLERANCE: f32 = 1e-4;
const TIE_FRACTION: f64 = 1e-4;

/// The test mesh: a displaced cube sphere (52272 triangles), 2000 random triangles in and
/// around it and a flat floor (800 triangles at y = -1.25).
fn test_mesh() -> Vec<[Vec3; 3]> {
    let mut triangles = procedural::noisy_sphere(7, 66, 2000);
    triangles.extend(procedural::floor(-1.25, 1.6, 20));
    triangles
}

/// Rays from inside and outside the sphere: random directions, rays aimed at the mesh,
/// axis-aligned directions (other components exactly 0, some along the floor's plane), some
/// with one zero component, non-unit lengths, and finite t_max.
fn test_rays(bounds: (Vec3, Vec3), count: usize) -> Vec<TraceRay> {
    let mut rng = Random::new(11, 0);
    let (lo, hi) = (bounds.0 * 1.4, bounds.1 * 1.4);
    let axes = [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    (0..count)
        .map(|i| {
            let mut origin = rng.point_in(lo, hi);
            let mut t_max = f32::INFINITY;
            let direction = match i % 8 {
                // Aimed at a point of the mesh's bounds (from anywhere).
                0 | 1 => rng.point_in(bounds.0, bounds.1) - origin,
                // Axis-aligned, exactly.
                2 => axes[(rng.uniform() * 6.0) as usize % 6],
                // Axis-aligned within the floor's plane.
                3 if i % 16 == 3 => {
                    origin.y = -1.25;
                    axes[[0, 1, 4, 5][(rng.uniform() * 4.0) as usize % 4]]
                }
                // One zero component, not unit length.
                3 => {
                    let mut d = rng.direction() * rng.range(0.1, 10.0);
                    d[(rng.uniform() * 3.0) as usize % 3] = 0.0;
                    d
                }
                // Finite t_max: some hits beyond it.
                4 => {
                    t_max = rng.range(0.01, 2.0);
                    rng.direction()
                }
                _ => rng.direction() * rng.range(0.5, 2.0),
            };
            TraceRay::new(origin, direction, t_max)
        })
        .collect()
}

/// Every ray's hit, no traversal cut short by the device's loop limit.
fn trace(ctx: &Context, bvh: &GpuBvh, rays: &[TraceRay], mode: TraceMode) -> Vec<TraceHit> {
    let (hits, cuts) = trace_repeated(ctx, bvh, rays, mode, 1);
    cuts.unwrap_or_else(|e| panic!("{e}"));
    hits
}

/// Every ray's hit, each ray traced `repeat` times by its invocation, and what
/// `GpuBvh::check_loop_cuts` says after the submission.
fn trace_repeated(
    ctx: &Context,
    bvh: &GpuBvh,
    rays: &[TraceRay],
    mode: TraceMode,
    repeat: u32,
) -> (Vec<TraceHit>, GpuResult<()>) {
    let trace = TraceRays::new(ctx).unwrap();
    let ray_buffer = Buffer::from_slice(ctx, "rays", rays).unwrap();
    let hits = Buffer::<TraceHit>::zeroed(ctx, "hits", rays.len()).unwrap();
    let mut cmd = Commands::new(ctx).unwrap();
    cmd.pass("trace", |cmd| {
        trace.record_repeated(cmd, bvh, &ray_buffer, &hits, mode, repeat)
    })
    .unwrap();
    cmd.submit_and_wait().unwrap();
    (hits.read().unwrap(), bvh.check_loop_cuts())
}

/// The closest hit by obvhs's BVH2 traversal: (input triangle, t, u, v).
struct CpuReference {
    bvh2: obvhs::bvh2::Bvh2,
    triangles: Vec<BvhTriangle>,
}

impl CpuReference {
    fn new(triangles: &[[Vec3; 3]]) -> Self {
        // Another builder configuration than the GPU's, so the trees differ.
        let params = BvhBuildParams::fast_build();
        CpuReference {
            bvh2: build_bvh2_from_tris(
                &obvhs_triangles(triangles),
                params,
                &mut Default::default(),
            ),
            triangles: triangles.iter().map(BvhTriangle::new).collect(),
        }
    }

    fn closest(&self, r: &TraceRay) -> Option<(u32, f32, f32, f32)> {
        let ray = Ray::new(r.origin().into(), r.direction().into(), 0.0, r.t_max);
        let mut hit = RayHit::none();
        let indices = &self.bvh2.primitive_indices;
        let found = self.bvh2.ray_traverse(ray, &mut hit, |ray, id| {
            self.triangles[indices[id] as usize]
                .intersect(r.origin(), r.direction(), ray.tmax)
                .map_or(f32::INFINITY, |(t, _, _)| t)
        });
        found.then(|| {
            let input = indices[hit.primitive_id as usize];
            let (t, u, v) = self.triangles[input as usize]
                .intersect(r.origin(), r.direction(), r.t_max)
                .expect("the reported triangle is hit");
            (input, t, u, v)
        })
    }
}

fn edge_distance(u: f32, v: f32) -> f32 {
    u.min(v).min(1.0 - u - v)
}

#[test]
fn gpu_traversal_matches_obvhs_on_100k_rays() {
    let triangles = test_mesh();
    assert!(triangles.len() >= 50_000);
    let bvh = Bvh::build(&triangles);
    let mut order = bvh.triangle_order.clone();
    order.sort_unstable();
    assert!(
        order.iter().enumerate().all(|(i, &t)| t == i as u32),
        "triangle_order is a permutation"
    );
    assert!(bvh.depth() <= GPU_STACK_SIZE);
    let rays = test_rays(procedural::bounds(&triangles), 120_000);
    let reference = CpuReference::new(&triangles);

    common::with_gpu(|ctx| {
        let gpu_bvh = GpuBvh::upload(ctx, &bvh).unwrap();
        let closest = trace(ctx, &gpu_bvh, &rays, TraceMode::Closest);
        let any = trace(ctx, &gpu_bvh, &rays, TraceMode::Any);

        let (mut hits, mut axis_hits, mut ties, mut edge_misses) = (0, 0, 0, 0);
        let mut failures = Vec::new();
        for (i, (r, g)) in rays.iter().zip(&closest).enumerate() {
            let expected = reference.closest(r);
            let zero_components = r.direction.iter().filter(|&&c| c == 0.0).count();
            match (expected, g.triangle) {
                (None, NO_TRIANGLE) => {}
                (Some((tri, t, u, v)), gpu) if gpu != NO_TRIANGLE => {
                    hits += 1;
                    axis_hits += usize::from(zero_components >= 2);
                    let input = bvh.triangle_order[gpu as usize];
                    let t_close = (g.t - t).abs() <= T_TOLERANCE * t;
                    if input == tri {
                        let uv_close = (g.barycentrics[0] - u).abs() <= 1e-4
                            && (g.barycentrics[1] - v).abs() <= 1e-4;
                        if !t_close || !uv_close {
                            failures.push(format!(
                                "ray {i}: triangle {tri} at t {t} (u {u}, v {v}), GPU t {} (u {}, v {})",
                                g.t, g.barycentrics[0], g.barycentrics[1]
                            ));
                        }
                    } else {
                        // A tie: the GPU's triangle is hit at the same t on the CPU too.
                        let on_cpu = reference.triangles[input as usize].intersect(
                            r.origin(),
                            r.direction(),
                            r.t_max,
                        );
                        match on_cpu {
                            Some((t2, _, _)) if t_close && (t2 - t).abs() <= T_TOLERANCE * t => {
                                ties += 1
                            }
                            _ => failures.push(format!(
                                "ray {i}: CPU triangle {tri} at t {t}, GPU triangle {input} at t {} (CPU sees {on_cpu:?})",
                                g.t
                            )),
                        }
                    }
                }
                (Some((tri, t, u, v)), _) => {
                    // A ray slipping through an edge on the GPU only.
                    if edge_distance(u, v) <= 1e-5 {
                        edge_misses += 1;
                    } else {
                        failures.push(format!(
                            "ray {i}: GPU misses, CPU hits triangle {tri} at t {t} (u {u}, v {v})"
                        ));
                    }
                }
                (None, gpu) => {
                    let input = bvh.triangle_order[gpu as usize];
                    let on_cpu = reference.triangles[input as usize].intersect(
                        r.origin(),
                        r.direction(),
                        r.t_max,
                    );
                    match on_cpu {
                        Some((_, u, v)) if edge_distance(u, v) <= 1e-5 => edge_misses += 1,
                        _ => failures.push(format!(
                            "ray {i}: CPU misses, GPU hits triangle {input} at t {} (CPU sees {on_cpu:?})",
                            g.t
                        )),
                    }
                }
            }
        }
        let any_disagree = closest
            .iter()
            .zip(&any)
            .filter(|(c, a)| c.is_hit() != (a.triangle == ANY_HIT))
            .count();
        eprintln!(
            "{} rays, {} triangles: {hits} hits ({axis_hits} with axis-aligned directions), \
             {ties} ties, {edge_misses} edge misses, {} failures, any-hit disagrees on {any_disagree}",
            rays.len(),
            triangles.len(),
            failures.len()
        );
        assert!(
            failures.is_empty(),
            "{} ray(s) differ:\n{}",
            failures.len(),
            failures[..failures.len().min(20)].join("\n")
        );
        assert!(
            (ties + edge_misses) as f64 <= TIE_FRACTION * rays.len() as f64,
            "{ties} ties and {edge_misses} edge misses in {} rays",
            rays.len()
        );
        assert!(
            hits > rays.len() / 3 && axis_hits > 1000,
            "the rays hit enough"
        );
        assert!(
            any.iter()
                .all(|a| a.triangle == ANY_HIT || a.triangle == NO_TRIANGLE),
            "any-hit writes only ANY_HIT or NO_TRIANGLE"
        );
        assert_eq!(any_disagree, 0, "any-hit and closest-hit disagree");
    });
}

/// Small and degenerate inputs against brute force: no triangles, one triangle, a flat
/// axis-aligned floor hit along and across its plane, and a degenerate triangle.
#[test]
fn small_and_flat_meshes_match_brute_force() {
    let one = vec![[
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ]];
    let mut with_degenerate = procedural::floor(0.0, 1.0, 3);
    with_degenerate.push([Vec3::ONE, Vec3::ONE, Vec3::ONE]);
    with_degenerate.push([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]);
    let meshes: Vec<Vec<[Vec3; 3]>> = vec![Vec::new(), one, with_degenerate];
    let mut rng = Random::new(3, 1);
    let mut rays = Vec::new();
    for _ in 0..2000 {
        let origin = rng.point_in(Vec3::splat(-2.0), Vec3::splat(2.0));
        rays.push(TraceRay::new(origin, rng.direction(), f32::INFINITY));
        rays.push(TraceRay::new(
            origin,
            Vec3::new(0.0, -origin.y.signum(), 0.0),
            f32::INFINITY,
        ));
        rays.push(TraceRay::new(origin.with_y(0.0), Vec3::X, f32::INFINITY));
    }
    common::with_gpu(|ctx| {
        for triangles in &meshes {
            let bvh = Bvh::build(triangles);
            let gpu_bvh = GpuBvh::upload(ctx, &bvh).unwrap();
            let closest = trace(ctx, &gpu_bvh, &rays, TraceMode::Closest);
            let any = trace(ctx, &gpu_bvh, &rays, TraceMode::Any);
            let tris: Vec<BvhTriangle> = triangles.iter().map(BvhTriangle::new).collect();
            for (i, r) in rays.iter().enumerate() {
                let brute = tris
                    .iter()
                    .enumerate()
                    .filter_map(|(k, t)| {
                        t.intersect(r.origin(), r.direction(), r.t_max)
                            .map(|h| (k, h.0))
                    })
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                let g = closest[i];
                match brute {
                    None => assert!(
                        !g.is_hit(),
                        "{} triangles, ray {i}: GPU hit, brute force misses",
                        triangles.len()
                    ),
                    Some((_, t)) => {
                        assert!(
                            g.is_hit(),
                            "{} triangles, ray {i}: GPU misses, brute force hits at {t}",
                            triangles.len()
                        );
                        assert!(
                            (g.t - t).abs() <= T_TOLERANCE * t,
                            "ray {i}: t {} vs {t}",
                            g.t
                        );
                    }
                }
                assert_eq!(
                    g.is_hit(),
                    any[i].triangle == ANY_HIT,
                    "ray {i}: any-hit disagrees"
                );
            }
        }
    });
}

/// A traversal cut short by lavapipe's loop limit (65535 iterations an invocation, all its
/// loops together, then every loop breaks out silently; docs/DESIGN.md "The loop budget") is
/// reported, not left in the hits: each invocation traces its ray 65535 times, which spends the
/// budget within a few thousand traversals and cuts the one under way. Without the limit (a GPU
/// driver) nothing is cut and nothing reported. Traced once or 64 times (within the budget),
/// nothing is reported, and the check clears the record, so the next submission starts clean.
#[test]
fn a_traversal_cut_by_the_loop_limit_is_reported() {
    let triangles = procedural::noisy_sphere(5, 24, 500);
    let bvh = Bvh::build(&triangles);
    let rays = test_rays(procedural::bounds(&triangles), 128);
    common::with_gpu(|ctx| {
        let gpu_bvh = GpuBvh::upload(ctx, &bvh).unwrap();
        let limited = ctx.info().driver.contains("llvmpipe");
        for mode in [TraceMode::Closest, TraceMode::Any] {
            let once = trace(ctx, &gpu_bvh, &rays, mode);
            assert!(
                once.iter().filter(|h| h.is_hit()).count() > rays.len() / 4,
                "{mode:?}: the rays hit enough to traverse far"
            );
            // Within the budget (a few thousand iterations): nothing cut, nothing reported.
            let (within, cuts) = trace_repeated(ctx, &gpu_bvh, &rays, mode, 64);
            cuts.unwrap_or_else(|e| panic!("{mode:?}, traced 64 times: {e}"));
            assert_eq!(within, once, "{mode:?}: traced 64 times, the same hits");
            let (repeated, cuts) = trace_repeated(ctx, &gpu_bvh, &rays, mode, 65535);
            let differ = once.iter().zip(&repeated).filter(|(a, b)| a != b).count();
            eprintln!(
                "{mode:?}, driver {}: traced 65535 times, {differ} of {} hits differ from \
                 traced once; check: {cuts:?}",
                ctx.info().driver,
                rays.len()
            );
            if limited {
                let e = cuts.expect_err("a cut traversal is reported");
                assert!(matches!(e, GpuError::TraversalCut), "{e}");
                assert!(e.to_string().contains("loop limit"), "{e}");
                assert!(differ > 0, "{mode:?}: the cut traversals' hits are wrong");
            } else {
                cuts.unwrap_or_else(|e| panic!("{mode:?}: {e}"));
                assert_eq!(differ, 0, "{mode:?}: the same hit every time");
            }
            // The record was cleared: traced once again, nothing is reported.
            assert_eq!(trace(ctx, &gpu_bvh, &rays, mode), once);
        }
    });
}
