//! Light-field luminaires (Lu 14 Chapter 4): the two-plane model of Eq. 4.1, its
//! on-disk format, and luminaires generated from analytic emitters.
//!
//! In the luminaire's frame the filter plane U is z = 0 and the image plane S is z = delta;
//! light leaves toward +z. W x H basis functions Phi_m sit on a grid of pitch (du, dv) centred
//! on U's origin, basis m = j W + i at ((i - (W-1)/2) du, (j - (H-1)/2) dv): bilinear hats
//! (support +-1 pitch: Heidrich's canned light source) or quadratic B-splines (support +-1.5
//! pitches: Goesele et al.). Image m, C_m, is RGB and piecewise constant over R_s x R_t
//! texels covering [-sx/2, sx/2] x [-sy/2, sy/2] of S, texel row 0 at -sy/2. The radiance along
//! the ray from u through s is Eq. 4.1,
//!   L(u -> s) = |s - u|^4 / delta^2 * sum_m C_m(s) Phi_m(u).
//! Samplers use the luminance of C_m and scale by its colour ratio (Section 4.4).
//!
//! On disk: a TOML file and one EXR atlas beside it,
//! ```toml
//! grid = [3, 3]                 # W x H basis functions
//! pitch = [0.01, 0.01]          # metres between basis nodes on the filter plane
//! basis = "bilinear"            # or "quadratic-bspline"
//! delta = 0.05                  # metres from the filter plane to the image plane
//! image_size = [0.2, 0.2]       # metres covered by every image on the image plane
//! atlas = "images.exr"          # W R_s x H R_t texels: image (i, j) is tile (i, j)
//! ```
//! `atlas` may be a glob in the file name (`"beam_*.exr"`): a sequence of atlases of one size,
//! in name order, frame f of a render showing atlas f mod n (a luminaire whose images change,
//! as a levelling headlight's do).
//!
//! `emitters` generates luminaires from analytic emitters (`irad luminaire generate`).

pub mod emitters;

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use super::environment::{expand_glob, is_glob, split_glob};
use super::toml_arrays::exact;
use super::SceneError;
use crate::image::{exr, Image};

pub use emitters::Emitter;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Basis {
    /// Bilinear hats, support +-1 pitch (the canned light source).
    Bilinear,
    /// Quadratic B-splines, support +-1.5 pitches (Goesele et al.).
    QuadraticBSpline,
}

impl Basis {
    pub fn name(self) -> &'static str {
        match self {
            Basis::Bilinear => "bilinear",
            Basis::QuadraticBSpline => "quadratic-bspline",
        }
    }

    /// The 1D basis at x pitches from its node.
    pub fn weight(self, x: f64) -> f64 {
        let a = x.abs();
        match self {
            Basis::Bilinear => (1.0 - a).max(0.0),
            Basis::QuadraticBSpline => {
                if a < 0.5 {
                    0.75 - a * a
                } else if a < 1.5 {
                    0.5 * (1.5 - a) * (1.5 - a)
                } else {
                    0.0
                }
            }
        }
    }

    /// Half the support's width, in pitches.
    pub fn reach(self) -> f64 {
        match self {
            Basis::Bilinear => 1.0,
            Basis::QuadraticBSpline => 1.5,
        }
    }
}

/// The luminaire's geometry: everything but the images.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// W x H basis functions.
    pub grid: [usize; 2],
    /// (du, dv), metres.
    pub pitch: [f64; 2],
    pub basis: Basis,
    /// The image plane's distance from the filter plane, metres.
    pub delta: f64,
    /// (sx, sy): the images' extent on the image plane, metres.
    pub image_size: [f64; 2],
    /// (R_s, R_t): texels per image.
    pub resolution: [usize; 2],
}

impl Geometry {
    /// Node u_m of basis m.
    pub fn node(&self, m: usize) -> (f64, f64) {
        let (i, j) = (m % self.grid[0], m / self.grid[0]);
        let x = (i as f64 - (self.grid[0] - 1) as f64 / 2.0) * self.pitch[0];
        let y = (j as f64 - (self.grid[1] - 1) as f64 / 2.0) * self.pitch[1];
        (x, y)
    }

    /// Phi_m(u).
    pub fn phi(&self, m: usize, u: (f64, f64)) -> f64 {
        let (x, y) = self.node(m);
        self.basis.weight((u.0 - x) / self.pitch[0]) * self.basis.weight((u.1 - y) / self.pitch[1])
    }

    /// The centre of texel (a, b) on the image plane.
    pub fn texel_centre(&self, a: usize, b: usize) -> (f64, f64) {
        (
            ((a as f64 + 0.5) / self.resolution[0] as f64 - 0.5) * self.image_size[0],
            ((b as f64 + 0.5) / self.resolution[1] as f64 - 0.5) * self.image_size[1],
        )
    }

    pub fn images(&self) -> usize {
        self.grid[0] * self.grid[1]
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Luminaire {
    pub geometry: Geometry,
    /// Per image m (m = j W + i), R_s x R_t RGB texels, row-major (of the first atlas, for a
    /// sequence).
    pub images: Vec<Vec<Vec3>>,
    /// A sequence's images, every atlas in order (frame f of a render shows f mod len);
    /// empty for a still luminaire.
    pub sequence: Vec<Vec<Vec<Vec3>>>,
    pub source: PathBuf,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LuminaireFile {
    #[serde(deserialize_with = "exact")]
    grid: [i64; 2],
    #[serde(deserialize_with = "exact")]
    pitch: [f64; 2],
    basis: String,
    delta: f64,
    #[serde(deserialize_with = "exact")]
    image_size: [f64; 2],
    atlas: String,
}

impl Luminaire {
    /// A luminaire from an emitter's radiance L(u -> s) (u on U, s on S, RGB): image m at a
    /// texel centre s is the mean of L(u -> s) over basis m's support weighted by Phi_m (an
    /// 8 x 8 midpoint rule), times delta^2 / |s - u_m|^4, so that Eq. 4.1 gives L back at the
    /// node and, for an emitter that does not depend on s, the projection keeps its flux.
    pub fn from_emitter(
        geometry: Geometry,
        radiance: impl Fn((f64, f64), (f64, f64)) -> Vec3,
        source: &str,
    ) -> Luminaire {
        let g = geometry;
        let q = 8usize;
        let reach = g.basis.reach();
        let images = (0..g.images())
            .map(|m| {
                let (x, y) = g.node(m);
                let points: Vec<((f64, f64), f64)> = (0..q * q)
                    .map(|k| {
                        let (a, b) = ((k % q) as f64 + 0.5, (k / q) as f64 + 0.5);
                        let u = (
                            x + (2.0 * a / q as f64 - 1.0) * reach * g.pitch[0],
                            y + (2.0 * b / q as f64 - 1.0) * reach * g.pitch[1],
                        );
                        (u, g.phi(m, u))
                    })
                    .collect();
                let norm: f64 = points.iter().map(|p| p.1).sum();
                let [rs, rt] = g.resolution;
                (0..rs * rt)
                    .map(|k| {
                        let s = g.texel_centre(k % rs, k / rs);
                        let mean = points
                            .iter()
                            .fold(Vec3::ZERO, |acc, &(u, w)| acc + radiance(u, s) * w as f32)
                            / norm as f32;
                        let d2 = (s.0 - x).powi(2) + (s.1 - y).powi(2) + g.delta * g.delta;
                        mean * (g.delta * g.delta / (d2 * d2)) as f32
                    })
                    .collect()
            })
            .collect();
        Luminaire {
            geometry,
            images,
            sequence: vec![],
            source: source.into(),
        }
    }

    /// Reads `path` (the TOML) and its atlas; errors name the file, field and value.
    pub fn load(path: &Path) -> Result<Luminaire, SceneError> {
        let display = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| SceneError::Read {
            path: display.clone(),
            referenced_by: "the luminaire file".into(),
            error,
        })?;
        let f: LuminaireFile = toml::from_str(&text).map_err(|e| SceneError::File {
            file: display.clone(),
            message: e.to_string(),
        })?;
        let invalid = |field: &str, value: String, problem: &str| SceneError::Invalid {
            file: display.clone(),
            field: field.into(),
            value,
            problem: problem.into(),
        };
        let [w, h] = f.grid;
        if !(1..=64).contains(&w) || !(1..=64).contains(&h) {
            return Err(invalid(
                "grid",
                format!("[{w}, {h}]"),
                "each must be in 1..=64",
            ));
        }
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(f.pitch[0]) || !positive(f.pitch[1]) {
            return Err(invalid(
                "pitch",
                format!("{:?}", f.pitch),
                "must be finite and > 0",
            ));
        }
        if !positive(f.delta) {
            return Err(invalid(
                "delta",
                f.delta.to_string(),
                "must be finite and > 0",
            ));
        }
        if !positive(f.image_size[0]) || !positive(f.image_size[1]) {
            return Err(invalid(
                "image_size",
                format!("{:?}", f.image_size),
                "must be finite and > 0",
            ));
        }
        let basis = match f.basis.as_str() {
            "bilinear" => Basis::Bilinear,
            "quadratic-bspline" => Basis::QuadraticBSpline,
            other => {
                return Err(invalid(
                    "basis",
                    format!("{other:?}"),
                    "must be \"bilinear\" or \"quadratic-bspline\"",
                ))
            }
        };
        let folder = path.parent().unwrap_or(Path::new(""));
        let atlas_paths = if is_glob(&f.atlas) {
            let (dir, pattern) = split_glob(&f.atlas);
            if is_glob(&dir.to_string_lossy()) || pattern.contains(['[', '{']) {
                return Err(SceneError::Unsupported {
                    file: display.clone(),
                    field: "atlas".into(),
                    value: format!("{:?}", f.atlas),
                    what: "globs other than * and ? in the file name".into(),
                });
            }
            let found =
                expand_glob(&folder.join(&dir), &pattern).map_err(|error| SceneError::Read {
                    path: folder.join(&dir).display().to_string(),
                    referenced_by: format!("{display}: atlas = {:?} (its folder)", f.atlas),
                    error,
                })?;
            if found.is_empty() {
                return Err(invalid(
                    "atlas",
                    format!("{:?}", f.atlas),
                    &format!("no file in {} matches", folder.join(&dir).display()),
                ));
            }
            found
        } else {
            vec![folder.join(&f.atlas)]
        };
        let (w, h) = (w as usize, h as usize);
        let mut sequence: Vec<Vec<Vec<Vec3>>> = Vec::with_capacity(atlas_paths.len());
        let mut first_size = None;
        for atlas_path in &atlas_paths {
            let atlas = exr::read(atlas_path).map_err(|e| SceneError::File {
                file: atlas_path.display().to_string(),
                message: format!("atlas (referenced by {display}): {e:#}"),
            })?;
            let (aw, ah) = (atlas.width as usize, atlas.height as usize);
            if aw % w != 0 || ah % h != 0 || aw == 0 || ah == 0 {
                return Err(invalid(
                    "atlas",
                    format!("{:?} ({}: {aw}x{ah})", f.atlas, atlas_path.display()),
                    &format!("its size must be a multiple of the grid, {w}x{h}"),
                ));
            }
            match first_size {
                None => first_size = Some((aw, ah)),
                Some((fw, fh)) if (fw, fh) != (aw, ah) => {
                    return Err(invalid(
                        "atlas",
                        format!("{:?} ({}: {aw}x{ah})", f.atlas, atlas_path.display()),
                        &format!(
                            "every atlas of a sequence must have the size of the first, {} ({fw}x{fh})",
                            atlas_paths[0].display()
                        ),
                    ));
                }
                Some(_) => {}
            }
            if let Some(k) = atlas
                .pixels
                .iter()
                .position(|p| !p.iter().all(|c| c.is_finite() && *c >= 0.0))
            {
                return Err(SceneError::Invalid {
                    file: atlas_path.display().to_string(),
                    field: format!("texel (x {}, y {})", k % aw, k / aw),
                    value: format!("{:?}", atlas.pixels[k]),
                    problem: "must be finite and >= 0 in every channel".into(),
                });
            }
            // The lightfield method sums texels into f32 tables (column CDFs, marginals,
            // summed-area tables), so they are held to the bound on every emitter's radiance.
            let max = super::power::MAX_RADIANCE;
            if let Some(k) = atlas
                .pixels
                .iter()
                .position(|p| p.iter().any(|&c| c as f64 > max))
            {
                let brightest = atlas.pixels[k].iter().fold(0.0f32, |a, &c| a.max(c));
                return Err(SceneError::Invalid {
                    file: atlas_path.display().to_string(),
                    field: format!("texel (x {}, y {})", k % aw, k / aw),
                    value: format!("{:?}", atlas.pixels[k]),
                    problem: format!(
                        "radiance up to {brightest:.3e}, over {max:.3e}, the most irad's f32 \
                         kernels carry with room for what they compute from it; at most {} \
                         works",
                        super::power::shown(max)
                    ),
                });
            }
            let [rs, rt] = [aw / w, ah / h];
            sequence.push(
                (0..w * h)
                    .map(|m| {
                        let (i, j) = (m % w, m / w);
                        (0..rs * rt)
                            .map(|k| {
                                Vec3::from(atlas.pixels[(j * rt + k / rs) * aw + i * rs + k % rs])
                            })
                            .collect()
                    })
                    .collect(),
            );
        }
        let (aw, ah) = first_size.unwrap_or((w, h));
        let geometry = Geometry {
            grid: [w, h],
            pitch: f.pitch,
            basis,
            delta: f.delta,
            image_size: f.image_size,
            resolution: [aw / w, ah / h],
        };
        let images = sequence[0].clone();
        if sequence.len() < 2 {
            sequence.clear();
        }
        Ok(Luminaire {
            geometry,
            images,
            sequence,
            source: path.to_path_buf(),
        })
    }

    /// Whether any texel of any atlas is above zero.
    pub fn emits(&self) -> bool {
        self.frames()
            .into_iter()
            .flatten()
            .flatten()
            .any(|t| t.max_element() > 0.0)
    }

    /// The atlases a render shows in turn: the sequence, or the one still atlas.
    pub fn frames(&self) -> Vec<&Vec<Vec<Vec3>>> {
        if self.sequence.is_empty() {
            vec![&self.images]
        } else {
            self.sequence.iter().collect()
        }
    }

    /// Writes `<dir>/luminaire.toml` and `<dir>/images.exr` (a sequence: `images_000.exr`,
    /// `images_001.exr`, ... and `atlas = "images_*.exr"`); returns the TOML's path.
    pub fn write(&self, dir: &Path) -> anyhow::Result<PathBuf> {
        use anyhow::Context as _;
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create the folder", dir.display()))?;
        let g = &self.geometry;
        let [w, h] = g.grid;
        let [rs, rt] = g.resolution;
        let frames = self.frames();
        // A sequence written over an older one must not leave its extra atlases behind (the
        // glob would read them back).
        for stale in expand_glob(dir, "images_*.exr")
            .with_context(|| format!("{}: cannot list the folder", dir.display()))?
        {
            std::fs::remove_file(&stale)
                .with_context(|| format!("{}: cannot remove it", stale.display()))?;
        }
        for (f, images) in frames.iter().enumerate() {
            let mut atlas = Image::new((w * rs) as u32, (h * rt) as u32);
            for (m, image) in images.iter().enumerate() {
                let (i, j) = (m % w, m / w);
                for (k, texel) in image.iter().enumerate() {
                    atlas.pixels[(j * rt + k / rs) * w * rs + i * rs + k % rs] = texel.to_array();
                }
            }
            let name = if self.sequence.is_empty() {
                "images.exr".to_string()
            } else {
                format!("images_{f:03}.exr")
            };
            exr::write(&dir.join(name), &atlas)?;
        }
        let (atlas, what) = if self.sequence.is_empty() {
            ("images.exr", "the images are images.exr".to_string())
        } else {
            (
                "images_*.exr",
                format!(
                    "a sequence of {} atlases, images_*.exr, frame f showing f mod {}",
                    frames.len(),
                    frames.len()
                ),
            )
        };
        let toml_path = dir.join("luminaire.toml");
        let text = format!(
            "# A light-field luminaire (docs/methods/lightfield.md); {what}.\n\
             grid = [{w}, {h}]\npitch = [{:?}, {:?}]\nbasis = \"{}\"\ndelta = {:?}\n\
             image_size = [{:?}, {:?}]\natlas = \"{atlas}\"\n",
            g.pitch[0],
            g.pitch[1],
            g.basis.name(),
            g.delta,
            g.image_size[0],
            g.image_size[1]
        );
        std::fs::write(&toml_path, text)
            .with_context(|| format!("{}: cannot write it", toml_path.display()))?;
        Ok(toml_path)
    }
}

/// A luminaire placed in a scene: its filter-plane origin at `position`, its axes in world
/// space (z the emission axis toward `look_at`, y toward `up`, x = y cross z).
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedLuminaire {
    pub luminaire: Luminaire,
    pub position: Vec3,
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl PlacedLuminaire {
    /// Places `luminaire` as `[[luminaire]]` entry k of scene `file` says.
    pub fn place(
        file: &str,
        k: usize,
        luminaire: Luminaire,
        f: &super::file::LuminairePlacementFile,
    ) -> Result<PlacedLuminaire, SceneError> {
        let [position, x, y, z] = Self::frame(file, k, f)?;
        Ok(PlacedLuminaire {
            luminaire,
            position,
            x,
            y,
            z,
        })
    }

    /// The position and axes (x, y, z) `[[luminaire]]` entry k places a luminaire at.
    pub fn frame(
        file: &str,
        k: usize,
        f: &super::file::LuminairePlacementFile,
    ) -> Result<[Vec3; 4], SceneError> {
        let invalid = |field: &str, value: String, problem: &str| SceneError::Invalid {
            file: file.to_string(),
            field: format!("luminaire[{k}].{field}"),
            value,
            problem: problem.into(),
        };
        let position = Vec3::from(f.position);
        let look_at = Vec3::from(f.look_at);
        if !position.is_finite() || !look_at.is_finite() {
            return Err(invalid(
                "position",
                format!("{:?}", f.position),
                "must be finite",
            ));
        }
        for (field, v) in [("position", f.position), ("look_at", f.look_at)] {
            if v.iter()
                .any(|x| x.abs() > crate::scene::obj::MAX_COORDINATE)
            {
                return Err(invalid(
                    field,
                    format!("{v:?}"),
                    &format!(
                        "a coordinate's magnitude is over {:e}, the most irad's f32 rays handle \
                         (scale the scene down)",
                        crate::scene::obj::MAX_COORDINATE
                    ),
                ));
            }
        }
        let z = (look_at - position).normalize_or_zero();
        if z == Vec3::ZERO {
            return Err(invalid(
                "look_at",
                format!("{:?}", f.look_at),
                "must differ from position",
            ));
        }
        // Without `up`, +Y, or -Z for a luminaire aimed straight up or down.
        let up = match f.up {
            Some(up) => Vec3::from(up),
            None if z.y.abs() > 0.999 => Vec3::new(0.0, 0.0, -1.0),
            None => Vec3::Y,
        };
        let y = (up - up.dot(z) * z).normalize_or_zero();
        if y == Vec3::ZERO || !y.is_finite() {
            return Err(invalid(
                "up",
                format!("{:?}", up.to_array()),
                "must be finite and not parallel to look_at - position",
            ));
        }
        Ok([position, y.cross(z), y, z])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bases_are_partitions_of_unity() {
        for basis in [Basis::Bilinear, Basis::QuadraticBSpline] {
            for k in 0..100 {
                let x = k as f64 / 100.0;
                let sum: f64 = (-3..=3).map(|n| basis.weight(x - n as f64)).sum();
                assert!((sum - 1.0).abs() < 1e-12, "{basis:?} at {x}: {sum}");
            }
        }
    }

    fn geometry() -> Geometry {
        Geometry {
            grid: [3, 2],
            pitch: [0.02, 0.03],
            basis: Basis::QuadraticBSpline,
            delta: 0.1,
            image_size: [0.4, 0.3],
            resolution: [8, 6],
        }
    }

    #[test]
    fn written_luminaires_read_back_and_bad_files_are_refused() {
        let dir = std::env::temp_dir().join(format!("irad-luminaire-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let emitter = Emitter::Headlight {
            radius: 0.04,
            radiance: 10.0,
            sharpness: 8.0,
            tilt: 5.0,
        };
        let lum = Luminaire::from_emitter(geometry(), |u, s| emitter.radiance(u, s, 0.1), "test");
        let path = lum.write(&dir).unwrap();
        let back = Luminaire::load(&path).unwrap();
        assert_eq!(back.geometry, lum.geometry);
        assert_eq!(back.images, lum.images);
        let toml = std::fs::read_to_string(&path).unwrap();
        for (from, to, parts) in [
            (
                "basis = \"quadratic-bspline\"",
                "basis = \"cubic\"",
                vec!["basis = \"cubic\"", "bilinear"],
            ),
            (
                "grid = [3, 2]",
                "grid = [0, 2]",
                vec!["grid = [0, 2]", "1..=64"],
            ),
            ("delta = 0.1", "delta = -1.0", vec!["delta = -1", "> 0"]),
            (
                "grid = [3, 2]",
                "grid = [5, 2]",
                vec!["atlas", "multiple of the grid, 5x2"],
            ),
            (
                "atlas = \"images.exr\"",
                "atlas = \"gone.exr\"",
                vec!["gone.exr"],
            ),
            ("delta = 0.1", "delta = 0.1\ncolour = 1", vec!["colour"]),
        ] {
            std::fs::write(&path, toml.replace(from, to)).unwrap();
            let e = Luminaire::load(&path).unwrap_err().to_string();
            for part in parts {
                assert!(e.contains(part), "`{part}` not in: {e}");
            }
            assert!(
                e.contains("luminaire.toml") || e.contains("gone.exr"),
                "{e}"
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A sequence (`atlas` a glob) writes, reads back in name order and keeps its first atlas
    /// as `images`; an empty match and atlases of different sizes are refused, naming the
    /// file, field and value.
    #[test]
    fn atlas_sequences_read_back_and_bad_ones_are_refused() {
        let dir = std::env::temp_dir().join(format!("irad-luminaire-seq-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let emitter = Emitter::Reflector {
            radius: 0.04,
            radiance: 10.0,
            facet: 0.01,
            beam: 3.0,
            spread: 20.0,
            tilt: 0.0,
        };
        let frames: Vec<Luminaire> = [0.0, 4.0, 8.0]
            .iter()
            .map(|&t| {
                let e = emitter.tilted(t).unwrap();
                Luminaire::from_emitter(geometry(), |u, s| e.radiance(u, s, 0.1), "test")
            })
            .collect();
        assert_ne!(frames[0].images, frames[2].images);
        let mut lum = frames[0].clone();
        lum.sequence = frames.iter().map(|l| l.images.clone()).collect();
        let path = lum.write(&dir).unwrap();
        let back = Luminaire::load(&path).unwrap();
        assert_eq!(back.sequence, lum.sequence);
        assert_eq!(back.images, frames[0].images);
        assert_eq!(back.frames().len(), 3);
        // A shorter sequence written over it reads back alone.
        let mut two = lum.clone();
        two.sequence.truncate(2);
        two.write(&dir).unwrap();
        assert_eq!(Luminaire::load(&path).unwrap().sequence, two.sequence);
        lum.write(&dir).unwrap();
        let toml = std::fs::read_to_string(&path).unwrap();
        assert!(toml.contains("atlas = \"images_*.exr\""), "{toml}");
        std::fs::write(&path, toml.replace("images_*.exr", "beam_*.exr")).unwrap();
        let e = Luminaire::load(&path).unwrap_err().to_string();
        assert!(
            e.contains("atlas") && e.contains("beam_*.exr") && e.contains("no file"),
            "{e}"
        );
        std::fs::write(&path, &toml).unwrap();
        let small = Luminaire::from_emitter(
            Geometry {
                resolution: [4, 3],
                ..geometry()
            },
            |u, s| emitter.radiance(u, s, 0.1),
            "test",
        );
        small.write(&dir.join("small")).unwrap();
        std::fs::rename(dir.join("small/images.exr"), dir.join("images_003.exr")).unwrap();
        let e = Luminaire::load(&path).unwrap_err().to_string();
        assert!(
            e.contains("images_003.exr")
                && e.contains("size of the first")
                && e.contains("images_000.exr"),
            "{e}"
        );
        assert!(Emitter::Disk {
            radius: 0.1,
            radiance: 1.0
        }
        .tilted(3.0)
        .is_none());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
