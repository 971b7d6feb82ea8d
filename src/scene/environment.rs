//! The `[environment]` table: an equirectangular RGB OpenEXR map (docs/DESIGN.md "Conventions"),
//! checked texel by texel and multiplied by `scale`; or a sequence of them (a glob, one map per
//! frame); or a built-in procedural sky (sky.rs).

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::file::EnvironmentFile;
use super::{Environment, SceneError};

/// Whether `exr` names a sequence (a glob) rather than one file.
pub fn is_glob(exr: &str) -> bool {
    exr.contains(['*', '?', '[', '{'])
}

/// Checks `[environment]`: one of `exr` and `sky`, the sky's fields only with `sky`, a glob
/// only in the file name and with `*` and `?` only, and `scale`; `file` is the scene file.
pub fn check(file: &str, env: &EnvironmentFile) -> Result<(), SceneError> {
    let invalid = |field: &str, value: String, problem: &str| SceneError::Invalid {
        file: file.to_string(),
        field: format!("environment.{field}"),
        value,
        problem: problem.into(),
    };
    match (&env.exr, &env.sky) {
        (Some(exr), Some(sky)) => {
            return Err(invalid(
                "sky",
                format!("{sky:?}"),
                &format!("give exr ({exr:?}) or sky, not both"),
            ))
        }
        (None, None) => {
            return Err(invalid(
                "exr",
                "(missing)".into(),
                "give exr (a map or a glob naming a sequence) or sky = \"moving-sun\"",
            ))
        }
        (Some(exr), None) => {
            let sky_fields = [
                ("size", env.size.is_some()),
                ("frames", env.frames.is_some()),
                ("sun_elevation", env.sun_elevation.is_some()),
                ("sun_radius", env.sun_radius.is_some()),
                ("sun_radiance", env.sun_radiance.is_some()),
            ];
            if let Some((field, _)) = sky_fields.iter().find(|f| f.1) {
                return Err(invalid(
                    field,
                    "(given)".into(),
                    "applies to sky only, not to exr",
                ));
            }
            if is_glob(exr) {
                let (dir, name) = split_glob(exr);
                if is_glob(&dir.to_string_lossy()) || name.contains(['[', '{']) {
                    return Err(SceneError::Unsupported {
                        file: file.to_string(),
                        field: "environment.exr".into(),
                        value: format!("{exr:?}"),
                        what: "globs other than * and ? in the file name".into(),
                    });
                }
            }
        }
        (None, Some(_)) => {}
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

/// How many times as wide as tall a map may be: weigh_env_pyramid.comp's leaves (H' >= H rows
/// of W' = 2 H' columns, env_pyramid.glsl) each search at most (W / 2H' + 2) x 2 map texels in
/// one loop, about 16k at this ratio, a quarter of lavapipe's loop budget of 65535 iterations
/// an invocation. The built-in sky is at most 16384 x 1.
pub const MAX_ASPECT: u64 = 16384;

/// Reads the map at `path` (named `display` in messages) and scales it; every texel must be
/// finite and non-negative, before and after scaling.
/// At most `MAX_ASPECT` times as wide as tall.
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
    if image.width as u64 > MAX_ASPECT * image.height as u64 {
        return Err(SceneError::Invalid {
            file: display.to_string(),
            field: "size".into(),
            value: format!("{}x{}", image.width, image.height),
            problem: format!(
                "an equirectangular map may be at most {MAX_ASPECT} times as wide as tall (2:1 \
                 is usual): each leaf of env's hierarchical sampler searches the map texels it \
                 covers in one loop, which must stay within the device's loop budget"
            ),
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

/// A glob's folder (literal) and file-name pattern.
pub fn split_glob(pattern: &str) -> (PathBuf, String) {
    let path = Path::new(pattern);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    (
        path.parent().map(Path::to_path_buf).unwrap_or_default(),
        name,
    )
}

/// Whether `name` matches `pattern`: `*` any run of characters, `?` any one.
pub fn glob_matches(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    // Positions in the pattern and the name, and where to resume after the last `*`.
    let (mut i, mut j, mut star, mut resume) = (0, 0, None, 0);
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || p[i] == n[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some(i);
            resume = j;
            i += 1;
        } else if let Some(s) = star {
            i = s + 1;
            resume += 1;
            j = resume;
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

/// The files in `dir` whose names match `pattern`, sorted by name.
pub fn expand_glob(dir: &Path, pattern: &str) -> std::io::Result<Vec<PathBuf>> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok())
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .filter(|e| glob_matches(pattern, &e.file_name().to_string_lossy()))
        .map(|e| e.path())
        .collect();
    found.sort();
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_far_wider_than_tall_are_refused_by_name() {
        let dir = std::env::temp_dir().join(format!("irad-env-aspect-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("wide.exr");
        let w = MAX_ASPECT as u32 + 1;
        let image = crate::image::Image::new(w, 1);
        crate::image::exr::write(&path, &image).unwrap();
        let e = read("wide.exr", &path, 1.0).unwrap_err().to_string();
        assert!(
            e.contains("wide.exr") && e.contains(&format!("{w}x1")),
            "{e}"
        );
        assert!(e.contains("16384 times as wide as tall"), "{e}");
        let path = dir.join("ok.exr");
        crate::image::exr::write(&path, &crate::image::Image::new(w - 1, 1)).unwrap();
        assert!(read("ok.exr", &path, 1.0).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn globs_are_recognized() {
        assert!(is_glob("sky/*.exr") && is_glob("sky_??.exr"));
        assert!(!is_glob("sky.exr") && !is_glob("skies/noon-2.exr"));
    }

    #[test]
    fn glob_matching() {
        assert!(glob_matches("sky_*.exr", "sky_0001.exr"));
        assert!(glob_matches("sky_*.exr", "sky_.exr"));
        assert!(glob_matches("*", "anything"));
        assert!(glob_matches("s?y_*_*.exr", "sky_a_b.exr"));
        assert!(glob_matches("*a*b", "xxaxxb"));
        assert!(!glob_matches("sky_*.exr", "sky_0001.png"));
        assert!(!glob_matches("sky_??.exr", "sky_1.exr"));
        assert!(!glob_matches("*a*b", "xxbxxa"));
        assert_eq!(
            split_glob("frames/sky_*.exr"),
            ("frames".into(), "sky_*.exr".into())
        );
        assert_eq!(split_glob("sky_*.exr"), ("".into(), "sky_*.exr".into()));
    }
}
