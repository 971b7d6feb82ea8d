//! The guard of a refactor: every method renders two scenes at 24 x 16 pixels with small
//! counts and fixed seeds, and the image's bits must hash to what tests/data/pixel_hashes.txt
//! recorded (FNV-1a over every f32 of the image, then each extra map). The bits are the
//! device's: the file holds lavapipe's (this project's CI device); elsewhere the test only
//! reports. `scripts/record-pixel-hashes.sh` rewrites the file (`IRAD_RECORD_PIXEL_HASHES=1`),
//! for a change that means to alter images (say which in its commit), after the statistical
//! tier has passed: these hashes stand in CI for the statistical tests (scripts/test.sh).

use crate::common;

use irad::methods::renderers::Renderers;
use irad::methods::Method;
use irad::scene::gpu::GpuScene;

use common::{scene_file, with_gpu};

/// (method, scene, settings): each method on its home scene and one more.
const CASES: &[(&str, &str, &str)] = &[
    ("reference", "cornell-box", "spp = 4\nseed = 3"),
    ("reference", "glossy-env", "spp = 4\nseed = 3"),
    ("ir", "cornell-box", "vpls = 64\nframes = 2\nseed = 3"),
    (
        "ir",
        "failure/corner-light",
        "vpls = 64\nframes = 2\nseed = 3",
    ),
    ("bir", "cornell-box", "vpls = 64\nframes = 2\nseed = 3"),
    ("bir", "failure/u-office", "vpls = 64\nframes = 2\nseed = 3"),
    (
        "bundles",
        "failure/glossy-cornell",
        "frames = 2\niterations = 8\nseed = 3",
    ),
    (
        "bundles",
        "spot-light",
        "frames = 2\niterations = 8\nseed = 3",
    ),
    ("env", "glossy-env", "frames = 2\nspp = 8\nseed = 3"),
    ("env", "failure/sun-behind", "frames = 2\nspp = 8\nseed = 3"),
    ("lightfield", "car-headlights", "frames = 2\nseed = 3"),
    ("restir", "cornell-box", "frames = 2\nseed = 3"),
    ("restir", "glossy-env", "frames = 2\nseed = 3"),
    (
        "restir",
        "cornell-box",
        "frames = 2\ncombination = \"one-over-z\"\nseed = 3",
    ),
    (
        "restir",
        "spot-light",
        "frames = 2\ncombination = \"biased\"\nlight_sampler = \"power\"\nseed = 3",
    ),
    (
        "reference",
        "spot-light",
        "spp = 4\nlight_sampler = \"bvh\"\nseed = 3",
    ),
    (
        "lightfield",
        "failure/headlight-wall",
        "frames = 2\nseed = 3",
    ),
    // The configurations of the statistical tier (scripts/test.sh --statistical, left out of
    // both CI passes), so that their kernels' bits are checked in CI, exactly, at 8 and 4
    // lanes and staged: a statistical test reads its means and variances off these bits.
    // reference: alpha_direct_light_is_unbiased_and_lowers_the_variance.
    (
        "reference",
        "glossy-env",
        "spp = 4\nmax_depth = 1\nalpha_frames = 2\nseed = 3",
    ),
    // ir: fractional_and_roulette_absorption_match_the_reference, ir_mean_matches_the_reference_
    // with_and_without_interleaving, error_falls_with_vpls_and_clamping_darkens_corners, and
    // compensation's plain clamp.
    (
        "ir",
        "cornell-box",
        "vpls = 64\nframes = 2\nabsorption = \"roulette\"\nclamp = 0\nseed = 3",
    ),
    (
        "ir",
        "cornell-box",
        "vpls = 64\nframes = 2\ninterleave = 4\nseed = 3",
    ),
    (
        "ir",
        "cornell-box",
        "vpls = 64\nframes = 2\ndirect = \"vpl\"\nclamp = 10\ncompensate = false\nseed = 3",
    ),
    (
        "ir",
        "failure/corner-light",
        "vpls = 64\nframes = 2\ncompensate = false\nseed = 3",
    ),
    // bir: every_strategy_matches_the_reference_mean_in_the_cornell_box, both_sides_beat_
    // reverse_only_in_the_halogen_office, the_uniform_floor_keeps_the_mean_where_power_
    // estimates_miss_vpls; compensated on the corner light (compensation.rs).
    (
        "bir",
        "cornell-box",
        "vpls = 64\nframes = 2\nstrategy = \"standard\"\nseed = 3",
    ),
    (
        "bir",
        "cornell-box",
        "vpls = 64\nframes = 2\nstrategy = \"reverse\"\nseed = 3",
    ),
    (
        "bir",
        "cornell-box",
        "vpls = 64\nframes = 2\nratio = 0\nbatch = 32\nseed = 3",
    ),
    (
        "bir",
        "failure/halogen-office",
        "vpls = 64\nframes = 2\nclamp = 0\ndirect_spp = 1\nseed = 3",
    ),
    (
        "bir",
        "failure/corner-light",
        "vpls = 64\nframes = 2\nfloor = 0\nseed = 3",
    ),
    // bundles: every_strategy_matches_the_path_length_limited_reference_mean,
    // environment_bundles_match_the_reference_direct_light, mis_beats_vpls_and_bundles_alone_
    // in_the_corner, roughness_clamping_suppresses_glossy_spikes_and_keeps_more_energy_than_
    // clamping.
    (
        "bundles",
        "spot-light",
        "frames = 2\niterations = 8\nstrategy = \"vpl\"\nseed = 3",
    ),
    (
        "bundles",
        "spot-light",
        "frames = 2\niterations = 8\nstrategy = \"bundle\"\nseed = 3",
    ),
    (
        "bundles",
        "failure/corner-light",
        "frames = 2\niterations = 8\ntwo_bounce = true\nseed = 3",
    ),
    (
        "bundles",
        "glossy-env",
        "frames = 2\niterations = 8\ndirections = \"environment\"\nseed = 3",
    ),
    (
        "bundles",
        "glossy-env",
        "frames = 2\niterations = 8\ndirections = \"uniform\"\nseed = 3",
    ),
    (
        "bundles",
        "failure/glossy-cornell",
        "frames = 2\niterations = 8\nglossy = \"clamp\"\nseed = 3",
    ),
    // env: every_strategy_matches_the_reference_direct_light, decorrelated_light_samples_keep_
    // the_image_mean_within_its_standard_error, dynamic_shares_waste_fewer_samples_with_the_
    // sun_behind, uniform_faces_needs_more_samples_at_equal_error.
    (
        "env",
        "glossy-env",
        "frames = 2\nspp = 8\nstrategy = \"uniform-faces\"\nseed = 3",
    ),
    (
        "env",
        "glossy-env",
        "frames = 2\nspp = 8\nstrategy = \"brdf\"\nseed = 3",
    ),
    (
        "env",
        "glossy-env",
        "frames = 2\nspp = 8\nstrategy = \"cosine\"\nseed = 3",
    ),
    (
        "env",
        "glossy-env",
        "frames = 2\nspp = 8\nstrategy = \"latlong\"\nseed = 3",
    ),
    (
        "env",
        "glossy-env",
        "frames = 2\nspp = 8\nstrategy = \"hierarchical\"\nseed = 3",
    ),
    (
        "env",
        "glossy-env",
        "frames = 2\nspp = 8\nstrategy = \"alpha\"\nalpha_samples = 5\nseed = 3",
    ),
    (
        "env",
        "glossy-env",
        "frames = 2\nspp = 8\nlight_only = true\nseed = 3",
    ),
    (
        "env",
        "failure/sun-behind",
        "frames = 2\nspp = 8\nshared_samples = true\nseed = 3",
    ),
    ("env", "moving-sun", "frames = 2\nspp = 8\nseed = 3"),
    // tests/state_across_frames.rs: temporal reuse across a change of map.
    ("restir", "moving-sun", "frames = 3\nseed = 3"),
    // lightfield: every_lightfield_strategy_matches_the_brute_force, strategies_at_equal_error.
    (
        "lightfield",
        "failure/headlight-wall",
        "frames = 2\nspp = 64\nstrategy = \"brute-force\"\nseed = 3",
    ),
    (
        "lightfield",
        "failure/headlight-wall",
        "frames = 2\nstrategy = \"uniform\"\nseed = 3",
    ),
    (
        "lightfield",
        "failure/headlight-wall",
        "frames = 2\nstrategy = \"precomputed\"\nseed = 3",
    ),
    (
        "lightfield",
        "failure/headlight-wall",
        "frames = 2\nshared_samples = true\nseed = 3",
    ),
    // The rest of the statistical tier's configurations (scripts/test.sh --statistical), so
    // that a change to any image those tests judge fails CI: the depth-limited path tracer at
    // pixel centres (the env, bundles and lightfield tests' references), alpha's direct light
    // on area lights and with a light share every frame, bundles without the two-bounce term,
    // without a map, unsuppressed and with an unclamped two-bounce term and on a map sequence,
    // ir's VPL direct light unclamped and its one-sample direct light, env's light samples
    // alone with uniform faces.
    (
        "reference",
        "cornell-box",
        "spp = 4\nmax_depth = 1\npixel_centres = true\nseed = 3",
    ),
    (
        "reference",
        "glossy-env",
        "spp = 4\nmax_depth = 2\npixel_centres = true\nseed = 3",
    ),
    (
        "reference",
        "failure/corner-light",
        "spp = 4\nmax_depth = 3\npixel_centres = true\nseed = 3",
    ),
    (
        "reference",
        "cornell-box",
        "spp = 4\nmax_depth = 1\nalpha_frames = 2\nseed = 3",
    ),
    (
        "reference",
        "cornell-box",
        "spp = 2\nmax_depth = 1\nalpha_frames = 2\nseed = 3",
    ),
    (
        "bundles",
        "spot-light",
        "frames = 2\niterations = 8\nstrategy = \"vpl\"\ntwo_bounce = false\nseed = 3",
    ),
    (
        "bundles",
        "failure/glossy-cornell",
        "frames = 2\niterations = 8\nglossy = \"none\"\ntwo_bounce = false\nseed = 3",
    ),
    (
        "bundles",
        "failure/corner-light",
        "frames = 2\niterations = 8\ntwo_bounce_clamp = 0\nseed = 3",
    ),
    (
        "bundles",
        "moving-sun",
        "frames = 2\niterations = 8\nseed = 3",
    ),
    (
        "ir",
        "cornell-box",
        "vpls = 64\nframes = 2\ndirect = \"vpl\"\nclamp = 0\nseed = 3",
    ),
    (
        "ir",
        "cornell-box",
        "vpls = 64\nframes = 2\ndirect_spp = 1\nseed = 3",
    ),
    (
        "env",
        "glossy-env",
        "frames = 2\nspp = 8\nstrategy = \"uniform-faces\"\nlight_only = true\nseed = 3",
    ),
];

/// (method, animated scene, frames, settings): sequences whose frames carry state (restir's
/// reservoirs through a moving light and dimming emission, and through a walk where lights
/// switch off), every frame's bits (tests/restir_motion.rs judges these configurations).
const SEQUENCE_CASES: &[(&str, &str, std::ops::Range<u32>, &str)] = &[
    (
        "restir",
        "cornell-circling",
        0..3,
        "frames = 1
seed = 3",
    ),
    (
        "restir",
        "many-lights-walk",
        23..26,
        "frames = 1
pixel_centres = true
seed = 3",
    ),
];

fn fnv1a(hash: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *hash ^= b as u64;
        *hash = hash.wrapping_mul(0x100000001b3);
    }
}

fn data_file() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pixel_hashes.txt")
}

#[test]
fn every_method_renders_the_recorded_bits() {
    with_gpu(|ctx| {
        let renderers = Renderers::default();
        let mut lines = Vec::new();
        for &(name, scene_name, settings) in CASES {
            let scene = scene_file(scene_name, 24, 16);
            let gpu = GpuScene::upload(ctx, &scene).unwrap();
            let params: toml::Table = settings.parse().unwrap();
            let method = Method::from_params(name, &params).unwrap_or_else(|e| panic!("{e}"));
            let out = renderers
                .run(ctx, &method, &scene, &gpu, |_, _| {})
                .unwrap_or_else(|e| panic!("{name} on {scene_name}: {e}"));
            let mut hash = 0xcbf29ce484222325u64;
            fnv1a(&mut hash, bytemuck::cast_slice(&out.image.pixels));
            for (_, map) in &out.maps {
                fnv1a(&mut hash, bytemuck::cast_slice(&map.pixels));
            }
            lines.push(format!("{name} {scene_name} {hash:016x}"));
        }
        for (name, scene_name, frames, settings) in SEQUENCE_CASES {
            let scene = scene_file(scene_name, 24, 16);
            let params: toml::Table = settings.parse().unwrap();
            let method = Method::from_params(name, &params).unwrap_or_else(|e| panic!("{e}"));
            let mut hash = 0xcbf29ce484222325u64;
            irad::sequence::render_frames_with(
                ctx,
                &renderers,
                &scene,
                &method,
                frames.clone(),
                |_, _, out| {
                    fnv1a(&mut hash, bytemuck::cast_slice(&out.image.pixels));
                    Ok(())
                },
            )
            .unwrap_or_else(|e| panic!("{name} on {scene_name}: {e:#}"));
            lines.push(format!(
                "{name} {scene_name} frames {}..{} {hash:016x}",
                frames.start, frames.end
            ));
        }
        let text = lines.join("\n") + "\n";
        let device = ctx.info().name.clone();
        if std::env::var("IRAD_RECORD_PIXEL_HASHES").is_ok_and(|v| v == "1") {
            assert!(
                device.contains("llvmpipe"),
                "{device}: the file holds lavapipe's bits; record them on lavapipe \
                 (IRAD_DEVICE=llvmpipe)"
            );
            std::fs::write(data_file(), &text).unwrap();
            return;
        }
        if !device.contains("llvmpipe") {
            eprintln!("{device}: the recorded bits are lavapipe's; this device renders:\n{text}");
            return;
        }
        let recorded = std::fs::read_to_string(data_file()).unwrap();
        let differ: Vec<String> = lines
            .iter()
            .zip(recorded.lines())
            .filter(|(now, then)| now.as_str() != *then)
            .map(|(now, then)| format!("now {now}, recorded {then}"))
            .collect();
        assert_eq!(
            lines.len(),
            recorded.lines().count(),
            "cases changed: record again"
        );
        assert!(differ.is_empty(), "images changed:\n{}", differ.join("\n"));
    });
}
