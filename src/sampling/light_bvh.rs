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
//! The build runs in f64; the nodes are stored compactly (48 bytes, `LightNode`) in depth-first
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
/// The leaf flag in `LightNode::bounds_max.w`'s bits.
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
    pub fn spot(position: Vec3, axis: Vec3, cone_angle: f32, falloff_angle: f32, power: f64) -> LightBounds {
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
        let (axis, cos_theta_o) =
            cone_union((self.axis, self.cos_theta_o), (other.axis, other.cos_theta_o));
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
                * (2.0 * theta_w * sin_theta_o - (theta_o - 2.0 * theta_w).cos()
                    - 2.0 * theta_o * sin_theta_o
                    + self.cos_theta_o);
        let d = parent_diagonal.as_dvec3();
        let kr = if d[dim] > 0.0 { d.max_element() / d[dim] } else { 1.0 };
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

/// One node as the GPU reads it (glsl/include/light_bvh.glsl `LightNode`), 48 bytes:
/// `bounds_min` xyz and phi; `bounds_max` xyz and, as bits, child 1's index (interior) or
/// the light's entry in the light table with `LEAF` set (leaf); `axis` xyz and, as bits,
/// cos theta_o (low 16 bits) and cos theta_e (high 16 bits) as half floats rounded down, so the
/// stored cone is never narrower than the true one.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct LightNode {
    pub bounds_min: Vec4,
    pub bounds_max: Vec4,
    pub axis: Vec4,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(LightNode as "LightNode" { bounds_min, bounds_max, axis })]
};

impl LightNode {
    fn new(b: &LightBounds, link: u32) -> LightNode {
        let cosines = f32_to_f16_down(b.cos_theta_o as f32) as u32
            | (f32_to_f16_down(b.cos_theta_e as f32) as u32) << 16;
        LightNode {
            bounds_min: b.min.extend(b.phi as f32),
            bounds_max: b.max.extend(f32::from_bits(link)),
            axis: b.axis.extend(f32::from_bits(cosines)),
        }
    }

    pub fn is_leaf(&self) -> bool {
        self.bounds_max.w.to_bits() & LEAF != 0
    }

    /// Child 1's node index (interior) or the light's entry (leaf).
    pub fn link(&self) -> u32 {
        self.bounds_max.w.to_bits() & !LEAF
    }

    pub fn cos_theta_o(&self) -> f32 {
        f16_to_f32(self.axis.w.to_bits() as u16)
    }

    pub fn cos_theta_e(&self) -> f32 {
        f16_to_f32((self.axis.w.to_bits() >> 16) as u16)
    }
}

/// The largest half float at most `x` (finite x in [-1, 1] here), as bits.
pub fn f32_to_f16_down(x: f32) -> u16 {
    // Candidates: every half in [-1, 1] is sign | exponent | mantissa; search the ordered
    // encodings by bisection on their values (monotone within each sign).
    let x = x.clamp(-1.0, 1.0);
    if x >= 0.0 {
        // Non-negative halves are ordered by their bits: the largest with value <= x.
        let (mut lo, mut hi) = (0u16, 0x3c00u16); // 0 .. 1.0
        while lo < hi {
            let mid = lo + (hi - lo).div_ceil(2);
            if f16_to_f32(mid) <= x {
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
            if f16_to_f32(mid) >= m {
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
        let mut work: Vec<(u32, LightBounds)> =
            lights.iter().copied().filter(|l| l.1.phi > 0.0 && l.1.phi.is_finite()).collect();
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
                    let below = buckets[..=split].iter().fold(LightBounds::EMPTY, |a, b| a.union(b));
                    let above = buckets[split + 1..].iter().fold(LightBounds::EMPTY, |a, b| a.union(b));
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
            if t < i0 || !(i1 > 0.0) {
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
            return if root.link() == entry && importance(root, p, n) > 0.0 { 1.0 } else { 0.0 };
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
                return if self.nodes[node].link() == entry { pmf } else { 0.0 };
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
    let (bmin, bmax) = (node.bounds_min.truncate(), node.bounds_max.truncate());
    let phi = node.bounds_min.w;
    let pc = 0.5 * (bmin + bmax);
    let to_p = p - pc;
    let dist2 = to_p.dot(to_p);
    let half_diagonal = 0.5 * (bmax - bmin).length();
    // pbrt clamps d^2 below by half the diagonal's length (not its square).
    let d2 = dist2.max(half_diagonal);
    let wi = if dist2 > 0.0 { to_p / dist2.sqrt() } else { Vec3::Z };
    let cos_theta_w = node.axis.truncate().dot(wi);
    let sin_theta_w = safe_sqrt(1.0 - cos_theta_w * cos_theta_w);
    // The cone of directions from p that the node's bounding sphere subtends.
    let r2 = half_diagonal * half_diagonal;
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
    if cos_theta_p <= node.cos_theta_e() {
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

    #[test]
    fn half_floats_round_down_and_decode_exactly() {
        for x in [1.0f32, 0.0, -1.0, 0.5, 0.70710677, -0.3, 0.9999, -0.9999, 1e-6] {
            let h = f32_to_f16_down(x);
            let y = f16_to_f32(h);
            assert!(y <= x, "{x} -> {y}");
            assert!(x - y < 1e-3, "{x} -> {y}");
        }
        assert_eq!(f16_to_f32(f32_to_f16_down(1.0)), 1.0);
        assert_eq!(f16_to_f32(f32_to_f16_down(-1.0)), -1.0);
        assert_eq!(f16_to_f32(f32_to_f16_down(0.0)), 0.0);
    }
}
