//! glTF cameras as irad's pinhole camera: a perspective camera looks down its node's -z with
//! +y up; `yfov` is the vertical field of view; the image is 640 pixels wide and
//! round(640 / aspectRatio) high (640 x 480 without an aspect ratio). Orthographic cameras are
//! refused. A file with no camera gets one that frames the scene's bounds, with a warning.

use glam::{DMat4, DVec3, Vec3};
use gltf::json::camera::Type;

use super::Ctx;
use crate::scene::file::CameraFile;
use crate::scene::{Camera, SceneError, Triangle, MAX_RESOLUTION};

/// The image width given to glTF cameras (glTF has none).
pub const WIDTH: u32 = 640;
/// The height where the camera gives no aspect ratio (4:3).
pub const HEIGHT: u32 = 480;
/// The vertical field of view of the camera made for a file with none, in degrees.
pub const FRAMING_FOV_Y: f32 = 45.0;

/// Camera `index` of the file, placed by `world` (the transform of node `node`).
pub fn perspective(
    ctx: &Ctx,
    doc: &gltf::Document,
    index: usize,
    node: usize,
    world: DMat4,
) -> Result<Camera, SceneError> {
    let json = &doc.as_json().cameras[index];
    let field = format!("cameras[{index}]");
    let label = super::label(&field, json.name.as_deref());
    let perspective = match (json.type_, &json.perspective) {
        (gltf::json::validation::Checked::Valid(Type::Perspective), Some(p)) => p,
        (gltf::json::validation::Checked::Valid(Type::Perspective), None) => {
            return Err(ctx.invalid(
                &format!("{field}.perspective"),
                "(missing)",
                "a perspective camera needs its `perspective` parameters",
            ))
        }
        _ => {
            return Err(SceneError::Unsupported {
                file: ctx.file.clone(),
                field: format!("{field}.type"),
                value: "\"orthographic\"".into(),
                what: format!(
                    "orthographic cameras ({label} is one; the file has {} cameras, and \
                     `irad render --camera N` picks another)",
                    doc.cameras().len()
                ),
            })
        }
    };
    let height = match perspective.aspect_ratio {
        None => HEIGHT,
        Some(a) => {
            let h = (f64::from(WIDTH) / f64::from(a)).round();
            if !(a.is_finite() && a > 0.0 && h >= 1.0 && h <= f64::from(MAX_RESOLUTION)) {
                return Err(ctx.invalid(
                    &format!("{field}.perspective.aspectRatio"),
                    &a.to_string(),
                    &format!(
                        "must be positive, giving a {WIDTH}-pixel-wide image 1 to \
                         {MAX_RESOLUTION} pixels high"
                    ),
                ));
            }
            h as u32
        }
    };
    if world.determinant() <= 0.0 {
        return Err(ctx.invalid(
            &format!("nodes[{node}]"),
            &format!("determinant {}", world.determinant()),
            &format!(
                "the transform placing {label} mirrors or collapses the view (a negative or \
                 zero scale), which irad's camera cannot"
            ),
        ));
    }
    let position = world.transform_point3(DVec3::ZERO);
    let forward = world.transform_vector3(DVec3::NEG_Z).normalize();
    let up = world.transform_vector3(DVec3::Y).normalize();
    let file = CameraFile {
        position: position.as_vec3().to_array(),
        look_at: (position + forward).as_vec3().to_array(),
        up: up.as_vec3().to_array(),
        fov_y: perspective.yfov.to_degrees(),
        resolution: [i64::from(WIDTH), i64::from(height)],
    };
    crate::scene::camera::build(&format!("{} ({label} on nodes[{node}])", ctx.file), &file)
}

/// A camera on the +z side of the triangles' bounds, looking down -z (glTF's default view
/// direction) at their centre, far enough that their bounding sphere fits the view.
pub fn framing(ctx: &Ctx, triangles: &[Triangle]) -> Result<Camera, SceneError> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in triangles.iter().flat_map(|t| t.positions) {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let centre = (lo.as_dvec3() + hi.as_dvec3()) / 2.0;
    let radius = ((hi.as_dvec3() - lo.as_dvec3()).length() / 2.0).max(1e-3);
    let half = f64::from(FRAMING_FOV_Y).to_radians() / 2.0;
    let position = centre + DVec3::Z * (radius / half.sin());
    let file = CameraFile {
        position: position.as_vec3().to_array(),
        look_at: centre.as_vec3().to_array(),
        up: [0.0, 1.0, 0.0],
        fov_y: FRAMING_FOV_Y,
        resolution: [i64::from(WIDTH), i64::from(HEIGHT)],
    };
    crate::scene::camera::build(
        &format!("{} (the camera made to frame it)", ctx.file),
        &file,
    )
}
