//! GpuScene: a `Scene` uploaded for the kernels (glsl/include/scene.glsl and bvh.glsl): the
//! BVH, shading data per triangle in BVH order, materials, analytic lights, the light
//! selection table (every light by power), the emissive triangles and the environment map
//! with its texel CDF, and the albedo textures (texture_upload.rs). Buffers are sized from the scene; an absent part gets a one-element
//! placeholder because every binding of a kernel must be bound.

use std::f64::consts::PI;

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

use crate::bvh::{Bvh, GpuBvh};
use crate::gpu::{bind, Binding, Buffer, Commands, Context, GpuBuffer, GpuError, GpuResult};
use crate::sampling::distribution::Distribution1D;
use crate::sampling::environment::{luminance, sampling_weights, texel_solid_angle};
use crate::sampling::light_bvh::{LightBounds, LightBvh, LightNode};

use super::texture_upload::{self, TriangleUv};
use super::{Environment, Light, Scene};

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadingTriangle {
    pub n0: Vec4,
    pub n1: Vec4,
    pub n2: Vec4,
    pub geometric_normal: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMaterial {
    pub kd: Vec4,
    pub ks: Vec4,
    pub ke: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightEntry {
    pub kind: u32,
    pub index: u32,
    /// Realised selection probability (src/sampling/distribution.rs).
    pub probability: f32,
    /// Exclusive upper bound of the entry's range of 31-bit random integers.
    pub upper: u32,
}

pub const LIGHT_TRIANGLE: u32 = 0;
pub const LIGHT_POINT: u32 = 1;
pub const LIGHT_SPOT: u32 = 2;
pub const LIGHT_ENVIRONMENT: u32 = 3;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    pub position: Vec4,
    pub intensity: Vec4,
    pub direction: Vec4,
    pub cone: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct EmitterTriangle {
    pub p0: Vec4,
    pub e1: Vec4,
    pub e2: Vec4,
    pub normal: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct SceneConstants {
    pub camera_position: Vec4,
    pub camera_forward: Vec4,
    pub camera_right: Vec4,
    pub camera_up: Vec4,
    pub size: [u32; 4],
    pub env_size: [u32; 4],
    pub env: Vec4,
    pub bounds: Vec4,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(ShadingTriangle as "ShadingTriangle" { n0, n1, n2, geometric_normal }),
        gpu_layout!(GpuMaterial as "Material" { kd, ks, ke }),
        gpu_layout!(LightEntry as "LightEntry" { kind, index, probability, upper }),
        gpu_layout!(GpuLight as "Light" { position, intensity, direction, cone }),
        gpu_layout!(EmitterTriangle as "EmitterTriangle" { p0, e1, e2, normal }),
        gpu_layout!(SceneConstants as "SceneConstants" {
            camera_position,
            camera_forward,
            camera_right,
            camera_up,
            size,
            env_size,
            env,
            bounds,
        }),
    ]
};

/// What the light table holds, for reports and tests.
#[derive(Clone, Debug)]
pub struct LightTable {
    pub entries: Vec<LightEntry>,
    /// Probability of choosing the environment (0 without one).
    pub environment_probability: f64,
}

/// What a scene holds, for kernels specialized to it (scene.glsl's specialization constants
/// SCENE_HAS_*, in this order): code for what a scene lacks is compiled out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SceneFeatures {
    /// An environment map (still, a sequence or the procedural sky).
    pub environment: bool,
    /// Point or spot lights.
    pub delta_lights: bool,
    /// A material with a Phong lobe (Ks > 0).
    pub glossy: bool,
    /// A material with an albedo texture.
    pub textures: bool,
}

impl SceneFeatures {
    /// Every feature: what a kernel built without specialization handles.
    pub const ALL: SceneFeatures = SceneFeatures {
        environment: true,
        delta_lights: true,
        glossy: true,
        textures: true,
    };

    /// How many there are: SceneKernel's table holds 2^COUNT variants per own constant.
    pub const COUNT: usize = 4;

    /// The values of specialization constants 0, 1, 2, 3.
    pub fn constants(self) -> [u32; Self::COUNT] {
        [
            self.environment,
            self.delta_lights,
            self.glossy,
            self.textures,
        ]
        .map(u32::from)
    }

    /// A dense index (0..16), for a kernel's table of specialized variants.
    pub fn index(self) -> usize {
        usize::from(self.environment)
            | usize::from(self.delta_lights) << 1
            | usize::from(self.glossy) << 2
            | usize::from(self.textures) << 3
    }
}

/// CPU milliseconds of an upload's builds.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildTimes {
    /// The triangle BVH (obvhs).
    pub triangle_bvh: f64,
    /// The light BVH over the light table.
    pub light_bvh: f64,
    /// The whole upload's wall time: the builds, the shading data and tables, and the
    /// buffers' transfer to the device.
    pub upload: f64,
}

pub struct GpuScene {
    pub bvh: GpuBvh,
    pub shading_triangles: Buffer<ShadingTriangle>,
    pub materials: Buffer<GpuMaterial>,
    pub lights: Buffer<GpuLight>,
    pub light_entries: Buffer<LightEntry>,
    pub emitter_triangles: Buffer<EmitterTriangle>,
    /// The light BVH over every light but the environment (glsl/include/light_bvh.glsl), and
    /// each light-table entry's bit trail in it (two uints: depths 0-31, 32-63).
    pub light_nodes: Buffer<LightNode>,
    pub light_trails: Buffer<[u32; 2]>,
    pub light_bvh: LightBvh,
    pub env_texels: Buffer<Vec4>,
    pub env_cdf: Buffer<u32>,
    /// texture.glsl's tables: each triangle's texture coordinates (BVH order), each
    /// material's texture and the texels; one-element placeholders without textures.
    pub triangle_uvs: Buffer<TriangleUv>,
    pub material_textures: Buffer<[u32; 4]>,
    pub texels: Buffer<[u32; 2]>,
    /// A dynamic map's frames, copied into env_texels and env_cdf per frame.
    env_frames: Option<EnvironmentFrames>,
    pub constants: Buffer<SceneConstants>,
    pub light_table: LightTable,
    /// Each light-table entry's identity across an animation's frames, whose tables differ
    /// where a light switches on or off: `light_key` of its kind and its index in the scene
    /// (the triangle's in `Scene::triangles`, the light's in `Scene::lights`).
    pub light_keys: Vec<u64>,
    /// SceneConstants' camera, as `camera_constants` gives it.
    pub camera: [Vec4; 4],
    /// How long the upload's CPU builds took.
    pub build_ms: BuildTimes,
    /// The environment map's texels across and down, when the scene has one.
    pub environment_size: Option<[u32; 2]>,
    pub width: u32,
    pub height: u32,
    pub triangle_count: usize,
    pub features: SceneFeatures,
}

/// The probability with which bsdf.glsl samples the Phong lobe of `m` (Material.kd.w):
/// Y(Ks) / (Y(Kd) + Y(Ks)).
pub fn phong_probability(m: &super::Material) -> f32 {
    let (yd, ys) = (luminance(m.kd), luminance(m.ks));
    (if ys > 0.0 { ys / (yd + ys) } else { 0.0 }) as f32
}

/// Every frame's environment tables, back to back.
struct EnvironmentFrames {
    count: u32,
    texels: Buffer<Vec4>,
    cdf: Buffer<u32>,
}

/// A map's texels with the solid-angle pdf of env_sample in .w, its CDF (W x H entries) and
/// its sampling weights' total (luminance times solid angle; 0 for a black map, whose texels
/// then hold the pdf of sampling by solid angle alone, so that a frame of a sequence can be
/// black without a zero pdf anywhere).
fn environment_tables(env: &Environment) -> (Vec<Vec4>, Vec<u32>, f64) {
    let mut texels: Vec<Vec4> = env.texels.iter().map(|t| t.extend(0.0)).collect();
    let weights = sampling_weights(env);
    let (d, total) = match Distribution1D::new(&weights) {
        Some(d) => {
            let total = d.total;
            (d, total)
        }
        None => {
            let by_solid_angle: Vec<f64> = (0..texels.len() as u32)
                .map(|i| texel_solid_angle(i / env.width, env.width, env.height))
                .collect();
            (
                Distribution1D::new(&by_solid_angle).expect("solid angles are positive"),
                0.0,
            )
        }
    };
    for (i, texel) in texels.iter_mut().enumerate() {
        let row = i as u32 / env.width;
        texel.w = (d.probabilities[i] / texel_solid_angle(row, env.width, env.height)) as f32;
    }
    (texels, d.upper, total)
}

/// Centre and radius of a sphere around the triangles and point lights.
pub(crate) fn bounds(scene: &Scene) -> (Vec3, f32) {
    let mut lo = Vec3::splat(f32::MAX);
    let mut hi = Vec3::splat(f32::MIN);
    let points = scene
        .triangles
        .iter()
        .flat_map(|t| t.positions)
        .chain(scene.lights.iter().map(|l| match l {
            Light::Point { position, .. } | Light::Spot { position, .. } => *position,
        }));
    for p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if lo.x > hi.x {
        return (Vec3::ZERO, 1.0);
    }
    let centre = 0.5 * (lo + hi);
    (centre, (0.5 * (hi - lo).length()).max(1e-6))
}

fn spot_cosines(cone_angle: f32, falloff_angle: f32) -> (f32, f32) {
    (
        cone_angle.to_radians().cos(),
        falloff_angle.to_radians().cos(),
    )
}

/// Power of each light for light selection (luminance, watts): pbrt-v4's Light::Phi.
/// Emissive triangle: pi A Y(Le); point: 4 pi Y(I); spot: 2 pi Y(I) (1 - (cos_start +
/// cos_end) / 2); environment: pi r^2 times the integral of Y(L) over the sphere, r the scene
/// radius (the power crossing the scene's cross-section).
fn light_power(light: &Light) -> f64 {
    match light {
        Light::Point { intensity, .. } => 4.0 * PI * luminance(*intensity),
        Light::Spot {
            intensity,
            cone_angle,
            falloff_angle,
            ..
        } => {
            let (cos_start, cos_end) = spot_cosines(*cone_angle, *falloff_angle);
            2.0 * PI * luminance(*intensity) * (1.0 - 0.5 * (cos_start as f64 + cos_end as f64))
        }
    }
}

/// A light's identity across an animation's frames: its kind (LIGHT_*) and its index in the
/// scene (`GpuScene::light_keys`).
pub fn light_key(kind: u32, index: u32) -> u64 {
    (u64::from(kind) << 32) | u64::from(index)
}

/// A light's entry before selection: (kind, index, power), kind one of LIGHT_*.
type LightPower = (u32, u32, f64);

/// Shading data per triangle and the emissive triangles, in the BVH's triangle order.
struct TriangleData {
    shading: Vec<ShadingTriangle>,
    emitters: Vec<EmitterTriangle>,
    /// Each emitter's index in `shading`.
    emitter_gpu_index: Vec<usize>,
    /// Each emitter's power: (LIGHT_TRIANGLE, its index in `emitters`, power).
    powers: Vec<LightPower>,
}

/// The environment as uploaded: the live texels and CDF (a one-element placeholder without
/// a map, frame 0's for a sequence), a sequence's frames, SceneConstants.env_size and the
/// power for light selection (none for a black map).
struct EnvironmentData {
    texels: Vec<Vec4>,
    cdf: Vec<u32>,
    frames: Option<EnvironmentFrames>,
    size: [u32; 4],
    power: Option<f64>,
}

/// The light table over `powers`, in their order (those not positive and finite dropped):
/// each entry's realised probability and range of random integers.
fn selection_table(mut powers: Vec<LightPower>) -> LightTable {
    powers.retain(|p| p.2 > 0.0 && p.2.is_finite());
    let mut entries = Vec::new();
    let mut environment_probability = 0.0;
    if let Some(d) = Distribution1D::new(&powers.iter().map(|p| p.2).collect::<Vec<_>>()) {
        for (i, &(kind, index, _)) in powers.iter().enumerate() {
            let probability = d.probabilities[i];
            entries.push(LightEntry {
                kind,
                index,
                probability: probability as f32,
                upper: d.upper[i],
            });
            if kind == LIGHT_ENVIRONMENT {
                environment_probability = probability;
            }
        }
    }
    LightTable {
        entries,
        environment_probability,
    }
}

/// Shading data and emitters, in the BVH's triangle order. ShadingTriangle.n1.w (the
/// emitter's selection probability) is left 0: `with_emitter_probabilities` sets it.
fn shading_triangles(scene: &Scene, bvh: &Bvh) -> TriangleData {
    let mut shading = Vec::with_capacity(scene.triangles.len());
    let mut emitters = Vec::new();
    let mut emitter_gpu_index = Vec::new();
    let mut powers = Vec::new();
    for (gpu_index, &original) in bvh.triangle_order.iter().enumerate() {
        let t = &scene.triangles[original as usize];
        let [p0, p1, p2] = t.positions;
        let cross = (p1 - p0).cross(p2 - p0);
        let area = 0.5 * cross.length();
        let ng = cross.normalize_or_zero();
        let material = t.material;
        shading.push(ShadingTriangle {
            n0: t.normals[0].extend(f32::from_bits(material)),
            n1: t.normals[1].extend(0.0),
            n2: t.normals[2].extend(area),
            geometric_normal: ng.extend(0.0),
        });
        let m = &scene.materials[material as usize];
        let power = PI * area as f64 * luminance(m.ke);
        if m.is_emissive() && power > 0.0 {
            powers.push((LIGHT_TRIANGLE, emitters.len() as u32, power));
            emitter_gpu_index.push(gpu_index);
            emitters.push(EmitterTriangle {
                p0: p0.extend(0.0),
                e1: (p1 - p0).extend(0.0),
                e2: (p2 - p0).extend(area),
                normal: ng.extend(f32::from_bits(material)),
            });
        }
    }
    TriangleData {
        shading,
        emitters,
        emitter_gpu_index,
        powers,
    }
}

/// `shading` with each emissive triangle's selection probability (the light table's) in n1.w
/// and its entry in the table in geometric_normal.w's bits (the light BVH's pmf needs it;
/// u32::MAX for a triangle the table does not hold).
fn with_emitter_probabilities(
    mut shading: Vec<ShadingTriangle>,
    emitter_gpu_index: &[usize],
    table: &LightTable,
) -> Vec<ShadingTriangle> {
    for t in &mut shading {
        t.geometric_normal.w = f32::from_bits(u32::MAX);
    }
    for (i, entry) in table.entries.iter().enumerate() {
        if entry.kind == LIGHT_TRIANGLE {
            let t = &mut shading[emitter_gpu_index[entry.index as usize]];
            t.n1.w = entry.probability;
            t.geometric_normal.w = f32::from_bits(i as u32);
        }
    }
    shading
}

/// The light BVH over the table's entries but the environment (pbrt-v4's bounds: an emissive
/// triangle's power and normal cone; a point light's 4 pi Y(I) in every direction; a spot's
/// 4 pi Y(I) within its cone and falloff).
fn light_bvh(scene: &Scene, table: &LightTable, emitters: &[EmitterTriangle]) -> LightBvh {
    let mut lights = Vec::new();
    for (i, entry) in table.entries.iter().enumerate() {
        let bounds = match entry.kind {
            LIGHT_TRIANGLE => {
                let t = &emitters[entry.index as usize];
                let p0 = t.p0.truncate();
                let positions = [p0, p0 + t.e1.truncate(), p0 + t.e2.truncate()];
                let ke = scene.materials[t.normal.w.to_bits() as usize].ke;
                let power = PI * t.e2.w as f64 * luminance(ke);
                LightBounds::triangle(positions, t.normal.truncate(), power)
            }
            LIGHT_POINT | LIGHT_SPOT => match &scene.lights[entry.index as usize] {
                Light::Point {
                    position,
                    intensity,
                } => LightBounds::point(*position, 4.0 * PI * luminance(*intensity)),
                Light::Spot {
                    position,
                    intensity,
                    direction,
                    cone_angle,
                    falloff_angle,
                } => LightBounds::spot(
                    *position,
                    *direction,
                    *cone_angle,
                    *falloff_angle,
                    4.0 * PI * luminance(*intensity),
                ),
            },
            _ => continue,
        };
        lights.push((i as u32, bounds));
    }
    LightBvh::build(&lights, table.entries.len())
}

/// The point and spot lights, and their powers, in the scene's order.
pub(crate) fn analytic_lights(scene: &Scene) -> (Vec<GpuLight>, Vec<LightPower>) {
    let mut lights = Vec::new();
    let mut powers = Vec::new();
    for (i, light) in scene.lights.iter().enumerate() {
        let power = light_power(light);
        let gpu = match light {
            Light::Point {
                position,
                intensity,
            } => {
                powers.push((LIGHT_POINT, i as u32, power));
                GpuLight {
                    position: position.extend(LIGHT_POINT as f32),
                    intensity: intensity.extend(0.0),
                    direction: Vec4::ZERO,
                    cone: Vec4::ZERO,
                }
            }
            Light::Spot {
                position,
                intensity,
                direction,
                cone_angle,
                falloff_angle,
            } => {
                powers.push((LIGHT_SPOT, i as u32, power));
                let (cos_cone, cos_falloff) = spot_cosines(*cone_angle, *falloff_angle);
                GpuLight {
                    position: position.extend(LIGHT_SPOT as f32),
                    intensity: intensity.extend(0.0),
                    direction: direction.normalize().extend(cos_falloff),
                    cone: Vec4::new(cos_cone, 0.0, 0.0, 0.0),
                }
            }
        };
        lights.push(gpu);
    }
    (lights, powers)
}

/// The environment: texels, their CDF, and its power for light selection (pi r^2 times the
/// sampling weights' total, r the scene radius). Texel .w is the solid-angle pdf of
/// env_sample there: realised probability / solid angle. Uploads a sequence's frames.
fn environment_buffers(ctx: &Context, scene: &Scene, radius: f32) -> GpuResult<EnvironmentData> {
    let mut data = EnvironmentData {
        texels: vec![Vec4::ZERO],
        cdf: vec![1u32 << 31],
        frames: None,
        size: [0u32; 4],
        power: None,
    };
    let Some(env) = &scene.environment else {
        return Ok(data);
    };
    data.size = [env.width, env.height, 1, 0];
    if scene.environment_sequence.is_empty() {
        let (mut texels, cdf, total) = environment_tables(env);
        if total == 0.0 {
            // A black still map is no light: nothing samples it.
            texels.iter_mut().for_each(|t| t.w = 0.0);
        }
        data.texels = texels;
        if total > 0.0 {
            data.cdf = cdf;
            data.power = Some(PI * (radius as f64).powi(2) * total);
        }
    } else {
        // A sequence: every frame's tables, one after another; frame 0's are live
        // until record_environment_frame copies another's over them. Light selection
        // weighs the map by its mean power over the frames.
        let (mut texels, mut cdfs, mut power) = (vec![], vec![], 0.0);
        for map in &scene.environment_sequence {
            let (t, c, total) = environment_tables(map);
            texels.extend(t);
            cdfs.extend(c);
            power += total / scene.environment_sequence.len() as f64;
        }
        let texel_count = (env.width * env.height) as usize;
        data.texels = texels[..texel_count].to_vec();
        data.cdf = cdfs[..texel_count].to_vec();
        if power > 0.0 {
            data.power = Some(PI * (radius as f64).powi(2) * power);
        }
        data.frames = Some(EnvironmentFrames {
            count: scene.environment_sequence.len() as u32,
            texels: Buffer::from_slice(ctx, "environment frames' texels", &texels)?,
            cdf: Buffer::from_slice(ctx, "environment frames' CDFs", &cdfs)?,
        });
    }
    Ok(data)
}

/// Each material as bsdf.glsl reads it: Kd with the Phong lobe's probability, Ks with Ns,
/// Ke with 1 when emissive.
pub fn gpu_materials(scene: &Scene) -> Vec<GpuMaterial> {
    scene
        .materials
        .iter()
        .map(|m| GpuMaterial {
            kd: m.kd.extend(phong_probability(m)),
            ks: m.ks.extend(m.ns),
            ke: m.ke.extend(if m.is_emissive() { 1.0 } else { 0.0 }),
        })
        .collect()
}

/// SceneConstants' camera: position (w: tan(fov_y / 2)), forward (w: width / height), right, up.
pub fn camera_constants(cam: &super::Camera) -> [Vec4; 4] {
    let (forward, right, up) = cam.basis();
    [
        cam.position.extend((cam.fov_y.to_radians() * 0.5).tan()),
        forward.extend(cam.width as f32 / cam.height as f32),
        right.extend(0.0),
        up.extend(0.0),
    ]
}

/// SceneConstants: the camera, the frame size, the light table's and the triangles' counts,
/// the environment's size and selection probability, and the scene's bounding sphere.
fn scene_constants(
    scene: &Scene,
    table: &LightTable,
    triangle_count: usize,
    env_size: [u32; 4],
    (centre, radius): (Vec3, f32),
) -> SceneConstants {
    let cam = &scene.camera;
    let [camera_position, camera_forward, camera_right, camera_up] = camera_constants(cam);
    SceneConstants {
        camera_position,
        camera_forward,
        camera_right,
        camera_up,
        size: [
            cam.width,
            cam.height,
            table.entries.len() as u32,
            triangle_count as u32,
        ],
        env_size,
        env: Vec4::new(table.environment_probability as f32, 0.0, 0.0, 0.0),
        bounds: centre.extend(radius),
    }
}

impl GpuScene {
    /// Builds the BVH and uploads the scene; DoesNotFit when the image or the environment
    /// maps would exceed the device's maxStorageBufferRange (methods/device_fit.rs).
    pub fn upload(ctx: &Context, scene: &Scene) -> GpuResult<GpuScene> {
        crate::methods::device_fit::check_scene(scene, ctx.info().max_storage_buffer_range)
            .map_err(GpuError::DoesNotFit)?;
        let upload_start = std::time::Instant::now();
        let positions: Vec<[Vec3; 3]> = scene.triangles.iter().map(|t| t.positions).collect();
        let start = std::time::Instant::now();
        let bvh = Bvh::build(&positions);
        let triangle_bvh_ms = start.elapsed().as_secs_f64() * 1e3;
        let (centre, radius) = bounds(scene);

        let triangles = shading_triangles(scene, &bvh);
        let (lights, light_powers) = analytic_lights(scene);
        let env = environment_buffers(ctx, scene, radius)?;
        // Selection order: emissive triangles, point and spot lights, the environment.
        let powers = triangles
            .powers
            .into_iter()
            .chain(light_powers)
            .chain(env.power.map(|power| (LIGHT_ENVIRONMENT, 0, power)))
            .collect();
        let light_table = selection_table(powers);
        let light_keys = light_table
            .entries
            .iter()
            .map(|e| match e.kind {
                LIGHT_TRIANGLE => {
                    let gpu_index = triangles.emitter_gpu_index[e.index as usize];
                    light_key(e.kind, bvh.triangle_order[gpu_index])
                }
                _ => light_key(e.kind, e.index),
            })
            .collect();
        let shading = with_emitter_probabilities(
            triangles.shading,
            &triangles.emitter_gpu_index,
            &light_table,
        );
        let start = std::time::Instant::now();
        let light_bvh = light_bvh(scene, &light_table, &triangles.emitters);
        let light_bvh_ms = start.elapsed().as_secs_f64() * 1e3;
        let trails: Vec<[u32; 2]> = light_bvh
            .trails
            .iter()
            .map(|t| [*t as u32, (*t >> 32) as u32])
            .collect();
        let materials = gpu_materials(scene);
        // Every material's header, textured or not: a kernel built without specialization
        // (SCENE_HAS_TEXTURES true) reads it for any material.
        let textured = texture_upload::has_textures(scene);
        let (material_textures, texels) = texture_upload::texture_tables(scene);
        let triangle_uvs = if textured {
            texture_upload::triangle_uvs(scene, &bvh.triangle_order)
        } else {
            vec![TriangleUv::zeroed()]
        };
        let constants = scene_constants(
            scene,
            &light_table,
            shading.len(),
            env.size,
            (centre, radius),
        );

        let cam = &scene.camera;
        let mut gpu = GpuScene {
            bvh: GpuBvh::upload(ctx, &bvh)?,
            shading_triangles: Buffer::from_slice(ctx, "ShadingTriangles", &shading)?,
            materials: Buffer::from_slice(ctx, "Materials", &materials)?,
            lights: Buffer::from_slice(ctx, "Lights", &or_placeholder(lights, GpuLight::zeroed()))?,
            light_entries: Buffer::from_slice(
                ctx,
                "LightEntries",
                &or_placeholder(light_table.entries.clone(), LightEntry::zeroed()),
            )?,
            emitter_triangles: Buffer::from_slice(
                ctx,
                "EmitterTriangles",
                &or_placeholder(triangles.emitters, EmitterTriangle::zeroed()),
            )?,
            light_nodes: Buffer::from_slice(
                ctx,
                "LightBvhNodes",
                &or_placeholder(light_bvh.nodes.clone(), LightNode::EMPTY),
            )?,
            light_trails: Buffer::from_slice(ctx, "LightTrails", &or_placeholder(trails, [0; 2]))?,
            light_bvh,
            env_texels: Buffer::from_slice(ctx, "EnvTexels", &env.texels)?,
            env_cdf: Buffer::from_slice(ctx, "EnvCdf", &env.cdf)?,
            triangle_uvs: Buffer::from_slice(ctx, "TriangleUvs", &triangle_uvs)?,
            material_textures: Buffer::from_slice(ctx, "MaterialTextures", &material_textures)?,
            texels: Buffer::from_slice(ctx, "Texels", &or_placeholder(texels, [0; 2]))?,
            env_frames: env.frames,
            constants: Buffer::from_slice(ctx, "SceneParams", &[constants])?,
            light_table,
            light_keys,
            build_ms: BuildTimes {
                triangle_bvh: triangle_bvh_ms,
                light_bvh: light_bvh_ms,
                upload: 0.0,
            },
            camera: camera_constants(cam),
            environment_size: (env.size[2] != 0).then_some([env.size[0], env.size[1]]),
            width: cam.width,
            height: cam.height,
            triangle_count: scene.triangles.len(),
            features: SceneFeatures {
                environment: env.size[2] != 0,
                delta_lights: !scene.lights.is_empty(),
                glossy: scene.materials.iter().any(|m| m.ks.max_element() > 0.0),
                textures: textured,
            },
        };
        gpu.build_ms.upload = upload_start.elapsed().as_secs_f64() * 1e3;
        Ok(gpu)
    }

    /// Device bytes of the light data: the light table, the emissive triangles, the light
    /// BVH's nodes and its trails.
    pub fn light_bytes(&self) -> u64 {
        self.light_entries.byte_size()
            + self.emitter_triangles.byte_size()
            + self.light_nodes.byte_size()
            + self.light_trails.byte_size()
    }

    /// Device bytes of everything the scene uploads: the BVH, the shading data, materials,
    /// lights, the light data, the environment's tables (every map of a sequence), the
    /// textures' tables and the constants.
    pub fn device_bytes(&self) -> u64 {
        let frames = self
            .env_frames
            .as_ref()
            .map_or(0, |f| f.texels.byte_size() + f.cdf.byte_size());
        self.bvh.nodes.byte_size()
            + self.bvh.triangles.byte_size()
            + self.bvh.loop_cuts.byte_size()
            + self.shading_triangles.byte_size()
            + self.materials.byte_size()
            + self.lights.byte_size()
            + self.light_bytes()
            + self.env_texels.byte_size()
            + self.env_cdf.byte_size()
            + frames
            + self.triangle_uvs.byte_size()
            + self.material_textures.byte_size()
            + self.texels.byte_size()
            + self.constants.byte_size()
    }

    /// The number of maps in the scene's environment sequence (1 for a still map or none).
    pub fn environment_frames(&self) -> u32 {
        self.env_frames.as_ref().map_or(1, |f| f.count)
    }

    /// Pass "environment frame" for a dynamic map: copies frame `frame` mod len's texels and
    /// CDF into the live buffers every kernel reads. Nothing for a still map.
    pub fn record_environment_frame<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let Some(frames) = &self.env_frames else {
            return Ok(());
        };
        let k = (frame % frames.count) as u64;
        let texels = self.env_texels.byte_size();
        let cdf = self.env_cdf.byte_size();
        cmd.pass("environment frame", |cmd| {
            cmd.copy_region(&frames.texels, k * texels, &self.env_texels, texels);
            cmd.copy_region(&frames.cdf, k * cdf, &self.env_cdf, cdf);
            Ok(())
        })
    }

    /// The environment texels frame `frame` shows, as a buffer and the index of its first texel
    /// there: a sequence's frame `frame` mod its length among all its frames, a still map's
    /// (or the placeholder's) live texels at 0. For a kernel that needs another frame's map
    /// beside the live one (restir's temporal reuse reads the previous frame's).
    pub fn environment_texels_of(&self, frame: u32) -> (&Buffer<Vec4>, u32) {
        match &self.env_frames {
            Some(frames) => {
                let texels = self.env_texels.len() as u32;
                (&frames.texels, (frame % frames.count) * texels)
            }
            None => (&self.env_texels, 0),
        }
    }

    /// Every scene binding (bvh.glsl and scene.glsl), by block name.
    pub fn bindings(&self) -> Vec<Binding<'_>> {
        let mut b: Vec<Binding<'_>> = self.bvh.bindings().into_iter().collect();
        b.extend(self.scene_bindings());
        b
    }

    /// light_bvh.glsl's bindings, for kernels that choose lights through the light BVH.
    pub fn light_bvh_bindings(&self) -> [Binding<'_>; 2] {
        [
            bind("LightBvhNodes", &self.light_nodes),
            bind("LightTrails", &self.light_trails),
        ]
    }

    /// scene.glsl's bindings alone, for kernels that trace no rays.
    pub fn scene_bindings(&self) -> Vec<Binding<'_>> {
        vec![
            bind("ShadingTriangles", &self.shading_triangles),
            bind("Materials", &self.materials),
            bind("Lights", &self.lights),
            bind("LightEntries", &self.light_entries),
            bind("EmitterTriangles", &self.emitter_triangles),
            bind("EnvTexels", &self.env_texels),
            bind("EnvCdf", &self.env_cdf),
            bind("SceneParams", &self.constants),
            bind("TriangleUvs", &self.triangle_uvs),
            bind("MaterialTextures", &self.material_textures),
            bind("Texels", &self.texels),
        ]
    }

    /// Workgroups of an 8 x 8 image kernel over the frame.
    pub fn image_workgroups(&self) -> [u32; 3] {
        [self.width.div_ceil(8), self.height.div_ceil(8), 1]
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// `v`, or one zeroed element when it is empty (a binding cannot be an empty buffer).
fn or_placeholder<T: Pod>(v: Vec<T>, zero: T) -> Vec<T> {
    if v.is_empty() {
        vec![zero]
    } else {
        v
    }
}
