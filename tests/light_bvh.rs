//! The light BVH on the GPU (glsl/include/light_bvh.glsl) against its CPU mirror
//! (src/sampling/light_bvh.rs), and the path tracer with it against the power table.
//!
//! `gpu_picks_and_pmfs_match_the_cpu_mirror` runs glsl/gpu/sample_light_bvh.comp over 4096
//! queries (point, normal or none, random number) in a scene of a few hundred emissive
//! triangles and point and spot lights: the same found flag, the same light and its pmf within
//! 1e-5 relative, and the GPU's re-walked pmf equal to its select pmf (exact on lavapipe,
//! where both sites compile alike). The tolerance: the two
//! sides compute every importance with the same f32 operations, but LLVM on lavapipe may fuse
//! some of them (FMA) where rustc does not, so an importance may differ in its last bits; a
//! random number within 1e-5 (relative) of a child's boundary may then take the other child.
//! Such queries are counted and may be at most 0.5% of them.
//!
//! `path_tracer_is_unbiased_with_either_sampler` renders one scene (a few hundred small emissive
//! quads over three orders of magnitude of power, a point light and two spots, one of them
//! hard-edged, over a diffuse floor with occluding boxes and a wall) with the reference
//! choosing its lights by power and through the BVH, at depth 1 and at the default depth, over
//! seeds: the image means agree within 4 combined standard errors (from the spread over
//! seeds), and each standard error is below 1% of the mean, so a delta light the BVH cannot
//! choose (a bias of a few percent: the hard-edged spot did before its fix) or a pmf at a BSDF
//! hit that is not the one the light was sampled with fails. (An emissive triangle the BVH
//! cannot choose would not show here: its BSDF hits take MIS weight 1. The CPU tests in
//! src/sampling/light_bvh.rs check that every light that reaches a point has pmf > 0.)

use crate::common;

use glam::{Vec3, Vec4};
use irad::gpu::{bind, Buffer, Commands, Context, Kernel};
use irad::methods::paths::LightSampler;
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::methods::Renderer;
use irad::sampling::light_bvh::{importance, LightBvh, ONE_MINUS_EPSILON};
use irad::sampling::pcg::{rand, rand3, sphere_direction as direction};
use irad::scene::gpu::GpuScene;
use irad::scene::{Light, Scene, Triangle};

use common::shapes::*;
use common::{luminance_mean, mean_and_stderr, with_gpu};

/// Two triangles: the quad at `centre` spanned by `a` and `b` (half-extents), facing a x b.
fn quad(centre: Vec3, a: Vec3, b: Vec3, material: u32) -> [Triangle; 2] {
    let p = |s: f32, t: f32| centre + s * a + t * b;
    [
        flat([p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0)], material),
        flat([p(-1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)], material),
    ]
}

/// A closed box between `lo` and `hi`, faces outward.
fn cuboid(lo: Vec3, hi: Vec3, material: u32) -> Vec<Triangle> {
    let c = 0.5 * (lo + hi);
    let h = 0.5 * (hi - lo);
    let (x, y, z) = (Vec3::X * h.x, Vec3::Y * h.y, Vec3::Z * h.z);
    [
        (x, y, z),
        (-x, z, y),
        (y, z, x),
        (-y, x, z),
        (z, x, y),
        (-z, y, x),
    ]
    .into_iter()
    .flat_map(|(n, a, b)| quad(c + n, a, b, material))
    .collect()
}

/// Emission levels of the emissive quads: Ke from 0.1 to 100, log-spaced.
const EMISSION_LEVELS: u32 = 8;

/// The test scene: `quads` small emissive quads (sizes 0.04 to 0.3, random orientations, Ke
/// over three orders of magnitude) above a diffuse floor with two boxes and a wall, a point
/// light, a soft spot (cone 25, falloff 35 degrees) and a hard-edged one (cone = falloff).
fn many_lights(quads: u32, size: u32) -> Scene {
    let mut materials = vec![
        material("floor", 0.6, 0.0, 1.0, 0.0),
        material("boxes", 0.4, 0.0, 1.0, 0.0),
    ];
    for k in 0..EMISSION_LEVELS {
        let ke = 0.1 * 1000f32.powf(k as f32 / (EMISSION_LEVELS - 1) as f32);
        materials.push(material(&format!("emitter {k}"), 0.0, 0.0, 1.0, ke));
    }
    let mut triangles = plane_y(6.0, 0.0, 0);
    triangles.extend(cuboid(
        Vec3::new(-1.5, 0.0, -1.0),
        Vec3::new(-0.5, 1.2, 0.0),
        1,
    ));
    triangles.extend(cuboid(
        Vec3::new(0.8, 0.0, 0.5),
        Vec3::new(1.6, 0.7, 1.5),
        1,
    ));
    // A wall across the back, half the lights behind it.
    triangles.extend(cuboid(
        Vec3::new(-4.0, 0.0, -2.2),
        Vec3::new(2.0, 2.0, -2.0),
        1,
    ));
    for i in 0..quads {
        let centre = Vec3::new(8.0, 2.5, 8.0) * rand3(1, i, 0) - Vec3::new(4.0, -0.4, 4.0);
        let size = 0.04 + 0.26 * rand(1, i, 3);
        let n = direction(1, i, 4);
        let a = n.any_orthonormal_vector();
        let b = n.cross(a);
        let level = (rand(1, i, 6) * EMISSION_LEVELS as f32) as u32;
        triangles.extend(quad(centre, size * a, size * b, 2 + level));
    }
    let mut scene = scene(
        "many lights",
        camera(
            Vec3::new(0.0, 5.0, 6.0),
            Vec3::new(0.0, 0.0, -0.5),
            Vec3::Y,
            60.0,
            size,
        ),
        triangles,
        materials,
    );
    scene.lights.push(Light::Point {
        position: Vec3::new(2.5, 2.0, -1.0),
        intensity: Vec3::splat(3.0),
    });
    scene.lights.push(Light::Spot {
        position: Vec3::new(-2.0, 3.0, 2.0),
        intensity: Vec3::splat(15.0),
        direction: Vec3::new(0.2, -1.0, 0.0),
        cone_angle: 25.0,
        falloff_angle: 35.0,
    });
    scene.lights.push(Light::Spot {
        position: Vec3::new(1.0, 3.5, 0.0),
        intensity: Vec3::splat(60.0),
        direction: Vec3::new(0.0, -1.0, 0.3),
        cone_angle: 20.0,
        falloff_angle: 20.0,
    });
    scene
}

/// The CPU's pick for a query (`LightBvh::sample`), and whether its random number passed
/// within `margin` (relative to the node's total importance) of a child boundary on the way.
// (The negated comparisons are the descent's, which takes NaN as zero.)
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn cpu_pick(bvh: &LightBvh, p: Vec3, n: Vec3, u: f32, margin: f32) -> (Option<(u32, f32)>, bool) {
    let pick = bvh.sample(p, n, u);
    // The descent of `sample`, watching the boundaries.
    let mut near = false;
    if bvh.nodes.len() > 1 {
        let (mut node, mut u) = (0usize, u);
        for _ in 0..64 {
            let (c0, c1) = (node + 1, bvh.nodes[node].link() as usize);
            let i0 = importance(&bvh.nodes[c0], p, n);
            let i1 = importance(&bvh.nodes[c1], p, n);
            if !(i0 > 0.0 || i1 > 0.0) {
                break;
            }
            let sum = i0 + i1;
            let t = u * sum;
            near |= (t - i0).abs() <= margin * sum;
            if t < i0 || !(i1 > 0.0) {
                u = (t / i0).min(ONE_MINUS_EPSILON);
                node = c0;
            } else {
                u = ((t - i0) / i1).min(ONE_MINUS_EPSILON);
                node = c1;
            }
            if bvh.nodes[node].is_leaf() {
                break;
            }
        }
    }
    (pick, near)
}

#[test]
fn gpu_picks_and_pmfs_match_the_cpu_mirror() {
    const QUERIES: u32 = 4096;
    let scene = many_lights(150, 16);
    with_gpu(|ctx: &Context| {
        let gpu_scene = GpuScene::upload(ctx, &scene).expect("upload");
        let bvh = &gpu_scene.light_bvh;
        assert!(bvh.nodes.len() > 500, "{} nodes", bvh.nodes.len());
        // Points over the floor, among the lights and around them; one normal in four none.
        let queries: Vec<[Vec4; 2]> = (0..QUERIES)
            .map(|i| {
                let p = Vec3::new(10.0, 4.0, 10.0) * rand3(9, i, 0) - Vec3::new(5.0, 0.5, 5.0);
                let n = if i % 4 == 0 {
                    Vec3::ZERO
                } else {
                    direction(9, i, 3)
                };
                [p.extend(rand(9, i, 5)), n.extend(0.0)]
            })
            .collect();
        let query_buffer = Buffer::from_slice(ctx, "LightQueries", &queries).unwrap();
        let picks = Buffer::<[u32; 4]>::zeroed(ctx, "LightPicks", queries.len()).unwrap();
        let kernel =
            Kernel::specialized(ctx, "sample_light_bvh", &gpu_scene.features.constants()).unwrap();
        let mut bindings = gpu_scene.scene_bindings();
        bindings.extend(gpu_scene.light_bvh_bindings());
        bindings.push(bind("LightQueries", &query_buffer));
        bindings.push(bind("LightPicks", &picks));
        let mut cmd = Commands::new(ctx).unwrap();
        kernel
            .dispatch_threads(&mut cmd, &bindings, &(), [QUERIES, 1, 1])
            .unwrap();
        cmd.submit_and_wait().unwrap();
        let picks = picks.read().unwrap();

        let (mut found, mut near_boundary, mut differ_near, mut worst) = (0, 0, 0, 0f32);
        for (i, (q, g)) in queries.iter().zip(&picks).enumerate() {
            let (p, n, u) = (q[0].truncate(), q[1].truncate(), q[0].w);
            let (cpu, near) = cpu_pick(bvh, p, n, u, 1e-5);
            near_boundary += near as u32;
            let gpu_found = g[3] == 1;
            let (gpu_pmf, gpu_rewalked) = (f32::from_bits(g[1]), f32::from_bits(g[2]));
            // Near a child's boundary the other child may lead into a dead end on one side only.
            if gpu_found != cpu.is_some() {
                assert!(
                    near,
                    "query {i} ({p}, n {n}, u {u}): found on the GPU {gpu_found}, on the CPU \
                     {cpu:?}, u not near a boundary"
                );
                differ_near += 1;
                continue;
            }
            let Some((entry, pmf)) = cpu else { continue };
            found += 1;
            assert_eq!(
                gpu_pmf.to_bits(),
                gpu_rewalked.to_bits(),
                "query {i}: the GPU's select pmf {gpu_pmf} and re-walked pmf {gpu_rewalked}"
            );
            if g[0] != entry {
                assert!(
                    near,
                    "query {i} ({p}, n {n}, u {u}): the GPU picks {} (pmf {gpu_pmf}), the CPU \
                     {entry} (pmf {pmf}), u not near a boundary",
                    g[0]
                );
                differ_near += 1;
                // The GPU's pick is one the CPU could make, with the pmf the CPU gives it.
                let cpu_pmf = bvh.pmf(p, n, g[0]);
                assert!(
                    (gpu_pmf - cpu_pmf).abs() <= 1e-5 * cpu_pmf,
                    "query {i}: GPU pmf {gpu_pmf}, CPU {cpu_pmf} for entry {}",
                    g[0]
                );
                continue;
            }
            let relative = (gpu_pmf - pmf).abs() / pmf;
            worst = worst.max(relative);
            assert!(
                relative <= 1e-5,
                "query {i}: entry {entry}: GPU pmf {gpu_pmf}, CPU {pmf}"
            );
        }
        eprintln!(
            "{found} of {QUERIES} queries found a light; {near_boundary} passed within 1e-5 of \
             a boundary, {differ_near} picked differently; worst pmf difference {worst:e}"
        );
        // Dead ends (light_bvh.rs's tests) leave about a tenth without a light.
        assert!(found > QUERIES * 8 / 10, "{found}");
        assert!(
            (near_boundary as f64) < 0.005 * QUERIES as f64,
            "{near_boundary} queries near a boundary"
        );
    });
}

/// Mean luminance of the reference's image per seed.
#[allow(clippy::too_many_arguments)]
fn image_means(
    ctx: &Context,
    scene: &Scene,
    gpu_scene: &GpuScene,
    reference: &Renderer<Reference>,
    sampler: LightSampler,
    max_depth: u32,
    spp: u32,
    seeds: u32,
) -> Vec<f64> {
    (0..seeds)
        .map(|seed| {
            let settings = ReferenceSettings {
                spp,
                seed: 1000 + seed,
                max_depth,
                light_sampler: sampler,
                ..Default::default()
            };
            let out = reference
                .render(ctx, scene, gpu_scene, &settings, |_, _| {})
                .expect("render");
            assert_eq!(out.nonfinite_estimates, 0);
            luminance_mean(&out.image)
        })
        .collect()
}

#[test]
fn path_tracer_is_unbiased_with_either_sampler() {
    let scene = many_lights(200, 32);
    with_gpu(|ctx| {
        let gpu_scene = GpuScene::upload(ctx, &scene).expect("upload");
        let reference = Renderer::<Reference>::new(ctx).expect("kernels");
        let default_depth = ReferenceSettings::default().max_depth;
        for (max_depth, spp, seeds) in [(1, 64, 6), (default_depth, 64, 6)] {
            let start = std::time::Instant::now();
            let [power, bvh] = [LightSampler::Power, LightSampler::Bvh].map(|sampler| {
                let means = image_means(
                    ctx, &scene, &gpu_scene, &reference, sampler, max_depth, spp, seeds,
                );
                mean_and_stderr(&means)
            });
            let combined = (power.1.powi(2) + bvh.1.powi(2)).sqrt();
            eprintln!(
                "max_depth {max_depth}: power {:.5} +- {:.5}, bvh {:.5} +- {:.5}; difference \
                 {:.2} combined standard errors ({:.1} s)",
                power.0,
                power.1,
                bvh.0,
                bvh.1,
                (bvh.0 - power.0) / combined,
                start.elapsed().as_secs_f64()
            );
            for (name, (mean, stderr)) in [("power", power), ("bvh", bvh)] {
                assert!(
                    stderr < 0.01 * mean,
                    "max_depth {max_depth}, {name}: too noisy to test (standard error {stderr} \
                     of mean {mean})"
                );
            }
            assert!(
                (bvh.0 - power.0).abs() < 4.0 * combined,
                "max_depth {max_depth}: mean {} through the BVH, {} by power (combined standard \
                 error {combined})",
                bvh.0,
                power.0
            );
        }
    });
}
