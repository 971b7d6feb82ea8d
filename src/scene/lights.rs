//! `[[light]]` tables checked and turned into point and spot `Light`s.

use glam::Vec3;

use super::file::{fmt3, LightFile};
use super::obj::MAX_COORDINATE;
use super::{Light, SceneError};

/// Builds `light[index]`.
pub fn build(file: &str, index: usize, l: &LightFile) -> Result<Light, SceneError> {
    let invalid = |field: &str, value: String, problem: &str| SceneError::Invalid {
        file: file.to_string(),
        field: format!("light[{index}].{field}"),
        value,
        problem: problem.to_string(),
    };
    if !l.position.iter().all(|x| x.is_finite()) {
        return Err(invalid("position", fmt3(l.position), "must be finite"));
    }
    if l.position.iter().any(|x| x.abs() > MAX_COORDINATE) {
        return Err(invalid(
            "position",
            fmt3(l.position),
            &format!(
                "a coordinate's magnitude is over {MAX_COORDINATE:e}, the most irad's f32 rays \
                 handle (scale the scene down)"
            ),
        ));
    }
    if !l.intensity.iter().all(|x| x.is_finite() && *x >= 0.0) {
        return Err(invalid(
            "intensity",
            fmt3(l.intensity),
            "must be finite and >= 0 in every channel",
        ));
    }
    let position = Vec3::from(l.position);
    let intensity = Vec3::from(l.intensity);
    match l.kind.as_str() {
        "point" => {
            let spot_only = [
                ("direction", l.direction.map(fmt3)),
                ("cone_angle", l.cone_angle.map(|a| a.to_string())),
                ("falloff_angle", l.falloff_angle.map(|a| a.to_string())),
            ];
            if let Some((field, Some(value))) = spot_only.into_iter().find(|(_, v)| v.is_some()) {
                return Err(invalid(
                    field,
                    value,
                    "is for spot lights only; this light has kind = \"point\"",
                ));
            }
            Ok(Light::Point {
                position,
                intensity,
            })
        }
        "spot" => {
            let missing = |field: &str| SceneError::Invalid {
                file: file.to_string(),
                field: format!("light[{index}].{field}"),
                value: "(missing)".to_string(),
                problem: "is required for a spot light".to_string(),
            };
            let d = l.direction.ok_or_else(|| missing("direction"))?;
            let cone = l.cone_angle.ok_or_else(|| missing("cone_angle"))?;
            let falloff = l.falloff_angle.ok_or_else(|| missing("falloff_angle"))?;
            let direction = Vec3::from(d).normalize_or_zero();
            if !d.iter().all(|x| x.is_finite()) || direction == Vec3::ZERO {
                return Err(invalid("direction", fmt3(d), "must be finite and non-zero"));
            }
            for (field, a) in [("cone_angle", cone), ("falloff_angle", falloff)] {
                if !(a > 0.0 && a <= 180.0) {
                    return Err(invalid(field, a.to_string(), "must be in (0, 180] degrees"));
                }
            }
            if cone > falloff {
                return Err(invalid(
                    "cone_angle",
                    cone.to_string(),
                    &format!("must be <= falloff_angle ({falloff})"),
                ));
            }
            Ok(Light::Spot {
                position,
                intensity,
                direction,
                cone_angle: cone,
                falloff_angle: falloff,
            })
        }
        other => Err(invalid(
            "kind",
            format!("{other:?}"),
            "must be \"point\" or \"spot\"",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot() -> LightFile {
        LightFile {
            kind: "spot".into(),
            position: [0.0, 2.0, 0.0],
            intensity: [1.0, 2.0, 3.0],
            direction: Some([0.0, -2.0, 0.0]),
            cone_angle: Some(20.0),
            falloff_angle: Some(30.0),
        }
    }

    #[test]
    fn spot_direction_is_normalized() {
        match build("s.toml", 0, &spot()).unwrap() {
            Light::Spot { direction, .. } => assert_eq!(direction, -Vec3::Y),
            l => panic!("{l:?}"),
        }
    }

    #[test]
    fn bad_values_are_named() {
        let cases = [
            (
                LightFile {
                    intensity: [1.0, -1.0, 0.0],
                    ..spot()
                },
                "light[2].intensity = [1, -1, 0]",
            ),
            (
                LightFile {
                    direction: Some([0.0; 3]),
                    ..spot()
                },
                "light[2].direction = [0, 0, 0]",
            ),
            (
                LightFile {
                    cone_angle: Some(40.0),
                    ..spot()
                },
                "light[2].cone_angle = 40",
            ),
            (
                LightFile {
                    falloff_angle: Some(190.0),
                    ..spot()
                },
                "light[2].falloff_angle = 190",
            ),
            (
                LightFile {
                    falloff_angle: None,
                    ..spot()
                },
                "light[2].falloff_angle = (missing)",
            ),
            (
                LightFile {
                    kind: "area".into(),
                    ..spot()
                },
                "light[2].kind = \"area\"",
            ),
            (
                LightFile {
                    kind: "point".into(),
                    ..spot()
                },
                "light[2].direction = [0, -2, 0]",
            ),
        ];
        for (light, expected) in cases {
            let m = build("s.toml", 2, &light).unwrap_err().to_string();
            assert!(m.starts_with("s.toml: ") && m.contains(expected), "{m}");
        }
    }
}
