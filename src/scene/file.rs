//! The scene file's TOML schema (docs/DESIGN.md "Scene files"), deserialized with unknown fields
//! refused. Values are checked where they become scene types (camera.rs, lights.rs, ...).

use serde::Deserialize;

use super::toml_arrays::{exact, exact_opt};
use super::SceneError;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub camera: CameraFile,
    #[serde(default)]
    pub mesh: Vec<MeshFile>,
    #[serde(default)]
    pub light: Vec<LightFile>,
    pub environment: Option<EnvironmentFile>,
    /// Light-field luminaires (scene/luminaire/), placed in the scene.
    #[serde(default)]
    pub luminaire: Vec<LuminairePlacementFile>,
    pub failure: Option<FailureFile>,
    /// Keyframed tracks over animation frames (scene/animation.rs).
    pub animation: Option<AnimationFile>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimationFile {
    /// Signed so that zero and negative counts get the loader's message, not serde's.
    pub frames: i64,
    /// Frames per second: key times are in seconds, frame f at f / fps.
    #[serde(default = "default_fps")]
    pub fps: f32,
    #[serde(default)]
    pub track: Vec<TrackFile>,
}

fn default_fps() -> f32 {
    24.0
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackFile {
    /// What the track moves: `camera.position`, `light[0].intensity`, ...
    pub target: String,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// One value a key: a number or an [x, y, z] array, as the target takes.
    pub values: Vec<KeyValue>,
    /// `linear` (the default) or `smooth` (a Catmull-Rom spline through the keys).
    pub interpolation: Option<String>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum KeyValue {
    Number(f32),
    Array(Vec<f32>),
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    #[serde(deserialize_with = "exact")]
    pub position: [f32; 3],
    #[serde(deserialize_with = "exact")]
    pub look_at: [f32; 3],
    #[serde(default = "default_up", deserialize_with = "exact")]
    pub up: [f32; 3],
    pub fov_y: f32,
    /// Signed so that zero and negative sizes get the loader's message, not serde's.
    #[serde(deserialize_with = "exact")]
    pub resolution: [i64; 2],
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshFile {
    /// The OBJ file; `.gz` for one stored gzip-compressed (read as a stream).
    pub obj: String,
    /// An MTL file whose materials `groups` names, for an OBJ without its own (relative to
    /// the OBJ's folder, as its own `mtllib` lines are).
    #[serde(default)]
    pub mtl: Option<String>,
    /// Each OBJ group (`g NAME`) to a material of `mtl`: every group of the OBJ must be named
    /// (or `"*"` gives the material of the groups not named).
    #[serde(default)]
    pub groups: Option<std::collections::BTreeMap<String, String>>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightFile {
    pub kind: String,
    #[serde(deserialize_with = "exact")]
    pub position: [f32; 3],
    #[serde(deserialize_with = "exact")]
    pub intensity: [f32; 3],
    #[serde(default, deserialize_with = "exact_opt")]
    pub direction: Option<[f32; 3]>,
    pub cone_angle: Option<f32>,
    pub falloff_angle: Option<f32>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LuminairePlacementFile {
    /// The luminaire's TOML, relative to the scene file.
    pub path: String,
    /// Where the luminaire's filter-plane origin sits.
    #[serde(deserialize_with = "exact")]
    pub position: [f32; 3],
    /// A point the luminaire's +z (its emission axis) points at.
    #[serde(deserialize_with = "exact")]
    pub look_at: [f32; 3],
    /// The world direction the luminaire's +y leans toward (default +Y; -Z when aimed
    /// straight up or down).
    #[serde(default, deserialize_with = "exact_opt")]
    pub up: Option<[f32; 3]>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentFile {
    /// An equirectangular EXR, or a glob (`*`, `?` in the file name) naming a sequence: one
    /// map per frame, in file-name order.
    pub exr: Option<String>,
    /// A built-in procedural sky instead of `exr`: "moving-sun" or "rising-sun" (src/scene/sky.rs).
    pub sky: Option<String>,
    /// sky: texels across and down (signed so that bad sizes get the loader's message).
    #[serde(default, deserialize_with = "exact_opt")]
    pub size: Option<[i64; 2]>,
    /// sky: frames in one revolution of the sun (one map per frame).
    pub frames: Option<i64>,
    /// sky: the sun's elevation above the horizon, degrees.
    pub sun_elevation: Option<f32>,
    /// sky: the sun disk's angular radius, degrees.
    pub sun_radius: Option<f32>,
    /// sky: the sun disk's radiance.
    #[serde(default, deserialize_with = "exact_opt")]
    pub sun_radiance: Option<[f32; 3]>,
    #[serde(default = "default_scale")]
    pub scale: f32,
}

fn default_scale() -> f32 {
    1.0
}

/// `[failure]`: the methods a stability-suite scene is expected to defeat, and why.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FailureFile {
    pub methods: Vec<String>,
    pub why: String,
    pub source: String,
}

/// Parses the scene file's text; `file` names it in messages.
pub fn parse(file: &str, text: &str) -> Result<SceneFile, SceneError> {
    toml::from_str(text).map_err(|e| SceneError::Toml {
        file: file.to_string(),
        message: e.to_string().trim_end().to_string(),
    })
}

/// `[a, b, c]` with f32 Display (NaN and inf spelled out), for messages.
pub fn fmt3(v: [f32; 3]) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str =
        "[camera]\nposition = [0, 1, 3]\nlook_at = [0, 1, 0]\nfov_y = 40\nresolution = [4, 3]\n";

    #[test]
    fn integers_are_accepted_where_floats_are_expected() {
        let f = parse("s.toml", MINIMAL).unwrap();
        assert_eq!(f.camera.position, [0.0, 1.0, 3.0]);
        assert_eq!(f.camera.up, [0.0, 1.0, 0.0]);
        assert!(f.mesh.is_empty() && f.light.is_empty() && f.environment.is_none());
        assert!(f.failure.is_none());
    }

    #[test]
    fn unknown_nested_field_is_refused_with_its_name_and_line() {
        let text = format!("{MINIMAL}[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\ncolour = 3\n");
        let e = parse("s.toml", &text).unwrap_err().to_string();
        assert!(e.starts_with("s.toml: "), "{e}");
        assert!(e.contains("colour") && e.contains("line 10"), "{e}");
    }

    #[test]
    fn environment_scale_defaults_to_one() {
        let text = format!("{MINIMAL}[environment]\nexr = \"sky.exr\"\n");
        assert_eq!(
            parse("s.toml", &text).unwrap().environment.unwrap().scale,
            1.0
        );
    }

    #[test]
    fn failure_table_is_parsed() {
        let text = format!(
            "{MINIMAL}[failure]\nmethods = [\"ir\", \"bir\"]\nwhy = \"VPLs starve.\"\n\
             source = \"Segovia 06, Fig. 4\"\n"
        );
        let f = parse("s.toml", &text).unwrap().failure.unwrap();
        assert_eq!(f.methods, ["ir", "bir"]);
        assert_eq!(
            (f.why.as_str(), f.source.as_str()),
            ("VPLs starve.", "Segovia 06, Fig. 4")
        );
    }

    #[test]
    fn unknown_field_in_failure_is_refused() {
        let text = format!(
            "{MINIMAL}[failure]\nmethods = [\"ir\"]\nwhy = \"w\"\nsource = \"s\"\nseverity = 2\n"
        );
        let e = parse("s.toml", &text).unwrap_err().to_string();
        assert!(e.starts_with("s.toml: "), "{e}");
        assert!(
            e.contains("unknown field `severity`") && e.contains("line 10"),
            "{e}"
        );
    }

    #[test]
    fn failure_fields_are_required() {
        let text = format!("{MINIMAL}[failure]\nmethods = [\"ir\"]\nwhy = \"w\"\n");
        let e = parse("s.toml", &text).unwrap_err().to_string();
        assert!(e.contains("missing field `source`"), "{e}");
    }
}
