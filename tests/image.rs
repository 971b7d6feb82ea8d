//! Image outputs and error metrics (docs/DESIGN.md "Error metrics", "Outputs"): metrics against
//! values worked by hand, Lab against published values, the sRGB curve at its defining points,
//! and EXR, PNG and JSON round trips. No GPU.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;

use irad::image::metrics::{
    self, compare, rel_mse_against_split_reference, variance_across_seeds, MetricsError,
};
use irad::image::sidecar::{self, PassRecord, RenderRecord};
use irad::image::{exr, png, tonemap, Image};

fn image(width: u32, height: u32, pixels: &[[f32; 3]]) -> Image {
    assert_eq!(pixels.len(), (width * height) as usize);
    Image {
        width,
        height,
        pixels: pixels.to_vec(),
    }
}

fn gray(v: f32) -> [f32; 3] {
    [v, v, v]
}

/// A fresh folder under the system temp dir, unique to this test and process.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("irad-image-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn assert_close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, want {want} (tolerance {tol})"
    );
}

// --- tone map -------------------------------------------------------------------------------

#[test]
fn srgb_oetf_at_its_defining_points() {
    assert_eq!(tonemap::srgb_oetf(0.0), 0.0);
    // The linear segment ends at 0.0031308 with slope 12.92.
    assert_close(
        tonemap::srgb_oetf(0.0031308),
        12.92 * 0.0031308,
        1e-12,
        "at the knee",
    );
    assert_close(tonemap::srgb_oetf(0.001), 0.01292, 1e-12, "linear segment");
    // 1.055 * 0.5^(1/2.4) - 0.055
    assert_close(
        tonemap::srgb_oetf(0.5),
        0.735_356_983_052_449_5,
        1e-12,
        "at 0.5",
    );
    assert_close(tonemap::srgb_oetf(1.0), 1.0, 1e-12, "at 1");
    // The curve is continuous at the knee (to the rounding of the standard's constants).
    let below = tonemap::srgb_oetf(0.0031308);
    let above = tonemap::srgb_oetf(0.0031308 + 1e-12);
    assert!((above - below).abs() < 1e-6, "{below} vs {above}");
}

#[test]
fn srgb_eotf_inverts_oetf() {
    for i in 0..=1000 {
        let v = i as f64 / 1000.0;
        let back = tonemap::srgb_eotf(tonemap::srgb_oetf(v));
        assert_close(back, v, 1e-6, &format!("round trip of {v}"));
    }
}

#[test]
fn tonemap_to_8_bits() {
    assert_eq!(tonemap::tonemap_u8(0.0, 0.0), 0);
    assert_eq!(tonemap::tonemap_u8(0.0031308, 0.0), 10); // 0.04045 * 255 = 10.31
    assert_eq!(tonemap::tonemap_u8(0.5, 0.0), 188); // 0.73536 * 255 = 187.52
    assert_eq!(tonemap::tonemap_u8(1.0, 0.0), 255);
    // Clamp before the curve.
    assert_eq!(tonemap::tonemap_u8(7.5, 0.0), 255);
    assert_eq!(tonemap::tonemap_u8(-0.5, 0.0), 0);
    // Exposure in stops, applied before the clamp.
    assert_eq!(tonemap::tonemap_u8(0.25, 1.0), 188);
    assert_eq!(tonemap::tonemap_u8(1.0, -1.0), 188);
    assert_eq!(tonemap::tonemap_u8(2.0, -1.0), 255);
    assert_eq!(tonemap::tonemap_u8(4.0, -2.0), 255);
    assert_eq!(tonemap::tonemap_u8(8.0, -4.0), 188);
    // Non-finite values never reach the output.
    assert_eq!(tonemap::tonemap_u8(f32::NAN, 0.0), 0);
    assert_eq!(tonemap::tonemap_u8(f32::INFINITY, 0.0), 255);
    assert_eq!(tonemap::tonemap_u8(f32::NEG_INFINITY, 0.0), 0);
}

// --- Lab --------------------------------------------------------------------------------------

#[test]
fn lab_of_known_srgb_colours() {
    // Published D65 values (Lindbloom's calculator, sRGB companding).
    let cases: [([u8; 3], [f64; 3]); 6] = [
        ([255, 0, 0], [53.2408, 80.0925, 67.2032]),
        ([0, 255, 0], [87.7347, -86.1827, 83.1793]),
        ([0, 0, 255], [32.2970, 79.1875, -107.8602]),
        ([255, 255, 255], [100.0, 0.0, 0.0]),
        ([0, 0, 0], [0.0, 0.0, 0.0]),
        ([128, 128, 128], [53.5850, 0.0, 0.0]),
    ];
    for (rgb, want) in cases {
        let got = metrics::srgb8_to_lab(rgb);
        for c in 0..3 {
            assert_close(got[c], want[c], 2e-3, &format!("Lab[{c}] of sRGB {rgb:?}"));
        }
    }
}

#[test]
fn lab_of_dark_values_uses_the_linear_segment() {
    // Y = 0.001 is below (6/29)^3: L* = 903.3 Y (CIE 15).
    let lab = metrics::linear_to_lab([0.001, 0.001, 0.001]);
    assert_close(lab[0], 24389.0 / 27.0 * 0.001, 1e-6, "L* of a dark gray");
}

// --- metrics ----------------------------------------------------------------------------------

#[test]
fn metrics_by_hand_on_two_pixels() {
    let x = image(2, 1, &[[1.0, 0.5, 0.0], gray(0.25)]);
    let r = image(2, 1, &[gray(0.5), gray(0.0)]);
    let m = compare(&x, &r).unwrap();
    // Squared differences: 0.25, 0, 0.25 | 0.0625 x 3.
    // relMSE = (2 * 0.25 / 0.26 + 3 * 0.0625 / 0.01) / 6
    assert_close(
        m.rel_mse,
        (2.0 * 0.25 / 0.26 + 3.0 * 6.25) / 6.0,
        1e-12,
        "relMSE",
    );
    assert_close(m.rmse, (0.6875f64 / 6.0).sqrt(), 1e-12, "RMSE");
    // mean(x) = 2.25 / 6 = 0.375, mean(r) = 1.5 / 6 = 0.25.
    assert_close(m.bias, 0.5, 1e-12, "bias");
    // Pixel 0: Y(x) = 0.5702 is not above 10 * 0.5 + 0.1; pixel 1: 0.25 > 0.1.
    assert_close(m.outliers, 0.5, 0.0, "outliers");
    assert_eq!(m.nan_inf, 0);
    // Pixel 1: gray 0.25 against black is L* = 116 * 0.25^(1/3) - 16 with a* = b* = 0.
    let de1 = 116.0 * 0.25f64.cbrt() - 16.0;
    let de0 = metrics::delta_e76(
        metrics::linear_to_lab([1.0, 0.5, 0.0]),
        metrics::linear_to_lab([0.5, 0.5, 0.5]),
    );
    assert_close(m.lab_error, (de0 + de1) / 2.0, 1e-9, "Lab error");
}

#[test]
fn lab_error_by_hand_against_black() {
    // Red against black is the length of red's Lab vector; gray 0.25 against black is its L*.
    let x = image(2, 1, &[[1.0, 0.0, 0.0], gray(0.25)]);
    let r = image(2, 1, &[gray(0.0), gray(0.0)]);
    let red = (53.2408f64.powi(2) + 80.0925f64.powi(2) + 67.2032f64.powi(2)).sqrt();
    let g = 116.0 * 0.25f64.cbrt() - 16.0;
    assert_close(
        compare(&x, &r).unwrap().lab_error,
        (red + g) / 2.0,
        2e-3,
        "Lab error",
    );
}

#[test]
fn lab_error_sees_the_tone_map_clamp() {
    // Above 1 both tone map to white: no Lab error, though RMSE sees the difference.
    let x = image(1, 1, &[gray(4.0)]);
    let r = image(1, 1, &[gray(1.0)]);
    let m = compare(&x, &r).unwrap();
    assert_eq!(m.lab_error, 0.0);
    assert_close(m.rmse, 3.0, 1e-12, "RMSE");
}

#[test]
fn identical_images_score_zero() {
    let pixels: Vec<[f32; 3]> = (0..12)
        .map(|i| [i as f32 * 0.3, 1.0 / (i + 1) as f32, (i % 3) as f32 * 2.0])
        .collect();
    let x = image(4, 3, &pixels);
    let m = compare(&x, &x.clone()).unwrap();
    assert_eq!(
        [m.rel_mse, m.rmse, m.lab_error, m.bias, m.outliers],
        [0.0; 5]
    );
    assert_eq!(m.nan_inf, 0);
}

#[test]
fn bias_ignores_the_sign() {
    let r = image(2, 1, &[gray(1.0), gray(3.0)]); // mean 2
    let high = image(2, 1, &[gray(1.5), gray(3.5)]); // mean 2.5
    let low = image(2, 1, &[gray(0.5), gray(2.5)]); // mean 1.5
    let b_high = compare(&high, &r).unwrap().bias;
    let b_low = compare(&low, &r).unwrap().bias;
    assert_close(b_high, 0.25, 1e-12, "bias above");
    assert_close(b_low, 0.25, 1e-12, "bias below");
    // Noise that averages out is not bias.
    let noisy = image(2, 1, &[gray(1.5), gray(2.5)]);
    assert_eq!(compare(&noisy, &r).unwrap().bias, 0.0);
}

#[test]
fn outlier_threshold_at_the_boundary() {
    // Exactly at the threshold is not an outlier; one ulp above is (10 * 0.25 + 0.1 is 2.6 in
    // f64, and 0 * 10 + 0.1 is 0.1).
    assert!(!metrics::is_outlier(2.6, 0.25));
    assert!(metrics::is_outlier(
        f64::from_bits(2.6f64.to_bits() + 1),
        0.25
    ));
    assert!(!metrics::is_outlier(0.1, 0.0));
    assert!(metrics::is_outlier(
        f64::from_bits(0.1f64.to_bits() + 1),
        0.0
    ));
    // Through compare, black reference: threshold 0.1.
    let r = image(2, 1, &[gray(0.0), gray(0.0)]);
    let x = image(2, 1, &[gray(0.0999), gray(0.1001)]);
    assert_eq!(compare(&x, &r).unwrap().outliers, 0.5);
    // Reference 0.25: threshold 10 * 0.25 + 0.1 = 2.6 (2.5 without the offset, 0.35 without
    // the scale).
    let r = image(2, 2, &[gray(0.25); 4]);
    let x = image(2, 2, &[gray(2.59), gray(2.61), gray(2.55), gray(0.25)]);
    assert_eq!(compare(&x, &r).unwrap().outliers, 0.25);
    // Luminance, not a channel: a pure blue 2.0 has Y = 0.1444 (an outlier against black), a
    // pure blue 1.3 has Y = 0.0939 (not one).
    let r = image(2, 1, &[gray(0.0), gray(0.0)]);
    let x = image(2, 1, &[[0.0, 0.0, 2.0], [0.0, 0.0, 1.3]]);
    assert_eq!(compare(&x, &r).unwrap().outliers, 0.5);
}

#[test]
fn non_finite_values_are_counted_and_left_out() {
    let r = image(3, 1, &[gray(0.5), gray(0.5), gray(0.5)]);
    let x = image(
        3,
        1,
        &[
            [f32::NAN, 0.5, 0.5],
            [0.5, f32::INFINITY, f32::NEG_INFINITY],
            gray(0.75),
        ],
    );
    let m = compare(&x, &r).unwrap();
    assert_eq!(m.nan_inf, 3);
    // The finite values: 0.5, 0.5 (pixel 0), 0.5 (pixel 1), 0.75 x 3 (pixel 2).
    assert_close(
        m.rmse,
        (3.0f64 * 0.0625 / 6.0).sqrt(),
        1e-12,
        "RMSE over finite values",
    );
    assert_close(
        m.bias,
        (2.25 / 6.0 + 0.5 * 3.0 / 6.0 - 0.5) / 0.5,
        1e-12,
        "bias",
    );
    // Per-pixel figures only over pixel 2.
    assert_eq!(m.outliers, 0.0);
    let de = metrics::delta_e76(
        metrics::tonemapped_lab(gray(0.75)),
        metrics::tonemapped_lab(gray(0.5)),
    );
    assert_close(m.lab_error, de, 1e-12, "Lab error");
    // Every figure survives JSON (NaN as null).
    let all_nan = image(1, 1, &[gray(f32::NAN)]);
    let m = compare(&all_nan, &image(1, 1, &[gray(1.0)])).unwrap();
    assert_eq!(m.nan_inf, 3);
    assert!(m.rel_mse.is_nan() && m.lab_error.is_nan() && m.outliers.is_nan());
    let back: metrics::Metrics = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
    assert!(back.rmse.is_nan() && back.bias.is_nan());
    assert_eq!(back.nan_inf, 3);
}

#[test]
fn bias_against_a_black_reference_is_undefined() {
    let black = image(1, 1, &[gray(0.0)]);
    assert!(compare(&image(1, 1, &[gray(0.1)]), &black)
        .unwrap()
        .bias
        .is_nan());
    assert_eq!(compare(&black, &black).unwrap().bias, 0.0);
}

#[test]
fn bad_inputs_are_errors() {
    let a = image(2, 1, &[gray(0.0); 2]);
    let b = image(1, 2, &[gray(0.0); 2]);
    let err = compare(&a, &b).unwrap_err();
    assert_eq!(
        err,
        MetricsError::SizeMismatch {
            test: (2, 1),
            reference: (1, 2)
        }
    );
    let msg = err.to_string();
    assert!(msg.contains("2x1") && msg.contains("1x2"), "{msg}");

    let nan_ref = image(2, 1, &[gray(0.0), [0.0, f32::NAN, 0.0]]);
    assert_eq!(
        compare(&a, &nan_ref).unwrap_err(),
        MetricsError::NonFiniteReference { count: 1 }
    );
    let empty = Image::new(0, 4);
    assert!(matches!(
        compare(&empty, &empty),
        Err(MetricsError::Empty { .. })
    ));
    let short = Image {
        width: 2,
        height: 2,
        pixels: vec![gray(0.0); 3],
    };
    assert!(matches!(
        compare(&short, &a),
        Err(MetricsError::Malformed { len: 3, .. })
    ));
}

#[test]
fn variance_across_seeds_by_hand() {
    // One pixel, channel 0 takes 1, 2, 3 (sample variance 1), the others are constant.
    let imgs: Vec<Image> = [1.0, 2.0, 3.0]
        .iter()
        .map(|&v| image(1, 1, &[[v, 5.0, 5.0]]))
        .collect();
    assert_close(
        variance_across_seeds(&imgs).unwrap(),
        1.0 / 3.0,
        1e-12,
        "1 pixel",
    );
    // Two seeds, two pixels: values a, b have unbiased variance (a - b)^2 / 2.
    let a = image(2, 1, &[[0.0, 1.0, 2.0], gray(4.0)]);
    let b = image(2, 1, &[[1.0, 1.0, 0.0], gray(0.0)]);
    let want = (0.5 + 0.0 + 2.0 + 8.0 * 3.0) / 6.0;
    assert_close(
        variance_across_seeds(&[a.clone(), b]).unwrap(),
        want,
        1e-12,
        "2 pixels",
    );
    // Identical seeds have no variance.
    assert_eq!(variance_across_seeds(&[a.clone(), a.clone()]).unwrap(), 0.0);
    assert_eq!(
        variance_across_seeds(std::slice::from_ref(&a)).unwrap_err(),
        MetricsError::TooFewImages { count: 1 }
    );
    let other = image(1, 2, &[gray(0.0); 2]);
    let err = variance_across_seeds(&[a.clone(), a, other]).unwrap_err();
    assert!(
        matches!(err, MetricsError::SeedSizeMismatch { index: 2, .. }),
        "{err}"
    );
}

#[test]
fn flicker_by_hand() {
    // One pixel; channel 0 takes 1, 2, 3 (variance 1) over a reference of 2: 1 / (4 + 0.01);
    // the constant channels add 0. Averaged over 3 channels, then the square root.
    let frames: Vec<Image> = [1.0, 2.0, 3.0]
        .iter()
        .map(|&v| image(1, 1, &[[v, 5.0, 5.0]]))
        .collect();
    let reference = image(1, 1, &[[2.0, 5.0, 5.0]]);
    assert_close(
        metrics::flicker(&frames, &reference).unwrap(),
        (1.0 / 4.01f64 / 3.0).sqrt(),
        1e-12,
        "1 pixel",
    );
    // A black reference pixel is normalized by 0.01: values 0 and 0.5 have variance 0.125.
    let frames = [image(1, 1, &[gray(0.0)]), image(1, 1, &[[0.0, 0.0, 0.5]])];
    let want = (0.125f64 / 0.01 / 3.0).sqrt();
    assert_close(
        metrics::flicker(&frames, &image(1, 1, &[gray(0.0)])).unwrap(),
        want,
        1e-6,
        "black reference",
    );
    // Identical frames do not flicker; one frame cannot.
    let a = image(1, 1, &[gray(0.3)]);
    assert_eq!(metrics::flicker(&[a.clone(), a.clone()], &a).unwrap(), 0.0);
    assert_eq!(
        metrics::flicker(std::slice::from_ref(&a), &a).unwrap_err(),
        MetricsError::TooFewImages { count: 1 }
    );
}

/// A sequence's flicker on cases known by hand: the error alternating in sign every frame
/// (x_f = r (1 + a (-1)^f)) gives a r sqrt(2) / sqrt(r^2 + 0.01); a constant bias, the same
/// error every frame, and a reference that itself brightens frame by frame, matched exactly,
/// give 0; frames with independent noise give about the still flicker's relative deviation.
#[test]
fn sequence_flicker_by_hand() {
    let (a, r) = (0.1f32, 0.5f32);
    let refs: Vec<Image> = (0..6).map(|_| image(2, 1, &[gray(r); 2])).collect();
    let alternating: Vec<Image> = (0..6)
        .map(|f| {
            image(
                2,
                1,
                &[gray(r * (1.0 + a * if f % 2 == 0 { 1.0 } else { -1.0 })); 2],
            )
        })
        .collect();
    let expected = (a * r) as f64 * 2f64.sqrt() / ((r * r) as f64 + 0.01).sqrt();
    let got = metrics::sequence_flicker(&alternating, &refs).unwrap();
    assert!(
        (got - expected).abs() < 1e-6 * expected,
        "{got} against {expected}"
    );

    let biased: Vec<Image> = (0..6)
        .map(|_| image(2, 1, &[gray(r * (1.0 + a)); 2]))
        .collect();
    assert_eq!(metrics::sequence_flicker(&biased, &refs).unwrap(), 0.0);
    let brightening: Vec<Image> = (0..6)
        .map(|f| image(2, 1, &[gray(0.25 * f as f32); 2]))
        .collect();
    assert_eq!(
        metrics::sequence_flicker(&brightening, &brightening).unwrap(),
        0.0
    );

    // Independent noise of relative standard deviation 0.2 about a reference of 1 (and
    // r^2 + 0.01 = 1.01): flicker about 0.2 / sqrt(1.01), within sampling error.
    let mut state = 12345u64;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) as f32
    };
    let n = 4096;
    let ones: Vec<Image> = (0..8)
        .map(|_| image(n, 1, &vec![gray(1.0); n as usize]))
        .collect();
    let noisy: Vec<Image> = (0..8)
        .map(|_| {
            // Uniform on [-0.2 sqrt(3), 0.2 sqrt(3)]: standard deviation 0.2.
            let px: Vec<[f32; 3]> = (0..n)
                .map(|_| gray(1.0 + 0.2 * 3f32.sqrt() * (2.0 * uniform() - 1.0)))
                .collect();
            image(n, 1, &px)
        })
        .collect();
    let got = metrics::sequence_flicker(&noisy, &ones).unwrap();
    let expected = 0.2 / 1.01f64.sqrt();
    assert!(
        (got / expected - 1.0).abs() < 0.03,
        "{got} against {expected}"
    );

    // Per frame and over the sequence: the worst frame named, the mean over frames.
    let (per_frame, summary) = metrics::compare_sequence(&alternating, &refs).unwrap();
    assert_eq!(per_frame.len(), 6);
    assert!((summary.flicker - expected_alternating(a, r)).abs() < 1e-6);
    assert!((summary.mean.rel_mse - per_frame[0].rel_mse).abs() < 1e-12);
    assert!(metrics::sequence_flicker(&alternating[..1], &refs[..1]).is_err());
}

fn expected_alternating(a: f32, r: f32) -> f64 {
    (a * r) as f64 * 2f64.sqrt() / ((r * r) as f64 + 0.01).sqrt()
}

// --- files ------------------------------------------------------------------------------------

#[test]
fn exr_round_trip_keeps_every_bit() {
    let dir = temp_dir("exr");
    let path = dir.join("round.exr");
    let special = [
        0.0,
        -0.0,
        1.0,
        -2.5,
        f32::MIN_POSITIVE,
        1e-42, // subnormal
        f32::MAX,
        65504.0,
        std::f32::consts::PI,
        1.0 / 3.0,
        123456.79,
        1e-7,
    ];
    let pixels: Vec<[f32; 3]> = (0..20)
        .map(|i| {
            [
                special[i % special.len()],
                special[(i * 7 + 3) % special.len()],
                i as f32 * 0.37,
            ]
        })
        .collect();
    let img = image(5, 4, &pixels);
    exr::write(&path, &img).unwrap();
    let back = exr::read(&path).unwrap();
    assert_eq!((back.width, back.height), (5, 4));
    for (i, (a, b)) in img.pixels.iter().zip(&back.pixels).enumerate() {
        assert_eq!(
            a.map(f32::to_bits),
            b.map(f32::to_bits),
            "pixel {i}: wrote {a:?}, read {b:?}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

fn decode_png(
    path: &std::path::Path,
) -> (
    ::png::OutputInfo,
    Option<::png::SrgbRenderingIntent>,
    Vec<u8>,
) {
    let decoder = ::png::Decoder::new(BufReader::new(File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let srgb = reader.info().srgb;
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info, srgb, buf)
}

#[test]
fn png_round_trip_gives_the_tone_mapped_bytes() {
    let dir = temp_dir("png");
    let path = dir.join("round.png");
    // Row 0: black, 0.5 (188), 1 (255); row 1: clamped, non-finite, the knee.
    let img = image(
        3,
        2,
        &[
            gray(0.0),
            [0.5, 0.25, 0.0031308],
            gray(1.0),
            [2.0, -1.0, 0.125],
            [f32::NAN, f32::INFINITY, f32::NEG_INFINITY],
            [0.0031308, 0.001, 0.75],
        ],
    );
    png::write(&path, &img, 0.0).unwrap();
    let (info, srgb, bytes) = decode_png(&path);
    assert_eq!((info.width, info.height), (3, 2));
    assert_eq!(info.color_type, ::png::ColorType::Rgb);
    assert_eq!(info.bit_depth, ::png::BitDepth::Eight);
    assert!(srgb.is_some(), "the PNG should carry an sRGB chunk");
    assert_eq!(bytes, tonemap::tonemap_rgb8(&img, 0.0));
    // The same bytes worked by hand, row by row (0.25 -> 137, 0.125 -> 99, 0.75 -> 225,
    // 0.001 -> 0.01292 * 255 = 3.29).
    #[rustfmt::skip]
    let want: [u8; 18] = [
        0, 0, 0,   188, 137, 10,   255, 255, 255,
        255, 0, 99,   0, 255, 0,   10, 3, 225,
    ];
    assert_eq!(bytes, want);

    // Exposure: +1 stop maps 0.25 to what 0.5 was.
    png::write(&path, &image(1, 1, &[gray(0.25)]), 1.0).unwrap();
    assert_eq!(decode_png(&path).2, vec![188; 3]);
    assert!(png::write(&path, &img, f32::NAN).is_err());
    assert!(png::write(&path, &Image::new(0, 0), 0.0).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

fn record() -> RenderRecord {
    let mut parameters = BTreeMap::new();
    parameters.insert("spp".to_string(), serde_json::json!(1024));
    parameters.insert("clamp".to_string(), serde_json::json!(0.1));
    parameters.insert("interleave".to_string(), serde_json::json!([4, 4]));
    RenderRecord {
        method: "reference".into(),
        parameters,
        scene: "embedded:cornell-box".into(),
        scene_path: Some("/home/u/scenes/a b/scene.toml".into()),
        scene_hash: "0123456789abcdef".into(),
        resolution: [256, 192],
        seed: u64::MAX,
        frame: None,
        samples: 1024,
        device: "llvmpipe (LLVM 19.1.7, 256 bits) \u{e9}".into(),
        driver: "Mesa 25.0.7".into(),
        staging: None,
        passes: vec![
            PassRecord {
                name: "gbuffer".into(),
                gpu_ms: Some(0.1 + 0.2),
                count: 1024,
            },
            PassRecord {
                name: "path_trace".into(),
                gpu_ms: None,
                count: 1024,
            },
        ],
        gpu_ms_total: Some(1.0 / 3.0),
        wall_ms: 12345.678901234567,
        metrics: Some(metrics::Metrics {
            rel_mse: 1e-5 / 3.0,
            rmse: 0.012345678901234568,
            lab_error: 2.0f64.sqrt(),
            bias: 7.0e-300,
            outliers: 0.25,
            nan_inf: 0,
            flip: Some(0.125),
        }),
        reference: Some("/home/u/out/reference.exr".into()),
        warnings: vec!["spot light 2: \"cone\" wider than 90 degrees".into()],
        stats: [("kept_reverse_fraction".to_string(), 0.25)]
            .into_iter()
            .collect(),
        files: vec!["cornell.exr".into(), "cornell.png".into()],
        irad_version: sidecar::IRAD_VERSION.into(),
        git_commit: format!("{}-dirty", "0123456789abcdef0123456789abcdef01234567"),
        load: None,
    }
}

#[test]
fn json_round_trip() {
    let dir = temp_dir("json");
    let path = dir.join("record.json");
    let rec = record();
    rec.write(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.ends_with("}\n"));
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(value["scene_hash"], "0123456789abcdef");
    assert_eq!(value["resolution"], serde_json::json!([256, 192]));
    assert_eq!(value["passes"][1]["gpu_ms"], serde_json::Value::Null);
    assert_eq!(value["metrics"]["outliers"], 0.25);
    assert_eq!(value["metrics"]["flip"], 0.125);
    assert_eq!(RenderRecord::read(&path).unwrap(), rec);

    // A record written before metrics had FLIP reads back with it `None`, which is not written.
    let mut old = value.clone();
    old["metrics"].as_object_mut().unwrap().remove("flip");
    std::fs::write(&path, serde_json::to_string(&old).unwrap()).unwrap();
    let read = RenderRecord::read(&path).unwrap();
    let without = metrics::Metrics {
        flip: None,
        ..rec.metrics.unwrap()
    };
    assert_eq!(read.metrics, Some(without));
    read.write(&path).unwrap();
    assert!(!std::fs::read_to_string(&path).unwrap().contains("flip"));

    // Without a reference the metrics are null.
    let bare = RenderRecord {
        metrics: None,
        gpu_ms_total: None,
        ..record()
    };
    bare.write(&path).unwrap();
    assert_eq!(RenderRecord::read(&path).unwrap(), bare);

    std::fs::write(&path, "{\"method\": 3}").unwrap();
    let err = format!("{:#}", RenderRecord::read(&path).unwrap_err());
    assert!(err.contains("record.json"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn output_paths_append_extensions() {
    let p = |s: &str| PathBuf::from(s);
    assert_eq!(
        sidecar::output_paths(&p("out/cornell")),
        (
            p("out/cornell.exr"),
            p("out/cornell.png"),
            p("out/cornell.json")
        )
    );
    // A dot in the stem stays; one of our own extensions is not doubled.
    assert_eq!(
        sidecar::output_paths(&p("out/run.v2")).0,
        p("out/run.v2.exr")
    );
    assert_eq!(
        sidecar::output_paths(&p("out/cornell.png")).2,
        p("out/cornell.json")
    );
    assert_eq!(sidecar::output_paths(&p("cornell.EXR")).1, p("cornell.png"));
}

#[test]
fn write_all_creates_folders_and_three_files() {
    let dir = temp_dir("all");
    let out = dir.join("nested/deeper/cornell");
    let img = image(2, 2, &[gray(0.5), gray(0.25), gray(2.0), gray(0.0)]);
    let rec = record();
    let files = sidecar::write_all(&out, &img, &rec, 0.0, &[]).unwrap();
    let (exr_path, png_path, json_path) = (files.exr, files.png, files.json);
    assert_eq!(exr_path, dir.join("nested/deeper/cornell.exr"));
    assert_eq!(exr::read(&exr_path).unwrap(), img);
    assert_eq!(decode_png(&png_path).2, tonemap::tonemap_rgb8(&img, 0.0));
    assert_eq!(RenderRecord::read(&json_path).unwrap(), rec);
    // A bare file name writes into the current folder's relative path without a parent.
    assert_eq!(
        sidecar::output_paths(&PathBuf::from("x")).0,
        PathBuf::from("x.exr")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every file in `dir`, by name, with its bytes.
fn files_in(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    files.sort();
    files
}

#[test]
fn output_paths_of_a_folder_are_render_files_in_it() {
    let dir = temp_dir("folder-paths");
    let p = |s: &str| PathBuf::from(s);
    assert_eq!(sidecar::output_paths(&p("out/")).0, p("out/render.exr"));
    assert_eq!(sidecar::output_paths(&p(".")).1, p("./render.png"));
    assert_eq!(sidecar::output_paths(&p("..")).2, p("../render.json"));
    assert_eq!(sidecar::output_paths(&p("out/.")).0, p("out/./render.exr"));
    // An existing folder, even named like an image.
    std::fs::create_dir_all(dir.join("shots.exr")).unwrap();
    assert_eq!(
        sidecar::output_paths(&dir.join("shots.exr")).2,
        dir.join("shots.exr/render.json")
    );
    assert_eq!(
        sidecar::map_paths(&p("out/"), "alpha"),
        (p("out/render.alpha.exr"), p("out/render.alpha.png"))
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A write that fails partway through the set (a map whose file cannot be created, after the
/// EXR and PNG were written; a folder where the PNG goes) leaves the previous set byte for byte
/// and no temporary file.
#[test]
fn a_failed_write_leaves_the_previous_set() {
    let dir = temp_dir("unit");
    let out = dir.join("cornell");
    let old = image(1, 1, &[gray(0.5)]);
    let alpha = image(1, 1, &[gray(1.0)]);
    let maps = vec![("alpha".to_string(), alpha.clone())];
    sidecar::write_all(&out, &old, &record(), 0.0, &maps).unwrap();
    let before = files_in(&dir);
    assert_eq!(before.len(), 5);
    let new = image(1, 1, &[gray(2.0)]);
    let bad_map = vec![("no/such".to_string(), alpha)];
    let e = format!(
        "{:#}",
        sidecar::write_all(&out, &new, &record(), 0.0, &bad_map).unwrap_err()
    );
    assert!(e.contains("cornell.no/such.exr"), "{e}");
    assert_eq!(files_in(&dir), before);

    std::fs::remove_file(dir.join("cornell.png")).unwrap();
    std::fs::create_dir(dir.join("cornell.png")).unwrap();
    let before = files_in(&dir);
    let e = format!(
        "{:#}",
        sidecar::write_all(&out, &new, &record(), 0.0, &[]).unwrap_err()
    );
    assert!(e.contains("cornell.png is a folder"), "{e}");
    assert_eq!(files_in(&dir), before);
    let e = sidecar::write_all(&out, &new, &record(), f32::NAN, &[]).unwrap_err();
    assert!(e.to_string().contains("exposure"), "{e}");
    assert_eq!(files_in(&dir), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Two writers racing to the same `-o`, many times: the EXR, PNG and JSON left are always one
/// writer's (the EXR's value, the PNG's tone-mapped bytes and the JSON's seed agree).
#[test]
fn racing_writers_leave_one_writers_set() {
    let dir = temp_dir("race");
    let out = dir.join("shot");
    for trial in 0..40 {
        let barrier = std::sync::Barrier::new(2);
        std::thread::scope(|s| {
            for writer in 0..2u64 {
                let (barrier, out) = (&barrier, &out);
                s.spawn(move || {
                    let v = 0.1 + 0.4 * writer as f32;
                    let img = image(8, 8, &[gray(v); 64]);
                    let rec = RenderRecord {
                        seed: writer,
                        ..record()
                    };
                    barrier.wait();
                    sidecar::write_all(out, &img, &rec, 0.0, &[]).unwrap();
                });
            }
        });
        let exr = exr::read(&dir.join("shot.exr")).unwrap();
        let writer = if exr.pixels[0][0] < 0.3 { 0 } else { 1 };
        let png = decode_png(&dir.join("shot.png")).2;
        assert_eq!(png, tonemap::tonemap_rgb8(&exr, 0.0), "trial {trial}");
        let rec = RenderRecord::read(&dir.join("shot.json")).unwrap();
        assert_eq!(rec.seed, writer, "trial {trial}");
    }
    assert_eq!(files_in(&dir).len(), 3, "temporary files left");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn split_reference_rel_mse_takes_out_the_references_noise() {
    // Two references 0.9 and 1.1 around a converged 1.0: an exact image scores
    // (0 - 0.01) / 1.01, below zero by the references' own variance; relMSE against their
    // mean alone would be 0.
    let x = image(1, 1, &[gray(1.0)]);
    let a = image(1, 1, &[gray(0.9)]);
    let b = image(1, 1, &[gray(1.1)]);
    assert_close(
        rel_mse_against_split_reference(&x, &a, &b).unwrap(),
        -0.01 / 1.01,
        1e-7, // 0.9 and 1.1 are f32
        "exact image",
    );
    // An image 0.5 off: (0.25 - 0.01) / 1.01.
    let x = image(1, 1, &[gray(1.5)]);
    assert_close(
        rel_mse_against_split_reference(&x, &a, &b).unwrap(),
        0.24 / 1.01,
        1e-7,
        "off by 0.5",
    );
    // Equal references reduce it to compare's relMSE.
    let r = image(2, 1, &[gray(0.3), [0.1, 0.2, 0.4]]);
    let x = image(2, 1, &[gray(0.5), [0.0, 0.3, 0.2]]);
    assert_close(
        rel_mse_against_split_reference(&x, &r, &r).unwrap(),
        compare(&x, &r).unwrap().rel_mse,
        1e-12,
        "equal references",
    );
    let small = image(1, 1, &[gray(1.0)]);
    assert!(matches!(
        rel_mse_against_split_reference(&small, &r, &r),
        Err(MetricsError::SizeMismatch { .. })
    ));
}
