//! `irad::export::write_mitsuba` on every shipped scene, CPU only: each scene
//! with no light-field luminaire is exported and its XML read back and checked against the
//! scene (one sensor with the camera's field of view, size and view, not mirrored; one shape
//! per material in use, whose PLY files hold the scene's triangles; one emitter per emissive
//! material, point and spot light and environment; every referenced file written); each scene
//! with luminaires is refused with the message that says so; albedo textures are written as
//! bitmaps beside the XML (copied, or baked with a note).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::common::shipped_scenes;
use glam::Vec3;
use irad::export::{write_mitsuba, ExportError, MitsubaExport};
use irad::scene::{Light, Scene};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("irad-export-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn floats(s: &str) -> Vec<f32> {
    s.split(',').map(|t| t.trim().parse().unwrap()).collect()
}

fn vec3(s: &str) -> Vec3 {
    let v = floats(s);
    assert_eq!(v.len(), 3, "{s}");
    Vec3::new(v[0], v[1], v[2])
}

/// The `value` of the child `<tag name="name" .../>` of `node`.
fn property<'a>(node: roxmltree::Node<'a, '_>, tag: &str, name: &str) -> Option<&'a str> {
    node.children()
        .find(|c| c.has_tag_name(tag) && c.attribute("name") == Some(name))
        .and_then(|c| c.attribute("value"))
}

fn children<'a, 'i>(node: roxmltree::Node<'a, 'i>, tag: &str) -> Vec<roxmltree::Node<'a, 'i>> {
    node.children().filter(|c| c.has_tag_name(tag)).collect()
}

/// (faces, vertices) from a PLY file's header; checks the binary layout ply.rs writes and that
/// the body has exactly the size the header promises.
fn ply_counts(path: &Path) -> (usize, usize) {
    let (faces, vertices, _) = ply_layout(path);
    (faces, vertices)
}

/// (faces, vertices, bytes per vertex: 24, or 32 with `u v`) as `ply_counts` checks them.
fn ply_layout(path: &Path) -> (usize, usize, usize) {
    let bytes = std::fs::read(path).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap_or_else(|| panic!("{}: no end_header", path.display()))
        + 11;
    let header = std::str::from_utf8(&bytes[..end]).unwrap();
    assert!(
        header.starts_with("ply\nformat binary_little_endian 1.0\n"),
        "{header}"
    );
    let count = |element: &str| -> usize {
        let line = header
            .lines()
            .find(|l| l.starts_with(&format!("element {element} ")))
            .unwrap_or_else(|| panic!("{}: no {element} element", path.display()));
        line.rsplit(' ').next().unwrap().parse().unwrap()
    };
    for p in ["x", "y", "z", "nx", "ny", "nz"] {
        assert!(
            header.contains(&format!("property float {p}\n")),
            "{header}"
        );
    }
    assert!(header.contains("property list uchar uint vertex_indices\n"));
    let uvs = header.contains("property float nz\nproperty float u\nproperty float v\n");
    let stride = if uvs { 32 } else { 24 };
    let (faces, vertices) = (count("face"), count("vertex"));
    assert_eq!(
        bytes.len() - end,
        vertices * stride + faces * 13,
        "{}",
        path.display()
    );
    (faces, vertices, stride)
}

/// The PLY's vertex positions and normals.
fn ply_vertices(path: &Path) -> Vec<(Vec3, Vec3)> {
    let bytes = std::fs::read(path).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let (_, vertices, stride) = ply_layout(path);
    let f = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    (0..vertices)
        .map(|k| {
            let at = end + stride * k;
            (
                Vec3::new(f(at), f(at + 4), f(at + 8)),
                Vec3::new(f(at + 12), f(at + 16), f(at + 20)),
            )
        })
        .collect()
}

/// The camera ray through image point (sx, sy) in [0, 1]^2 (y down) as Mitsuba 3 computes it
/// from the exported XML: `Transform4f::look_at` (columns left = normalize(cross(up, dir)),
/// cross(dir, left), dir) and `perspective_projection` (sample = (0.5 (1 - ndc.x),
/// 0.5 aspect (1 / aspect - ndc.y)), ndc = camera xy / z / tan(fov_x / 2)), fov_x from
/// fov_axis y as `parse_fov` does.
fn mitsuba_ray(sensor: roxmltree::Node, sx: f32, sy: f32) -> Vec3 {
    let lookat = sensor
        .descendants()
        .find(|n| n.has_tag_name("lookat"))
        .unwrap();
    let origin = vec3(lookat.attribute("origin").unwrap());
    let target = vec3(lookat.attribute("target").unwrap());
    let up = vec3(lookat.attribute("up").unwrap());
    let dir = (target - origin).normalize();
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    let film = children(sensor, "film")[0];
    let w: f32 = property(film, "integer", "width").unwrap().parse().unwrap();
    let h: f32 = property(film, "integer", "height")
        .unwrap()
        .parse()
        .unwrap();
    let aspect = w / h;
    let fov_y: f32 = property(sensor, "float", "fov").unwrap().parse().unwrap();
    let tan_x = (fov_y.to_radians() * 0.5).tan() * aspect;
    let ndc_x = 1.0 - 2.0 * sx;
    let ndc_y = (1.0 - 2.0 * sy) / aspect;
    let local = Vec3::new(ndc_x * tan_x, ndc_y * tan_x, 1.0);
    (left * local.x + new_up * local.y + dir * local.z).normalize()
}

/// Checks the export of `scene` in `out` against the scene.
fn check_export(scene: &Scene, dir: &Path, out: &MitsubaExport) {
    let name = &scene.name;
    let text = std::fs::read_to_string(&out.xml).unwrap();
    let doc = roxmltree::Document::parse(&text)
        .unwrap_or_else(|e| panic!("{name}: the XML does not parse: {e}"));
    let root = doc.root_element();
    assert!(root.has_tag_name("scene"));
    assert!(
        root.attribute("version").unwrap().starts_with("3."),
        "{name}"
    );

    // The sensor.
    let sensors = children(root, "sensor");
    assert_eq!(sensors.len(), 1, "{name}");
    let sensor = sensors[0];
    let c = &scene.camera;
    assert_eq!(sensor.attribute("type"), Some("perspective"));
    assert_eq!(property(sensor, "string", "fov_axis"), Some("y"));
    let fov: f32 = property(sensor, "float", "fov").unwrap().parse().unwrap();
    assert_eq!(fov, c.fov_y, "{name}");
    let film = children(sensor, "film")[0];
    assert_eq!(film.attribute("type"), Some("hdrfilm"));
    assert_eq!(
        property(film, "integer", "width"),
        Some(c.width.to_string().as_str())
    );
    assert_eq!(
        property(film, "integer", "height"),
        Some(c.height.to_string().as_str())
    );
    assert_eq!(children(film, "rfilter")[0].attribute("type"), Some("box"));
    // Mitsuba's rays through the image corners and centre are irad's (no mirroring, no flip).
    for (sx, sy) in [
        (0.0, 0.0),
        (1.0, 0.0),
        (0.0, 1.0),
        (1.0, 1.0),
        (0.5, 0.5),
        (0.9, 0.2),
    ] {
        let m = mitsuba_ray(sensor, sx, sy);
        let i = c.direction(sx * c.width as f32, sy * c.height as f32);
        assert!(
            m.dot(i) > 1.0 - 1e-6,
            "{name}: image point ({sx}, {sy}): Mitsuba {m}, irad {i}"
        );
    }
    // Clip planes beyond the scene: no triangle nearer than near_clip or beyond far_clip.
    let near: f32 = property(sensor, "float", "near_clip")
        .unwrap()
        .parse()
        .unwrap();
    let far: f32 = property(sensor, "float", "far_clip")
        .unwrap()
        .parse()
        .unwrap();
    let reach = scene
        .triangles
        .iter()
        .flat_map(|t| t.positions)
        .map(|p| (p - c.position).length())
        .fold(0.0f32, f32::max);
    assert!(
        near <= 1e-2 && far > 2.0 * reach,
        "{name}: {near} {far} {reach}"
    );

    // Shapes: one per material in use, PLY files holding all triangles.
    let used: BTreeSet<u32> = scene.triangles.iter().map(|t| t.material).collect();
    let shapes = children(root, "shape");
    assert_eq!(shapes.len(), used.len(), "{name}: shapes");
    let mut faces = 0;
    let mut area_emitters = 0;
    for shape in &shapes {
        assert_eq!(shape.attribute("type"), Some("ply"));
        let file = dir.join(property(*shape, "string", "filename").unwrap());
        let (f, v) = ply_counts(&file);
        assert_eq!(v, 3 * f);
        faces += f;
        let bsdfs = children(*shape, "bsdf");
        assert_eq!(bsdfs.len(), 1, "{name}");
        assert_eq!(bsdfs[0].attribute("type"), Some("twosided"));
        for e in children(*shape, "emitter") {
            assert_eq!(e.attribute("type"), Some("area"));
            area_emitters += 1;
        }
    }
    assert_eq!(faces, scene.triangles.len(), "{name}: faces");
    let emissive = used
        .iter()
        .filter(|&&m| scene.materials[m as usize].is_emissive())
        .count();
    assert_eq!(area_emitters, emissive, "{name}: area emitters");

    // Emitters: the lights and the environment.
    let emitters = children(root, "emitter");
    let kinds = |kind: &str| {
        emitters
            .iter()
            .filter(|e| e.attribute("type") == Some(kind))
            .count()
    };
    let points = scene
        .lights
        .iter()
        .filter(|l| matches!(l, Light::Point { .. }))
        .count();
    let spots = scene.lights.len() - points;
    let env = usize::from(scene.environment.is_some());
    assert_eq!(
        (kinds("point"), kinds("spot"), kinds("envmap")),
        (points, spots, env),
        "{name}"
    );
    assert_eq!(emitters.len(), points + spots + env, "{name}: emitters");
    for (e, l) in emitters.iter().zip(&scene.lights) {
        let intensity = vec3(property(*e, "rgb", "intensity").unwrap());
        match l {
            Light::Point {
                position,
                intensity: i,
            } => {
                assert_eq!(intensity, *i);
                let p = children(*e, "point")[0];
                let xyz = ["x", "y", "z"].map(|a| p.attribute(a).unwrap().parse().unwrap());
                assert_eq!(Vec3::from(xyz), *position);
            }
            Light::Spot {
                intensity: i,
                direction,
                position,
                cone_angle,
                falloff_angle,
                ..
            } => {
                assert_eq!(intensity, *i);
                let lookat = e.descendants().find(|n| n.has_tag_name("lookat")).unwrap();
                let origin = vec3(lookat.attribute("origin").unwrap());
                let target = vec3(lookat.attribute("target").unwrap());
                assert_eq!(origin, *position);
                assert!((target - origin).normalize().dot(*direction) > 1.0 - 1e-6);
                let cutoff: f32 = property(*e, "float", "cutoff_angle")
                    .unwrap()
                    .parse()
                    .unwrap();
                let beam: f32 = property(*e, "float", "beam_width")
                    .unwrap()
                    .parse()
                    .unwrap();
                assert!(cone_angle <= &beam && beam <= cutoff && &cutoff <= falloff_angle);
            }
        }
    }

    // Files: every referenced one written and listed, and nothing else listed.
    let referenced: BTreeSet<PathBuf> = root
        .descendants()
        .filter(|n| n.has_tag_name("string") && n.attribute("name") == Some("filename"))
        .map(|n| dir.join(n.attribute("value").unwrap()))
        .collect();
    let listed: BTreeSet<PathBuf> = out.files.iter().cloned().collect();
    assert_eq!(referenced, listed, "{name}");
    assert_eq!(listed.len(), out.files.len());
    for f in &referenced {
        assert!(f.is_file(), "{name}: {} missing", f.display());
    }
    if let Some(e) = &scene.environment {
        let map = irad::image::exr::read(&dir.join("environment.exr")).unwrap();
        let k = map.width / e.width;
        assert!(k >= 2 && map.width == k * e.width && map.height == k * e.height + 1);
        assert!(out
            .approximations
            .iter()
            .any(|a| a.starts_with("environment map")));
    }
}

#[test]
fn every_shipped_scene_exports_or_is_refused() {
    let scenes = shipped_scenes();
    assert!(scenes.len() >= 14, "{scenes:?}");
    let (mut exported, mut refused, mut with_luminaires) = (0, 0, 0);
    for path in &scenes {
        let scene = irad::scene::load(path).unwrap();
        with_luminaires += usize::from(!scene.luminaires.is_empty());
        let dir = temp_dir(&path.parent().unwrap().to_string_lossy().replace('/', "_"));
        match write_mitsuba(&scene, &dir) {
            Ok(out) => {
                assert!(scene.luminaires.is_empty());
                assert_eq!(out.xml, dir.join("scene.xml"));
                check_export(&scene, &dir, &out);
                exported += 1;
            }
            Err(e) => {
                let message = e.to_string();
                assert!(matches!(e, ExportError::Luminaires { .. }), "{message}");
                let expected = format!(
                    "{}: Mitsuba has no light-field luminaires (the scene places {});",
                    path.display(),
                    scene.luminaires.len()
                );
                assert!(message.starts_with(&expected), "{message}");
                assert!(!dir.exists(), "nothing written for a refused scene");
                refused += 1;
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    // car-headlights and failure/headlight-wall at least.
    assert!(refused >= 2);
    assert_eq!(refused, with_luminaires);
    assert_eq!(exported + refused, scenes.len());
}

#[test]
fn approximations_name_what_mitsuba_cannot_reproduce() {
    let export = |scene: &str| {
        let s = irad::scene::load(&repo().join("scenes").join(scene).join("scene.toml")).unwrap();
        let dir = temp_dir(&scene.replace('/', "_"));
        let out = write_mitsuba(&s, &dir).unwrap();
        let xml = std::fs::read_to_string(&out.xml).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        (out.approximations, xml)
    };
    // Lambert, emissive triangles, flat normals: exact.
    let (a, xml) = export("cornell-box");
    assert!(a.is_empty(), "{a:?}");
    assert!(xml.contains(r#"<emitter type="area">"#));
    assert!(!xml.contains("blendbsdf"));
    // A spot light.
    let (a, xml) = export("spot-light");
    assert!(a.iter().any(|l| l.starts_with("light[0] (spot")), "{a:?}");
    assert!(xml.contains(r#"<emitter type="spot">"#));
    // Phong lobes, smooth normals, an environment map.
    let (a, xml) = export("glossy-env");
    assert!(a.iter().any(|l| l.contains("Phong lobe")), "{a:?}");
    assert!(a.iter().any(|l| l.contains("shading normals")), "{a:?}");
    assert!(xml.contains("blendbsdf") && xml.contains(r#"value="beckmann""#));
    // A sky sequence: frame 0 only.
    let (a, xml) = export("moving-sun");
    assert!(a.iter().any(|l| l.contains("frame 0 only")), "{a:?}");
    // Every line also stands in the XML as a comment.
    for line in &a {
        assert!(xml.contains(line.as_str()), "{line}");
    }
}

#[test]
fn emissive_normals_against_their_side_become_face_normals() {
    let mut scene = irad::scene::load(&repo().join("scenes/cornell-box/scene.toml")).unwrap();
    let light = scene
        .materials
        .iter()
        .position(|m| m.is_emissive())
        .unwrap() as u32;
    let mut flipped = 0;
    for t in scene.triangles.iter_mut().filter(|t| t.material == light) {
        t.normals = t.normals.map(|n| -n);
        flipped += 1;
    }
    assert!(flipped > 0);
    let dir = temp_dir("flipped");
    let out = write_mitsuba(&scene, &dir).unwrap();
    assert!(
        out.approximations
            .iter()
            .any(|a| a.starts_with("emissive materials") && a.contains("face normals")),
        "{:?}",
        out.approximations
    );
    let name = &scene.materials[light as usize].name;
    let ply = out
        .files
        .iter()
        .find(|f| f.to_string_lossy().ends_with(&format!("-{name}.ply")))
        .unwrap();
    let vertices = ply_vertices(ply);
    for tri in vertices.chunks(3) {
        let ng = (tri[1].0 - tri[0].0).cross(tri[2].0 - tri[0].0).normalize();
        for (_, n) in tri {
            assert!(n.dot(ng) > 1.0 - 1e-6, "{n} vs {ng}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn values_mitsuba_cannot_parse_are_refused_by_name() {
    let mut scene = irad::scene::load(&repo().join("scenes/cornell-box/scene.toml")).unwrap();
    scene.materials[0].kd.x = f32::NAN;
    let dir = temp_dir("nan");
    let e = write_mitsuba(&scene, &dir).unwrap_err().to_string();
    let m = &scene.materials[0].name;
    assert!(
        e.contains("scene.toml") && e.contains(&format!("material `{m}`")) && e.contains("NaN"),
        "{e}"
    );
    assert!(!dir.exists());
}

/// The textured Cornell box: its checker (Kd 1, PNG) and poster (Kd 0.9, JPEG) are copied
/// beside the XML byte for byte, the checker as the bare bitmap, the poster in a blend with
/// black of weight 0.9 (exact); textured meshes carry u v and flip_tex_coords; nothing is
/// approximate. A coloured Kd is baked into its own PNG, with a note.
#[test]
fn textured_materials_write_their_images_beside_the_xml() {
    let folder = repo().join("scenes/textured-cornell");
    let mut scene = irad::scene::load(&folder.join("scene.toml")).unwrap();
    let dir = temp_dir("textured");
    let out = write_mitsuba(&scene, &dir).unwrap();
    check_export(&scene, &dir, &out);
    assert!(out.approximations.is_empty(), "{:?}", out.approximations);
    let text = std::fs::read_to_string(&out.xml).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let shape = |material: &str| {
        let i = scene
            .materials
            .iter()
            .position(|m| m.name == material)
            .unwrap();
        doc.root_element()
            .children()
            .find(|c| {
                c.has_tag_name("shape")
                    && c.attribute("id")
                        .is_some_and(|id| id.starts_with(&format!("mesh-{i:03}-")))
            })
            .unwrap()
    };
    for (material, image, wrap) in [
        ("checker", "checker.png", "repeat"),
        ("poster", "poster.jpg", "clamp"),
    ] {
        let s = shape(material);
        assert_eq!(property(s, "boolean", "flip_tex_coords"), Some("true"));
        let ply = dir.join(property(s, "string", "filename").unwrap());
        assert_eq!(ply_layout(&ply).2, 32, "{material}: u v");
        let bitmap = s
            .descendants()
            .find(|n| n.has_tag_name("texture"))
            .unwrap_or_else(|| panic!("{material}: no bitmap"));
        assert_eq!(bitmap.attribute("type"), Some("bitmap"));
        assert_eq!(bitmap.attribute("name"), Some("reflectance"));
        assert_eq!(property(bitmap, "string", "wrap_mode"), Some(wrap));
        let file = property(bitmap, "string", "filename").unwrap();
        assert_eq!(
            std::fs::read(dir.join(file)).unwrap(),
            std::fs::read(folder.join(image)).unwrap(),
            "{material}: {file} is {image}'s copy"
        );
        let blend = s
            .descendants()
            .find(|n| n.has_tag_name("bsdf") && n.attribute("type") == Some("blendbsdf"));
        match material {
            "checker" => assert!(blend.is_none()),
            _ => assert_eq!(property(blend.unwrap(), "float", "weight"), Some("0.9")),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);

    // A coloured Kd times the checker: baked.
    let red = scene
        .materials
        .iter()
        .position(|m| m.name == "red")
        .unwrap();
    let checker = scene
        .materials
        .iter()
        .find(|m| m.name == "checker")
        .unwrap()
        .albedo_texture;
    scene.materials[red].albedo_texture = checker;
    let dir = temp_dir("baked");
    let out = write_mitsuba(&scene, &dir).unwrap();
    check_export(&scene, &dir, &out);
    let baked = format!("mesh-{red:03}-red-albedo.png");
    assert!(
        out.approximations
            .iter()
            .any(|a| a.starts_with("material `red`: Kd") && a.contains(&baked)),
        "{:?}",
        out.approximations
    );
    assert!(dir.join(&baked).is_file());
    let _ = std::fs::remove_dir_all(&dir);
}
