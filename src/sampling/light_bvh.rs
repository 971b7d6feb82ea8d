//! The light BVH (pbrt-v4's `BVHLightSampler`, Pharr et al. 2023 Section 12.6.3; Conty and
//! Kulla 2018): a binary tree over the scene's emitters (emissive triangles, point and spot
//! lights; the environment map is chosen apart, by its share of the power table), built once per
//! scene, one light per leaf. A shading point descends from the root choosing each child in
//! proportion to its importance, pbrt's bound on the light the node's lights can send there:
//! power times a bound on the emitter's cosine over the squared distance (clamped below by half
//! the node's diagonal, as pbrt does), times a bound on the receiver's cosine. The pmf of a given
//! light is the product of the choices along its path, which `pmf` re-walks from the light's bit
//! trail (MIS needs it when a BSDF-sampled ray hits an emitter).
//!
//! The build runs in f64; the nodes are stored compactly (32 bytes, `LightNode`) in depth-first
//! order, child 0 right after its parent and child 1 at the index the parent stores, so the GPU
//! descends without a stack (glsl/include/light_bvh.glsl). `importance`, `sample` and `pmf` here
//! are the f32 mirror of that GLSL, operation for operation, for the tests.

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

/// Deepest a leaf may be: bit trails are 64 bits (two uints on the GPU). Past
/// `MEDIAN_SPLIT_DEPTH` the build splits at the median, so no tree reaches it.
pub const MAX_DEPTH: usize = 64;
const MEDIAN_SPLIT_DEPTH: usize = 40;
/// pbrt's bucket count for the split search.
const BUCKETS: usize = 12;
/// The largest f32 below 1 (pbrt's OneMinusEpsilon).
pub const ONE_MINUS_EPSILON: f32 = 0.99999994;
/// The leaf flag in `LightNode::packed.y`'s bits.
pub const LEAF: u32 = 0x8000_0000;

/// What bounds one light or a node's lights: where (an AABB), how much (phi, the power), and
/// in which directions (an emission cone of half-angle theta_o around `axis`, widened by
/// theta_e for the falloff beyond it: cosines stored).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub min: Vec3,
    pub max: Vec3,
    pub phi: f64,
    pub axis: Vec3,
    pub cos_theta_o: f64,
    pub cos_theta_e: f64,
}

impl LightBounds {
    /// An emissive triangle: one-sided, emitting into the hemisphere around its normal.
    pub fn triangle(positions: [Vec3; 3], normal: Vec3, power: f64) -> LightBounds {
        LightBounds {
            min: positions[0].min(positions[1]).min(positions[2]),
            max: positions[0].max(positions[1]).max(positions[2]),
            phi: power,
            axis: normal,
            cos_theta_o: 1.0,
            cos_theta_e: 0.0,
        }
    }

    /// A point light: every direction (pbrt: theta_o = pi, theta_e = pi / 2).
    pub fn point(position: Vec3, power: f64) -> LightBounds {
        LightBounds {
            min: position,
            max: position,
            phi: power,
            axis: Vec3::Z,
            cos_theta_o: -1.0,
            cos_theta_e: 0.0,
        }
    }

    /// A spot light: full intensity within `cone_angle` of `axis`, falling off to zero at
    /// `falloff_angle` (degrees). pbrt's phi for a spot is its point light's 4 pi I, the cone
    /// being the importance's business.
    pub fn spot(
        position: Vec3,
        axis: Vec3,
        cone_angle: f32,
        falloff_angle: f32,
        power: f64,
    ) -> LightBounds {
        let theta_o = (cone_angle as f64).to_radians();
        let theta_e = ((falloff_angle - cone_angle).max(0.0) as f64).to_radians();
        LightBounds {
            min: position,
            max: position,
            phi: power,
            axis: axis.normalize(),
            cos_theta_o: theta_o.cos(),
            cos_theta_e: theta_e.cos(),
        }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// pbrt's `Union(LightBounds, LightBounds)`: boxes and powers add, cones merge
    /// (`DirectionCone` union), theta_e is the larger.
    fn union(&self, other: &LightBounds) -> LightBounds {
        if self.phi == 0.0 {
            return *other;
        }
        if other.phi == 0.0 {
            return *self;
        }
        let (axis, cos_theta_o) = cone_union(
            (self.axis, self.cos_theta_o),
            (other.axis, other.cos_theta_o),
        );
        LightBounds {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
            phi: self.phi + other.phi,
            axis,
            cos_theta_o,
            cos_theta_e: self.cos_theta_e.min(other.cos_theta_e),
        }
    }

    const EMPTY: LightBounds = LightBounds {
        min: Vec3::splat(f32::MAX),
        max: Vec3::splat(f32::MIN),
        phi: 0.0,
        axis: Vec3::Z,
        cos_theta_o: 1.0,
        cos_theta_e: 1.0,
    };

    /// pbrt's `EvaluateCost`: power times the cone's solid-angle measure M_omega times the
    /// box's surface area, times Kr, the box's aspect along the split dimension.
    fn cost(&self, parent_diagonal: Vec3, dim: usize) -> f64 {
        let theta_o = self.cos_theta_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_theta_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(std::f64::consts::PI);
        let sin_theta_o = (1.0 - self.cos_theta_o * self.cos_theta_o).max(0.0).sqrt();
        let pi = std::f64::consts::PI;
        let m_omega = 2.0 * pi * (1.0 - self.cos_theta_o)
            + pi / 2.0
                * (2.0 * theta_w * sin_theta_o
                    - (theta_o - 2.0 * theta_w).cos()
                    - 2.0 * theta_o * sin_theta_o
                    + self.cos_theta_o);
        let d = parent_diagonal.as_dvec3();
        let kr = if d[dim] > 0.0 {
            d.max_element() / d[dim]
        } else {
            1.0
        };
        let e = (self.max - self.min).as_dvec3().max(glam::DVec3::ZERO);
        let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
        self.phi * m_omega * kr * area
    }
}

/// pbrt's `Union(DirectionCone, DirectionCone)`, in f64.
fn cone_union(a: (Vec3, f64), b: (Vec3, f64)) -> (Vec3, f64) {
    let pi = std::f64::consts::PI;
    let (wa, wb) = (a.0.as_dvec3(), b.0.as_dvec3());
    let theta_a = a.1.clamp(-1.0, 1.0).acos();
    let theta_b = b.1.clamp(-1.0, 1.0).acos();
    let theta_d = wa.dot(wb).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(pi) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(pi) <= theta_b {
        return b;
    }
    let theta_o = (theta_a + theta_d + theta_b) / 2.0;
    if theta_o >= pi {
        return (Vec3::Z, -1.0);
    }
    let theta_r = theta_o - theta_a;
    let wr = wa.cross(wb);
    if wr.length_squared() == 0.0 {
        return (Vec3::Z, -1.0);
    }
    let w = glam::DQuat::from_axis_angle(wr.normalize(), theta_r) * wa;
    (w.normalize().as_vec3(), theta_o.cos())
}

/// One node as the GPU reads it (glsl/include/light_bvh.glsl `LightNode`), 32 bytes (pbrt's
/// CompactLightBounds is 28): `sphere`, the centre and radius of a sphere around the node's
/// box (the importance reads only these: pbrt's `BoundingSphere`), the radius rounded up;
/// `packed`: x phi, and as bits y child 1's index (interior) or the light's entry in the light
/// table with `LEAF` set (leaf), z the cone's axis as an octahedral vector of two snorm16
/// (`octahedral_decode`), w cos theta_o (low 16 bits) and cos theta_e (high 16 bits) as half
/// floats rounded down, theta_o first widened by the axis's encoding error, so the stored cone
/// is never narrower than the true one.
///
/// Measured on the many-light hall (lavapipe, the path tracer's direct light): the first
/// layout, 48 bytes (box corners, axis as floats), made the paths pass 15% slower (2224 against
/// 1937 ms, 16 spp at 256x192), and a BVH sample cost 1.5x a power-table sample where it now
/// costs 1.3x (the efficiency suite's calibrated counts at 128x96).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct LightNode {
    pub sphere: Vec4,
    pub packed: Vec4,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(LightNode as "LightNode" { sphere, packed })]
};

impl LightNode {
    fn new(b: &LightBounds, link: u32) -> LightNode {
        // The sphere: its centre in f32, its radius the farthest corner's distance from that
        // centre (in f64), rounded up to an f32.
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let centre = (0.5 * (lo + hi)).as_vec3();
        let c = centre.as_dvec3();
        let radius = f32_up((lo - c).abs().max((hi - c).abs()).length());
        // The axis, encoded; theta_o widened by the angle between it and the decoded one.
        let axis = b.axis.as_dvec3().normalize_or(glam::DVec3::Z);
        let bits = octahedral_encode(axis);
        // Plus 1e-6 radians for what the axis lost before (its f32 rounding in the cone's
        // union, about 6e-8) and the acos of the cone's cosine near 0 and pi.
        let error = angle_between(axis, octahedral_decode(bits).as_dvec3()) + 1e-6;
        let cos_theta_o = if b.cos_theta_o <= -1.0 {
            -1.0
        } else {
            let theta_o = b.cos_theta_o.clamp(-1.0, 1.0).acos() + error;
            if theta_o >= std::f64::consts::PI {
                -1.0
            } else {
                theta_o.cos()
            }
        };
        let cosines = f16_down(cos_theta_o) as u32 | (f16_down(b.cos_theta_e) as u32) << 16;
        LightNode {
            sphere: centre.extend(radius),
            packed: Vec4::new(
                b.phi as f32,
                f32::from_bits(link),
                f32::from_bits(bits),
                f32::from_bits(cosines),
            ),
        }
    }

    /// What the GPU reads where the tree is empty (a scene whose only light is the environment,
    /// or none): a leaf of no power, which no descent chooses.
    pub const EMPTY: LightNode = LightNode {
        sphere: Vec4::ZERO,
        packed: Vec4::new(0.0, f32::from_bits(LEAF), 0.0, 0.0),
    };

    pub fn is_leaf(&self) -> bool {
        self.packed.y.to_bits() & LEAF != 0
    }

    /// Child 1's node index (interior) or the light's entry (leaf).
    pub fn link(&self) -> u32 {
        self.packed.y.to_bits() & !LEAF
    }

    pub fn phi(&self) -> f32 {
        self.packed.x
    }

    /// The cone's axis as the GPU decodes it.
    pub fn axis(&self) -> Vec3 {
        octahedral_decode(self.packed.z.to_bits())
    }

    pub fn cos_theta_o(&self) -> f32 {
        f16_to_f32(self.packed.w.to_bits() as u16)
    }

    pub fn cos_theta_e(&self) -> f32 {
        f16_to_f32((self.packed.w.to_bits() >> 16) as u16)
    }
}

/// The angle between two vectors, accurate for small angles too (acos of the dot product
/// is not: at 1e-4 radians an f32 rounding of the dot is already 5e-4 radians).
fn angle_between(a: glam::DVec3, b: glam::DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The smallest f32 at least `x` (finite, non-negative here).
fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f32::from_bits(f.to_bits() + 1)
    } else {
        f
    }
}

/// A unit vector as an octahedral vector (pbrt's OctahedralVector): the octahedron's
/// coordinates, the lower half folded over the upper, as two snorm16 (x low, y high), rounded
/// to nearest.
pub fn octahedral_encode(v: glam::DVec3) -> u32 {
    let v = v / (v.x.abs() + v.y.abs() + v.z.abs());
    let sign = |f: f64| if f >= 0.0 { 1.0 } else { -1.0 };
    let (x, y) = if v.z >= 0.0 {
        (v.x, v.y)
    } else {
        ((1.0 - v.y.abs()) * sign(v.x), (1.0 - v.x.abs()) * sign(v.y))
    };
    let q = |f: f64| (f.clamp(-1.0, 1.0) * 32767.0).round() as i16 as u16 as u32;
    q(x) | q(y) << 16
}

/// `octahedral_encode`'s vector back, in f32 as the GPU computes it
/// (glsl/include/light_bvh.glsl `octahedral_decode`).
pub fn octahedral_decode(bits: u32) -> Vec3 {
    // glslang folds GLSL's 1.0 / 32767.0 in f64.
    const SCALE: f32 = (1.0f64 / 32767.0) as f32;
    let x = ((bits as u16 as i16) as f32 * SCALE).max(-1.0);
    let y = (((bits >> 16) as u16 as i16) as f32 * SCALE).max(-1.0);
    let mut v = Vec3::new(x, y, 1.0 - x.abs() - y.abs());
    if v.z < 0.0 {
        let sign = |f: f32| if f >= 0.0 { 1.0 } else { -1.0 };
        v = Vec3::new((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y), v.z);
    }
    v / v.dot(v).sqrt()
}

/// The largest half float at most `x` (finite x in [-1, 1] here), as bits. In f64, so the
/// rounding is down from the exact cosine (an f32 on the way could round up).
pub fn f16_down(x: f64) -> u16 {
    // Candidates: every half in [-1, 1] is sign | exponent | mantissa; search the ordered
    // encodings by bisection on their values (monotone within each sign).
    let x = x.clamp(-1.0, 1.0);
    if x >= 0.0 {
        // Non-negative halves are ordered by their bits: the largest with value <= x.
        let (mut lo, mut hi) = (0u16, 0x3c00u16); // 0 .. 1.0
        while lo < hi {
            let mid = lo + (hi - lo).div_ceil(2);
            if f16_to_f32(mid) as f64 <= x {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        lo
    } else {
        // Negative: the smallest magnitude >= |x|.
        let m = -x;
        let (mut lo, mut hi) = (0u16, 0x3c00u16);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if f16_to_f32(mid) as f64 >= m {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        0x8000 | lo
    }
}

/// A half float's value (exact), as GLSL's unpackHalf2x16.
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = ((h >> 10) & 0x1f) as i32;
    let mantissa = (h & 0x3ff) as f32;
    let magnitude = match exponent {
        0 => mantissa * 2f32.powi(-24),
        31 => f32::INFINITY,
        e => (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    };
    sign * magnitude
}

/// The built tree: nodes depth-first from the root (index 0), and each light's bit trail
/// (bit d: 1 where the path to its leaf takes child 1 at depth d), by light-table entry.
#[derive(Clone, Debug, Default)]
pub struct LightBvh {
    pub nodes: Vec<LightNode>,
    /// By entry index (entries not in the tree, such as the environment, hold 0).
    pub trails: Vec<u64>,
    pub depth: usize,
}

impl LightBvh {
    /// Builds the tree over `lights`: (light-table entry, bounds); lights of zero power are
    /// left out (pbrt does so too). `entries` sizes the trail table.
    pub fn build(lights: &[(u32, LightBounds)], entries: usize) -> LightBvh {
        let mut work: Vec<(u32, LightBounds)> = lights
            .iter()
            .copied()
            .filter(|l| l.1.phi > 0.0 && l.1.phi.is_finite())
            .collect();
        let mut bvh = LightBvh {
            nodes: Vec::with_capacity(2 * work.len()),
            trails: vec![0; entries],
            depth: 0,
        };
        if !work.is_empty() {
            let n = work.len();
            bvh.build_range(&mut work, 0, n, 0, 0);
        }
        bvh
    }

    /// pbrt's `buildBVH`: a leaf per light; else the split (dimension, bucket) of least cost
    /// over 12 buckets of the centroids, or the median where none helps (and below
    /// MEDIAN_SPLIT_DEPTH, so trails fit 64 bits).
    fn build_range(
        &mut self,
        lights: &mut [(u32, LightBounds)],
        start: usize,
        end: usize,
        trail: u64,
        depth: usize,
    ) -> LightBounds {
        self.depth = self.depth.max(depth);
        // Below MEDIAN_SPLIT_DEPTH the splits halve, so a leaf is deeper than MAX_DEPTH only
        // with more than 2^24 lights, which no device's buffers hold (maxStorageBufferRange).
        assert!(
            depth < MAX_DEPTH,
            "light BVH deeper than {MAX_DEPTH} levels"
        );
        if end - start == 1 {
            let (entry, bounds) = lights[start];
            self.nodes.push(LightNode::new(&bounds, entry | LEAF));
            self.trails[entry as usize] = trail;
            return bounds;
        }
        let mut bounds = LightBounds::EMPTY;
        let (mut cmin, mut cmax) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for (_, b) in &lights[start..end] {
            bounds = LightBounds {
                min: bounds.min.min(b.min),
                max: bounds.max.max(b.max),
                ..bounds
            };
            cmin = cmin.min(b.centroid());
            cmax = cmax.max(b.centroid());
        }
        let bucket = |c: Vec3, dim: usize| -> usize {
            let t = (c[dim] - cmin[dim]) / (cmax[dim] - cmin[dim]);
            ((BUCKETS as f32 * t) as usize).min(BUCKETS - 1)
        };
        let diagonal = bounds.max - bounds.min;
        let mut best: Option<(f64, usize, usize)> = None;
        if depth < MEDIAN_SPLIT_DEPTH {
            for dim in 0..3 {
                if cmax[dim] == cmin[dim] {
                    continue;
                }
                let mut buckets = [LightBounds::EMPTY; BUCKETS];
                for (_, b) in &lights[start..end] {
                    let i = bucket(b.centroid(), dim);
                    buckets[i] = buckets[i].union(b);
                }
                for split in 1..BUCKETS - 1 {
                    let below = buckets[..=split]
                        .iter()
                        .fold(LightBounds::EMPTY, |a, b| a.union(b));
                    let above = buckets[split + 1..]
                        .iter()
                        .fold(LightBounds::EMPTY, |a, b| a.union(b));
                    let cost = below.cost(diagonal, dim) + above.cost(diagonal, dim);
                    if cost > 0.0 && best.is_none_or(|(c, _, _)| cost < c) {
                        best = Some((cost, dim, split));
                    }
                }
            }
        }
        let mut mid = (start + end) / 2;
        if let Some((_, dim, split)) = best {
            let slice = &mut lights[start..end];
            let mut i = 0;
            for j in 0..slice.len() {
                if bucket(slice[j].1.centroid(), dim) <= split {
                    slice.swap(i, j);
                    i += 1;
                }
            }
            if i > 0 && i < slice.len() {
                mid = start + i;
            }
        }
        let index = self.nodes.len();
        self.nodes.push(LightNode::zeroed());
        let b0 = self.build_range(lights, start, mid, trail, depth + 1);
        let child1 = self.nodes.len() as u32;
        let b1 = self.build_range(lights, mid, end, trail | 1 << depth, depth + 1);
        let union = b0.union(&b1);
        self.nodes[index] = LightNode::new(&union, child1);
        union
    }

    /// Samples a light for shading point `p` with surface normal `n` (zero: none) from
    /// `u` in [0, 1): its entry and pmf, or None where no light can reach `p`. The GPU's
    /// `light_bvh_select`, operation for operation.
    pub fn sample(&self, p: Vec3, n: Vec3, mut u: f32) -> Option<(u32, f32)> {
        let root = self.nodes.first()?;
        if root.is_leaf() {
            return (importance(root, p, n) > 0.0).then_some((root.link(), 1.0));
        }
        let mut node = 0usize;
        let mut pmf = 1.0f32;
        for _ in 0..MAX_DEPTH {
            let c0 = node + 1;
            let c1 = self.nodes[node].link() as usize;
            let i0 = importance(&self.nodes[c0], p, n);
            let i1 = importance(&self.nodes[c1], p, n);
            if !(i0 > 0.0 || i1 > 0.0) {
                return None;
            }
            let sum = i0 + i1;
            let t = u * sum;
            if t < i0 || i1.is_nan() || i1 <= 0.0 {
                pmf *= i0 / sum;
                u = (t / i0).min(ONE_MINUS_EPSILON);
                node = c0;
            } else {
                pmf *= i1 / sum;
                u = ((t - i0) / i1).min(ONE_MINUS_EPSILON);
                node = c1;
            }
            if self.nodes[node].is_leaf() {
                return Some((self.nodes[node].link(), pmf));
            }
        }
        None
    }

    /// The pmf with which `sample` picks `entry` at (p, n), by re-walking its bit trail: the
    /// GPU's `light_bvh_pmf`. 0 for a light the tree does not hold.
    pub fn pmf(&self, p: Vec3, n: Vec3, entry: u32) -> f32 {
        let Some(root) = self.nodes.first() else {
            return 0.0;
        };
        if root.is_leaf() {
            return if root.link() == entry && importance(root, p, n) > 0.0 {
                1.0
            } else {
                0.0
            };
        }
        let Some(&trail) = self.trails.get(entry as usize) else {
            return 0.0;
        };
        let mut node = 0usize;
        let mut pmf = 1.0f32;
        for depth in 0..MAX_DEPTH {
            let c0 = node + 1;
            let c1 = self.nodes[node].link() as usize;
            let i0 = importance(&self.nodes[c0], p, n);
            let i1 = importance(&self.nodes[c1], p, n);
            if !(i0 > 0.0 || i1 > 0.0) {
                return 0.0;
            }
            let sum = i0 + i1;
            if trail >> depth & 1 == 0 {
                pmf *= i0 / sum;
                node = c0;
            } else {
                pmf *= i1 / sum;
                node = c1;
            }
            if self.nodes[node].is_leaf() {
                return if self.nodes[node].link() == entry {
                    pmf
                } else {
                    0.0
                };
            }
        }
        0.0
    }
}

fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// cos(max(0, a - b)) from the sines and cosines of a and b (pbrt's cosSubClamped).
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// sin(max(0, a - b)) (pbrt's sinSubClamped).
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

/// pbrt's `LightBounds::Importance` of `node` at point `p` with normal `n` (zero: none), in
/// f32 as the GPU computes it (glsl/include/light_bvh.glsl `light_importance`).
pub fn importance(node: &LightNode, p: Vec3, n: Vec3) -> f32 {
    let pc = node.sphere.truncate();
    let radius = node.sphere.w;
    let phi = node.phi();
    let to_p = p - pc;
    let dist2 = to_p.dot(to_p);
    // pbrt clamps d^2 below by half the diagonal's length (not its square): here the radius.
    let d2 = dist2.max(radius);
    let wi = if dist2 > 0.0 {
        to_p / dist2.sqrt()
    } else {
        Vec3::Z
    };
    let cos_theta_w = node.axis().dot(wi);
    let sin_theta_w = safe_sqrt(1.0 - cos_theta_w * cos_theta_w);
    // The cone of directions from p that the node's bounding sphere subtends.
    let r2 = radius * radius;
    let cos_theta_b = if dist2 < r2 {
        -1.0
    } else {
        safe_sqrt(1.0 - r2 / dist2)
    };
    let sin_theta_b = safe_sqrt(1.0 - cos_theta_b * cos_theta_b);
    let cos_theta_o = node.cos_theta_o();
    let sin_theta_o = safe_sqrt(1.0 - cos_theta_o * cos_theta_o);
    let cos_theta_x = cos_sub_clamped(sin_theta_w, cos_theta_w, sin_theta_o, cos_theta_o);
    let sin_theta_x = sin_sub_clamped(sin_theta_w, cos_theta_w, sin_theta_o, cos_theta_o);
    let cos_theta_p = cos_sub_clamped(sin_theta_x, cos_theta_x, sin_theta_b, cos_theta_b);
    // Zero strictly beyond the falloff (pbrt tests `<=`): a hard-edged spot has cos theta_e = 1
    // and cos theta' = 1 inside its cone, which `<=` would count as outside. At the boundary
    // of a finite falloff the product below is what it is (0 for cos theta_e = 0).
    if cos_theta_p < node.cos_theta_e() {
        return 0.0;
    }
    let mut importance = phi * cos_theta_p / d2;
    if n != Vec3::ZERO {
        let cos_theta_i = wi.dot(n).abs();
        let sin_theta_i = safe_sqrt(1.0 - cos_theta_i * cos_theta_i);
        importance *= cos_sub_clamped(sin_theta_i, cos_theta_i, sin_theta_b, cos_theta_b);
    }
    importance.max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::pcg::{rand, rand3, sphere_direction as direction};

    /// A power spanning three orders of magnitude (log-uniform in [0.1, 100]).
    fn power(seed: u32, index: u32, dim: u32) -> f64 {
        0.1 * 10f64.powf(3.0 * rand(seed, index, dim) as f64)
    }

    /// A light as the tests know it: its bounds and what it is, to decide where it can reach.
    #[derive(Clone, Copy, Debug)]
    enum Emitter {
        Triangle([Vec3; 3]),
        Point(Vec3),
        /// Position, unit axis, falloff angle in degrees (where the intensity reaches zero).
        Spot(Vec3, Vec3, f32),
    }

    /// `triangles` emissive triangles (random sizes from 0.02 to 2, random orientations) in
    /// a 20-unit cube, and `deltas` point lights and as many spots (cones of 5 to 60 degrees,
    /// falloffs up to 20 degrees wider, every third hard-edged), powers log-uniform over three
    /// orders of magnitude.
    fn random_lights(seed: u32, triangles: u32, deltas: u32) -> Vec<(LightBounds, Emitter)> {
        let mut out = Vec::new();
        for i in 0..triangles {
            let centre = 20.0 * rand3(seed, i, 0) - Vec3::splat(10.0);
            let size = 0.02 * 100f32.powf(rand(seed, i, 3));
            let v: [Vec3; 3] = [4, 6, 8].map(|d| centre + size * direction(seed, i, d));
            let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            if normal == Vec3::ZERO {
                continue;
            }
            out.push((
                LightBounds::triangle(v, normal, power(seed, i, 10)),
                Emitter::Triangle(v),
            ));
        }
        for i in 0..deltas {
            let j = 10_000 + i;
            let position = 20.0 * rand3(seed, j, 0) - Vec3::splat(10.0);
            out.push((
                LightBounds::point(position, power(seed, j, 3)),
                Emitter::Point(position),
            ));
            let position = 20.0 * rand3(seed, j, 4) - Vec3::splat(10.0);
            let axis = direction(seed, j, 7);
            let cone = 5.0 + 55.0 * rand(seed, j, 9);
            // Every third spot hard-edged (falloff = cone).
            let falloff = if i % 3 == 2 {
                cone
            } else {
                cone + 20.0 * rand(seed, j, 10)
            };
            out.push((
                LightBounds::spot(position, axis, cone, falloff, power(seed, j, 11)),
                Emitter::Spot(position, axis, falloff),
            ));
        }
        out
    }

    fn build(lights: &[(LightBounds, Emitter)]) -> LightBvh {
        // One entry more than the lights: an entry the tree does not hold (as the environment).
        let entries: Vec<(u32, LightBounds)> = lights
            .iter()
            .enumerate()
            .map(|(i, l)| (i as u32, l.0))
            .collect();
        LightBvh::build(&entries, lights.len() + 1)
    }

    /// Shading points in and around the lights' cube, with random normals, one in four none.
    fn shading_points(seed: u32, count: u32) -> Vec<(Vec3, Vec3)> {
        (0..count)
            .map(|i| {
                let p = 30.0 * rand3(seed, i, 100) - Vec3::splat(15.0);
                let n = if i % 4 == 0 {
                    Vec3::ZERO
                } else {
                    direction(seed, i, 103)
                };
                (p, n)
            })
            .collect()
    }

    /// Whether `light` sends any light to p: strictly in front of a triangle, anywhere but at
    /// a point light, strictly inside a spot's falloff cone (a receiver normal only scales).
    fn reaches(light: &Emitter, p: Vec3) -> bool {
        match *light {
            Emitter::Triangle(v) => {
                let normal = (v[1] - v[0]).cross(v[2] - v[0]);
                // In f64: which side p is on, with a margin for the f32 rounding of the normal.
                let d = (p - v[0]).as_dvec3().dot(normal.as_dvec3().normalize());
                d > 1e-4
            }
            Emitter::Point(position) => p != position,
            Emitter::Spot(position, axis, falloff) => {
                let to_p = (p - position).as_dvec3();
                let cos = to_p.normalize().dot(axis.as_dvec3());
                cos > (falloff as f64 + 1e-3).to_radians().cos()
            }
        }
    }

    /// The probability with which `sample` reaches a node both of whose children have zero
    /// importance at (p, n) (pbrt's `BVHLightSampler` returns no light there, as `sample`
    /// does), by walking the whole tree: what the lights' pmfs miss of 1.
    fn dead_end_mass(bvh: &LightBvh, p: Vec3, n: Vec3) -> f64 {
        fn walk(bvh: &LightBvh, node: usize, p: Vec3, n: Vec3, mass: f64) -> f64 {
            if bvh.nodes[node].is_leaf() || mass == 0.0 {
                return 0.0;
            }
            let (c0, c1) = (node + 1, bvh.nodes[node].link() as usize);
            let i0 = importance(&bvh.nodes[c0], p, n) as f64;
            let i1 = importance(&bvh.nodes[c1], p, n) as f64;
            if !(i0 > 0.0 || i1 > 0.0) {
                return mass;
            }
            walk(bvh, c0, p, n, mass * i0 / (i0 + i1)) + walk(bvh, c1, p, n, mass * i1 / (i0 + i1))
        }
        if bvh.nodes.is_empty() {
            return 0.0;
        }
        walk(bvh, 0, p, n, 1.0)
    }

    /// (a) Over random light sets and shading points, the lights' pmfs sum to 1 where any is
    /// positive, less exactly what the descent loses at dead ends (nodes both of whose children
    /// have zero importance, where `sample` returns None, as pbrt's does): with one-sided
    /// triangles facing every way there is such a node under almost every point (measured: 5%
    /// to 44% of the mass, 9% on average), with point lights alone none, and there the sum is 1.
    /// And every light that can reach p has a positive pmf there: that, not the sum, is what
    /// keeps next-event estimation unbiased (a dead end only drops lights that send nothing).
    #[test]
    fn pmfs_sum_to_one_and_every_light_that_reaches_p_can_be_chosen() {
        let (mut points_checked, mut with_dead_ends, mut dead_total) = (0, 0, 0.0);
        for seed in 0..6u32 {
            let mut lights = random_lights(seed, 300, 12);
            if seed >= 4 {
                // Point lights alone: every node has positive importance everywhere.
                lights = random_lights(seed, 0, 200);
                lights.retain(|l| matches!(l.1, Emitter::Point(_)));
            }
            let bvh = build(&lights);
            for (k, &(p, n)) in shading_points(seed, 150).iter().enumerate() {
                let pmfs: Vec<f32> = (0..=lights.len() as u32)
                    .map(|e| bvh.pmf(p, n, e))
                    .collect();
                assert_eq!(pmfs[lights.len()], 0.0, "the entry outside the tree");
                for (e, light) in lights.iter().enumerate() {
                    assert!(
                        !reaches(&light.1, p) || pmfs[e] > 0.0,
                        "seed {seed}, point {k} ({p}, n {n}): light {e} ({:?}) reaches p but \
                         has pmf 0",
                        light.1
                    );
                }
                let sum: f64 = pmfs.iter().map(|&x| x as f64).sum();
                if sum == 0.0 {
                    continue;
                }
                points_checked += 1;
                let dead = dead_end_mass(&bvh, p, n);
                dead_total += dead;
                if dead > 0.0 {
                    with_dead_ends += 1;
                    assert!(
                        seed < 4,
                        "seed {seed}, point {k}: a dead end among point lights"
                    );
                } else {
                    assert!(
                        (sum - 1.0).abs() < 1e-4,
                        "seed {seed}, point {k}: sum {sum}"
                    );
                }
                assert!(
                    (sum + dead - 1.0).abs() < 1e-4,
                    "seed {seed}, point {k}: sum {sum}, dead ends {dead}"
                );
            }
        }
        eprintln!(
            "{points_checked} points, {with_dead_ends} with dead ends, mean dead-end mass {:.3}",
            dead_total / points_checked as f64
        );
        assert!(points_checked > 800 && with_dead_ends < points_checked);
    }

    /// A hard-edged spot (cone_angle = falloff_angle, which scenes allow and lights.glsl
    /// `spot_falloff` renders as a step) has theta_e = 0, cos theta_e = 1, and the importance
    /// inside its cone is cos theta' = 1: it must not count as outside (`<=` did, and the BVH
    /// never chose such a spot). Alone and among other lights, at points inside its cone.
    #[test]
    fn a_hard_edged_spot_can_be_chosen_inside_its_cone() {
        let spot = LightBounds::spot(Vec3::ZERO, -Vec3::Y, 20.0, 20.0, 10.0);
        let others = random_lights(3, 100, 6);
        for with_others in [false, true] {
            let mut lights = vec![(0u32, spot)];
            if with_others {
                lights.extend(others.iter().enumerate().map(|(i, l)| (i as u32 + 1, l.0)));
            }
            let bvh = LightBvh::build(&lights, lights.len());
            for k in 0..50u32 {
                // Inside the cone (up to 19 degrees off the axis), 1 to 10 units below.
                let theta = 19f32.to_radians() * rand(5, k, 0);
                let phi = std::f32::consts::TAU * rand(5, k, 1);
                let dir = Vec3::new(
                    theta.sin() * phi.cos(),
                    -theta.cos(),
                    theta.sin() * phi.sin(),
                );
                let p = (1.0 + 9.0 * rand(5, k, 2)) * dir;
                for n in [Vec3::ZERO, Vec3::Y] {
                    assert!(
                        bvh.pmf(p, n, 0) > 0.0,
                        "with others {with_others}: the spot has pmf 0 at {p} (n {n}), inside its cone"
                    );
                }
            }
            // Outside it (30 degrees off the axis) it still sends nothing: pmf 0 when alone.
            let p = 3.0 * Vec3::new(30f32.to_radians().sin(), -30f32.to_radians().cos(), 0.0);
            if !with_others {
                assert_eq!(bvh.pmf(p, Vec3::ZERO, 0), 0.0);
            }
        }
    }

    /// (b) `sample` returns, bit for bit, the pmf that `pmf` finds for its pick by re-walking
    /// the pick's trail; it returns None only where the descent meets a dead end.
    #[test]
    fn sample_returns_exactly_the_rewalked_pmf() {
        let mut samples = 0;
        for seed in 0..4u32 {
            let lights = random_lights(seed, 300, 12);
            let bvh = build(&lights);
            for (k, &(p, n)) in shading_points(seed + 100, 100).iter().enumerate() {
                for j in 0..32u32 {
                    let u = rand(seed, k as u32, 200 + j);
                    match bvh.sample(p, n, u) {
                        Some((entry, pmf)) => {
                            let rewalked = bvh.pmf(p, n, entry);
                            assert_eq!(
                                pmf.to_bits(),
                                rewalked.to_bits(),
                                "seed {seed}, point {k}, u {u}: entry {entry}: sample's pmf \
                                 {pmf}, pmf's {rewalked}"
                            );
                            assert!(pmf > 0.0 && (entry as usize) < lights.len());
                            samples += 1;
                        }
                        None => assert!(
                            dead_end_mass(&bvh, p, n) > 0.0
                                || (0..lights.len() as u32).all(|e| bvh.pmf(p, n, e) == 0.0),
                            "seed {seed}, point {k}, u {u}: None without a dead end"
                        ),
                    }
                }
            }
        }
        assert!(samples > 10_000, "{samples}");
    }

    /// The upper tail probability of the chi-square distribution with `dof` degrees of
    /// freedom at `x`, by the Wilson-Hilferty normal approximation.
    fn chi_square_p_value(x: f64, dof: usize) -> f64 {
        let k = dof as f64;
        let z = ((x / k).powf(1.0 / 3.0) - (1.0 - 2.0 / (9.0 * k))) / (2.0 / (9.0 * k)).sqrt();
        0.5 * erfc(z / std::f64::consts::SQRT_2)
    }

    /// erfc to a relative error below 1.2e-7 (Numerical Recipes' `erfcc`, Chebyshev fit).
    fn erfc(x: f64) -> f64 {
        let z = x.abs();
        let t = 1.0 / (1.0 + 0.5 * z);
        let poly = -z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277))))))));
        let r = t * poly.exp();
        if x >= 0.0 {
            r
        } else {
            2.0 - r
        }
    }

    /// Pearson's chi-square of observed counts against expected ones (bins whose expected
    /// count is under 5 pooled into one, dropped if the pool is still under 5, the statistic
    /// infinite if the dropped pool holds many): (statistic, degrees of freedom).
    fn chi_square(observed: &[u64], expected: &[f64]) -> (f64, usize) {
        let (mut stat, mut bins) = (0.0, 0);
        let (mut pool_o, mut pool_e) = (0.0, 0.0);
        for (&o, &e) in observed.iter().zip(expected) {
            if e < 5.0 {
                pool_o += o as f64;
                pool_e += e;
            } else {
                stat += (o as f64 - e).powi(2) / e;
                bins += 1;
            }
        }
        if pool_e >= 5.0 {
            stat += (pool_o - pool_e).powi(2) / pool_e;
            bins += 1;
        } else if pool_o > 5.0 + 4.0 * pool_e {
            // Where (almost) nothing was expected, many were seen: a wrong pmf, whatever
            // the other bins say.
            stat = f64::INFINITY;
        }
        (stat, bins - 1)
    }

    /// (c) At fixed points, 200k choices drawn with PCG numbers match the pmf by a chi-square
    /// test (p-value above 1e-4), and the same counts reject both a uniform pmf and the
    /// power-proportional one, so the test has the power to see a wrong pmf.
    #[test]
    fn choices_follow_the_pmf_by_chi_square() {
        const N: u32 = 200_000;
        let lights = random_lights(7, 300, 12);
        let bvh = build(&lights);
        let total_power: f64 = lights.iter().map(|l| l.0.phi).sum();
        let points = [
            (Vec3::new(0.5, -1.0, 2.0), Vec3::new(0.0, 1.0, 0.0)),
            (Vec3::new(-6.0, 4.0, -3.0), Vec3::ZERO),
            (Vec3::new(12.0, 0.0, 0.0), Vec3::new(-0.6, 0.0, 0.8)),
        ];
        for (k, &(p, n)) in points.iter().enumerate() {
            // Bins: one per light, and the last for None (a dead end).
            let mut counts = vec![0u64; lights.len() + 1];
            for i in 0..N {
                let u = rand(0xc41, k as u32, i);
                match bvh.sample(p, n, u) {
                    Some((e, _)) => counts[e as usize] += 1,
                    None => counts[lights.len()] += 1,
                }
            }
            let with_none = |pmf: Vec<f64>| -> Vec<f64> {
                let rest = (1.0 - pmf.iter().sum::<f64>()).max(0.0);
                pmf.into_iter()
                    .chain([rest])
                    .map(|x| x * N as f64)
                    .collect()
            };
            let pmf = with_none(
                (0..lights.len() as u32)
                    .map(|e| bvh.pmf(p, n, e) as f64)
                    .collect(),
            );
            let (stat, dof) = chi_square(&counts, &pmf);
            let p_value = chi_square_p_value(stat, dof);
            eprintln!(
                "point {k}: chi-square {stat:.1} over {dof} degrees of freedom, p = {p_value:.3}"
            );
            assert!(dof > 20, "point {k}: too few bins to test ({dof})");
            assert!(p_value > 1e-4, "point {k}: p = {p_value}");

            let uniform = with_none(vec![1.0 / lights.len() as f64; lights.len()]);
            let by_power = with_none(lights.iter().map(|l| l.0.phi / total_power).collect());
            for (name, wrong) in [("uniform", uniform), ("by power", by_power)] {
                let (stat, dof) = chi_square(&counts, &wrong);
                let p_value = chi_square_p_value(stat, dof);
                assert!(
                    p_value < 1e-4,
                    "point {k}: a {name} pmf passes (p = {p_value})"
                );
            }
        }
        // The approximation itself: the median and the 1e-4 tail at 100 degrees of freedom
        // (exact: 99.334 and 161.32, from the regularized incomplete gamma function).
        assert!((chi_square_p_value(99.334, 100) - 0.5).abs() < 2e-3);
        assert!((chi_square_p_value(161.32, 100) / 1e-4 - 1.0).abs() < 0.2);
    }

    /// (d) Trails fit 64 bits (the tree at most 64 deep) for degenerate sets: thousands of lights
    /// at one point, and collinear lights whose powers double, which the cost peels off one a
    /// level until the median split takes over; every trail leads to its own leaf.
    #[test]
    fn degenerate_sets_stay_within_64_levels() {
        let same_point: Vec<(u32, LightBounds)> = (0..5000)
            .map(|i| {
                (
                    i,
                    LightBounds::point(Vec3::new(1.0, 2.0, 3.0), 1.0 + (i % 7) as f64),
                )
            })
            .collect();
        let collinear: Vec<(u32, LightBounds)> = (0..5000)
            .map(|i| {
                let x = i as f32 * 0.01;
                let v = [
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x + 0.005, 0.0, 0.0),
                    Vec3::new(x, 0.005, 0.0),
                ];
                (
                    i,
                    LightBounds::triangle(v, Vec3::Z, 2f64.powi(i as i32 % 120)),
                )
            })
            .collect();
        let doubling: Vec<(u32, LightBounds)> = (0..120)
            .map(|i| {
                (
                    i,
                    LightBounds::point(Vec3::new(i as f32, 0.0, 0.0), 2f64.powi(i as i32)),
                )
            })
            .collect();
        for (name, lights) in [
            ("same point", same_point),
            ("collinear", collinear),
            ("doubling", doubling),
        ] {
            let bvh = LightBvh::build(&lights, lights.len());
            eprintln!("{name}: {} lights, depth {}", lights.len(), bvh.depth);
            assert!(bvh.depth <= MAX_DEPTH, "{name}: depth {}", bvh.depth);
            assert_eq!(bvh.nodes.len(), 2 * lights.len() - 1, "{name}");
            for &(entry, _) in &lights {
                let trail = bvh.trails[entry as usize];
                let mut node = 0usize;
                let mut depth = 0;
                while !bvh.nodes[node].is_leaf() {
                    assert!(
                        depth < MAX_DEPTH,
                        "{name}: entry {entry}'s trail runs past 64 levels"
                    );
                    node = if trail >> depth & 1 == 0 {
                        node + 1
                    } else {
                        bvh.nodes[node].link() as usize
                    };
                    depth += 1;
                }
                assert_eq!(
                    bvh.nodes[node].link(),
                    entry,
                    "{name}: entry {entry}'s trail"
                );
            }
            // Above the lights every one is reachable, and its pmf re-walks its own path.
            let p = Vec3::new(20.0, 5.0, 30.0);
            let sum: f64 = lights
                .iter()
                .map(|&(e, _)| bvh.pmf(p, Vec3::ZERO, e) as f64)
                .sum();
            assert!((sum - 1.0).abs() < 1e-4, "{name}: pmfs sum to {sum}");
        }
    }

    #[test]
    fn half_floats_round_down_and_decode_exactly() {
        for x in [
            1.0f64, 0.0, -1.0, 0.5, 0.70710677, -0.3, 0.9999, -0.9999, 1e-6,
        ] {
            let h = f16_down(x);
            let y = f16_to_f32(h) as f64;
            assert!(y <= x, "{x} -> {y}");
            assert!(x - y < 1e-3, "{x} -> {y}");
        }
        assert_eq!(f16_to_f32(f16_down(1.0)), 1.0);
        assert_eq!(f16_to_f32(f16_down(-1.0)), -1.0);
        assert_eq!(f16_to_f32(f16_down(0.0)), 0.0);
    }

    /// The octahedral axis decodes within 1e-4 radians of the true one and of unit length, and
    /// a node's stored cone (the decoded axis, theta_o widened) holds the true cone: every
    /// direction of the true cone's boundary is within the stored cone.
    #[test]
    fn octahedral_axes_round_trip_and_cones_stay_conservative() {
        for i in 0..20000u32 {
            let v = direction(0x0c7a, i, 0).as_dvec3();
            let d = octahedral_decode(octahedral_encode(v));
            assert!((d.length() - 1.0).abs() < 1e-6, "{v}: |{d}|");
            let angle = angle_between(v, d.as_dvec3());
            assert!(angle < 1e-4, "{v}: decoded {d}, {angle} rad off");
            // A spot of cone angle 0..90 degrees around v, no falloff.
            let cone = 90.0 * rand(0x0c7b, i, 0);
            let b = LightBounds::spot(Vec3::ZERO, v.as_vec3(), cone, cone, 1.0);
            let node = LightNode::new(&b, LEAF);
            let stored = (node.cos_theta_o() as f64).clamp(-1.0, 1.0).acos();
            let theta_o = (b.cos_theta_o).clamp(-1.0, 1.0).acos();
            let between = angle_between(v, node.axis().as_dvec3());
            assert!(
                theta_o + between <= stored,
                "{v}: cone {theta_o} rad, axis {between} off, stored {stored}"
            );
        }
    }
}
