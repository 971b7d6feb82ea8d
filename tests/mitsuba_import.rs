//! Mitsuba 3 XML import (src/scene/mitsuba), CPU only: every shipped scene exported by
//! `irad export mitsuba` reads back as the scene it was (camera bit for bit, each material's
//! triangles bit for bit, the BSDF fit inverted within f32 rounding, lights, the environment's
//! mean), textured scenes with their textures and texture coordinates; the research subset
//! (primitives, transforms, defaults, BSDFs, emitters, bitmaps the right way up) reads as
//! Mitsuba defines it; bad input is refused naming the file, the element's line and the value;
//! `irad render scene.xml` renders.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;

use crate::common::shipped_scenes;
use glam::Vec3;
use irad::export::write_mitsuba;
use irad::scene::{Light, Scene, SceneError};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("irad-mitsuba-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A triangle's bits, for comparing sets of triangles.
fn bits(positions: [Vec3; 3], normals: [Vec3; 3]) -> Vec<u32> {
    positions
        .iter()
        .chain(&normals)
        .flat_map(|v| v.to_array())
        .map(f32::to_bits)
        .collect()
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).abs().max_element()
        <= tolerance * a.abs().max_element().max(b.abs().max_element()).max(1e-30)
}

/// Each material's triangles, by the material's index in `scene`.
fn groups(scene: &Scene) -> BTreeMap<u32, Vec<Vec<u32>>> {
    let mut g: BTreeMap<u32, Vec<Vec<u32>>> = BTreeMap::new();
    for t in &scene.triangles {
        g.entry(t.material)
            .or_default()
            .push(bits(t.positions, t.normals));
    }
    for v in g.values_mut() {
        v.sort();
    }
    g
}

/// Scenes that hold every thing the export writes: Lambert and glossy materials, emitters
/// with face and shading normals, point and spot lights, environment maps (a CI-sized choice
/// of `shipped_scenes()`, which all read back: checked when this test was written).
const ROUND_TRIP: [&str; 5] = [
    "cornell-box",
    "glossy-env",
    "spot-light",
    "failure/sun-behind",
    "failure/halogen-office",
];

#[test]
fn exported_scenes_read_back_as_they_were() {
    let mut checked = 0;
    let scenes: Vec<PathBuf> = match std::env::var_os("IRAD_EVERY_SCENE") {
        Some(_) => shipped_scenes(),
        None => ROUND_TRIP
            .iter()
            .map(|s| repo().join("scenes").join(s).join("scene.toml"))
            .collect(),
    };
    for path in scenes {
        let scene = irad::scene::load(&path).unwrap();
        let label = path.display().to_string();
        let dir = temp_dir(&format!("round-trip-{checked}"));
        let Ok(export) = write_mitsuba(&scene, &dir) else {
            // Light-field luminaires: refused by the export (tests/export.rs).
            assert!(!scene.luminaires.is_empty(), "{label}");
            continue;
        };
        let back = irad::scene::load(&export.xml).unwrap_or_else(|e| panic!("{label}: {e}"));
        assert_eq!(
            back.camera, scene.camera,
            "{label}: the camera, bit for bit"
        );
        assert_eq!(back.triangles.len(), scene.triangles.len(), "{label}");
        // Material i was written as the shape mesh-{i:03}-...: its fit inverted, its
        // triangles the same bits (the geometric normal where the export gave face normals).
        let (original, imported) = (groups(&scene), groups(&back));
        for (&i, triangles) in &original {
            let m = &scene.materials[i as usize];
            let prefix = format!("mesh-{i:03}-");
            let (j, b) = back
                .materials
                .iter()
                .enumerate()
                .find(|(_, b)| b.name.starts_with(&prefix))
                .unwrap_or_else(|| panic!("{label}: no material {prefix}"));
            assert!(
                close(b.kd, m.kd, 1e-6),
                "{label} {}: Kd {} read back as {}",
                m.name,
                m.kd,
                b.kd
            );
            assert!(
                close(b.ks, m.ks, 1e-6),
                "{label} {}: Ks {} read back as {}",
                m.name,
                m.ks,
                b.ks
            );
            assert_eq!(b.ke, m.ke, "{label} {}: Ke", m.name);
            if m.ks.max_element() > 0.0 {
                assert!(
                    (b.ns - m.ns).abs() <= 1e-5 * m.ns.max(1.0),
                    "{label} {}: Ns {} read back as {}",
                    m.name,
                    m.ns,
                    b.ns
                );
            }
            let face_normals = |v: &Vec<Vec<u32>>| -> Vec<Vec<u32>> {
                let mut out: Vec<Vec<u32>> = v
                    .iter()
                    .map(|t| {
                        let f: Vec<f32> = t.iter().map(|&b| f32::from_bits(b)).collect();
                        let p = [0, 3, 6].map(|k| Vec3::new(f[k], f[k + 1], f[k + 2]));
                        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
                        bits(p, [n; 3])
                    })
                    .collect();
                out.sort();
                out
            };
            let got = &imported[&(j as u32)];
            assert!(
                got == triangles || *got == face_normals(triangles),
                "{label} {}: the triangles differ",
                m.name
            );
        }
        assert_eq!(back.lights.len(), scene.lights.len(), "{label}");
        for (a, b) in scene.lights.iter().zip(&back.lights) {
            match (a, b) {
                (Light::Point { .. }, Light::Point { .. }) => assert_eq!(a, b, "{label}"),
                (
                    Light::Spot {
                        position: p,
                        intensity: i,
                        direction: d,
                        cone_angle,
                        falloff_angle,
                    },
                    Light::Spot {
                        position: q,
                        intensity: j,
                        direction: e,
                        cone_angle: c2,
                        falloff_angle: f2,
                    },
                ) => {
                    assert_eq!((p, i), (q, j), "{label}");
                    assert!(close(*d, *e, 1e-6), "{label}: {d} against {e}");
                    // The export fits Mitsuba's linear ramp to irad's smoothstep (the same
                    // power); read back, the ramp's angles are irad's cone and falloff.
                    eprintln!(
                        "{label}: spot cone {cone_angle} falloff {falloff_angle} read back as \
                         cone {c2} falloff {f2}"
                    );
                    assert!(*c2 > 0.0 && c2 <= f2);
                }
                _ => panic!("{label}: {a:?} read back as {b:?}"),
            }
        }
        match (&scene.environment, &back.environment) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                // The mean over the sphere (rows weighted by their solid angle): the export
                // upsamples the map keeping each texel's power.
                let mean = |e: &irad::scene::Environment| {
                    let (mut sum, mut weight) = (glam::DVec3::ZERO, 0.0);
                    for (k, t) in e.texels.iter().enumerate() {
                        let j = k as u32 / e.width;
                        let (t0, t1) = (
                            std::f64::consts::PI * j as f64 / e.height as f64,
                            std::f64::consts::PI * (j + 1) as f64 / e.height as f64,
                        );
                        let w = t0.cos() - t1.cos();
                        sum += w * t.as_dvec3();
                        weight += w;
                    }
                    sum / weight
                };
                let (ma, mb) = (mean(a), mean(b));
                // The export weights the upsampled map's edge rows for Mitsuba's bilinear
                // lookup (src/export/mitsuba/envmap.rs); read back piecewise constant, the
                // power moves by about 0.2% (sun-behind: 0.18%).
                eprintln!(
                    "{label}: environment's mean radiance {:.4}% off",
                    100.0 * ((mb - ma).abs().max_element() / ma.max_element())
                );
                assert!(
                    (ma - mb).abs().max_element() <= 1e-2 * ma.max_element(),
                    "{label}: environment mean {ma} read back as {mb}"
                );
            }
            _ => panic!("{label}: the environment"),
        }
        checked += 1;
        std::fs::remove_dir_all(&dir).ok();
    }
    assert!(checked >= ROUND_TRIP.len(), "{checked} scenes read back");
}

const RESEARCH: &str = r#"<?xml version="1.0"?>
<scene version="3.0.0">
    <default name="width" value="40"/>
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="60"/>
        <transform name="to_world">
            <lookat origin="0, 1, 5" target="0, 1, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="$width"/>
            <integer name="height" value="20"/>
        </film>
    </sensor>
    <bsdf type="twosided" id="white">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.7, 0.6"/></bsdf>
    </bsdf>
    <bsdf type="roughplastic" id="coat">
        <float name="alpha" value="0.2"/>
        <rgb name="diffuse_reflectance" value="0.5"/>
    </bsdf>
    <bsdf type="phong" id="phong">
        <rgb name="diffuse_reflectance" value="0.3"/>
        <rgb name="specular_reflectance" value="0.2"/>
        <float name="exponent" value="40"/>
    </bsdf>
    <shape type="rectangle" id="floor">
        <transform name="to_world">
            <scale value="2"/>
            <rotate x="1" angle="-90"/>
            <translate y="-1"/>
        </transform>
        <ref id="white"/>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.25"/></transform>
        <ref id="coat"/>
    </shape>
    <shape type="sphere">
        <point name="center" x="1" y="0" z="0"/>
        <float name="radius" value="0.5"/>
        <integer name="tessellation" value="48"/>
        <ref id="phong"/>
    </shape>
    <shape type="disk">
        <transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="4"/></emitter>
    </shape>
    <emitter type="point">
        <point name="position" value="0, 3, 0"/>
        <rgb name="intensity" value="2, 2, 2"/>
    </emitter>
    <emitter type="spot">
        <transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0" up="1, 0, 0"/></transform>
        <float name="cutoff_angle" value="30"/>
    </emitter>
    <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
</scene>
"#;

fn load_text(name: &str, text: &str) -> Result<Scene, SceneError> {
    let dir = temp_dir(name);
    let path = dir.join("scene.xml");
    std::fs::write(&path, text).unwrap();
    let r = irad::scene::load(&path);
    std::fs::remove_dir_all(&dir).ok();
    r
}

fn area(scene: &Scene, material: &str) -> f64 {
    scene
        .triangles
        .iter()
        .filter(|t| scene.materials[t.material as usize].name == material)
        .map(|t| t.area())
        .sum()
}

#[test]
fn the_research_subset_reads_as_mitsuba_defines_it() {
    let scene = load_text("research", RESEARCH).unwrap();
    let c = &scene.camera;
    assert_eq!((c.width, c.height), (40, 20), "$width from <default>");
    // fov_axis x (Mitsuba's default) over a 2:1 film: tan(fov_y / 2) = tan(30 deg) / 2.
    let want = (2.0 * (30f64.to_radians().tan() / 2.0).atan()).to_degrees();
    assert!(
        (c.fov_y as f64 - want).abs() < 1e-4,
        "{} against {want}",
        c.fov_y
    );
    assert_eq!(
        (c.position, c.look_at),
        (Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0))
    );
    // The floor: [-1, 1]^2 scaled by 2, turned to face +y, then moved down: 16 square units
    // at y = -1, lit side up.
    assert!((area(&scene, "white") - 16.0).abs() < 1e-5);
    for t in scene
        .triangles
        .iter()
        .filter(|t| scene.materials[t.material as usize].name == "white")
    {
        assert!(
            t.positions.iter().all(|p| (p.y + 1.0).abs() < 1e-6),
            "{:?}",
            t.positions
        );
        let n = (t.positions[1] - t.positions[0]).cross(t.positions[2] - t.positions[0]);
        assert!(n.y > 0.0, "faces +y");
    }
    // A cube of side 0.5, a sphere of radius 0.5 (48 segments: within 1% of 4 pi r^2).
    assert!((area(&scene, "coat") - 1.5).abs() < 1e-5);
    assert!((area(&scene, "phong") / std::f64::consts::PI - 1.0).abs() < 0.01);
    let white = scene.materials.iter().find(|m| m.name == "white").unwrap();
    assert_eq!(white.kd, Vec3::new(0.8, 0.7, 0.6));
    let phong = scene.materials.iter().find(|m| m.name == "phong").unwrap();
    assert_eq!(
        (phong.kd, phong.ks, phong.ns),
        (Vec3::splat(0.3), Vec3::splat(0.2), 40.0)
    );
    // roughplastic: F0 of eta 1.49 / 1.000277, Ns of alpha 0.2 = (25 - 1) / 2.
    let coat = scene.materials.iter().find(|m| m.name == "coat").unwrap();
    let eta = 1.49 / 1.000277f64;
    let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2) as f32;
    assert!((coat.ks.x - f0).abs() < 1e-6 && (coat.kd.x - 0.5 * (1.0 - f0)).abs() < 1e-6);
    assert!((coat.ns - 12.0).abs() < 1e-3, "{}", coat.ns);
    // The disk: emitting 4, facing down after its turn about x.
    let lamp = scene
        .materials
        .iter()
        .find(|m| m.ke == Vec3::splat(4.0))
        .unwrap();
    assert!(lamp.name.contains("disk"));
    assert_eq!(scene.lights.len(), 2);
    match scene.lights[1] {
        Light::Spot {
            direction,
            cone_angle,
            falloff_angle,
            ..
        } => {
            assert!((direction - Vec3::NEG_Y).length() < 1e-6, "{direction}");
            assert_eq!(
                (cone_angle, falloff_angle),
                (22.5, 30.0),
                "beam_width 3/4 of cutoff"
            );
        }
        ref other => panic!("{other:?}"),
    }
    let env = scene.environment.as_ref().unwrap();
    assert!(env.texels.iter().all(|t| *t == Vec3::splat(0.1)));
    // Each approximation says what it did.
    let warnings = scene.warnings.join("\n");
    for needle in [
        "roughplastic as Kd = diffuse_reflectance (1 - F0)",
        "sphere tessellated",
        "spot's linear ramp",
    ] {
        assert!(
            warnings.contains(needle),
            "{needle} missing from:\n{warnings}"
        );
    }
}

/// "line N", N the line of RESEARCH holding `text`.
fn line_of(text: &str) -> String {
    let n = RESEARCH
        .lines()
        .position(|l| l.contains(text))
        .expect("in RESEARCH")
        + 1;
    format!("line {n}")
}

#[test]
fn bad_mitsuba_input_names_the_file_the_element_and_the_value() {
    let cases = [
        (
            RESEARCH.replace("<shape type=\"cube\">", "<shape type=\"hair\">"),
            vec![
                line_of("<shape type=\"cube\">") + " <shape type=\"hair\">",
                "hair".into(),
                "not supported".into(),
            ],
        ),
        (
            RESEARCH.replace("type=\"constant\"", "type=\"directional\""),
            vec![
                "<emitter type=\"directional\">".into(),
                "Mitsuba `directional` emitters".into(),
            ],
        ),
        (
            RESEARCH.replace("value=\"0.8, 0.7, 0.6\"", "value=\"0.8, x, 0.6\""),
            vec![
                line_of("0.8, 0.7, 0.6") + " <rgb name=\"reflectance\">",
                "0.8, x, 0.6".into(),
                "finite numbers".into(),
            ],
        ),
        (
            RESEARCH.replace(
                "<shape type=\"cube\">",
                "<shape type=\"ply\"><string name=\"filename\" value=\"missing.ply\"/>",
            ),
            vec![
                "missing.ply".into(),
                "cannot read it".into(),
                "<shape type=\"ply\">".into(),
            ],
        ),
        (
            RESEARCH.replace(
                "<float name=\"fov\" value=\"60\"/>",
                "<float name=\"fov\" value=\"180\"/>",
            ),
            vec!["180".into(), "(0, 180)".into()],
        ),
        (
            RESEARCH.replace("</scene>", ""),
            vec!["not well-formed XML".into()],
        ),
        (
            RESEARCH.replace(
                "<rgb name=\"reflectance\" value=\"0.8, 0.7, 0.6\"/>",
                "<texture type=\"bitmap\" name=\"reflectance\">\
                 <string name=\"filename\" value=\"maps/missing.png\"/></texture>",
            ),
            vec![
                line_of("0.8, 0.7, 0.6") + " <string name=\"filename\">",
                format!(
                    "maps{}missing.png: cannot read it",
                    std::path::MAIN_SEPARATOR
                ),
            ],
        ),
        (
            RESEARCH.replace(
                "<rgb name=\"reflectance\" value=\"0.8, 0.7, 0.6\"/>",
                "<texture type=\"bitmap\" name=\"reflectance\">\
                 <string name=\"filename\" value=\"missing.png\"/>\
                 <string name=\"wrap_mode\" value=\"tile\"/></texture>",
            ),
            vec![
                line_of("0.8, 0.7, 0.6") + " <string name=\"wrap_mode\">",
                "tile".into(),
                "wrap_mode is repeat, mirror or clamp".into(),
            ],
        ),
    ];
    for (k, (text, needles)) in cases.iter().enumerate() {
        let e = load_text(&format!("bad-{k}"), text)
            .err()
            .unwrap_or_else(|| panic!("case {k} loaded"));
        let message = e.to_string();
        assert!(message.contains("scene.xml"), "case {k}: {message}");
        for n in needles {
            assert!(
                message.contains(n.as_str()),
                "case {k}: `{n}` missing from: {message}"
            );
        }
    }
}

/// `irad render scene.xml` renders an exported scene.
#[test]
fn irad_renders_a_mitsuba_scene() {
    let dir = temp_dir("render");
    let scene = irad::scene::load(&repo().join("scenes/cornell-box/scene.toml")).unwrap();
    let export = write_mitsuba(&scene, &dir.join("xml")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_irad"))
        .args([
            "render",
            export.xml.to_str().unwrap(),
            "--resolution",
            "16x16",
            "--spp",
            "2",
            "-o",
        ])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out.json")).unwrap()).unwrap();
    assert!(
        record["scene_path"]
            .as_str()
            .unwrap()
            .ends_with("scene.xml"),
        "{record}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A 35 mm focal length is over the film's diagonal (Mitsuba's sensor.cpp), and PLY meshes
/// read in every format, smoothed where they have no normals.
#[test]
fn focal_lengths_and_ply_formats_read_as_mitsuba_reads_them() {
    let text = RESEARCH.replace(
        "<float name=\"fov\" value=\"60\"/>",
        "<string name=\"focal_length\" value=\"35mm\"/>",
    );
    let scene = load_text("focal", &text).unwrap();
    let t = 43.266_615_305_567_87f64 / 70.0;
    let want = (2.0 * (t / 5f64.sqrt()).atan()).to_degrees();
    assert!(
        (scene.camera.fov_y as f64 - want).abs() < 1e-4,
        "{} against {want}",
        scene.camera.fov_y
    );

    // A fold of two triangles sharing the edge (0, 1): ASCII without normals, and the same
    // mesh big-endian with them.
    let dir = temp_dir("ply");
    let ascii =
        "ply\r\nformat ascii 1.0\r\nelement vertex 4\r\nproperty float x\r\nproperty float y\r\n\
                 property float z\r\nelement face 2\r\nproperty list uchar int vertex_indices\r\n\
                 end_header\r\n0 0 0\n1 0 0\n0 1 0\n0 -1 1\n3 0 1 2\n3 1 0 3\n";
    std::fs::write(dir.join("fold.ply"), ascii).unwrap();
    let mut big = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
    for v in [
        [0f32, 0.0, 0.0, 0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
    ] {
        for c in v {
            big.extend_from_slice(&c.to_be_bytes());
        }
    }
    big.push(3);
    for i in [0u32, 1, 2] {
        big.extend_from_slice(&i.to_be_bytes());
    }
    std::fs::write(dir.join("big.ply"), &big).unwrap();
    let xml = RESEARCH.replace(
        "<shape type=\"cube\">",
        "<shape type=\"ply\"><string name=\"filename\" value=\"fold.ply\"/><ref id=\"white\"/></shape>\
         <shape type=\"ply\"><string name=\"filename\" value=\"big.ply\"/><ref id=\"phong\"/></shape>\
         <shape type=\"cube\">",
    );
    std::fs::write(dir.join("scene.xml"), xml).unwrap();
    let scene = irad::scene::load(&dir.join("scene.xml")).unwrap();
    let fold: Vec<&irad::scene::Triangle> = scene
        .triangles
        .iter()
        .filter(|t| t.positions.contains(&Vec3::new(0.0, -1.0, 1.0)))
        .collect();
    assert_eq!(fold.len(), 1);
    // Vertices 0 and 1 are on both faces: their normal is the area-weighted mean of the faces'
    // (0, 0, 1) and (0, 1, 1) / sqrt(2), twice the areas 1 and sqrt(2): (0, 1, 2) / sqrt(5).
    let shared = fold[0].normals[0];
    assert!(
        (shared - Vec3::new(0.0, 1.0, 2.0).normalize()).length() < 1e-6,
        "{shared}"
    );
    // Vertex 3 is on the second face only.
    assert!((fold[0].normals[2] - Vec3::new(0.0, 1.0, 1.0).normalize()).length() < 1e-6);
    let big: Vec<&irad::scene::Triangle> = scene
        .triangles
        .iter()
        .filter(|t| t.positions == [Vec3::ZERO, Vec3::X, Vec3::Y])
        .collect();
    assert!(
        big.len() >= 2,
        "the fold's first face and the big-endian triangle"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A material's triangles as the bits of their positions and texture coordinates, sorted.
fn uv_bits(scene: &Scene, material: u32) -> Vec<Vec<u32>> {
    let mut out: Vec<Vec<u32>> = scene
        .triangles
        .iter()
        .filter(|t| t.material == material)
        .map(|t| {
            t.positions
                .iter()
                .flat_map(|v| v.to_array())
                .chain(t.uvs.iter().flat_map(|v| v.to_array()))
                .map(f32::to_bits)
                .collect()
        })
        .collect();
    out.sort();
    out
}

/// The 8-bit sRGB code (unrounded) of a linear value.
fn srgb(linear: f32) -> f64 {
    let x = linear as f64;
    255.0
        * if x <= 0.0031308 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        }
}

/// The textured Cornell box (checker: Kd 1, PNG, repeat; poster: Kd 0.9, JPEG, clamp) with a
/// coloured Kd on the checker (red: baked), a glossy material on the poster (green: a grey
/// diffuse part, the file copied) and a texture whose file is gone (white: written as PNG,
/// u and v wrapping differently) reads back with every texture, Kd, wrap and texture
/// coordinate: texels bit for bit where the file is copied or written from 8-bit texels,
/// within half an 8-bit code where a colour is baked in; uvs bit for bit.
#[test]
fn textured_scenes_read_back_with_their_textures_and_uvs() {
    let mut scene = irad::scene::load(&repo().join("scenes/textured-cornell/scene.toml")).unwrap();
    let find = |scene: &Scene, name: &str| {
        scene
            .materials
            .iter()
            .position(|m| m.name == name)
            .unwrap_or_else(|| panic!("no material {name}"))
    };
    let (red, green, white) = (
        find(&scene, "red"),
        find(&scene, "green"),
        find(&scene, "white"),
    );
    let checker = scene.materials[find(&scene, "checker")].albedo_texture;
    let poster = scene.materials[find(&scene, "poster")].albedo_texture;
    scene.materials[red].albedo_texture = checker;
    let g = &mut scene.materials[green];
    (g.kd, g.ks, g.ns, g.albedo_texture) = (Vec3::splat(0.3), Vec3::splat(0.2), 50.0, poster);
    let mut gone = scene.textures[checker.unwrap() as usize].clone();
    gone.source = PathBuf::from("/nonexistent/irad/checker.png");
    gone.wrap = [irad::scene::Wrap::Mirror, irad::scene::Wrap::Repeat];
    scene.textures.push(gone);
    let w = &mut scene.materials[white];
    (w.kd, w.albedo_texture) = (Vec3::splat(0.7), Some(scene.textures.len() as u32 - 1));
    for t in scene.triangles.iter_mut() {
        if [red, green, white].contains(&(t.material as usize)) {
            t.uvs = t
                .positions
                .map(|p| glam::Vec2::new(1.7 * p.x - 0.3, 2.3 * p.z + 0.9 * p.y - 1.1));
        }
    }

    let dir = temp_dir("textured-round-trip");
    let export = write_mitsuba(&scene, &dir).unwrap();
    let notes = export.approximations.join("\n");
    assert!(notes.contains("material `red`: Kd"), "{notes}");
    assert!(notes.contains("wraps u mirror and v repeat"), "{notes}");
    let back = irad::scene::load(&export.xml).unwrap();
    for (i, m) in scene.materials.iter().enumerate() {
        if !scene.triangles.iter().any(|t| t.material as usize == i) {
            continue;
        }
        let j = back
            .materials
            .iter()
            .position(|b| b.name.starts_with(&format!("mesh-{i:03}-")))
            .unwrap();
        let b = &back.materials[j];
        assert_eq!(
            uv_bits(&back, j as u32),
            uv_bits(&scene, i as u32),
            "{}: positions and uvs",
            m.name
        );
        let Some(t) = m.albedo_texture else {
            assert_eq!(b.albedo_texture, None, "{}", m.name);
            continue;
        };
        let (a, t2) = (
            &scene.textures[t as usize],
            &back.textures[b.albedo_texture.expect("a texture") as usize],
        );
        assert_eq!((t2.width, t2.height), (a.width, a.height), "{}", m.name);
        assert_eq!(t2.wrap, [a.wrap[0]; 2], "{}: u's wrap", m.name);
        assert!(
            close(b.ks, m.ks, 1e-6),
            "{}: Ks {} as {}",
            m.name,
            m.ks,
            b.ks
        );
        if i == red {
            // Kd baked into the image: Kd 1, each texel Kd x the checker's to 8 bits.
            assert_eq!(b.kd, Vec3::ONE);
            for (x, y) in a.texels.iter().zip(&t2.texels) {
                for c in 0..3 {
                    let (want, got) = (srgb(x[c] * m.kd[c]), srgb(y[c]));
                    assert!(
                        (want - got).abs() <= 0.6,
                        "{}: code {want} as {got}",
                        m.name
                    );
                }
            }
        } else {
            assert!(
                close(b.kd, m.kd, 1e-6),
                "{}: Kd {} as {}",
                m.name,
                m.kd,
                b.kd
            );
            assert!(t2.texels == a.texels, "{}: texels bit for bit", m.name);
        }
    }
    // Copied files keep their names' extensions; the lost one was written as PNG.
    let names: Vec<String> = export
        .files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for suffix in ["-checker.png", "-poster.jpg"] {
        assert!(names.iter().any(|n| n.ends_with(suffix)), "{names:?}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A 2x2 image, red green over blue white, on rectangles, PLY meshes and through to_uv:
/// Mitsuba's uv (0, 0) is the image's top-left corner, at the rectangle's (-1, -1).
#[test]
fn bitmaps_read_the_right_way_up() {
    let dir = temp_dir("bitmap-orientation");
    irad::image::png::write_rgb8(
        &dir.join("quad.png"),
        2,
        2,
        &[255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255],
    )
    .unwrap();
    let ply = |name: &str, flip: bool| {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                    property float y\nproperty float z\nproperty float s\nproperty float t\n\
                    element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 -2 0.75 0.75\n1 0 -2 0.75 0.75\n0 1 -2 0.75 0.75\n3 0 1 2\n";
        std::fs::write(dir.join(format!("{name}.ply")), text).unwrap();
        format!(
            r#"<shape type="ply" id="{name}"><string name="filename" value="{name}.ply"/>
               <boolean name="flip_tex_coords" value="{flip}"/>
               <bsdf type="diffuse"><ref name="reflectance" id="quad"/></bsdf></shape>"#
        )
    };
    let xml = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <texture type="bitmap" id="quad">
        <string name="filename" value="quad.png"/>
        <string name="wrap_mode" value="clamp"/>
        <string name="filter_type" value="nearest"/>
    </texture>
    <shape type="rectangle" id="plain">
        <bsdf type="twosided"><bsdf type="diffuse"><ref name="reflectance" id="quad"/></bsdf></bsdf>
    </shape>
    <shape type="rectangle" id="shifted">
        <transform name="to_world"><translate z="-1"/></transform>
        <bsdf type="diffuse">
            <texture type="bitmap" name="reflectance">
                <string name="filename" value="quad.png"/>
                <transform name="to_uv"><scale x="2" y="2"/><translate x="0.5"/></transform>
            </texture>
        </bsdf>
    </shape>
    {}
    {}
    <shape type="rectangle" id="coated">
        <transform name="to_world"><translate z="-3"/></transform>
        <bsdf type="roughplastic"><ref name="diffuse_reflectance" id="quad"/></bsdf>
    </shape>
    <shape type="rectangle" id="mixed">
        <transform name="to_world"><translate z="-4"/></transform>
        <bsdf type="blendbsdf">
            <ref name="weight" id="quad"/>
            <bsdf type="diffuse"><ref name="reflectance" id="quad"/></bsdf>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.2"/></bsdf>
        </bsdf>
    </shape>
    <emitter type="constant"/>
</scene>"#,
        ply("unflipped", false),
        ply("flipped", true)
    );
    std::fs::write(dir.join("scene.xml"), xml).unwrap();
    let scene = irad::scene::load(&dir.join("scene.xml")).unwrap();
    let (red, green, blue, white) = (Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE);
    // The albedo (Kd x texture) of `material` at the point `p` of one of its triangles.
    let albedo = |material: &str, p: Vec3| -> Vec3 {
        let (i, m) = scene
            .materials
            .iter()
            .enumerate()
            .find(|(_, m)| m.name == material)
            .unwrap_or_else(|| panic!("no material {material}"));
        for t in scene.triangles.iter().filter(|t| t.material as usize == i) {
            let [a, b, c] = t.positions;
            let n = (b - a).cross(c - a);
            let w = [
                (c - b).cross(p - b),
                (a - c).cross(p - c),
                (b - a).cross(p - a),
            ]
            .map(|x| x.dot(n) / n.length_squared());
            if w.iter().all(|&x| x >= -1e-6) && (p - a).dot(n).abs() < 1e-6 {
                let uv = t.uvs[0] * w[0] + t.uvs[1] * w[1] + t.uvs[2] * w[2];
                let texture = &scene.textures[m.albedo_texture.unwrap() as usize];
                return m.kd * texture.sample(uv);
            }
        }
        panic!("{material}: no triangle at {p}")
    };
    let near = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-4;
    for (x, y, want) in [
        (-0.5, -0.5, red),
        (0.5, -0.5, green),
        (-0.5, 0.5, blue),
        (0.5, 0.5, white),
    ] {
        let got = albedo("plain", Vec3::new(x, y, 0.0));
        assert!(near(got, want), "plain at ({x}, {y}): {got}, not {want}");
    }
    // to_uv 2 uv + (0.5, 0), repeated: (-0.75, -0.75) is uv (0.125, 0.125) -> (0.75, 0.25),
    // top-right; (-0.25, -0.75) -> (1.25, 0.25), top-left.
    assert!(near(
        albedo("shifted", Vec3::new(-0.75, -0.75, -1.0)),
        green
    ));
    assert!(near(albedo("shifted", Vec3::new(-0.25, -0.75, -1.0)), red));
    // s t = (0.75, 0.75): Mitsuba's bottom-right; flip_tex_coords: top-right.
    let inside = Vec3::new(0.25, 0.25, -2.0);
    assert!(near(albedo("unflipped", inside), white));
    assert!(near(albedo("flipped", inside), green));
    // roughplastic keeps the texture, Kd 1 - F0.
    let f0 = ((1.49 / 1.000277f64 - 1.0) / (1.49 / 1.000277f64 + 1.0)).powi(2) as f32;
    assert!(near(
        albedo("coated", Vec3::new(-0.5, -0.5, -3.0)),
        red * (1.0 - f0)
    ));
    // A blend of a texture and a colour: the texture's mean, with a warning; the weight a
    // bitmap too (its mean, 0.5).
    let mixed = scene.materials.iter().find(|m| m.name == "mixed").unwrap();
    assert_eq!(mixed.albedo_texture, None);
    assert!(near(
        mixed.kd,
        0.5 * Vec3::splat(0.5) + 0.5 * Vec3::splat(0.2)
    ));
    let warnings = scene.warnings.join("\n");
    for needle in ["as its mean colour", "filter_type nearest read as bilinear"] {
        assert!(
            warnings.contains(needle),
            "{needle} missing from:\n{warnings}"
        );
    }
    // One scene texture per wrap (clamp, repeat), the file decoded once.
    assert_eq!(scene.textures.len(), 2);
    std::fs::remove_dir_all(&dir).ok();
}
