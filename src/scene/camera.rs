//! The `[camera]` table checked and turned into a `Camera`.

use glam::Vec3;

use super::file::{fmt3, CameraFile};
use super::obj::MAX_COORDINATE;
use super::{Camera, SceneError};

/// Largest width or height of an image, the same for scene files, suite files and every
/// `WxH` flag: Vulkan's guaranteed maxImageDimension2D on desktop GPUs, and a frame larger
/// than that is a typo. Whether a size fits the device's buffers is checked before rendering.
pub const MAX_RESOLUTION: u32 = 16384;

pub fn build(file: &str, c: &CameraFile) -> Result<Camera, SceneError> {
    let invalid = |field: &str, value: String, problem: &str| SceneError::Invalid {
        file: file.to_string(),
        field: format!("camera.{field}"),
        value,
        problem: problem.to_string(),
    };
    for (field, v) in [
        ("position", c.position),
        ("look_at", c.look_at),
        ("up", c.up),
    ] {
        if !v.iter().all(|x| x.is_finite()) {
            return Err(invalid(field, fmt3(v), "must be finite"));
        }
    }
    // Beyond the vertices' limit the view direction's f32 arithmetic overflows (at 1e30,
    // look_at - position squared is infinite and the direction came out zero).
    for (field, v) in [("position", c.position), ("look_at", c.look_at)] {
        if v.iter().any(|x| x.abs() > MAX_COORDINATE) {
            return Err(invalid(
                field,
                fmt3(v),
                &format!(
                    "a coordinate's magnitude is over {MAX_COORDINATE:e}, the most irad's f32 \
                     rays handle (scale the scene down)"
                ),
            ));
        }
    }
    if !(c.fov_y > 0.0 && c.fov_y < 180.0) {
        return Err(invalid(
            "fov_y",
            c.fov_y.to_string(),
            "must be in (0, 180) degrees",
        ));
    }
    let [w, h] = c.resolution;
    let range = 1..=i64::from(MAX_RESOLUTION);
    if !range.contains(&w) || !range.contains(&h) {
        return Err(invalid(
            "resolution",
            format!("[{w}, {h}]"),
            &format!("width and height must be in 1..={MAX_RESOLUTION}"),
        ));
    }
    let position = Vec3::from(c.position);
    let look_at = Vec3::from(c.look_at);
    let up = Vec3::from(c.up);
    let forward = (look_at - position).normalize_or_zero();
    if forward == Vec3::ZERO {
        return Err(invalid(
            "look_at",
            fmt3(c.look_at),
            "equals camera.position: the view direction is undefined",
        ));
    }
    if forward.cross(up.normalize_or_zero()).length() < 1e-6 {
        return Err(invalid(
            "up",
            fmt3(c.up),
            &format!(
                "is zero or parallel to the view direction {}",
                fmt3(forward.to_array())
            ),
        ));
    }
    Ok(Camera {
        position,
        look_at,
        up,
        fov_y: c.fov_y,
        width: w as u32,
        height: h as u32,
    })
}

impl Camera {
    /// (forward, right, true_up), unit vectors, as the `Camera` doc defines them.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        (forward, right, right.cross(forward))
    }

    /// The unit direction through image point (x, y) in pixels (pixel (i, j) covers
    /// [i, i + 1) x [j, j + 1), y down), as write_gbuffer.comp computes it.
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        let (forward, right, up) = self.basis();
        let t = (self.fov_y.to_radians() * 0.5).tan();
        let (w, h) = (self.width as f32, self.height as f32);
        let a = (2.0 * x / w - 1.0) * t * w / h;
        let b = (1.0 - 2.0 * y / h) * t;
        (forward + a * right + b * up).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> CameraFile {
        CameraFile {
            position: [0.0, 1.0, 3.4],
            look_at: [0.0, 1.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y: 40.0,
            resolution: [256, 128],
        }
    }

    fn message(c: CameraFile) -> String {
        build("s.toml", &c).unwrap_err().to_string()
    }

    #[test]
    fn a_good_camera_is_kept_as_given() {
        let c = build("s.toml", &camera()).unwrap();
        assert_eq!((c.width, c.height, c.fov_y), (256, 128, 40.0));
        assert_eq!(c.up, Vec3::Y);
    }

    #[test]
    fn a_camera_beyond_the_coordinate_limit_is_named_as_such() {
        // At 1e30 the view direction's arithmetic overflows: this was reported as "look_at
        // equals camera.position".
        let m = message(CameraFile {
            position: [0.0, 0.0, 1e30],
            ..camera()
        });
        assert!(
            m.contains("camera.position = [0, 0, 1000000000000000000000000000000]")
                && m.contains("magnitude is over 1e8"),
            "{m}"
        );
        let m = message(CameraFile {
            look_at: [-2e8, 0.0, 0.0],
            ..camera()
        });
        assert!(
            m.contains("camera.look_at") && m.contains("over 1e8"),
            "{m}"
        );
        assert!(build(
            "s.toml",
            &CameraFile {
                position: [0.0, 1.0, 1e8],
                ..camera()
            }
        )
        .is_ok());
    }

    #[test]
    fn each_bad_field_is_named() {
        let m = message(CameraFile {
            look_at: [0.0, 1.0, 3.4],
            ..camera()
        });
        assert!(m.contains("camera.look_at = [0, 1, 3.4]"), "{m}");
        let m = message(CameraFile {
            up: [0.0, 0.0, -2.0],
            ..camera()
        });
        assert!(
            m.contains("camera.up = [0, 0, -2]") && m.contains("parallel"),
            "{m}"
        );
        let m = message(CameraFile {
            up: [0.0; 3],
            ..camera()
        });
        assert!(m.contains("camera.up = [0, 0, 0]"), "{m}");
        let m = message(CameraFile {
            fov_y: 180.0,
            ..camera()
        });
        assert!(m.contains("camera.fov_y = 180"), "{m}");
        let m = message(CameraFile {
            resolution: [-4, 4],
            ..camera()
        });
        assert!(m.contains("camera.resolution = [-4, 4]"), "{m}");
        let m = message(CameraFile {
            position: [f32::NAN, 0.0, 0.0],
            ..camera()
        });
        assert!(m.contains("camera.position = [NaN, 0, 0]"), "{m}");
    }
}
