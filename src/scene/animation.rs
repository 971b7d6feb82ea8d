//! Animated scenes: a frame count and rate and keyframed tracks over what a scene's light and
//! view need to move (docs/DESIGN.md "Animation"): the camera (position, look_at, fov_y), each
//! analytic light (position, direction, intensity), an emissive material's radiance scale
//! (lights switching on and off), the environment's rotation about +Y, and each luminaire's
//! placement (position, look_at). A map sequence or procedural sky shows map f mod n at
//! animation frame f, a luminaire's atlas sequence atlas f mod n. Geometry does not move: every
//! frame shares the scene's triangles, so one BVH serves the whole sequence.
//!
//! A track's keys are (time in seconds, value); frame f is at time f / fps; before the first
//! key a track holds its first value, after the last its last. Linear interpolation, or
//! `smooth`: the cubic Hermite spline with Catmull-Rom tangents (the neighbouring keys' slope,
//! one-sided at the ends), which passes through every key.
//!
//! Every frame's state is built through the same builders as the scene file's own tables
//! (camera.rs, lights.rs, the luminaire placement), at load, so a track that leaves a field's
//! range at some frame (a smooth track overshooting below zero, a camera at its look_at) is
//! refused naming the field, the frame and the value.

use glam::Vec3;

use super::file::{AnimationFile, CameraFile, KeyValue, LightFile, LuminairePlacementFile};
use super::luminaire::PlacedLuminaire;
use super::{camera, lights, Camera, Environment, Light, Material, Scene, SceneError};

/// Most frames of an animation: a sequence's files are numbered with four digits
/// (frame_NNNN), and 10000 frames is about 7 minutes at 24 fps.
pub const MAX_FRAMES: u32 = 10000;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Linear,
    Smooth,
}

/// What a track moves.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    CameraPosition,
    CameraLookAt,
    CameraFov,
    LightPosition(usize),
    LightDirection(usize),
    LightIntensity(usize),
    /// The materials of one name (each mesh reads its own copy of an MTL) whose Ke is scaled:
    /// the name and their indices.
    Emission(String, Vec<usize>),
    /// Degrees about +Y, right-handed.
    EnvironmentRotation,
    LuminairePosition(usize),
    LuminaireLookAt(usize),
}

impl Target {
    /// Whether the target takes one number (else an [x, y, z] array).
    fn scalar(&self) -> bool {
        matches!(
            self,
            Target::CameraFov | Target::Emission(..) | Target::EnvironmentRotation
        )
    }
}

/// The forms `target` takes, for messages.
const TARGETS: &str = "camera.position, camera.look_at, camera.fov_y, light[i].position, \
                       light[i].direction, light[i].intensity, material.NAME.emission, \
                       environment.rotation, luminaire[i].position, luminaire[i].look_at";

#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub target: Target,
    pub interpolation: Interpolation,
    /// Seconds, strictly increasing.
    pub times: Vec<f32>,
    /// One a key; a scalar target's value in x.
    pub values: Vec<Vec3>,
}

impl Track {
    /// The track's value at `t` seconds.
    pub fn at(&self, t: f32) -> Vec3 {
        let (times, values) = (&self.times, &self.values);
        let last = times.len() - 1;
        if t <= times[0] {
            return values[0];
        }
        if t >= times[last] {
            return values[last];
        }
        let k = times.partition_point(|&x| x <= t) - 1;
        let h = times[k + 1] - times[k];
        let u = (t - times[k]) / h;
        match self.interpolation {
            Interpolation::Linear => values[k].lerp(values[k + 1], u),
            Interpolation::Smooth => {
                let tangent = |i: usize| {
                    let (a, b) = (i.saturating_sub(1), (i + 1).min(last));
                    (values[b] - values[a]) / (times[b] - times[a])
                };
                let (u2, u3) = (u * u, u * u * u);
                let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
                let h10 = u3 - 2.0 * u2 + u;
                let h01 = -2.0 * u3 + 3.0 * u2;
                let h11 = u3 - u2;
                values[k] * h00
                    + tangent(k) * (h10 * h)
                    + values[k + 1] * h01
                    + tangent(k + 1) * (h11 * h)
            }
        }
    }
}

/// A scene's animation: its tracks, and the scene file's tables they start from, so each frame
/// is built by the file's own builders.
#[derive(Clone, Debug)]
pub struct Animation {
    pub frames: u32,
    pub fps: f32,
    pub tracks: Vec<Track>,
    file: String,
    camera: CameraFile,
    lights: Vec<LightFile>,
    luminaires: Vec<LuminairePlacementFile>,
}

/// What changes from one frame to the next: everything `Scene::at_frame` replaces.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameState {
    pub camera: Camera,
    pub lights: Vec<Light>,
    /// Each material's Ke scale (1 where no track moves it).
    pub emission: Vec<f32>,
    /// Degrees about +Y.
    pub environment_rotation: f32,
    /// Each luminaire's position and axes x, y, z.
    pub luminaires: Vec<[Vec3; 4]>,
}

impl Animation {
    /// Checks `[animation]` of scene `file` against the scene's tables and materials, and
    /// builds every frame once so that none is out of range.
    pub fn build(
        file: &str,
        a: &AnimationFile,
        camera: &CameraFile,
        lights: &[LightFile],
        luminaires: &[LuminairePlacementFile],
        materials: &[Material],
        has_environment: bool,
    ) -> Result<Animation, SceneError> {
        let invalid = |field: String, value: String, problem: String| SceneError::Invalid {
            file: file.to_string(),
            field,
            value,
            problem,
        };
        if !(1..=i64::from(MAX_FRAMES)).contains(&a.frames) {
            return Err(invalid(
                "animation.frames".into(),
                a.frames.to_string(),
                format!("must be in 1..={MAX_FRAMES}"),
            ));
        }
        if !(a.fps.is_finite() && a.fps > 0.0) {
            return Err(invalid(
                "animation.fps".into(),
                a.fps.to_string(),
                "must be a positive number of frames per second".into(),
            ));
        }
        let frames = a.frames as u32;
        let end = (frames - 1) as f32 / a.fps;
        let mut tracks = Vec::with_capacity(a.track.len());
        for (k, t) in a.track.iter().enumerate() {
            let field = |name: &str| format!("animation.track[{k}].{name}");
            let target = parse_target(&t.target, lights, luminaires, materials, has_environment)
                .map_err(|problem| invalid(field("target"), format!("{:?}", t.target), problem))?;
            let interpolation = match t.interpolation.as_deref() {
                None | Some("linear") => Interpolation::Linear,
                Some("smooth") => Interpolation::Smooth,
                Some(other) => {
                    return Err(invalid(
                        field("interpolation"),
                        format!("{other:?}"),
                        "must be \"linear\" or \"smooth\"".into(),
                    ))
                }
            };
            if t.times.is_empty() || t.times.len() != t.values.len() {
                return Err(invalid(
                    field("values"),
                    format!("{} value(s)", t.values.len()),
                    format!(
                        "a track needs at least one key and one value per time ({} time(s))",
                        t.times.len()
                    ),
                ));
            }
            for (i, &time) in t.times.iter().enumerate() {
                let value = format!("{time}");
                if !(time.is_finite() && time >= 0.0) {
                    return Err(invalid(
                        format!("{}[{i}]", field("times")),
                        value,
                        "must be a finite time >= 0 in seconds".into(),
                    ));
                }
                if i > 0 && time <= t.times[i - 1] {
                    return Err(invalid(
                        format!("{}[{i}]", field("times")),
                        value,
                        format!(
                            "keys must be in order of time: it is not after the key before it \
                             ({})",
                            t.times[i - 1]
                        ),
                    ));
                }
                // Within half a frame of the last: times written to a few decimals.
                if time > end + 0.5 / a.fps {
                    return Err(invalid(
                        format!("{}[{i}]", field("times")),
                        value,
                        format!(
                            "is past the animation's end: its last frame, {}, is at {end} s \
                             ({frames} frames at {} fps)",
                            frames - 1,
                            a.fps
                        ),
                    ));
                }
            }
            let mut values = Vec::with_capacity(t.values.len());
            for (i, v) in t.values.iter().enumerate() {
                let (value, problem) = match (v, target.scalar()) {
                    (KeyValue::Number(x), true) => (Vec3::new(*x, 0.0, 0.0), None),
                    (KeyValue::Array(xs), false) if xs.len() == 3 => (Vec3::from_slice(xs), None),
                    (_, true) => (Vec3::ZERO, Some("must be a number for this target")),
                    (_, false) => (
                        Vec3::ZERO,
                        Some("must be an [x, y, z] array for this target"),
                    ),
                };
                if let Some(problem) = problem {
                    return Err(invalid(
                        format!("{}[{i}]", field("values")),
                        key_text(v),
                        problem.into(),
                    ));
                }
                if !value.is_finite() {
                    return Err(invalid(
                        format!("{}[{i}]", field("values")),
                        key_text(v),
                        "must be finite".into(),
                    ));
                }
                if matches!(target, Target::Emission(..)) && value.x < 0.0 {
                    return Err(invalid(
                        format!("{}[{i}]", field("values")),
                        key_text(v),
                        "an emission scale must be >= 0".into(),
                    ));
                }
                values.push(value);
            }
            if let Some(other) = tracks.iter().position(|o: &Track| o.target == target) {
                return Err(invalid(
                    field("target"),
                    format!("{:?}", t.target),
                    format!("animation.track[{other}] moves it already: one track a target"),
                ));
            }
            tracks.push(Track {
                target,
                interpolation,
                times: t.times.clone(),
                values,
            });
        }
        let animation = Animation {
            frames,
            fps: a.fps,
            tracks,
            file: file.to_string(),
            camera: camera.clone(),
            lights: lights.to_vec(),
            luminaires: luminaires.to_vec(),
        };
        for f in 0..frames {
            animation.state(f, materials.len())?;
        }
        Ok(animation)
    }

    /// Frame `f`'s camera, lights, emission scales, map rotation and luminaire placements,
    /// each built and checked as the scene file's own tables are; an error names the frame.
    pub fn state(&self, f: u32, materials: usize) -> Result<FrameState, SceneError> {
        let t = f as f32 / self.fps;
        let file = self.file.as_str();
        let mut camera = self.camera.clone();
        let mut lights = self.lights.clone();
        let mut luminaires = self.luminaires.clone();
        let mut emission = vec![1.0f32; materials];
        let mut environment_rotation = 0.0;
        for (k, track) in self.tracks.iter().enumerate() {
            let v = track.at(t);
            match track.target {
                Target::CameraPosition => camera.position = v.to_array(),
                Target::CameraLookAt => camera.look_at = v.to_array(),
                Target::CameraFov => camera.fov_y = v.x,
                Target::LightPosition(i) => lights[i].position = v.to_array(),
                Target::LightDirection(i) => lights[i].direction = Some(v.to_array()),
                Target::LightIntensity(i) => lights[i].intensity = v.to_array(),
                Target::Emission(ref name, ref ms) => {
                    if v.x.is_nan() || v.x < 0.0 {
                        return Err(SceneError::Invalid {
                            file: file.to_string(),
                            field: format!(
                                "animation.track[{k}] (material.{name}.emission) at animation \
                                 frame {f}"
                            ),
                            value: v.x.to_string(),
                            problem: "an emission scale must be >= 0: the smooth track \
                                      overshoots below zero between its keys (use \
                                      interpolation = \"linear\" there)"
                                .into(),
                        });
                    }
                    ms.iter().for_each(|&m| emission[m] = v.x)
                }
                Target::EnvironmentRotation => environment_rotation = v.x,
                Target::LuminairePosition(i) => luminaires[i].position = v.to_array(),
                Target::LuminaireLookAt(i) => luminaires[i].look_at = v.to_array(),
            }
        }
        let at_frame = |e: SceneError| e.in_context(&format!("at animation frame {f}"));
        let camera = camera::build(file, &camera).map_err(at_frame)?;
        let lights = lights
            .iter()
            .enumerate()
            .map(|(i, l)| lights::build(file, i, l))
            .collect::<Result<Vec<_>, _>>()
            .map_err(at_frame)?;
        let luminaires = luminaires
            .iter()
            .enumerate()
            .map(|(k, l)| PlacedLuminaire::frame(file, k, l))
            .collect::<Result<Vec<_>, _>>()
            .map_err(at_frame)?;
        Ok(FrameState {
            camera,
            lights,
            emission,
            environment_rotation,
            luminaires,
        })
    }

    /// Each material's largest emission scale over the animation (1 where none moves it), and
    /// each light's largest intensity per channel: what the power bound is checked at.
    pub fn brightest(&self, materials: usize) -> (Vec<f32>, Vec<Vec3>) {
        let mut emission = vec![0.0f32; materials];
        let mut intensity = vec![Vec3::ZERO; self.lights.len()];
        for f in 0..self.frames {
            let t = f as f32 / self.fps;
            let mut e = vec![1.0f32; materials];
            let mut l: Vec<Vec3> = self
                .lights
                .iter()
                .map(|l| Vec3::from(l.intensity))
                .collect();
            for track in &self.tracks {
                match track.target {
                    Target::Emission(_, ref ms) => ms.iter().for_each(|&m| e[m] = track.at(t).x),
                    Target::LightIntensity(i) => l[i] = track.at(t),
                    _ => {}
                }
            }
            emission.iter_mut().zip(e).for_each(|(a, b)| *a = a.max(b));
            intensity.iter_mut().zip(l).for_each(|(a, b)| *a = a.max(b));
        }
        (emission, intensity)
    }
}

fn key_text(v: &KeyValue) -> String {
    match v {
        KeyValue::Number(x) => x.to_string(),
        KeyValue::Array(xs) => format!("{xs:?}"),
    }
}

/// `name[i].rest` as (i, rest), `i` checked against `count`.
fn indexed<'a>(
    text: &'a str,
    name: &str,
    count: usize,
    table: &str,
) -> Option<Result<(usize, &'a str), String>> {
    let rest = text.strip_prefix(name)?.strip_prefix('[')?;
    let (index, rest) = rest.split_once("].")?;
    Some(match index.parse::<usize>() {
        Ok(i) if i < count => Ok((i, rest)),
        Ok(i) => Err(format!(
            "the scene has {count} [[{table}]] entr{} (indices 0..{count}), not {i}",
            if count == 1 { "y" } else { "ies" }
        )),
        Err(_) => Err(format!("{name}[{index}] is not an index")),
    })
}

fn parse_target(
    text: &str,
    lights: &[LightFile],
    luminaires: &[LuminairePlacementFile],
    materials: &[Material],
    has_environment: bool,
) -> Result<Target, String> {
    let unknown = || format!("is not a target irad animates; targets: {TARGETS}");
    match text {
        "camera.position" => return Ok(Target::CameraPosition),
        "camera.look_at" => return Ok(Target::CameraLookAt),
        "camera.fov_y" => return Ok(Target::CameraFov),
        "environment.rotation" if has_environment => return Ok(Target::EnvironmentRotation),
        "environment.rotation" => return Err("the scene has no [environment]".into()),
        _ => {}
    }
    if let Some(r) = indexed(text, "light", lights.len(), "light") {
        let (i, field) = r?;
        return match field {
            "position" => Ok(Target::LightPosition(i)),
            "intensity" => Ok(Target::LightIntensity(i)),
            "direction" if lights[i].kind == "spot" => Ok(Target::LightDirection(i)),
            "direction" => Err(format!(
                "light[{i}] has kind = {:?}: only spot lights have a direction",
                lights[i].kind
            )),
            _ => Err(unknown()),
        };
    }
    if let Some(r) = indexed(text, "luminaire", luminaires.len(), "luminaire") {
        let (i, field) = r?;
        return match field {
            "position" => Ok(Target::LuminairePosition(i)),
            "look_at" => Ok(Target::LuminaireLookAt(i)),
            _ => Err(unknown()),
        };
    }
    if let Some(name) = text
        .strip_prefix("material.")
        .and_then(|t| t.strip_suffix(".emission"))
    {
        let named: Vec<usize> = (0..materials.len())
            .filter(|&m| materials[m].name == name)
            .collect();
        return if named.is_empty() {
            Err(format!("no material is named `{name}`"))
        } else if !named.iter().any(|&m| materials[m].is_emissive()) {
            Err(format!(
                "material `{name}` emits nothing (Ke = 0): its emission cannot be scaled"
            ))
        } else {
            Ok(Target::Emission(name.to_string(), named))
        };
    }
    Err(unknown())
}

/// `map` turned `degrees` about +Y, right-handed (a direction d of the turned map shows what the
/// map showed at d turned back), to whole columns: the map is piecewise constant over its
/// texels, so a turn by whole columns keeps every method's pdfs exact. A turn of theta moves u
/// by -theta / 360 (docs/DESIGN.md "Conventions": u = atan2(x, -z) / 2 pi).
pub fn turned(map: &Environment, degrees: f32) -> Environment {
    let w = map.width as usize;
    let shift = ((degrees / 360.0) * w as f32).round().rem_euclid(w as f32) as usize % w;
    if shift == 0 {
        return map.clone();
    }
    let mut texels = Vec::with_capacity(map.texels.len());
    for row in map.texels.chunks(w) {
        texels.extend((0..w).map(|i| row[(i + shift) % w]));
    }
    Environment {
        texels,
        ..map.clone()
    }
}

impl Scene {
    /// The still scene animation frame `f` shows: its camera, lights, emission, map (map f
    /// mod n of a sequence, turned) and luminaires (atlas f mod n of a sequence, placed), with
    /// no animation left; the scene itself when it has none.
    pub fn at_frame(&self, f: u32) -> Result<Scene, SceneError> {
        let Some(animation) = &self.animation else {
            return Ok(self.clone());
        };
        let state = animation.state(f, self.materials.len())?;
        let mut scene = self.clone();
        scene.animation = None;
        // The resolution is not animated, and a caller may have set it (a suite's width).
        let (width, height) = (self.camera.width, self.camera.height);
        scene.camera = Camera {
            width,
            height,
            ..state.camera
        };
        scene.lights = state.lights;
        for (m, s) in scene.materials.iter_mut().zip(&state.emission) {
            m.ke *= *s;
        }
        if !scene.environment_sequence.is_empty() {
            let n = scene.environment_sequence.len();
            scene.environment = Some(scene.environment_sequence[f as usize % n].clone());
            scene.environment_sequence.clear();
        }
        if let Some(map) = &scene.environment {
            scene.environment = Some(turned(map, state.environment_rotation));
        }
        for (placed, [position, x, y, z]) in scene.luminaires.iter_mut().zip(state.luminaires) {
            (placed.position, placed.x, placed.y, placed.z) = (position, x, y, z);
            let lum = &mut placed.luminaire;
            if !lum.sequence.is_empty() {
                let n = lum.sequence.len();
                lum.images = lum.sequence[f as usize % n].clone();
                lum.sequence.clear();
            }
        }
        Ok(scene)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(interpolation: Interpolation, times: &[f32], xs: &[f32]) -> Track {
        Track {
            target: Target::CameraFov,
            interpolation,
            times: times.to_vec(),
            values: xs.iter().map(|&x| Vec3::new(x, 0.0, 0.0)).collect(),
        }
    }

    #[test]
    fn linear_keys_interpolate_and_hold_outside() {
        let t = track(Interpolation::Linear, &[1.0, 2.0, 4.0], &[10.0, 20.0, 0.0]);
        assert_eq!(t.at(0.0).x, 10.0);
        assert_eq!(t.at(1.5).x, 15.0);
        assert_eq!(t.at(2.0).x, 20.0);
        assert_eq!(t.at(3.0).x, 10.0);
        assert_eq!(t.at(9.0).x, 0.0);
    }

    #[test]
    fn smooth_keys_follow_the_catmull_rom_spline() {
        // Keys (0, 0), (1, 1), (2, 0), (3, 1): tangents 1 (one-sided), 0, 0, 1 (one-sided).
        let t = track(
            Interpolation::Smooth,
            &[0.0, 1.0, 2.0, 3.0],
            &[0.0, 1.0, 0.0, 1.0],
        );
        // Segment 0 at u = 1/2: h00 = h01 = 1/2, h10 = 1/8, h11 = -1/8:
        // 0 / 2 + 1 * 1/8 + 1 / 2 + 0 = 0.625.
        assert!((t.at(0.5).x - 0.625).abs() < 1e-6, "{}", t.at(0.5).x);
        // Segment 1 at u = 1/4: h00 = 27/32, tangents 0: 27/32.
        assert!(
            (t.at(1.25).x - 27.0 / 32.0).abs() < 1e-6,
            "{}",
            t.at(1.25).x
        );
        for (time, x) in [(0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (3.0, 1.0)] {
            assert!((t.at(time).x - x).abs() < 1e-6);
        }
    }

    #[test]
    fn a_quarter_turn_moves_the_sun_from_minus_z_to_minus_x() {
        // Column i covers u in [i/8, (i+1)/8): -Z is u = 0 (column 0), -X is u = 3/4 (column 6).
        let map = Environment {
            width: 8,
            height: 1,
            texels: (0..8).map(|i| Vec3::splat(i as f32)).collect(),
            source: "test".into(),
        };
        let t = turned(&map, 90.0);
        assert_eq!(t.texels[6], map.texels[0]);
        assert_eq!(turned(&map, 360.0), map);
        assert_eq!(turned(&map, -90.0).texels[2], map.texels[0]);
    }
}
