//! Sampling the two-plane light-field luminaire of Lu 14 Chapter 4 (the model is
//! src/scene/luminaire/) in f64: the CPU mirror of what method `lightfield` does on the GPU,
//! and its tests.
//!
//! In the luminaire's frame the filter plane U is z = 0 and the image plane S is z = delta;
//! light leaves toward +z. W x H basis functions Phi_m sit on a grid of pitch (du, dv)
//! centred on the origin of U: bilinear hats (support +-1 pitch; Heidrich's canned light
//! source) or quadratic B-splines (support +-1.5 pitches; Goesele et al.). Image m, C_m, is
//! piecewise constant over R_s x R_t texels covering [-sx/2, sx/2] x [-sy/2, sy/2] on S. The
//! radiance along the ray from u through s is Eq. 4.1,
//!   L(u -> s) = |s - u|^4 / delta^2 * sum_m C_m(s) Phi_m(u) = sum_m C_m(s) Psi_m(u -> s).
//!
//! At a point p beyond S (Delta = p.z - delta > 0) the light arriving through s comes from
//! u(s), where the line p-s meets U, and d omega = Delta / |s - p|^3 ds, so the scalar
//! irradiance I(p) = the integral of L over the directions from p splits per image (Eq. 4.5):
//!   I_m(p) = Delta * integral over S of C_m(s) Psi_m(u -> s) / |s - p|^3 ds.
//! Phi_m vanishes outside its support box, whose projection from p onto S is the window of
//! Eq. 4.11. Sampling s in the window with pdf C_m / A_m (sampling/restricted.rs, windowed
//! marginal: the pdf it realises), A_m the window's integral of C_m, gives Eq. 4.17:
//!   I_m(p) ~ A_m Delta / K_m * sum_k Psi_m(u_k -> s_k) / |s_k - p|^3.
//! K_m(p) = round(K A_m / A), at least 1 where A_m > 0 (so no image with energy is dropped:
//! each I_m keeps its own unbiased estimate whatever K_m) and at most K_max; 0 where A_m = 0.

use glam::{DVec3, Vec3};

use super::restricted::{ImageTables, Marginal, Search, Window};
use crate::scene::luminaire::{Geometry, Luminaire};

/// A luminaire's sampling tables: per image the luminance tables of sampling/restricted.rs.
#[derive(Clone, Debug)]
pub struct LuminaireSampler {
    pub geometry: Geometry,
    pub images: Vec<ImageTables>,
}

/// One image's share at a point: the window on S (texel units), A_m (in S's units, m^2) and
/// the samples it gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Share {
    pub window: Window,
    pub area: f64,
    pub samples: u32,
}

impl LuminaireSampler {
    /// The tables of `luminaire`'s images' luminance (Y = 0.2126 R + 0.7152 G + 0.0722 B).
    pub fn new(luminaire: &Luminaire) -> LuminaireSampler {
        let [rs, rt] = luminaire.geometry.resolution;
        let y = |c: &Vec3| 0.2126 * c.x as f64 + 0.7152 * c.y as f64 + 0.0722 * c.z as f64;
        LuminaireSampler {
            geometry: luminaire.geometry,
            images: luminaire
                .images
                .iter()
                .map(|im| ImageTables::new(rs, rt, im.iter().map(y).collect()))
                .collect(),
        }
    }

    fn node(&self, m: usize) -> (f64, f64) {
        self.geometry.node(m)
    }

    fn phi(&self, m: usize, u: (f64, f64)) -> f64 {
        self.geometry.phi(m, u)
    }

    /// A point of S in texel units of the images, and back.
    fn plane_to_texels(&self, s: (f64, f64)) -> (f64, f64) {
        let r = (self.images[0].width as f64, self.images[0].height as f64);
        (
            (s.0 / self.geometry.image_size[0] + 0.5) * r.0,
            (s.1 / self.geometry.image_size[1] + 0.5) * r.1,
        )
    }

    fn texels_to_plane(&self, t: (f64, f64)) -> (f64, f64) {
        let r = (self.images[0].width as f64, self.images[0].height as f64);
        (
            (t.0 / r.0 - 0.5) * self.geometry.image_size[0],
            (t.1 / r.1 - 0.5) * self.geometry.image_size[1],
        )
    }

    /// m^2 of S per texel.
    fn texel_area(&self) -> f64 {
        self.geometry.image_size[0] / self.images[0].width as f64 * self.geometry.image_size[1]
            / self.images[0].height as f64
    }

    /// C_m at s (0 outside the images).
    pub fn image_value(&self, m: usize, s: (f64, f64)) -> f64 {
        let im = &self.images[m];
        let (a, b) = self.plane_to_texels(s);
        if a < 0.0 || b < 0.0 || a >= im.width as f64 || b >= im.height as f64 {
            return 0.0;
        }
        im.texel(a as usize, b as usize)
    }

    /// Where the line from p through s meets U.
    pub fn filter_point(&self, p: DVec3, s: (f64, f64)) -> (f64, f64) {
        let tau = p.z / (p.z - self.geometry.delta);
        (p.x + tau * (s.0 - p.x), p.y + tau * (s.1 - p.y))
    }

    /// Psi_m(u -> s) = Phi_m(u) |s - u|^4 / delta^2 (Eq. 4.1).
    pub fn psi(&self, m: usize, u: (f64, f64), s: (f64, f64)) -> f64 {
        let d2 =
            (s.0 - u.0).powi(2) + (s.1 - u.1).powi(2) + self.geometry.delta * self.geometry.delta;
        self.phi(m, u) * d2 * d2 / (self.geometry.delta * self.geometry.delta)
    }

    /// Eq. 4.11: the window on S (texel units) through which p sees basis m's support.
    pub fn window(&self, m: usize, p: DVec3) -> Window {
        let (x, y) = self.node(m);
        let (rx, ry) = (
            self.geometry.basis.reach() * self.geometry.pitch[0],
            self.geometry.basis.reach() * self.geometry.pitch[1],
        );
        // s = p + (u - p) Delta / (Delta + delta), Delta + delta = p.z.
        let k = (p.z - self.geometry.delta) / p.z;
        let project =
            |u: (f64, f64)| self.plane_to_texels((p.x + (u.0 - p.x) * k, p.y + (u.1 - p.y) * k));
        let (a, b) = (project((x - rx, y - ry)), project((x + rx, y + ry)));
        Window {
            s0: a.0,
            s1: b.0,
            t0: a.1,
            t1: b.1,
        }
    }

    /// Eq. 4.14 and 4.16 at p: each image's window, A_m and K_m (at least 1 where A_m > 0,
    /// at most `k_max`).
    pub fn shares(&self, p: DVec3, k: u32, k_max: u32) -> Vec<Share> {
        let texel = self.texel_area();
        let mut shares: Vec<Share> = (0..self.images.len())
            .map(|m| {
                let window = self.window(m, p);
                let area = self.images[m].window_integral(window) * texel;
                Share {
                    window,
                    area,
                    samples: 0,
                }
            })
            .collect();
        let total: f64 = shares.iter().map(|s| s.area).sum();
        for s in shares.iter_mut().filter(|s| s.area > 0.0) {
            let ideal = (k as f64 * s.area / total).round() as u32;
            s.samples = ideal.clamp(1, k_max.max(1));
        }
        shares
    }

    /// Eq. 4.17 at p (Delta > 0): the scalar irradiance from K samples spread by Eq. 4.16, s
    /// drawn by the windowed restricted sampler with uniforms from `next`. Returns the
    /// estimate and the samples drawn.
    pub fn irradiance(
        &self,
        p: DVec3,
        k: u32,
        k_max: u32,
        search: Search,
        mut next: impl FnMut() -> f64,
    ) -> (f64, u32) {
        let delta_p = p.z - self.geometry.delta;
        let mut sum = 0.0;
        let mut drawn = 0;
        for (m, share) in self.shares(p, k, k_max).iter().enumerate() {
            if share.samples == 0 {
                continue;
            }
            let mut image_sum = 0.0;
            for _ in 0..share.samples {
                drawn += 1;
                let Some(d) =
                    self.images[m].draw(share.window, (next(), next()), Marginal::Windowed, search)
                else {
                    continue;
                };
                let s = self.texels_to_plane((d.s, d.t));
                let u = self.filter_point(p, s);
                let r = ((s.0 - p.x).powi(2) + (s.1 - p.y).powi(2) + delta_p * delta_p).sqrt();
                image_sum += self.psi(m, u, s) / (r * r * r);
            }
            sum += share.area * delta_p / share.samples as f64 * image_sum;
        }
        (sum, drawn)
    }

    /// The brute-force reference of I(p): n x n midpoint points over the whole of S.
    pub fn irradiance_brute_force(&self, p: DVec3, n: usize) -> f64 {
        let delta_p = p.z - self.geometry.delta;
        let (sx, sy) = (self.geometry.image_size[0], self.geometry.image_size[1]);
        let mut sum = 0.0;
        for a in 0..n {
            for b in 0..n {
                let s = (
                    (-0.5 + (a as f64 + 0.5) / n as f64) * sx,
                    (-0.5 + (b as f64 + 0.5) / n as f64) * sy,
                );
                let u = self.filter_point(p, s);
                let r = ((s.0 - p.x).powi(2) + (s.1 - p.y).powi(2) + delta_p * delta_p).sqrt();
                let radiance: f64 = (0..self.images.len())
                    .map(|m| self.image_value(m, s) * self.psi(m, u, s))
                    .sum();
                sum += radiance * delta_p / (r * r * r);
            }
        }
        sum * sx * sy / (n * n) as f64
    }
    /// I(p) integrated over U instead of S (Lu Section 4.3.4, which holds at every p beyond
    /// S, on S included): p.z times the integral over U of L(u -> p) / |u - p|^3, by an n x n
    /// midpoint rule over each basis support box, L(u -> p) = sum_m C_m(s) Psi_m(u -> s) with
    /// s where the line u-p meets S. With `cosine`, the irradiance of a surface at p facing
    /// the luminaire (normal -z): each direction weighed by cos = p.z / |u - p|.
    pub fn irradiance_over_filter_plane(&self, p: DVec3, n: usize, cosine: bool) -> f64 {
        let g = &self.geometry;
        let (rx, ry) = (g.basis.reach() * g.pitch[0], g.basis.reach() * g.pitch[1]);
        let mut sum = 0.0;
        for m in 0..self.images.len() {
            let (x, y) = self.node(m);
            for a in 0..n {
                for b in 0..n {
                    let u = (
                        x + (2.0 * (a as f64 + 0.5) / n as f64 - 1.0) * rx,
                        y + (2.0 * (b as f64 + 0.5) / n as f64 - 1.0) * ry,
                    );
                    let tau = g.delta / p.z;
                    let s = (u.0 + (p.x - u.0) * tau, u.1 + (p.y - u.1) * tau);
                    let r = ((u.0 - p.x).powi(2) + (u.1 - p.y).powi(2) + p.z * p.z).sqrt();
                    let weight = if cosine { p.z / r } else { 1.0 };
                    sum += self.image_value(m, s) * self.psi(m, u, s) * p.z / (r * r * r) * weight;
                }
            }
        }
        sum * 4.0 * rx * ry / (n * n) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::luminaire::{Basis, Emitter};

    /// A 3 x 3 luminaire, pitch 0.1, delta 0.5, 32 x 32 grey images over 2 x 2: each image a
    /// smooth lobe toward its own side plus a hot spot, one image black.
    fn luminaire(basis: Basis) -> LuminaireSampler {
        let (w, h) = (3usize, 3usize);
        let r = 32usize;
        let images = (0..w * h)
            .map(|m| {
                let (i, j) = ((m % w) as f64 - 1.0, (m / w) as f64 - 1.0);
                (0..r * r)
                    .map(|k| {
                        if m == 5 {
                            return Vec3::ZERO;
                        }
                        let (a, b) = (
                            (k % r) as f64 / r as f64 - 0.5,
                            (k / r) as f64 / r as f64 - 0.5,
                        );
                        let lobe = (-((a - 0.2 * i).powi(2) + (b - 0.2 * j).powi(2)) * 8.0).exp();
                        let spot = if (k % r, k / r) == (20 + m, 11) {
                            30.0
                        } else {
                            0.0
                        };
                        Vec3::splat((lobe + spot) as f32)
                    })
                    .collect()
            })
            .collect();
        LuminaireSampler::new(&Luminaire {
            geometry: Geometry {
                grid: [w, h],
                pitch: [0.1, 0.1],
                basis,
                delta: 0.5,
                image_size: [2.0, 2.0],
                resolution: [r, r],
            },
            images,
            sequence: vec![],
            source: "test".into(),
        })
    }

    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut x = seed.wrapping_mul(0x9e3779b97f4a7c15) | 1;
        move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Eq. 4.17 with the restricted windows against the brute force over the whole of S,
    /// within 1% (and 4 standard errors), at points near and far, on axis and off it (windows
    /// at the images' borders), for both bases; K_m never 0 where A_m > 0, and no sample where
    /// every A_m = 0 (a point S's light cannot reach).
    #[test]
    fn restricted_estimates_match_the_brute_force_irradiance() {
        for basis in [Basis::Bilinear, Basis::QuadraticBSpline] {
            let lum = luminaire(basis);
            for (k, p) in [
                DVec3::new(0.0, 0.0, 0.8),
                DVec3::new(0.3, -0.2, 1.5),
                DVec3::new(1.4, 0.9, 0.9),
                DVec3::new(-0.5, 0.7, 4.0),
            ]
            .into_iter()
            .enumerate()
            {
                let truth = lum.irradiance_brute_force(p, 384);
                let mut next = rng(7 + k as u64);
                let runs: Vec<f64> = (0..2000)
                    .map(|_| lum.irradiance(p, 64, 16, Search::Secant, &mut next).0)
                    .collect();
                let n = runs.len() as f64;
                let mean = runs.iter().sum::<f64>() / n;
                let stderr =
                    (runs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
                eprintln!(
                    "{basis:?} at {p}: restricted / brute force {:.4} ± {:.4}",
                    mean / truth,
                    stderr / truth
                );
                assert!(
                    (mean / truth - 1.0).abs() < 0.01
                        && (mean - truth).abs() < 4.0 * stderr + 1e-12,
                    "{basis:?} at {p}: {mean} ± {stderr} against {truth}"
                );
                for s in lum.shares(p, 64, 16) {
                    assert_eq!(s.samples == 0, s.area <= 0.0, "{basis:?} at {p}: {s:?}");
                }
            }
            // Beyond the reach of every basis through S: no light, no samples.
            let far = DVec3::new(50.0, 0.0, 1.0);
            assert_eq!(
                lum.irradiance(far, 64, 16, Search::Binary, rng(1)),
                (0.0, 0)
            );
            assert_eq!(lum.irradiance_brute_force(far, 200), 0.0);
        }
    }

    /// The closed-form case: a uniform Lambertian disk of radius R and radiance L0 in the
    /// filter plane, turned into a luminaire (9 x 9 bases over the disk, the image plane 0.2
    /// above it, 32 x 32 images over 0.5 x 0.5); on its axis at height h the scalar
    /// irradiance is L0 times the disk's solid angle, 2 pi L0 (1 - h / sqrt(h^2 + R^2)). The
    /// restricted estimate matches within 1%.
    #[test]
    fn a_disk_luminaire_matches_the_closed_form() {
        let (r, l0) = (0.1, 1.0);
        let disk = Emitter::Disk {
            radius: r,
            radiance: l0,
        };
        for basis in [Basis::Bilinear, Basis::QuadraticBSpline] {
            let geometry = Geometry {
                grid: [9, 9],
                pitch: [2.0 * r / 8.0, 2.0 * r / 8.0],
                basis,
                delta: 0.2,
                image_size: [0.5, 0.5],
                resolution: [32, 32],
            };
            let lum = LuminaireSampler::new(&Luminaire::from_emitter(
                geometry,
                |u, s| disk.radiance(u, s, 0.2),
                "disk",
            ));
            for h in [0.3f64, 1.0] {
                let exact = 2.0 * std::f64::consts::PI * l0 * (1.0 - h / (h * h + r * r).sqrt());
                let p = DVec3::new(0.0, 0.0, h);
                let mut next = rng(3);
                let runs = 2000;
                let mean = (0..runs)
                    .map(|_| lum.irradiance(p, 64, 16, Search::Secant, &mut next).0)
                    .sum::<f64>()
                    / runs as f64;
                let brute = lum.irradiance_brute_force(p, 512);
                eprintln!(
                    "disk, {basis:?}, h {h}: restricted / exact {:.4}, brute force / exact {:.4}",
                    mean / exact,
                    brute / exact
                );
                assert!(
                    (mean / exact - 1.0).abs() < 0.01,
                    "{basis:?} h {h}: {mean} against {exact}"
                );
            }
        }
    }

    /// Section 4.3.4's integral over U against the brute force over S, away from S (where both
    /// hold), for both bases and on and off axis.
    #[test]
    fn the_integral_over_the_filter_plane_matches_the_image_plane() {
        for basis in [Basis::Bilinear, Basis::QuadraticBSpline] {
            let lum = luminaire(basis);
            for p in [DVec3::new(0.0, 0.0, 1.5), DVec3::new(0.3, -0.2, 0.8)] {
                let over_s = lum.irradiance_brute_force(p, 1024);
                let over_u = lum.irradiance_over_filter_plane(p, 256, false);
                eprintln!("{basis:?} at {p}: over U / over S {:.4}", over_u / over_s);
                assert!(
                    (over_u / over_s - 1.0).abs() < 0.01,
                    "{basis:?} at {p}: {over_u} against {over_s}"
                );
            }
        }
    }
}
