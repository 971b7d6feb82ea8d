//! Full-size error maps with their colour bars, for `irad compare`: the relative squared error
//! (preview.rs's ramp and scale, as the reports' thumbnails), the signed relative error on a
//! diverging ramp, and HDR-FLIP's per-pixel map. Each is an 8-bit RGB image with a bar under
//! it: the ramp, a tick at each labelled value and its label, drawn with a 3x5 pixel font so
//! that no font file is needed.

use super::flip::FlipResult;
use super::metrics::{luminance, REL_MSE_EPSILON};
use super::preview::{error_map_rgb8, heat, ERROR_MAP_MAX, ERROR_MAP_MIN};
use super::Image;

/// An 8-bit RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb8 {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

/// The signed map's range: (Y(x) - Y(r)) / sqrt(Y(r)^2 + 0.01) from -SIGNED_RANGE (blue) through
/// 0 (black) to +SIGNED_RANGE (red), linear and clamped.
pub const SIGNED_RANGE: f64 = 1.0;

/// Per-pixel relMSE on preview.rs's log ramp, with its bar (1e-4 to 10).
pub fn rel_mse_map(x: &Image, r: &Image) -> Rgb8 {
    let (width, height, data) = error_map_rgb8(x, r, 1);
    let lo = ERROR_MAP_MIN.log10();
    let span = ERROR_MAP_MAX.log10() - lo;
    let labels = ["1e-4", "1e-3", "0.01", "0.1", "1", "10"];
    let ticks: Vec<(f64, &str)> = labels
        .iter()
        .enumerate()
        .map(|(i, l)| ((i as f64) / span, *l))
        .collect();
    with_bar(
        Rgb8 {
            width,
            height,
            data,
        },
        &|t| heat(10f64.powf(lo + t * span)),
        &ticks,
    )
}

/// The signed relative error of luminance, (Y(x) - Y(r)) / sqrt(Y(r)^2 + 0.01): blue where x is
/// darker than the reference, red where brighter, black where equal; magenta where x is not
/// finite. With its bar (-1 to +1).
pub fn signed_map(x: &Image, r: &Image) -> Rgb8 {
    let mut data = Vec::with_capacity(3 * x.pixels.len());
    for (px, pr) in x.pixels.iter().zip(&r.pixels) {
        if px.iter().any(|v| !v.is_finite()) {
            data.extend_from_slice(&[255, 0, 255]);
            continue;
        }
        let (y, y_ref) = (luminance(px.map(f64::from)), luminance(pr.map(f64::from)));
        let s = (y - y_ref) / (y_ref * y_ref + REL_MSE_EPSILON).sqrt();
        data.extend_from_slice(&diverging(0.5 + 0.5 * (s / SIGNED_RANGE).clamp(-1.0, 1.0)));
    }
    with_bar(
        Rgb8 {
            width: x.width,
            height: x.height,
            data,
        },
        &diverging,
        &[
            (0.0, "-1"),
            (0.25, "-.5"),
            (0.5, "0"),
            (0.75, ".5"),
            (1.0, "1"),
        ],
    )
}

/// HDR-FLIP's per-pixel error in [0, 1] on the heat ramp's colours (black 0, white 1), with its
/// bar.
pub fn flip_map(flip: &FlipResult) -> Rgb8 {
    let ramp = |t: f64| heat(10f64.powf(ERROR_MAP_MIN.log10() + t * 5.0));
    let mut data = Vec::with_capacity(3 * flip.error_map.len());
    for &e in &flip.error_map {
        data.extend_from_slice(&ramp(f64::from(e).clamp(0.0, 1.0)));
    }
    with_bar(
        Rgb8 {
            width: flip.width,
            height: flip.height,
            data,
        },
        &ramp,
        &[(0.0, "0"), (0.5, ".5"), (1.0, "1")],
    )
}

/// The diverging ramp at t in [0, 1]: blue, black at 0.5, red.
fn diverging(t: f64) -> [u8; 3] {
    let s = 2.0 * t - 1.0;
    let c = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    if s < 0.0 {
        let a = -s;
        [c(0.25 * a), c(0.55 * a), c(a)]
    } else {
        [c(s), c(0.2 * s), c(0.1 * s)]
    }
}

/// The least canvas width, so that a small image's bar still has room for its labels.
const MIN_WIDTH: u32 = 192;

/// `map` above a bar of `ramp` over t in [0, 1], with a tick and a label at each (t, label).
/// The canvas is at least MIN_WIDTH wide (the map at its left, grey beside it).
fn with_bar(map: Rgb8, ramp: &dyn Fn(f64) -> [u8; 3], ticks: &[(f64, &str)]) -> Rgb8 {
    let width = map.width.max(MIN_WIDTH);
    // The labels' scale: 1 up to 383 pixels wide, 2 to 767, and so on.
    let scale = (width / 384 + 1).min(4);
    let (gap, bar, tick, text) = (4 * scale, 8 * scale, 3 * scale, 5 * scale);
    let height = map.height + gap + bar + tick + 2 * scale + text + gap;
    let mut out = Rgb8 {
        width,
        height,
        data: vec![48; 3 * (width * height) as usize],
    };
    for y in 0..map.height {
        let from = 3 * (y * map.width) as usize;
        let to = 3 * (y * width) as usize;
        out.data[to..to + 3 * map.width as usize]
            .copy_from_slice(&map.data[from..from + 3 * map.width as usize]);
    }
    // The bar spans the canvas less a margin that leaves room for the end labels.
    let margin = 8 * scale;
    let (x0, x1) = (margin, width - margin);
    let top = map.height + gap;
    for x in x0..x1 {
        let rgb = ramp((x - x0) as f64 / (x1 - x0 - 1).max(1) as f64);
        for y in top..top + bar {
            out.put(x, y, rgb);
        }
    }
    for &(t, label) in ticks {
        let x = x0 + (t.clamp(0.0, 1.0) * (x1 - x0 - 1) as f64).round() as u32;
        for y in top + bar..top + bar + tick {
            for dx in 0..scale {
                out.put((x + dx).min(width - 1), y, [220, 220, 220]);
            }
        }
        let w = label_width(label) * scale;
        let left = x.saturating_sub(w / 2).min(width.saturating_sub(w));
        draw_label(&mut out, left, top + bar + tick + 2 * scale, label, scale);
    }
    out
}

impl Rgb8 {
    fn put(&mut self, x: u32, y: u32, rgb: [u8; 3]) {
        if x < self.width && y < self.height {
            let i = 3 * (y * self.width + x) as usize;
            self.data[i..i + 3].copy_from_slice(&rgb);
        }
    }
}

/// 3x5 glyphs, a row of 3 bits each (the high bit the left column).
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b010, 0b010, 0b010],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        'e' => [0b000, 0b111, 0b111, 0b100, 0b111],
        '-' => [0b000, 0b000, 0b111, 0b000, 0b000],
        '+' => [0b000, 0b010, 0b111, 0b010, 0b000],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        _ => [0b111, 0b111, 0b111, 0b111, 0b111],
    }
}

/// A label's width in font pixels: 3 a glyph and 1 between.
fn label_width(label: &str) -> u32 {
    (4 * label.chars().count() as u32).saturating_sub(1)
}

fn draw_label(out: &mut Rgb8, left: u32, top: u32, label: &str, scale: u32) {
    for (k, c) in label.chars().enumerate() {
        let g = glyph(c);
        for (row, bits) in g.iter().enumerate() {
            for col in 0..3u32 {
                if bits & (0b100 >> col) != 0 {
                    for sy in 0..scale {
                        for sx in 0..scale {
                            out.put(
                                left + (4 * k as u32 + col) * scale + sx,
                                top + row as u32 * scale + sy,
                                [230, 230, 230],
                            );
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, value: [f32; 3]) -> Image {
        Image {
            width,
            height,
            pixels: vec![value; (width * height) as usize],
        }
    }

    /// The map keeps its pixels at the top left, the bar runs the ramp from its low end to its
    /// high end, and the canvas is widened for a small image's labels.
    #[test]
    fn maps_keep_their_pixels_above_a_bar_of_their_ramp() {
        let r = image(4, 3, [1.0; 3]);
        let mut x = image(4, 3, [1.0; 3]);
        x.pixels[0] = [2.0; 3]; // brighter: red in the signed map
        x.pixels[1] = [0.5; 3]; // darker: blue
        let m = signed_map(&x, &r);
        assert_eq!(m.width, MIN_WIDTH);
        assert!(m.height > 3 + 8);
        let px = |m: &Rgb8, x: u32, y: u32| {
            let i = 3 * (y * m.width + x) as usize;
            [m.data[i], m.data[i + 1], m.data[i + 2]]
        };
        assert!(
            px(&m, 0, 0)[0] > 100 && px(&m, 0, 0)[2] < 50,
            "{:?}",
            px(&m, 0, 0)
        );
        assert!(
            px(&m, 1, 0)[2] > 100 && px(&m, 1, 0)[0] < 50,
            "{:?}",
            px(&m, 1, 0)
        );
        assert_eq!(px(&m, 2, 0), [0, 0, 0]);
        // Beside the map: the canvas's grey.
        assert_eq!(px(&m, 10, 0), [48, 48, 48]);
        // The bar's ends: full blue at the left, full red at the right.
        let bar_y = 3 + 4 + 2;
        assert_eq!(px(&m, 8, bar_y), diverging(0.0));
        assert_eq!(px(&m, MIN_WIDTH - 9, bar_y), diverging(1.0));

        let e = rel_mse_map(&x, &r);
        assert_eq!(px(&e, 2, 0), [0, 0, 0]);
        assert_eq!(px(&e, 8, bar_y), heat(ERROR_MAP_MIN));
        assert_eq!(px(&e, MIN_WIDTH - 9, bar_y), heat(ERROR_MAP_MAX));
        // A wide image keeps its width and scales its labels.
        let wide = rel_mse_map(&image(800, 2, [1.0; 3]), &image(800, 2, [1.0; 3]));
        assert_eq!(wide.width, 800);
        assert_eq!(wide.data.len(), 3 * (800 * wide.height) as usize);
    }

    #[test]
    fn a_non_finite_pixel_is_magenta() {
        let r = image(2, 1, [1.0; 3]);
        let mut x = image(2, 1, [1.0; 3]);
        x.pixels[1] = [f32::NAN, 0.0, 0.0];
        let m = signed_map(&x, &r);
        assert_eq!(&m.data[3..6], &[255, 0, 255]);
    }
}
