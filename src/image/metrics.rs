//! The error metrics of docs/DESIGN.md "Error metrics", one definition used by tests, `render` and
//! the benchmark harness. With x the image under test and r the reference:
//!
//! - relMSE = mean over pixels and channels of (x - r)^2 / (r^2 + 0.01);
//! - RMSE = sqrt(mean over pixels and channels of (x - r)^2);
//! - Lab error = mean over pixels of CIELAB Delta E 1976 (the "mean Lab error" of Lu 14),
//!   both images through the PNG's tone map at exposure 0 (clamp, sRGB, not quantized), then
//!   decoded to linear, to XYZ with the IEC 61966-2-1 matrix, to L*a*b* with the D65 white;
//! - bias = |mean(x) - mean(r)| / mean(r), means over all pixels and channels together;
//! - outliers = fraction of pixels with Y(x) > 10 Y(r) + 0.1, Y = 0.2126 R + 0.7152 G + 0.0722 B;
//! - nan_inf = number of non-finite values (channels) in x;
//! - flicker = temporal standard deviation across renders with successive seeds relative to
//!   the reference, averaged (see `flicker`); a sequence's flicker the same of the error's
//!   change from frame to frame (see `sequence_flicker`).
//! - flip = mean HDR-FLIP (src/image/flip.rs) at FLIP's default 67.02 pixels per degree, on
//!   request only (`compare_with_flip`, `SequenceScore::with_flip`): ~100 ms per exposure at
//!   128x96 in a debug build (0.65 s for a lit image's 6 exposures, 2.8 s when over half the
//!   reference is black, 28), 35 to 250 times `compare`'s own cost; 7 ms per exposure in
//!   release. `None` when not asked for, and when the image under test has non-finite values.
//!
//! Everything accumulates in f64. Non-finite values of x are counted in `nan_inf` and left
//! out of every other figure (a pixel with any non-finite channel is left out of the per-pixel
//! figures), so one NaN does not hide how far the rest of the image is. A figure with nothing
//! to average, or a bias against a black reference, is undefined: NaN in memory, `null` in
//! JSON.

use serde::{Deserialize, Serialize};

use super::{flip, tonemap, Image};

/// Offset in the relMSE denominator that keeps black reference pixels from dominating.
pub const REL_MSE_EPSILON: f64 = 0.01;
/// A pixel is an outlier when Y(x) > OUTLIER_SCALE Y(r) + OUTLIER_OFFSET.
pub const OUTLIER_SCALE: f64 = 10.0;
pub const OUTLIER_OFFSET: f64 = 0.1;

/// Rec. 709 luminance weights (docs/DESIGN.md "Conventions").
pub const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Linear sRGB (Rec. 709 primaries) to CIE XYZ, IEC 61966-2-1 as tabulated by Lindbloom.
const RGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.4124564, 0.3575761, 0.1804375],
    [0.2126729, 0.7151522, 0.0721750],
    [0.0193339, 0.1191920, 0.9503041],
];
/// The D65 white point in XYZ, (0.95047, 1, 1.08883): taken as the row sums of `RGB_TO_XYZ`
/// (equal to 7 digits), so RGB white is exactly L* = 100 and every gray has a* = b* = 0.
pub const D65_WHITE: [f64; 3] = [
    RGB_TO_XYZ[0][0] + RGB_TO_XYZ[0][1] + RGB_TO_XYZ[0][2],
    RGB_TO_XYZ[1][0] + RGB_TO_XYZ[1][1] + RGB_TO_XYZ[1][2],
    RGB_TO_XYZ[2][0] + RGB_TO_XYZ[2][1] + RGB_TO_XYZ[2][2],
];

/// The figures of one comparison. Undefined figures are NaN (`null` in JSON).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    #[serde(with = "nullable_f64")]
    pub rel_mse: f64,
    #[serde(with = "nullable_f64")]
    pub rmse: f64,
    #[serde(with = "nullable_f64")]
    pub lab_error: f64,
    #[serde(with = "nullable_f64")]
    pub bias: f64,
    #[serde(with = "nullable_f64")]
    pub outliers: f64,
    pub nan_inf: u64,
    /// Mean HDR-FLIP, computed on request (`compare_with_flip`); absent from JSON when `None`,
    /// so files written before it read back.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip: Option<f64>,
}

impl Metrics {
    /// Each figure's mean over `all` (NaN when any is NaN), the NaN/Inf counts summed: the
    /// expected error of one image, estimated from several. `flip` is the mean of theirs when
    /// every one has it, `None` otherwise.
    pub fn mean(all: &[Metrics]) -> Metrics {
        let n = all.len() as f64;
        let mean = |f: fn(&Metrics) -> f64| all.iter().map(f).sum::<f64>() / n;
        Metrics {
            rel_mse: mean(|m| m.rel_mse),
            rmse: mean(|m| m.rmse),
            lab_error: mean(|m| m.lab_error),
            bias: mean(|m| m.bias),
            outliers: mean(|m| m.outliers),
            nan_inf: all.iter().map(|m| m.nan_inf).sum(),
            flip: all
                .iter()
                .map(|m| m.flip)
                .sum::<Option<f64>>()
                .filter(|_| !all.is_empty())
                .map(|sum| sum / n),
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MetricsError {
    #[error("the image under test is {}x{} but the reference is {}x{}", .test.0, .test.1, .reference.0, .reference.1)]
    SizeMismatch {
        test: (u32, u32),
        reference: (u32, u32),
    },
    #[error("image {index} is {}x{} but image 0 is {}x{}", .size.0, .size.1, .first.0, .first.1)]
    SeedSizeMismatch {
        index: usize,
        size: (u32, u32),
        first: (u32, u32),
    },
    #[error("the {which} is {width}x{height} but holds {len} pixels")]
    Malformed {
        which: &'static str,
        width: u32,
        height: u32,
        len: usize,
    },
    #[error("the {which} is empty ({width}x{height})")]
    Empty {
        which: &'static str,
        width: u32,
        height: u32,
    },
    #[error("the reference has {count} NaN or infinite values; a reference must be finite")]
    NonFiniteReference { count: u64 },
    #[error("the image under test has {count} NaN or infinite values; FLIP needs finite images")]
    NonFiniteTest { count: u64 },
    #[error("pixels per degree must be in (0, 10000], got {value}")]
    PixelsPerDegree { value: f32 },
    #[error("variance across seeds needs at least 2 images, got {count}")]
    TooFewImages { count: usize },
}

/// Scores `x` against the reference `r` (docs/DESIGN.md "Error metrics").
pub fn compare(x: &Image, r: &Image) -> Result<Metrics, MetricsError> {
    check(x, "image under test")?;
    check(r, "reference")?;
    if (x.width, x.height) != (r.width, r.height) {
        return Err(MetricsError::SizeMismatch {
            test: (x.width, x.height),
            reference: (r.width, r.height),
        });
    }
    let ref_bad = count_non_finite(r);
    if ref_bad > 0 {
        return Err(MetricsError::NonFiniteReference { count: ref_bad });
    }

    let mut nan_inf = 0u64;
    // Per channel sums over finite values of x.
    let (mut n_values, mut sum_rel, mut sum_sq, mut sum_x, mut sum_r) = (0u64, 0.0, 0.0, 0.0, 0.0);
    // Per pixel sums over pixels whose three channels are finite.
    let (mut n_pixels, mut sum_lab, mut n_outliers) = (0u64, 0.0, 0u64);

    for (px, pr) in x.pixels.iter().zip(&r.pixels) {
        let xs = px.map(f64::from);
        let rs = pr.map(f64::from);
        let mut all_finite = true;
        for c in 0..3 {
            if !xs[c].is_finite() {
                nan_inf += 1;
                all_finite = false;
                continue;
            }
            let d = xs[c] - rs[c];
            sum_sq += d * d;
            sum_rel += d * d / (rs[c] * rs[c] + REL_MSE_EPSILON);
            sum_x += xs[c];
            sum_r += rs[c];
            n_values += 1;
        }
        if all_finite {
            n_pixels += 1;
            sum_lab += delta_e76(tonemapped_lab(*px), tonemapped_lab(*pr));
            if is_outlier(luminance(xs), luminance(rs)) {
                n_outliers += 1;
            }
        }
    }

    let mean = |sum: f64, n: u64| if n == 0 { f64::NAN } else { sum / n as f64 };
    Ok(Metrics {
        rel_mse: mean(sum_rel, n_values),
        rmse: mean(sum_sq, n_values).sqrt(),
        lab_error: mean(sum_lab, n_pixels),
        bias: relative_bias(mean(sum_x, n_values), mean(sum_r, n_values)),
        outliers: mean(n_outliers as f64, n_pixels),
        nan_inf,
        flip: None,
    })
}

/// `compare`, and the mean HDR-FLIP of `x` against `r` at `pixels_per_degree`
/// (`flip::DEFAULT_PIXELS_PER_DEGREE` is FLIP's default) in `flip`, left `None` when `x` has
/// non-finite values (counted in `nan_inf`). Far costlier than `compare` (see the module
/// comment), hence asked for apart.
pub fn compare_with_flip(
    x: &Image,
    r: &Image,
    pixels_per_degree: f32,
) -> Result<Metrics, MetricsError> {
    let mut metrics = compare(x, r)?;
    metrics.flip = match flip::hdr_flip(r, x, pixels_per_degree) {
        Ok(result) => Some(result.mean),
        Err(MetricsError::NonFiniteTest { .. }) => None,
        Err(e) => return Err(e),
    };
    Ok(metrics)
}

/// relMSE against a reference known only through two independent renders `a` and `b` (same
/// method, different seeds), with the reference's own noise taken out: per pixel and channel
/// ((x - r)^2 - (a - b)^2 / 4) / (r^2 + 0.01) with r = (a + b) / 2, averaged. (a - b)^2 / 4 is
/// an unbiased estimate of the variance of r, so the result estimates relMSE against the
/// converged image (up to the normalization's use of r), and can be slightly negative when x
/// is closer to it than the references are to each other. Used where an estimator's error is
/// near the error of any affordable reference.
pub fn rel_mse_against_split_reference(
    x: &Image,
    a: &Image,
    b: &Image,
) -> Result<f64, MetricsError> {
    check(x, "image under test")?;
    for r in [a, b] {
        check(r, "reference")?;
        if (x.width, x.height) != (r.width, r.height) {
            return Err(MetricsError::SizeMismatch {
                test: (x.width, x.height),
                reference: (r.width, r.height),
            });
        }
        let count = count_non_finite(r);
        if count > 0 {
            return Err(MetricsError::NonFiniteReference { count });
        }
    }
    let mut sum = 0.0f64;
    for ((px, pa), pb) in x.pixels.iter().zip(&a.pixels).zip(&b.pixels) {
        for c in 0..3 {
            let (x, a, b) = (px[c] as f64, pa[c] as f64, pb[c] as f64);
            let r = 0.5 * (a + b);
            sum += ((x - r).powi(2) - 0.25 * (a - b).powi(2)) / (r * r + REL_MSE_EPSILON);
        }
    }
    Ok(sum / (3 * x.pixels.len()) as f64)
}

/// Variance across seeds: for each pixel and channel the unbiased sample variance (divided by
/// K - 1) of its K values, one per image, averaged over pixels and channels. NaN when any
/// value is non-finite (check `nan_inf` of [`compare`] first).
pub fn variance_across_seeds(images: &[Image]) -> Result<f64, MetricsError> {
    if images.len() < 2 {
        return Err(MetricsError::TooFewImages {
            count: images.len(),
        });
    }
    let first = &images[0];
    for (index, image) in images.iter().enumerate() {
        check(image, "image")?;
        if (image.width, image.height) != (first.width, first.height) {
            return Err(MetricsError::SeedSizeMismatch {
                index,
                size: (image.width, image.height),
                first: (first.width, first.height),
            });
        }
    }
    let k = images.len() as f64;
    let mut total = 0.0f64;
    for i in 0..first.pixels.len() {
        for c in 0..3 {
            // Two passes per value: the mean first, so the squares do not cancel.
            let mean = images.iter().map(|im| im.pixels[i][c] as f64).sum::<f64>() / k;
            let ss: f64 = images
                .iter()
                .map(|im| (im.pixels[i][c] as f64 - mean).powi(2))
                .sum();
            total += ss / (k - 1.0);
        }
    }
    Ok(total / (3 * first.pixels.len()) as f64)
}

/// Flicker (temporal stability): `frames` are renders of one static view with successive
/// seeds, as an animation would show them. Per pixel and channel the temporal variance
/// (unbiased, divided by F - 1) relative to the reference, var / (r^2 + 0.01) (relMSE's
/// normalization), averaged over pixels and channels, then the square root: a relative
/// temporal standard deviation whose square is the variance part of relMSE, with no bias
/// from the number of frames (a mean of per-pixel square roots would shrink with few
/// frames). Non-finite values make it NaN.
pub fn flicker(frames: &[Image], reference: &Image) -> Result<f64, MetricsError> {
    if frames.len() < 2 {
        return Err(MetricsError::TooFewImages {
            count: frames.len(),
        });
    }
    check(reference, "reference")?;
    for (index, image) in frames.iter().enumerate() {
        check(image, "image")?;
        if (image.width, image.height) != (reference.width, reference.height) {
            return Err(MetricsError::SeedSizeMismatch {
                index,
                size: (image.width, image.height),
                first: (reference.width, reference.height),
            });
        }
    }
    let k = frames.len() as f64;
    let mut total = 0.0f64;
    for (i, r) in reference.pixels.iter().enumerate() {
        for (c, &rc) in r.iter().enumerate() {
            let mean = frames.iter().map(|im| im.pixels[i][c] as f64).sum::<f64>() / k;
            let ss: f64 = frames
                .iter()
                .map(|im| (im.pixels[i][c] as f64 - mean).powi(2))
                .sum();
            let rc = rc as f64;
            total += ss / (k - 1.0) / (rc * rc + REL_MSE_EPSILON);
        }
    }
    Ok((total / (3 * reference.pixels.len()) as f64).sqrt())
}

/// Flicker of a sequence: `frames[f]` an animation's frame f, `references[f]` that frame's
/// reference. The error e = x - r changes from frame to frame by de = dx - dr, the image's
/// change less the reference's own; per pixel and channel de^2 / (2 (m^2 + 0.01)), m the two
/// references' mean, averaged over pixels, channels and frame pairs, then the square root. For
/// frames with independent noise of relative variance v it is sqrt(v), the scale of `flicker`
/// on a still view; an error that stays put (a bias, the same noise every frame) is 0, and so
/// is the reference's own change. Non-finite values make it NaN.
pub fn sequence_flicker(frames: &[Image], references: &[Image]) -> Result<f64, MetricsError> {
    if frames.len() < 2 || references.len() != frames.len() {
        return Err(MetricsError::TooFewImages {
            count: frames.len().min(references.len()),
        });
    }
    let mut score = SequenceScore::default();
    for (x, r) in frames.iter().zip(references) {
        score.push(x.clone(), r.clone())?;
    }
    Ok(score.finish().1.flicker)
}

/// A sequence scored frame by frame against its frames' references: the mean of each frame's
/// metrics, the worst frame's relMSE and which frame (an index into the frames scored), and
/// `sequence_flicker`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceMetrics {
    pub mean: Metrics,
    #[serde(with = "nullable_f64")]
    pub worst_rel_mse: f64,
    pub worst_frame: usize,
    #[serde(with = "nullable_f64")]
    pub flicker: f64,
}

/// Scores a sequence one frame at a time (`push` each frame and its reference in order), so
/// only two frames are in memory: each frame's `compare` (`compare_with_flip` when made by
/// `with_flip`), and the flicker's sums over consecutive pairs.
#[derive(Default)]
pub struct SequenceScore {
    per_frame: Vec<Metrics>,
    flicker_sum: f64,
    flicker_count: usize,
    previous: Option<(Image, Image)>,
    /// Pixels per degree of the per-frame HDR-FLIP; `None`: no FLIP.
    flip: Option<f32>,
}

impl SequenceScore {
    /// The next frame pushed does not follow the last one (a gap in the frames scored): no
    /// flicker is taken between them.
    pub fn gap(&mut self) {
        self.previous = None;
    }

    /// A score that also takes each frame's mean HDR-FLIP at `pixels_per_degree`, so
    /// `SequenceMetrics::mean.flip` is their mean.
    pub fn with_flip(pixels_per_degree: f32) -> SequenceScore {
        SequenceScore {
            flip: Some(pixels_per_degree),
            ..SequenceScore::default()
        }
    }

    pub fn push(&mut self, x: Image, r: Image) -> Result<Metrics, MetricsError> {
        let metrics = match self.flip {
            Some(ppd) => compare_with_flip(&x, &r, ppd)?,
            None => compare(&x, &r)?,
        };
        if let Some((x0, r0)) = &self.previous {
            if (r0.width, r0.height) != (r.width, r.height) {
                return Err(MetricsError::SizeMismatch {
                    test: (r.width, r.height),
                    reference: (r0.width, r0.height),
                });
            }
            for i in 0..r.pixels.len() {
                for c in 0..3 {
                    let (a, b) = (r0.pixels[i][c] as f64, r.pixels[i][c] as f64);
                    let de = (x.pixels[i][c] as f64 - b) - (x0.pixels[i][c] as f64 - a);
                    let m = 0.5 * (a + b);
                    self.flicker_sum += de * de / (2.0 * (m * m + REL_MSE_EPSILON));
                }
            }
            self.flicker_count += 3 * r.pixels.len();
        }
        self.previous = Some((x, r));
        self.per_frame.push(metrics);
        Ok(metrics)
    }

    /// Each frame's metrics and the sequence's; the flicker is NaN for a single frame.
    pub fn finish(self) -> (Vec<Metrics>, SequenceMetrics) {
        let (worst_frame, worst_rel_mse) =
            self.per_frame.iter().map(|m| m.rel_mse).enumerate().fold(
                (0, f64::NAN),
                |(k, w), (i, v)| {
                    if w.is_nan() || v > w {
                        (i, v)
                    } else {
                        (k, w)
                    }
                },
            );
        let flicker = if self.flicker_count > 0 {
            (self.flicker_sum / self.flicker_count as f64).sqrt()
        } else {
            f64::NAN
        };
        let summary = SequenceMetrics {
            mean: Metrics::mean(&self.per_frame),
            worst_rel_mse,
            worst_frame,
            flicker,
        };
        (self.per_frame, summary)
    }
}

/// `frames` against `references`, frame by frame (`compare`), and the sequence's figures.
pub fn compare_sequence(
    frames: &[Image],
    references: &[Image],
) -> Result<(Vec<Metrics>, SequenceMetrics), MetricsError> {
    let mut score = SequenceScore::default();
    for (x, r) in frames.iter().zip(references) {
        score.push(x.clone(), r.clone())?;
    }
    Ok(score.finish())
}

/// Y = 0.2126 R + 0.7152 G + 0.0722 B of linear RGB.
pub fn luminance(rgb: [f64; 3]) -> f64 {
    LUMINANCE[0] * rgb[0] + LUMINANCE[1] * rgb[1] + LUMINANCE[2] * rgb[2]
}

/// Whether a pixel of luminance `y` is a spike against a reference pixel of luminance `y_ref`:
/// y > 10 y_ref + 0.1, strictly.
pub fn is_outlier(y: f64, y_ref: f64) -> bool {
    y > OUTLIER_SCALE * y_ref + OUTLIER_OFFSET
}

/// Linear sRGB in [0, 1] to CIELAB (D65 white).
pub fn linear_to_lab(rgb: [f64; 3]) -> [f64; 3] {
    let xyz = RGB_TO_XYZ.map(|row| row[0] * rgb[0] + row[1] * rgb[1] + row[2] * rgb[2]);
    let f = [0, 1, 2].map(|i| lab_f(xyz[i] / D65_WHITE[i]));
    [
        116.0 * f[1] - 16.0,
        500.0 * (f[0] - f[1]),
        200.0 * (f[1] - f[2]),
    ]
}

/// 8-bit sRGB code values to CIELAB (D65 white).
pub fn srgb8_to_lab(rgb: [u8; 3]) -> [f64; 3] {
    linear_to_lab(rgb.map(|v| tonemap::srgb_eotf(v as f64 / 255.0)))
}

/// Lab of a linear radiance after the PNG's tone map at exposure 0. The sRGB encoding is not
/// quantized to 8 bits (so the metric stays continuous: differences below one code value
/// still count), and encoding then decoding unquantized is the identity, so what is left of
/// the tone map is the clamp.
pub fn tonemapped_lab(rgb: [f32; 3]) -> [f64; 3] {
    linear_to_lab(rgb.map(|v| tonemap::display_linear(v, 0.0)))
}

/// CIE 1976 colour difference: the Euclidean distance in L*a*b*.
pub fn delta_e76(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The CIELAB companding function (CIE 15: linear below (6/29)^3).
fn lab_f(t: f64) -> f64 {
    const DELTA: f64 = 6.0 / 29.0;
    if t > DELTA * DELTA * DELTA {
        t.cbrt()
    } else {
        t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
    }
}

fn relative_bias(mean_x: f64, mean_r: f64) -> f64 {
    let diff = (mean_x - mean_r).abs();
    if diff == 0.0 {
        0.0
    } else if mean_r == 0.0 {
        // A relative bias against a black reference is undefined.
        f64::NAN
    } else {
        diff / mean_r.abs()
    }
}

pub(super) fn check(image: &Image, which: &'static str) -> Result<(), MetricsError> {
    let (width, height) = (image.width, image.height);
    if image.pixels.len() != width as usize * height as usize {
        return Err(MetricsError::Malformed {
            which,
            width,
            height,
            len: image.pixels.len(),
        });
    }
    if image.pixels.is_empty() {
        return Err(MetricsError::Empty {
            which,
            width,
            height,
        });
    }
    Ok(())
}

pub(super) fn count_non_finite(image: &Image) -> u64 {
    image
        .pixels
        .iter()
        .flatten()
        .filter(|v| !v.is_finite())
        .count() as u64
}

/// f64 that is written as `null` when not finite (JSON has no NaN) and read back as NaN.
pub mod nullable_f64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else {
            s.serialize_none()
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}
