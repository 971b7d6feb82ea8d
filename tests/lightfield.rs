//! Light-field luminaires (issue 9, in progress): the GPU sampling tables against the f64
//! mirror.

mod common;

use irad::gpu::Commands;
use irad::methods::lightfield::tables::LuminaireTables;
use irad::sampling::luminaire::LuminaireSampler;
use irad::scene::luminaire::{Basis, Emitter, Geometry, Luminaire};

use common::with_gpu;

/// The GPU's conditional CDFs, marginal CDFs and summed-area tables of a generated headlight
/// (5 x 3 images of 24 x 16 texels) against sampling/restricted.rs's f64 tables, at every knot,
/// within 1e-5 of the image's total (f32 scans).
#[test]
fn gpu_tables_match_the_f64_mirror() {
    with_gpu(|ctx| {
        let geometry = Geometry {
            grid: [5, 3],
            pitch: [0.02, 0.03],
            basis: Basis::QuadraticBSpline,
            delta: 0.05,
            image_size: [0.3, 0.2],
            resolution: [24, 16],
        };
        let headlight = Emitter::Headlight {
            radius: 0.05,
            radiance: 20.0,
            sharpness: 12.0,
            tilt: 3.0,
        };
        let lum = Luminaire::from_emitter(geometry, |u, s| headlight.radiance(u, s, 0.05), "test");
        let mirror = LuminaireSampler::new(&lum);
        let tables = LuminaireTables::new(ctx, &lum).unwrap();
        let mut cmd = Commands::new(ctx).unwrap();
        cmd.pass("luminaire tables", |cmd| tables.record(cmd))
            .unwrap();
        cmd.submit_and_wait().unwrap();
        let (rs, rt) = (24usize, 16usize);
        let column_cdf = tables.column_cdf.read().unwrap();
        let marginal = tables.marginal_cdf.read().unwrap();
        let sat = tables.sat.read().unwrap();
        let totals = tables.image_totals.read().unwrap();
        let mut lit = 0;
        for (m, image) in mirror.images.iter().enumerate() {
            let total = image.marginal_knot(rs);
            if total > 0.0 {
                lit += 1;
            }
            let tolerance = 1e-5 * total.max(1e-30);
            let close = |gpu: f32, cpu: f64, what: &str| {
                assert!(
                    (gpu as f64 - cpu).abs() <= tolerance,
                    "image {m} {what}: GPU {gpu} against {cpu} (total {total})"
                );
            };
            close(totals[m], total, "total");
            for s in 0..rs {
                close(
                    marginal[m * rs + s],
                    image.marginal_knot(s + 1),
                    &format!("marginal at {s}"),
                );
                for t in 0..rt {
                    close(
                        column_cdf[(m * rs + s) * rt + t],
                        image.column_knot(s, t + 1),
                        &format!("column {s} at {t}"),
                    );
                    close(
                        sat[(m * rt + t) * rs + s],
                        image.sat_knot(s + 1, t + 1),
                        &format!("SAT at ({s}, {t})"),
                    );
                }
            }
        }
        assert!(lit >= 10, "only {lit} of 15 images carry light");
    });
}
