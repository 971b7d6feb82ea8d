//! irad's environment map, piecewise constant over its texels (docs/DESIGN.md "Conventions"),
//! resampled for Mitsuba 3's `envmap`, which interpolates bilinearly.

use crate::image::Image;
use crate::scene::Environment;

/// Most texels of the upsampled environment map `environment_factor` aims for (48 MiB as
/// float32 RGB).
pub const MAX_ENVIRONMENT_TEXELS: u64 = 1 << 22;

/// The upsampling factor k for a W x H map: the largest k in 2..=16 whose map, kW x (kH + 1),
/// has at most `MAX_ENVIRONMENT_TEXELS` texels, and 2 when none has. Larger k leaves less
/// of each texel to Mitsuba's interpolation; k >= 2 leaves every texel rows of its own.
pub fn environment_factor(width: u32, height: u32) -> u32 {
    (2..=16u32)
        .rev()
        .find(|&k| {
            (k as u64 * width as u64) * (k as u64 * height as u64 + 1) <= MAX_ENVIRONMENT_TEXELS
        })
        .unwrap_or(2)
}

/// irad's map, piecewise constant over W x H texels, as a (kW) x (kH + 1) map for Mitsuba's
/// `envmap`, which interpolates bilinearly between values it places at u = (x + 0.5) / W'
/// (periodic) and v = y / (H' - 1) (clamped) (envmap.cpp `eval_spectrum`; the same in 3.0 to
/// 3.9).
///
/// Columns: irad texel i becomes columns ik .. ik + k - 1, whose centres lie inside it, so the
/// lookup is exact but within 0.5 / (kW) of a texel's left and right edges, where it ramps
/// linearly across the edge, symmetric about it (the same integral over u).
///
/// Rows: v = y / (kH) puts row y = jk on irad's edge v = j / H. Rows strictly between two
/// edges take that texel row, the poles (y = 0 and y = kH) their own texel row, so the lookup
/// is exact but within 1 / (kH) of an inner edge, where it ramps linearly from the texel
/// above to the row on the edge and on to the texel below. That row is
/// a A + (1 - a) B (A above, B below) with `edge_weight`'s a, which makes the ramp's
/// integral over solid angle (sin(theta) d theta) equal to A and B each over its own side:
/// every texel's power is irad's.
pub fn resample_environment(env: &Environment, k: u32) -> Image {
    // k >= 2: the ramps need a row of each texel on either side of an edge row.
    let (w, h) = (env.width as usize, env.height as usize);
    let k = k.max(2) as usize;
    let (ow, oh) = (k * w, k * h + 1);
    let texel = |i: usize, j: usize| env.texels[j * w + i];
    let delta = std::f64::consts::PI / (k * h) as f64;
    let mut image = Image::new(ow as u32, oh as u32);
    for y in 0..oh {
        let (row, edge) = (y / k, y % k == 0);
        let a = edge_weight(std::f64::consts::PI * row as f64 / h as f64, delta) as f32;
        for x in 0..ow {
            let i = x / k;
            let v = if !edge {
                texel(i, row)
            } else if row == 0 {
                texel(i, 0)
            } else if row == h {
                texel(i, h - 1)
            } else {
                a * texel(i, row - 1) + (1.0 - a) * texel(i, row)
            };
            image.pixels[y * ow + x] = v.to_array();
        }
    }
    image
}

/// The weight a of the texel above (smaller theta) in the value at an edge at polar angle
/// `theta` between rows `delta` apart (radians), for `resample_environment`: with A = 1 and
/// B = 0 the ramp's integral of sin(theta) over [theta - delta, theta + delta] must equal
/// that of the step, which gives a = L / (L + R), L and R the integrals of sin against the
/// two halves of the tent centred on the edge:
/// L = (sin t - sin(t - d) - d cos t) / d, R = (sin t - sin(t + d) + d cos t) / d. At the
/// equator a = 1/2; towards a pole the value leans to the texel on the side away from it
/// (more solid angle per unit of ramp).
pub fn edge_weight(theta: f64, delta: f64) -> f64 {
    let (s, c) = theta.sin_cos();
    let l = s - (theta - delta).sin() - delta * c;
    let r = s - (theta + delta).sin() + delta * c;
    if l + r > 0.0 {
        l / (l + r)
    } else {
        0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use std::f64::consts::PI;
    use std::path::PathBuf;

    fn env(width: u32, height: u32, texel: impl Fn(u32, u32) -> Vec3) -> Environment {
        let texels = (0..height)
            .flat_map(|j| (0..width).map(move |i| (i, j)))
            .map(|(i, j)| texel(i, j))
            .collect();
        Environment {
            width,
            height,
            texels,
            source: PathBuf::from("test.exr"),
        }
    }

    /// irad's lookup (envmap.glsl `env_texel_index`).
    fn irad_lookup(e: &Environment, d: [f64; 3]) -> Vec3 {
        let (u, v) = uv(d);
        let i = ((u * e.width as f64) as u32).min(e.width - 1);
        let j = ((v * e.height as f64) as u32).min(e.height - 1);
        e.texels[(j * e.width + i) as usize]
    }

    fn uv(d: [f64; 3]) -> (f64, f64) {
        let u = d[0].atan2(-d[2]) / (2.0 * PI);
        (u - u.floor(), d[1].clamp(-1.0, 1.0).acos() / PI)
    }

    /// Mitsuba 3's `envmap` lookup (envmap.cpp `eval_spectrum`, as of 3.5): bilinear between
    /// columns at u = (x + 0.5) / W (periodic) and rows at v = y / (H - 1) (clamped).
    fn mitsuba_lookup(m: &Image, d: [f64; 3]) -> [f64; 3] {
        let (w, h) = (m.width as usize, m.height as usize);
        let (u, v) = uv(d);
        let mut u = u - 0.5 / w as f64;
        u -= u.floor();
        let (x, y) = (u * w as f64, v * (h - 1) as f64);
        let (x0, y0) = ((x as usize).min(w - 1), (y as usize).min(h - 2));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let at = |x: usize, y: usize| m.pixels[y * w + x % w].map(f64::from);
        let mut out = [0.0; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let top = (1.0 - fx) * at(x0, y0)[c] + fx * at(x0 + 1, y0)[c];
            let bottom = (1.0 - fx) * at(x0, y0 + 1)[c] + fx * at(x0 + 1, y0 + 1)[c];
            *o = (1.0 - fy) * top + fy * bottom;
        }
        out
    }

    fn direction(u: f64, v: f64) -> [f64; 3] {
        let (phi, theta) = (2.0 * PI * u, PI * v);
        [
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        ]
    }

    /// splitmix64 in [0, 1).
    fn random(state: &mut u64) -> f64 {
        *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn environment_factor_stays_within_its_budget() {
        assert_eq!(environment_factor(64, 32), 16);
        assert_eq!(environment_factor(1024, 512), 2);
        assert_eq!(environment_factor(8192, 4096), 2);
        let k = environment_factor(300, 150) as u64;
        assert!(k * 300 * (k * 150 + 1) <= MAX_ENVIRONMENT_TEXELS);
        assert!((k + 1) * 300 * ((k + 1) * 150 + 1) > MAX_ENVIRONMENT_TEXELS);
    }

    #[test]
    fn a_constant_map_stays_constant() {
        let c = Vec3::new(0.25, 1.5, 3.0);
        let m = resample_environment(&env(5, 3, |_, _| c), 4);
        assert_eq!((m.width, m.height), (20, 13));
        assert!(m.pixels.iter().all(|&p| p == c.to_array()));
        let mut s = 7;
        for _ in 0..1000 {
            let d = direction(random(&mut s), random(&mut s));
            let l = mitsuba_lookup(&m, d);
            for ch in 0..3 {
                assert!((l[ch] - c[ch] as f64).abs() < 1e-6, "{d:?}: {l:?}");
            }
        }
    }

    #[test]
    fn lookups_away_from_texel_edges_are_irads() {
        let (w, h, k) = (12u32, 6u32, 8u32);
        let mut s = 11;
        let values: Vec<f32> = (0..w * h).map(|_| random(&mut s) as f32).collect();
        let e = env(w, h, |i, j| Vec3::splat(values[(j * w + i) as usize]));
        let m = resample_environment(&e, k);
        let (ramp_u, ramp_v) = (0.5 / (k * w) as f64, 1.0 / (k * h) as f64);
        let mut checked = 0;
        for _ in 0..20_000 {
            let (u, v) = (random(&mut s), random(&mut s));
            let fu = (u * w as f64).fract();
            // Distance to the nearest inner edge in v (the poles have no ramp).
            let j = (v * h as f64).round();
            let to_edge = if j == 0.0 || j == h as f64 {
                f64::INFINITY
            } else {
                (v - j / h as f64).abs()
            };
            if fu.min(1.0 - fu) / w as f64 <= ramp_u + 1e-9 || to_edge <= ramp_v + 1e-9 {
                continue;
            }
            let d = direction(u, v);
            let (a, b) = (mitsuba_lookup(&m, d)[0], irad_lookup(&e, d).x as f64);
            assert!((a - b).abs() < 1e-5, "u {u} v {v}: Mitsuba {a}, irad {b}");
            checked += 1;
        }
        assert!(checked > 10_000, "{checked}");
    }

    #[test]
    fn edge_weights_favour_the_wider_side() {
        assert!((edge_weight(PI / 2.0, 0.1) - 0.5).abs() < 1e-12);
        // Near the north pole the ramp's half below the edge (larger theta) has more solid
        // angle, so the edge value leans to the texel below.
        let a = edge_weight(0.3, 0.1);
        assert!(a > 0.4 && a < 0.5, "{a}");
        assert!((edge_weight(PI - 0.3, 0.1) - (1.0 - a)).abs() < 1e-12);
    }

    #[test]
    fn one_bright_texel_keeps_its_power_and_place() {
        let (w, h, k) = (16u32, 8u32, 8u32);
        for (ti, tj) in [(5u32, 3u32), (0, 0), (15, 7), (9, 1)] {
            let e = env(w, h, |i, j| {
                if (i, j) == (ti, tj) {
                    Vec3::ONE
                } else {
                    Vec3::ZERO
                }
            });
            let m = resample_environment(&e, k);
            // irad: radiance 1 over the texel's solid angle.
            let cos = |j: i64| (PI * (j.clamp(0, h as i64)) as f64 / h as f64).cos();
            let (tj, ti) = (tj as i64, ti as i64);
            let solid = 2.0 * PI / w as f64 * (cos(tj) - cos(tj + 1));
            // Mitsuba: integrate its lookup over the texel and its neighbours, where it is
            // non-zero (midpoints in u and in cos(theta), which is uniform in solid angle).
            let (u0, u1) = ((ti - 1) as f64 / w as f64, (ti + 2) as f64 / w as f64);
            let (y0, y1) = (cos(tj - 1), cos(tj + 2));
            let n = 600;
            let dw = 2.0 * PI * (u1 - u0) * (y0 - y1) / (n * n) as f64;
            let (mut power, mut centroid) = (0.0, [0.0f64; 3]);
            for b in 0..n {
                let y = y0 + (y1 - y0) * (b as f64 + 0.5) / n as f64;
                let v = y.clamp(-1.0, 1.0).acos() / PI;
                for a in 0..n {
                    let d = direction(u0 + (u1 - u0) * (a as f64 + 0.5) / n as f64, v);
                    let l = mitsuba_lookup(&m, d)[0] * dw;
                    power += l;
                    for c in 0..3 {
                        centroid[c] += l * d[c];
                    }
                }
            }
            let rel = (power - solid) / solid;
            assert!(
                rel.abs() < 1e-4,
                "texel ({ti}, {tj}): power {power} vs {solid}"
            );
            // Its mean direction is irad's texel's: the mean of (sin t sin p, cos t,
            // -sin t cos p) over the texel, uniform in p and in cos t.
            let (p0, p1) = (
                2.0 * PI * ti as f64 / w as f64,
                2.0 * PI * (ti + 1) as f64 / w as f64,
            );
            let (c0, c1) = (cos(tj), cos(tj + 1));
            let mean_sin = (0..n)
                .map(|i| {
                    let c = c0 + (c1 - c0) * (i as f64 + 0.5) / n as f64;
                    (1.0 - c * c).sqrt()
                })
                .sum::<f64>()
                / n as f64;
            let expected = [
                mean_sin * (p0.cos() - p1.cos()) / (p1 - p0),
                0.5 * (c0 + c1),
                -mean_sin * (p1.sin() - p0.sin()) / (p1 - p0),
            ];
            for c in 0..3 {
                let got = centroid[c] / power;
                assert!(
                    (got - expected[c]).abs() < 2e-3,
                    "texel ({ti}, {tj}) axis {c}: {got} vs {}",
                    expected[c]
                );
            }
        }
    }
}
