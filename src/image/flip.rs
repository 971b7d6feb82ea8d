// HDR-FLIP, ported from NVIDIA's reference implementation (src/cpp/FLIP.h of
// github.com/NVlabs/flip as shipped in flip-evaluator 1.7), which carries this notice:
//
// Copyright (c) 2020-2025, NVIDIA CORPORATION & AFFILIATES. All rights reserved.
//
// Redistribution and use in source and binary forms, with or without
// modification, are permitted provided that the following conditions are met:
//
// 1. Redistributions of source code must retain the above copyright notice, this
// list of conditions and the following disclaimer.
//
// 2. Redistributions in binary form must reproduce the above copyright notice,
// this list of conditions and the following disclaimer in the documentation
// and/or other materials provided with the distribution.
//
// 3. Neither the name of the copyright holder nor the names of its
// contributors may be used to endorse or promote products derived from
// this software without specific prior written permission.
//
// THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS"
// AND ANY EXPRESS OR IMPLIED WARRANTIES, INCLUDING, BUT NOT LIMITED TO, THE
// IMPLIED WARRANTIES OF MERCHANTABILITY AND FITNESS FOR A PARTICULAR PURPOSE ARE
// DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT HOLDER OR CONTRIBUTORS BE LIABLE
// FOR ANY DIRECT, INDIRECT, INCIDENTAL, SPECIAL, EXEMPLARY, OR CONSEQUENTIAL
// DAMAGES (INCLUDING, BUT NOT LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR
// SERVICES; LOSS OF USE, DATA, OR PROFITS; OR BUSINESS INTERRUPTION) HOWEVER
// CAUSED AND ON ANY THEORY OF LIABILITY, WHETHER IN CONTRACT, STRICT LIABILITY,
// OR TORT (INCLUDING NEGLIGENCE OR OTHERWISE) ARISING IN ANY WAY OUT OF THE USE
// OF THIS SOFTWARE, EVEN IF ADVISED OF THE POSSIBILITY OF SUCH DAMAGE.
//
// SPDX-License-Identifier: BSD-3-Clause (this file's port of FLIP.h); the rest of irad is
// MIT OR Apache-2.0.

//! HDR-FLIP (Andersson, Nilsson, Shirley and Akenine-Moller, "Visualizing Errors in Rendered
//! High Dynamic Range Images", Eurographics 2021), docs/DESIGN.md "Error metrics": a per-pixel
//! perceptual error in [0, 1] between a linear HDR reference and a test image, and its mean.
//!
//! Both images are exposed at `n` exposures from `start` to `stop` (in stops), tone mapped by
//! ACES (FLIP's fit, pre-exposure cancelled) and clamped to [0, 1]; LDR-FLIP scores each
//! pair, and a pixel's HDR-FLIP is its largest LDR-FLIP over the exposures. From the
//! reference's luminances Y (Rec. 709 weights), with x the ACES input that maps to 0.85:
//! start = log2(x / max Y), stop = log2(x / max(median Y, f32::EPSILON)),
//! n = max(2, ceil(stop - start)). LDR-FLIP: both images to YCxCz (a linearized CIELAB, D65);
//! the colour pipeline filters each channel with its contrast sensitivity function (Gaussians
//! in visual degrees at `pixels_per_degree`, separable, edges clamped), back to linear RGB,
//! clamped, to L*a*b*, Hunt-adjusted (a, b scaled by L / 100), and takes the HyAB distance
//! (|dL| + Euclidean in a, b) to the power 0.7, remapped to [0, 1] (0.95 at 0.4 of the largest
//! distance, green to blue); the feature pipeline filters the normalized achromatic channel
//! with the first and second derivatives of a Gaussian (sigma 0.041 degrees: edges and points)
//! and takes the larger difference of their magnitudes, over sqrt(2), to the power 0.5 (fd);
//! the pixel's error is the colour error to the power 1 - fd.
//!
//! Why a port and not a crate: the Rust crate `nv-flip` (0.1.2, July 2023, bindings through
//! `nv-flip-sys`) compiles NVIDIA's C++ with `cc` and binds only LDR-FLIP on 8-bit sRGB
//! images, from FLIP 1.2's sources (before the single-header rewrite, the 1.4 median change
//! and the 1.7 median fix). HDR-FLIP on top of it would tone map, sRGB-encode and quantize
//! every exposure to 8 bits, so it could not reproduce flip-evaluator's figures (quantization
//! moves dark pixels' errors by far more than 1e-4), and it would put a C++ compiler and a
//! C++ compile (tens of seconds on the 2-core CI machine, in every clean build) in the build
//! of every user, for a dependency that lags the reference. The port is ~400 lines of safe
//! Rust with no dependency, compiled with the rest of irad; it follows FLIP.h operation by
//! operation in f32 (the same constants, filter construction, loop and rounding order), so its
//! error maps are flip-evaluator 1.7's bit for bit on x86-64 glibc and its means within 4e-7
//! (the reference sums its map in f32; tests/flip.rs against what the Python package computed,
//! tests/data/flip/make.py). It is deterministic: single-threaded, no reassociation, only IEEE
//! operations and the C library's expf, powf and log2 (the functions the reference calls).
//! BSD-3-Clause is compatible with irad's MIT OR Apache-2.0; its notice heads this file.
//! Maintenance: FLIP.h's HDR path changed twice since HDR-FLIP's release (1.4: the median by
//! selection; 1.7: the median at least f32::EPSILON); a change there is a diff to follow here,
//! checked by regenerating the test's data. Cost: ~7 ms per exposure for 128x96 in a release
//! build, ~100 ms in a debug build (docs/DESIGN.md "Error metrics").
//!
//! Where the reference is undefined this port defines the result: non-finite pixels in either
//! image and different sizes are errors (the reference's figures would be NaN or garbage); a
//! reference whose largest luminance is below f32::EPSILON (black) takes f32::EPSILON as its
//! largest luminance, as 1.7 does for the median (the reference exits, start > stop);
//! exposed values are clamped to [-1e4, 1e4] before the tone map, which changes no result (ACES
//! is above 1 beyond 12.1 and below -0.4, and the output is clamped to [0, 1]) but keeps c^2
//! finite (the reference's NaN for c^2 past f32's range reads as black).

use super::metrics::{check, count_non_finite, MetricsError};
use super::Image;

/// FLIP.h's pi, 3.14159265358979f, is this f32.
const PI: f32 = std::f32::consts::PI;

/// FLIP's default viewing condition: 0.7 m from a 0.7 m wide monitor of 3840 pixels, about 67.02
/// pixels per degree of visual angle (FLIP.h `calculatePPD(0.7, 3840, 0.7)`, in f32).
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = 0.7 * (3840.0 / 0.7) * (PI / 180.0);

/// The largest pixels per degree accepted: far past any display (a 0.7 m wide 8K monitor at
/// 10 m is ~2000); it bounds the filters' widths (about 0.14 ppd pixels each side).
pub const MAX_PIXELS_PER_DEGREE: f32 = 10_000.0;

// FLIP's constants (the paper's q_c, p_c, p_t, w, q_f).
const GQC: f32 = 0.7;
const GPC: f32 = 0.4;
const GPT: f32 = 0.95;
const GW: f32 = 0.082;
const GQF: f32 = 0.5;

/// ACES as a rational function, (a c^2 + b c + c0) / (d c^2 + e c + f), FLIP's coefficients
/// with its pre-exposure of 0.6 cancelled.
const ACES: [f32; 6] = [
    0.6 * 0.6 * 2.51,
    0.6 * 0.03,
    0.0,
    0.6 * 0.6 * 2.43,
    0.6 * 0.59,
    0.14,
];

// FLIP.h's literals as written there (more digits than f32 holds; each rounds to the f32 the
// C++ compiler makes of it).
/// D65 as FLIP writes it, and its inverse.
#[allow(clippy::excessive_precision)]
const ILLUMINANT: [f32; 3] = [0.950_428_545, 1.0, 1.088_900_371];
#[allow(clippy::excessive_precision)]
const INV_ILLUMINANT: [f32; 3] = [1.052_156_925, 1.0, 0.918_357_670];

/// Linear sRGB to XYZ (FLIP.h: rational entries, each rounded to f32 then divided in f32).
const RGB_TO_XYZ: [[f32; 3]; 3] = [
    [
        10_135_552.0 / 24_577_794.0,
        8_788_810.0 / 24_577_794.0,
        4_435_075.0 / 24_577_794.0,
    ],
    [
        2_613_072.0 / 12_288_897.0,
        8_788_810.0 / 12_288_897.0,
        887_015.0 / 12_288_897.0,
    ],
    [
        1_425_312.0 / 73_733_382.0,
        8_788_810.0 / 73_733_382.0,
        70_074_185.0 / 73_733_382.0,
    ],
];
#[allow(clippy::excessive_precision)]
const XYZ_TO_RGB: [[f32; 3]; 3] = [
    [3.241_003_275, -1.537_398_934, -0.498_615_861],
    [-0.969_224_334, 1.875_930_071, 0.041_554_224],
    [0.055_639_423, -0.204_011_202, 1.057_148_933],
];

/// The contrast sensitivity functions as sums of Gaussians a sqrt(pi / b) exp(-pi^2 x^2 / b),
/// x in degrees: achromatic, red-green, and blue-yellow (two terms).
const CSF_A1: [f32; 3] = [1.0, 1.0, 34.1];
const CSF_B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const CSF_A2_Z: f32 = 13.5;
const CSF_B2: [f32; 3] = [1.0e-5, 1.0e-5, 0.025];

type Rgb = [f32; 3];

/// HDR-FLIP of one image against its reference.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipResult {
    /// The mean of `error_map` (summed in f64).
    pub mean: f64,
    pub width: u32,
    pub height: u32,
    /// Per pixel, row 0 at the top as in `Image`: the largest LDR-FLIP over the exposures, in
    /// [0, 1].
    pub error_map: Vec<f32>,
    /// The exposures used, in stops: `exposures` evenly spaced from start to stop.
    pub start_exposure: f32,
    pub stop_exposure: f32,
    pub exposures: u32,
}

/// HDR-FLIP of `test` against `reference`, both linear RGB, at `pixels_per_degree`
/// ([`DEFAULT_PIXELS_PER_DEGREE`] is FLIP's default). Errors: different sizes, an empty or
/// malformed image, a NaN or infinite value in either image, pixels per degree not in
/// (0, [`MAX_PIXELS_PER_DEGREE`]].
pub fn hdr_flip(
    reference: &Image,
    test: &Image,
    pixels_per_degree: f32,
) -> Result<FlipResult, MetricsError> {
    check(reference, "reference")?;
    check(test, "image under test")?;
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(MetricsError::SizeMismatch {
            test: (test.width, test.height),
            reference: (reference.width, reference.height),
        });
    }
    let count = count_non_finite(reference);
    if count > 0 {
        return Err(MetricsError::NonFiniteReference { count });
    }
    let count = count_non_finite(test);
    if count > 0 {
        return Err(MetricsError::NonFiniteTest { count });
    }
    let ppd_ok = pixels_per_degree > 0.0 && pixels_per_degree <= MAX_PIXELS_PER_DEGREE;
    if !ppd_ok {
        return Err(MetricsError::PixelsPerDegree {
            value: pixels_per_degree,
        });
    }

    let (w, h) = (reference.width as usize, reference.height as usize);
    let (start, stop) = exposure_range(&reference.pixels);
    let exposures = (stop - start).ceil().max(2.0) as u32;
    let step = (stop - start) / (exposures - 1) as f32;

    let filters = Filters::new(pixels_per_degree);
    let mut scratch = Scratch::new(w * h);
    let mut error_map = vec![0.0f32; w * h];
    let mut ldr_error = vec![0.0f32; w * h];
    for i in 0..exposures {
        let exposure = start + i as f32 * step;
        let m = 2.0f32.powf(exposure);
        for (dst, src) in scratch.reference.iter_mut().zip(&reference.pixels) {
            *dst = linear_to_ycxcz(src.map(|c| tone_map(c * m)));
        }
        for (dst, src) in scratch.test.iter_mut().zip(&test.pixels) {
            *dst = linear_to_ycxcz(src.map(|c| tone_map(c * m)));
        }
        ldr_flip(w, h, &filters, &mut scratch, &mut ldr_error);
        for (e, &l) in error_map.iter_mut().zip(&ldr_error) {
            if l > *e {
                *e = l;
            }
        }
    }

    let mean = error_map.iter().map(|&e| e as f64).sum::<f64>() / (w * h) as f64;
    Ok(FlipResult {
        mean,
        width: reference.width,
        height: reference.height,
        error_map,
        start_exposure: start,
        stop_exposure: stop,
        exposures,
    })
}

/// FLIP.h `computeExposures` for ACES (1.7: the median at least f32::EPSILON; here the
/// maximum too, where the reference would stop with start > stop).
fn exposure_range(pixels: &[Rgb]) -> (f32, f32) {
    // The ACES input that maps to 0.85: the larger root of (a - t d) x^2 + (b - t e) x + (c - t f).
    let t = 0.85f32;
    let a = ACES[0] - t * ACES[3];
    let b = ACES[1] - t * ACES[4];
    let c = ACES[2] - t * ACES[5];
    let d1 = -0.5 * (b / a);
    let x_max = d1 + (d1 * d1 - c / a).sqrt();

    let mut luminances: Vec<f32> = pixels
        .iter()
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .collect();
    let y_max = luminances.iter().fold(-1e30f32, |m, &y| m.max(y));
    let mid = luminances.len() / 2;
    let (_, &mut median, _) = luminances.select_nth_unstable_by(mid, f32::total_cmp);
    let y_max = y_max.max(f32::EPSILON);
    let y_median = median.max(f32::EPSILON);
    // FLIP.h calls log2 unqualified on a float: the C library's double log2, rounded to f32.
    let log2 = |v: f32| (v as f64).log2() as f32;
    (log2(x_max / y_max), log2(x_max / y_median))
}

/// ACES (FLIP's fit), clamped to [0, 1]; the input clamped to [-1e4, 1e4] first, which changes
/// nothing after the output clamp and keeps c^2 finite.
fn tone_map(c: f32) -> f32 {
    let c = c.clamp(-1e4, 1e4);
    let v = (c * c * ACES[0] + c * ACES[1] + ACES[2]) / (c * c * ACES[3] + c * ACES[4] + ACES[5]);
    v.clamp(0.0, 1.0)
}

fn mat(m: &[[f32; 3]; 3], v: Rgb) -> Rgb {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

fn linear_to_ycxcz(rgb: Rgb) -> Rgb {
    let xyz = mat(&RGB_TO_XYZ, rgb);
    let [x, y, z] = [0, 1, 2].map(|i| xyz[i] * INV_ILLUMINANT[i]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_linear(ycxcz: Rgb) -> Rgb {
    let y = (ycxcz[0] + 16.0) / 116.0;
    let cx = ycxcz[1] / 500.0;
    let cz = ycxcz[2] / 200.0;
    let xyz = [y + cx, y, y - cz];
    mat(&XYZ_TO_RGB, [0, 1, 2].map(|i| xyz[i] * ILLUMINANT[i]))
}

fn linear_to_lab(rgb: Rgb) -> Rgb {
    const DELTA: f32 = 6.0 / 29.0;
    const DELTA_SQUARE: f32 = DELTA * DELTA;
    const DELTA_CUBE: f32 = DELTA * DELTA_SQUARE;
    const FACTOR: f32 = 1.0 / (3.0 * DELTA_SQUARE);
    const TERM: f32 = 4.0 / 29.0;
    let xyz = mat(&RGB_TO_XYZ, rgb);
    let [x, y, z] = [0, 1, 2].map(|i| {
        let v = xyz[i] * INV_ILLUMINANT[i];
        if v > DELTA_CUBE {
            v.powf(1.0 / 3.0)
        } else {
            FACTOR * v + TERM
        }
    });
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// L*a*b* with a and b scaled by 0.01 L (the Hunt effect).
fn hunt(lab: Rgb) -> Rgb {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

fn hyab(a: Rgb, b: Rgb) -> f32 {
    (a[0] - b[0]).abs() + ((a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2])).sqrt()
}

/// The separable filters of one pixels per degree, and the colour error's normalization.
struct Filters {
    /// Per tap: the achromatic and red-green CSF weights.
    csf_ycx: Vec<[f32; 2]>,
    /// Per tap: the two separated blue-yellow CSF terms.
    csf_cz: Vec<[f32; 2]>,
    /// Per tap: Gaussian, its first and its second derivative.
    feature: Vec<[f32; 3]>,
    cmax: f32,
    pccmax: f32,
}

impl Filters {
    fn new(ppd: f32) -> Filters {
        let pi_sq = PI * PI;
        let gaussian = |x2: f32, a: f32, b: f32| a * (PI / b).sqrt() * (-pi_sq * x2 / b).exp();
        // A Gaussian's square-root factor, so a 2D sum of Gaussians separates (FLIP's
        // misc/separatedConvolutions.pdf).
        let gaussian_sqrt =
            |x2: f32, a: f32, b: f32| (a * (PI / b).sqrt()).sqrt() * (-pi_sq * x2 / b).exp();

        let max_b = CSF_B1.iter().chain(&CSF_B2).fold(0.0f32, |m, &b| m.max(b));
        let radius = (3.0 * (max_b / (2.0 * pi_sq)).sqrt() * ppd).ceil() as i64;
        let dx = 1.0 / ppd;
        let mut csf_ycx = Vec::new();
        let mut csf_cz = Vec::new();
        let (mut sum_ycx, mut sum_cz) = ([0.0f32; 2], [0.0f32; 2]);
        for i in -radius..=radius {
            let x = i as f32 * dx;
            let x2 = x * x;
            let ycx = [
                gaussian(x2, CSF_A1[0], CSF_B1[0]),
                gaussian(x2, CSF_A1[1], CSF_B1[1]),
            ];
            let cz = [
                gaussian_sqrt(x2, CSF_A1[2], CSF_B1[2]),
                gaussian_sqrt(x2, CSF_A2_Z, CSF_B2[2]),
            ];
            for k in 0..2 {
                sum_ycx[k] += ycx[k];
                sum_cz[k] += cz[k];
            }
            csf_ycx.push(ycx);
            csf_cz.push(cz);
        }
        let norm_ycx = [1.0 / sum_ycx[0], 1.0 / sum_ycx[1]];
        let norm_cz = 1.0 / (sum_cz[0] * sum_cz[0] + sum_cz[1] * sum_cz[1]).sqrt();
        for v in &mut csf_ycx {
            *v = [v[0] * norm_ycx[0], v[1] * norm_ycx[1]];
        }
        for v in &mut csf_cz {
            *v = [v[0] * norm_cz, v[1] * norm_cz];
        }

        let sd = 0.5 * GW * ppd;
        let radius = (3.0 * sd).ceil() as i64;
        let mut feature = Vec::new();
        let (mut g_sum, mut dg_pos, mut dg_neg, mut ddg_pos, mut ddg_neg) =
            (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for i in -radius..=radius {
            let x = i as f32;
            let g = (-(x * x) / (2.0 * sd * sd)).exp();
            g_sum += g;
            let dg = -x * g;
            if dg > 0.0 {
                dg_pos += dg;
            } else {
                dg_neg -= dg;
            }
            let ddg = (x * x / (sd * sd) - 1.0) * g;
            if ddg > 0.0 {
                ddg_pos += ddg;
            } else {
                ddg_neg -= ddg;
            }
            feature.push([g, dg, ddg]);
        }
        // The Gaussian sums to 1; each derivative's positive weights to 1, negative to -1.
        for v in &mut feature {
            *v = [
                v[0] / g_sum,
                v[1] / if v[1] > 0.0 { dg_pos } else { dg_neg },
                v[2] / if v[2] > 0.0 { ddg_pos } else { ddg_neg },
            ];
        }

        // The largest colour distance: green to blue.
        let green = hunt(linear_to_lab([0.0, 1.0, 0.0]));
        let blue = hunt(linear_to_lab([0.0, 0.0, 1.0]));
        let cmax = hyab(green, blue).powf(GQC);
        Filters {
            csf_ycx,
            csf_cz,
            feature,
            cmax,
            pccmax: GPC * cmax,
        }
    }
}

/// The exposed images (YCxCz) and the filters' intermediate rows, kept across exposures.
struct Scratch {
    reference: Vec<Rgb>,
    test: Vec<Rgb>,
    /// After the horizontal pass: per image, YCx (2 values) and Cz (2 terms).
    ycx: [Vec<[f32; 2]>; 2],
    cz: [Vec<[f32; 2]>; 2],
    /// After the horizontal feature pass: per image, dx, ddx, Gaussian.
    features: [Vec<Rgb>; 2],
}

impl Scratch {
    fn new(n: usize) -> Scratch {
        Scratch {
            reference: vec![[0.0; 3]; n],
            test: vec![[0.0; 3]; n],
            ycx: [vec![[0.0; 2]; n], vec![[0.0; 2]; n]],
            cz: [vec![[0.0; 2]; n], vec![[0.0; 2]; n]],
            features: [vec![[0.0; 3]; n], vec![[0.0; 3]; n]],
        }
    }
}

/// LDR-FLIP of `scratch.reference` against `scratch.test` (YCxCz of tone-mapped images) into
/// `out`: FLIP.h `computeColorDifference` then `computeFeatureDifferenceAndFinalError`.
fn ldr_flip(w: usize, h: usize, f: &Filters, s: &mut Scratch, out: &mut [f32]) {
    let clamp = |i: usize, d: i64, n: usize| (i as i64 + d).clamp(0, n as i64 - 1) as usize;

    // Colour: CSF filtering, horizontal then vertical.
    let r = (f.csf_ycx.len() / 2) as i64;
    for (k, image) in [&s.reference, &s.test].into_iter().enumerate() {
        for y in 0..h {
            for x in 0..w {
                let (mut ycx, mut cz) = ([0.0f32; 2], [0.0f32; 2]);
                for d in -r..=r {
                    let p = image[y * w + clamp(x, d, w)];
                    let wy = f.csf_ycx[(d + r) as usize];
                    let wz = f.csf_cz[(d + r) as usize];
                    ycx[0] += wy[0] * p[0];
                    ycx[1] += wy[1] * p[1];
                    cz[0] += wz[0] * p[2];
                    cz[1] += wz[1] * p[2];
                }
                s.ycx[k][y * w + x] = ycx;
                s.cz[k][y * w + x] = cz;
            }
        }
    }
    for y in 0..h {
        for x in 0..w {
            let filtered = [0, 1].map(|k| {
                let (mut ycx, mut cz) = ([0.0f32; 2], [0.0f32; 2]);
                for d in -r..=r {
                    let i = clamp(y, d, h) * w + x;
                    let wy = f.csf_ycx[(d + r) as usize];
                    let wz = f.csf_cz[(d + r) as usize];
                    ycx[0] += wy[0] * s.ycx[k][i][0];
                    ycx[1] += wy[1] * s.ycx[k][i][1];
                    cz[0] += wz[0] * s.cz[k][i][0];
                    cz[1] += wz[1] * s.cz[k][i][1];
                }
                let rgb =
                    ycxcz_to_linear([ycx[0], ycx[1], cz[0] + cz[1]]).map(|c| c.clamp(0.0, 1.0));
                hunt(linear_to_lab(rgb))
            });
            let mut e = hyab(filtered[0], filtered[1]).powf(GQC);
            // Remapped to [0, 1]: [0, pccmax) to [0, gpt), the rest to [gpt, 1].
            e = if e < f.pccmax {
                e * (GPT / f.pccmax)
            } else {
                GPT + ((e - f.pccmax) / (f.cmax - f.pccmax)) * (1.0 - GPT)
            };
            out[y * w + x] = e;
        }
    }

    // Features: the achromatic channel normalized to [0, 1], derivative filters.
    let r = (f.feature.len() / 2) as i64;
    for (k, image) in [&s.reference, &s.test].into_iter().enumerate() {
        for y in 0..h {
            for x in 0..w {
                let (mut dx, mut ddx, mut g) = (0.0f32, 0.0f32, 0.0f32);
                for d in -r..=r {
                    let v = image[y * w + clamp(x, d, w)][0] * (1.0 / 116.0) + 16.0 / 116.0;
                    let wt = f.feature[(d + r) as usize];
                    dx += wt[1] * v;
                    ddx += wt[2] * v;
                    g += wt[0] * v;
                }
                s.features[k][y * w + x] = [dx, ddx, g];
            }
        }
    }
    let normalization = 1.0 / 2.0f32.sqrt();
    for y in 0..h {
        for x in 0..w {
            let [edge, point] = {
                let [e0, p0, e1, p1] = {
                    let mut v = [0.0f32; 4];
                    for k in 0..2 {
                        let (mut dx, mut ddx, mut dy, mut ddy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
                        for d in -r..=r {
                            let i = s.features[k][clamp(y, d, h) * w + x];
                            let wt = f.feature[(d + r) as usize];
                            dx += wt[0] * i[0];
                            ddx += wt[0] * i[1];
                            dy += wt[1] * i[2];
                            ddy += wt[2] * i[2];
                        }
                        v[2 * k] = (dx * dx + dy * dy).sqrt();
                        v[2 * k + 1] = (ddx * ddx + ddy * ddy).sqrt();
                    }
                    v
                };
                [(e0 - e1).abs(), (p0 - p1).abs()]
            };
            let larger = if edge > point { edge } else { point };
            let feature = (normalization * larger).powf(GQF);
            let i = y * w + x;
            out[i] = out[i].powf(1.0 - feature);
        }
    }
}
