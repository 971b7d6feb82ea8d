//! The absorption schedule of Keller 97's quasi-random walk (Section 3.2): how many of the N
//! paths reach each vertex and where each vertex's VPL slots start. Fractional absorption
//! (stills): N_j = floor(rho^j N) paths reach vertex j, rho the scene's mean reflectivity, and
//! a vertex-j VPL carries 1 / N_j of its path's throughput. Russian roulette (animation): every
//! path keeps a slot at every vertex and survives each with probability rho. Past the vertex
//! where N_j reaches 0, the last paths go on by roulette (irad's tail; see `Schedule::new`).

use crate::sampling::environment::luminance;
use crate::scene::Scene;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Absorption {
    Fractional,
    Roulette,
}

crate::methods::settings::named_choices!(Absorption {
    Fractional => "fractional",
    Roulette => "roulette",
});

/// Most vertices per path (light vertex included): a cap for rho close to 1, where
/// floor(rho^j N) stays positive for very long.
pub const MAX_VERTICES: usize = 128;
/// Fractional absorption's roulette tail ends where rho^j falls below this.
pub const TAIL_CUTOFF: f64 = 1e-6;

#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    pub path_count: u32,
    /// Per vertex: paths that reach it, first slot, 1 under roulette, 1 in fractional
    /// absorption's roulette tail.
    pub levels: Vec<[u32; 4]>,
    pub slot_count: u32,
    pub mean_albedo: f64,
}

impl Schedule {
    pub fn new(path_count: u32, mean_albedo: f64, absorption: Absorption) -> Schedule {
        let n = path_count.max(1);
        let mut levels = Vec::new();
        let mut offset = 0u32;
        for j in 0..MAX_VERTICES {
            let count = match absorption {
                Absorption::Fractional => (mean_albedo.powi(j as i32) * n as f64).floor() as u32,
                Absorption::Roulette => n,
            };
            if count == 0 || (absorption == Absorption::Roulette && j > 0 && mean_albedo <= 0.0) {
                break;
            }
            let roulette = u32::from(absorption == Absorption::Roulette);
            levels.push([count.min(n), offset, roulette, 0]);
            offset += count.min(n);
            if absorption == Absorption::Roulette && mean_albedo.powi(j as i32 + 1) < 1e-4 {
                break;
            }
        }
        // Keller's N_j reaches 0 at some vertex J and the walk would end there, losing every
        // longer path (15% of the U office's image lies past 10 bounces). irad continues the
        // N_{J-1} paths still alive by Russian roulette, so a vertex-j VPL still carries
        // 1 / N_{J-1} of an unbiased throughput, until rho^j < TAIL_CUTOFF. The tail's survival
        // follows the path's throughput (w = 1 marks it; trace_vpls.comp), not Keller's fixed
        // rho, whose 1 / rho^k weights made the tail's VPLs spikes.
        if absorption == Absorption::Fractional && mean_albedo > 0.0 {
            let alive = levels.last().map_or(0, |l| l[0]);
            let mut j = levels.len();
            while alive > 0 && j < MAX_VERTICES && mean_albedo.powi(j as i32) >= TAIL_CUTOFF {
                levels.push([alive, offset, 1, 1]);
                offset += alive;
                j += 1;
            }
        }
        Schedule {
            path_count: n,
            levels,
            slot_count: offset,
            mean_albedo,
        }
    }

    /// The schedule of `classes` interleaved walks of ceil(N / classes) paths each (ir's
    /// `--reuse`, reuse.rs): path i = k + classes t is path t of class k, reaches vertex j iff
    /// t < N_j of the class's own schedule, and a vertex's count is classes times the class's,
    /// so every class has the same paths at every vertex (none is empty where another is not)
    /// and a slot's weight 1 / (classes N_j) is the class's 1 / N_j averaged over the classes.
    /// One class is `new`'s schedule.
    pub fn interleaved(
        path_count: u32,
        mean_albedo: f64,
        absorption: Absorption,
        classes: u32,
    ) -> Schedule {
        let k = classes.max(1);
        if k == 1 {
            return Schedule::new(path_count, mean_albedo, absorption);
        }
        let class = Schedule::new(path_count.max(1).div_ceil(k), mean_albedo, absorption);
        let mut offset = 0;
        let levels = class
            .levels
            .iter()
            .map(|l| {
                let level = [l[0] * k, offset, l[2], l[3]];
                offset += l[0] * k;
                level
            })
            .collect();
        Schedule {
            path_count: class.path_count * k,
            levels,
            slot_count: offset,
            mean_albedo,
        }
    }

    /// The slots of the vertices past the light vertex (indirect light only).
    pub fn surface_slots(&self) -> std::ops::Range<u32> {
        self.levels.first().map_or(0, |l| l[0])..self.slot_count
    }
}

/// Keller's mean reflectivity: the area-weighted mean over all triangles of the luminance of
/// their albedo, Kd + Ks (the normalized Phong lobe's albedo at normal incidence), a textured
/// Kd times its texture's mean (a glTF base colour of 1 carries its colour in the texture:
/// taken as 1, the walk's absorption would keep every path to its last vertex).
pub fn mean_albedo(scene: &Scene) -> f64 {
    let texture_means: Vec<glam::Vec3> = scene
        .textures
        .iter()
        .map(|t| {
            let sum = t
                .texels
                .iter()
                .fold(glam::DVec3::ZERO, |s, c| s + c.as_dvec3());
            (sum / t.texels.len().max(1) as f64).as_vec3()
        })
        .collect();
    let (mut weighted, mut area) = (0.0, 0.0);
    for t in &scene.triangles {
        let a = t.area();
        let m = &scene.materials[t.material as usize];
        let kd = match m.albedo_texture.and_then(|k| texture_means.get(k as usize)) {
            Some(mean) => m.kd * *mean,
            None => m.kd,
        };
        weighted += a * luminance(kd + m.ks);
        area += a;
    }
    if area > 0.0 {
        (weighted / area).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fractional_counts_are_floor_rho_j_n() {
        let s = Schedule::new(1000, 0.5, Absorption::Fractional);
        let counts: Vec<u32> = s.levels.iter().map(|l| l[0]).take(10).collect();
        assert_eq!(counts, vec![1000, 500, 250, 125, 62, 31, 15, 7, 3, 1]);
        assert!(s.levels[..10].iter().all(|l| l[2] == 0));
        assert_eq!(s.levels[2][1], 1500);
        assert_eq!(s.slot_count, s.levels.iter().map(|l| l[0]).sum::<u32>());
        assert_eq!(s.surface_slots(), 1000..s.slot_count);
    }

    /// Past N_j = 0 the last path goes on by roulette until rho^j < TAIL_CUTOFF (0.5^19 is
    /// the last at or above 1e-6), the tail marked in w.
    #[test]
    fn fractional_paths_go_on_by_roulette_where_n_j_reaches_zero() {
        let s = Schedule::new(1000, 0.5, Absorption::Fractional);
        let tail = &s.levels[10..];
        assert_eq!(tail.len(), 10);
        assert!(tail.iter().all(|l| l[0] == 1 && l[2] == 1 && l[3] == 1));
        assert_eq!(tail[0][1], 1994);
    }

    /// Four classes of 250 paths: every class has the same paths at every vertex, so the
    /// class a frame walks afresh is never missing where the others are.
    #[test]
    fn interleaved_classes_share_every_vertex_alike() {
        let s = Schedule::interleaved(1000, 0.5, Absorption::Fractional, 4);
        let class = Schedule::new(250, 0.5, Absorption::Fractional);
        assert_eq!(s.path_count, 1000);
        assert_eq!(s.levels.len(), class.levels.len());
        for (l, c) in s.levels.iter().zip(&class.levels) {
            assert_eq!((l[0], l[2], l[3]), (4 * c[0], c[2], c[3]));
        }
        assert_eq!(s.slot_count, 4 * class.slot_count);
        assert_eq!(
            Schedule::interleaved(1000, 0.5, Absorption::Fractional, 1),
            Schedule::new(1000, 0.5, Absorption::Fractional)
        );
    }

    #[test]
    fn roulette_keeps_every_path_at_every_vertex() {
        let s = Schedule::new(64, 0.5, Absorption::Roulette);
        assert!(s.levels.iter().all(|l| l[0] == 64 && l[2] == 1));
        assert!(s.levels.len() > 10 && s.levels.len() < MAX_VERTICES);
    }
}
