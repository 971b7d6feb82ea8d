//! Luminaires generated from analytic emitters, as `irad luminaire generate` makes them: the
//! emitters (a Lambertian disk, a ringed headlight, a faceted reflector), the command's options
//! (`GenerateOptions`, one field a flag), the checks on them before any work (sizes against
//! what a GPU binds and the memory the host has), and the generation itself: the emitter
//! evaluated over the basis grid, once per frame of a tilt sweep for a sequence.
//!
//! The errors name the command's flags (`--grid`, `--radius`...): the options mirror them, and
//! the command prints the errors as they are.

use glam::Vec3;

use super::{Basis, Geometry, Luminaire};

/// Which analytic emitter `GenerateOptions` generates (`--emitter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmitterKind {
    /// `Emitter::Disk`.
    Disk,
    /// `Emitter::Headlight`, sharpness 12, tilted 3 degrees down.
    Headlight,
    /// `Emitter::Reflector`, untilted.
    Reflector,
}

/// Frames a sequence has at most (`--frames`).
pub const MAX_FRAMES: u32 = 256;
/// Basis functions along a side of the filter plane's grid at most (`--grid`).
pub const MAX_GRID: u32 = 64;
/// Texels along a side of an image at most (`--resolution`); the CLI refuses more when it
/// parses the flag, with the same limit.
pub const MAX_IMAGE_RESOLUTION: u32 = 4096;

/// What `irad luminaire generate` builds: its flags, less the output folder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GenerateOptions {
    pub emitter: EmitterKind,
    /// Basis functions on the filter plane, W x H (at most 64 x 64).
    pub grid: (u32, u32),
    /// Texels per image, W x H (at most 4096 x 4096).
    pub resolution: (u32, u32),
    pub basis: Basis,
    /// The emitter's radius in metres; the basis grid spans it.
    pub radius: f64,
    /// The emitter's peak radiance.
    pub radiance: f64,
    /// Reflector: the facets' side, metres.
    pub facet: f64,
    /// Reflector: each facet's beam width (Gaussian standard deviation), degrees.
    pub beam: f64,
    /// Reflector: the facets aim within +-spread degrees horizontally and up to spread degrees
    /// down.
    pub spread: f64,
    /// Atlases to write, 1..=MAX_FRAMES: more than one is a sequence, the beam lowered by
    /// `sweep` over them (headlight and reflector only).
    pub frames: u32,
    /// Degrees the beam is lowered from the first atlas to the last, within +-45.
    pub sweep: f64,
    /// The image plane's distance from the filter plane, metres.
    pub delta: f64,
    /// The images' extent on the image plane, metres (square).
    pub image_size: f64,
}

/// Why `GenerateOptions` cannot be generated. The messages are the command's, flags named.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    /// A size, radiance or angle that must be positive is not (or is not finite).
    #[error("--{flag} {value}: must be finite and > 0")]
    NotPositive { flag: &'static str, value: f64 },
    /// No frames, or more than MAX_FRAMES (the command's flag parser refuses these first).
    #[error("--frames {0}: must be 1..={MAX_FRAMES}")]
    Frames(u32),
    /// An empty grid or image (the command's flag parser refuses these first).
    #[error(
        "--grid {}x{} --resolution {}x{}: must be at least 1x1",
        .grid.0,
        .grid.1,
        .resolution.0,
        .resolution.1
    )]
    Empty {
        grid: (u32, u32),
        resolution: (u32, u32),
    },
    /// A grid over 64 x 64 or images over 4096 x 4096.
    #[error("--grid at most 64x64 and --resolution at most 4096x4096")]
    TooLarge,
    /// The atlases' buffer on the GPU would be over 4 GiB.
    #[error(
        "--grid {}x{} --resolution {}x{} --frames {frames}: {texels} texels an atlas, a {:.1} GiB \
         buffer on the GPU, over the 4 GiB any Vulkan device binds as one storage buffer (fewer \
         images, texels or frames)",
        .grid.0,
        .grid.1,
        .resolution.0,
        .resolution.1,
        gib(*.bytes)
    )]
    GpuBuffer {
        grid: (u32, u32),
        resolution: (u32, u32),
        frames: u32,
        texels: u64,
        bytes: u64,
    },
    /// Generation would need more memory than the host has available.
    #[error(
        "--grid {}x{} --resolution {}x{} --frames {frames}: generating needs {:.1} GiB of memory, \
         over the {:.1} GiB available",
        .grid.0,
        .grid.1,
        .resolution.0,
        .resolution.1,
        gib(*.needed),
        gib(*.available)
    )]
    HostMemory {
        grid: (u32, u32),
        resolution: (u32, u32),
        frames: u32,
        needed: u64,
        available: u64,
    },
    /// A sweep that is not finite or over 45 degrees either way.
    #[error("--sweep {0}: must be finite and within +-45 degrees")]
    Sweep(f64),
    /// A sequence of the disk, which has no direction to tilt.
    #[error(
        "--frames {0}: the disk does not change; a sequence needs --emitter headlight or reflector"
    )]
    StillEmitter(u32),
}

/// Bytes in GiB, for messages.
fn gib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 30) as f64
}

/// Memory available to a new allocation (Linux: /proc/meminfo MemAvailable), when known; for
/// `GenerateOptions::check`.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

impl GenerateOptions {
    /// Checks the options before any work, in the command's order: positive sizes, the grid
    /// and resolution limits, the GPU buffer (at most 4 GiB), the host's memory (against
    /// `available_memory`, skipped when None), then the sweep and that only a headlight or
    /// reflector makes a sequence. `warn` gets a warning (no "warning:" prefix) for an atlas
    /// over the 128 MiB every device binds, at its place in that order, so a command that
    /// fails on a later check has printed it first.
    pub fn check(
        &self,
        available_memory: Option<u64>,
        mut warn: impl FnMut(String),
    ) -> Result<(), GenerateError> {
        if !(1..=MAX_FRAMES).contains(&self.frames) {
            return Err(GenerateError::Frames(self.frames));
        }
        for (flag, value) in [
            ("radius", self.radius),
            ("radiance", self.radiance),
            ("delta", self.delta),
            ("image-size", self.image_size),
            ("facet", self.facet),
            ("beam", self.beam),
            ("spread", self.spread),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(GenerateError::NotPositive { flag, value });
            }
        }
        let (grid, resolution) = (self.grid, self.resolution);
        if grid.0 == 0 || grid.1 == 0 || resolution.0 == 0 || resolution.1 == 0 {
            return Err(GenerateError::Empty { grid, resolution });
        }
        if !(grid.0 <= MAX_GRID
            && grid.1 <= MAX_GRID
            && resolution.0 <= MAX_IMAGE_RESOLUTION
            && resolution.1 <= MAX_IMAGE_RESOLUTION)
        {
            return Err(GenerateError::TooLarge);
        }
        // Sizes checked before any work, so a luminaire too large is refused at once with its
        // size: the renderer holds each atlas as one storage buffer of 16 bytes a texel (at most
        // 4 GiB on any device, 128 MiB guaranteed), and generation holds every frame's images in
        // memory at 12 bytes a texel, twice while writing.
        let texels = u64::from(grid.0 * grid.1) * u64::from(resolution.0) * u64::from(resolution.1);
        // A sequence's atlases share one buffer (lightfield/tables.rs), beside the current frame's;
        // generation holds every frame's images, the first twice for a sequence, and one atlas.
        let frames = u64::from(self.frames);
        let gpu_bytes = texels * 16 * if frames > 1 { frames } else { 1 };
        let host_bytes = texels * 12 * (frames + 1 + u64::from(frames > 1));
        if gpu_bytes > u64::from(u32::MAX) {
            return Err(GenerateError::GpuBuffer {
                grid,
                resolution,
                frames: self.frames,
                texels,
                bytes: gpu_bytes,
            });
        }
        if let Some(available) = available_memory {
            if host_bytes > available {
                return Err(GenerateError::HostMemory {
                    grid,
                    resolution,
                    frames: self.frames,
                    needed: host_bytes,
                    available,
                });
            }
        }
        if gpu_bytes > 1 << 27 {
            warn(format!(
                "the atlas is a {:.2} GiB buffer on the GPU, over the 128 MiB every Vulkan \
                 device binds (maxStorageBufferRange; `irad info` shows a device's)",
                gib(gpu_bytes)
            ));
        }
        if !(self.sweep.is_finite() && self.sweep.abs() <= 45.0) {
            return Err(GenerateError::Sweep(self.sweep));
        }
        self.emitters().map(|_| ())
    }

    /// The luminaire's geometry: the grid spans the emitter's diameter (a single node sits at
    /// its centre).
    pub fn geometry(&self) -> Geometry {
        let grid = [self.grid.0 as usize, self.grid.1 as usize];
        let pitch = |n: usize| {
            if n > 1 {
                2.0 * self.radius / (n - 1) as f64
            } else {
                2.0 * self.radius
            }
        };
        Geometry {
            grid,
            pitch: [pitch(grid[0]), pitch(grid[1])],
            basis: self.basis,
            delta: self.delta,
            image_size: [self.image_size, self.image_size],
            resolution: [self.resolution.0 as usize, self.resolution.1 as usize],
        }
    }

    /// The emitter of the first frame.
    pub fn emitter(&self) -> Emitter {
        let (radius, radiance) = (self.radius, self.radiance);
        match self.emitter {
            EmitterKind::Disk => Emitter::Disk { radius, radiance },
            EmitterKind::Headlight => Emitter::Headlight {
                radius,
                radiance,
                sharpness: 12.0,
                tilt: 3.0,
            },
            EmitterKind::Reflector => Emitter::Reflector {
                radius,
                radiance,
                facet: self.facet,
                beam: self.beam,
                spread: self.spread,
                tilt: 0.0,
            },
        }
    }

    /// Degrees each frame's beam is lowered by: from 0 at the first to `sweep` at the last,
    /// evenly (one frame: 0).
    pub fn tilts(&self) -> Vec<f64> {
        (0..self.frames)
            .map(|f| self.sweep * f as f64 / (self.frames.max(2) - 1) as f64)
            .collect()
    }

    /// Each frame's emitter: the first frame's tilted by `tilts`, or the emitter alone for
    /// one frame; a sequence of the disk is refused.
    fn emitters(&self) -> Result<Vec<Emitter>, GenerateError> {
        let emitter = self.emitter();
        self.tilts()
            .iter()
            .map(|&t| emitter.tilted(t))
            .collect::<Option<Vec<Emitter>>>()
            .filter(|_| self.frames > 1)
            .map_or_else(
                || {
                    if self.frames == 1 {
                        Ok(vec![emitter])
                    } else {
                        Err(GenerateError::StillEmitter(self.frames))
                    }
                },
                Ok,
            )
    }

    /// Generates the luminaire: each frame's images (`progress` is called after each), and for
    /// more than one frame the sequence of every frame's images, the first frame's as
    /// `images`. Refuses what `check` refuses, bar the host's memory (the caller checks that,
    /// passing `available_memory()` to `check`). The caller writes it (`Luminaire::write`).
    pub fn generate(&self, mut progress: impl FnMut()) -> Result<Luminaire, GenerateError> {
        self.check(None, |_| {})?;
        let geometry = self.geometry();
        let delta = self.delta;
        let mut frames: Vec<Luminaire> = self
            .emitters()?
            .iter()
            .map(|e| {
                let l = Luminaire::from_emitter(
                    geometry,
                    |u, s| e.radiance(u, s, delta),
                    &format!("{e:?}"),
                );
                progress();
                l
            })
            .collect();
        let mut luminaire = frames.remove(0);
        if !frames.is_empty() {
            luminaire.sequence = std::iter::once(luminaire.images.clone())
                .chain(frames.into_iter().map(|l| l.images))
                .collect();
        }
        Ok(luminaire)
    }
}

/// The analytic emitters `irad luminaire generate` turns into luminaires.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Emitter {
    /// A uniform Lambertian disk of `radius` and `radiance` in the filter plane: on its axis
    /// at height h the scalar irradiance is 2 pi L (1 - h / sqrt(h^2 + r^2)).
    Disk { radius: f64, radiance: f64 },
    /// A headlight: a disk of `radius` with a reflector's rings of brightness, emitting a
    /// lobe about +z tilted `tilt` degrees down (-y), exponent `sharpness`, cut off above the
    /// horizontal (a low beam's cut-off line), warm white.
    Headlight {
        radius: f64,
        radiance: f64,
        sharpness: f64,
        tilt: f64,
    },
    /// A headlight with a faceted reflector and a cut-off (a bike light's, say): the disk of
    /// `radius` is cut into square facets of side `facet`, and each throws a narrow Gaussian
    /// beam (standard deviation `beam` degrees) in its own direction, chosen by a hash of the
    /// facet, uniformly within +-`spread` degrees horizontally and 0 to `spread` degrees
    /// down, with a brightness from 0.5 to 1. Nothing leaves above the horizontal (the
    /// cut-off line). The whole pattern is lowered by `tilt` degrees. The beam pattern is the
    /// sum of the facets' beams, as with real reflectors, so each basis function's image is a
    /// spray of spots over the image plane, and a point sees few of them: the case Lu's
    /// restriction is made for.
    Reflector {
        radius: f64,
        radiance: f64,
        facet: f64,
        beam: f64,
        spread: f64,
        tilt: f64,
    },
}

impl Emitter {
    /// The emitter lowered by `degrees` more (a levelling headlight's motion); None for the
    /// disk, which has no direction to tilt.
    pub fn tilted(self, degrees: f64) -> Option<Emitter> {
        match self {
            Emitter::Disk { .. } => None,
            Emitter::Headlight {
                radius,
                radiance,
                sharpness,
                tilt,
            } => Some(Emitter::Headlight {
                radius,
                radiance,
                sharpness,
                tilt: tilt + degrees,
            }),
            Emitter::Reflector {
                radius,
                radiance,
                facet,
                beam,
                spread,
                tilt,
            } => Some(Emitter::Reflector {
                radius,
                radiance,
                facet,
                beam,
                spread,
                tilt: tilt + degrees,
            }),
        }
    }

    /// L(u -> s) for a luminaire whose image plane is `delta` above the filter plane.
    pub fn radiance(&self, u: (f64, f64), s: (f64, f64), delta: f64) -> Vec3 {
        match *self {
            Emitter::Disk { radius, radiance } => {
                if u.0 * u.0 + u.1 * u.1 <= radius * radius {
                    Vec3::splat(radiance as f32)
                } else {
                    Vec3::ZERO
                }
            }
            Emitter::Headlight {
                radius,
                radiance,
                sharpness,
                tilt,
            } => {
                let r2 = (u.0 * u.0 + u.1 * u.1) / (radius * radius);
                if r2 > 1.0 {
                    return Vec3::ZERO;
                }
                // The reflector's rings.
                let rings = 0.6 + 0.4 * (r2.sqrt() * 5.0 * std::f64::consts::PI).cos().powi(2);
                let d = glam::DVec3::new(s.0 - u.0, s.1 - u.1, delta).normalize();
                if d.y > 0.02 {
                    return Vec3::ZERO;
                }
                let t = tilt.to_radians();
                let axis = glam::DVec3::new(0.0, -t.sin(), t.cos());
                let lobe = d.dot(axis).max(0.0).powf(sharpness);
                Vec3::new(1.0, 0.93, 0.8) * (radiance * rings * lobe) as f32
            }
            Emitter::Reflector {
                radius,
                radiance,
                facet,
                beam,
                spread,
                tilt,
            } => {
                if u.0 * u.0 + u.1 * u.1 > radius * radius {
                    return Vec3::ZERO;
                }
                let (fx, fy) = ((u.0 / facet).floor(), (u.1 / facet).floor());
                let (ax, ay, brightness) = facet_aim(fx as i64, fy as i64, spread);
                let (dx, dy) = (s.0 - u.0, s.1 - u.1);
                let (tx, ty) = (
                    dx.atan2(delta).to_degrees(),
                    dy.atan2(delta).to_degrees() + tilt,
                );
                if ty > 0.0 {
                    return Vec3::ZERO;
                }
                let (ex, ey) = ((tx - ax) / beam, (ty - ay) / beam);
                let lobe = (-0.5 * (ex * ex + ey * ey)).exp();
                Vec3::new(1.0, 0.95, 0.85) * (radiance * brightness * lobe) as f32
            }
        }
    }
}

/// A reflector facet's aim (horizontal and vertical degrees, + right and up) and brightness,
/// from a hash of its grid cell.
fn facet_aim(i: i64, j: i64, spread: f64) -> (f64, f64, f64) {
    let h = crate::sampling::pcg::hash(&[i as u32, j as u32, 0x6661]);
    let unit = |k: u32| crate::sampling::pcg::hash(&[h, k]) as f64 / 4294967296.0;
    (
        spread * (2.0 * unit(0) - 1.0),
        -spread * unit(1),
        0.5 + 0.5 * unit(2),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The command's defaults, on a small grid.
    fn options() -> GenerateOptions {
        GenerateOptions {
            emitter: EmitterKind::Headlight,
            grid: (2, 2),
            resolution: (4, 4),
            basis: Basis::QuadraticBSpline,
            radius: 0.06,
            radiance: 20.0,
            facet: 0.012,
            beam: 2.0,
            spread: 30.0,
            frames: 1,
            sweep: 0.0,
            delta: 0.05,
            image_size: 0.3,
        }
    }

    /// `options` changed by `f`, checked with `available` bytes of memory: the error's
    /// message, or the warnings.
    fn check(
        available: Option<u64>,
        f: impl FnOnce(&mut GenerateOptions),
    ) -> Result<Vec<String>, String> {
        let mut o = options();
        f(&mut o);
        let mut warnings = Vec::new();
        o.check(available, |w| warnings.push(w))
            .map(|()| warnings)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn each_check_refuses_with_the_commands_message() {
        assert_eq!(check(Some(1 << 30), |_| {}), Ok(vec![]));
        assert_eq!(
            check(None, |o| o.delta = 0.0).unwrap_err(),
            "--delta 0: must be finite and > 0"
        );
        assert_eq!(
            check(None, |o| o.image_size = f64::NAN).unwrap_err(),
            "--image-size NaN: must be finite and > 0"
        );
        assert_eq!(
            check(None, |o| o.grid = (65, 1)).unwrap_err(),
            "--grid at most 64x64 and --resolution at most 4096x4096"
        );
        assert_eq!(
            check(None, |o| o.resolution = (0, 4)).unwrap_err(),
            "--grid 2x2 --resolution 0x4: must be at least 1x1"
        );
        assert_eq!(
            check(None, |o| o.frames = 0).unwrap_err(),
            "--frames 0: must be 1..=256"
        );
        // tests/cli.rs's 824 GB atlas.
        assert_eq!(
            check(None, |o| {
                o.grid = (64, 64);
                o.resolution = (4096, 4096);
            })
            .unwrap_err(),
            "--grid 64x64 --resolution 4096x4096 --frames 1: 68719476736 texels an atlas, a \
             1024.0 GiB buffer on the GPU, over the 4 GiB any Vulkan device binds as one storage \
             buffer (fewer images, texels or frames)"
        );
        // 16 x 256 x 256 texels, 12 bytes each, twice: 24 MiB.
        let big = |o: &mut GenerateOptions| {
            o.grid = (4, 4);
            o.resolution = (256, 256);
        };
        assert_eq!(
            check(Some(16 << 20), big).unwrap_err(),
            "--grid 4x4 --resolution 256x256 --frames 1: generating needs 0.0 GiB of memory, \
             over the 0.0 GiB available"
        );
        assert!(check(Some(24 << 20), big).is_ok());
        assert!(check(None, big).is_ok(), "memory unknown: not checked");
        assert_eq!(
            check(None, |o| o.sweep = -46.0).unwrap_err(),
            "--sweep -46: must be finite and within +-45 degrees"
        );
    }

    /// An atlas over 128 MiB warns, and still warns when a later check refuses the options
    /// (the command printed the warning before the error).
    #[test]
    fn a_large_atlas_warns() {
        let large = |o: &mut GenerateOptions| {
            o.grid = (8, 8);
            o.resolution = (512, 512);
        };
        assert_eq!(
            check(None, large),
            Ok(vec![
                "the atlas is a 0.25 GiB buffer on the GPU, over the 128 MiB every Vulkan device \
                 binds (maxStorageBufferRange; `irad info` shows a device's)"
                    .to_string()
            ])
        );
        let mut o = options();
        large(&mut o);
        o.sweep = 90.0;
        let mut warnings = 0;
        assert!(o.check(None, |_| warnings += 1).is_err());
        assert_eq!(warnings, 1);
    }

    #[test]
    fn the_sweep_lowers_the_beam_from_0_to_sweep() {
        let mut o = options();
        o.frames = 5;
        o.sweep = 8.0;
        assert_eq!(o.tilts(), [0.0, 2.0, 4.0, 6.0, 8.0]);
        o.frames = 1;
        assert_eq!(o.tilts(), [0.0]);
    }

    #[test]
    fn the_disk_makes_no_sequence() {
        let mut o = options();
        o.emitter = EmitterKind::Disk;
        assert!(check(None, |o| o.emitter = EmitterKind::Disk).is_ok());
        o.frames = 2;
        let message = "--frames 2: the disk does not change; a sequence needs --emitter \
                       headlight or reflector";
        assert_eq!(o.check(None, |_| {}).unwrap_err().to_string(), message);
        assert_eq!(o.generate(|| {}).unwrap_err().to_string(), message);
    }

    #[test]
    fn generate_makes_one_image_a_basis_function_and_a_frame_a_progress_step() {
        let mut o = options();
        o.emitter = EmitterKind::Reflector;
        let mut steps = 0;
        let still = o.generate(|| steps += 1).unwrap();
        assert_eq!(steps, 1);
        assert_eq!(still.images.len(), 4);
        assert!(still.images.iter().all(|image| image.len() == 16));
        assert!(still.sequence.is_empty());
        assert_eq!(still.geometry, o.geometry());
        assert_eq!(
            still.geometry.pitch,
            [0.12, 0.12],
            "the grid spans the diameter"
        );

        o.frames = 3;
        o.sweep = 6.0;
        steps = 0;
        let seq = o.generate(|| steps += 1).unwrap();
        assert_eq!(steps, 3);
        assert_eq!(seq.sequence.len(), 3);
        assert_eq!(seq.sequence[0], seq.images);
        assert_eq!(seq.images, still.images, "the first frame is untilted");
        assert_ne!(seq.sequence[0], seq.sequence[2]);
        assert!(seq.sequence.iter().all(|atlas| atlas.len() == 4));
    }
}
