//! glTF 2.0 import (src/scene/gltf, docs/scenes.md "glTF scenes"), CPU only but for the one
//! render: the committed samples (scenes/gltf/) load with their node transforms, materials,
//! textures, texture coordinates, cameras, lights and emission as the files give them; bad
//! input is refused naming the file, the field and the value, never with a panic; `irad render`
//! renders a glTF scene.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{DMat4, DQuat, DVec3, Vec2, Vec3};
use irad::scene::{self, gltf, Light, Scene, SceneError, Wrap};
use serde_json::{json, Value};

fn samples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gltf")
}

/// A scratch folder under target/tmp, emptied first and removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("irad-gltf-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Copies `files` of scenes/gltf/`sample`/ here.
    fn copy(&self, sample: &str, files: &[&str]) -> &Scratch {
        for f in files {
            std::fs::copy(samples().join(sample).join(f), self.path(f)).unwrap();
        }
        self
    }

    fn write_json(&self, name: &str, doc: &Value) -> PathBuf {
        let path = self.path(name);
        std::fs::write(&path, serde_json::to_string_pretty(doc).unwrap()).unwrap();
        path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `doc` with a white point light of 1 cd on a new root node at `at`: the Khronos samples have
/// no light of their own (irad would light them by its default sky).
fn with_light(mut doc: Value, at: [f32; 3]) -> Value {
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes.push(json!({"translation": at, "extensions": {"KHR_lights_punctual": {"light": 0}}}));
    let node = nodes.len() - 1;
    let scene = doc["scene"].as_u64().unwrap_or(0) as usize;
    doc["scenes"][scene]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!(node));
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [{"type": "point"}]}});
    doc
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).abs().max_element() <= tolerance
}

/// sRGB 8-bit to linear.
fn linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A PNG's texel (i, j) as linear RGB, decoded independently of irad (palettes expanded).
fn png_texel(path: &Path, i: u32, j: u32) -> Vec3 {
    let mut decoder =
        png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().unwrap();
    let mut buffer = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buffer).unwrap();
    let channels = info.color_type.samples();
    let at = ((j * info.width + i) as usize) * channels;
    Vec3::new(
        linear(buffer[at]),
        linear(buffer[at + 1]),
        linear(buffer[at + 2]),
    )
}

/// The translation-rotation-scale matrix of a glTF node.
fn trs(t: [f64; 3], r: [f64; 4], s: [f64; 3]) -> DMat4 {
    DMat4::from_scale_rotation_translation(
        DVec3::from(s),
        DQuat::from_array(r).normalize(),
        DVec3::from(t),
    )
}

fn about_x(degrees: f64) -> [f64; 4] {
    let h = degrees.to_radians() / 2.0;
    [h.sin(), 0.0, 0.0, h.cos()]
}

fn about_y(degrees: f64) -> [f64; 4] {
    let h = degrees.to_radians() / 2.0;
    [0.0, h.sin(), 0.0, h.cos()]
}

fn geometric_normal(p: [Vec3; 3]) -> Vec3 {
    (p[1] - p[0]).cross(p[2] - p[0]).normalize()
}

/// Khronos's BoxTextured: a node matrix over a child node, external .bin and PNG, a base
/// colour texture with MIRRORED_REPEAT x CLAMP_TO_EDGE wrapping (assimp's copy; see its
/// README), texture coordinates flipped to irad's v-up convention.
#[test]
fn box_textured_reads_as_the_file_gives_it() {
    let dir = Scratch::new("box");
    dir.copy("BoxTextured", &["BoxTextured0.bin", "CesiumLogoFlat.png"]);
    let doc = with_light(
        read_json(&samples().join("BoxTextured/BoxTextured.gltf")),
        [2.0, 2.0, 2.0],
    );
    let scene = scene::load(&dir.write_json("BoxTextured.gltf", &doc)).unwrap();
    assert_eq!(scene.name, "BoxTextured");
    assert_eq!(scene.triangles.len(), 12);
    // The root's matrix takes (x, y, z) to (x, z, -y): the first corner (-0.5, -0.5, 0.5)
    // lands at (-0.5, 0.5, 0.5), its normal +z at +y.
    let t = scene.triangles[0];
    assert_eq!(t.positions[0], Vec3::new(-0.5, 0.5, 0.5));
    assert!(close(t.normals[0], Vec3::Y, 1e-6), "{}", t.normals[0]);
    assert!(geometric_normal(t.positions).dot(t.normals[0]) > 0.99);
    // TEXCOORD_0 (6, 0) of the first corner, v flipped.
    assert_eq!(t.uvs[0], Vec2::new(6.0, 1.0));
    // Every face points out of the box.
    for t in &scene.triangles {
        let centre = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
        assert!(geometric_normal(t.positions).dot(centre) > 0.0);
    }
    // A dielectric (metallicFactor 0, roughness 1 by default) of base colour 1 x the texture.
    assert_eq!(scene.materials.len(), 1);
    let m = &scene.materials[0];
    assert_eq!(m.name, "Texture");
    assert_eq!(
        (m.kd, m.ks, m.ns),
        (Vec3::splat(0.96), Vec3::splat(0.04), 0.0)
    );
    assert_eq!(m.ke, Vec3::ZERO);
    assert_eq!(m.albedo_texture, Some(0));
    let tex = &scene.textures[0];
    assert_eq!((tex.width, tex.height), (211, 211));
    assert_eq!(tex.wrap, [Wrap::Mirror, Wrap::Clamp]);
    let png = samples().join("BoxTextured/CesiumLogoFlat.png");
    for (i, j) in [(0, 0), (105, 105), (40, 170)] {
        let texel = tex.texels[(j * tex.width + i) as usize];
        assert!(
            close(texel, png_texel(&png, i, j), 2e-3),
            "({i}, {j}) {texel}"
        );
    }
    // No camera: one is made to frame the box, with a warning.
    assert!(
        scene.warnings.iter().any(|w| w.contains("no camera")),
        "{:?}",
        scene.warnings
    );
    assert_eq!((scene.camera.width, scene.camera.height), (640, 480));
    assert_eq!(scene.camera.look_at, Vec3::ZERO);
    assert!(scene.camera.position.z > 1.0);
    // The light: 1 cd of white read as 1 W/sr.
    assert_eq!(
        scene.lights,
        [Light::Point {
            position: Vec3::splat(2.0),
            intensity: Vec3::ONE
        }]
    );
}

/// Khronos's Cameras: the perspective camera by default; the orthographic one refused by
/// name; a camera number past the file's refused naming how many there are.
#[test]
fn cameras_sample_gives_its_perspective_camera() {
    let dir = Scratch::new("cameras");
    dir.copy("Cameras", &["simpleSquare.bin"]);
    let doc = with_light(
        read_json(&samples().join("Cameras/Cameras.gltf")),
        [0.5, 0.5, 2.0],
    );
    let path = dir.write_json("Cameras.gltf", &doc);
    let scene = scene::load(&path).unwrap();
    let c = &scene.camera;
    assert_eq!(c.position, Vec3::new(0.5, 0.5, 3.0));
    assert_eq!(c.look_at, Vec3::new(0.5, 0.5, 2.0));
    assert_eq!(c.up, Vec3::Y);
    assert!((c.fov_y - 0.7f32.to_degrees()).abs() < 1e-4, "{}", c.fov_y);
    assert_eq!((c.width, c.height), (640, 640));
    // The square under its node's rotation (about x by -45 degrees).
    assert_eq!(scene.triangles.len(), 2);
    let r = trs([0.0; 3], [-0.383, 0.0, 0.0, 0.92375], [1.0; 3]);
    let corner = r.transform_point3(DVec3::new(0.0, 1.0, 0.0)).as_vec3();
    assert!(
        close(scene.triangles[0].positions[2], corner, 1e-6),
        "{corner}"
    );
    // No material: glTF's default (base colour 1, metallic 1, roughness 1).
    let m = &scene.materials[0];
    assert_eq!((m.kd, m.ks, m.ns), (Vec3::ZERO, Vec3::ONE, 0.0));
    assert_eq!(
        gltf::load_with_camera(&path, Some(0)).unwrap().camera,
        scene.camera
    );
    let e = gltf::load_with_camera(&path, Some(1))
        .unwrap_err()
        .to_string();
    for part in [
        "Cameras.gltf",
        "cameras[1].type",
        "\"orthographic\"",
        "--camera",
    ] {
        assert!(e.contains(part), "`{part}` missing from: {e}");
    }
    let e = gltf::load_with_camera(&path, Some(2))
        .unwrap_err()
        .to_string();
    for part in ["Cameras.gltf", "--camera 2", "2 cameras", "0 to 1"] {
        assert!(e.contains(part), "`{part}` missing from: {e}");
    }
    // The chosen camera is part of the content hash (references are cached by it).
    let mut second = doc.clone();
    second["nodes"][2]["camera"] = json!(0);
    second["nodes"][1]["camera"] = json!(1);
    second["cameras"][1] = second["cameras"][0].clone();
    let moved = gltf::load_with_camera(&dir.write_json("b.gltf", &second), Some(1)).unwrap();
    assert_ne!(moved.content_hash, scene.content_hash);
}

/// scenes/gltf/lit-room (ours): TRS nodes under a parent, a mirroring matrix, metallic-roughness
/// fits, the emissive strength, point and spot lights, a skipped directional light, two cameras.
#[test]
fn lit_room_reads_transforms_materials_lights_and_cameras() {
    let path = samples().join("lit-room/lit-room.gltf");
    let scene = scene::load(&path).unwrap();
    assert_eq!(scene.name, "lit-room");
    // floor 2, wall 2, panel 2, box 12, mirrored box 12.
    assert_eq!(scene.triangles.len(), 30);
    // The box: table (translation) x box (TRS); the cube's first corner is (0.5, -0.5, -0.5).
    let world = trs([0.0, 0.1, 0.0], [0.0, 0.0, 0.0, 1.0], [1.0; 3])
        * trs([-0.6, 0.3, -0.3], about_y(30.0), [0.8, 0.6, 0.8]);
    let corner = world
        .transform_point3(DVec3::new(0.5, -0.5, -0.5))
        .as_vec3();
    assert!(
        close(scene.triangles[6].positions[0], corner, 1e-6),
        "{corner}"
    );
    let mirror = DMat4::from_cols_array(&[
        -0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.8, 0.25, 0.4, 1.0,
    ]);
    // Both boxes' faces point out of them, the mirrored one's too (its winding reversed), and
    // the shading normals agree.
    for (range, centre) in [
        (6..18, world.transform_point3(DVec3::ZERO)),
        (18..30, mirror.transform_point3(DVec3::ZERO)),
    ] {
        for t in &scene.triangles[range] {
            let n = geometric_normal(t.positions);
            let middle = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
            assert!(n.dot(middle - centre.as_vec3()) > 0.0, "{t:?}");
            for s in t.normals {
                assert!(n.dot(s) > 0.99, "{t:?}");
            }
        }
    }
    // The floor: uvs (0, 0), (4, 0), (4, 4) flipped to v-up.
    assert_eq!(
        scene.triangles[0].uvs,
        [
            Vec2::new(0.0, 1.0),
            Vec2::new(4.0, 1.0),
            Vec2::new(4.0, -3.0)
        ]
    );
    let by_name = |name: &str| {
        scene
            .materials
            .iter()
            .find(|m| m.name == name)
            .unwrap_or_else(|| panic!("no material {name}"))
    };
    let floor = by_name("floor");
    assert_eq!((floor.kd, floor.ks), (Vec3::splat(0.96), Vec3::splat(0.04)));
    // roughness 0.9: alpha 0.81, Ns = (1 / alpha^2 - 1) / 2.
    assert!(
        (floor.ns - (1.0 / 0.6561 - 1.0) / 2.0).abs() < 1e-5,
        "{}",
        floor.ns
    );
    let tex = &scene.textures[floor.albedo_texture.unwrap() as usize];
    assert_eq!((tex.width, tex.height, tex.wrap), (8, 8, [Wrap::Repeat; 2]));
    let png = samples().join("lit-room/checker.png");
    for (i, j) in [(0, 0), (1, 0), (7, 6)] {
        let texel = tex.texels[(j * 8 + i) as usize];
        assert!(
            close(texel, png_texel(&png, i, j), 2e-3),
            "({i}, {j}) {texel}"
        );
    }
    assert!(close(
        tex.texels[1],
        Vec3::new(linear(200), linear(60), linear(40)),
        2e-3
    ));
    let wall = by_name("wall");
    assert!(close(wall.kd, Vec3::new(0.7, 0.7, 0.65) * 0.96, 1e-6));
    assert_eq!(
        (wall.ks, wall.ns, wall.albedo_texture),
        (Vec3::splat(0.04), 0.0, None)
    );
    let gold = by_name("gold");
    assert_eq!(
        (gold.kd, gold.ks, gold.ns),
        (Vec3::ZERO, Vec3::new(1.0, 0.766, 0.336), 7.5)
    );
    // emissiveFactor (1, 0.9, 0.7) x KHR_materials_emissive_strength 3.
    let panel = by_name("panel");
    assert!(
        close(panel.ke, Vec3::new(3.0, 2.7, 2.1), 1e-6),
        "{}",
        panel.ke
    );
    assert!(close(panel.kd, Vec3::splat(0.8 * 0.96), 1e-6));
    // Lights: the point light's 2 cd x colour as W/sr; the spot's cone angles in degrees and
    // its -z turned down; the directional light skipped with a warning naming it.
    assert_eq!(scene.lights.len(), 2);
    assert_eq!(
        scene.lights[0],
        Light::Point {
            position: Vec3::new(1.2, 1.5, 1.0),
            intensity: Vec3::new(2.0, 1.6, 1.2)
        }
    );
    let Light::Spot {
        position,
        intensity,
        direction,
        cone_angle,
        falloff_angle,
    } = scene.lights[1].clone()
    else {
        panic!("{:?}", scene.lights[1]);
    };
    assert!(close(position, Vec3::new(0.8, 2.2, -0.8), 1e-6));
    assert!(close(intensity, Vec3::new(3.6, 4.8, 6.0), 1e-6));
    assert!(close(direction, Vec3::NEG_Y, 1e-6), "{direction}");
    assert!((cone_angle - 0.25f32.to_degrees()).abs() < 1e-4);
    assert!((falloff_angle - 0.5f32.to_degrees()).abs() < 1e-4);
    let warned = |parts: &[&str]| {
        scene
            .warnings
            .iter()
            .any(|w| w.contains("lit-room.gltf") && parts.iter().all(|p| w.contains(p)))
    };
    assert!(
        warned(&["lights[2] `sun`", "directional"]),
        "{:?}",
        scene.warnings
    );
    assert!(warned(&["lights[1] `spot`", "smoothstep"]));
    assert!(warned(&["Lambert plus normalized Phong"]));
    // The first camera, and the second by number.
    let c = &scene.camera;
    assert_eq!(c.position, Vec3::new(0.0, 1.4, 4.2));
    let forward = trs([0.0; 3], about_x(-10.0), [1.0; 3])
        .transform_vector3(DVec3::NEG_Z)
        .as_vec3();
    assert!(close(c.look_at - c.position, forward, 1e-6));
    assert!((c.fov_y - 0.9f32.to_degrees()).abs() < 1e-4);
    assert_eq!((c.width, c.height), (640, 480));
    let top = gltf::load_with_camera(&path, Some(1)).unwrap().camera;
    assert_eq!(top.position, Vec3::new(0.0, 6.0, 0.0));
    assert!(close(top.look_at, Vec3::new(0.0, 5.0, 0.0), 1e-6));
    assert!(close(top.up, Vec3::NEG_Z, 1e-6));
    assert_eq!((top.width, top.height), (640, 640));
}

/// A binary glTF of lit-room (its buffer and checker image in the BIN chunk) reads as the
/// .gltf does.
#[test]
fn glb_reads_as_its_gltf() {
    let dir = Scratch::new("glb");
    let room = samples().join("lit-room");
    let mut doc = read_json(&room.join("lit-room.gltf"));
    let mut bin = std::fs::read(room.join("lit-room.bin")).unwrap();
    let image = std::fs::read(room.join("checker.png")).unwrap();
    let offset = bin.len();
    bin.extend(&image);
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    doc["buffers"] = json!([{"byteLength": bin.len()}]);
    let views = doc["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": image.len()}));
    doc["images"] = json!([{"bufferView": views.len() - 1, "mimeType": "image/png"}]);
    let path = dir.path("lit-room.glb");
    std::fs::write(&path, glb(doc.to_string().as_bytes(), Some(&bin))).unwrap();
    let glb_scene = scene::load(&path).unwrap();
    let gltf_scene = scene::load(&room.join("lit-room.gltf")).unwrap();
    assert_eq!(glb_scene.triangles, gltf_scene.triangles);
    assert_eq!(glb_scene.materials, gltf_scene.materials);
    assert_eq!(glb_scene.lights, gltf_scene.lights);
    assert_eq!(glb_scene.camera, gltf_scene.camera);
    assert_eq!(glb_scene.textures[0].texels, gltf_scene.textures[0].texels);
}

/// A GLB of `json` and an optional BIN chunk, each padded to 4 bytes.
fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let mut chunks = Vec::new();
    for (data, kind, pad) in [(Some(json), b"JSON", b' '), (bin, b"BIN\0", 0)] {
        let Some(data) = data else { continue };
        let mut d = data.to_vec();
        while d.len() % 4 != 0 {
            d.push(pad);
        }
        chunks.extend((d.len() as u32).to_le_bytes());
        chunks.extend(kind);
        chunks.extend(d);
    }
    let mut file = b"glTF".to_vec();
    file.extend(2u32.to_le_bytes());
    file.extend(((chunks.len() + 12) as u32).to_le_bytes());
    file.extend(chunks);
    file
}

/// Base64 of `bytes` (for data: URIs).
fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = c
            .iter()
            .enumerate()
            .fold(0u32, |n, (k, b)| n | (*b as u32) << (16 - 8 * k));
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A unit square in z = 0 as one primitive of `mode` over `indices`, emissive so that it
/// loads, its buffer a data: URI.
fn square(mode: u32, indices: &[u16]) -> Value {
    let mut data = Vec::new();
    for p in [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ] {
        for x in p {
            data.extend(x.to_le_bytes());
        }
    }
    for i in indices {
        data.extend(i.to_le_bytes());
    }
    json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": mode,
                                     "material": 0}]}],
        "materials": [{"emissiveFactor": [1.0, 1.0, 1.0]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 2 * indices.len()}
        ],
        "buffers": [{"byteLength": data.len(),
                     "uri": format!("data:application/octet-stream;base64,{}", base64(&data))}]
    })
}

/// Triangle strips and fans in the specification's vertex orders (front faces stay
/// counter-clockwise); points are skipped with a warning.
#[test]
fn strips_and_fans_keep_their_winding() {
    let dir = Scratch::new("modes");
    for (mode, indices) in [
        (4, &[0u16, 1, 2, 1, 3, 2][..]),
        (5, &[0, 1, 2, 3]),
        (6, &[0, 1, 3, 2]),
    ] {
        let scene = scene::load(&dir.write_json("s.gltf", &square(mode, indices))).unwrap();
        assert_eq!(scene.triangles.len(), 2, "mode {mode}");
        for t in &scene.triangles {
            assert_eq!(geometric_normal(t.positions), Vec3::Z, "mode {mode}: {t:?}");
        }
        let area: f64 = scene.triangles.iter().map(|t| t.area()).sum();
        assert!((area - 1.0).abs() < 1e-9, "mode {mode}: {area}");
    }
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    let points = json!({"attributes": {"POSITION": 0}, "mode": 0});
    doc["meshes"][0]["primitives"]
        .as_array_mut()
        .unwrap()
        .push(points);
    let scene = scene::load(&dir.write_json("p.gltf", &doc)).unwrap();
    assert_eq!(scene.triangles.len(), 2);
    assert!(scene
        .warnings
        .iter()
        .any(|w| w.contains("primitives[1]") && w.contains("Points")));
}

/// The error of loading `path`, checked to name every one of `parts`.
fn error(path: &Path, parts: &[&str]) -> SceneError {
    let e = match scene::load(path) {
        Ok(_) => panic!("{} loaded", path.display()),
        Err(e) => e,
    };
    let text = e.to_string();
    for part in parts {
        assert!(text.contains(part), "`{part}` missing from: {text}");
    }
    e
}

/// Errors name the file, the field and the value.
#[test]
fn bad_files_are_refused_by_field_and_value() {
    let dir = Scratch::new("errors");
    let room = samples().join("lit-room");
    let room_doc = read_json(&room.join("lit-room.gltf"));
    // A missing .bin, named with the field that references it.
    let e = error(
        &dir.write_json("nobin.gltf", &room_doc),
        &[
            "lit-room.bin",
            "nobin.gltf",
            "buffers[0].uri",
            "cannot read it",
        ],
    );
    assert!(matches!(e, SceneError::Read { .. }), "{e:?}");
    // A texture that is not a PNG or JPEG.
    dir.copy("lit-room", &["lit-room.bin"]);
    std::fs::write(dir.path("checker.png"), b"GIF89a\x01\x00\x01\x00").unwrap();
    error(
        &dir.write_json("gif.gltf", &room_doc),
        &[
            "gif.gltf",
            "materials[0].pbrMetallicRoughness.baseColorTexture (images[0].uri)",
            "\"checker.png\"",
            "not a PNG or JPEG",
        ],
    );
    // A bad data: URI.
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,AAAA*AAA");
    error(
        &dir.write_json("uri.gltf", &doc),
        &[
            "uri.gltf",
            "buffers[0].uri",
            "data:application/octet-stream",
            "\"*\"",
            "not base64",
        ],
    );
    // A buffer shorter than its byteLength, an accessor past its view.
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["buffers"][0]["byteLength"] = json!(1000);
    error(
        &dir.write_json("short.gltf", &doc),
        &["buffers[0].byteLength = 1000", "60 bytes"],
    );
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["accessors"][0]["count"] = json!(40);
    error(
        &dir.write_json("count.gltf", &doc),
        &[
            "attributes.POSITION (accessors[0])",
            "count 40",
            "bufferViews[0]",
        ],
    );
    // An index past the vertices, a reference to no accessor, a wrong accessor type.
    let doc = square(4, &[0, 1, 2, 1, 3, 9]);
    error(
        &dir.write_json("index.gltf", &doc),
        &["primitives[0].indices = 9", "4 vertices"],
    );
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7);
    error(
        &dir.write_json("ref.gltf", &doc),
        &[
            "meshes[0].primitives[0].attributes[\"POSITION\"] = 7",
            "Index out of bounds",
        ],
    );
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["accessors"][0]["type"] = json!("VEC2");
    error(
        &dir.write_json("type.gltf", &doc),
        &["POSITION (accessors[0]) = Vec2 F32", "Vec3 F32"],
    );
    // An extension the file requires and irad does not read.
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["extensionsRequired"] = json!(["KHR_texture_transform"]);
    doc["extensionsUsed"] = json!(["KHR_texture_transform"]);
    error(
        &dir.write_json("ext.gltf", &doc),
        &[
            "extensionsRequired[0] = \"KHR_texture_transform\"",
            "requires",
        ],
    );
    // An orthographic camera, the file's only one.
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["cameras"] = json!([{"name": "ortho", "type": "orthographic",
        "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]);
    doc["nodes"] = json!([{"mesh": 0}, {"camera": 0, "translation": [0, 0, 5]}]);
    doc["scenes"][0]["nodes"] = json!([0, 1]);
    error(
        &dir.write_json("ortho.gltf", &doc),
        &[
            "ortho.gltf",
            "cameras[0].type = \"orthographic\"",
            "`ortho`",
        ],
    );
    // A node that is its own child, a bad quaternion, a bad material factor.
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["nodes"][0]["children"] = json!([0]);
    error(
        &dir.write_json("cycle.gltf", &doc),
        &["scenes[0].nodes = 0", "child of nodes[0]"],
    );
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["nodes"][0]["rotation"] = json!([0, 0, 0, 0]);
    error(
        &dir.write_json("quat.gltf", &doc),
        &["nodes[0].rotation = [0, 0, 0, 0]"],
    );
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["materials"][0]["pbrMetallicRoughness"] = json!({"metallicFactor": 2.0});
    error(
        &dir.write_json("metal.gltf", &doc),
        &[
            "materials[0].pbrMetallicRoughness.metallicFactor = 2",
            "[0, 1]",
        ],
    );
    // No light, or only a directional one: lit by a uniform white sky, with a warning.
    let mut doc = square(4, &[0, 1, 2, 1, 3, 2]);
    doc["materials"] = json!([{}]);
    let lit = |file: &str, doc: &Value, why: &str| {
        let scene = irad::scene::load(&dir.write_json(file, doc)).unwrap();
        let env = scene.environment.as_ref().expect("the default sky");
        assert!(env.texels.iter().all(|t| *t == Vec3::ONE));
        assert!(
            scene
                .warnings
                .iter()
                .any(|w| w.contains(file) && w.contains(why) && w.contains("uniform white sky")),
            "{:?}",
            scene.warnings
        );
    };
    lit("dark.gltf", &doc, "it has no light");
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] =
        json!({"KHR_lights_punctual": {"lights": [{"name": "sun", "type": "directional"}]}});
    doc["nodes"] = json!([{"mesh": 0}, {"extensions": {"KHR_lights_punctual": {"light": 0}}}]);
    doc["scenes"][0]["nodes"] = json!([0, 1]);
    lit("sun.gltf", &doc, "lights[0] `sun`, is directional");
    // Not JSON; glTF 1.0.
    std::fs::write(dir.path("text.gltf"), "{\"asset\": ").unwrap();
    error(
        &dir.path("text.gltf"),
        &["text.gltf", "not glTF 2.0 JSON", "line 1"],
    );
    let v1 = json!({"asset": {"version": "1.0"}});
    error(
        &dir.write_json("v1.gltf", &v1),
        &["asset.version = \"1.0\""],
    );
}

/// A .glb with a bad header or chunk is refused naming the header field.
#[test]
fn bad_glb_headers_are_refused() {
    let dir = Scratch::new("glb-errors");
    let json = square(4, &[0, 1, 2, 1, 3, 2]).to_string();
    let good = glb(json.as_bytes(), None);
    let cases: [(&str, Vec<u8>, &[&str]); 5] = [
        (
            "magic.glb",
            b"glTX\x02\0\0\0".to_vec(),
            &["GLB header magic = \"glTX\""],
        ),
        (
            "short.glb",
            b"glTF\x02\0".to_vec(),
            &["GLB header = 6 bytes"],
        ),
        (
            "version.glb",
            [&b"glTF\x01\0\0\0"[..], &good[8..]].concat(),
            &["GLB header version = 1"],
        ),
        (
            "length.glb",
            [&good[..8], &9999u32.to_le_bytes()[..], &good[12..]].concat(),
            &["GLB header length = 9999", "bytes"],
        ),
        (
            "chunk.glb",
            [&good[..12], &9999u32.to_le_bytes()[..], &good[16..]].concat(),
            &["GLB chunk 0 length = 9999"],
        ),
    ];
    for (name, bytes, parts) in cases {
        std::fs::write(dir.path(name), bytes).unwrap();
        let parts: Vec<&str> = parts.iter().copied().chain([name]).collect();
        error(&dir.path(name), &parts);
    }
    std::fs::write(dir.path("good.glb"), &good).unwrap();
    assert_eq!(
        scene::load(&dir.path("good.glb")).unwrap().triangles.len(),
        2
    );
}

/// Truncated and corrupted files give errors (or scenes), never a panic or a NaN.
#[test]
fn corrupted_files_never_panic() {
    let dir = Scratch::new("fuzz");
    let room = samples().join("lit-room");
    let mut doc = read_json(&room.join("lit-room.gltf"));
    let bin = std::fs::read(room.join("lit-room.bin")).unwrap();
    doc["buffers"] = json!([{"byteLength": bin.len()}]);
    doc["images"] = json!([]);
    doc["textures"] = json!([]);
    doc["materials"][0]["pbrMetallicRoughness"] = json!({});
    let file = glb(doc.to_string().as_bytes(), Some(&bin));
    let path = dir.path("f.glb");
    let check = |bytes: &[u8], what: &str| {
        std::fs::write(&path, bytes).unwrap();
        if let Ok(s) = scene::load(&path) {
            assert!(finite(&s), "{what}");
        }
    };
    for cut in (0..file.len()).step_by(97) {
        check(&file[..cut], &format!("cut at {cut}"));
    }
    // Flip bytes all over the BIN chunk (indices, positions, normals).
    let json_len = u32::from_le_bytes(file[12..16].try_into().unwrap()) as usize;
    let bin_start = 20 + json_len + 8;
    let mut state = 12345u64;
    for k in 0..60 {
        let mut bytes = file.clone();
        for _ in 0..4 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let at = bin_start + (state >> 33) as usize % bin.len();
            bytes[at] ^= (state >> 20) as u8 | 1;
        }
        check(&bytes, &format!("flip {k}"));
    }
}

fn finite(s: &Scene) -> bool {
    s.triangles.iter().all(|t| {
        t.positions.iter().chain(&t.normals).all(|v| v.is_finite())
            && t.uvs.iter().all(|u| u.is_finite())
    })
}

/// `irad render` renders a glTF scene (and refuses --camera for another format).
#[test]
fn irad_renders_a_gltf_scene() {
    let dir = Scratch::new("render");
    let scene = samples().join("lit-room/lit-room.gltf");
    let out = dir.path("out");
    let o = Command::new(env!("CARGO_BIN_EXE_irad"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "4",
            "--resolution",
            "32x24",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let image = irad::image::exr::read(&dir.path("out.exr")).unwrap();
    assert_eq!((image.width, image.height), (32, 24));
    assert!(image.pixels.iter().flatten().all(|x| x.is_finite()));
    let mean = image.mean();
    assert!(mean.iter().all(|m| *m > 0.0), "{mean:?}");
    // A Khronos sample as it is: no light of its own (the default sky), no camera (a framing
    // one).
    let sample = samples().join("BoxTextured/BoxTextured.gltf");
    let o = Command::new(env!("CARGO_BIN_EXE_irad"))
        .args([
            "render",
            sample.to_str().unwrap(),
            "--spp",
            "4",
            "--resolution",
            "32x24",
            "-o",
        ])
        .arg(dir.path("box"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let image = irad::image::exr::read(&dir.path("box.exr")).unwrap();
    assert!(image.pixels.iter().flatten().all(|x| x.is_finite()));
    assert!(image.mean().iter().all(|m| *m > 0.0));
    let o = Command::new(env!("CARGO_BIN_EXE_irad"))
        .args([
            "render",
            "scenes/cornell-box/scene.toml",
            "--camera",
            "1",
            "-o",
        ])
        .arg(dir.path("no"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("scene.toml: --camera = 1: picks a glTF scene's camera"),
        "{stderr}"
    );
}
