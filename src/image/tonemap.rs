//! The one tone map from linear radiance to display sRGB (docs/DESIGN.md "Outputs", "Error
//! metrics"): scale by 2^exposure, clamp to [0, 1], then the piecewise sRGB transfer function
//! of IEC 61966-2-1. The PNG writer and the Lab error metric both go through here, so what is
//! scored is what is shown.

use super::Image;

/// The linear value below which the sRGB curve is a straight line (IEC 61966-2-1).
pub const SRGB_LINEAR_THRESHOLD: f64 = 0.0031308;

/// sRGB opto-electronic transfer function: linear [0, 1] to encoded [0, 1]. Inputs outside
/// [0, 1] are clamped first and NaN gives 0, so the result is always a valid code value.
pub fn srgb_oetf(linear: f64) -> f64 {
    let v = clamp01(linear);
    if v <= SRGB_LINEAR_THRESHOLD {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`srgb_oetf`]: encoded [0, 1] to linear [0, 1] (clamped, NaN gives 0).
pub fn srgb_eotf(encoded: f64) -> f64 {
    let v = clamp01(encoded);
    // 0.04045 is the encoded threshold the standard gives for the decoding direction.
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear radiance to a display value in [0, 1]: exposure (in stops), clamp, sRGB OETF.
/// Non-finite input never escapes: NaN gives 0, +Inf gives 1, -Inf gives 0.
pub fn tonemap(linear: f32, exposure: f32) -> f64 {
    srgb_oetf(display_linear(linear, exposure))
}

/// The tone map before its sRGB encoding: exposure, then clamp to [0, 1] (NaN gives 0). This is
/// what the display shows, in linear terms; the Lab metric starts here, since encoding to sRGB
/// and decoding again without 8-bit quantization is the identity (up to rounding).
pub fn display_linear(linear: f32, exposure: f32) -> f64 {
    clamp01(linear as f64 * (exposure as f64).exp2())
}

/// [`tonemap`] quantized to 8 bits (round to nearest).
pub fn tonemap_u8(linear: f32, exposure: f32) -> u8 {
    quantize(tonemap(linear, exposure))
}

/// An encoded value in [0, 1] to 8 bits, rounding to nearest.
pub fn quantize(encoded: f64) -> u8 {
    (clamp01(encoded) * 255.0).round() as u8
}

/// The whole image as tightly packed 8-bit sRGB RGB rows, row 0 first (what the PNG holds).
pub fn tonemap_rgb8(image: &Image, exposure: f32) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flat_map(|p| p.map(|c| tonemap_u8(c, exposure)))
        .collect()
}

/// Clamps to [0, 1]; NaN goes to 0 (`f64::clamp` would pass NaN through).
fn clamp01(v: f64) -> f64 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, 1.0)
    }
}
