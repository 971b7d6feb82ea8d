//! Mitsuba 3 XML's values: `<default>` substitution, numbers, colours, points and the
//! `to_world` transforms (translate, rotate, scale, matrix, lookat), each error naming the
//! file, the element's path and line, and the value.

use std::collections::HashMap;

use glam::{DMat4, DVec3, Vec3};
use roxmltree::Node;

use crate::scene::SceneError;

/// The file and its `<default>` values, for reading an element's attributes.
pub struct Context<'a> {
    pub file: &'a str,
    pub text: &'a str,
    /// The folder files are relative to.
    pub base: std::path::PathBuf,
    pub defaults: HashMap<String, String>,
    /// The content hash: the XML and every file it names.
    pub hash: std::cell::RefCell<crate::scene::hash::Fnv1a64>,
    /// Bitmaps decoded so far, by file and `raw` flag (a BSDF shared by many shapes is fitted
    /// once per shape, its bitmap decoded once).
    pub textures: std::cell::RefCell<
        HashMap<(std::path::PathBuf, bool), std::rc::Rc<super::textures::Image>>,
    >,
}

impl Context<'_> {
    /// Where `node` is: "line N <tag name=...>".
    pub fn at(&self, node: Node) -> String {
        let line = self.text[..node.range().start].matches('\n').count() + 1;
        let name = node
            .attribute("name")
            .map(|n| format!(" name=\"{n}\""))
            .unwrap_or_default();
        let kind = node
            .attribute("type")
            .map(|n| format!(" type=\"{n}\""))
            .unwrap_or_default();
        format!("line {line} <{}{kind}{name}>", node.tag_name().name())
    }

    pub fn invalid(&self, node: Node, value: &str, problem: &str) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_string(),
            field: self.at(node),
            value: value.to_string(),
            problem: problem.to_string(),
        }
    }

    /// An attribute with `$name` defaults substituted.
    pub fn attr(&self, node: Node, key: &str) -> Option<String> {
        let raw = node.attribute(key)?;
        if !raw.contains('$') {
            return Some(raw.to_string());
        }
        let mut out = raw.to_string();
        // Longest names first, so that $spp_max is not read as $spp.
        let mut names: Vec<&String> = self.defaults.keys().collect();
        names.sort_by_key(|n| std::cmp::Reverse(n.len()));
        for n in names {
            out = out.replace(&format!("${n}"), &self.defaults[n]);
        }
        Some(out)
    }

    pub fn required(&self, node: Node, key: &str) -> Result<String, SceneError> {
        self.attr(node, key)
            .ok_or_else(|| self.invalid(node, "", &format!("needs a `{key}` attribute")))
    }

    pub fn float_attr(&self, node: Node, key: &str) -> Result<f64, SceneError> {
        let v = self.required(node, key)?;
        v.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| self.invalid(node, &v, &format!("`{key}` must be a finite number")))
    }

    fn optional_float(&self, node: Node, key: &str) -> Result<Option<f64>, SceneError> {
        match node.attribute(key) {
            Some(_) => self.float_attr(node, key).map(Some),
            None => Ok(None),
        }
    }

    /// Numbers separated by commas and/or spaces.
    pub fn numbers(&self, node: Node, text: &str) -> Result<Vec<f64>, SceneError> {
        text.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| {
                s.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| self.invalid(node, text, "must be finite numbers"))
            })
            .collect()
    }

    /// A vector from `x`, `y`, `z` attributes (missing ones `default`) or a `value` of three
    /// (or one, for every component).
    pub fn vector(&self, node: Node, default: f64) -> Result<DVec3, SceneError> {
        if let Some(v) = self.attr(node, "value") {
            let n = self.numbers(node, &v)?;
            return match n.len() {
                1 => Ok(DVec3::splat(n[0])),
                3 => Ok(DVec3::new(n[0], n[1], n[2])),
                _ => Err(self.invalid(node, &v, "must be one number or three")),
            };
        }
        Ok(DVec3::new(
            self.optional_float(node, "x")?.unwrap_or(default),
            self.optional_float(node, "y")?.unwrap_or(default),
            self.optional_float(node, "z")?.unwrap_or(default),
        ))
    }

    /// A colour property: `<rgb value>` (three numbers or one), `<float value>` (grey) or
    /// `<spectrum value>` (one number; an `srgb` spectrum's `<rgb name="color">`).
    pub fn colour(&self, node: Node) -> Result<Vec3, SceneError> {
        match node.tag_name().name() {
            "rgb" | "float" => {
                let v = self.required(node, "value")?;
                let n = self.numbers(node, &v)?;
                match n.len() {
                    1 => Ok(Vec3::splat(n[0] as f32)),
                    3 => Ok(Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32)),
                    _ => Err(self.invalid(node, &v, "a colour is one number or three")),
                }
            }
            "spectrum" => {
                if let Some(v) = self.attr(node, "value") {
                    let n = self.numbers(node, &v)?;
                    if n.len() == 1 {
                        return Ok(Vec3::splat(n[0] as f32));
                    }
                    return Err(self.invalid(
                        node,
                        &v,
                        "a spectrum given by wavelengths is not read: give an <rgb> or one number",
                    ));
                }
                let colour = node
                    .children()
                    .find(|c| c.is_element() && c.attribute("name") == Some("color"));
                match colour {
                    Some(c) => self.colour(c),
                    None => Err(self.invalid(
                        node,
                        "",
                        "a spectrum needs a value or an <rgb name=\"color\">",
                    )),
                }
            }
            other => Err(self.invalid(node, other, "expected <rgb>, <float> or <spectrum>")),
        }
    }
}

/// The `to_world` of `transform` (a `<transform>` element): its children composed in order,
/// each applied after the ones before it (Mitsuba's convention).
pub fn transform(ctx: &Context, transform: Node) -> Result<DMat4, SceneError> {
    let mut m = DMat4::IDENTITY;
    for op in transform.children().filter(|c| c.is_element()) {
        let step = match op.tag_name().name() {
            "translate" => DMat4::from_translation(ctx.vector(op, 0.0)?),
            "scale" => DMat4::from_scale(ctx.vector(op, 1.0)?),
            "rotate" => {
                let axis = ctx.vector(op, 0.0)?;
                let angle = ctx.float_attr(op, "angle")?;
                if axis.length_squared() == 0.0 {
                    return Err(ctx.invalid(op, "0, 0, 0", "a rotation needs a non-zero axis"));
                }
                DMat4::from_axis_angle(axis.normalize(), angle.to_radians())
            }
            "matrix" => {
                let v = ctx.required(op, "value")?;
                let n = ctx.numbers(op, &v)?;
                match n.len() {
                    16 => DMat4::from_cols_array(&[
                        n[0], n[4], n[8], n[12], n[1], n[5], n[9], n[13], n[2], n[6], n[10], n[14],
                        n[3], n[7], n[11], n[15],
                    ]),
                    9 => DMat4::from_cols_array(&[
                        n[0], n[3], n[6], 0.0, n[1], n[4], n[7], 0.0, n[2], n[5], n[8], 0.0, 0.0,
                        0.0, 0.0, 1.0,
                    ]),
                    _ => return Err(ctx.invalid(op, &v, "a matrix has 16 numbers (or 9)")),
                }
            }
            "lookat" => {
                let l = lookat(ctx, op)?;
                l.matrix()
            }
            other => {
                return Err(ctx.invalid(
                    op,
                    other,
                    "transforms are translate, rotate, scale, matrix and lookat",
                ))
            }
        };
        m = step * m;
    }
    Ok(m)
}

/// A `<lookat origin target up>`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookAt {
    pub origin: DVec3,
    pub target: DVec3,
    pub up: DVec3,
}

impl LookAt {
    /// Mitsuba's matrix: columns left = up x dir, up' = dir x left, dir, origin.
    pub fn matrix(&self) -> DMat4 {
        let dir = (self.target - self.origin).normalize();
        let left = self.up.cross(dir).normalize();
        let up = dir.cross(left);
        DMat4::from_cols(
            left.extend(0.0),
            up.extend(0.0),
            dir.extend(0.0),
            self.origin.extend(1.0),
        )
    }
}

pub fn lookat(ctx: &Context, op: Node) -> Result<LookAt, SceneError> {
    let point = |key: &str, default: Option<DVec3>| -> Result<DVec3, SceneError> {
        match (ctx.attr(op, key), default) {
            (Some(v), _) => {
                let n = ctx.numbers(op, &v)?;
                if n.len() != 3 {
                    return Err(ctx.invalid(op, &v, &format!("`{key}` needs three numbers")));
                }
                Ok(DVec3::new(n[0], n[1], n[2]))
            }
            (None, Some(d)) => Ok(d),
            (None, None) => Err(ctx.invalid(op, "", &format!("needs `{key}`"))),
        }
    };
    let origin = point("origin", None)?;
    let target = point("target", None)?;
    // Without an up (or a zero one), Mitsuba's: the first axis of coordinate_system(dir).
    let up = point("up", Some(DVec3::ZERO))?;
    let up = if up == DVec3::ZERO {
        let n = (target - origin).normalize_or_zero();
        let sign = 1f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x)
    } else {
        up
    };
    let l = LookAt { origin, target, up };
    let dir = l.target - l.origin;
    if dir.length_squared() == 0.0 || l.up.cross(dir).length_squared() == 0.0 {
        return Err(ctx.invalid(
            op,
            &format!("{:?} -> {:?}, up {:?}", l.origin, l.target, l.up),
            "origin and target must differ and up must not be along the view",
        ));
    }
    Ok(l)
}
