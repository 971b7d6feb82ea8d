//! HDR-FLIP (src/image/flip.rs) against NVIDIA's implementation: tests/data/flip/expected.json
//! holds what flip-evaluator 1.7 computed for image pairs made by formula
//! (tests/data/flip/make.py); the same images are made here, bit for bit, and scored by the
//! port. The means must agree to 1e-5 relative and every pixel of the error maps to 1e-5
//! absolute, the exposures to 1e-6 relative and their count exactly. Measured on x86-64 Linux
//! (glibc): every pixel of every map bit for bit, the means 1.1e-7 to 3.4e-7 apart, all of it
//! flip-evaluator summing its map in f32 in row order (that sum over 768 reproduces its means
//! exactly; the port sums in f64). The tolerances leave room for another C library's
//! expf/powf. No Python and no GPU.

use irad::image::flip::{hdr_flip, DEFAULT_PIXELS_PER_DEGREE};
use irad::image::metrics::MetricsError;
use irad::image::Image;
use serde::Deserialize;

const W: u32 = 32;
const H: u32 = 24;

#[derive(Deserialize)]
struct Expected {
    flip_evaluator: String,
    width: u32,
    height: u32,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    name: String,
    ppd: Option<f32>,
    mean: f64,
    start_exposure: f32,
    stop_exposure: f32,
    exposures: u32,
    error_map: Vec<f32>,
}

/// make.py's `lcg`: uniform f64 in [0, 1) from the top 53 bits of a 64-bit LCG.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn spot(x: f64, y: f64, cx: f64, cy: f64, peak: f64) -> f64 {
    let d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
    peak / (1.0 + d2)
}

fn gradient(x: f64, y: f64, cx: f64, cy: f64, peak: f64, scale: f64) -> [f64; 3] {
    let s = spot(x, y, cx, cy, peak);
    [
        scale * (0.05 + 0.9 * x / (W - 1) as f64) + s,
        scale * (0.05 + 0.9 * y / (H - 1) as f64) + s,
        scale * 0.3 + s,
    ]
}

fn image(f: impl Fn(f64, f64) -> [f64; 3]) -> Image {
    let mut pixels = Vec::new();
    for y in 0..H {
        for x in 0..W {
            pixels.push(f(x as f64, y as f64).map(|v| v as f32));
        }
    }
    Image {
        width: W,
        height: H,
        pixels,
    }
}

fn noisy(base: &Image, seed: u64, amount: f64, floor: f64) -> Image {
    let mut u = Lcg(seed);
    let mut out = base.clone();
    for p in &mut out.pixels {
        for v in p.iter_mut() {
            let (a, b) = (u.next(), u.next());
            *v = (*v as f64 * (1.0 + amount * (a - 0.5)) + floor * b) as f32;
        }
    }
    out
}

/// make.py's `cases`, in its order.
fn cases() -> Vec<(&'static str, Image, Image)> {
    let base = image(|x, y| gradient(x, y, 22.0, 7.0, 20.0, 1.0));
    let shifted = image(|x, y| gradient(x, y, 20.0, 9.0, 20.0, 1.25));
    let dark = image(|x, y| {
        if x < 20.0 {
            [0.0; 3]
        } else {
            gradient(x, y, 26.0, 12.0, 500.0, 0.02)
        }
    });
    vec![
        ("identical", base.clone(), base.clone()),
        ("noise", base.clone(), noisy(&base, 1, 0.4, 0.0)),
        ("shifted", base.clone(), shifted),
        ("dark", dark.clone(), noisy(&dark, 2, 0.6, 0.002)),
        ("noise_ppd30", base.clone(), noisy(&base, 1, 0.4, 0.0)),
    ]
}

fn expected() -> Expected {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/flip/expected.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn matches_flip_evaluator() {
    let expected = expected();
    assert_eq!(expected.flip_evaluator, "1.7");
    assert_eq!((expected.width, expected.height), (W, H));
    let cases = cases();
    assert_eq!(cases.len(), expected.cases.len());
    for ((name, reference, test), want) in cases.iter().zip(&expected.cases) {
        assert_eq!(*name, want.name);
        let ppd = want.ppd.unwrap_or(DEFAULT_PIXELS_PER_DEGREE);
        let got = hdr_flip(reference, test, ppd).unwrap();
        let max_pixel_diff = got
            .error_map
            .iter()
            .zip(&want.error_map)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        let relative = if want.mean == 0.0 {
            got.mean.abs()
        } else {
            (got.mean / want.mean - 1.0).abs()
        };
        println!(
            "{name}: mean {:.9} (flip-evaluator {:.9}, relative difference {relative:.2e}), \
             largest pixel difference {max_pixel_diff:.2e}, exposures {} from {} to {}",
            got.mean, want.mean, got.exposures, got.start_exposure, got.stop_exposure
        );
        assert_eq!(got.exposures, want.exposures, "{name}: exposures");
        assert!(
            (got.start_exposure - want.start_exposure).abs() <= 1e-6 * want.start_exposure.abs()
                && (got.stop_exposure - want.stop_exposure).abs()
                    <= 1e-6 * want.stop_exposure.abs(),
            "{name}: exposures {}..{} against {}..{}",
            got.start_exposure,
            got.stop_exposure,
            want.start_exposure,
            want.stop_exposure
        );
        assert!(
            relative <= 1e-5,
            "{name}: mean {} against {}",
            got.mean,
            want.mean
        );
        assert!(
            max_pixel_diff <= 1e-5,
            "{name}: a pixel {max_pixel_diff} apart"
        );
    }
}

#[test]
fn identical_images_score_zero_and_errors_are_in_range() {
    let (_, reference, _) = &cases()[0];
    let same = hdr_flip(reference, reference, DEFAULT_PIXELS_PER_DEGREE).unwrap();
    assert_eq!(same.mean, 0.0);
    assert!(same.error_map.iter().all(|&e| e == 0.0));
    for (name, reference, test) in cases() {
        let got = hdr_flip(&reference, &test, DEFAULT_PIXELS_PER_DEGREE).unwrap();
        assert!(
            got.error_map.iter().all(|e| (0.0..=1.0).contains(e)),
            "{name}"
        );
    }
}

#[test]
fn bad_inputs_are_refused_by_name() {
    let (_, reference, test) = &cases()[1];
    let ppd = DEFAULT_PIXELS_PER_DEGREE;

    let mut nan = test.clone();
    nan.pixels[5][1] = f32::NAN;
    nan.pixels[9][0] = f32::INFINITY;
    assert_eq!(
        hdr_flip(reference, &nan, ppd).unwrap_err(),
        MetricsError::NonFiniteTest { count: 2 }
    );
    assert_eq!(
        hdr_flip(&nan, reference, ppd).unwrap_err(),
        MetricsError::NonFiniteReference { count: 2 }
    );

    let small = Image::new(4, 4);
    assert!(matches!(
        hdr_flip(reference, &small, ppd),
        Err(MetricsError::SizeMismatch { .. })
    ));
    let empty = Image::new(0, 0);
    assert!(matches!(
        hdr_flip(&empty, &empty, ppd),
        Err(MetricsError::Empty { .. })
    ));
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e5] {
        assert!(
            matches!(
                hdr_flip(reference, test, bad),
                Err(MetricsError::PixelsPerDegree { .. })
            ),
            "{bad}"
        );
    }
}

/// Where flip-evaluator stops (a black reference: start exposure past the stop) or reads a
/// pixel past f32's square as black, the port gives a defined, finite result.
#[test]
fn black_references_and_huge_values_give_finite_errors() {
    let black = Image::new(W, H);
    let ppd = DEFAULT_PIXELS_PER_DEGREE;
    let same = hdr_flip(&black, &black, ppd).unwrap();
    assert_eq!(same.mean, 0.0);
    assert_eq!(same.start_exposure, same.stop_exposure);

    let (_, _, test) = &cases()[1];
    let lit = hdr_flip(&black, test, ppd).unwrap();
    assert!(lit.mean.is_finite() && lit.mean > 0.9, "{}", lit.mean);

    let mut huge = black.clone();
    huge.pixels[100] = [f32::MAX, 1e30, -1e30];
    let got = hdr_flip(test, &huge, ppd).unwrap();
    assert!(got.mean.is_finite() && got.error_map.iter().all(|e| e.is_finite()));
}

#[test]
fn metrics_carry_flip_on_request() {
    use irad::image::metrics::{compare, compare_with_flip, Metrics, SequenceScore};
    let all = cases();
    let (_, reference, test) = &all[1];
    let ppd = DEFAULT_PIXELS_PER_DEGREE;
    let plain = compare(test, reference).unwrap();
    assert_eq!(plain.flip, None);
    let with = compare_with_flip(test, reference, ppd).unwrap();
    let want = hdr_flip(reference, test, ppd).unwrap().mean;
    assert_eq!(with.flip, Some(want));
    assert_eq!(Metrics { flip: None, ..with }, plain);

    // A NaN in the image under test: the other figures as ever, no FLIP.
    let mut nan = test.clone();
    nan.pixels[3][2] = f32::NAN;
    let m = compare_with_flip(&nan, reference, ppd).unwrap();
    assert_eq!((m.nan_inf, m.flip), (1, None));
    assert!(m.rel_mse.is_finite());
    assert!(compare_with_flip(test, reference, -1.0).is_err());

    // The mean has FLIP when every image has it.
    let both = Metrics::mean(&[with, with]);
    assert_eq!(both.flip, Some(want));
    assert_eq!(Metrics::mean(&[with, plain]).flip, None);
    assert_eq!(Metrics::mean(&[]).flip, None);

    // Sequences: per frame and in the mean, only when asked for.
    let frames = [
        (test, reference),
        (&all[2].2, &all[2].1),
        (&all[4].2, &all[4].1),
    ];
    let mut score = SequenceScore::with_flip(ppd);
    let mut plain_score = SequenceScore::default();
    let mut sum = 0.0;
    for (x, r) in frames {
        let m = score.push(x.clone(), r.clone()).unwrap();
        sum += hdr_flip(r, x, ppd).unwrap().mean;
        assert!(m.flip.is_some());
        assert_eq!(plain_score.push(x.clone(), r.clone()).unwrap().flip, None);
    }
    let (per_frame, summary) = score.finish();
    assert_eq!(per_frame.len(), 3);
    assert!((summary.mean.flip.unwrap() - sum / 3.0).abs() < 1e-15);
    assert_eq!(plain_score.finish().1.mean.flip, None);
}
