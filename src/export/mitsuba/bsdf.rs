//! irad's BSDF (Lambert plus a normalized Phong lobe, docs/DESIGN.md "Conventions") in Mitsuba 3
//! terms, which has no Phong plugin: the lobe as a Beckmann `roughconductor` with no Fresnel
//! (`material` none: eta 0 + 1i, a perfect mirror), blended with the `diffuse` part.

use glam::Vec3;

/// Beckmann roughness for irad's Phong exponent `ns`: alpha = 1 / sqrt(2 ns + 1).
///
/// irad's lobe is centred on the mirror direction: at normal incidence it falls as
/// cos^n(a) ~ exp(-n a^2 / 2) with the angle a from the mirror direction. There the half
/// vector is at a / 2 from the normal, so Beckmann's D ~ exp(-tan^2(a / 2) / alpha^2)
/// ~ exp(-a^2 / (4 alpha^2)) has the same width for alpha^2 = 1 / (2 n); 1 / (2 n + 1) is
/// Walter et al. 2007's Blinn-Phong match alpha = sqrt(2 / (N + 2)) for the Blinn exponent
/// N = 4 n that a mirror-centred exponent n amounts to, finite at n = 0. The two lobes'
/// half-maximum angles at normal incidence then agree within 8% for n >= 10, 4% for n >= 20
/// and 1.5% for n >= 50 (the test); broad lobes (n < 10) differ more.
pub fn phong_alpha(ns: f32) -> f32 {
    (1.0 / (2.0 * ns.max(0.0) as f64 + 1.0)).sqrt() as f32
}

/// How Kd / pi + Ks lobe is split for `blendbsdf`, whose result is (1 - w) f0 + w f1 with one
/// scalar w and reflectances that Mitsuba requires in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub enum GlossySplit {
    /// Kd = 0: the conductor alone, specular reflectance Ks.
    SpecularOnly,
    /// w = max Ks / (max Kd + max Ks), diffuse reflectance Kd / (1 - w), specular Ks / w.
    /// Both are <= max Kd + max Ks, so within [0, 1] whenever that sum is (always when the
    /// largest channels of Kd and Ks are the same one, irad requiring Kd + Ks <= 1 per
    /// channel); values over 1 by rounding (up to 1e-4) are clamped to 1, larger ones
    /// written as an unbounded `srgb` spectrum.
    Blend {
        weight: f64,
        diffuse: [f64; 3],
        specular: [f64; 3],
    },
}

pub fn split_glossy(kd: Vec3, ks: Vec3) -> GlossySplit {
    let (d, s) = (kd.max_element() as f64, ks.max_element() as f64);
    if d <= 0.0 {
        return GlossySplit::SpecularOnly;
    }
    // The weight as the XML writes it (f32), so (1 - w) and w undo the division exactly.
    let w = (s / (d + s)) as f32 as f64;
    let scale = |v: Vec3, by: f64| {
        v.as_dvec3().to_array().map(|c| {
            if c / by <= 1.0 + 1e-4 {
                (c / by).min(1.0)
            } else {
                c / by
            }
        })
    };
    GlossySplit::Blend {
        weight: w,
        diffuse: scale(kd, 1.0 - w),
        specular: scale(ks, w),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phong_alpha_matches_the_lobe_width_at_normal_incidence() {
        assert_eq!(phong_alpha(0.0), 1.0);
        assert!((phong_alpha(4.0) - 1.0 / 3.0).abs() < 1e-7);
        // Half-maximum angle from the mirror direction (= the normal) of irad's lobe,
        // cos^n(a) = 1/2, and of the Beckmann BRDF D G1 / (4 cos i) at normal incidence
        // (the half vector at a / 2; G1 ~ 1 this near the peak, left out).
        for ns in [10.0f32, 50.0, 200.0, 1000.0] {
            let phong = (0.5f64.powf(1.0 / ns as f64)).acos();
            let alpha = phong_alpha(ns) as f64;
            let beckmann = |a: f64| {
                let th = 0.5 * a;
                (-(th.tan() / alpha).powi(2)).exp() / th.cos().powi(4) / a.cos()
            };
            let (mut lo, mut hi) = (0.0, 1.5);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if beckmann(mid) > 0.5 * beckmann(0.0) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let ratio = lo / phong;
            let tolerance = if ns < 20.0 { 0.09 } else { 0.04 };
            assert!(
                (ratio - 1.0).abs() < tolerance,
                "Ns {ns}: width ratio {ratio}"
            );
        }
    }

    #[test]
    fn glossy_split_reproduces_kd_and_ks() {
        let (kd, ks) = (Vec3::new(0.1, 0.2, 0.05), Vec3::new(0.6, 0.5, 0.6));
        let GlossySplit::Blend {
            weight,
            diffuse,
            specular,
        } = split_glossy(kd, ks)
        else {
            panic!("a blend")
        };
        for c in 0..3 {
            assert!(((1.0 - weight) * diffuse[c] - kd[c] as f64).abs() < 1e-7);
            assert!((weight * specular[c] - ks[c] as f64).abs() < 1e-7);
            assert!(diffuse[c] <= 1.0 && specular[c] <= 1.0);
        }
        // Kd + Ks = 1 exactly: rounding never pushes a reflectance over 1.
        let GlossySplit::Blend {
            diffuse, specular, ..
        } = split_glossy(Vec3::splat(0.3), Vec3::splat(0.7))
        else {
            panic!("a blend")
        };
        assert!(diffuse.iter().chain(&specular).all(|&c| c <= 1.0));
        assert_eq!(split_glossy(Vec3::ZERO, ks), GlossySplit::SpecularOnly);
    }
}
