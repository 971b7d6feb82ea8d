//! Procedural scenes for the analytic tests: planes, spheres and uniform or sun-lit
//! environment maps, built in code so each test states its whole setup.
#![allow(dead_code)]

use glam::Vec3;
use irad::scene::{Camera, Environment, Material, Scene, Triangle};

pub fn material(name: &str, kd: f32, ks: f32, ns: f32, ke: f32) -> Material {
    Material {
        name: name.into(),
        kd: Vec3::splat(kd),
        ks: Vec3::splat(ks),
        ns,
        ke: Vec3::splat(ke),
        albedo_texture: None,
    }
}

pub fn flat(positions: [Vec3; 3], material: u32) -> Triangle {
    let n = (positions[1] - positions[0])
        .cross(positions[2] - positions[0])
        .normalize();
    Triangle {
        positions,
        normals: [n; 3],
        material,
        uvs: [glam::Vec2::ZERO; 3],
    }
}

/// The square y = height, |x|, |z| <= half, facing +Y.
pub fn plane_y(half: f32, height: f32, material: u32) -> Vec<Triangle> {
    let p = |x: f32, z: f32| Vec3::new(x * half, height, z * half);
    vec![
        flat([p(-1.0, -1.0), p(-1.0, 1.0), p(1.0, 1.0)], material),
        flat([p(-1.0, -1.0), p(1.0, 1.0), p(1.0, -1.0)], material),
    ]
}

/// A UV sphere of flat triangles; `inward` makes the counter-clockwise side face the centre.
pub fn sphere(
    radius: f32,
    rings: u32,
    segments: u32,
    inward: bool,
    material: u32,
) -> Vec<Triangle> {
    use std::f32::consts::PI;
    let point = |r: u32, s: u32| {
        let theta = PI * r as f32 / rings as f32;
        let phi = 2.0 * PI * s as f32 / segments as f32;
        radius
            * Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            )
    };
    let mut tris = Vec::new();
    let mut push = |a: Vec3, b: Vec3, c: Vec3| {
        if (b - a).cross(c - a).length() < 1e-9 {
            return;
        }
        let t = if inward { [a, b, c] } else { [a, c, b] };
        tris.push(flat(t, material));
    };
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (
                point(r, s),
                point(r + 1, s),
                point(r + 1, s + 1),
                point(r, s + 1),
            );
            push(a, b, c);
            push(a, c, d);
        }
    }
    tris
}

pub fn camera(position: Vec3, look_at: Vec3, up: Vec3, fov_y: f32, size: u32) -> Camera {
    Camera {
        position,
        look_at,
        up,
        fov_y,
        width: size,
        height: size,
    }
}

pub fn uniform_environment(radiance: f32) -> Environment {
    Environment {
        width: 16,
        height: 8,
        texels: vec![Vec3::splat(radiance); 16 * 8],
        source: "uniform".into(),
    }
}

pub fn scene(
    name: &str,
    camera: Camera,
    triangles: Vec<Triangle>,
    materials: Vec<Material>,
) -> Scene {
    Scene {
        source: None,
        name: name.into(),
        content_hash: 0,
        camera,
        triangles,
        materials,
        lights: Vec::new(),
        textures: Vec::new(),
        environment: None,
        environment_sequence: vec![],
        luminaires: vec![],
        failure: None,
        warnings: Vec::new(),
        animation: None,
        load_ms: 0.0,
    }
}
