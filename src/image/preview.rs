//! Small images for reports: thumbnails (box-filtered down by an integer factor, so each
//! thumbnail pixel is the plain average of the pixels it covers) and error maps (per-pixel
//! relMSE against the reference, docs/DESIGN.md "Error metrics", on a log colour scale).

use super::metrics::REL_MSE_EPSILON;
use super::Image;

/// The smallest integer factor that brings `width` to at most `max_width`.
pub fn factor_for(width: u32, max_width: u32) -> u32 {
    width.div_ceil(max_width.max(1)).max(1)
}

/// `image` averaged over `factor` x `factor` blocks; the last row and column of blocks average
/// what is left. Non-finite values count as black.
pub fn downscale(image: &Image, factor: u32) -> Image {
    let f = factor.max(1);
    let (w, h) = (image.width.div_ceil(f), image.height.div_ceil(f));
    let mut out = Image::new(w, h);
    for ty in 0..h {
        for tx in 0..w {
            let mut sum = [0.0f64; 3];
            let mut n = 0.0;
            for y in ty * f..((ty + 1) * f).min(image.height) {
                for x in tx * f..((tx + 1) * f).min(image.width) {
                    let p = image.get(x, y);
                    for c in 0..3 {
                        if p[c].is_finite() {
                            sum[c] += p[c] as f64;
                        }
                    }
                    n += 1.0;
                }
            }
            out.pixels[(ty * w + tx) as usize] = sum.map(|s| (s / n) as f32);
        }
    }
    out
}

/// The error map's scale: per-pixel relMSE from `ERROR_MAP_MIN` (black) to `ERROR_MAP_MAX`
/// (white), log10 in between.
pub const ERROR_MAP_MIN: f64 = 1e-4;
pub const ERROR_MAP_MAX: f64 = 10.0;

/// Per-pixel relMSE of `x` against `r` (mean over channels of (x - r)^2 / (r^2 + 0.01)),
/// block-averaged by `factor`, as 8-bit sRGB on a black-red-yellow-white ramp over
/// [ERROR_MAP_MIN, ERROR_MAP_MAX] (log scale). A non-finite pixel is magenta.
pub fn error_map_rgb8(x: &Image, r: &Image, factor: u32) -> (u32, u32, Vec<u8>) {
    let f = factor.max(1);
    let (w, h) = (x.width.div_ceil(f), x.height.div_ceil(f));
    let mut data = Vec::with_capacity(3 * (w * h) as usize);
    for ty in 0..h {
        for tx in 0..w {
            let (mut sum, mut n, mut bad) = (0.0f64, 0.0f64, false);
            for y in ty * f..((ty + 1) * f).min(x.height) {
                for px in tx * f..((tx + 1) * f).min(x.width) {
                    let (a, b) = (x.get(px, y), r.get(px, y));
                    for c in 0..3 {
                        let (a, b) = (a[c] as f64, b[c] as f64);
                        if !a.is_finite() {
                            bad = true;
                        } else {
                            sum += (a - b) * (a - b) / (b * b + REL_MSE_EPSILON) / 3.0;
                        }
                    }
                    n += 1.0;
                }
            }
            data.extend_from_slice(&if bad { [255, 0, 255] } else { heat(sum / n) });
        }
    }
    (w, h, data)
}

/// The ramp: black, dark red, red, orange, yellow, white at equal steps of log10(e).
pub(crate) fn heat(e: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 6] = [
        [0.0, 0.0, 0.0],
        [0.35, 0.0, 0.05],
        [0.8, 0.1, 0.05],
        [1.0, 0.5, 0.0],
        [1.0, 0.9, 0.1],
        [1.0, 1.0, 1.0],
    ];
    let (lo, hi) = (ERROR_MAP_MIN.log10(), ERROR_MAP_MAX.log10());
    let t = if e > 0.0 {
        ((e.log10() - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (STOPS.len() - 1) as f64;
    let i = (s.floor() as usize).min(STOPS.len() - 2);
    let u = s - i as f64;
    [0, 1, 2].map(|c| {
        let v = STOPS[i][c] + u * (STOPS[i + 1][c] - STOPS[i][c]);
        (v * 255.0).round() as u8
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downscale_averages_blocks_and_keeps_the_mean_of_even_sizes() {
        let mut im = Image::new(4, 2);
        for (i, p) in im.pixels.iter_mut().enumerate() {
            *p = [i as f32; 3];
        }
        let small = downscale(&im, 2);
        assert_eq!((small.width, small.height), (2, 1));
        assert_eq!(small.pixels, vec![[2.5; 3], [4.5; 3]]);
        assert_eq!(small.mean(), im.mean());
        assert_eq!(factor_for(1024, 256), 4);
        assert_eq!(factor_for(64, 256), 1);
        assert_eq!(factor_for(300, 256), 2);
    }

    #[test]
    fn error_map_is_black_when_equal_and_white_far_off() {
        let r = Image {
            width: 2,
            height: 1,
            pixels: vec![[1.0; 3], [1.0; 3]],
        };
        let x = Image {
            width: 2,
            height: 1,
            pixels: vec![[1.0; 3], [100.0; 3]],
        };
        let (w, h, data) = error_map_rgb8(&x, &r, 1);
        assert_eq!((w, h), (2, 1));
        assert_eq!(&data[0..3], &[0, 0, 0]);
        assert_eq!(&data[3..6], &[255, 255, 255]);
        let nan = Image {
            width: 1,
            height: 1,
            pixels: vec![[f32::NAN, 0.0, 0.0]],
        };
        let one = Image {
            width: 1,
            height: 1,
            pixels: vec![[0.0; 3]],
        };
        assert_eq!(error_map_rgb8(&nan, &one, 1).2, vec![255, 0, 255]);
    }
}
