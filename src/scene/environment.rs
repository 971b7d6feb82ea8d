//! The `[environment]` table: an equirectangular RGB OpenEXR map (DESIGN.md "Conventions"),
//! checked texel by texel and multiplied by `scale`.

use std::path::Path;

use glam::Vec3;

use super::file::EnvironmentFile;
use super::{Environment, SceneError};

/// Whether `exr` names a sequence (a glob) rather than one file.
pub fn is_glob(exr: &str) -> bool {
    exr.contains(['*', '?', '[', '{'])
}

/// Checks `environment.scale` and refuses sequences; `file` is the scene file.
pub fn check(file: &str, env: &EnvironmentFile) -> Result<(), SceneError> {
    if is_glob(&env.exr) {
        return Err(SceneError::Unsupported {
            file: file.to_string(),
            field: "environment.exr".into(),
            value: format!("{:?}", env.exr),
            what: "environment map sequences (globs)".into(),
        });
    }
    if !(env.scale.is_finite() && env.scale >= 0.0) {
        return Err(SceneError::Invalid {
            file: file.to_string(),
            field: "environment.scale".into(),
            value: env.scale.to_string(),
            problem: "must be finite and >= 0".into(),
        });
    }
    Ok(())
}

/// Reads the map at `path` (named `display` in messages) and scales it; every texel must be
/// finite and non-negative, before and after scaling.
pub fn read(display: &str, path: &Path, scale: f32) -> Result<Environment, SceneError> {
    let image = crate::image::exr::read(path).map_err(|e| SceneError::File {
        file: display.to_string(),
        message: format!("environment.exr: {e:#}"),
    })?;
    if image.width == 0 || image.height == 0 {
        return Err(SceneError::Invalid {
            file: display.to_string(),
            field: "size".into(),
            value: format!("{}x{}", image.width, image.height),
            problem: "an environment map needs at least one texel".into(),
        });
    }
    let mut texels = Vec::with_capacity(image.pixels.len());
    for (k, p) in image.pixels.iter().enumerate() {
        let v = Vec3::from(*p);
        let scaled = v * scale;
        if !(v.is_finite() && v.min_element() >= 0.0 && scaled.is_finite()) {
            let (x, y) = (k as u32 % image.width, k as u32 / image.width);
            return Err(SceneError::Invalid {
                file: display.to_string(),
                field: format!("texel (x {x}, y {y})"),
                value: format!("[{}, {}, {}]", p[0], p[1], p[2]),
                problem: if v.is_finite() && v.min_element() >= 0.0 {
                    format!("becomes infinite times environment.scale = {scale}")
                } else {
                    "radiance must be finite and >= 0 in every channel".into()
                },
            });
        }
        texels.push(scaled);
    }
    Ok(Environment {
        width: image.width,
        height: image.height,
        texels,
        source: path.to_path_buf(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn globs_are_recognized() {
        assert!(is_glob("sky/*.exr") && is_glob("sky_??.exr"));
        assert!(!is_glob("sky.exr") && !is_glob("skies/noon-2.exr"));
    }
}
