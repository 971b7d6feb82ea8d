//! irad's spot falloff, smoothstep(cos falloff, cos cone, cos theta) (pbrt-v4's), fitted with
//! Mitsuba 3's `spot`, which ramps linearly in theta from `beam_width` to `cutoff_angle`.

/// Mitsuba spot parameters (degrees) fitted to an irad spot, and the largest intensity
/// difference between the two profiles, as a fraction of the peak.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotFit {
    pub beam_width: f64,
    pub cutoff_angle: f64,
    pub max_difference: f64,
}

/// irad's spot profile (lights.glsl `spot_falloff`) at angle `theta` (radians) from the axis:
/// smoothstep(cos falloff, cos cone, cos theta), a step at the cone when the two are equal.
pub fn irad_spot_profile(theta: f64, cone: f64, falloff: f64) -> f64 {
    let (c, e0, e1) = (theta.cos(), falloff.cos(), cone.cos());
    if e1 <= e0 {
        return if c >= e1 { 1.0 } else { 0.0 };
    }
    let t = ((c - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Mitsuba's spot profile (spot.cpp `falloff_curve`): 1 within `beam`, falling linearly in
/// angle to 0 at `cutoff` (radians).
pub fn mitsuba_spot_profile(theta: f64, beam: f64, cutoff: f64) -> f64 {
    if theta >= cutoff {
        0.0
    } else if theta <= beam {
        1.0
    } else {
        (cutoff - theta) / (cutoff - beam)
    }
}

/// Integral of irad's profile over the sphere / (2 pi): (1 - cos cone) + (cos cone - cos
/// falloff) / 2 (emission.glsl).
fn irad_spot_power(cone: f64, falloff: f64) -> f64 {
    (1.0 - cone.cos()) + 0.5 * (cone.cos() - falloff.cos())
}

/// Integral of Mitsuba's profile over the sphere / (2 pi):
/// 1 - (sin cutoff - sin beam) / (cutoff - beam), 1 - cos beam when they are equal.
fn mitsuba_spot_power(beam: f64, cutoff: f64) -> f64 {
    if cutoff - beam < 1e-9 {
        1.0 - beam.cos()
    } else {
        1.0 - (cutoff.sin() - beam.sin()) / (cutoff - beam)
    }
}

/// Fits Mitsuba's linear ramp to irad's smoothstep: among (beam_width, cutoff_angle) pairs
/// with irad's total power, the one with the least squared intensity difference integrated
/// over the sphere (beam_width by a grid and a golden-section search in [cone, the beam
/// whose flat cone alone has the power], cutoff_angle by bisection on the power). A step
/// (cone = falloff) maps exactly.
pub fn fit_spot(cone_deg: f32, falloff_deg: f32) -> SpotFit {
    let (cone, falloff) = (
        (cone_deg as f64).to_radians(),
        (falloff_deg as f64).to_radians(),
    );
    if falloff - cone < 1e-9 {
        return SpotFit {
            beam_width: cone_deg as f64,
            cutoff_angle: cone_deg as f64,
            max_difference: 0.0,
        };
    }
    let power = irad_spot_power(cone, falloff);
    // The cutoff giving `power` for a beam (None: none up to pi does).
    let cutoff_for = |beam: f64| -> Option<f64> {
        if mitsuba_spot_power(beam, std::f64::consts::PI) < power {
            return None;
        }
        let (mut lo, mut hi) = (beam, std::f64::consts::PI);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if mitsuba_spot_power(beam, mid) < power {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    };
    let error = |beam: f64| -> f64 {
        let Some(cutoff) = cutoff_for(beam) else {
            return f64::INFINITY;
        };
        let end = cutoff.max(falloff);
        let n = 2048;
        let h = end / n as f64;
        (0..n)
            .map(|i| {
                let theta = (i as f64 + 0.5) * h;
                let d = mitsuba_spot_profile(theta, beam, cutoff)
                    - irad_spot_profile(theta, cone, falloff);
                d * d * theta.sin() * h
            })
            .sum()
    };
    let top = (1.0 - power).clamp(-1.0, 1.0).acos().clamp(cone, falloff);
    let steps = 64;
    let at = |i: usize| cone + (top - cone) * i as f64 / steps as f64;
    let best = (0..=steps)
        .min_by(|&a, &b| error(at(a)).total_cmp(&error(at(b))))
        .unwrap_or(0);
    let (mut lo, mut hi) = (at(best.saturating_sub(1)), at((best + 1).min(steps)));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if error(a) <= error(b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    let beam = 0.5 * (lo + hi);
    let cutoff = cutoff_for(beam).unwrap_or(falloff);
    let end = cutoff.max(falloff);
    let max_difference = (0..=4096)
        .map(|i| {
            let theta = end * i as f64 / 4096.0;
            (mitsuba_spot_profile(theta, beam, cutoff) - irad_spot_profile(theta, cone, falloff))
                .abs()
        })
        .fold(0.0, f64::max);
    SpotFit {
        beam_width: beam.to_degrees(),
        cutoff_angle: cutoff.to_degrees(),
        max_difference,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Integral of a profile over the sphere / (2 pi), numerically.
    fn power(f: impl Fn(f64) -> f64) -> f64 {
        let n = 200_000;
        let h = PI / n as f64;
        (0..n)
            .map(|i| {
                let t = (i as f64 + 0.5) * h;
                f(t) * t.sin() * h
            })
            .sum()
    }

    #[test]
    fn spot_fit_keeps_the_power_and_follows_the_smoothstep() {
        assert!(
            (power(|t| mitsuba_spot_profile(t, 0.3, 0.7)) - mitsuba_spot_power(0.3, 0.7)).abs()
                < 1e-8
        );
        assert!(
            (power(|t| irad_spot_profile(t, 0.3, 0.7)) - irad_spot_power(0.3, 0.7)).abs() < 1e-8
        );
        for (cone, falloff) in [(20.0f32, 30.0f32), (6.0, 8.0), (10.0, 90.0), (1.0, 179.0)] {
            let fit = fit_spot(cone, falloff);
            let (c, f) = ((cone as f64).to_radians(), (falloff as f64).to_radians());
            let (b, k) = (fit.beam_width.to_radians(), fit.cutoff_angle.to_radians());
            assert!(cone as f64 <= fit.beam_width && fit.beam_width <= fit.cutoff_angle);
            assert!(fit.cutoff_angle <= 180.0);
            let (pm, pi) = (
                power(|t| mitsuba_spot_profile(t, b, k)),
                irad_spot_power(c, f),
            );
            assert!(
                (pm - pi).abs() < 1e-6 * pi,
                "{cone}/{falloff}: power {pm} vs {pi}"
            );
            // A linear ramp through the smoothstep's middle: the two cross near its middle
            // and differ by well under the whole step.
            assert!(fit.max_difference < 0.1, "{cone}/{falloff}: {fit:?}");
            // Better than the naive choice (beam = cone, cutoff = falloff) in the
            // least-squares sense the fit minimizes.
            let sq = |b: f64, k: f64| {
                power(|t| (mitsuba_spot_profile(t, b, k) - irad_spot_profile(t, c, f)).powi(2))
            };
            assert!(sq(b, k) <= sq(c, f), "{cone}/{falloff}: {fit:?}");
        }
        let step = fit_spot(25.0, 25.0);
        assert_eq!(
            (step.beam_width, step.cutoff_angle, step.max_difference),
            (25.0, 25.0, 0.0)
        );
    }
}
