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

const KINDS: [LightKind; 4] = [
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
        add: "give a material an emission",
    },
    LightKind {
        support: |l| l.point,
        count: |s| s.lights.len(),
        name: "point and spot lights",
        one: "a point or spot light",
        add: "add a [[light]]",
    },
    LightKind {
        support: |l| l.luminaires,
        count: |s| s.luminaires.len(),
        name: "light-field luminaires",
        one: "a light-field luminaire",
        add: "add a [[luminaire]]",
    },
];

/// The refusal without its alternatives: the first kind of light `lights` declines and
/// `scene` has, or needs and `scene` lacks; with, for a light it needs, how to add one.
fn refusal(name: &str, lights: &Lights, scene: &Scene) -> Option<(String, Option<&'static str>)> {
    for kind in &KINDS {
        let n = (kind.count)(scene);
        match (kind.support)(lights) {
            Support::Declines(why) if n > 0 => {
                let has = match kind.name {
                    "environment maps" => "one".to_string(),
                    _ => n.to_string(),
                };
                let text = format!(
                    "{name} does not render {} ({why}), and this scene has {has}",
                    kind.name
                );
                return Some((text, None));
            }
            Support::Needs(why) if n == 0 => {
                let text = format!("{name} needs {} ({why}), and this scene has none", kind.one);
                return Some((text, Some(kind.add)));
            }
            _ => {}
        }
    }
    None
}

/// Why a method named `name` that treats lights as `lights` declines `scene`, in one line
/// with what renders it instead (irad's methods that render it), or None when it renders it.
pub fn declines(name: &str, lights: &Lights, scene: &Scene) -> Option<String> {
    let (why, add) = refusal(name, lights, scene)?;
    let others: Vec<&str> = Registry::builtin()
        .entries()
        .iter()
        .filter(|e| e.name() != name && refusal(e.name(), &e.lights(), scene).is_none())
        .map(|e| e.name())
        .collect();
    let others = match others.split_last() {
        None => None,
        Some((last, [])) => Some(format!("use --method {last}")),
        Some((last, rest)) => Some(format!("use --method {} or {last}", rest.join(", "))),
    };
    Some(match (add, others) {
        (Some(add), Some(others)) => format!("{why}: {add}, or {others}"),
        (Some(add), None) => format!("{why}: {add}"),
        (None, Some(others)) => format!("{why}: {others}"),
        (None, None) => format!("{why}; no method of irad renders this scene"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const IR_LIKE: Lights = Lights {
        environment: Support::Declines("its walk starts on the scene's lights"),
        area: Support::Renders,
        point: Support::Renders,
        luminaires: Support::Declines("only lightfield models them"),
    };

    #[test]
    fn a_declined_light_is_named_with_the_methods_that_render_the_scene() {
        let mut scene = crate::scene::default_scene();
        assert_eq!(declines("x", &IR_LIKE, &scene), None);
        let needs = Lights {
            environment: Support::Needs("it shades the map"),
            ..IR_LIKE
        };
        let why = declines("x", &needs, &scene).unwrap();
        assert!(
            why.starts_with("x needs an environment map (it shades the map), and this scene has none: add an [environment] table, or use --method reference"),
            "{why}"
        );
        scene.lights.clear();
        scene.triangles.clear();
        let why = declines("x", &needs, &scene).unwrap();
        assert!(why.contains("or use --method"), "{why}");
    }
}
