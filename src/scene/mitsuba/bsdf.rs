//! Mitsuba BSDFs as irad's Lambert plus one normalized Phong lobe (docs/scenes.md "Mitsuba
//! scenes" states each fit and its error):
//! - `diffuse`: Kd = reflectance, exact; a bitmap reflectance is an albedo texture (Kd 1).
//! - `twosided`: its BSDF (irad's reflect on both sides), exact.
//! - `roughconductor` (beckmann or ggx): Ks = specular_reflectance, Ns = (1 / alpha^2 - 1) / 2,
//!   the inverse of the export's alpha = 1 / sqrt(2 Ns + 1) (src/export/mitsuba/bsdf.rs): the
//!   same lobe width and albedo at normal incidence. A `material` or `eta`/`k` (Fresnel) is
//!   left out: the reflectance is specular_reflectance's, with a warning. Anisotropic alphas
//!   are averaged with a warning.
//! - `conductor` (smooth): a mirror, as Ns = MIRROR_NS with a warning.
//! - `blendbsdf` of a diffuse and a (rough)conductor, the export's form: Kd = (1 - w) Kd',
//!   Ks = w Ks'. A texture stays when one part alone has a diffuse part, or both read the same
//!   texture (Kd (1 - w) Kd1 + w Kd2 times it); otherwise it stands in as its mean colour.
//! - `plastic` / `roughplastic`: Kd = diffuse_reflectance (1 - F0), Ks =
//!   specular_reflectance F0 with F0 = ((eta - 1) / (eta + 1))^2 for int_ior / ext_ior
//!   (1.49 / 1.000277: F0 0.039), Ns from alpha (roughplastic, 0.1 by default) or MIRROR_NS
//!   (plastic): the albedos at normal incidence; the Fresnel rise towards grazing angles and
//!   the internal scattering of the coat are not modelled (a warning says so). A textured
//!   diffuse_reflectance stays a texture (the fit is linear in it) unless `nonlinear` is set.
//! - `phong` (Mitsuba 0.6's, the normalized modified Phong irad uses): exact, its
//!   diffuse_reflectance a texture where it is a bitmap.
//!   Anything else: grey Lambert (Kd 0.5) with a warning naming the element.
//!
//! Bitmaps elsewhere (specular reflectance, roughness, blend weights) stand in as their mean.

use glam::Vec3;
use roxmltree::Node;

use super::props::Context;
use super::textures::{self, Albedo};
use crate::scene::SceneError;

/// Ns standing in for a smooth (mirror) lobe: a lobe of half-width about 1 degree.
pub const MIRROR_NS: f32 = 10000.0;

/// irad's material parts from a Mitsuba BSDF: Kd times `texture` where there is one.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    pub kd: Vec3,
    pub ks: Vec3,
    pub ns: f32,
    pub texture: Option<Albedo>,
}

impl Fit {
    /// A fit without a texture.
    fn plain(kd: Vec3, ks: Vec3, ns: f32) -> Fit {
        Fit {
            kd,
            ks,
            ns,
            texture: None,
        }
    }
}

/// The Phong exponent of a Beckmann roughness (the export's inverse).
pub fn ns_of_alpha(alpha: f64) -> f32 {
    let a = alpha.clamp(1e-4, 1.0);
    (((1.0 / (a * a)) - 1.0) / 2.0) as f32
}

/// The named child property of `node`.
fn property<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.attribute("name") == Some(name))
}

/// A colour property (or a bitmap texture's mean, nested or referenced) named `name`, else
/// `default`.
fn colour<'a, 'i>(
    ctx: &Context,
    node: Node<'a, 'i>,
    name: &str,
    default: Vec3,
    resolve: &dyn Fn(&str) -> Option<Node<'a, 'i>>,
    warnings: &mut Vec<String>,
) -> Result<Vec3, SceneError> {
    match property(node, name) {
        None => Ok(default),
        Some(p) if p.tag_name().name() == "texture" => textures::mean(ctx, p, warnings),
        Some(p) if p.tag_name().name() == "ref" => {
            let id = p.attribute("id").unwrap_or_default();
            match resolve(id).filter(|t| t.has_tag_name("texture")) {
                Some(t) => textures::mean(ctx, t, warnings),
                None => Err(ctx.invalid(p, id, "names no <texture id> of the file")),
            }
        }
        Some(p) => ctx.colour(p),
    }
}

/// A diffuse reflectance `name`: a colour (no texture), or a bitmap, nested or referenced, as
/// an albedo texture with factor 1; `default` where there is none.
fn albedo<'a, 'i>(
    ctx: &Context,
    node: Node<'a, 'i>,
    name: &str,
    default: Vec3,
    resolve: &dyn Fn(&str) -> Option<Node<'a, 'i>>,
    warnings: &mut Vec<String>,
) -> Result<(Vec3, Option<Albedo>), SceneError> {
    let texture = match property(node, name) {
        Some(p) if p.tag_name().name() == "texture" => p,
        Some(p) if p.tag_name().name() == "ref" => {
            let id = p.attribute("id").unwrap_or_default();
            match resolve(id).filter(|t| t.has_tag_name("texture")) {
                Some(t) => t,
                None => return Err(ctx.invalid(p, id, "names no <texture id> of the file")),
            }
        }
        _ => return Ok((colour(ctx, node, name, default, resolve, warnings)?, None)),
    };
    Ok((Vec3::ONE, Some(textures::albedo(ctx, texture, warnings)?)))
}

/// An index of refraction: a number or one of Mitsuba's named materials.
fn ior(ctx: &Context, node: Node, name: &str, default: f64) -> Result<f64, SceneError> {
    let Some(p) = property(node, name) else {
        return Ok(default);
    };
    if p.tag_name().name() != "string" {
        return ctx.float_attr(p, "value");
    }
    let v = ctx.required(p, "value")?;
    let known = [
        ("vacuum", 1.0),
        ("helium", 1.000036),
        ("hydrogen", 1.000132),
        ("air", 1.000277),
        ("carbon dioxide", 1.00045),
        ("water", 1.333),
        ("acetone", 1.36),
        ("ethanol", 1.361),
        ("carbon tetrachloride", 1.461),
        ("glycerol", 1.4729),
        ("benzene", 1.501),
        ("silicone oil", 1.52045),
        ("bromine", 1.661),
        ("water ice", 1.31),
        ("fused quartz", 1.458),
        ("pyrex", 1.47),
        ("acrylic glass", 1.49),
        ("polypropylene", 1.49),
        ("bk7", 1.5046),
        ("sodium chloride", 1.544),
        ("amber", 1.55),
        ("pet", 1.575),
        ("diamond", 2.419),
    ];
    known
        .iter()
        .find(|(n, _)| *n == v)
        .map(|(_, x)| *x)
        .ok_or_else(|| ctx.invalid(p, &v, "names no index of refraction Mitsuba knows"))
}

/// A number `name` (a bitmap, nested or referenced, as the mean of its mean colour's
/// channels, with a warning), else `default`.
fn float<'a, 'i>(
    ctx: &Context,
    node: Node<'a, 'i>,
    name: &str,
    default: f64,
    resolve: &dyn Fn(&str) -> Option<Node<'a, 'i>>,
    warnings: &mut Vec<String>,
) -> Result<f64, SceneError> {
    match property(node, name) {
        None => Ok(default),
        Some(p) if matches!(p.tag_name().name(), "texture" | "ref") => {
            let mean = colour(ctx, node, name, Vec3::ZERO, resolve, warnings)?;
            Ok(mean.as_dvec3().element_sum() / 3.0)
        }
        Some(p) => ctx.float_attr(p, "value"),
    }
}

/// Beckmann/GGX `alpha` (or the mean of `alpha_u` and `alpha_v`, with a warning).
fn alpha<'a, 'i>(
    ctx: &Context,
    node: Node<'a, 'i>,
    default: f64,
    resolve: &dyn Fn(&str) -> Option<Node<'a, 'i>>,
    warnings: &mut Vec<String>,
) -> Result<f64, SceneError> {
    if property(node, "alpha").is_some() {
        return float(ctx, node, "alpha", default, resolve, warnings);
    }
    if property(node, "alpha_u").is_some() || property(node, "alpha_v").is_some() {
        let (u, v) = (
            float(ctx, node, "alpha_u", default, resolve, warnings)?,
            float(ctx, node, "alpha_v", default, resolve, warnings)?,
        );
        warnings.push(format!(
            "{}: {} anisotropic roughness ({u}, {v}) as its mean {}",
            ctx.file,
            ctx.at(node),
            0.5 * (u + v)
        ));
        return Ok(0.5 * (u + v));
    }
    Ok(default)
}

/// irad's material parts for the `<bsdf>` element `node`; approximations are added to
/// `warnings`. `resolve` finds a `<ref id>`'s BSDF.
pub fn fit<'a, 'i>(
    ctx: &Context,
    node: Node<'a, 'i>,
    resolve: &dyn Fn(&str) -> Option<Node<'a, 'i>>,
    warnings: &mut Vec<String>,
) -> Result<Fit, SceneError> {
    let kind = ctx.attr(node, "type").unwrap_or_default();
    let nested = || -> Vec<Node<'a, 'i>> {
        node.children()
            .filter(|c| c.is_element())
            .filter_map(|c| match c.tag_name().name() {
                "bsdf" => Some(c),
                // A referenced BSDF (a `<ref>` to a texture is a property).
                "ref" => c
                    .attribute("id")
                    .and_then(resolve)
                    .filter(|n| n.has_tag_name("bsdf")),
                _ => None,
            })
            .collect()
    };
    let at = ctx.at(node);
    let zero = Vec3::ZERO;
    Ok(match kind.as_str() {
        "diffuse" => {
            let (kd, texture) = albedo(
                ctx,
                node,
                "reflectance",
                Vec3::splat(0.5),
                resolve,
                warnings,
            )?;
            Fit {
                kd,
                ks: zero,
                ns: 0.0,
                texture,
            }
        }
        "twosided" => match nested().first() {
            Some(inner) => fit(ctx, *inner, resolve, warnings)?,
            None => return Err(ctx.invalid(node, "twosided", "needs a nested <bsdf>")),
        },
        "roughconductor" | "conductor" => {
            let ks = colour(
                ctx,
                node,
                "specular_reflectance",
                Vec3::ONE,
                resolve,
                warnings,
            )?;
            if property(node, "material")
                .is_some_and(|m| ctx.attr(m, "value").as_deref() != Some("none"))
                || property(node, "eta").is_some()
            {
                warnings.push(format!(
                    "{}: {at}: the conductor's Fresnel term (its material or eta, k) is left \
                     out: irad's lobe reflects specular_reflectance {ks}",
                    ctx.file
                ));
            }
            let ns = if kind == "conductor" {
                warnings.push(format!(
                    "{}: {at}: a smooth mirror as a Phong lobe of Ns {MIRROR_NS}",
                    ctx.file
                ));
                MIRROR_NS
            } else {
                let distribution = property(node, "distribution")
                    .and_then(|d| ctx.attr(d, "value"))
                    .unwrap_or_else(|| "beckmann".into());
                if distribution != "beckmann" {
                    warnings.push(format!(
                        "{}: {at}: the {distribution} distribution fitted as Beckmann's (the \
                         same alpha): its longer tails are not modelled",
                        ctx.file
                    ));
                }
                ns_of_alpha(alpha(ctx, node, 0.1, resolve, warnings)?)
            };
            Fit::plain(zero, ks, ns)
        }
        "blendbsdf" => {
            let w = float(ctx, node, "weight", 0.5, resolve, warnings)?.clamp(0.0, 1.0) as f32;
            let parts = nested();
            if parts.len() != 2 {
                return Err(ctx.invalid(node, "blendbsdf", "needs two nested BSDFs"));
            }
            let (a, b) = (
                fit(ctx, parts[0], resolve, warnings)?,
                fit(ctx, parts[1], resolve, warnings)?,
            );
            if a.ks.max_element() > 0.0 && b.ks.max_element() > 0.0 && a.ns != b.ns {
                warnings.push(format!(
                    "{}: {at}: two glossy lobes (Ns {} and {}) as one of Ns {} (the second's)",
                    ctx.file, a.ns, b.ns, b.ns
                ));
            }
            let ks = (1.0 - w) * a.ks + w * b.ks;
            let ns = if b.ks.max_element() > 0.0 { b.ns } else { a.ns };
            let diffuse = |f: &Fit| f.kd.max_element() > 0.0;
            // (1 - w) Kd1 T1 + w Kd2 T2 is Kd T when one part has no diffuse part, or both read
            // the same texture the same way.
            let texture = match (&a.texture, &b.texture) {
                (None, None) => None,
                (Some(t), None) if !diffuse(&b) => Some(t.clone()),
                (None, Some(t)) if !diffuse(&a) => Some(t.clone()),
                (Some(t), Some(u)) if t == u => Some(t.clone()),
                _ => {
                    let why = "the blend's other part reflects diffusely too: irad's material \
                               is one Kd times one texture";
                    let flat = |f: &Fit, warnings: &mut Vec<String>| match &f.texture {
                        Some(t) => t.flatten(ctx, f.kd, why, warnings),
                        None => f.kd,
                    };
                    let (ka, kb) = (flat(&a, warnings), flat(&b, warnings));
                    return Ok(Fit::plain((1.0 - w) * ka + w * kb, ks, ns));
                }
            };
            Fit {
                kd: (1.0 - w) * a.kd + w * b.kd,
                ks,
                ns,
                texture,
            }
        }
        "plastic" | "roughplastic" => {
            let int_ior = ior(ctx, node, "int_ior", 1.49)?;
            let ext_ior = ior(ctx, node, "ext_ior", 1.000277)?;
            let eta = int_ior / ext_ior;
            let f0 = (((eta - 1.0) / (eta + 1.0)).powi(2)) as f32;
            let (kd, mut texture) = albedo(
                ctx,
                node,
                "diffuse_reflectance",
                Vec3::splat(0.5),
                resolve,
                warnings,
            )?;
            let mut kd = kd;
            let nonlinear = property(node, "nonlinear")
                .and_then(|p| ctx.attr(p, "value"))
                .is_some_and(|v| v == "true");
            if nonlinear {
                if let Some(t) = texture.take() {
                    kd = t.flatten(
                        ctx,
                        kd,
                        "nonlinear: the coat's internal scattering is not linear in the \
                         reflectance",
                        warnings,
                    );
                }
            }
            let ks = colour(
                ctx,
                node,
                "specular_reflectance",
                Vec3::ONE,
                resolve,
                warnings,
            )?;
            let ns = if kind == "plastic" {
                MIRROR_NS
            } else {
                ns_of_alpha(alpha(ctx, node, 0.1, resolve, warnings)?)
            };
            warnings.push(format!(
                "{}: {at}: {kind} as Kd = diffuse_reflectance (1 - F0), Ks = specular_reflectance \
                 F0 (F0 = {f0:.4} for eta {eta:.4}), Ns {ns}: albedos at normal incidence; the \
                 Fresnel rise towards grazing angles and the coat's internal scattering are not \
                 modelled",
                ctx.file
            ));
            Fit {
                kd: kd * (1.0 - f0),
                ks: ks * f0,
                ns,
                texture,
            }
        }
        "phong" => {
            let (kd, texture) = albedo(
                ctx,
                node,
                "diffuse_reflectance",
                Vec3::splat(0.5),
                resolve,
                warnings,
            )?;
            Fit {
                kd,
                ks: colour(
                    ctx,
                    node,
                    "specular_reflectance",
                    Vec3::splat(0.2),
                    resolve,
                    warnings,
                )?,
                ns: float(ctx, node, "exponent", 30.0, resolve, warnings)? as f32,
                texture,
            }
        }
        other => {
            warnings.push(format!(
                "{}: {at}: BSDF `{other}` is not modelled: rendered as grey Lambert (Kd 0.5)",
                ctx.file
            ));
            Fit::plain(Vec3::splat(0.5), zero, 0.0)
        }
    })
}
