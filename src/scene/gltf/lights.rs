//! KHR_lights_punctual lights as irad's point and spot lights. glTF gives intensity in candela
//! (lm/sr); irad's lights are in unitless radiometric W/sr, so 1 cd is read as 1 W/sr, times
//! the light's linear colour (no 683 lm/W: irad has no photometric units). A spot's inner and
//! outer cone angles become cone_angle and falloff_angle; glTF's falloff between them (the
//! square of a ramp linear in cos theta) is read as irad's smoothstep in cos theta, which
//! differs from it by at most 8/27 = 0.30 of the intensity (2 t^2 (1 - t) at t = 2/3).
//! Directional lights are skipped with a warning (irad has none); `range` is ignored with a
//! warning (irad's lights fall off as 1/d^2 everywhere).

use glam::{DMat4, DVec3};
use gltf::khr_lights_punctual::Kind;

use super::Ctx;
use crate::scene::file::LightFile;
use crate::scene::{Light, SceneError};

/// The smallest cone_angle (degrees) a spot's inner angle is read as: glTF's default inner
/// angle is 0, irad's cone must be positive.
pub const MIN_CONE: f32 = 1e-3;

/// The light `light` placed by `world` (node `node`) as the scene's light number `count`, or
/// None for a directional light (with a warning).
pub fn punctual(
    ctx: &mut Ctx,
    light: &gltf::khr_lights_punctual::Light,
    node: usize,
    world: DMat4,
    count: usize,
) -> Result<Option<Light>, SceneError> {
    let field = super::label(
        &format!("extensions.KHR_lights_punctual.lights[{}]", light.index()),
        light.name(),
    );
    let colour = glam::Vec3::from(light.color());
    let intensity = colour * light.intensity();
    if let Some(range) = light.range() {
        ctx.warn(format!(
            "{field}: range {range} is ignored (irad's lights fall off as 1/d^2 at every \
             distance)"
        ));
    }
    let position = world.transform_point3(DVec3::ZERO).as_vec3().to_array();
    let direction = world
        .transform_vector3(DVec3::NEG_Z)
        .normalize_or_zero()
        .as_vec3()
        .to_array();
    let file = LightFile {
        kind: "point".into(),
        position,
        intensity: intensity.to_array(),
        direction: None,
        cone_angle: None,
        falloff_angle: None,
    };
    let file = match light.kind() {
        Kind::Directional => {
            ctx.warn(format!(
                "{field} on nodes[{node}]: a directional light is skipped (irad has none)"
            ));
            ctx.skipped_directional.get_or_insert(field);
            return Ok(None);
        }
        Kind::Point => file,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let (inner, outer) = (inner_cone_angle.to_degrees(), outer_cone_angle.to_degrees());
            if !(inner >= 0.0 && inner < outer && outer <= 90.0) {
                return Err(ctx.invalid(
                    &format!("{field}.spot"),
                    &format!(
                        "innerConeAngle {inner_cone_angle}, outerConeAngle {outer_cone_angle}"
                    ),
                    "needs 0 <= innerConeAngle < outerConeAngle <= pi / 2",
                ));
            }
            ctx.warn(format!(
                "{field}: the spot's falloff (glTF's square of a ramp in cos theta) as irad's \
                 smoothstep in cos theta between the same angles, {inner} and {outer} degrees \
                 (at most 0.30 of the intensity apart)"
            ));
            LightFile {
                kind: "spot".into(),
                direction: Some(direction),
                cone_angle: Some(inner.max(MIN_CONE)),
                falloff_angle: Some(outer),
                ..file
            }
        }
    };
    // The TOML lights' checks (finite, within the coordinate limit, intensity >= 0).
    crate::scene::lights::build(
        &format!("{} ({field} on nodes[{node}])", ctx.file),
        count,
        &file,
    )
    .map(Some)
}
