//! Sampling tables rebuilt only when their input changes (docs/DESIGN.md principle 9): a still
//! map's cube map, CDFs, latitude-longitude table, pyramid and bundle-direction table are built
//! once per render, a sequence's every frame, and `TableRebuild::EveryFrame` (`--rebuild-tables
//! every-frame`) rebuilds a still map's every frame with the same image bits. The counts are
//! the ones a render's JSON records per pass.

use crate::common;

use glam::Vec3;
use irad::methods::bundles::{Bundles, BundlesSettings};
use irad::methods::envmap::{Env, EnvSettings, Strategy};
use irad::methods::rebuild::TableRebuild;
use irad::methods::RenderOutput;
use irad::methods::Renderer;
use irad::scene::gpu::GpuScene;
use irad::scene::Scene;

use common::{scene_file, with_gpu};

const FRAMES: u32 = 3;

fn runs(out: &RenderOutput, pass: &str) -> u32 {
    out.passes
        .passes
        .iter()
        .find(|p| p.0 == pass)
        .map_or(0, |p| p.2)
}

/// glossy-env under a 3-map moving sun.
fn sequence(still: &Scene) -> Scene {
    let sky = irad::scene::sky::MovingSun {
        width: 32,
        height: 16,
        frames: FRAMES,
        sun_elevation: 35.0,
        sun_radius: 8.0,
        sun_radiance: Vec3::splat(20.0),
        rising: false,
    };
    let mut scene = still.clone();
    scene.environment_sequence = (0..FRAMES).map(|f| sky.map(f, 1.0)).collect();
    scene.environment = Some(scene.environment_sequence[0].clone());
    scene
}

#[test]
fn env_and_bundles_tables_are_built_once_for_a_still_map() {
    with_gpu(|ctx| {
        let still = scene_file("glossy-env", 8, 8);
        let moving = sequence(&still);
        let still_gpu = GpuScene::upload(ctx, &still).unwrap();
        let moving_gpu = GpuScene::upload(ctx, &moving).unwrap();
        let env = Renderer::<Env>::new(ctx).unwrap();
        for (strategy, passes) in [
            (Strategy::Dynamic, &["cube map", "cdf"][..]),
            (Strategy::Latlong, &["latlong table"][..]),
            (Strategy::Hierarchical, &["pyramid"][..]),
        ] {
            let settings = |rebuild| EnvSettings {
                spp: 4,
                frames: FRAMES,
                strategy,
                face_resolution: 16,
                rebuild,
                ..Default::default()
            };
            let render = |scene, gpu, rebuild| {
                let out = env
                    .render(ctx, scene, gpu, &settings(rebuild), |_, _| {})
                    .unwrap();
                assert_eq!(out.nonfinite_estimates, 0);
                out
            };
            let once = render(&still, &still_gpu, TableRebuild::WhenChanged);
            let every = render(&still, &still_gpu, TableRebuild::EveryFrame);
            let moving = render(&moving, &moving_gpu, TableRebuild::WhenChanged);
            for pass in passes {
                assert_eq!(runs(&once, pass), 1, "{strategy:?} {pass}: still map");
                assert_eq!(
                    runs(&every, pass),
                    FRAMES,
                    "{strategy:?} {pass}: every frame"
                );
                assert_eq!(runs(&moving, pass), FRAMES, "{strategy:?} {pass}: sequence");
            }
            assert_eq!(once.image.pixels, every.image.pixels, "{strategy:?}: bits");
        }

        let bundles = Renderer::<Bundles>::new(ctx).unwrap();
        let settings = |rebuild| BundlesSettings {
            iterations: 2,
            frames: FRAMES,
            rebuild,
            ..Default::default()
        };
        let render = |scene, gpu, rebuild| {
            bundles
                .render(ctx, scene, gpu, &settings(rebuild), |_, _| {})
                .unwrap()
        };
        let once = render(&still, &still_gpu, TableRebuild::WhenChanged);
        let every = render(&still, &still_gpu, TableRebuild::EveryFrame);
        let moving = render(&moving, &moving_gpu, TableRebuild::WhenChanged);
        assert_eq!(runs(&once, "bundle directions"), 1);
        assert_eq!(runs(&every, "bundle directions"), FRAMES);
        assert_eq!(runs(&moving, "bundle directions"), FRAMES);
        assert_eq!(once.image.pixels, every.image.pixels, "bundles: bits");
    });
}
