//! Self-contained HTML pages (docs/DESIGN.md "Looking at results"): the encodings every page
//! uses and the image viewer (`viewer`) that report.html, `irad render --html` and `irad
//! compare --html` embed. No JavaScript library and no network: the pages open from file://.

pub mod viewer;

use crate::image::Image;

/// `image` as half-float RGB, little-endian, in base64. Finite values past the half floats'
/// range are clamped to its largest (65504), so a firefly stays a bright finite pixel.
pub fn half_base64(image: &Image) -> String {
    let mut bytes = Vec::with_capacity(6 * image.pixels.len());
    let most = f32::from(half::f16::MAX);
    for p in &image.pixels {
        for c in p {
            let v = if c.is_finite() {
                c.clamp(-most, most)
            } else {
                *c
            };
            bytes.extend_from_slice(&half::f16::from_f32(v).to_bits().to_le_bytes());
        }
    }
    base64(&bytes)
}

/// `s` as a JSON string safe inside a `<script>` element (no `<`, so no `</script>`).
pub fn json_string(s: &str) -> String {
    serde_json::to_string(s)
        .expect("a string serializes")
        .replace('<', "\\u003c")
}

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// `s` as HTML text or an attribute's value.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A name cannot end the page's script, and a firefly past the half floats' range stays
    /// finite.
    #[test]
    fn names_and_values_are_embedded_safely() {
        let key = json_string("spp=4 </script><b>\"x\"");
        assert!(!key.contains('<'), "{key}");
        assert_eq!(
            serde_json::from_str::<String>(&key).unwrap(),
            "spp=4 </script><b>\"x\""
        );
        let firefly = Image {
            width: 1,
            height: 1,
            pixels: vec![[1e6, f32::NAN, -1e6]],
        };
        // 65504 = 0x7bff, NaN stays NaN (0x7e00), -65504 = 0xfbff.
        assert_eq!(
            half_base64(&firefly),
            base64(&[0xff, 0x7b, 0x00, 0x7e, 0xff, 0xfb])
        );
    }

    #[test]
    fn base64_matches_the_standard_alphabet_and_padding() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
        assert_eq!(base64(&[0xff, 0xfe, 0xfd]), "//79");
    }

    #[test]
    fn half_floats_keep_exposure_precision() {
        let im = Image {
            width: 1,
            height: 1,
            pixels: vec![[1.0, 0.5, 1000.25]],
        };
        // 1.0 = 0x3c00, 0.5 = 0x3800, 1000.25 rounds to 1000 (0x63d0): 11 bits of mantissa.
        let b64 = half_base64(&im);
        assert_eq!(b64, base64(&[0x00, 0x3c, 0x00, 0x38, 0xd0, 0x63]));
    }
}
