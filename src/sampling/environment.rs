//! The environment map's geometry (docs/DESIGN.md "Conventions"), mirrored from envmap.glsl: texel
//! solid angles integrated exactly over each row, the sampling weights (luminance times solid
//! angle) and the cosine-weighted integrals the analytic tests compare against.

use std::f64::consts::PI;

use glam::{DVec3, Vec3};

use crate::scene::Environment;

pub fn luminance(c: Vec3) -> f64 {
    0.2126 * c.x as f64 + 0.7152 * c.y as f64 + 0.0722 * c.z as f64
}

/// Polar angles (from +Y) of the top and bottom edges of row `j`.
pub fn row_angles(j: u32, height: u32) -> (f64, f64) {
    (
        PI * j as f64 / height as f64,
        PI * (j + 1) as f64 / height as f64,
    )
}

/// Solid angle of any texel in row `j`: (2 pi / W) (cos theta_top - cos theta_bottom).
pub fn texel_solid_angle(j: u32, width: u32, height: u32) -> f64 {
    let (a, b) = row_angles(j, height);
    2.0 * PI / width as f64 * (a.cos() - b.cos())
}

/// Per texel, luminance times solid angle: what env_sample picks texels by.
pub fn sampling_weights(env: &Environment) -> Vec<f64> {
    let (w, h) = (env.width, env.height);
    (0..h)
        .flat_map(|j| {
            let omega = texel_solid_angle(j, w, h);
            (0..w).map(move |i| (j, i, omega))
        })
        .map(|(j, i, omega)| luminance(env.texels[(j * w + i) as usize]) * omega)
        .collect()
}

/// The texel a unit direction falls in, as envmap.glsl computes it.
pub fn texel_index(env: &Environment, d: Vec3) -> usize {
    let u = (d.x.atan2(-d.z) / (2.0 * std::f32::consts::PI)).rem_euclid(1.0);
    let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
    let i = ((u * env.width as f32) as u32).min(env.width - 1);
    let j = ((v * env.height as f32) as u32).min(env.height - 1);
    (j * env.width + i) as usize
}

/// Irradiance at an unoccluded point with normal +Y: the integral of L(w) max(0, cos theta)
/// over the sphere, exact for the piecewise-constant map (each row's cos-weighted solid angle
/// in closed form: (2 pi / W) (sin^2 b - sin^2 a) / 2 over the row's part above the horizon).
pub fn irradiance_up(env: &Environment) -> DVec3 {
    let (w, h) = (env.width, env.height);
    let mut e = DVec3::ZERO;
    for j in 0..h {
        let (a, b) = row_angles(j, h);
        let b = b.min(PI / 2.0);
        if a >= b {
            continue;
        }
        let weight = 2.0 * PI / w as f64 * 0.5 * (b.sin().powi(2) - a.sin().powi(2));
        for i in 0..w {
            e += env.texels[(j * w + i) as usize].as_dvec3() * weight;
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solid_angles_cover_the_sphere() {
        let (w, h) = (7, 5);
        let total: f64 = (0..h).map(|j| texel_solid_angle(j, w, h) * w as f64).sum();
        assert!((total - 4.0 * PI).abs() < 1e-12);
    }

    #[test]
    fn uniform_irradiance_is_pi_l() {
        let env = Environment {
            width: 8,
            height: 5,
            texels: vec![Vec3::splat(2.0); 40],
            source: "uniform".into(),
        };
        let e = irradiance_up(&env);
        assert!((e.x - 2.0 * PI).abs() < 1e-12, "{e}");
    }

    #[test]
    fn texel_lookup_follows_the_convention() {
        let env = Environment {
            width: 4,
            height: 2,
            texels: vec![Vec3::ZERO; 8],
            source: "".into(),
        };
        // -Z is u = 0, +X is u = 1/4; up is row 0, down row 1.
        assert_eq!(texel_index(&env, Vec3::new(0.0, 0.1, -1.0).normalize()), 0);
        assert_eq!(texel_index(&env, Vec3::new(1.0, 0.1, 0.01).normalize()), 1);
        assert_eq!(
            texel_index(&env, Vec3::new(0.0, -0.1, 1.0).normalize()),
            4 + 2
        );
    }
}
