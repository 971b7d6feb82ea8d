//! Mitsuba 3 XML scenes (docs/scenes.md "Mitsuba scenes"): `irad render scene.xml` reads the
//! subset `irad export mitsuba` writes and the common research subset, each element irad does
//! not model exactly approximated with a warning that names it and what was done, or refused.
//!
//! Read: `<default>` values (`$name`); `sensor` perspective (fov and fov_axis, or
//! focal_length; `to_world`; `hdrfilm` width and height); shapes ply, obj, rectangle, cube,
//! disk, sphere (tessellated: `<integer name="tessellation">` segments, 64 by default), each
//! with `to_world`, `flip_normals`, `face_normals`, texture coordinates (shapes.rs), a nested
//! or referenced BSDF (bsdf.rs, its bitmap reflectance an albedo texture: textures.rs) and
//! an `area` emitter; emitters point, spot, envmap (EXR) and constant. Ignored without a word:
//! `integrator`, `sampler`, `rfilter`, a film's formats (irad has its own). Refused: other
//! emitters and shapes, `include`, a second sensor is ignored with a warning.

mod bsdf;
mod props;
mod shapes;
mod textures;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3, Vec3};
use roxmltree::{Document, Node};

use super::hash::Fnv1a64;
use super::{environment, power};
use super::{Camera, Environment, Light, Material, Scene, SceneError, Texture, Triangle, Wrap};
use props::Context;

/// The diagonal of the 36 x 24 mm film a 35 mm-equivalent focal length is over.
const DIAGONAL_MM: f64 = 43.266_615_305_567_87;
use shapes::RawTriangle;

pub use bsdf::{ns_of_alpha, MIRROR_NS};

/// Whether `path` names a Mitsuba XML scene (by its extension).
pub fn is_mitsuba(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// Loads the Mitsuba scene at `path`; the files it names are relative to its folder.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let (file, bytes) = crate::scene::load::read_scene_file(path)?;
    let text = String::from_utf8(bytes).map_err(|e| SceneError::File {
        file: file.clone(),
        message: format!("not UTF-8 text: {e}"),
    })?;
    let doc = Document::parse(&text).map_err(|e| SceneError::File {
        file: file.clone(),
        message: format!("not well-formed XML: {e}"),
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "scene" {
        return Err(SceneError::File {
            file,
            message: format!(
                "the root element is <{}>, not <scene>",
                root.tag_name().name()
            ),
        });
    }
    // Mitsuba 0.x files name properties in camelCase (toWorld, diffuseReflectance), which
    // Mitsuba 3 upgrades on reading; irad reads Mitsuba 3's names only.
    let version = root.attribute("version").unwrap_or("");
    let major: u32 = version
        .split('.')
        .next()
        .and_then(|m| m.parse().ok())
        .unwrap_or(0);
    if major < 2 {
        return Err(SceneError::Unsupported {
            file,
            field: "<scene version>".into(),
            value: format!("{version:?}"),
            what: "Mitsuba 0.x scenes (camelCase property names; Mitsuba 3's \
                   `mitsuba.xml.upgrade` or a load and save in Mitsuba 3 converts them)"
                .into(),
        });
    }
    let mut hash = Fnv1a64::default();
    hash.write(text.as_bytes());
    let mut ctx = Context {
        file: &file,
        text: &text,
        base: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        defaults: HashMap::new(),
        hash: std::cell::RefCell::new(hash),
        textures: Default::default(),
    };
    for d in root.children().filter(|c| c.has_tag_name("default")) {
        let (Some(name), Some(value)) = (d.attribute("name"), d.attribute("value")) else {
            return Err(ctx.invalid(d, "", "a <default> needs a name and a value"));
        };
        ctx.defaults.insert(name.to_string(), value.to_string());
    }
    let mut builder = Builder::default();
    let ids: HashMap<String, Node> = root
        .descendants()
        .filter(|n| n.is_element() && !n.has_tag_name("ref"))
        .filter_map(|n| n.attribute("id").map(|id| (id.to_string(), n)))
        .collect();
    let resolve = |id: &str| ids.get(id).copied();
    for (k, node) in root.children().filter(|c| c.is_element()).enumerate() {
        match node.tag_name().name() {
            "default" | "integrator" | "sampler" | "bsdf" | "texture" => {}
            "sensor" => {
                if builder.camera.is_some() {
                    builder.warnings.push(format!(
                        "{file}: {}: a second sensor is ignored",
                        ctx.at(node)
                    ));
                } else {
                    builder.camera = Some(sensor(&ctx, node)?);
                }
            }
            "shape" => builder.shape(&ctx, node, k, &resolve)?,
            "emitter" => builder.emitter(&ctx, node)?,
            "include" => {
                return Err(SceneError::Unsupported {
                    file: file.clone(),
                    field: ctx.at(node),
                    value: ctx.attr(node, "filename").unwrap_or_default(),
                    what: "included files".into(),
                })
            }
            other => builder
                .warnings
                .push(format!("{file}: {}: <{other}> is not read", ctx.at(node))),
        }
    }
    builder.finish(&ctx, path)
}

#[derive(Default)]
struct Builder {
    camera: Option<Camera>,
    triangles: Vec<Triangle>,
    materials: Vec<Material>,
    /// Material index by its key (BSDF id or shape, and emitted radiance bits).
    material_index: HashMap<String, u32>,
    lights: Vec<Light>,
    textures: Vec<Texture>,
    /// Scene texture by file, `raw` flag and wrap.
    texture_index: HashMap<(PathBuf, bool, [Wrap; 2]), u32>,
    environment: Option<(Environment, f32, String)>,
    warnings: Vec<String>,
    dropped: usize,
}

/// The named child property of `node`.
fn property<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.attribute("name") == Some(name))
}

fn float_property(ctx: &Context, node: Node, name: &str, default: f64) -> Result<f64, SceneError> {
    match property(node, name) {
        Some(p) => ctx.float_attr(p, "value"),
        None => Ok(default),
    }
}

fn bool_property(ctx: &Context, node: Node, name: &str) -> bool {
    property(node, name)
        .and_then(|p| ctx.attr(p, "value"))
        .is_some_and(|v| v == "true")
}

fn to_world(ctx: &Context, node: Node) -> Result<DMat4, SceneError> {
    match node
        .children()
        .find(|c| c.has_tag_name("transform") && c.attribute("name") == Some("to_world"))
    {
        Some(t) => props::transform(ctx, t),
        None => Ok(DMat4::IDENTITY),
    }
}

/// A perspective sensor as irad's camera.
fn sensor(ctx: &Context, node: Node) -> Result<Camera, SceneError> {
    let kind = ctx.attr(node, "type").unwrap_or_default();
    if kind != "perspective" {
        return Err(SceneError::Unsupported {
            file: ctx.file.to_string(),
            field: ctx.at(node),
            value: kind,
            what: "sensors other than perspective".into(),
        });
    }
    let film = node.children().find(|c| c.has_tag_name("film"));
    let (mut width, mut height) = (768u32, 576u32);
    if let Some(f) = film {
        for (name, v) in [("width", &mut width), ("height", &mut height)] {
            if let Some(p) = property(f, name) {
                let value = ctx.float_attr(p, "value")?;
                if !(1.0..=super::MAX_RESOLUTION as f64).contains(&value) || value.fract() != 0.0 {
                    return Err(ctx.invalid(
                        p,
                        &value.to_string(),
                        &format!("must be a whole number in 1..={}", super::MAX_RESOLUTION),
                    ));
                }
                *v = value as u32;
            }
        }
    }
    let aspect = width as f64 / height as f64;
    let (fov, axis) = match (property(node, "fov"), property(node, "focal_length")) {
        (Some(p), _) => (
            ctx.float_attr(p, "value")?,
            property(node, "fov_axis")
                .and_then(|a| ctx.attr(a, "value"))
                .unwrap_or_else(|| "x".into()),
        ),
        (None, Some(p)) => {
            // A 35 mm equivalent focal length: Mitsuba's field of view over the 36 x 24 mm
            // film's diagonal (43.27 mm).
            let v = ctx.required(p, "value")?;
            let mm: f64 = v
                .trim_end_matches("mm")
                .trim()
                .parse()
                .ok()
                .filter(|f: &f64| *f > 0.0)
                .ok_or_else(|| ctx.invalid(p, &v, "a focal length such as \"50mm\""))?;
            (
                2.0 * (DIAGONAL_MM / (2.0 * mm)).atan().to_degrees(),
                "diagonal".to_string(),
            )
        }
        // Mitsuba's default: a 50 mm focal length.
        (None, None) => (
            2.0 * (DIAGONAL_MM / 100.0).atan().to_degrees(),
            "diagonal".to_string(),
        ),
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(ctx.invalid(node, &fov.to_string(), "fov must be in (0, 180) degrees"));
    }
    // tan(fov_y / 2) from the axis the fov is given over.
    let t = (fov.to_radians() / 2.0).tan();
    let diagonal = (1.0 + aspect * aspect).sqrt();
    let ty = match axis.to_ascii_lowercase().as_str() {
        "x" => t / aspect,
        "y" => t,
        "diagonal" => t / diagonal,
        "smaller" => {
            if aspect >= 1.0 {
                t
            } else {
                t / aspect
            }
        }
        "larger" => {
            if aspect >= 1.0 {
                t / aspect
            } else {
                t
            }
        }
        other => {
            return Err(ctx.invalid(node, other, "fov_axis is x, y, diagonal, smaller or larger"))
        }
    };
    let fov_y = (2.0 * ty.atan()).to_degrees() as f32;
    // A lookat alone is kept as written (bit for bit); any other transform by its axes.
    let transform = node
        .children()
        .find(|c| c.has_tag_name("transform") && c.attribute("name") == Some("to_world"));
    let ops: Vec<Node> = transform
        .map(|t| t.children().filter(|c| c.is_element()).collect())
        .unwrap_or_default();
    let (position, look_at, up) = if ops.len() == 1 && ops[0].has_tag_name("lookat") {
        let l = props::lookat(ctx, ops[0])?;
        (l.origin, l.target, l.up)
    } else {
        let m = to_world(ctx, node)?;
        if m.determinant() <= 0.0 {
            return Err(ctx.invalid(
                node,
                &format!("determinant {}", m.determinant()),
                "the sensor's to_world mirrors or collapses the view (a negative or zero \
                 scale), which irad's camera cannot",
            ));
        }
        let p = m.transform_point3(DVec3::ZERO);
        let forward = m.transform_vector3(DVec3::Z).normalize();
        (p, p + forward, m.transform_vector3(DVec3::Y).normalize())
    };
    // The TOML camera's checks (finite, within the coordinate limit, up off the view).
    let file = super::file::CameraFile {
        position: position.as_vec3().to_array(),
        look_at: look_at.as_vec3().to_array(),
        up: up.as_vec3().to_array(),
        fov_y,
        resolution: [i64::from(width), i64::from(height)],
    };
    super::camera::build(&format!("{} ({})", ctx.file, ctx.at(node)), &file)
}

impl Builder {
    fn shape<'a, 'i>(
        &mut self,
        ctx: &Context,
        node: Node<'a, 'i>,
        k: usize,
        resolve: &dyn Fn(&str) -> Option<Node<'a, 'i>>,
    ) -> Result<(), SceneError> {
        let kind = ctx.attr(node, "type").unwrap_or_default();
        let m = to_world(ctx, node)?;
        let segments = match property(node, "tessellation") {
            Some(p) => {
                let v = ctx.float_attr(p, "value")?;
                if !(3.0..=4096.0).contains(&v) {
                    return Err(ctx.invalid(
                        p,
                        &v.to_string(),
                        "tessellation is 3..=4096 segments",
                    ));
                }
                v as u32
            }
            None => shapes::DEFAULT_SEGMENTS,
        };
        let file_of = |name: &str| -> Result<PathBuf, SceneError> {
            let p = property(node, name).ok_or_else(|| {
                ctx.invalid(node, &kind, &format!("needs <string name=\"{name}\">"))
            })?;
            Ok(ctx.base.join(ctx.required(p, "value")?))
        };
        let local = match kind.as_str() {
            "ply" | "obj" => {
                let path = file_of("filename")?;
                let bytes = std::fs::read(&path).map_err(|error| SceneError::Read {
                    path: path.display().to_string(),
                    referenced_by: format!("{}: {}", ctx.file, ctx.at(node)),
                    error,
                })?;
                ctx.hash.borrow_mut().write(&bytes);
                let display = path.display().to_string();
                // Mitsuba's defaults: ply false, obj true.
                let flip = match property(node, "flip_tex_coords") {
                    Some(p) => ctx.attr(p, "value").is_some_and(|v| v == "true"),
                    None => kind == "obj",
                };
                match kind.as_str() {
                    "ply" => {
                        shapes::read_ply(&bytes, flip).map_err(|message| SceneError::File {
                            file: display,
                            message: format!(
                                "{message} (the ply shape at {} of {})",
                                ctx.at(node),
                                ctx.file
                            ),
                        })?
                    }
                    _ => shapes::read_obj(&display, &String::from_utf8_lossy(&bytes), flip)?,
                }
            }
            "rectangle" => shapes::rectangle(),
            "cube" => shapes::cube(),
            "disk" => shapes::disk(segments),
            "sphere" => {
                let center = match property(node, "center") {
                    Some(p) => ctx.vector(p, 0.0)?,
                    None => DVec3::ZERO,
                };
                let radius = float_property(ctx, node, "radius", 1.0)?;
                if radius <= 0.0 {
                    return Err(ctx.invalid(
                        node,
                        &radius.to_string(),
                        "a sphere's radius must be positive",
                    ));
                }
                self.warnings.push(format!(
                    "{}: {}: the sphere tessellated into {} segments and {} rings",
                    ctx.file,
                    ctx.at(node),
                    segments.max(4),
                    (segments / 2).max(2)
                ));
                shapes::sphere(center, radius, segments)
            }
            other => {
                return Err(SceneError::Unsupported {
                    file: ctx.file.to_string(),
                    field: ctx.at(node),
                    value: other.to_string(),
                    what: format!("Mitsuba `{other}` shapes"),
                })
            }
        };
        let local = if bool_property(ctx, node, "face_normals") {
            local
                .into_iter()
                .map(|t| shapes::LocalTriangle { normals: None, ..t })
                .collect()
        } else {
            local
        };
        let raw = shapes::to_world(local, m, bool_property(ctx, node, "flip_normals"));
        // Its BSDF: nested, referenced, or Mitsuba's default (diffuse 0.5).
        let mut warnings = Vec::new();
        let mut bsdf = None;
        for c in node.children().filter(|c| c.is_element()) {
            match c.tag_name().name() {
                "bsdf" => bsdf = bsdf.or(Some((c, None))),
                "ref" if c.attribute("name").is_none_or(|n| n == "bsdf") => {
                    let id = c.attribute("id").unwrap_or_default();
                    let target = resolve(id)
                        .filter(|t| t.has_tag_name("bsdf"))
                        .ok_or_else(|| ctx.invalid(c, id, "names no <bsdf id> of the file"))?;
                    bsdf = bsdf.or(Some((target, Some(id.to_string()))));
                }
                _ => {}
            }
        }
        if let Some((b, _)) = bsdf
            .as_ref()
            .filter(|(b, _)| ctx.attr(*b, "type").as_deref() != Some("twosided"))
        {
            warnings.push(format!(
                "{}: {}: a one-sided BSDF (black from behind in Mitsuba): irad's materials \
                 reflect on both sides",
                ctx.file,
                ctx.at(*b)
            ));
        }
        let (fit, bsdf_name) = match bsdf {
            Some((b, id)) => (
                bsdf::fit(ctx, b, resolve, &mut warnings)?,
                id.or_else(|| b.attribute("id").map(str::to_string)),
            ),
            None => (
                bsdf::Fit {
                    kd: Vec3::splat(0.5),
                    ks: Vec3::ZERO,
                    ns: 0.0,
                    texture: None,
                },
                None,
            ),
        };
        // A texture reads the shape's coordinates through its to_uv; Mitsuba reads (0, 0)
        // where a mesh has none.
        let uv_map = fit.texture.as_ref().map(|t| t.uv);
        if fit.texture.is_some() && raw.iter().any(|t| t.uvs.is_none()) {
            self.warnings.push(format!(
                "{}: {}: a textured shape without texture coordinates: its texture is read at \
                 uv (0, 0), one texel's colour, as Mitsuba reads it",
                ctx.file,
                ctx.at(node)
            ));
        }
        let ke = match node.children().find(|c| c.has_tag_name("emitter")) {
            Some(e) => {
                let kind = ctx.attr(e, "type").unwrap_or_default();
                if kind != "area" {
                    return Err(ctx.invalid(e, &kind, "a shape's emitter must be `area`"));
                }
                match property(e, "radiance") {
                    Some(r) => ctx.colour(r)?,
                    None => Vec3::ONE,
                }
            }
            None => Vec3::ZERO,
        };
        let name = bsdf_name.unwrap_or_else(|| {
            node.attribute("id")
                .map(str::to_string)
                .unwrap_or_else(|| format!("shape {k} ({kind})"))
        });
        let material = self.material(ctx, node, name, fit, ke, warnings)?;
        let limit = super::obj::MAX_COORDINATE;
        if let Some(bad) = raw
            .iter()
            .flat_map(|t| t.positions)
            .find(|p| !p.is_finite() || p.abs().max_element() > limit)
        {
            return Err(ctx.invalid(
                node,
                &format!("{bad}"),
                &format!(
                    "a vertex in the world is not finite or past {limit:e}, the most irad's f32 \
                     rays and BVH handle"
                ),
            ));
        }
        for t in raw {
            if super::load::is_degenerate(t.positions) {
                self.dropped += 1;
                continue;
            }
            let uvs = match (uv_map, t.uvs) {
                (Some(map), uvs) => uvs
                    .unwrap_or([glam::Vec2::new(0.0, 1.0); 3])
                    .map(|uv| map.apply(uv)),
                (None, uvs) => uvs.unwrap_or([glam::Vec2::ZERO; 3]),
            };
            self.triangles.push(triangle(t, uvs, material));
        }
        Ok(())
    }

    /// The index of the material `name` with `fit` and emission `ke`, added when new (its
    /// Kd + Ks brought within 1 per channel, with a warning, as irad requires).
    fn material(
        &mut self,
        ctx: &Context,
        node: Node,
        name: String,
        fit: bsdf::Fit,
        ke: Vec3,
        warnings: Vec<String>,
    ) -> Result<u32, SceneError> {
        let texture = fit.texture.as_ref().map(|t| self.texture(t));
        let key = format!(
            "{name}|{:?}|{:?}|{:?}|{:?}|{texture:?}",
            fit.kd, fit.ks, fit.ns, ke
        );
        if let Some(&i) = self.material_index.get(&key) {
            return Ok(i);
        }
        self.warnings.extend(warnings);
        let mut fit = fit;
        for v in [fit.kd, fit.ks, ke] {
            if !(v.is_finite() && v.min_element() >= 0.0) {
                return Err(ctx.invalid(node, &format!("{v}"), "colours must be finite and >= 0"));
            }
        }
        if !(fit.ns.is_finite() && fit.ns >= 0.0) {
            return Err(ctx.invalid(
                node,
                &fit.ns.to_string(),
                "the Phong exponent must be finite and >= 0",
            ));
        }
        let sum = (fit.kd + fit.ks).max_element();
        if sum > 1.0 + 1e-5 {
            self.warnings.push(format!(
                "{}: {}: Kd {} + Ks {} reflects more than it receives; both scaled by {}",
                ctx.file,
                ctx.at(node),
                fit.kd,
                fit.ks,
                1.0 / sum
            ));
            fit.kd /= sum;
            fit.ks /= sum;
        }
        let index = self.materials.len() as u32;
        let emitting = if ke.max_element() > 0.0 && self.materials.iter().any(|m| m.name == name) {
            format!("{name} (emitting)")
        } else {
            name
        };
        self.materials.push(Material {
            name: emitting,
            kd: fit.kd,
            ks: fit.ks,
            ns: fit.ns,
            ke,
            albedo_texture: texture,
        });
        self.material_index.insert(key, index);
        Ok(index)
    }

    /// The scene texture of `albedo` (one per file, `raw` flag and wrap).
    fn texture(&mut self, albedo: &textures::Albedo) -> u32 {
        let key = (albedo.path.clone(), albedo.raw, albedo.wrap);
        if let Some(&i) = self.texture_index.get(&key) {
            return i;
        }
        let index = self.textures.len() as u32;
        self.textures.push(Texture {
            wrap: albedo.wrap,
            ..albedo.image.texture.clone()
        });
        self.texture_index.insert(key, index);
        index
    }

    fn emitter(&mut self, ctx: &Context, node: Node) -> Result<(), SceneError> {
        let kind = ctx.attr(node, "type").unwrap_or_default();
        let m = to_world(ctx, node)?;
        let colour = |name: &str, default: Vec3| -> Result<Vec3, SceneError> {
            match property(node, name) {
                Some(p) => ctx.colour(p),
                None => Ok(default),
            }
        };
        match kind.as_str() {
            "point" => {
                let position = match property(node, "position") {
                    Some(p) => ctx.vector(p, 0.0)?,
                    None => m.transform_point3(DVec3::ZERO),
                };
                let light = super::file::LightFile {
                    kind: "point".into(),
                    position: position.as_vec3().to_array(),
                    intensity: colour("intensity", Vec3::ONE)?.to_array(),
                    direction: None,
                    cone_angle: None,
                    falloff_angle: None,
                };
                self.lights.push(self.checked_light(ctx, node, &light)?);
            }
            "spot" => {
                let cutoff = float_property(ctx, node, "cutoff_angle", 20.0)?;
                let beam = float_property(ctx, node, "beam_width", cutoff * 0.75)?;
                if !(beam > 0.0 && beam <= cutoff && cutoff <= 180.0) {
                    return Err(ctx.invalid(
                        node,
                        &format!("beam_width {beam}, cutoff_angle {cutoff}"),
                        "needs 0 < beam_width <= cutoff_angle <= 180",
                    ));
                }
                self.warnings.push(format!(
                    "{}: {}: the spot's linear ramp in angle from beam_width {beam} to \
                     cutoff_angle {cutoff} degrees as irad's smoothstep in cos(theta) between \
                     the same angles",
                    ctx.file,
                    ctx.at(node)
                ));
                let light = super::file::LightFile {
                    kind: "spot".into(),
                    position: m.transform_point3(DVec3::ZERO).as_vec3().to_array(),
                    intensity: colour("intensity", Vec3::ONE)?.to_array(),
                    direction: Some(
                        m.transform_vector3(DVec3::Z)
                            .normalize()
                            .as_vec3()
                            .to_array(),
                    ),
                    cone_angle: Some(beam as f32),
                    falloff_angle: Some(cutoff as f32),
                };
                self.lights.push(self.checked_light(ctx, node, &light)?);
            }
            "envmap" | "constant" => {
                if self.environment.is_some() {
                    return Err(ctx.invalid(node, &kind, "irad takes one environment emitter"));
                }
                if m != DMat4::IDENTITY {
                    self.warnings.push(format!(
                        "{}: {}: the environment's to_world is left out (irad's map is in \
                         world axes)",
                        ctx.file,
                        ctx.at(node)
                    ));
                }
                let scale = float_property(ctx, node, "scale", 1.0)? as f32;
                if scale < 0.0 {
                    return Err(ctx.invalid(node, &scale.to_string(), "scale must be >= 0"));
                }
                let (map, source) = if kind == "constant" {
                    let radiance = colour("radiance", Vec3::ONE)?;
                    if !(radiance.is_finite() && radiance.min_element() >= 0.0) {
                        return Err(ctx.invalid(
                            node,
                            &format!("{radiance}"),
                            "radiance must be finite and >= 0",
                        ));
                    }
                    let map = Environment {
                        width: 8,
                        height: 4,
                        texels: vec![radiance * scale; 32],
                        source: PathBuf::from("constant"),
                    };
                    (map, "the constant emitter's radiance".to_string())
                } else {
                    let p = property(node, "filename").ok_or_else(|| {
                        ctx.invalid(node, &kind, "needs <string name=\"filename\">")
                    })?;
                    let name = ctx.required(p, "value")?;
                    if !name.to_ascii_lowercase().ends_with(".exr") {
                        return Err(SceneError::Unsupported {
                            file: ctx.file.to_string(),
                            field: ctx.at(p),
                            value: name,
                            what: "environment maps other than OpenEXR".into(),
                        });
                    }
                    let path = ctx.base.join(&name);
                    let bytes = std::fs::read(&path).map_err(|error| SceneError::Read {
                        path: path.display().to_string(),
                        referenced_by: format!("{}: {}", ctx.file, ctx.at(p)),
                        error,
                    })?;
                    ctx.hash.borrow_mut().write(&bytes);
                    let map = environment::read(&path.display().to_string(), &path, scale)?;
                    (map, format!("envmap filename {name:?}"))
                };
                self.environment = Some((map, scale, source));
            }
            other => {
                return Err(SceneError::Unsupported {
                    file: ctx.file.to_string(),
                    field: ctx.at(node),
                    value: other.to_string(),
                    what: format!("Mitsuba `{other}` emitters"),
                })
            }
        }
        Ok(())
    }

    /// A light through the TOML lights' checks (finite, within the coordinate limit, intensity
    /// >= 0, angles in range).
    fn checked_light(
        &self,
        ctx: &Context,
        node: Node,
        light: &super::file::LightFile,
    ) -> Result<Light, SceneError> {
        super::lights::build(
            &format!("{} ({})", ctx.file, ctx.at(node)),
            self.lights.len(),
            light,
        )
    }

    fn finish(self, ctx: &Context, path: &Path) -> Result<Scene, SceneError> {
        let file = ctx.file.to_string();
        let mut warnings = self.warnings;
        if self.dropped > 0 {
            warnings.push(format!(
                "{file}: dropped {} degenerate triangles (area <= {:e} x the square of the \
                 triangle's longest edge)",
                self.dropped,
                super::DEGENERATE_AREA
            ));
        }
        let Some(camera) = self.camera else {
            return Err(SceneError::File {
                file,
                message: "no <sensor type=\"perspective\">: irad needs a camera".into(),
            });
        };
        if self.triangles.is_empty() {
            return Err(SceneError::Empty {
                file,
                detail: " (no <shape> with triangles)".into(),
            });
        }
        let emits = self
            .triangles
            .iter()
            .any(|t| self.materials[t.material as usize].is_emissive())
            || self.lights.iter().any(|l| match l {
                Light::Point { intensity, .. } | Light::Spot { intensity, .. } => {
                    intensity.max_element() > 0.0
                }
            })
            || self
                .environment
                .as_ref()
                .is_some_and(|(e, _, _)| e.texels.iter().any(|t| t.max_element() > 0.0));
        if !emits {
            return Err(SceneError::NoLight { file });
        }
        let (environment, env_source) = match self.environment {
            Some((map, scale, source)) => (Some(map), Some((scale, source))),
            None => (None, None),
        };
        let scene = Scene {
            source: Some(path.to_path_buf()),
            name: String::new(),
            content_hash: ctx.hash.borrow().finish(),
            camera,
            triangles: self.triangles,
            materials: self.materials,
            lights: self.lights,
            textures: self.textures,
            environment,
            environment_sequence: Vec::new(),
            luminaires: Vec::new(),
            failure: None,
            warnings,
            animation: None,
            load_ms: 0.0,
        };
        let material_files = vec![Some(file.clone()); scene.materials.len()];
        power::check(
            &scene,
            &power::PowerSources {
                file: &file,
                material_files: &material_files,
                environment: env_source,
            },
        )?;
        Ok(scene)
    }
}

/// A shape's triangle with unit shading normals (the geometric one where a normal is zero).
fn triangle(t: RawTriangle, uvs: [glam::Vec2; 3], material: u32) -> Triangle {
    let p = t.positions;
    let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
    Triangle {
        positions: p,
        normals: t.normals.map(|n| {
            // A unit normal (to f32 rounding) keeps its bits.
            let n = if (n.length_squared() - 1.0).abs() <= 1e-6 {
                n
            } else {
                n.normalize_or_zero()
            };
            if n == Vec3::ZERO || !n.is_finite() {
                face
            } else {
                n
            }
        }),
        material,
        uvs,
    }
}
