//! The bound on a scene's light power and emitted radiance, checked at load (docs/DESIGN.md
//! "Errors").
//!
//! The samplers carry power and radiance in f32, and what they compute from them grows with
//! the scene's geometry: the light BVH stores each node's power phi and weighs a child by
//! phi cos / d^2 (src/sampling/light_bvh.rs), summed over two children; a light-table sample's
//! estimate is Le G f / p with p the light's share of the total power, so it is the total
//! power times f cos / (4 pi d^2) (times up to 14, the largest channel over the luminance the
//! table weighs by); restir sums such weights over its candidates and reservoirs and, in its
//! MIS weights, multiplies targets by confidences M (hundreds); VPLs carry I / p, again the
//! total power. Emitted
//! radiance seen directly (a camera ray or a BSDF sample hitting an emitter or escaping to the
//! environment) is summed over a submission's frames in f32.
//!
//! So the scene's total power P, each light counted by its largest channel (never below the
//! luminance power the tables and the BVH hold), must leave room below f32::MAX (about 2^128)
//! for those factors: P <= 2^64 W leaves 2^64 for the 1/d^2, BSDF, channel and sum factors,
//! e.g. 2^10 for sums and confidences, 2^4 for a channel, 2^50 for f cos / d^2: a diffuse
//! surface down to 2^-25 (3e-8) units from a light at the bound. Every emitter's radiance (MTL Ke, an
//! environment texel) is held to 2^64 W/(sr m^2) for the same reason. Measured on a plane under
//! a point light 1 unit above (16x16, lavapipe): the light BVH broke where 4 pi I left f32's
//! range (I = 3e37: phi infinite, every estimate NaN) and restir's reservoirs overflowed and
//! were dropped from I = 2e37, about 2^63 above the bound's largest intensity (1.46e18).
//!
//! A scene past the bound is refused naming the file and field at fault and the largest
//! value that would pass with the rest of the scene unchanged.

use std::f64::consts::PI;

use super::{Light, Scene, SceneError};
use crate::sampling::environment::texel_solid_angle;

/// The most light power a scene may hold, every light's power at its largest channel summed
/// (watts): 2^64, f32's range halved in exponent (see the module's documentation).
pub const MAX_POWER: f64 = 18_446_744_073_709_551_616.0;
/// The most radiance an emitter may have in any channel: MTL `Ke`, an environment texel.
pub const MAX_RADIANCE: f64 = MAX_POWER;

/// Where the check reports a term of the total.
pub struct PowerSources<'a> {
    /// The scene file (lights, `environment.scale`).
    pub file: &'a str,
    /// Per material, the MTL file that defined it (None for the default material).
    pub material_files: &'a [Option<String>],
    /// `environment.scale` as the file gives it, and the map's file or sky as written there.
    pub environment: Option<(f32, String)>,
}

/// One part of the total: a field whose value scales its power.
struct Term {
    /// (file, field, value as written) for the message.
    file: String,
    field: String,
    value: String,
    /// The field's value the bound applies to (largest channel, or the scale) and its power.
    amount: f64,
    power: f64,
    /// What the term is, for the message.
    what: String,
    /// The largest amount its emitted radiance allows (infinite for point and spot lights),
    /// and its brightest radiance.
    radiance_limit: f64,
    brightest: f64,
}

/// Every light's power at its largest channel: a point or spot light's 4 pi I (the light BVH
/// weighs a spot as a point light), an emissive material's pi Ke times its triangles' area, the
/// environment's pi r^2 times its integral over the sphere (r the scene's bounding radius, as
/// src/scene/gpu.rs weighs it; the largest over a sequence's maps).
fn terms(scene: &Scene, sources: &PowerSources) -> Vec<Term> {
    let mut terms = Vec::new();
    for (i, light) in scene.lights.iter().enumerate() {
        let (Light::Point { intensity, .. } | Light::Spot { intensity, .. }) = light;
        let amount = intensity.max_element() as f64;
        terms.push(Term {
            file: sources.file.to_string(),
            field: format!("light[{i}].intensity"),
            value: fmt3(*intensity),
            amount,
            power: 4.0 * PI * amount,
            what: "4 pi I, I its largest channel".into(),
            radiance_limit: f64::INFINITY,
            brightest: 0.0,
        });
    }
    let mut areas = vec![0.0f64; scene.materials.len()];
    for t in &scene.triangles {
        areas[t.material as usize] += t.area();
    }
    // Each [[mesh]] parses its own copy of its MTL files, so a material two OBJs share is
    // several scene materials; it is one field to edit, so one term, over all their triangles
    // (else its largest value would hold the other copies fixed and itself be refused).
    // Files compare by their canonical path where they are on disk (two OBJs in different
    // folders may name one MTL by different paths).
    let mut merged: Vec<(std::path::PathBuf, &str, String, usize, f64)> = Vec::new();
    for (k, m) in scene.materials.iter().enumerate() {
        if !m.is_emissive() {
            continue;
        }
        let file = sources.material_files.get(k).cloned().flatten();
        let file = file.unwrap_or_else(|| sources.file.to_string());
        let key = std::fs::canonicalize(&file).unwrap_or_else(|_| file.clone().into());
        // Ke compared too: an MTL may repeat a name with other values (the OBJ uses one).
        match merged.iter_mut().find(|(f, name, _, j, _)| {
            *f == key && *name == m.name && scene.materials[*j].ke == m.ke
        }) {
            Some((.., area)) => *area += areas[k],
            None => merged.push((key, &m.name, file, k, areas[k])),
        }
    }
    for (_, name, file, k, area) in merged {
        let m = &scene.materials[k];
        let amount = m.ke.max_element() as f64;
        terms.push(Term {
            file,
            field: format!("material `{name}` Ke"),
            value: fmt3(m.ke),
            amount,
            power: PI * amount * area,
            what: format!("pi Ke A, A = {area:.3e} its triangles' area"),
            radiance_limit: MAX_RADIANCE,
            brightest: amount,
        });
    }
    // Light-field luminaires ([[luminaire]]) are no term: they are sampled by the lightfield
    // method alone, never through the light table or the light BVH whose f32 sums this total
    // bounds. Their atlas texels are held to MAX_RADIANCE where they are read
    // (src/scene/luminaire/mod.rs), as the lightfield method's f32 tables sum them.
    if let (Some(env), Some((scale, map))) = (&scene.environment, &sources.environment) {
        let (_, radius) = super::gpu::bounds(scene);
        let r2 = (radius as f64).powi(2);
        let integral = std::iter::once(env)
            .chain(&scene.environment_sequence)
            .map(|e| {
                e.texels
                    .iter()
                    .enumerate()
                    .map(|(i, t)| {
                        t.max_element() as f64
                            * texel_solid_angle(i as u32 / e.width, e.width, e.height)
                    })
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
        let brightest = std::iter::once(env)
            .chain(&scene.environment_sequence)
            .flat_map(|e| e.texels.iter().map(|t| t.max_element()))
            .fold(0.0f32, f32::max) as f64;
        let amount = *scale as f64;
        terms.push(Term {
            file: sources.file.to_string(),
            field: "environment.scale".into(),
            value: fmt1(*scale),
            amount,
            power: PI * r2 * integral,
            what: format!(
                "pi r^2 times the integral of {map} over the sphere, r = {radius:.3e} the \
                 scene's bounding radius"
            ),
            radiance_limit: if brightest > 0.0 {
                amount * MAX_RADIANCE / brightest
            } else {
                f64::INFINITY
            },
            brightest,
        });
    }
    terms
}

/// `x` rounded down to three significant digits, as a message shows the largest value that
/// works (rounding up could show one that does not).
fn round_down(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 || x.is_infinite() {
        return 0.0;
    }
    let e = x.log10().floor();
    let scale = 10f64.powf(e - 2.0);
    let r = (x / scale).floor() * scale;
    // The division and product may round r a hair above x.
    if r > x {
        ((x / scale).floor() - 1.0) * scale
    } else {
        r
    }
}

/// `x` in exponent form where plain digits would run long (3e37, not a 3 and 37 zeros).
fn fmt1(x: f32) -> String {
    if x == 0.0 || (1e-4..1e7).contains(&x.abs()) {
        x.to_string()
    } else {
        format!("{x:e}")
    }
}

/// `[a, b, c]`, each as `fmt1` writes it.
fn fmt3(v: glam::Vec3) -> String {
    format!("[{}, {}, {}]", fmt1(v.x), fmt1(v.y), fmt1(v.z))
}

/// `x` as a message shows the largest value that works: three digits, rounded down.
pub(super) fn shown(x: f64) -> String {
    fmt1(round_down(x) as f32)
}

/// Refuses a scene whose total light power or any emitter's radiance passes the bounds,
/// naming the field, its value and the largest value that would pass with the rest of the
/// scene as it is.
pub fn check(scene: &Scene, sources: &PowerSources) -> Result<(), SceneError> {
    let terms = terms(scene, sources);
    let total: f64 = terms.iter().map(|t| t.power).sum();
    // An emitter too bright in itself is the field to fix whatever the rest; else the largest
    // term of a total past the bound.
    let (top, radiance) = match terms.iter().find(|t| t.amount > t.radiance_limit) {
        Some(t) => (t, true),
        None if total <= MAX_POWER => return Ok(()),
        None => match terms.iter().max_by(|a, b| a.power.total_cmp(&b.power)) {
            Some(t) => (t, false),
            None => return Ok(()),
        },
    };
    let others = total - top.power;
    let power_limit = if top.power > 0.0 {
        top.amount * (MAX_POWER - others) / top.power
    } else {
        f64::INFINITY
    };
    let largest = top.radiance_limit.min(power_limit);
    let works = if largest > 0.0 {
        format!("at most {} works", shown(largest))
    } else {
        "no value works (the other lights pass the bound without it)".to_string()
    };
    let problem = if radiance {
        format!(
            "emitted radiance up to {:.3e}, over {MAX_RADIANCE:.3e}, the most irad's f32 \
             kernels carry with room for what they compute from it; {works}",
            top.brightest
        )
    } else {
        format!(
            "the scene's light power would be {total:.3e} W ({:.3e} W from this: {}), over \
             {MAX_POWER:.3e} W, the most irad's f32 samplers carry with room for what they \
             compute from it; {works} with the other lights as they are",
            top.power, top.what
        )
    };
    Err(SceneError::Invalid {
        file: top.file.clone(),
        field: top.field.clone(),
        value: top.value.clone(),
        problem,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_down_keeps_three_digits_and_never_rounds_up() {
        assert_eq!(round_down(1.4679e18), 1.46e18);
        assert_eq!(round_down(2.0), 2.0);
        assert_eq!(round_down(0.0), 0.0);
        for x in [1.234567e-7, 9.999999e30, 3.3e3, 1.0e19] {
            assert!(round_down(x) <= x && round_down(x) > 0.98 * x, "{x}");
        }
    }

    #[test]
    fn the_bound_leaves_f32_room() {
        // 2^64 times 2^64 is f32's range (f32::MAX is just under 2^128).
        assert_eq!(MAX_POWER, 2f64.powi(64));
        assert!(MAX_POWER * MAX_POWER > f32::MAX as f64);
        assert!(MAX_POWER * 2f64.powi(63) < f32::MAX as f64);
    }
}
