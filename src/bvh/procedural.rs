//! Procedural meshes and ray sets for the BVH test and `irad bench rays`: a displaced sphere
//! with random triangles around it, camera rays, and incoherent random rays. Deterministic
//! per seed (PCG hash, docs/DESIGN.md "Sampling").

use glam::Vec3;

use crate::sampling::pcg::{hash, unit_f32};
use crate::scene::Camera;
use crate::trace::TraceRay;

/// A counter-based stream of uniform floats: (seed, stream, index) hashed.
pub struct Random {
    seed: u32,
    stream: u32,
    index: u32,
}

impl Random {
    pub fn new(seed: u32, stream: u32) -> Self {
        Random {
            seed,
            stream,
            index: 0,
        }
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        self.index += 1;
        unit_f32(hash(&[self.seed, self.stream, self.index]))
    }

    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.uniform()
    }

    pub fn point_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }

    /// Uniform on the unit sphere.
    pub fn direction(&mut self) -> Vec3 {
        let z = 1.0 - 2.0 * self.uniform();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * self.uniform();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// A sphere of radius about 1 at the origin, displaced by a few sines, tessellated as a cube
/// sphere (6 faces of `n` x `n` quads, 12 n^2 triangles, none degenerate), plus
/// `random_triangles` triangles of random size (up to 0.3) scattered in [-1.5, 1.5]^3.
pub fn noisy_sphere(seed: u32, n: usize, random_triangles: usize) -> Vec<[Vec3; 3]> {
    let n = n.max(1);
    let displaced = |p: Vec3| {
        let d = p.normalize();
        let r = 1.0
            + 0.08 * (5.0 * d.x + 1.3).sin() * (6.0 * d.y + 0.7).sin() * (7.0 * d.z + 2.1).sin()
            + 0.02 * (23.0 * d.x + 17.0 * d.y).sin() * (19.0 * d.z + 0.4).cos();
        d * r
    };
    let mut triangles = Vec::with_capacity(12 * n * n + random_triangles);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            // Face `axis = sign` of the cube [-1, 1]^3, spanned by the other two axes.
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |i: usize, j: usize| {
                let mut p = Vec3::ZERO;
                p[axis] = sign;
                p[a] = 2.0 * i as f32 / n as f32 - 1.0;
                p[b] = 2.0 * j as f32 / n as f32 - 1.0;
                displaced(p)
            };
            for i in 0..n {
                for j in 0..n {
                    let (p00, p10) = (corner(i, j), corner(i + 1, j));
                    let (p01, p11) = (corner(i, j + 1), corner(i + 1, j + 1));
                    triangles.push([p00, p10, p11]);
                    triangles.push([p00, p11, p01]);
                }
            }
        }
    }
    let mut rng = Random::new(seed, 0x6d657368);
    for _ in 0..random_triangles {
        let center = rng.point_in(Vec3::splat(-1.5), Vec3::splat(1.5));
        let size = rng.range(0.01, 0.3);
        triangles.push([
            center + size * rng.direction(),
            center + size * rng.direction(),
            center + size * rng.direction(),
        ]);
    }
    triangles
}

/// A flat square of `2 n^2` triangles in the plane y = `y`, spanning [-half, half] in x and z:
/// geometry with a zero extent on one axis, for axis-parallel rays and flat BVH nodes.
pub fn floor(y: f32, half: f32, n: usize) -> Vec<[Vec3; 3]> {
    let n = n.max(1);
    let at = |i: usize, j: usize| {
        let s = 2.0 * half / n as f32;
        Vec3::new(-half + s * i as f32, y, -half + s * j as f32)
    };
    let mut triangles = Vec::with_capacity(2 * n * n);
    for i in 0..n {
        for j in 0..n {
            triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    triangles
}

/// The axis-aligned bounds (min, max) of a triangle list; zero for an empty one.
pub fn bounds(triangles: &[[Vec3; 3]]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in triangles.iter().flatten() {
        lo = lo.min(*t);
        hi = hi.max(*t);
    }
    if triangles.is_empty() {
        (Vec3::ZERO, Vec3::ZERO)
    } else {
        (lo, hi)
    }
}

/// One ray per pixel through the pixel centre, per the `Camera` convention, unbounded.
pub fn camera_rays(camera: &Camera) -> Vec<TraceRay> {
    let mut rays = Vec::with_capacity(camera.width as usize * camera.height as usize);
    for y in 0..camera.height {
        for x in 0..camera.width {
            let direction = camera.direction(x as f32 + 0.5, y as f32 + 0.5);
            rays.push(TraceRay::new(camera.position, direction, f32::INFINITY));
        }
    }
    rays
}

/// A camera looking at the centre of `bounds` from outside them (front, a little above), for
/// camera-ray benchmarks of a mesh without a scene camera.
pub fn camera_for_bounds(bounds: (Vec3, Vec3), width: u32, height: u32) -> Camera {
    let (lo, hi) = bounds;
    let center = 0.5 * (lo + hi);
    // Half the largest extent fills the vertical field of view (the corners may fall outside).
    let radius = (0.5 * (hi - lo).max_element()).max(1e-3);
    let fov_y = 40.0f32;
    let distance = radius / (0.5 * fov_y.to_radians()).sin();
    Camera {
        position: center + distance * Vec3::new(0.0, 0.3, 1.0).normalize(),
        look_at: center,
        up: Vec3::Y,
        fov_y,
        width,
        height,
    }
}

/// Incoherent rays: origins uniform in `bounds`, directions uniform on the sphere, unbounded.
pub fn random_rays(seed: u32, bounds: (Vec3, Vec3), count: usize) -> Vec<TraceRay> {
    let mut rng = Random::new(seed, 0x72617973);
    (0..count)
        .map(|_| {
            let origin = rng.point_in(bounds.0, bounds.1);
            TraceRay::new(origin, rng.direction(), f32::INFINITY)
        })
        .collect()
}
