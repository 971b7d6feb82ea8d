//! Scene loading (docs/DESIGN.md "Scene files"; docs/scenes.md), CPU only: every committed
//! scene and the embedded default load with the documented conventions; every kind of bad input
//! gives one error naming the file, the field and the value.

use std::path::{Path, PathBuf};

use glam::Vec3;
use irad::image::{exr, Image};
use irad::scene::{self, hash::fnv1a64, FailureNote, Scene};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// A scratch folder under the system temp dir, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("irad-scene-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    fn write(&self, name: &str, text: &str) -> &Scratch {
        std::fs::write(self.0.join(name), text).unwrap();
        self
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    fn load(&self) -> Result<Scene, scene::SceneError> {
        scene::load(&self.path("scene.toml"))
    }

    /// The error of loading scene.toml, checked to contain every one of `parts`.
    fn error(&self, parts: &[&str]) -> String {
        let message = match self.load() {
            Ok(_) => panic!(
                "{} loaded, expected an error",
                self.path("scene.toml").display()
            ),
            Err(e) => e.to_string(),
        };
        for part in parts {
            assert!(message.contains(part), "`{part}` not in: {message}");
        }
        message
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

const CAMERA: &str = "[camera]\nposition = [0, 1, 3]\nlook_at = [0, 1, 0]\nup = [0, 1, 0]\n\
                      fov_y = 40\nresolution = [16, 16]\n";
const MESH: &str = "[[mesh]]\nobj = \"m.obj\"\n";
const POINT: &str = "[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n";
/// A 2 x 2 quad at y = 0 facing +Y (lines 2-5 are its vertices).
const OBJ: &str = "mtllib m.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nusemtl grey\nf 1 4 3 2\n";
const MTL: &str = "newmtl grey\nKd 0.5 0.5 0.5\n";

/// A valid scene (quad + point light) in which `replace` swaps one piece of text.
fn scratch(name: &str, toml: &str, obj: &str, mtl: &str) -> Scratch {
    let s = Scratch::new(name);
    s.write("scene.toml", toml)
        .write("m.obj", obj)
        .write("m.mtl", mtl);
    s
}

fn good_toml() -> String {
    format!("{CAMERA}{MESH}{POINT}")
}

fn sky(width: u32, height: u32, bad: Option<(u32, u32, [f32; 3])>) -> Image {
    let mut image = Image::new(width, height);
    image.pixels.iter_mut().for_each(|p| *p = [0.5, 0.6, 0.8]);
    if let Some((x, y, v)) = bad {
        image.pixels[(y * width + x) as usize] = v;
    }
    image
}

// ---- bad input: one test per case -------------------------------------------------------

#[test]
fn missing_scene_file() {
    let s = Scratch::new("missing-toml");
    let e = s.error(&["scene.toml", "cannot read it", "the scene file"]);
    assert!(
        e.contains(&s.path("scene.toml").display().to_string()),
        "{e}"
    );
}

#[test]
fn missing_obj() {
    let toml = format!("{CAMERA}[[mesh]]\nobj = \"gone.obj\"\n{POINT}");
    let s = scratch("missing-obj", &toml, OBJ, MTL);
    s.error(&[
        "gone.obj",
        "cannot read it",
        "scene.toml: mesh[0].obj = \"gone.obj\"",
    ]);
}

#[test]
fn missing_mtl() {
    let obj = OBJ.replace("mtllib m.mtl", "mtllib gone.mtl");
    let s = scratch("missing-mtl", &good_toml(), &obj, MTL);
    s.error(&[
        "gone.mtl",
        "cannot read it",
        "m.obj line 1: mtllib gone.mtl",
    ]);
}

#[test]
fn missing_exr() {
    let toml = format!("{}[environment]\nexr = \"gone.exr\"\n", good_toml());
    let s = scratch("missing-exr", &toml, OBJ, MTL);
    s.error(&[
        "gone.exr",
        "cannot read it",
        "scene.toml: environment.exr = \"gone.exr\"",
    ]);
}

#[test]
fn malformed_toml() {
    let toml = good_toml().replace("fov_y = 40", "fov_y = 40 40");
    let s = scratch("malformed", &toml, OBJ, MTL);
    s.error(&["scene.toml: ", "line 5", "fov_y = 40 40"]);
}

#[test]
fn unknown_field() {
    let toml = good_toml().replace("fov_y = 40", "fov_y = 40\nfocus_distance = 2.5");
    let s = scratch("unknown-field", &toml, OBJ, MTL);
    s.error(&["scene.toml: ", "line 6", "unknown field `focus_distance`"]);
}

#[test]
fn wrong_type() {
    let toml = good_toml().replace("fov_y = 40", "fov_y = \"wide\"");
    let s = scratch("wrong-type", &toml, OBJ, MTL);
    s.error(&["scene.toml: ", "line 5", "fov_y = \"wide\""]);
}

#[test]
fn nan_texel_in_exr() {
    let toml = format!("{}[environment]\nexr = \"sky.exr\"\n", good_toml());
    let s = scratch("nan-texel", &toml, OBJ, MTL);
    exr::write(
        &s.path("sky.exr"),
        &sky(8, 4, Some((3, 1, [0.5, f32::NAN, 0.5]))),
    )
    .unwrap();
    s.error(&["sky.exr: texel (x 3, y 1) = [0.5, NaN, 0.5]", "finite"]);
}

#[test]
fn negative_texel_in_exr() {
    let toml = format!("{}[environment]\nexr = \"sky.exr\"\n", good_toml());
    let s = scratch("negative-texel", &toml, OBJ, MTL);
    exr::write(
        &s.path("sky.exr"),
        &sky(8, 4, Some((0, 2, [-1.0, 0.0, 0.0]))),
    )
    .unwrap();
    s.error(&["sky.exr: texel (x 0, y 2) = [-1, 0, 0]", ">= 0"]);
}

#[test]
fn infinite_texel_in_exr() {
    let toml = format!("{}[environment]\nexr = \"sky.exr\"\n", good_toml());
    let s = scratch("inf-texel", &toml, OBJ, MTL);
    exr::write(
        &s.path("sky.exr"),
        &sky(8, 4, Some((7, 3, [f32::INFINITY, 0.0, 0.0]))),
    )
    .unwrap();
    s.error(&["sky.exr: texel (x 7, y 3) = [inf, 0, 0]"]);
}

#[test]
fn corrupt_exr() {
    let toml = format!("{}[environment]\nexr = \"sky.exr\"\n", good_toml());
    let s = scratch("corrupt-exr", &toml, OBJ, MTL);
    s.write("sky.exr", "not an image");
    s.error(&["sky.exr: environment.exr: ", "OpenEXR"]);
}

#[test]
fn bad_environment_scale() {
    let toml = format!(
        "{}[environment]\nexr = \"sky.exr\"\nscale = -2.0\n",
        good_toml()
    );
    let s = scratch("bad-scale", &toml, OBJ, MTL);
    exr::write(&s.path("sky.exr"), &sky(8, 4, None)).unwrap();
    s.error(&["scene.toml: environment.scale = -2", ">= 0"]);
}

#[test]
fn nan_in_mtl_kd() {
    let s = scratch("nan-kd", &good_toml(), OBJ, "newmtl grey\nKd 0.5 nan 0.5\n");
    s.error(&[
        "m.mtl: material `grey` Kd (line 2) = [0.5, NaN, 0.5]",
        "finite",
    ]);
}

#[test]
fn negative_ke() {
    let s = scratch(
        "negative-ke",
        &good_toml(),
        OBJ,
        "newmtl grey\nKd 0.5\nKe -1 0 0\n",
    );
    s.error(&["m.mtl: material `grey` Ke (line 3) = [-1, 0, 0]", ">= 0"]);
}

#[test]
fn kd_plus_ks_above_one() {
    let mtl = "newmtl grey\nKd 0.75\nKs 0.5 0.25 0.25\nNs 10\n";
    let s = scratch("kd-ks", &good_toml(), OBJ, mtl);
    s.error(&[
        "m.mtl: material `grey` Kd + Ks = [1.25, 1, 1]",
        "Kd = [0.75, 0.75, 0.75]",
        "Ks = [0.5, 0.25, 0.25]",
    ]);
}

#[test]
fn degenerate_triangles_are_dropped_with_a_warning() {
    // A collinear triangle and one with a repeated corner beside the quad.
    let obj = format!("{OBJ}v 2 0 0\nv 3 0 0\nv 4 0 0\nf 5 6 7\nf 1 1 2\n");
    let s = scratch("degenerate", &good_toml(), &obj, MTL);
    let scene = s.load().unwrap();
    assert_eq!(scene.triangles.len(), 2);
    let w = scene.warnings.join("\n");
    assert!(w.contains("m.obj: dropped 2 degenerate triangles"), "{w}");
}

/// A two-sided light written as two faces with the same corners: the loader warns, naming the
/// OBJ and the count of emissive triangles (src/scene/coincident.rs says why); 1 mm apart, back
/// to back, it does not.
#[test]
fn emitters_coinciding_with_another_face_are_warned_of() {
    let light = "newmtl light\nKd 0 0 0\nKe 5 5 5\n";
    let quad =
        |y: &str| format!("v -0.5 {y} -0.5\nv 0.5 {y} -0.5\nv 0.5 {y} 0.5\nv -0.5 {y} 0.5\n");
    let two_sided = format!("{OBJ}{}usemtl light\nf 5 6 7 8\nf 5 8 7 6\n", quad("1"));
    let s = scratch(
        "two-sided",
        &good_toml(),
        &two_sided,
        &format!("{MTL}{light}"),
    );
    let w = s.load().unwrap().warnings.join("\n");
    assert!(
        w.contains("m.obj: 4 emissive triangle(s) have the same corners as another triangle"),
        "{w}"
    );
    let apart = format!(
        "{OBJ}{}{}usemtl light\nf 5 6 7 8\nf 9 12 11 10\n",
        quad("1"),
        quad("1.001")
    );
    let s = scratch(
        "two-sided-apart",
        &good_toml(),
        &apart,
        &format!("{MTL}{light}"),
    );
    let scene = s.load().unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn nan_vertex() {
    let obj = OBJ.replace("v 1 0 1", "v 1 nan 1");
    let s = scratch("nan-vertex", &good_toml(), &obj, MTL);
    s.error(&["m.obj line 4: vertex position [1, NaN, 1] is not finite"]);
}

#[test]
fn empty_scene() {
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let s = scratch("empty", &good_toml(), obj, MTL);
    s.error(&["scene.toml: the scene has no triangles in its 1 mesh file(s)"]);
    let s = scratch("no-mesh", &format!("{CAMERA}{POINT}"), OBJ, MTL);
    s.error(&["scene.toml: the scene has no triangles (it names no [[mesh]])"]);
}

#[test]
fn no_lights() {
    let s = scratch("no-light", &format!("{CAMERA}{MESH}"), OBJ, MTL);
    s.error(&[
        "scene.toml: the scene has no light",
        "Ke",
        "[[light]]",
        "[environment]",
    ]);
    // A light of zero intensity does not count either.
    let toml = good_toml().replace("intensity = [1, 1, 1]", "intensity = [0, 0, 0]");
    let s = scratch("dark-light", &toml, OBJ, MTL);
    s.error(&["scene.toml: the scene has no light"]);
}

#[test]
fn zero_resolution() {
    let toml = good_toml().replace("resolution = [16, 16]", "resolution = [0, 16]");
    let s = scratch("zero-res", &toml, OBJ, MTL);
    s.error(&[
        "scene.toml: camera.resolution = [0, 16]",
        "width and height",
    ]);
    let toml = good_toml().replace("resolution = [16, 16]", "resolution = [16, -3]");
    let s = scratch("negative-res", &toml, OBJ, MTL);
    s.error(&["scene.toml: camera.resolution = [16, -3]"]);
    // One limit for scene files, suite files and WxH flags (scenes took 65536, suites 16384).
    let toml = good_toml().replace("resolution = [16, 16]", "resolution = [16385, 16]");
    let s = scratch("wide-res", &toml, OBJ, MTL);
    s.error(&["camera.resolution = [16385, 16]", "1..=16384"]);
    assert_eq!(scene::MAX_RESOLUTION, 16384);
}

/// An array of the wrong length is refused with its key and line, not cut to its first items
/// (`position = [0, 1, 3, 9]` loaded as [0, 1, 3], `resolution = [16, 16, 3]` as 16x16).
#[test]
fn arrays_of_the_wrong_length_are_refused() {
    let sky = "[environment]\nsky = \"moving-sun\"\nsize = [16, 8]\n";
    let spot = "[[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n\
                direction = [0, -1, 0]\ncone_angle = 30\n";
    for (from, to, key) in [
        (
            "position = [0, 1, 3]",
            "position = [0, 1, 3, 9]",
            "position",
        ),
        (
            "resolution = [16, 16]",
            "resolution = [16, 16, 3]",
            "resolution",
        ),
        ("resolution = [16, 16]", "resolution = [16]", "resolution"),
        (
            "intensity = [1, 1, 1]",
            "intensity = [1, 1, 1, 1]",
            "intensity",
        ),
        ("direction = [0, -1, 0]", "direction = [0, -1]", "direction"),
        ("size = [16, 8]", "size = [16, 8, 2]", "size"),
    ] {
        let toml = format!("{CAMERA}{MESH}{spot}{sky}");
        assert!(toml.contains(from), "{from}");
        let s = scratch("array-length", &toml.replacen(from, to, 1), OBJ, MTL);
        s.error(&["scene.toml", "invalid length", key]);
    }
}

#[test]
fn bad_fov() {
    for fov in ["0", "180", "-5", "nan"] {
        let toml = good_toml().replace("fov_y = 40", &format!("fov_y = {fov}"));
        let s = scratch("bad-fov", &toml, OBJ, MTL);
        let shown = if fov == "nan" { "NaN" } else { fov };
        s.error(&[&format!("scene.toml: camera.fov_y = {shown}: "), "(0, 180)"]);
    }
}

#[test]
fn camera_position_equals_look_at() {
    let toml = good_toml().replace("look_at = [0, 1, 0]", "look_at = [0, 1, 3]");
    let s = scratch("look-at", &toml, OBJ, MTL);
    s.error(&["scene.toml: camera.look_at = [0, 1, 3]", "camera.position"]);
}

#[test]
fn bad_spot_angles() {
    let spot = |cone: &str, falloff: &str| {
        format!(
            "{CAMERA}{MESH}[[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n\
             direction = [0, -1, 0]\ncone_angle = {cone}\nfalloff_angle = {falloff}\n"
        )
    };
    let s = scratch("spot-order", &spot("40", "30"), OBJ, MTL);
    s.error(&["scene.toml: light[0].cone_angle = 40", "falloff_angle (30)"]);
    let s = scratch("spot-range", &spot("30", "200"), OBJ, MTL);
    s.error(&["scene.toml: light[0].falloff_angle = 200", "(0, 180]"]);
    let s = scratch("spot-zero", &spot("0", "30"), OBJ, MTL);
    s.error(&["scene.toml: light[0].cone_angle = 0", "(0, 180]"]);
}

#[test]
fn bad_light_intensity_and_direction() {
    let toml = good_toml().replace("intensity = [1, 1, 1]", "intensity = [1, -1, 1]");
    let s = scratch("neg-intensity", &toml, OBJ, MTL);
    s.error(&["scene.toml: light[0].intensity = [1, -1, 1]"]);
    let toml = format!(
        "{CAMERA}{MESH}{POINT}[[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\n\
         intensity = [1, 1, 1]\ndirection = [0, 0, 0]\ncone_angle = 10\nfalloff_angle = 20\n"
    );
    let s = scratch("zero-direction", &toml, OBJ, MTL);
    s.error(&["scene.toml: light[1].direction = [0, 0, 0]", "non-zero"]);
}

#[test]
fn environment_glob_is_a_sequence_in_name_order() {
    let toml = format!("{}[environment]\nexr = \"sky/f_*.exr\"\n", good_toml());
    let s = scratch("glob", &toml, OBJ, MTL);
    std::fs::create_dir_all(s.path("sky")).unwrap();
    // Written out of order; a non-matching file beside them is left out.
    for (name, value) in [
        ("f_2.exr", 3.0),
        ("f_0.exr", 1.0),
        ("f_1.exr", 2.0),
        ("g_9.exr", 9.0),
    ] {
        let mut image = sky(8, 4, None);
        image.pixels.iter_mut().for_each(|p| *p = [value; 3]);
        exr::write(&s.path("sky").join(name), &image).unwrap();
    }
    let scene = s.load().unwrap();
    let frames: Vec<f32> = scene
        .environment_sequence
        .iter()
        .map(|e| e.texels[0].x)
        .collect();
    assert_eq!(frames, vec![1.0, 2.0, 3.0]);
    assert_eq!(scene.environment.as_ref().unwrap().texels[0].x, 1.0);
    // Every frame is in the content hash.
    let before = scene.content_hash;
    exr::write(&s.path("sky").join("f_2.exr"), &sky(8, 4, None)).unwrap();
    assert_ne!(s.load().unwrap().content_hash, before);
    // A frame of another size is refused, naming it and the first.
    exr::write(&s.path("sky").join("f_1.exr"), &sky(16, 8, None)).unwrap();
    s.error(&["f_1.exr: size = 16x8", "f_0.exr (8x4)"]);
}

#[test]
fn environment_glob_errors() {
    let toml = format!("{}[environment]\nexr = \"sky/*.exr\"\n", good_toml());
    let s = scratch("glob-none", &toml, OBJ, MTL);
    std::fs::create_dir_all(s.path("sky")).unwrap();
    s.error(&[
        "scene.toml: environment.exr = \"sky/*.exr\"",
        "no file in",
        "matches",
    ]);
    let toml = format!("{}[environment]\nexr = \"gone/*.exr\"\n", good_toml());
    let s = scratch("glob-folder", &toml, OBJ, MTL);
    s.error(&["gone", "environment.exr = \"gone/*.exr\" (its folder)"]);
    let toml = format!("{}[environment]\nexr = \"sky/[ab].exr\"\n", good_toml());
    let s = scratch("glob-class", &toml, OBJ, MTL);
    s.error(&[
        "scene.toml: environment.exr = \"sky/[ab].exr\"",
        "not supported yet",
    ]);
    let toml = format!("{}[environment]\nexr = \"*/a.exr\"\n", good_toml());
    let s = scratch("glob-dir", &toml, OBJ, MTL);
    s.error(&["environment.exr = \"*/a.exr\"", "not supported yet"]);
}

#[test]
fn procedural_sky_and_its_errors() {
    let sky_toml =
        |fields: &str| format!("{CAMERA}{MESH}[environment]\nsky = \"moving-sun\"\n{fields}");
    let s = scratch("sky", &sky_toml("size = [16, 8]\nframes = 5\n"), OBJ, MTL);
    let scene = s.load().unwrap();
    assert_eq!(scene.environment_sequence.len(), 5);
    assert_eq!(scene.environment.as_ref().unwrap().width, 16);
    assert_ne!(
        scene.environment_sequence[0].texels,
        scene.environment_sequence[1].texels
    );
    for (fields, parts) in [
        (
            "size = [0, 8]\n",
            vec!["environment.size = [0, 8]", "1..=16384"],
        ),
        ("frames = 0\n", vec!["environment.frames = 0", "1..=4096"]),
        (
            "sun_elevation = 95\n",
            vec!["environment.sun_elevation = 95", "-90..=90"],
        ),
        (
            "sun_radius = 0\n",
            vec!["environment.sun_radius = 0", "(0, 90]"],
        ),
        (
            "sun_radiance = [1, -1, 1]\n",
            vec!["environment.sun_radiance", ">= 0"],
        ),
        (
            "size = [16384, 16384]\nframes = 4096\n",
            vec!["environment.frames = 4096", "texels in all"],
        ),
    ] {
        scratch("sky-bad", &sky_toml(fields), OBJ, MTL).error(&parts);
    }
    let toml = format!("{CAMERA}{MESH}[environment]\nsky = \"noon\"\n");
    scratch("sky-name", &toml, OBJ, MTL).error(&["environment.sky = \"noon\"", "moving-sun"]);
    let toml = format!("{CAMERA}{MESH}[environment]\nsky = \"moving-sun\"\nexr = \"a.exr\"\n");
    scratch("sky-both", &toml, OBJ, MTL).error(&["environment.sky", "not both"]);
    let toml = format!("{CAMERA}{MESH}[environment]\nscale = 2\n");
    scratch("sky-neither", &toml, OBJ, MTL).error(&["environment.exr = (missing)", "moving-sun"]);
    let toml = format!("{CAMERA}{MESH}[environment]\nexr = \"a.exr\"\nframes = 3\n");
    scratch("sky-field", &toml, OBJ, MTL).error(&["environment.frames", "sky only"]);
}

#[test]
fn luminaires_are_placed_and_bad_placements_refused() {
    use irad::scene::luminaire::{Basis, Emitter, Geometry, Luminaire};
    let placement = |path: &str, look_at: &str| {
        format!(
            "{CAMERA}{MESH}[[luminaire]]\npath = \"{path}\"\nposition = [0, 1, 0]\nlook_at = {look_at}\n"
        )
    };
    let s = scratch(
        "luminaire",
        &placement("headlight/luminaire.toml", "[0, 0, 0]"),
        OBJ,
        MTL,
    );
    s.error(&[
        "headlight/luminaire.toml",
        "cannot read it",
        "scene.toml: luminaire[0].path = \"headlight/luminaire.toml\"",
    ]);
    let geometry = Geometry {
        grid: [2, 2],
        pitch: [0.02, 0.02],
        basis: Basis::Bilinear,
        delta: 0.05,
        image_size: [0.2, 0.2],
        resolution: [4, 4],
    };
    let disk = Emitter::Disk {
        radius: 0.02,
        radiance: 1.0,
    };
    Luminaire::from_emitter(geometry, |u, t| disk.radiance(u, t, 0.05), "test")
        .write(&s.path("headlight"))
        .unwrap();
    // Placed: z toward look_at (down), y the world's up made perpendicular to it.
    let scene = s.load().unwrap();
    assert_eq!(scene.luminaires.len(), 1);
    let l = &scene.luminaires[0];
    assert!(
        (l.z - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6,
        "{:?}",
        l.z
    );
    assert!(l.x.dot(l.y).abs() < 1e-6 && l.x.cross(l.y).dot(l.z) > 0.999);
    // A scene lit only by a luminaire is lit.
    let s2 = scratch(
        "luminaire-same",
        &placement("headlight/luminaire.toml", "[0, 1, 0]"),
        OBJ,
        MTL,
    );
    Luminaire::from_emitter(geometry, |u, t| disk.radiance(u, t, 0.05), "test")
        .write(&s2.path("headlight"))
        .unwrap();
    s2.error(&[
        "scene.toml: luminaire[0].look_at = [0.0, 1.0, 0.0]",
        "must differ from position",
    ]);
}

const FAILURE: &str = "[failure]\nmethods = [\"ir\"]\nwhy = \"light-side VPLs starve.\"\n\
                       source = \"Segovia 06, Fig. 4\"\n";

#[test]
fn failure_with_no_methods() {
    let toml = format!("{}{}", good_toml(), FAILURE.replace("[\"ir\"]", "[]"));
    let s = scratch("failure-no-methods", &toml, OBJ, MTL);
    s.error(&["scene.toml: failure.methods = []: must name at least one method"]);
}

#[test]
fn failure_with_an_empty_method_or_text() {
    for (from, to, expected) in [
        (
            "[\"ir\"]",
            "[\"ir\", \"\"]",
            "scene.toml: failure.methods[1] = \"\": ",
        ),
        (
            "why = \"light-side VPLs starve.\"",
            "why = \"\"",
            "scene.toml: failure.why = \"\": ",
        ),
        (
            "source = \"Segovia 06, Fig. 4\"",
            "source = \" \"",
            "scene.toml: failure.source = \" \": ",
        ),
    ] {
        let toml = format!("{}{}", good_toml(), FAILURE.replace(from, to));
        let s = scratch("failure-empty", &toml, OBJ, MTL);
        s.error(&[expected]);
    }
}

#[test]
fn unknown_field_in_failure() {
    let toml = format!("{}{FAILURE}expected_relmse = 0.5\n", good_toml());
    let s = scratch("failure-unknown-field", &toml, OBJ, MTL);
    s.error(&["scene.toml: ", "unknown field `expected_relmse`", "line 17"]);
}

#[test]
fn bad_obj_face_index() {
    let obj = OBJ.replace("f 1 4 3 2", "f 1 4 3 9");
    let s = scratch("face-index", &good_toml(), &obj, MTL);
    s.error(&["m.obj line 7: face corner `9`: vertex index 9 is out of range"]);
}

// ---- handled as documented ----------------------------------------------------------------

#[test]
fn faces_without_material_get_the_default_with_a_warning() {
    let obj = OBJ.replace("usemtl grey\n", "");
    let s = scratch("no-material", &good_toml(), &obj, MTL);
    let scene = s.load().unwrap();
    let m = &scene.materials[scene.triangles[0].material as usize];
    assert_eq!(
        (m.kd, m.ks, m.ke),
        (Vec3::splat(0.5), Vec3::ZERO, Vec3::ZERO)
    );
    let w = scene.warnings.join("\n");
    assert!(w.contains("m.obj: 2 triangles have no material"), "{w}");
}

#[test]
fn obj_normals_are_used_normalized_with_geometric_fallback() {
    let obj =
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 -1\nvn 0 3 0.0\nvn 0 0 0\nvn 1 0 0\nusemtl grey\n\
               f 1//1 2//2 3//3\nf 1 2 3\n";
    let s = scratch("normals", &good_toml(), obj, MTL);
    let scene = s.load().unwrap();
    assert_eq!(scene.triangles[0].normals, [Vec3::Y, Vec3::Y, Vec3::X]);
    assert_eq!(scene.triangles[1].normals, [Vec3::Y; 3]);
}

#[test]
fn environment_is_scaled_and_row_major() {
    let toml = format!(
        "{}[environment]\nexr = \"sky.exr\"\nscale = 2.0\n",
        good_toml()
    );
    let s = scratch("env-scale", &toml, OBJ, MTL);
    let mut image = sky(8, 4, None);
    image.pixels[2 * 8 + 5] = [1.0, 2.0, 3.0];
    exr::write(&s.path("sky.exr"), &image).unwrap();
    let env = s.load().unwrap().environment.unwrap();
    assert_eq!((env.width, env.height), (8, 4));
    assert_eq!(env.texels[2 * 8 + 5], Vec3::new(2.0, 4.0, 6.0));
    assert_eq!(env.texels[0], Vec3::new(1.0, 1.2, 1.6));
    assert_eq!(env.source, s.path("sky.exr"));
}

#[test]
fn content_hash_covers_every_file_in_order() {
    let toml = format!("{}[environment]\nexr = \"sky.exr\"\n", good_toml());
    let s = scratch("hash", &toml, OBJ, MTL);
    exr::write(&s.path("sky.exr"), &sky(4, 2, None)).unwrap();
    let exr_bytes = std::fs::read(s.path("sky.exr")).unwrap();
    let all = [toml.as_bytes(), OBJ.as_bytes(), MTL.as_bytes(), &exr_bytes].concat();
    let first = s.load().unwrap().content_hash;
    assert_eq!(first, fnv1a64(&all));
    s.write("m.mtl", "newmtl grey\nKd 0.5 0.5 0.25\n");
    assert_ne!(s.load().unwrap().content_hash, first);
}

#[test]
fn failure_table_is_kept_and_method_names_are_not_checked() {
    let toml = format!(
        "{}{}",
        good_toml(),
        FAILURE.replace("\"ir\"", "\"ir\", \"no-such-method\"")
    );
    let scene = scratch("failure-kept", &toml, OBJ, MTL).load().unwrap();
    assert_eq!(
        scene.failure,
        Some(FailureNote {
            methods: vec!["ir".into(), "no-such-method".into()],
            why: "light-side VPLs starve.".into(),
            source: "Segovia 06, Fig. 4".into(),
        })
    );
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let plain = scratch("failure-none", &good_toml(), OBJ, MTL)
        .load()
        .unwrap();
    assert_eq!(plain.failure, None);
    assert_eq!(scene::default_scene().failure, None);
}

#[test]
fn load_str_reads_files_relative_to_base_dir() {
    let s = scratch("load-str", "", OBJ, MTL);
    let scene = scene::load_str(&good_toml(), &s.0, "inline").unwrap();
    assert_eq!(scene.name, "inline");
    assert!(scene.source.is_none());
    assert_eq!(scene.triangles.len(), 2);
    let e = scene::load_str("[camera]\n", &s.0, "inline")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("inline: ") && e.contains("missing field"),
        "{e}"
    );
}

// ---- the committed scenes ------------------------------------------------------------------

fn check_scene(scene: &Scene) {
    let label = &scene.name;
    assert!(!scene.triangles.is_empty(), "{label}");
    // Sponza is a model from elsewhere, stored unchanged: its one degenerate face is dropped
    // with a warning, the only one a committed scene may have.
    let expected: &[&str] = match label.as_str() {
        "sponza" => &["sponza.obj.gz: dropped 1 degenerate triangles"],
        _ => &[],
    };
    assert_eq!(
        scene.warnings.len(),
        expected.len(),
        "{label}: {:?}",
        scene.warnings
    );
    for (w, e) in scene.warnings.iter().zip(expected) {
        assert!(w.contains(e), "{label}: {w}");
    }
    if label == "sponza" {
        // Dabrovic's 66,454 faces, a material for every group from sponza.mtl.
        assert!(scene.triangles.len() > 66_000, "{}", scene.triangles.len());
        let mut used: Vec<&str> = scene
            .triangles
            .iter()
            .map(|t| scene.materials[t.material as usize].name.as_str())
            .collect();
        used.sort();
        used.dedup();
        assert_eq!(used, ["ceiling", "floor", "glass", "stone", "wood"]);
    }
    assert!(scene.camera.width > 0 && scene.camera.height > 0, "{label}");
    assert_ne!(scene.content_hash, 0);
    for m in &scene.materials {
        assert!((m.kd + m.ks).max_element() <= 1.0, "{label}: {m:?}");
        assert!(m.kd.min_element() >= 0.0 && m.ks.min_element() >= 0.0 && m.ns >= 0.0);
    }
    for t in &scene.triangles {
        assert!((t.material as usize) < scene.materials.len(), "{label}");
        assert!(t.positions.iter().all(|p| p.is_finite()), "{label}");
        for n in t.normals {
            assert!((n.length() - 1.0).abs() < 1e-5, "{label}: {n}");
        }
    }
}

fn committed(name: &str) -> Scene {
    scene::load(&scenes_dir().join(name).join("scene.toml"))
        .unwrap_or_else(|e| panic!("scenes/{name}: {e}"))
}

/// Every `*/scene.toml` directly under `dir`, loaded and checked.
fn load_every_scene_in(dir: &Path) -> Vec<Scene> {
    let mut scenes = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let dir = entry.unwrap().path();
        if dir.join("scene.toml").is_file() {
            let scene = scene::load(&dir.join("scene.toml"))
                .unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
            assert_eq!(scene.name, dir.file_name().unwrap().to_string_lossy());
            check_scene(&scene);
            scenes.push(scene);
        }
    }
    scenes
}

#[test]
fn every_committed_scene_loads() {
    let count = load_every_scene_in(&scenes_dir()).len();
    assert!(count >= 4, "only {count} scenes under scenes/");
}

/// The stability suite: every scene under scenes/failure/ loads like the others and says which
/// methods are expected to fail on it.
#[test]
fn every_failure_scene_loads_with_its_failure_table() {
    let scenes = load_every_scene_in(&scenes_dir().join("failure"));
    assert!(
        scenes.len() >= 3,
        "only {} scenes under scenes/failure/",
        scenes.len()
    );
    for scene in &scenes {
        let note = scene
            .failure
            .as_ref()
            .unwrap_or_else(|| panic!("scenes/failure/{}: no [failure] table", scene.name));
        assert!(note.methods.iter().all(|m| !m.is_empty()), "{}", scene.name);
        // Environment-lit scenes are open by nature (the map must reach them).
        if scene.environment.is_none() {
            outer_walls_face_in(scene);
        }
    }
}

/// Every triangle lying on a face of the scene's bounding box faces into the box: the suite's
/// scenes are closed rooms seen from inside.
fn outer_walls_face_in(scene: &Scene) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in scene.triangles.iter().flat_map(|t| t.positions) {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let mut on_box = 0;
    for t in &scene.triangles {
        let [a, b, c] = t.positions;
        let n = (b - a).cross(c - a).normalize();
        for axis in 0..3 {
            for (at, inward) in [(lo[axis], 1.0), (hi[axis], -1.0)] {
                if t.positions.iter().all(|p| p[axis] == at) {
                    assert_eq!(n[axis], inward, "{}: {t:?} faces out", scene.name);
                    on_box += 1;
                }
            }
        }
    }
    assert!(
        on_box >= 12,
        "{}: only {on_box} triangles on the box",
        scene.name
    );
}

#[test]
fn failure_scene_facts() {
    let facing_down = |scene: &Scene| {
        let emissive: Vec<_> = scene
            .triangles
            .iter()
            .filter(|t| scene.materials[t.material as usize].is_emissive())
            .collect();
        emissive.iter().all(|t| {
            let [a, b, c] = t.positions;
            (b - a).cross(c - a).normalize().y < -0.999
        }) && !emissive.is_empty()
    };
    let failure = |name: &str| {
        scene::load(&scenes_dir().join("failure").join(name).join("scene.toml"))
            .unwrap_or_else(|e| panic!("scenes/failure/{name}: {e}"))
    };

    // u-office: the light is in room A (x < 3, z < 3), the camera in room B (x > 3.4, z < 3).
    let office = failure("u-office");
    assert!(office.lights.is_empty() && facing_down(&office));
    for t in office
        .triangles
        .iter()
        .filter(|t| office.materials[t.material as usize].is_emissive())
    {
        assert!(t.positions.iter().all(|p| p.x < 3.0 && p.z < 3.0), "{t:?}");
    }
    let eye = office.camera.position;
    assert!(
        eye.x > 3.4 && eye.x < 6.4 && eye.z > 0.0 && eye.z < 3.0,
        "{eye}"
    );

    // corner-light: one point light within 0.1 of two walls and the ceiling; a bright object.
    let corner = failure("corner-light");
    match corner.lights[..] {
        [scene::Light::Point { position, .. }] => {
            assert!(
                2.0 - position.x <= 0.1 && position.z + 2.0 <= 0.1,
                "{position}"
            );
            assert!(2.5 - position.y <= 0.1, "{position}");
        }
        ref l => panic!("{l:?}"),
    }
    assert!(corner.materials.iter().any(|m| m.kd.min_element() >= 0.9));
    assert!(corner.materials.iter().all(|m| m.ks == Vec3::ZERO));

    // glossy-walls: glossy Phong walls (Ns in 100..=300) and one ceiling light facing down.
    let glossy = failure("glossy-walls");
    assert!(glossy.lights.is_empty() && facing_down(&glossy));
    assert!(glossy
        .materials
        .iter()
        .any(|m| m.ks.min_element() >= 0.5 && (100.0..=300.0).contains(&m.ns)));
}

#[test]
fn cornell_box_facts() {
    let scene = committed("cornell-box");
    assert_eq!((scene.camera.width, scene.camera.height), (256, 256));
    assert_eq!(scene.camera.fov_y, 40.0);
    assert!(scene.lights.is_empty() && scene.environment.is_none());
    let geometric = |t: &irad::scene::Triangle| {
        let [a, b, c] = t.positions;
        (b - a).cross(c - a).normalize()
    };
    let emissive: Vec<_> = scene
        .triangles
        .iter()
        .filter(|t| scene.materials[t.material as usize].is_emissive())
        .collect();
    assert_eq!(emissive.len(), 2);
    for t in &emissive {
        assert!(geometric(t).y < -0.999, "the light must face down");
        assert!(t.positions.iter().all(|p| p.y > 1.9 && p.y < 2.0));
    }
    // The five walls face into the box.
    let inward = [
        (0usize, -1.0f32, Vec3::X, "red"),
        (0, 1.0, -Vec3::X, "green"),
        (1, 0.0, Vec3::Y, "white"),
        (1, 2.0, -Vec3::Y, "white"),
        (2, -1.0, Vec3::Z, "white"),
    ];
    for (axis, at, normal, material) in inward {
        let on_wall: Vec<_> = scene
            .triangles
            .iter()
            .filter(|t| t.positions.iter().all(|p| p[axis] == at))
            .collect();
        assert_eq!(on_wall.len(), 2, "wall at axis {axis} = {at}");
        for t in on_wall {
            assert_eq!(geometric(t), normal);
            assert_eq!(scene.materials[t.material as usize].name, material);
        }
    }
}

#[test]
fn default_scene_is_the_cornell_box_from_embedded_copies() {
    let embedded = scene::default_scene();
    let file = committed("cornell-box");
    assert_eq!(embedded.name, "cornell-box");
    assert!(embedded.source.is_none());
    assert_eq!(embedded.content_hash, file.content_hash);
    assert_eq!(embedded.camera, file.camera);
    assert_eq!(embedded.triangles, file.triangles);
    assert_eq!(embedded.materials, file.materials);
    check_scene(&embedded);
}

#[test]
fn small_scenes_facts() {
    let plane = committed("point-light-plane");
    assert!(matches!(plane.lights[..], [scene::Light::Point { .. }]));
    let spot = committed("spot-light");
    match &spot.lights[..] {
        [scene::Light::Spot { direction, .. }] => assert!((direction.length() - 1.0).abs() < 1e-6),
        l => panic!("{l:?}"),
    }
    let glossy = committed("glossy-env");
    let env = glossy.environment.as_ref().unwrap();
    assert_eq!((env.width, env.height), (64, 32));
    assert!(env
        .texels
        .iter()
        .all(|t| t.is_finite() && t.min_element() >= 0.0));
    assert!(glossy
        .materials
        .iter()
        .any(|m| m.ks.max_element() > 0.0 && m.ns >= 1000.0));
}

/// Regenerates scenes/failure/sun-behind/sky.exr: the glossy-env sky's gradient and a low sun
/// toward -Z (0 to 11 degrees up, hidden by the wall), 4 texels across the u = 0 seam,
/// 2000 W/(sr m^2).
/// `cargo test --test all -- --ignored scene_loading::`.
#[test]
#[ignore]
fn regenerate_sun_behind_sky() {
    let (w, h) = (64u32, 32u32);
    let mut image = Image::new(w, h);
    for j in 0..h {
        let y = (std::f32::consts::PI * (j as f32 + 0.5) / h as f32).cos();
        for i in 0..w {
            let v = if y > 0.0 {
                let t = y.powf(0.5);
                Vec3::new(1.0, 1.0, 1.05).lerp(Vec3::new(0.25, 0.45, 1.0), t)
            } else {
                Vec3::new(0.2, 0.18, 0.15)
            };
            image.pixels[(j * w + i) as usize] = v.to_array();
        }
    }
    for (i, j) in [(63, 14), (0, 14), (63, 15), (0, 15)] {
        image.pixels[(j * w + i) as usize] = [2000.0, 1900.0, 1700.0];
    }
    exr::write(&scenes_dir().join("failure/sun-behind/sky.exr"), &image).unwrap();
}

/// Regenerates scenes/glossy-env/sky.exr: a blue sky brightening to the horizon, a dim ground
/// and a small sun (4 texels). `cargo test --test all -- --ignored scene_loading::`.
#[test]
#[ignore]
fn regenerate_glossy_env_sky() {
    let (w, h) = (64u32, 32u32);
    let mut image = Image::new(w, h);
    for j in 0..h {
        let y = (std::f32::consts::PI * (j as f32 + 0.5) / h as f32).cos();
        for i in 0..w {
            let v = if y > 0.0 {
                let t = y.powf(0.5);
                Vec3::new(1.0, 1.0, 1.05).lerp(Vec3::new(0.25, 0.45, 1.0), t)
            } else {
                Vec3::new(0.2, 0.18, 0.15)
            };
            image.pixels[(j * w + i) as usize] = v.to_array();
        }
    }
    for (i, j) in [(40, 9), (41, 9), (40, 10), (41, 10)] {
        image.pixels[(j * w + i) as usize] = [400.0, 380.0, 340.0];
    }
    exr::write(&scenes_dir().join("glossy-env/sky.exr"), &image).unwrap();
}

/// Degeneracy is judged per triangle: a 4 x 4 quad beside a triangle 1e7 across is kept (a
/// threshold relative to the scene's extent would drop it).
#[test]
fn a_small_triangle_beside_a_huge_one_is_kept() {
    let obj = "mtllib m.mtl\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nusemtl grey\nf 1 4 3 2\n\
               v -1e7 -10 -1e7\nv 1e7 -10 -1e7\nv 0 -10 1e7\nf 5 7 6\n";
    let s = scratch("small-beside-huge", &good_toml(), obj, MTL);
    let scene = s.load().unwrap();
    assert_eq!(scene.triangles.len(), 3, "{:?}", scene.warnings);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

/// Coordinates beyond what f32 rays and the BVH handle are refused, naming the file, the line,
/// the vertex and the limit (beyond it, 1e19 and 1e30 panic in obvhs and 1e10 renders
/// black).
#[test]
fn coordinates_beyond_the_limit_are_refused() {
    for value in ["1e9", "-1e30", "1e19", "1e10"] {
        let obj = OBJ.replace("v 1 0 1", &format!("v {value} 0 1"));
        let s = scratch("far-vertex", &good_toml(), &obj, MTL);
        s.error(&[
            "m.obj line 4: vertex position [",
            "over 1e8",
            "scale the scene down",
        ]);
    }
    // At the limit the scene loads (tests/reference.rs renders one there).
    let obj = OBJ.replace("v 1 0 1", "v 1e8 0 1");
    assert!(scratch("limit-vertex", &good_toml(), &obj, MTL)
        .load()
        .is_ok());
}

/// scripts/generate-many-lights.py: `--help` documents it; into a fresh folder it writes a
/// hall of the lights asked for that irad loads (two emissive triangles a light), and with the
/// defaults the shipped files byte for byte (but the sky scene's path to its map); without
/// `--out`, or with `--out` at the shipped scenes but no `--overwrite-shipped`, it refuses and
/// writes nothing. Skipped without python3 (outside CI).
#[test]
fn the_many_lights_generator_writes_halls_irad_loads() {
    use std::process::{Command, Output};
    let python = |args: &[&str]| -> Option<Output> {
        Command::new("python3")
            .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/generate-many-lights.py"))
            .args(args)
            .output()
            .ok()
    };
    let Some(help) = python(&["--help"]) else {
        let ci = std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0");
        assert!(!ci, "python3 is needed under CI");
        eprintln!("note: no python3; skipping");
        return;
    };
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(help.status.success(), "{text}");
    for flag in ["--out", "--lights", "--seed", "--overwrite-shipped"] {
        assert!(text.contains(flag), "{flag} not in\n{text}");
    }
    let files = [
        "many-lights/scene.toml",
        "many-lights/hall.obj",
        "many-lights/ceiling.obj",
        "many-lights/many-lights.mtl",
        "many-lights-sky/scene.toml",
    ];
    let read_all = |dir: &Path| -> Vec<String> {
        files
            .iter()
            .map(|f| std::fs::read_to_string(dir.join(f)).unwrap())
            .collect()
    };
    let shipped = read_all(&scenes_dir());
    let scratch = Scratch::new("many-lights-generator");
    let dir = |name: &str| scratch.0.join(name).to_str().unwrap().to_string();
    let shipped_dir = scenes_dir().to_str().unwrap().to_string();
    for args in [
        &[][..],
        &["--lights", "1000"],
        &["--out", &shipped_dir],
        &["--out", &dir("bad"), "--lights", "0"],
        &["--out", &dir("bad"), "--lights", "1048577"],
    ] {
        let o = python(args).unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("error: "),
            "{args:?}: {err}"
        );
    }
    assert_eq!(
        read_all(&scenes_dir()),
        shipped,
        "a refused run wrote the shipped scenes"
    );
    assert!(!scratch.0.join("bad").exists());
    let emissive = |scene: &Scene| {
        scene
            .triangles
            .iter()
            .filter(|t| scene.materials[t.material as usize].is_emissive())
            .count()
    };
    // A hall of 1000 lights: grown or shrunk to hold them, some slots left empty.
    let o = python(&["--out", &dir("k"), "--lights", "1000", "--seed", "2"]).unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let hall = scene::load(&scratch.0.join("k/many-lights/scene.toml")).unwrap();
    assert_eq!(emissive(&hall), 2000);
    let sky = scene::load(&scratch.0.join("k/many-lights-sky/scene.toml")).unwrap();
    assert!(sky.environment.is_some() && emissive(&sky) < 2000 && emissive(&sky) > 1000);
    // The defaults: the shipped hall.
    let o = python(&["--out", &dir("d")]).unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let fresh = read_all(&scratch.0.join("d"));
    assert_eq!(fresh[..4], shipped[..4]);
    let no_map = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| !l.contains("sky.exr"))
            .map(String::from)
            .collect()
    };
    assert_eq!(no_map(&fresh[4]), no_map(&shipped[4]));
    assert!(scene::load(&scratch.0.join("d/many-lights-sky/scene.toml")).is_ok());
}

/// The generator's largest hall, 2^20 lights (about a minute of python and 140 MB of OBJ), loads
/// with its 2^21 emissive triangles. Too slow for CI: `cargo test --test all --
/// --ignored scene_loading::many_lights`.
#[test]
#[ignore]
fn the_many_lights_generator_writes_a_hall_of_2_20_lights() {
    let scratch = Scratch::new("many-lights-2-20");
    let started = std::time::Instant::now();
    let o = std::process::Command::new("python3")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/generate-many-lights.py"))
        .args(["--lights", "1048576", "--out"])
        .arg(&scratch.0)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let generated = started.elapsed();
    let hall = scene::load(&scratch.0.join("many-lights/scene.toml")).unwrap();
    let emissive = hall
        .triangles
        .iter()
        .filter(|t| hall.materials[t.material as usize].is_emissive())
        .count();
    assert_eq!(emissive, 1 << 21);
    eprintln!(
        "2^20 lights: generated in {:.0} s, loaded in {:.0} s",
        generated.as_secs_f64(),
        (started.elapsed() - generated).as_secs_f64()
    );
}

// ---- animation ----------------------------------------------------------------------------

/// `good_toml()` with a point light's position moving over `[animation]`, the track's fields
/// replaced by `track` when given.
fn animated(track: &str, frames: &str) -> String {
    format!("{CAMERA}{MESH}{POINT}[animation]\n{frames}\n[[animation.track]]\n{track}\n")
}

const MOVING: &str =
    "target = \"light[0].position\"\ntimes = [0.0, 1.0]\nvalues = [[0, 1, 0], [1, 1, 0]]";

#[test]
fn an_animated_scene_shows_each_frame_as_a_still() {
    let s = scratch(
        "animated",
        &animated(MOVING, "frames = 25\nfps = 24"),
        OBJ,
        MTL,
    );
    let scene = s.load().unwrap();
    let animation = scene.animation.as_ref().unwrap();
    assert_eq!((animation.frames, animation.fps), (25, 24.0));
    // Frame 12 at 0.5 s: halfway.
    let still = scene.at_frame(12).unwrap();
    assert!(still.animation.is_none());
    match &still.lights[0] {
        scene::Light::Point { position, .. } => {
            assert!(
                (*position - Vec3::new(0.5, 1.0, 0.0)).length() < 1e-6,
                "{position}"
            )
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(still.triangles, scene.triangles);
}

#[test]
fn bad_tracks_are_refused_naming_the_field_and_value() {
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "target = \"light[3].position\"\ntimes = [0.0]\nvalues = [[0, 1, 0]]",
            "frames = 4",
            &[
                "animation.track[0].target",
                "\"light[3].position\"",
                "1 [[light]] entry",
            ],
        ),
        (
            "target = \"camera.zoom\"\ntimes = [0.0]\nvalues = [1.0]",
            "frames = 4",
            &["animation.track[0].target", "camera.zoom", "camera.fov_y"],
        ),
        (
            "target = \"light[0].direction\"\ntimes = [0.0]\nvalues = [[0, -1, 0]]",
            "frames = 4",
            &["animation.track[0].target", "only spot lights"],
        ),
        (
            "target = \"light[0].position\"\ntimes = [1.0, 0.5]\nvalues = [[0, 1, 0], [1, 1, 0]]",
            "frames = 48",
            &["animation.track[0].times[1] = 0.5", "in order of time"],
        ),
        (
            "target = \"light[0].position\"\ntimes = [0.0, 3.0]\nvalues = [[0, 1, 0], [1, 1, 0]]",
            "frames = 24\nfps = 24",
            &[
                "animation.track[0].times[1] = 3",
                "past the animation's end",
                "0.9583",
            ],
        ),
        (
            "target = \"light[0].position\"\ntimes = [0.0]\nvalues = [[0, 1]]",
            "frames = 4",
            &["animation.track[0].values[0] = [0.0, 1.0]", "[x, y, z]"],
        ),
        (
            "target = \"camera.fov_y\"\ntimes = [0.0]\nvalues = [[40, 40, 40]]",
            "frames = 4",
            &["animation.track[0].values[0]", "must be a number"],
        ),
        (
            "target = \"light[0].position\"\ntimes = [0.0, 0.1]\nvalues = [[0, 1, 0]]",
            "frames = 4",
            &["animation.track[0].values", "one value per time"],
        ),
        (
            "target = \"material.grey.emission\"\ntimes = [0.0]\nvalues = [1.0]",
            "frames = 4",
            &["material.grey.emission", "emits nothing"],
        ),
        (
            "target = \"camera.fov_y\"\ntimes = [0.0, 0.5]\nvalues = [40.0, 200.0]",
            "frames = 24",
            &["camera.fov_y at animation frame", "(0, 180)"],
        ),
        (MOVING, "frames = 0", &["animation.frames = 0", "1..="]),
        (MOVING, "frames = 4\nfps = -1", &["animation.fps = -1"]),
        (
            "target = \"light[0].intensity\"\ntimes = [0.0, 0.5]\nvalues = [[1, 1, 1], [-1, 1, 1]]",
            "frames = 24",
            &["light[0].intensity at animation frame", ">= 0"],
        ),
    ];
    for (k, (track, frames, parts)) in cases.iter().enumerate() {
        let s = scratch(
            &format!("bad-track-{k}"),
            &animated(track, frames),
            OBJ,
            MTL,
        );
        s.error(parts);
    }
    // The only light switched off from frame 12: a frame without light, refused by name.
    let off =
        "target = \"light[0].intensity\"\ntimes = [0.0, 0.5]\nvalues = [[1, 1, 1], [0, 0, 0]]";
    scratch("all-off", &animated(off, "frames = 24"), OBJ, MTL)
        .error(&["[animation] = frame 12", "nothing emits light"]);
    // An emission scale below zero: at its key, and where a smooth track overshoots.
    let lamp = format!("{MTL}newmtl lamp\nKe 1 1 1\n");
    let negative = "target = \"material.lamp.emission\"\ntimes = [0.0]\nvalues = [-1.0]";
    scratch(
        "emission-negative",
        &animated(negative, "frames = 4"),
        OBJ,
        &lamp,
    )
    .error(&[
        "animation.track[0].values[0] = -1",
        "emission scale must be >= 0",
    ]);
    let overshoot = "target = \"material.lamp.emission\"\ninterpolation = \"smooth\"\n\
                     times = [0.0, 0.25, 0.5, 1.0]\nvalues = [1.0, 0.0, 0.0, 1.0]";
    scratch(
        "emission-overshoot",
        &animated(overshoot, "frames = 25"),
        OBJ,
        &lamp,
    )
    .error(&[
        "animation.track[0] (material.lamp.emission) at animation frame",
        "overshoots",
    ]);
    // Two tracks on one target, and an unknown key in a track.
    let twice = format!(
        "{}[[animation.track]]\n{MOVING}\n",
        animated(MOVING, "frames = 30")
    );
    scratch("track-twice", &twice, OBJ, MTL)
        .error(&["animation.track[1].target", "moves it already"]);
    let unknown = animated(&format!("{MOVING}\nease = 2"), "frames = 30");
    scratch("track-key", &unknown, OBJ, MTL).error(&["ease"]);
}

/// A gzip-compressed OBJ reads as the plain one, and `[mesh.groups]` gives each `g` group its
/// material of `mtl`; a group left out is an error naming it, its line and the table.
#[test]
fn gzip_meshes_and_group_materials() {
    use std::io::Write as _;
    let obj = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nv 2 0 0\nv 2 0 -1\ng left\nf 1 2 3\ng right\nf 2 4 5\n";
    let mtl = "newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0.1 0.1 0.8\n";
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(obj.as_bytes()).unwrap();
    let gz = gz.finish().unwrap();
    let toml = |groups: &str| {
        format!(
            "{CAMERA}[[mesh]]\nobj = \"g.obj.gz\"\nmtl = \"g.mtl\"\n[mesh.groups]\n{groups}\n{POINT}"
        )
    };
    let s = scratch(
        "groups",
        &toml("left = \"red\"\nright = \"blue\""),
        OBJ,
        MTL,
    );
    std::fs::write(s.path("g.obj.gz"), &gz).unwrap();
    s.write("g.mtl", mtl);
    let scene = s.load().unwrap();
    let names: Vec<&str> = scene
        .triangles
        .iter()
        .map(|t| scene.materials[t.material as usize].name.as_str())
        .collect();
    assert_eq!(names, ["red", "blue"]);
    assert!(scene.load_ms > 0.0);
    // "*" names the rest.
    s.write("scene.toml", &toml("left = \"red\"\n\"*\" = \"blue\""));
    assert_eq!(s.load().unwrap().triangles.len(), 2);
    s.write("scene.toml", &toml("left = \"red\""));
    s.error(&["g.obj.gz line 8", "group `right`", "mesh[0].groups"]);
    s.write(
        "scene.toml",
        &format!("{CAMERA}[[mesh]]\nobj = \"g.obj.gz\"\nmtl = \"g.mtl\"\n{POINT}"),
    );
    s.error(&["mesh[0]", "`mtl` and `groups` go together"]);
    std::fs::write(s.path("g.obj.gz"), b"not gzip").unwrap();
    s.write("scene.toml", &toml("left = \"red\"\nright = \"blue\""));
    s.error(&["g.obj.gz", "not a readable gzip file"]);
}
