//! What lights a method renders, as data (`RenderMethod::LIGHTS`), and the one place that
//! turns it into a refusal: the light the scene has that the method declines, or the one it
//! needs and the scene lacks, why, and the methods that do render the scene.

use crate::scene::Scene;

use super::registry::Registry;

/// Why a method other than lightfield declines light-field luminaires.
pub const NO_LUMINAIRES: &str = "it does not sample their images";

/// How a method treats one kind of light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Support {
    /// It renders this light where the scene has it.
    Renders,
    /// It declines a scene that has this light, for this reason (a clause: "the
    /// quasi-random walk starts on emissive triangles, point and spot lights").
    Declines(&'static str),
    /// It renders this light and declines a scene without it, for this reason.
    Needs(&'static str),
}

/// How a method treats each kind of light a scene can have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lights {
    /// The scene's `[environment]` map (or sequence).
    pub environment: Support,
    /// Emissive triangles (area lights).
    pub area: Support,
    /// Point and spot lights.
    pub point: Support,
    /// Light-field luminaires (`[[luminaire]]`).
    pub luminaires: Support,
}

/// One kind of light: its support in `Lights`, how many the scene has, its name and how to
/// add one.
struct LightKind {
    support: fn(&Lights) -> Support,
    count: fn(&Scene) -> usize,
    /// Plural, as in "does not render {name}".
    name: &'static str,
    /// As in "needs {one}".
    one: &'static str,
    add: &'static str,
}

/// In the order refusals name them: luminaires first (only lightfield renders them).
const KINDS: [LightKind; 4] = [
    LightKind {
        support: |l| l.luminaires,
        count: |s| s.luminaires.len(),
        name: "light-field luminaires",
        one: "a light-field luminaire",
        add: "add a [[luminaire]]",
    },
    LightKind {
        support: |l| l.environment,
        count: |s| s.environment.is_some() as usize,
        name: "environment maps",
        one: "an environment map",
        add: "add an [environment] table",
    },
    LightKind {
        support: |l| l.area,
        count: |s| {
            s.triangles
                .iter()
                .filter(|t| s.materials[t.material as usize].is_emissive())
                .count()
        },
        name: "emissive triangles",
        one: "an emissive triangle",
        add: "give a material an emission (Ke)",
    },
    LightKind {
        support: |l| l.point,
        count: |s| s.lights.len(),
        name: "point and spot lights",
        one: "a point or spot light",
        add: "add a [[light]]",
    },
];

/// The refusal without its alternatives, or None: every kind of light the method declines and
/// the scene has (with how many), then every kind it needs and the scene lacks; how to add one
/// only where a missing light is the scene's only problem.
fn refusal(name: &str, lights: &Lights, scene: &Scene) -> Option<String> {
    let mut declined: Vec<String> = Vec::new();
    let mut whys: Vec<&str> = Vec::new();
    let mut needed: Vec<(&LightKind, &str)> = Vec::new();
    for kind in &KINDS {
        let n = (kind.count)(scene);
        match (kind.support)(lights) {
            Support::Declines(why) if n > 0 => {
                declined.push(match kind.name {
                    "environment maps" => "environment maps (this scene has one)".to_string(),
                    _ => format!("{} (this scene has {n})", kind.name),
                });
                if !whys.contains(&why) {
                    whys.push(why);
                }
            }
            Support::Needs(why) if n == 0 => needed.push((kind, why)),
            _ => {}
        }
    }
    let needs = |(kind, why): &(&LightKind, &str)| format!("{} ({why})", kind.one);
    match (declined.is_empty(), needed.as_slice()) {
        (true, []) => None,
        (true, [only]) => Some(format!(
            "{name} needs {}, and this scene has none: {}, or",
            needs(only),
            only.0.add
        )),
        (true, all) => Some(format!(
            "{name} needs {}, and this scene has none of them;",
            all.iter().map(needs).collect::<Vec<_>>().join(" and ")
        )),
        (false, _) => {
            let mut text = format!(
                "{name} does not render {}: {};",
                declined.join(" or "),
                whys.join("; ")
            );
            for (kind, _) in &needed {
                text += &format!(" and it needs {}, which this scene lacks;", kind.one);
            }
            Some(text)
        }
    }
}

/// Why a method named `name` that treats lights as `lights` declines `scene`, in one line
/// with irad's methods that render it, or None when it renders it.
pub fn declines(name: &str, lights: &Lights, scene: &Scene) -> Option<String> {
    let why = refusal(name, lights, scene)?;
    let others: Vec<&str> = Registry::builtin()
        .entries()
        .iter()
        .filter(|e| e.name() != name && refusal(e.name(), &e.lights(), scene).is_none())
        .map(|e| e.name())
        .collect();
    let others = match others.split_last() {
        None => "no method of irad renders this scene".to_string(),
        Some((last, [])) => format!("use --method {last}"),
        Some((last, rest)) => format!("use --method {} or {last}", rest.join(", ")),
    };
    Some(format!("{why} {others}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn why(method: &str, scene: &Scene) -> Option<String> {
        let e = Registry::builtin().get(method).ok()?;
        declines(method, &e.lights(), scene)
    }

    /// The refusals' exact words, per kind of light and method: what is declined with its
    /// count and reason, what is needed and how to add it where that alone would do, and the
    /// methods that render the scene.
    #[test]
    fn refusals_name_the_lights_the_reasons_and_the_methods_that_render_the_scene() {
        use crate::scene::{Environment, Light};
        let cornell = crate::scene::default_scene();
        assert_eq!(why("ir", &cornell), None);
        assert_eq!(
            why("env", &cornell).unwrap(),
            "env does not render emissive triangles (this scene has 2): it shades the \
             environment map's direct light only; and it needs an environment map, which this \
             scene lacks; use --method reference, ir, bir or restir"
        );
        assert_eq!(
            why("bundles", &cornell).unwrap(),
            "bundles does not render emissive triangles (this scene has 2): Tokuyoshi 12 \
             Section 4 starts VPLs from point lights; use --method reference, ir, bir or \
             restir"
        );
        assert_eq!(
            why("lightfield", &cornell).unwrap(),
            "lightfield needs a light-field luminaire (it renders light-field luminaires' \
             direct light), and this scene has none: add a [[luminaire]], or use --method \
             reference, ir, bir or restir"
        );
        // A map, no emissive triangles, one point light.
        let mut sky = cornell.clone();
        sky.materials
            .iter_mut()
            .for_each(|m| m.ke = glam::Vec3::ZERO);
        sky.environment = Some(Environment {
            width: 2,
            height: 1,
            texels: vec![glam::Vec3::ONE; 2],
            source: "sky.exr".into(),
        });
        sky.lights.push(Light::Point {
            position: glam::Vec3::Y,
            intensity: glam::Vec3::ONE,
        });
        assert_eq!(
            why("ir", &sky).unwrap(),
            "ir does not render environment maps (this scene has one): the quasi-random walk \
             starts on emissive triangles, point and spot lights; use --method reference, \
             bundles or restir"
        );
        assert_eq!(
            why("env", &sky).unwrap(),
            "env does not render point and spot lights (this scene has 1): it shades the \
             environment map's direct light only; use --method reference, bundles or restir"
        );
        // Luminaires are named first, and a light the method needs is not offered as a fix
        // where the scene would still be declined.
        let mut headlights = sky.clone();
        headlights.environment = None;
        headlights.luminaires = crate::scene::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/car-headlights/scene.toml"
        )))
        .unwrap()
        .luminaires;
        assert_eq!(
            why("env", &headlights).unwrap(),
            "env does not render light-field luminaires (this scene has 2) or point and spot \
             lights (this scene has 1): it does not sample their images; it shades the \
             environment map's direct light only; and it needs an environment map, which this \
             scene lacks; use --method lightfield"
        );
    }
}
