//! Scenes (docs/DESIGN.md "Scene files"): the CPU description every method starts from. A TOML
//! file names a camera, OBJ/MTL meshes, analytic lights, an optional environment map,
//! light-field luminaires and, for the stability suite (scenes/failure/), a `[failure]` note;
//! `load` turns it into flat triangle, material and light lists, checked and in irad's
//! conventions.
//! `gpu` uploads a `Scene` as a `GpuScene`.
//!
//! Loading conventions: paths are relative to the scene file (MTL files to their OBJ); an MTL
//! key a material does not set is 0; faces with no material get a grey default (Kd 0.5) and a
//! warning; OBJ `vn` normals are normalized, and corners with no, zero or NaN `vn` get the
//! geometric normal; triangles of area <= `DEGENERATE_AREA` x their longest edge squared are
//! dropped with a warning; Kd + Ks may exceed 1 by at most 1e-5 per channel (decimal rounding).

use glam::{Vec2, Vec3};
use std::path::PathBuf;

/// A pinhole camera. Pixel (x, y) with subpixel offset (sx, sy) in [0, 1)^2 looks along
/// `normalize(forward + a * right + b * true_up)` with
/// `forward = normalize(look_at - position)`, `right = normalize(cross(forward, up))`,
/// `true_up = cross(right, forward)`, `t = tan(fov_y / 2)`,
/// `a = (2 (x + sx) / width - 1) * t * width / height`, `b = (1 - 2 (y + sy) / height) * t`.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_y: f32,
    pub width: u32,
    pub height: u32,
}

/// Lambert plus one normalized Phong lobe, plus diffuse emission (docs/DESIGN.md "Conventions").
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub kd: Vec3,
    pub ks: Vec3,
    /// Phong exponent (MTL `Ns`), >= 0.
    pub ns: f32,
    /// Emitted radiance (MTL `Ke`), one-sided, on the side of the geometric normal.
    pub ke: Vec3,
    /// An albedo texture (`Scene::textures` index; MTL `map_Kd`) that multiplies `kd` at
    /// each point (docs/DESIGN.md "Textures").
    pub albedo_texture: Option<u32>,
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.ke.max_element() > 0.0
    }
}

/// One triangle; counter-clockwise `positions` give the geometric normal
/// `cross(p1 - p0, p2 - p0)`. `normals` are unit shading normals per corner (the geometric
/// normal on all three when the OBJ has none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub positions: [Vec3; 3],
    pub normals: [Vec3; 3],
    pub material: u32,
    /// Texture coordinates per corner, OBJ's convention: (0, 0) the image's bottom-left
    /// corner, v up. Zero where the mesh has none.
    pub uvs: [Vec2; 3],
}

impl Triangle {
    pub fn area(&self) -> f64 {
        0.5 * obj::double_area(self.positions)
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity `intensity` (W/sr per channel) in every direction.
    Point { position: Vec3, intensity: Vec3 },
    /// `intensity * smoothstep(cos(falloff_angle), cos(cone_angle), cos(theta))`, theta from
    /// `direction` (unit). Angles in degrees, 0 < cone_angle <= falloff_angle <= 180.
    Spot {
        position: Vec3,
        intensity: Vec3,
        direction: Vec3,
        cone_angle: f32,
        falloff_angle: f32,
    },
}

/// An equirectangular environment map (docs/DESIGN.md "Conventions"), radiance already
/// multiplied by the scene's `scale`. Texel (i, j) is `texels[j * width + i]`, row 0 at the
/// top (+Y).
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
    pub source: PathBuf,
}

/// How a texture repeats outside [0, 1] on one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    Repeat,
    Mirror,
    /// The edge texel's value.
    Clamp,
}

/// An albedo texture: linear RGB (sRGB-decoded from 8-bit files), each channel already rounded
/// to the half float the GPU stores (so a CPU mirror reads the values the kernels read).
/// Texel (i, j) is `texels[j * width + i]`, row 0 at the top of the image; sampled bilinearly
/// with texel centres at half-integers (docs/DESIGN.md "Textures").
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
    /// Across (u) and down (v).
    pub wrap: [Wrap; 2],
    /// The image file, for messages and reports.
    pub source: PathBuf,
}

/// A stability-suite scene's `[failure]` table: the methods expected to fail on it (names as
/// `irad render --method` spells them; the scene loader does not check them), why, and the
/// paper figure the scene reproduces. Every field is non-empty.
#[derive(Clone, Debug, PartialEq)]
pub struct FailureNote {
    pub methods: Vec<String>,
    pub why: String,
    pub source: String,
}

#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file, or None for a scene built in code or the embedded default.
    pub source: Option<PathBuf>,
    /// A short name for reports ("cornell-box").
    pub name: String,
    /// FNV-1a 64 of the scene file and every file it references, in a fixed order: the key
    /// under which references are cached.
    pub content_hash: u64,
    pub camera: Camera,
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// The map (of frame 0, for a sequence).
    pub environment: Option<Environment>,
    /// A dynamic map's frames (an `exr` glob or a procedural sky), all of one size; frame f
    /// of a render shows map f mod len. Empty for a still map.
    pub environment_sequence: Vec<Environment>,
    /// Albedo textures, which materials name by index.
    pub textures: Vec<Texture>,
    /// Light-field luminaires placed in the scene.
    pub luminaires: Vec<luminaire::PlacedLuminaire>,
    /// The scene's `[failure]` table, for scenes under scenes/failure/; None elsewhere.
    pub failure: Option<FailureNote>,
    /// Things the loader fixed and reports (for example "dropped 2 degenerate triangles").
    pub warnings: Vec<String>,
    /// Keyframed tracks over animation frames (animation.rs): None for a still scene. A
    /// render shows one frame of it (`Scene::at_frame`), a sequence render every frame.
    pub animation: Option<animation::Animation>,
    /// Wall milliseconds `load` took to read, decompress, parse and check the scene's files
    /// (0 for a scene built in code).
    pub load_ms: f64,
}

pub mod animation;
mod camera;
mod coincident;
mod environment;
mod error;
mod failure;
mod file;
pub mod gltf;
pub mod gpu;
pub mod hash;
mod lights;
mod load;
pub mod luminaire;
pub mod mitsuba;
mod mtl;
mod obj;
mod power;
pub mod sky;
pub mod texture;
pub mod texture_upload;
pub(crate) mod toml_arrays;

pub use camera::MAX_RESOLUTION;
pub use error::SceneError;
pub use load::{default_scene, load, load_str, load_with_camera, DEGENERATE_AREA};
pub use power::{MAX_POWER, MAX_RADIANCE};
