//! The built-in procedural skies, one equirectangular map per frame: a sky gradient over a dark
//! ground and a sun disk. `sky = "moving-sun"`: the sun at a fixed elevation, its azimuth
//! turning once every `frames` frames (a dynamic map for Lu 14 ch. 3 and Fig. 5.6's moving
//! sun). `sky = "rising-sun"`: the sun rising from just below the horizon to `sun_elevation`
//! over the frames while turning a quarter of a turn (from azimuth u = 1/4 to 1/2), the sky brightening with it from a
//! twentieth (a dawn: the light's distribution and its total both change). Each texel is the
//! mean radiance over a grid of points uniform in its solid angle, finer near the sun so that
//! a sun smaller than a texel keeps its power.

use std::f32::consts::PI;

use glam::Vec3;

use super::file::EnvironmentFile;
use super::{Environment, SceneError};

#[derive(Clone, Debug, PartialEq)]
pub struct MovingSun {
    pub width: u32,
    pub height: u32,
    /// Frames per revolution of the sun (the sequence's length).
    pub frames: u32,
    /// Degrees above the horizon.
    pub sun_elevation: f32,
    /// The disk's angular radius, degrees.
    pub sun_radius: f32,
    pub sun_radiance: Vec3,
    /// "rising-sun": the sun rises over the frames (see the module's comment).
    pub rising: bool,
}

impl Default for MovingSun {
    fn default() -> Self {
        MovingSun {
            width: 256,
            height: 128,
            frames: 64,
            sun_elevation: 20.0,
            sun_radius: 2.0,
            sun_radiance: Vec3::new(2000.0, 1900.0, 1700.0),
            rising: false,
        }
    }
}

/// The largest sequence accepted, in texels over all frames (4 GiB of GPU memory at 16 bytes a
/// texel).
const MAX_SEQUENCE_TEXELS: u64 = 1 << 28;

const HORIZON: Vec3 = Vec3::new(0.75, 0.8, 0.9);
const ZENITH: Vec3 = Vec3::new(0.15, 0.3, 0.75);
const GROUND: Vec3 = Vec3::new(0.12, 0.1, 0.08);

impl MovingSun {
    /// The sky of `[environment]` (`sky` given), defaults for the fields left out.
    pub fn from_file(file: &str, env: &EnvironmentFile) -> Result<MovingSun, SceneError> {
        let invalid = |field: &str, value: String, problem: &str| SceneError::Invalid {
            file: file.to_string(),
            field: format!("environment.{field}"),
            value,
            problem: problem.into(),
        };
        let name = env.sky.as_deref().unwrap_or_default();
        if name != "moving-sun" && name != "rising-sun" {
            return Err(invalid(
                "sky",
                format!("{name:?}"),
                "the built-in skies are: \"moving-sun\", \"rising-sun\"",
            ));
        }
        let d = MovingSun::default();
        let [w, h] = env.size.unwrap_or([d.width as i64, d.height as i64]);
        let range = 1..=i64::from(super::camera::MAX_RESOLUTION);
        if !range.contains(&w) || !range.contains(&h) {
            return Err(invalid(
                "size",
                format!("[{w}, {h}]"),
                &format!("each must be in 1..={}", super::camera::MAX_RESOLUTION),
            ));
        }
        let frames = env.frames.unwrap_or(d.frames as i64);
        if !(1..=4096).contains(&frames) {
            return Err(invalid("frames", frames.to_string(), "must be in 1..=4096"));
        }
        if (w * h) as u64 * frames as u64 > MAX_SEQUENCE_TEXELS {
            return Err(invalid(
                "frames",
                frames.to_string(),
                &format!("{frames} maps of {w}x{h} exceed {MAX_SEQUENCE_TEXELS} texels in all"),
            ));
        }
        let elevation = env.sun_elevation.unwrap_or(d.sun_elevation);
        if !(elevation.is_finite() && (-90.0..=90.0).contains(&elevation)) {
            return Err(invalid(
                "sun_elevation",
                elevation.to_string(),
                "degrees in -90..=90",
            ));
        }
        let radius = env.sun_radius.unwrap_or(d.sun_radius);
        if !(radius.is_finite() && radius > 0.0 && radius <= 90.0) {
            return Err(invalid(
                "sun_radius",
                radius.to_string(),
                "degrees in (0, 90]",
            ));
        }
        let radiance = env.sun_radiance.map_or(d.sun_radiance, Vec3::from);
        if !(radiance.is_finite() && radiance.min_element() >= 0.0) {
            return Err(invalid(
                "sun_radiance",
                format!("{:?}", radiance.to_array()),
                "must be finite and >= 0 in every channel",
            ));
        }
        if name == "rising-sun" && frames < 2 {
            return Err(invalid(
                "frames",
                frames.to_string(),
                "a rising sun needs 2 or more frames",
            ));
        }
        if name == "rising-sun" && elevation <= 0.0 {
            return Err(invalid(
                "sun_elevation",
                elevation.to_string(),
                "a rising sun rises to an elevation above the horizon: degrees in (0, 90]",
            ));
        }
        Ok(MovingSun {
            width: w as u32,
            height: h as u32,
            frames: frames as u32,
            sun_elevation: elevation,
            sun_radius: radius,
            sun_radiance: radiance,
            rising: name == "rising-sun",
        })
    }

    /// The sun's elevation at `frame`, degrees: fixed, or for a rising sun from one disk below
    /// the horizon at frame 0 to `sun_elevation` at the last frame.
    fn elevation(&self, frame: u32) -> f32 {
        if !self.rising {
            return self.sun_elevation;
        }
        let t = (frame % self.frames.max(1)) as f32 / (self.frames.max(2) - 1) as f32;
        let start = -self.sun_radius;
        start + (self.sun_elevation - start) * t
    }

    /// The sky's brightness at `frame` (1 for the moving sun; for a rising one from 1/20 with
    /// the sun at the horizon to 1 at its highest).
    fn sky_scale(&self, frame: u32) -> f32 {
        if !self.rising {
            return 1.0;
        }
        let e = self.elevation(frame).max(0.0);
        (0.05 + 0.95 * e / self.sun_elevation.max(1e-3)).clamp(0.05, 1.0)
    }

    /// The sun's direction at `frame`: azimuth 2 pi (frame mod frames) / frames, measured as
    /// the map's u (docs/DESIGN.md "Conventions": u = atan2(x, -z) / 2 pi).
    pub fn sun_direction(&self, frame: u32) -> Vec3 {
        // The rising sun comes up a quarter turn from the moving sun's start (u = 1/4, +x) and
        // turns on toward u = 1/2, reaching u = 1/4 + (F - 1) / 4F at the last of F frames.
        let (turn, start) = if self.rising {
            (0.25, 0.5 * PI)
        } else {
            (1.0, 0.0)
        };
        let phi = start
            + 2.0 * PI * turn * (frame % self.frames.max(1)) as f32 / self.frames.max(1) as f32;
        let e = self.elevation(frame).to_radians();
        Vec3::new(e.cos() * phi.sin(), e.sin(), -e.cos() * phi.cos())
    }

    /// The radiance in direction `d` (unit), the sun toward `sun`, the sky at `sky_scale`.
    pub fn radiance(&self, d: Vec3, sun: Vec3, sky_scale: f32) -> Vec3 {
        let sky = sky_scale
            * if d.y >= 0.0 {
                HORIZON.lerp(ZENITH, d.y.sqrt())
            } else {
                GROUND
            };
        // A rising sun below the horizon is behind the ground.
        let in_sun =
            d.dot(sun) >= self.sun_radius.to_radians().cos() && (!self.rising || d.y >= 0.0);
        sky + if in_sun {
            self.sun_radiance
        } else {
            Vec3::ZERO
        }
    }

    /// The map of `frame`, times `scale`.
    pub fn map(&self, frame: u32, scale: f32) -> Environment {
        let (w, h) = (self.width, self.height);
        let sun = self.sun_direction(frame);
        let sky_scale = self.sky_scale(frame);
        let radius = self.sun_radius.to_radians();
        // A texel's angular size along its diagonal, bounding how far its points lie from
        // its centre.
        let reach = |j: u32| {
            let theta = PI * (j as f32 + 0.5) / h as f32;
            let across = 2.0 * PI / w as f32 * theta.sin();
            (across * across + (PI / h as f32).powi(2)).sqrt()
        };
        let mut texels = Vec::with_capacity((w * h) as usize);
        for j in 0..h {
            let (c0, c1) = (
                (PI * j as f32 / h as f32).cos(),
                (PI * (j + 1) as f32 / h as f32).cos(),
            );
            let reach = reach(j);
            for i in 0..w {
                let direction = |a: f32, b: f32| {
                    let phi = 2.0 * PI * (i as f32 + a) / w as f32;
                    let y = c0 + (c1 - c0) * b;
                    let s = (1.0 - y * y).max(0.0).sqrt();
                    Vec3::new(s * phi.sin(), y, -s * phi.cos())
                };
                let near_sun =
                    direction(0.5, 0.5).dot(sun).clamp(-1.0, 1.0).acos() < radius + reach;
                let n = if near_sun { 32 } else { 4 };
                let mut sum = Vec3::ZERO;
                for a in 0..n {
                    for b in 0..n {
                        let d = direction((a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32);
                        sum += self.radiance(d, sun, sky_scale);
                    }
                }
                texels.push(sum / (n * n) as f32 * scale);
            }
        }
        Environment {
            width: w,
            height: h,
            texels,
            source: format!(
                "{} sky, frame {frame}",
                if self.rising {
                    "rising-sun"
                } else {
                    "moving-sun"
                }
            )
            .into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sun_turns_once_per_revolution_and_keeps_its_power() {
        let sky = MovingSun {
            width: 64,
            height: 32,
            frames: 8,
            ..Default::default()
        };
        let bright = |env: &Environment| {
            let k = (0..env.texels.len())
                .max_by(|&a, &b| env.texels[a].x.total_cmp(&env.texels[b].x))
                .unwrap();
            (k as u32 % env.width, k as u32 / env.width)
        };
        let mut powers = vec![];
        for frame in 0..8 {
            let env = sky.map(frame, 1.0);
            let (i, _) = bright(&env);
            // Azimuth frame / 8 of a turn: column frame * 8 (give or take the disk's extent).
            let expected = frame * 8;
            let off = (i as i32 - expected as i32)
                .rem_euclid(64)
                .min((expected as i32 - i as i32).rem_euclid(64));
            assert!(
                off <= 1,
                "frame {frame}: brightest column {i}, expected about {expected}"
            );
            // The sun's power: sum over texels of (L - sky) times the texel's solid angle.
            let mut power = 0.0f64;
            for (k, t) in env.texels.iter().enumerate() {
                let j = k as u32 / 64;
                let omega = 2.0 * std::f64::consts::PI / 64.0
                    * ((std::f64::consts::PI * j as f64 / 32.0).cos()
                        - (std::f64::consts::PI * (j + 1) as f64 / 32.0).cos());
                power += (t.x as f64 - 2.0).max(0.0) * omega;
            }
            powers.push(power);
        }
        assert_eq!(sky.map(8, 1.0).texels, sky.map(0, 1.0).texels);
        // The disk's solid angle times its radiance.
        let r = 2.0f64.to_radians();
        let expected = 2.0 * std::f64::consts::PI * (1.0 - r.cos()) * 2000.0;
        for p in &powers {
            assert!(
                (p / expected - 1.0).abs() < 0.03,
                "sun power {p} against {expected}"
            );
        }
    }

    #[test]
    fn the_rising_sun_climbs_to_its_elevation_and_the_sky_brightens() {
        let sky = MovingSun {
            width: 64,
            height: 32,
            frames: 9,
            sun_elevation: 40.0,
            rising: true,
            ..Default::default()
        };
        let elevation = |f: u32| sky.sun_direction(f).y.asin().to_degrees();
        assert!(
            (elevation(0) + sky.sun_radius).abs() < 1e-3,
            "{}",
            elevation(0)
        );
        assert!((elevation(8) - 40.0).abs() < 1e-3, "{}", elevation(8));
        assert!((1..9).all(|f| elevation(f) > elevation(f - 1)));
        // A quarter turn in azimuth over the frames.
        let (first, last) = (sky.sun_direction(0), sky.sun_direction(8));
        let azimuth = |d: Vec3| d.x.atan2(-d.z).to_degrees();
        assert!((azimuth(last) - azimuth(first) - 90.0 * 8.0 / 9.0).abs() < 1e-2);
        // The sky (the zenith texel row, far from the sun) brightens from a twentieth to full.
        let zenith = |f: u32| sky.map(f, 1.0).texels[0].z;
        assert!(
            (zenith(0) / zenith(8) - 0.05).abs() < 0.01,
            "{}",
            zenith(0) / zenith(8)
        );
        assert!((1..9).all(|f| zenith(f) > zenith(f - 1)));
    }
}
