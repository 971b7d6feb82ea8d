//! The cube map that drives environment sampling (Lu 14 Chapter 3; docs/DESIGN.md "Conventions"),
//! mirrored in f64 from cubemap.glsl, weigh_env_cube.comp and env_cube.glsl: the face layout
//! and the direction <-> (face, u, v) maps, the texels' exact solid angles, each cube texel's
//! conservative footprint on the equirectangular map and the sampling weights built from it,
//! the per-face pdf of Lu Eq. 3.3 with the exact solid angle, and the normal-dependent face
//! proportions of Lu Eq. 3.4. Tests use these as ground truth for the GPU kernels.
//!
//! Layout: faces 0..5 = +X, -X, +Y, -Y, +Z, -Z (the Vulkan/OpenGL order), face coordinates
//! (u, v) in [-1, 1], R x R texels per face, texel (i, j) covering
//! u in [-1 + 2i/R, -1 + 2(i+1)/R] and v in [-1 + 2j/R, -1 + 2(j+1)/R], index j R + i within
//! its face and f R^2 + j R + i over the cube.
//!
//! The cube map only shapes the pdf: the radiance every method sees stays the piecewise-constant
//! equirectangular map. Each cube texel's weight is therefore the largest luminance the map
//! takes over the texel (bounded conservatively through its footprint) times its solid angle,
//! so the pdf is positive wherever the map is.

use std::f64::consts::PI;

use glam::DVec3;

use crate::sampling::environment::luminance;
use crate::scene::Environment;

/// The unnormalized direction of (u, v) on face `face` (the OpenGL cube-map table):
/// +X (1, -v, -u), -X (-1, -v, u), +Y (u, 1, v), -Y (u, -1, -v), +Z (u, -v, 1), -Z (-u, -v, -1).
pub fn face_point(face: usize, u: f64, v: f64) -> DVec3 {
    match face {
        0 => DVec3::new(1.0, -v, -u),
        1 => DVec3::new(-1.0, -v, u),
        2 => DVec3::new(u, 1.0, v),
        3 => DVec3::new(u, -1.0, -v),
        4 => DVec3::new(u, -v, 1.0),
        5 => DVec3::new(-u, -v, -1.0),
        _ => panic!("cube face {face} out of range 0..6"),
    }
}

/// The unit direction of (u, v) on face `face`: `face_point` normalized.
pub fn face_direction(face: usize, u: f64, v: f64) -> DVec3 {
    face_point(face, u, v).normalize()
}

/// The face of a (not necessarily unit) direction d and its face coordinates, inverting
/// `face_point`: the major axis is the largest |component|, ties going to x, then y, then z;
/// with a = |major|, +X (-z, -y)/a, -X (z, -y)/a, +Y (x, z)/a, -Y (x, -z)/a, +Z (x, -y)/a,
/// -Z (-x, -y)/a. A zero component of the major axis counts as negative (faces -X, -Y, -Z).
pub fn direction_to_face(d: DVec3) -> (usize, f64, f64) {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x > 0.0 {
            (0, -d.z / a.x, -d.y / a.x)
        } else {
            (1, d.z / a.x, -d.y / a.x)
        }
    } else if a.y >= a.z {
        if d.y > 0.0 {
            (2, d.x / a.y, d.z / a.y)
        } else {
            (3, d.x / a.y, -d.z / a.y)
        }
    } else if d.z > 0.0 {
        (4, d.x / a.z, -d.y / a.z)
    } else {
        (5, -d.x / a.z, -d.y / a.z)
    }
}

/// The texel (i, j) of face coordinates (u, v) on a face of resolution r:
/// i = floor((u + 1) / 2 R), j = floor((v + 1) / 2 R), each clamped to [0, R - 1].
pub fn uv_texel(u: f64, v: f64, r: u32) -> (u32, u32) {
    let index = |x: f64| (((x + 1.0) * 0.5 * r as f64).max(0.0) as u32).min(r - 1);
    (index(u), index(v))
}

/// The cube texel a direction falls in: (face, i, j), by `direction_to_face` and `uv_texel`.
pub fn texel_of(d: DVec3, r: u32) -> (usize, u32, u32) {
    let (face, u, v) = direction_to_face(d);
    let (i, j) = uv_texel(u, v, r);
    (face, i, j)
}

/// The global index of texel (i, j) of face `face`: face R^2 + j R + i.
pub fn texel_index(r: u32, face: usize, i: u32, j: u32) -> usize {
    let r = r as usize;
    face * r * r + j as usize * r + i as usize
}

/// The (u, v) rectangle texel (i, j) covers: ((u0, v0), (u1, v1)) with
/// u0 = -1 + 2i/R, u1 = -1 + 2(i+1)/R and v likewise in j.
pub fn texel_bounds(r: u32, i: u32, j: u32) -> ((f64, f64), (f64, f64)) {
    let s = 2.0 / r as f64;
    let (u0, v0) = (-1.0 + s * i as f64, -1.0 + s * j as f64);
    ((u0, v0), (u0 + s, v0 + s))
}

/// The antiderivative of the solid-angle density (1 + u^2 + v^2)^(-3/2) du dv on a face:
/// A(u, v) = atan2(u v, sqrt(1 + u^2 + v^2)), with d^2 A / du dv = (1 + u^2 + v^2)^(-3/2).
fn solid_angle_antiderivative(u: f64, v: f64) -> f64 {
    (u * v).atan2((1.0 + u * u + v * v).sqrt())
}

/// The exact solid angle of the rectangle [u0, u1] x [v0, v1] on a face:
/// Omega = A(u1, v1) - A(u0, v1) - A(u1, v0) + A(u0, v0), A as above.
pub fn rectangle_solid_angle(u0: f64, v0: f64, u1: f64, v1: f64) -> f64 {
    let a = solid_angle_antiderivative;
    a(u1, v1) - a(u0, v1) - a(u1, v0) + a(u0, v0)
}

/// The exact solid angle of texel (i, j) of a face of resolution r (Lu Section 3.3.3, the
/// "brute force" integral in closed form; cubemap.glsl approximates it by Gauss-Legendre in f32,
/// where the closed form cancels catastrophically).
pub fn texel_solid_angle(r: u32, i: u32, j: u32) -> f64 {
    let ((u0, v0), (u1, v1)) = texel_bounds(r, i, j);
    rectangle_solid_angle(u0, v0, u1, v1)
}

/// The continuous (column, row) of a unit direction on a W x H equirectangular map
/// (docs/DESIGN.md "Conventions"): (frac(atan2(x, -z) / 2 pi) W, acos(y) / pi H). The column
/// lies in [0, W] (W only by rounding of a tiny negative angle), the row in [0, H].
pub fn equirect_coordinates(d: DVec3, w: u32, h: u32) -> (f64, f64) {
    let u = (d.x.atan2(-d.z) / (2.0 * PI)).rem_euclid(1.0);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    (u * w as f64, v * h as f64)
}

/// The equirectangular texel (ie, je) of a unit direction: the floors of
/// `equirect_coordinates`, clamped to the map (the f64 twin of `environment::texel_index`).
pub fn equirect_texel(d: DVec3, w: u32, h: u32) -> (u32, u32) {
    let (c, row) = equirect_coordinates(d, w, h);
    ((c as u32).min(w - 1), (row as u32).min(h - 1))
}

/// The equirectangular texels a cube texel may touch (`equirect_footprint`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Footprint {
    /// Inclusive range of rows je, within [0, H - 1].
    pub rows: (u32, u32),
    /// Inclusive range of columns ie, which may extend below 0 or beyond W - 1 (wrapping around
    /// the u_e = 0 seam; fewer than W columns in all), or None for every column.
    pub columns: Option<(i64, i64)>,
}

/// The boundary points of cube texel (i, j) of `face` on which its footprint is measured, in
/// the order weigh_env_cube.comp walks them (counter-clockwise in (u, v): bottom edge v = v0,
/// right u = u1, top v = v1, left u = u0): each corner, then, where the edge crosses the line
/// on which the polar angle along it can peak inside it, that point: u = 0 on the edges of
/// constant v (every face), v = 0 on the edges of constant u (faces +Y and -Y only). With the
/// corners these hold every extreme of the polar angle and the azimuth over the texel (see
/// `equirect_footprint`); 4 to 8 points.
pub fn footprint_boundary(r: u32, face: usize, i: u32, j: u32) -> Vec<(f64, f64)> {
    let ((u0, v0), (u1, v1)) = texel_bounds(r, i, j);
    let polar_face = face == 2 || face == 3;
    let mut points = Vec::with_capacity(8);
    let crosses = |a: f64, b: f64| a.min(b) < 0.0 && a.max(b) > 0.0;
    points.push((u0, v0));
    if crosses(u0, u1) {
        points.push((0.0, v0));
    }
    points.push((u1, v0));
    if polar_face && crosses(v0, v1) {
        points.push((u1, 0.0));
    }
    points.push((u1, v1));
    if crosses(u0, u1) {
        points.push((0.0, v1));
    }
    points.push((u0, v1));
    if polar_face && crosses(v0, v1) {
        points.push((u0, 0.0));
    }
    points
}

/// The conservative footprint of cube texel (i, j) of face `face` (resolution r) on a W x H
/// equirectangular map, as weigh_env_cube.comp computes it:
///
/// - The `footprint_boundary` points are mapped to continuous (column, row) coordinates
///   (`equirect_coordinates`).
/// - Rows: floor(min row) - 1 ..= floor(max row) + 1, clamped to [0, H - 1].
/// - Columns: the columns are unwrapped along the walk, each step's difference (to the previous
///   point's column taken mod W) wrapped into (-W/2, W/2]; then floor(min) - 1 ..= floor(max) + 1,
///   or None where that spans W columns or more.
/// - A texel holding a pole, which only faces +Y and -Y can (the closed rectangle contains
///   (u, v) = (0, 0)), takes every column (None) and its rows reach row 0 (+Y) or H - 1 (-Y).
///
/// Why it covers the texel: the texel is a spherical quadrilateral bounded by great-circle
/// arcs. Away from the poles neither the polar angle nor the azimuth has a critical point on
/// the sphere, so their extremes over the texel lie on its boundary. The azimuth is monotone
/// along each arc (a non-meridian great circle meets each half-meridian once), so its extremes
/// are at the corners. The polar angle along an arc is extremal at its ends or at the foot of
/// the perpendicular to it: u = 0 on a v-edge of a side face, u = 0 or v = 0 on +Y/-Y. The
/// walk holds the corners and those crossings, so it holds every extreme, and the one-texel
/// margins only absorb rounding (f32 on the GPU, where the radiance lookup is f32 too).
pub fn equirect_footprint(r: u32, face: usize, i: u32, j: u32, w: u32, h: u32) -> Footprint {
    let half = 0.5 * w as f64;
    let mut row_min = f64::INFINITY;
    let mut row_max = f64::NEG_INFINITY;
    let mut col_min = f64::INFINITY;
    let mut col_max = f64::NEG_INFINITY;
    let mut previous = 0.0f64;
    for (k, &(u, v)) in footprint_boundary(r, face, i, j).iter().enumerate() {
        let (mut col, row) = equirect_coordinates(face_direction(face, u, v), w, h);
        row_min = row_min.min(row);
        row_max = row_max.max(row);
        if k > 0 {
            let mut step = col - previous.rem_euclid(w as f64);
            if step > half {
                step -= w as f64;
            }
            if step <= -half {
                step += w as f64;
            }
            col = previous + step;
        }
        previous = col;
        col_min = col_min.min(col);
        col_max = col_max.max(col);
    }
    let mut j0 = (row_min.floor() as i64 - 1).max(0);
    let mut j1 = (row_max.floor() as i64 + 1).min(h as i64 - 1);
    let ((u0, v0), (u1, v1)) = texel_bounds(r, i, j);
    let pole = (face == 2 || face == 3) && u0 <= 0.0 && u1 >= 0.0 && v0 <= 0.0 && v1 >= 0.0;
    if pole {
        if face == 2 {
            j0 = 0;
        } else {
            j1 = h as i64 - 1;
        }
    }
    let (i0, i1) = (col_min.floor() as i64 - 1, col_max.floor() as i64 + 1);
    let columns = (!pole && i1 - i0 + 1 < w as i64).then_some((i0, i1));
    Footprint {
        rows: (j0 as u32, j1 as u32),
        columns,
    }
}

/// The map texels (ie, je) of a footprint on a map W wide, row by row, columns wrapped into
/// [0, W - 1] (each texel once).
pub fn footprint_texels(fp: Footprint, w: u32) -> impl Iterator<Item = (u32, u32)> {
    let (i0, i1) = fp.columns.unwrap_or((0, w as i64 - 1));
    (fp.rows.0..=fp.rows.1)
        .flat_map(move |je| (i0..=i1).map(move |ie| (ie.rem_euclid(w as i64) as u32, je)))
}

/// At least as many map texels as any cube texel's footprint holds, on a W x H map and faces R
/// texels wide: weigh_env_cube.comp splits its search over dispatches by it. Columns: at most W
/// (a wider footprint takes every column once). Rows: the footprint's points lie in one texel,
/// whose angular diameter is at most its diagonal on the face, 2 sqrt(2) / R (central projection
/// from a plane at distance 1 shortens every path), and the polar angle changes no faster than
/// the direction, so they span at most 2 sqrt(2) H / (pi R) rows, plus one for the floors, one
/// of margin each side and the pole's texel, which reaches the pole inside that diameter, and
/// one more against float rounding on the GPU.
pub fn footprint_bound(w: u32, h: u32, r: u32) -> u64 {
    let span = (2.0 * std::f64::consts::SQRT_2 * h as f64
        / (std::f64::consts::PI * r.max(1) as f64))
        .ceil() as u64;
    w as u64 * (span + 5).min(h as u64)
}

/// Per cube texel (index f R^2 + j R + i, 6 R^2 in all), its sampling weight: the largest
/// luminance Y over the map texels of its footprint, clamped at >= 0, times its exact solid
/// angle (weigh_env_cube.comp).
pub fn cube_weights(env: &Environment, r: u32) -> Vec<f64> {
    let (w, h) = (env.width, env.height);
    let mut weights = vec![0.0; 6 * (r * r) as usize];
    for face in 0..6 {
        for j in 0..r {
            for i in 0..r {
                let fp = equirect_footprint(r, face, i, j, w, h);
                let peak = footprint_texels(fp, w)
                    .map(|(ie, je)| luminance(env.texels[(je * w + ie) as usize]))
                    .fold(0.0f64, f64::max);
                weights[texel_index(r, face, i, j)] = peak * texel_solid_angle(r, i, j);
            }
        }
    }
    weights
}

/// The face totals I_f: the sums of each face's R^2 weights.
pub fn face_totals(weights: &[f64], r: u32) -> [f64; 6] {
    let n = (r * r) as usize;
    std::array::from_fn(|f| weights[f * n..(f + 1) * n].iter().sum())
}

/// pdf_L(d | f), f the face of d (Lu Eq. 3.3 with the exact weight): the texel t holding d is
/// picked with probability weight_t / I_f and d placed uniformly in (u, v) over its area 4 / R^2,
/// and d omega = (1 + u^2 + v^2)^(-3/2) du dv, so
///   pdf_L(d | f) = (weight_t / I_f) (R^2 / 4) (1 + u^2 + v^2)^(3/2),
/// with (u, v) the face coordinates of d; 0 where I_f = 0.
pub fn face_pdf(weights: &[f64], r: u32, d: DVec3) -> f64 {
    let (face, u, v) = direction_to_face(d);
    let (i, j) = uv_texel(u, v, r);
    let n = (r * r) as usize;
    let total: f64 = weights[face * n..(face + 1) * n].iter().sum();
    if total <= 0.0 {
        return 0.0;
    }
    let q = 1.0 + u * u + v * v;
    weights[texel_index(r, face, i, j)] / total * (n as f64 / 4.0) * q * q.sqrt()
}

/// A direction on face `face` drawn from pdf_L(. | face): the texel is the first, in row-major
/// order (index j R + i), whose inclusive running sum of weights exceeds u1 I_f (the last texel
/// of positive weight where rounding leaves none), and (u, v) = (-1 + 2(i + u2)/R,
/// -1 + 2(j + u3)/R). A face with I_f = 0 has no distribution: its texel is then floor(u1 R^2),
/// and face_pdf is 0 there, so the caller must weigh the sample by zero.
pub fn sample_face(weights: &[f64], r: u32, face: usize, u1: f64, u2: f64, u3: f64) -> DVec3 {
    let n = (r * r) as usize;
    let face_weights = &weights[face * n..(face + 1) * n];
    let total: f64 = face_weights.iter().sum();
    let t = if total > 0.0 {
        let x = u1 * total;
        let mut running = 0.0;
        face_weights
            .iter()
            .position(|&w| {
                running += w;
                x < running
            })
            .unwrap_or_else(|| face_weights.iter().rposition(|&w| w > 0.0).unwrap())
    } else {
        ((u1 * n as f64) as usize).min(n - 1)
    };
    let (i, j) = ((t % r as usize) as f64, (t / r as usize) as f64);
    let s = 2.0 / r as f64;
    face_direction(face, -1.0 + s * (i + u2), -1.0 + s * (j + u3))
}

/// The pdf of the mixture that draws face f with probability `mu[f]` and then samples
/// pdf_L(. | f): sum over g of mu_g pdf_L(d | g) = mu_f pdf_L(d | f), f the face of d (the
/// denominator of Lu Eq. 3.2, only d's own face having density at d).
pub fn mixture_pdf(weights: &[f64], r: u32, mu: &[f64; 6], d: DVec3) -> f64 {
    let (face, _, _) = direction_to_face(d);
    mu[face] * face_pdf(weights, r, d)
}

/// The mixture pdf with uniform face proportions mu_f = 1/6: face_pdf(d) / 6.
pub fn uniform_faces_pdf(weights: &[f64], r: u32, d: DVec3) -> f64 {
    face_pdf(weights, r, d) / 6.0
}

/// The normalized corner directions c_j of face `face`: face_direction(face, +-1, +-1).
pub fn face_corners(face: usize) -> [DVec3; 4] {
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(u, v)| face_direction(face, u, v))
}

/// Lu Eq. 3.4, the face proportions for a shading normal n:
///   mu_f(n) = F_f(n) I_f / sum_g F_g(n) I_g,
///   F_f(n) = sum over f's four corners c_j of max(0, <n, c_j>),
/// all zero where the denominator is not positive. A face whose corners are all at or below
/// the horizon gets mu_f = 0 and loses nothing: a face is the spherical convex hull of its
/// corners, so <n, d> <= 0 over all of it.
pub fn face_weights_mu(normal: DVec3, face_totals: [f64; 6]) -> [f64; 6] {
    let products: [f64; 6] = std::array::from_fn(|f| {
        let form_factor: f64 = face_corners(f)
            .iter()
            .map(|c| normal.dot(*c).max(0.0))
            .sum();
        form_factor * face_totals[f]
    });
    let sum: f64 = products.iter().sum();
    if sum > 0.0 {
        products.map(|p| p / sum)
    } else {
        [0.0; 6]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    use crate::sampling::environment;

    /// SplitMix64: uniform f64 in [0, 1) for the tests.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
            z ^= z >> 31;
            (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        }

        fn sphere(&mut self) -> DVec3 {
            let y = 1.0 - 2.0 * self.next();
            let phi = 2.0 * PI * self.next();
            let s = (1.0 - y * y).max(0.0).sqrt();
            DVec3::new(s * phi.cos(), y, s * phi.sin())
        }

        fn below(&mut self, n: u32) -> u32 {
            ((self.next() * n as f64) as u32).min(n - 1)
        }
    }

    fn blank_map(w: u32, h: u32) -> Environment {
        Environment {
            width: w,
            height: h,
            texels: vec![Vec3::ZERO; (w * h) as usize],
            source: "".into(),
        }
    }

    /// The unit direction at map coordinates (u_e, v_e): phi = 2 pi u_e, theta = pi v_e,
    /// d = (sin theta sin phi, cos theta, -sin theta cos phi).
    fn equirect_direction(ue: f64, ve: f64) -> DVec3 {
        let (phi, theta) = (2.0 * PI * ue, PI * ve);
        DVec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        )
    }

    #[test]
    fn faces_follow_the_opengl_table() {
        let centres = [
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        for (f, c) in centres.iter().enumerate() {
            assert_eq!(face_direction(f, 0.0, 0.0), *c);
            assert_eq!(direction_to_face(*c), (f, 0.0, 0.0));
        }
        // OpenGL: on +X, s grows towards -Z and t towards -Y; on +Y, s towards +X, t towards +Z.
        assert_eq!(face_point(0, 1.0, 1.0), DVec3::new(1.0, -1.0, -1.0));
        assert_eq!(face_point(2, 1.0, 1.0), DVec3::new(1.0, 1.0, 1.0));
        assert_eq!(face_point(5, 1.0, 1.0), DVec3::new(-1.0, -1.0, -1.0));
        // Ties go to x, then y.
        assert_eq!(direction_to_face(DVec3::new(1.0, 1.0, 0.0)).0, 0);
        assert_eq!(direction_to_face(DVec3::new(-1.0, 0.0, 1.0)).0, 1);
        assert_eq!(direction_to_face(DVec3::new(0.0, 1.0, -1.0)).0, 2);
        assert_eq!(direction_to_face(DVec3::new(1.0, -1.0, 1.0)).0, 0);
    }

    #[test]
    fn direction_and_face_coordinates_round_trip() {
        let mut rng = Rng(1);
        for _ in 0..100_000 {
            let d = rng.sphere();
            let (f, u, v) = direction_to_face(d);
            assert!((-1.0..=1.0).contains(&u) && (-1.0..=1.0).contains(&v));
            assert!((face_direction(f, u, v) - d).length() < 1e-12, "{d}");
            // Scaling (exactly, by a power of two) changes neither the face nor the coordinates.
            assert_eq!(direction_to_face(d * 4.0), (f, u, v));
        }
        for _ in 0..100_000 {
            let f = rng.below(6) as usize;
            let (u, v) = (2.0 * rng.next() - 1.0, 2.0 * rng.next() - 1.0);
            let (g, a, b) = direction_to_face(face_direction(f, u, v));
            assert_eq!(g, f);
            assert!((a - u).abs() < 1e-12 && (b - v).abs() < 1e-12);
        }
    }

    #[test]
    fn texels_follow_the_layout() {
        let r = 4;
        // +Z: u = -0.9 is column 0, v = 0.6 row 3.
        assert_eq!(texel_of(DVec3::new(-0.9, -0.6, 1.0), r), (4, 0, 3));
        // A tie goes to +X: (u, v) = (-z, -y) = (-1, 1); the far edges clamp into the last texel.
        assert_eq!(texel_of(DVec3::new(1.0, -1.0, 1.0), r), (0, 0, 3));
        assert_eq!(uv_texel(1.0, 1.0, r), (3, 3));
        assert_eq!(uv_texel(-1.0, 0.0, r), (0, 2));
        assert_eq!(texel_index(r, 4, 0, 3), 4 * 16 + 12);
        let mut rng = Rng(2);
        for _ in 0..10_000 {
            let d = rng.sphere();
            let (f, i, j) = texel_of(d, r);
            let (_, u, v) = direction_to_face(d);
            let ((u0, v0), (u1, v1)) = texel_bounds(r, i, j);
            assert_eq!(f, direction_to_face(d).0);
            assert!(u0 <= u && u <= u1 && v0 <= v && v <= v1);
        }
    }

    #[test]
    fn texel_solid_angles_cover_the_sphere() {
        for r in [1, 2, 3, 16, 64, 257] {
            let face: f64 = (0..r)
                .flat_map(|j| (0..r).map(move |i| texel_solid_angle(r, i, j)))
                .sum();
            assert!(
                (6.0 * face - 4.0 * PI).abs() < 1e-9,
                "R = {r}: {}",
                6.0 * face
            );
        }
    }

    #[test]
    fn texel_solid_angle_matches_quadrature() {
        // Composite Simpson of (1 + u^2 + v^2)^(-3/2) over the texel.
        let simpson = |r: u32, i: u32, j: u32| {
            let ((u0, v0), (u1, v1)) = texel_bounds(r, i, j);
            let n = 256;
            let weight = |k: usize| match k {
                0 => 1.0,
                k if k == n => 1.0,
                k if k % 2 == 1 => 4.0,
                _ => 2.0,
            };
            let (hu, hv) = ((u1 - u0) / n as f64, (v1 - v0) / n as f64);
            let mut sum = 0.0;
            for a in 0..=n {
                for b in 0..=n {
                    let (u, v) = (u0 + hu * a as f64, v0 + hv * b as f64);
                    sum += weight(a) * weight(b) * (1.0 + u * u + v * v).powf(-1.5);
                }
            }
            sum * hu * hv / 9.0
        };
        for (r, i, j) in [
            (1, 0, 0),
            (4, 0, 0),
            (4, 1, 2),
            (5, 2, 2),
            (16, 15, 3),
            (64, 31, 32),
        ] {
            let exact = texel_solid_angle(r, i, j);
            let numeric = simpson(r, i, j);
            assert!(
                (exact - numeric).abs() < 1e-9 * exact,
                "R {r} ({i}, {j}): {exact} vs {numeric}"
            );
        }
    }

    /// Texels worth testing on each face: corners, the pole texels of +Y/-Y, the texels along
    /// the u_e = 0 seam (-Z around u = 0; +Y and -Y around u = 0, on the -Z side), and random
    /// ones.
    fn interesting_texels(r: u32, rng: &mut Rng) -> Vec<(usize, u32, u32)> {
        let mut texels = Vec::new();
        let mid = [(r - 1) / 2, r / 2];
        for f in 0..6 {
            for (i, j) in [(0, 0), (r - 1, 0), (0, r - 1), (r - 1, r - 1)] {
                texels.push((f, i, j));
            }
            for _ in 0..12 {
                texels.push((f, rng.below(r), rng.below(r)));
            }
        }
        for f in [2, 3] {
            for i in mid {
                for j in mid {
                    texels.push((f, i, j));
                }
            }
        }
        for i in mid {
            for j in [0, r / 3, (r - 1) / 2, r / 2, r - 1] {
                texels.push((5, i, j)); // -Z: the seam is u = 0
                texels.push((2, i, j / 2)); // +Y: the seam is u = 0, v < 0
                texels.push((3, i, r - 1 - j / 2)); // -Y: the seam is u = 0, v > 0
            }
        }
        texels
    }

    #[test]
    fn footprints_cover_their_texels() {
        let mut rng = Rng(3);
        for r in [4, 5, 16, 64] {
            for (w, h) in [(64, 32), (256, 128), (16, 8)] {
                let map = blank_map(w, h);
                for (f, i, j) in interesting_texels(r, &mut rng) {
                    let fp = equirect_footprint(r, f, i, j, w, h);
                    let covered: std::collections::HashSet<(u32, u32)> =
                        footprint_texels(fp, w).collect();
                    let ((u0, v0), (u1, v1)) = texel_bounds(r, i, j);
                    // Random points inside, plus the corners and edges of the closed texel.
                    let mut points: Vec<(f64, f64)> = (0..2000)
                        .map(|_| (u0 + (u1 - u0) * rng.next(), v0 + (v1 - v0) * rng.next()))
                        .collect();
                    for k in 0..=16 {
                        let t = k as f64 / 16.0;
                        let (u, v) = (u0 + (u1 - u0) * t, v0 + (v1 - v0) * t);
                        points.extend([(u, v0), (u, v1), (u0, v), (u1, v)]);
                    }
                    for (u, v) in points {
                        let d = face_direction(f, u, v);
                        let (ie, je) = equirect_texel(d, w, h);
                        assert!(
                            covered.contains(&(ie, je)),
                            "R {r}, map {w}x{h}, texel ({f}, {i}, {j}) {fp:?}: \
                             ({u}, {v}) -> ({ie}, {je})"
                        );
                        // The f32 lookup the renderer's radiance uses lands inside too.
                        let k = environment::texel_index(&map, d.as_vec3()) as u32;
                        assert!(
                            covered.contains(&(k % w, k / w)),
                            "f32 lookup of ({u}, {v})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn footprints_at_poles_and_seam() {
        let (w, h) = (64, 32);
        // R = 4: four texels of +Y meet at the north pole; they take every column from row 0.
        for (i, j) in [(1, 1), (1, 2), (2, 1), (2, 2)] {
            let north = equirect_footprint(4, 2, i, j, w, h);
            assert_eq!(north.columns, None);
            assert_eq!(north.rows.0, 0);
            let south = equirect_footprint(4, 3, i, j, w, h);
            assert_eq!(south.columns, None);
            assert_eq!(south.rows.1, h - 1);
        }
        // R = 5: the centre texel holds the pole, its neighbours do not.
        assert_eq!(equirect_footprint(5, 2, 2, 2, w, h).columns, None);
        assert!(equirect_footprint(5, 2, 3, 2, w, h).columns.is_some());
        // -Z, u in [-0.5, 0]: x = -u >= 0, azimuth from 0 on, the margin wraps below column 0.
        let fp = equirect_footprint(4, 5, 1, 1, w, h);
        let (i0, i1) = fp.columns.unwrap();
        assert_eq!(i0, -1);
        assert!(i1 >= (w as f64 * (0.5f64).atan() / (2.0 * PI)) as i64);
        // A side-face texel keeps to its rows: +X, v in [-1, -0.5] (up), rows near the top.
        let fp = equirect_footprint(4, 0, 1, 0, w, h);
        assert!(fp.rows.0 >= 5 && fp.rows.1 <= 13, "{fp:?}");
        // Footprint texels wrap.
        let fp = Footprint {
            rows: (3, 4),
            columns: Some((-2, 1)),
        };
        let texels: Vec<_> = footprint_texels(fp, 8).collect();
        assert_eq!(
            texels,
            [
                (6, 3),
                (7, 3),
                (0, 3),
                (1, 3),
                (6, 4),
                (7, 4),
                (0, 4),
                (1, 4)
            ]
        );
        let all = Footprint {
            rows: (0, 0),
            columns: None,
        };
        assert_eq!(footprint_texels(all, 8).count(), 8);
    }

    #[test]
    fn footprint_bound_holds_every_footprint() {
        let maps = [
            (1, 1),
            (3, 2),
            (16, 8),
            (64, 32),
            (100, 50),
            (256, 128),
            (512, 256),
            (2048, 1024),
            (37, 91),
        ];
        for (w, h) in maps {
            for r in [1, 2, 3, 4, 5, 7, 8, 16, 33, 64] {
                let bound = footprint_bound(w, h, r);
                let mut largest = 0u64;
                for face in 0..6 {
                    for j in 0..r {
                        for i in 0..r {
                            let fp = equirect_footprint(r, face, i, j, w, h);
                            let columns = fp.columns.map_or(w as u64, |(a, b)| (b - a + 1) as u64);
                            let rows = (fp.rows.1 - fp.rows.0 + 1) as u64;
                            largest = largest.max(rows * columns);
                            assert_eq!(footprint_texels(fp, w).count() as u64, rows * columns);
                        }
                    }
                }
                assert!(
                    largest <= bound,
                    "map {w}x{h}, R {r}: footprint {largest} > bound {bound}"
                );
                // Tight enough that the split costs no more than a few dispatches more than it must.
                if h >= 256 {
                    assert!(
                        bound <= 3 * largest,
                        "map {w}x{h}, R {r}: bound {bound}, footprint {largest}"
                    );
                }
            }
        }
    }

    #[test]
    fn cube_weights_cover_a_single_bright_texel() {
        let mut rng = Rng(4);
        for (w, h) in [(32, 16), (16, 8), (64, 32)] {
            let targets = [
                (0, 0),
                (w - 1, 0),
                (0, h / 2),
                (w - 1, h - 1),
                (w / 3, h / 3),
            ];
            for (ie, je) in targets {
                let mut map = blank_map(w, h);
                map.texels[(je * w + ie) as usize] = Vec3::new(0.0, 5.0, 0.0);
                for r in [4, 5, 16] {
                    let weights = cube_weights(&map, r);
                    assert_eq!(weights.len(), (6 * r * r) as usize);
                    assert!(weights.iter().all(|&x| x >= 0.0));
                    for _ in 0..2000 {
                        let ue = (ie as f64 + rng.next()) / w as f64;
                        let ve = (je as f64 + rng.next()) / h as f64;
                        let (f, i, j) = texel_of(equirect_direction(ue, ve), r);
                        assert!(
                            weights[texel_index(r, f, i, j)] > 0.0,
                            "map {w}x{h} texel ({ie}, {je}), R {r}: cube texel ({f}, {i}, {j})"
                        );
                    }
                    if r == 16 && w == 64 && je == h / 3 {
                        // The support stays local.
                        let positive = weights.iter().filter(|&&x| x > 0.0).count();
                        assert!(positive < weights.len() / 10, "{positive}");
                    }
                }
            }
        }
        // A uniform map: weight = Y times solid angle, summing to 4 pi Y.
        let mut map = blank_map(16, 8);
        map.texels.fill(Vec3::splat(2.0));
        let total: f64 = cube_weights(&map, 8).iter().sum();
        assert!((total - 8.0 * PI).abs() < 1e-6, "{total}");
    }

    fn random_weights(r: u32, rng: &mut Rng) -> Vec<f64> {
        let mut weights: Vec<f64> = (0..6 * r * r)
            .map(|_| {
                if rng.next() < 0.3 {
                    0.0
                } else {
                    0.2 + rng.next()
                }
            })
            .collect();
        // Face -Y is empty.
        let n = (r * r) as usize;
        weights[3 * n..4 * n].fill(0.0);
        weights
    }

    #[test]
    fn face_pdfs_integrate_to_one() {
        // Stratified over the sphere (equal-area cells in (cos theta, phi), one jittered
        // direction each), independent of the cube's parametrization.
        let mut rng = Rng(5);
        for r in [5, 8] {
            let weights = random_weights(r, &mut rng);
            let (nz, nphi) = (1000, 2000);
            let cell = 4.0 * PI / (nz * nphi) as f64;
            let mut integral = [0.0f64; 6];
            let mut uniform = 0.0;
            for a in 0..nz {
                for b in 0..nphi {
                    let y = 1.0 - 2.0 * (a as f64 + rng.next()) / nz as f64;
                    let phi = 2.0 * PI * (b as f64 + rng.next()) / nphi as f64;
                    let s = (1.0 - y * y).max(0.0).sqrt();
                    let d = DVec3::new(s * phi.cos(), y, s * phi.sin());
                    let (f, _, _) = direction_to_face(d);
                    integral[f] += face_pdf(&weights, r, d) * cell;
                    uniform += uniform_faces_pdf(&weights, r, d) * cell;
                }
            }
            for (f, x) in integral.iter().enumerate() {
                let expected = if f == 3 { 0.0 } else { 1.0 };
                assert!((x - expected).abs() < 1e-3, "R {r}, face {f}: {x}");
            }
            assert!((uniform - 5.0 / 6.0).abs() < 1e-3, "{uniform}");
        }
    }

    #[test]
    fn sample_face_follows_the_weights() {
        let mut rng = Rng(6);
        let r = 4;
        let n = (r * r) as usize;
        let weights = random_weights(r, &mut rng);
        let totals = face_totals(&weights, r);
        for face in [0, 2, 5] {
            let samples = 200_000;
            let mut counts = vec![0u32; n];
            for _ in 0..samples {
                let d = sample_face(&weights, r, face, rng.next(), rng.next(), rng.next());
                assert!((d.length() - 1.0).abs() < 1e-12);
                let (f, i, j) = texel_of(d, r);
                assert_eq!(f, face);
                counts[(j * r + i) as usize] += 1;
            }
            let mut chi2 = 0.0;
            let mut dof = 0;
            for (t, &c) in counts.iter().enumerate() {
                let expected = weights[face * n + t] / totals[face] * samples as f64;
                if expected == 0.0 {
                    assert_eq!(c, 0, "face {face} texel {t} has no weight");
                } else {
                    chi2 += (c as f64 - expected).powi(2) / expected;
                    dof += 1;
                }
            }
            // Mean dof - 1, standard deviation sqrt(2 (dof - 1)): six of them.
            let bound = (dof - 1) as f64 + 6.0 * (2.0 * (dof - 1) as f64).sqrt();
            assert!(chi2 < bound, "face {face}: chi^2 {chi2} over {dof} texels");
        }
        // The extreme random numbers stay on positive texels.
        for face in [0, 2, 5] {
            for u1 in [0.0, 1.0 - f64::EPSILON, 1.0] {
                let d = sample_face(&weights, r, face, u1, 0.5, 0.5);
                assert!(face_pdf(&weights, r, d) > 0.0);
            }
        }
        // An empty face still yields a direction on it, of pdf 0.
        let d = sample_face(&weights, r, 3, 0.7, 0.5, 0.5);
        assert_eq!(direction_to_face(d).0, 3);
        assert_eq!(face_pdf(&weights, r, d), 0.0);
    }

    #[test]
    fn face_pdf_matches_eq_3_3() {
        let r = 4;
        let mut weights = vec![0.0; 6 * 16];
        weights[texel_index(r, 4, 3, 0)] = 1.0;
        weights[texel_index(r, 4, 0, 0)] = 3.0;
        // +Z texel (3, 0): u in [0.5, 1], v in [-1, -0.5]; d = (0.75, 0.75, 1) has (u, v) =
        // (0.75, -0.75), so pdf = 1/4 * 16/4 * (1 + 2 * 0.5625)^1.5.
        let pdf = face_pdf(&weights, r, DVec3::new(0.75, 0.75, 1.0));
        assert!((pdf - 0.25 * 4.0 * 2.125f64.powf(1.5)).abs() < 1e-12);
        let mu = [0.1, 0.1, 0.1, 0.1, 0.5, 0.1];
        let d = DVec3::new(0.75, 0.75, 1.0);
        assert!((mixture_pdf(&weights, r, &mu, d) - 0.5 * pdf).abs() < 1e-15);
        assert_eq!(face_pdf(&weights, r, DVec3::new(0.0, 0.0, 1.0)), 0.0);
        assert_eq!(face_pdf(&weights, r, DVec3::X), 0.0);
    }

    #[test]
    fn face_proportions_follow_eq_3_4() {
        let mut rng = Rng(7);
        let totals = [1.0, 2.0, 0.5, 3.0, 0.25, 4.0];
        for _ in 0..2000 {
            let n = rng.sphere();
            let mu = face_weights_mu(n, totals);
            assert!((mu.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{mu:?}");
            for (f, &m) in mu.iter().enumerate() {
                let below = face_corners(f).iter().all(|c| n.dot(*c) <= 0.0);
                assert_eq!(m == 0.0, below, "face {f}, n {n}");
                if below {
                    // Nothing on the face is above the horizon: mu_f = 0 loses nothing.
                    for _ in 0..200 {
                        let d = face_direction(f, 2.0 * rng.next() - 1.0, 2.0 * rng.next() - 1.0);
                        assert!(n.dot(d) <= 1e-12, "face {f}, n {n}, d {d}");
                    }
                }
            }
        }
        // The corners of +Y, for n = +Y: all four at <n, c> = 1/sqrt(3); -Y's all below.
        let mu = face_weights_mu(DVec3::Y, [1.0; 6]);
        assert_eq!(mu[3], 0.0);
        assert!(mu[2] > mu[0] && (mu[0] - mu[4]).abs() < 1e-15);
        // F_f = 4/sqrt(3) for +Y, 2/sqrt(3) for each side face: mu = 1/3 and 1/6.
        assert!((mu[2] - 1.0 / 3.0).abs() < 1e-12 && (mu[0] - 1.0 / 6.0).abs() < 1e-12);
        assert_eq!(face_weights_mu(DVec3::Y, [0.0; 6]), [0.0; 6]);
        assert_eq!(
            face_weights_mu(DVec3::Y, [0.0, 0.0, 0.0, 5.0, 0.0, 0.0]),
            [0.0; 6]
        );
    }
}
