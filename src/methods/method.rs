//! The methods by name: one `Method` value holds a method and all its settings, reads them
//! from named parameters (the vocabulary of `irad render`'s flags, used by suite files), lists
//! them for records, says when a method declines a scene, and runs it. `Renderers` keeps each
//! method's kernels, built on first use, so a benchmark that renders many times compiles its
//! pipelines once.

use std::cell::OnceCell;
use std::collections::BTreeMap;

use serde_json::json;
use thiserror::Error;

use crate::gpu::{Context, GpuError};
use crate::methods::bir::{Bir, BirError, BirSettings, Strategy};
use crate::methods::bundles::directions::DirectionDensity;
use crate::methods::bundles::light_vertices::LightSelection;
use crate::methods::bundles::{
    Bundles, BundlesError, BundlesSettings, Strategy as BundlesStrategy, Suppression,
};
use crate::methods::compensation::{ClampSettings, VplClamp};
use crate::methods::direct::MAX_DIRECT_SPP;
use crate::methods::envmap::{Env, EnvError, EnvSettings, Strategy as EnvStrategy};
use crate::methods::gbuffer::PixelSampling;
use crate::methods::ir::schedule::Absorption;
use crate::methods::ir::{DirectLight, InstantRadiosity, IrError, IrSettings};
use crate::methods::lightfield::{
    Lightfield, LightfieldError, LightfieldSettings, Strategy as LightfieldStrategy,
};
use crate::methods::rebuild::TableRebuild;
use crate::methods::reference::{Reference, ReferenceSettings};
use crate::methods::RenderOutput;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

/// Every method irad has, by the name `--method` and suite files use.
pub const METHOD_NAMES: &[&str] = &["reference", "ir", "bir", "bundles", "env", "lightfield"];

#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    Reference(ReferenceSettings),
    Ir(IrSettings),
    Bir(BirSettings),
    Bundles(BundlesSettings),
    Env(EnvSettings),
    Lightfield(LightfieldSettings),
}

/// A parameter a method cannot take: `method: key = value: problem`.
#[derive(Debug, Error, PartialEq)]
pub enum ParamError {
    #[error("unknown method `{0}` (irad has: {names})", names = METHOD_NAMES.join(", "))]
    UnknownMethod(String),
    #[error("{method}: {key} = {value}: {problem}")]
    Value {
        method: String,
        key: String,
        value: String,
        problem: String,
    },
}

impl Method {
    pub fn name(&self) -> &'static str {
        match self {
            Method::Reference(_) => "reference",
            Method::Ir(_) => "ir",
            Method::Bir(_) => "bir",
            Method::Bundles(_) => "bundles",
            Method::Env(_) => "env",
            Method::Lightfield(_) => "lightfield",
        }
    }

    pub fn seed(&self) -> u32 {
        match self {
            Method::Reference(s) => s.seed,
            Method::Ir(s) => s.seed,
            Method::Bir(s) => s.seed,
            Method::Bundles(s) => s.seed,
            Method::Env(s) => s.seed,
            Method::Lightfield(s) => s.seed,
        }
    }

    /// The same method and settings with another seed.
    pub fn with_seed(&self, seed: u32) -> Method {
        let mut m = self.clone();
        match &mut m {
            Method::Reference(s) => s.seed = seed,
            Method::Ir(s) => s.seed = seed,
            Method::Bir(s) => s.seed = seed,
            Method::Bundles(s) => s.seed = seed,
            Method::Env(s) => s.seed = seed,
            Method::Lightfield(s) => s.seed = seed,
        }
        m
    }

    /// Samples as the method counts them, for progress: samples per pixel, or frames.
    pub fn samples(&self) -> u64 {
        match self {
            Method::Reference(s) => s.spp as u64,
            Method::Ir(s) => s.frames as u64,
            Method::Bir(s) => s.frames as u64,
            Method::Bundles(s) => s.frames as u64,
            Method::Env(s) => s.frames as u64,
            Method::Lightfield(s) => s.frames as u64,
        }
    }

    /// The parameter a time budget calibrates (`time_ms` in a suite): the reference's `spp`,
    /// every other method's `frames`; `samples()` reads it.
    pub fn count_key(&self) -> &'static str {
        match self {
            Method::Reference(_) => "spp",
            _ => "frames",
        }
    }

    /// The same method and settings with `count_key()` set to `count`.
    pub fn with_count(&self, count: u32) -> Method {
        let mut m = self.clone();
        match &mut m {
            Method::Reference(s) => s.spp = count,
            Method::Ir(s) => s.frames = count,
            Method::Bir(s) => s.frames = count,
            Method::Bundles(s) => s.frames = count,
            Method::Env(s) => s.frames = count,
            Method::Lightfield(s) => s.frames = count,
        }
        m
    }

    /// Work in units that scale a method's cost at a fixed resolution, for time estimates:
    /// samples per pixel, or frames times light paths.
    pub fn work(&self) -> f64 {
        match self {
            Method::Reference(s) => s.spp as f64,
            Method::Ir(s) => s.frames as f64 * s.paths as f64,
            Method::Bir(s) => s.frames as f64 * s.vpls as f64,
            Method::Bundles(s) => s.frames as f64 * s.iterations as f64,
            Method::Env(s) => s.frames as f64 * s.spp as f64,
            Method::Lightfield(s) => s.frames as f64 * s.spp as f64,
        }
    }

    /// The method's settings by the names `from_params` reads (the seed apart), sorted, so a
    /// record's parameters can be fed back. A bias that is off is not listed.
    pub fn parameters(&self) -> BTreeMap<String, serde_json::Value> {
        let mut p = BTreeMap::new();
        match self {
            Method::Reference(s) => {
                p.insert("spp".into(), json!(s.spp));
                p.insert("max_depth".into(), json!(s.max_depth));
                p.insert("roulette_depth".into(), json!(s.roulette_depth));
                if let Some(m) = s.alpha_frames {
                    p.insert("alpha_frames".into(), json!(m));
                }
                p.insert(
                    "pixel_centres".into(),
                    json!(s.pixels == PixelSampling::Centres),
                );
            }
            Method::Ir(s) => {
                p.insert("direct_spp".into(), json!(s.direct_spp));
                p.insert("vpls".into(), json!(s.paths));
                p.insert("frames".into(), json!(s.frames));
                p.insert(
                    "absorption".into(),
                    json!(match s.absorption {
                        Absorption::Fractional => "fractional",
                        Absorption::Roulette => "roulette",
                    }),
                );
                // "auto" or b (0: unclamped); compensate false: the plain clamp's named bias.
                p.insert("clamp".into(), s.clamp.clamp_param());
                p.insert("compensate".into(), json!(s.clamp.compensate));
                p.insert("interleave".into(), json!(s.interleave));
                p.insert(
                    "pixel_centres".into(),
                    json!(s.pixels == PixelSampling::Centres),
                );
                p.insert(
                    "direct".into(),
                    json!(match s.direct {
                        DirectLight::NextEvent => "nee",
                        DirectLight::Vpl => "vpl",
                    }),
                );
            }
            Method::Bir(s) => {
                p.insert("direct_spp".into(), json!(s.direct_spp));
                p.insert("vpls".into(), json!(s.vpls));
                p.insert("frames".into(), json!(s.frames));
                p.insert("strategy".into(), json!(s.strategy.name()));
                p.insert("pool".into(), json!(s.pool));
                p.insert("light_samples".into(), json!(s.light_samples));
                p.insert("connections".into(), json!(s.connections));
                p.insert("depth".into(), json!(s.depth));
                p.insert("ratio".into(), json!(s.ratio));
                p.insert("floor".into(), json!(s.floor));
                p.insert("power_samples".into(), json!(s.power_samples));
                p.insert("batch".into(), json!(s.batch));
                p.insert("light_cdf".into(), json!(s.light_cdf));
                p.insert("clamp".into(), s.clamp.clamp_param());
                p.insert("compensate".into(), json!(s.clamp.compensate));
                p.insert("adaptive".into(), json!(s.adaptive));
                p.insert(
                    "pixel_centres".into(),
                    json!(s.pixels == PixelSampling::Centres),
                );
            }
            Method::Bundles(s) => {
                p.insert("direct_spp".into(), json!(s.direct_spp));
                p.insert("iterations".into(), json!(s.iterations));
                p.insert("frames".into(), json!(s.frames));
                p.insert("strategy".into(), json!(s.strategy.name()));
                p.insert(
                    "heuristic".into(),
                    json!(if s.beta == 1.0 { "balance" } else { "power" }),
                );
                p.insert("two_bounce".into(), json!(s.two_bounce));
                if s.two_bounce {
                    // 0: unclamped (the clamp is a named, measured bias).
                    p.insert("two_bounce_clamp".into(), s.two_bounce_clamp.clamp_param());
                    // false: the paper's clamp, a named bias.
                    p.insert("compensate".into(), json!(s.two_bounce_clamp.compensate));
                }
                p.insert("glossy".into(), json!(s.suppression.name()));
                match s.suppression {
                    Suppression::None => {}
                    Suppression::Roughness { m_prime } => {
                        p.insert("roughness_m".into(), json!(m_prime));
                    }
                    Suppression::Contribution { max } => {
                        p.insert("contribution_clamp".into(), json!(max));
                    }
                }
                p.insert("lights".into(), json!(s.lights.name()));
                p.insert("directions".into(), json!(s.directions.name()));
                if let Some(offset) = s.env_offset {
                    p.insert("env_offset".into(), json!(offset));
                }
                p.insert("rebuild_tables".into(), json!(s.rebuild.name()));
                p.insert(
                    "pixel_centres".into(),
                    json!(s.pixels == PixelSampling::Centres),
                );
            }
            Method::Env(s) => {
                p.insert("spp".into(), json!(s.spp));
                p.insert("frames".into(), json!(s.frames));
                p.insert("strategy".into(), json!(s.strategy.name()));
                p.insert("face_resolution".into(), json!(s.face_resolution));
                p.insert("light_only".into(), json!(s.light_only));
                p.insert("integer_counts".into(), json!(s.integer_counts));
                if let Some(m) = s.alpha_samples {
                    p.insert("alpha_samples".into(), json!(m));
                }
                p.insert("shadows".into(), json!(s.shadows));
                p.insert("shared_samples".into(), json!(s.shared_samples));
                p.insert("rebuild_tables".into(), json!(s.rebuild.name()));
                p.insert(
                    "pixel_centres".into(),
                    json!(s.pixels == PixelSampling::Centres),
                );
            }
            Method::Lightfield(s) => {
                p.insert("spp".into(), json!(s.spp));
                p.insert("frames".into(), json!(s.frames));
                p.insert("k_max".into(), json!(s.k_max));
                p.insert("strategy".into(), json!(s.strategy.name()));
                p.insert(
                    "search".into(),
                    json!(if s.secant { "secant" } else { "binary" }),
                );
                p.insert("shared_samples".into(), json!(s.shared_samples));
                p.insert("averaged_visibility".into(), json!(s.averaged_visibility));
                p.insert("shadows".into(), json!(s.shadows));
                if s.sampling_only {
                    p.insert("sampling_only".into(), json!(true));
                }
                p.insert("rebuild_tables".into(), json!(s.rebuild.name()));
                p.insert(
                    "pixel_centres".into(),
                    json!(s.pixels == PixelSampling::Centres),
                );
            }
        }
        p
    }

    /// `name` with `params` over its defaults (those of `irad render`). Keys are the flags of
    /// `irad render` with `-` written `_`: reference takes spp, max_depth, roulette_depth,
    /// pixel_centres, seed; ir takes vpls, frames, absorption, clamp ("auto" or a number),
    /// compensate, interleave, direct, direct_spp, pixel_centres, seed; bir takes vpls, frames, strategy,
    /// pool, light_samples, ratio, floor, power_samples, batch, clamp, compensate,
    /// direct_spp, pixel_centres, seed; bundles takes iterations, frames, strategy, heuristic, two_bounce,
    /// two_bounce_clamp, compensate, glossy, roughness_m, contribution_clamp, lights, directions,
    /// env_offset, rebuild_tables, direct_spp, pixel_centres, seed; env takes spp, frames, strategy,
    /// face_resolution, light_only, integer_counts, alpha_samples, shadows, shared_samples,
    /// rebuild_tables,
    /// pixel_centres, seed.
    pub fn from_params(name: &str, params: &toml::Table) -> Result<Method, ParamError> {
        let mut reader = Params {
            method: name,
            params,
        };
        let method = match name {
            "reference" => {
                let d = ReferenceSettings::default();
                let max_depth = reader.uint("max_depth", d.max_depth, 1, u32::MAX)?;
                if let Some(v) = reader.params.get("alpha_frames").filter(|_| max_depth != 1) {
                    return Err(reader.error(
                        "alpha_frames",
                        v,
                        "splits the direct light only: needs max_depth = 1",
                    ));
                }
                Method::Reference(ReferenceSettings {
                    spp: reader.uint("spp", d.spp, 1, u32::MAX)?,
                    seed: reader.uint("seed", d.seed, 0, u32::MAX)?,
                    max_depth,
                    roulette_depth: reader.uint("roulette_depth", d.roulette_depth, 0, u32::MAX)?,
                    alpha_frames: match reader.params.contains_key("alpha_frames") {
                        true => Some(reader.uint("alpha_frames", 0, 0, u32::MAX)?),
                        false => d.alpha_frames,
                    },
                    pixels: reader.pixels()?,
                })
            }
            "ir" => {
                let d = IrSettings::default();
                Method::Ir(IrSettings {
                    paths: reader.uint("vpls", d.paths, 1, 1 << 20)?,
                    frames: reader.uint("frames", d.frames, 1, u32::MAX)?,
                    seed: reader.uint("seed", d.seed, 0, u32::MAX)?,
                    absorption: match reader.choice("absorption", &["fractional", "roulette"])? {
                        Some("roulette") => Absorption::Roulette,
                        Some(_) => Absorption::Fractional,
                        None => d.absorption,
                    },
                    clamp: reader.clamp("clamp", d.clamp)?,
                    interleave: reader.uint("interleave", d.interleave, 1, 16)?,
                    direct: match reader.choice("direct", &["nee", "vpl"])? {
                        Some("vpl") => DirectLight::Vpl,
                        Some(_) => DirectLight::NextEvent,
                        None => d.direct,
                    },
                    direct_spp: reader.uint("direct_spp", d.direct_spp, 1, MAX_DIRECT_SPP)?,
                    pixels: reader.pixels()?,
                })
            }
            "bir" => {
                let d = BirSettings::default();
                Method::Bir(BirSettings {
                    vpls: reader.uint("vpls", d.vpls, 2, 1 << 20)?,
                    frames: reader.uint("frames", d.frames, 1, u32::MAX)?,
                    seed: reader.uint("seed", d.seed, 0, u32::MAX)?,
                    strategy: match reader.choice("strategy", &["standard", "reverse", "both"])? {
                        Some("standard") => Strategy::Standard,
                        Some("reverse") => Strategy::Reverse,
                        Some(_) => Strategy::Both,
                        None => d.strategy,
                    },
                    pool: reader.uint("pool", d.pool, 1, 1 << 16)?,
                    light_samples: reader.uint("light_samples", d.light_samples, 1, 1024)?,
                    connections: reader.uint("connections", d.connections, 0, 1 << 20)?,
                    depth: reader.uint("depth", d.depth, 1, 64)?,
                    ratio: reader.uint("ratio", d.ratio, 0, 1 << 16)?,
                    floor: reader.non_negative("floor", d.floor)?,
                    power_samples: reader.uint("power_samples", d.power_samples, 1, 1024)?,
                    batch: reader.uint("batch", d.batch, 0, 1 << 20)?,
                    light_cdf: reader.flag("light_cdf", d.light_cdf)?,
                    adaptive: reader.flag("adaptive", d.adaptive)?,
                    clamp: reader.clamp("clamp", d.clamp)?,
                    direct_spp: reader.uint("direct_spp", d.direct_spp, 1, MAX_DIRECT_SPP)?,
                    pixels: reader.pixels()?,
                })
            }
            "bundles" => {
                let d = BundlesSettings::default();
                Method::Bundles(BundlesSettings {
                    iterations: reader.uint("iterations", d.iterations, 1, 1 << 16)?,
                    frames: reader.uint("frames", d.frames, 1, u32::MAX)?,
                    seed: reader.uint("seed", d.seed, 0, u32::MAX)?,
                    strategy: match reader.choice("strategy", &["vpl", "bundle", "mis"])? {
                        Some("vpl") => BundlesStrategy::Vpl,
                        Some("bundle") => BundlesStrategy::Bundle,
                        Some(_) => BundlesStrategy::Mis,
                        None => d.strategy,
                    },
                    beta: match reader.choice("heuristic", &["balance", "power"])? {
                        Some("power") => 2.0,
                        Some(_) => 1.0,
                        None => d.beta,
                    },
                    two_bounce: reader.flag("two_bounce", d.two_bounce)?,
                    two_bounce_clamp: reader.clamp("two_bounce_clamp", d.two_bounce_clamp)?,
                    suppression: {
                        let m_prime = reader.non_negative("roughness_m", 16.0)?;
                        let max = reader.non_negative("contribution_clamp", 1.0)?;
                        match reader.choice("glossy", &["none", "roughness", "clamp"])? {
                            Some("none") => Suppression::None,
                            Some("clamp") => Suppression::Contribution { max },
                            Some(_) => Suppression::Roughness { m_prime },
                            None => match d.suppression {
                                Suppression::Roughness { .. } => Suppression::Roughness { m_prime },
                                other => other,
                            },
                        }
                    },
                    lights: match reader.choice("lights", &["all", "roulette"])? {
                        Some("roulette") => LightSelection::Roulette,
                        Some(_) => LightSelection::All,
                        None => d.lights,
                    },
                    directions: match reader.choice("directions", &["uniform", "environment"])? {
                        Some("uniform") => DirectionDensity::Uniform,
                        Some(_) => DirectionDensity::Environment,
                        None => d.directions,
                    },
                    env_offset: match reader.params.contains_key("env_offset") {
                        true => Some(reader.non_negative("env_offset", 0.0)?),
                        false => d.env_offset,
                    },
                    rebuild: reader.rebuild()?,
                    direct_spp: reader.uint("direct_spp", d.direct_spp, 1, MAX_DIRECT_SPP)?,
                    pixels: reader.pixels()?,
                })
            }
            "env" => {
                let d = EnvSettings::default();
                let names: Vec<&str> = EnvStrategy::ALL.iter().map(|s| s.name()).collect();
                Method::Env(EnvSettings {
                    spp: reader.uint("spp", d.spp, 1, 1 << 16)?,
                    frames: reader.uint("frames", d.frames, 1, u32::MAX)?,
                    seed: reader.uint("seed", d.seed, 0, u32::MAX)?,
                    strategy: match reader.choice("strategy", &names)? {
                        Some(c) => *EnvStrategy::ALL.iter().find(|s| s.name() == c).unwrap(),
                        None => d.strategy,
                    },
                    face_resolution: reader.uint("face_resolution", d.face_resolution, 1, 4096)?,
                    light_only: reader.flag("light_only", d.light_only)?,
                    integer_counts: reader.flag("integer_counts", d.integer_counts)?,
                    alpha_samples: match reader.params.contains_key("alpha_samples") {
                        true => Some(reader.uint("alpha_samples", 0, 0, 1 << 16)?),
                        false => d.alpha_samples,
                    },
                    shadows: reader.flag("shadows", d.shadows)?,
                    shared_samples: reader.flag("shared_samples", d.shared_samples)?,
                    rebuild: reader.rebuild()?,
                    pixels: reader.pixels()?,
                })
            }
            "lightfield" => {
                let d = LightfieldSettings::default();
                let names: Vec<&str> = LightfieldStrategy::ALL.iter().map(|s| s.name()).collect();
                Method::Lightfield(LightfieldSettings {
                    spp: reader.uint("spp", d.spp, 1, 1 << 16)?,
                    frames: reader.uint("frames", d.frames, 1, u32::MAX)?,
                    k_max: reader.uint("k_max", d.k_max, 1, 1 << 16)?,
                    seed: reader.uint("seed", d.seed, 0, u32::MAX)?,
                    strategy: match reader.choice("strategy", &names)? {
                        Some(c) => *LightfieldStrategy::ALL
                            .iter()
                            .find(|s| s.name() == c)
                            .unwrap(),
                        None => d.strategy,
                    },
                    secant: match reader.choice("search", &["binary", "secant"])? {
                        Some(c) => c == "secant",
                        None => d.secant,
                    },
                    shared_samples: reader.flag("shared_samples", d.shared_samples)?,
                    averaged_visibility: reader
                        .flag("averaged_visibility", d.averaged_visibility)?,
                    shadows: reader.flag("shadows", d.shadows)?,
                    sampling_only: false,
                    rebuild: reader.rebuild()?,
                    pixels: reader.pixels()?,
                })
            }
            _ => return Err(ParamError::UnknownMethod(name.to_string())),
        };
        reader.refuse_unknown()?;
        Ok(method)
    }

    /// Why this method cannot render `scene`, in one line, or None when it can.
    pub fn declines(&self, scene: &Scene) -> Option<String> {
        if !scene.luminaires.is_empty() && !matches!(self, Method::Lightfield(_)) {
            return Some(format!(
                "{} does not render light-field luminaires (the scene places {}); use --method lightfield",
                self.name(),
                scene.luminaires.len()
            ));
        }
        match self {
            Method::Reference(_) => None,
            Method::Ir(_) => scene
                .environment
                .is_some()
                .then(|| IrError::Environment.to_string()),
            Method::Bir(_) => scene
                .environment
                .is_some()
                .then(|| BirError::Environment.to_string()),
            Method::Bundles(_) => Bundles::declines(scene).map(|e| e.to_string()),
            Method::Env(_) => Env::declines(scene).map(|e| e.to_string()),
            Method::Lightfield(_) => Lightfield::declines(scene).map(|e| e.to_string()),
        }
    }
}

/// Reads typed values out of a parameter table, for `Method::from_params`.
struct Params<'a> {
    method: &'a str,
    params: &'a toml::Table,
}

impl<'a> Params<'a> {
    fn error(&self, key: &str, value: &toml::Value, problem: impl Into<String>) -> ParamError {
        ParamError::Value {
            method: self.method.to_string(),
            key: key.to_string(),
            value: value.to_string(),
            problem: problem.into(),
        }
    }

    fn uint(&mut self, key: &str, default: u32, min: u32, max: u32) -> Result<u32, ParamError> {
        let Some(v) = self.params.get(key) else {
            return Ok(default);
        };
        match v.as_integer() {
            Some(i) if i >= min as i64 && i <= max as i64 => Ok(i as u32),
            Some(_) => Err(self.error(key, v, format!("must be in {min}..={max}"))),
            None => Err(self.error(key, v, "expected an integer")),
        }
    }

    fn non_negative(&mut self, key: &str, default: f32) -> Result<f32, ParamError> {
        let Some(v) = self.params.get(key) else {
            return Ok(default);
        };
        let x = match v {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(i) => *i as f64,
            _ => return Err(self.error(key, v, "expected a number")),
        };
        if !(x.is_finite() && x >= 0.0) {
            return Err(self.error(key, v, "must be a finite number >= 0"));
        }
        Ok(x as f32)
    }

    fn choice(&mut self, key: &str, choices: &[&'a str]) -> Result<Option<&'a str>, ParamError> {
        let Some(v) = self.params.get(key) else {
            return Ok(None);
        };
        let expected = || {
            let quoted: Vec<String> = choices.iter().map(|c| format!("\"{c}\"")).collect();
            format!("expected one of {}", quoted.join(", "))
        };
        match v.as_str() {
            Some(s) => match choices.iter().find(|c| **c == s) {
                Some(c) => Ok(Some(*c)),
                None => Err(self.error(key, v, expected())),
            },
            None => Err(self.error(key, v, expected())),
        }
    }

    /// `key` (`clamp`, bundles' `two_bounce_clamp`: "auto" or a number >= 0, 0 unclamped) and
    /// `compensate` (true or false).
    fn clamp(&mut self, key: &str, default: ClampSettings) -> Result<ClampSettings, ParamError> {
        let clamp = match self.params.get(key) {
            None => default.clamp,
            Some(v) if v.as_str() == Some("auto") => VplClamp::Auto,
            Some(v) if v.is_str() => {
                return Err(self.error(key, v, "expected \"auto\" or a number >= 0"))
            }
            Some(_) => VplClamp::Fixed(self.non_negative(key, 0.0)?),
        };
        Ok(ClampSettings {
            clamp,
            compensate: self.flag("compensate", default.compensate)?,
        })
    }

    /// `rebuild_tables`: "when-changed" (the default) or "every-frame".
    fn rebuild(&mut self) -> Result<TableRebuild, ParamError> {
        Ok(
            match self.choice("rebuild_tables", &["when-changed", "every-frame"])? {
                Some("every-frame") => TableRebuild::EveryFrame,
                _ => TableRebuild::WhenChanged,
            },
        )
    }

    fn flag(&mut self, key: &str, default: bool) -> Result<bool, ParamError> {
        let Some(v) = self.params.get(key) else {
            return Ok(default);
        };
        v.as_bool()
            .ok_or_else(|| self.error(key, v, "expected true or false"))
    }

    fn pixels(&mut self) -> Result<PixelSampling, ParamError> {
        let Some(v) = self.params.get("pixel_centres") else {
            return Ok(PixelSampling::Jittered);
        };
        match v.as_bool() {
            Some(true) => Ok(PixelSampling::Centres),
            Some(false) => Ok(PixelSampling::Jittered),
            None => Err(self.error("pixel_centres", v, "expected true or false")),
        }
    }

    fn refuse_unknown(&self) -> Result<(), ParamError> {
        let known: &[&str] = match self.method {
            "reference" => &[
                "spp",
                "seed",
                "max_depth",
                "roulette_depth",
                "alpha_frames",
                "pixel_centres",
            ],
            "bir" => &[
                "vpls",
                "frames",
                "seed",
                "strategy",
                "pool",
                "light_samples",
                "connections",
                "depth",
                "ratio",
                "floor",
                "power_samples",
                "batch",
                "light_cdf",
                "adaptive",
                "clamp",
                "compensate",
                "direct_spp",
                "pixel_centres",
            ],
            "lightfield" => &[
                "spp",
                "frames",
                "k_max",
                "seed",
                "strategy",
                "search",
                "shared_samples",
                "averaged_visibility",
                "shadows",
                "rebuild_tables",
                "pixel_centres",
            ],
            "env" => &[
                "spp",
                "frames",
                "seed",
                "strategy",
                "face_resolution",
                "light_only",
                "integer_counts",
                "alpha_samples",
                "shadows",
                "shared_samples",
                "rebuild_tables",
                "pixel_centres",
            ],
            "bundles" => &[
                "iterations",
                "frames",
                "seed",
                "strategy",
                "heuristic",
                "two_bounce",
                "two_bounce_clamp",
                "compensate",
                "glossy",
                "roughness_m",
                "contribution_clamp",
                "lights",
                "directions",
                "env_offset",
                "rebuild_tables",
                "direct_spp",
                "pixel_centres",
            ],
            _ => &[
                "vpls",
                "frames",
                "seed",
                "absorption",
                "clamp",
                "compensate",
                "interleave",
                "direct",
                "direct_spp",
                "pixel_centres",
            ],
        };
        match self
            .params
            .iter()
            .find(|(k, _)| !known.contains(&k.as_str()))
        {
            Some((k, v)) => Err(self.error(
                k,
                v,
                format!("unknown parameter (known: {})", known.join(", ")),
            )),
            None => Ok(()),
        }
    }
}

/// Each method's kernels, built the first time the method runs.
#[derive(Default)]
pub struct Renderers {
    reference: OnceCell<Reference>,
    ir: OnceCell<InstantRadiosity>,
    bir: OnceCell<Bir>,
    bundles: OnceCell<Bundles>,
    env: OnceCell<Env>,
    lightfield: OnceCell<Lightfield>,
}

#[derive(Debug, Error)]
pub enum RunError {
    #[error("{0}")]
    Declined(String),
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl Renderers {
    /// Renders `scene` (uploaded as `gpu_scene`) with `method`, calling `progress(done, total)`
    /// as samples complete.
    pub fn run(
        &self,
        ctx: &Context,
        method: &Method,
        scene: &Scene,
        gpu_scene: &GpuScene,
        progress: impl FnMut(u32, u32),
    ) -> Result<RenderOutput, RunError> {
        if let Some(why) = method.declines(scene) {
            return Err(RunError::Declined(why));
        }
        match method {
            Method::Reference(settings) => {
                let r = get_or_try_init(&self.reference, || Reference::new(ctx))?;
                Ok(r.render(ctx, gpu_scene, settings, progress)?)
            }
            Method::Ir(settings) => {
                let ir = get_or_try_init(&self.ir, || InstantRadiosity::new(ctx))?;
                ir.render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        IrError::Environment => RunError::Declined(e.to_string()),
                        IrError::Gpu(g) => RunError::Gpu(g),
                    })
            }
            Method::Bir(settings) => {
                let bir = get_or_try_init(&self.bir, || Bir::new(ctx))?;
                bir.render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        BirError::Environment => RunError::Declined(e.to_string()),
                        BirError::Gpu(g) => RunError::Gpu(g),
                    })
            }
            Method::Bundles(settings) => {
                let bundles = get_or_try_init(&self.bundles, || Bundles::new(ctx))?;
                bundles
                    .render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        BundlesError::Gpu(g) => RunError::Gpu(g),
                        e => RunError::Declined(e.to_string()),
                    })
            }
            Method::Env(settings) => {
                let env = get_or_try_init(&self.env, || Env::new(ctx))?;
                env.render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        EnvError::Gpu(g) => RunError::Gpu(g),
                        e => RunError::Declined(e.to_string()),
                    })
            }
            Method::Lightfield(settings) => {
                let lf = get_or_try_init(&self.lightfield, || Lightfield::new(ctx))?;
                lf.render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        LightfieldError::Gpu(g) => RunError::Gpu(g),
                        e => RunError::Declined(e.to_string()),
                    })
            }
        }
    }
}

/// `OnceCell::get_or_try_init` is not stable yet.
fn get_or_try_init<T>(
    cell: &OnceCell<T>,
    init: impl FnOnce() -> Result<T, GpuError>,
) -> Result<&T, GpuError> {
    if let Some(v) = cell.get() {
        return Ok(v);
    }
    let v = init()?;
    Ok(cell.get_or_init(|| v))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Table {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn parameters_read_back_to_the_same_method() {
        let ir = Method::from_params(
            "ir",
            &table("vpls = 64\nframes = 3\nabsorption = \"roulette\"\nclamp = 2.5\ncompensate = false\ninterleave = 4\ndirect = \"vpl\"\npixel_centres = true"),
        )
        .unwrap();
        let back: toml::Table = ir
            .parameters()
            .into_iter()
            .map(|(k, v)| (k, toml::Value::try_from(v).unwrap()))
            .collect();
        assert_eq!(Method::from_params("ir", &back).unwrap(), ir);
        let reference =
            Method::from_params("reference", &table("spp = 7\nroulette_depth = 5")).unwrap();
        assert_eq!(
            reference,
            Method::Reference(ReferenceSettings {
                spp: 7,
                roulette_depth: 5,
                ..Default::default()
            })
        );
    }

    #[test]
    fn reference_alpha_frames_need_the_direct_light_only() {
        let r =
            Method::from_params("reference", &table("max_depth = 1\nalpha_frames = 32")).unwrap();
        assert_eq!(
            r,
            Method::Reference(ReferenceSettings {
                max_depth: 1,
                alpha_frames: Some(32),
                ..Default::default()
            })
        );
        let back: toml::Table = r
            .parameters()
            .into_iter()
            .map(|(k, v)| (k, toml::Value::try_from(v).unwrap()))
            .collect();
        assert_eq!(Method::from_params("reference", &back).unwrap(), r);
        let e = Method::from_params("reference", &table("alpha_frames = 32")).unwrap_err();
        assert!(e.to_string().contains("needs max_depth = 1"), "{e}");
    }

    #[test]
    fn bir_parameters_read_back() {
        let bir = Method::from_params(
            "bir",
            &table("vpls = 64\nframes = 3\nstrategy = \"reverse\"\npool = 7\nlight_samples = 2\nconnections = 3\ndepth = 5\nratio = 0\nfloor = 0.5\npower_samples = 9\nbatch = 32\nlight_cdf = false\nadaptive = false"),
        )
        .unwrap();
        let back: toml::Table = bir
            .parameters()
            .into_iter()
            .map(|(k, v)| (k, toml::Value::try_from(v).unwrap()))
            .collect();
        assert_eq!(Method::from_params("bir", &back).unwrap(), bir);
        let e = Method::from_params("bir", &table("strategy = \"sideways\"")).unwrap_err();
        assert!(e.to_string().contains("strategy = \"sideways\""), "{e}");
    }

    #[test]
    fn bundles_parameters_read_back() {
        let bundles = Method::from_params(
            "bundles",
            &table("iterations = 5\nframes = 2\nstrategy = \"vpl\"\nheuristic = \"power\"\ntwo_bounce = true\ntwo_bounce_clamp = 3.5\nglossy = \"clamp\"\ncontribution_clamp = 2.5\nlights = \"roulette\"\ndirections = \"uniform\"\nenv_offset = 0.25\npixel_centres = true"),
        )
        .unwrap();
        let back: toml::Table = bundles
            .parameters()
            .into_iter()
            .map(|(k, v)| (k, toml::Value::try_from(v).unwrap()))
            .collect();
        assert_eq!(Method::from_params("bundles", &back).unwrap(), bundles);
        let e = Method::from_params("bundles", &table("strategy = \"both\"")).unwrap_err();
        assert!(
            e.to_string()
                .contains("expected one of \"vpl\", \"bundle\", \"mis\""),
            "{e}"
        );
        let e = Method::from_params("bundles", &table("vpls = 4")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("bundles: vpls = 4: unknown parameter"),
            "{e}"
        );
    }

    #[test]
    fn env_parameters_read_back() {
        let env = Method::from_params(
            "env",
            &table("spp = 20\nframes = 3\nstrategy = \"uniform-faces\"\nface_resolution = 64\nlight_only = true\ninteger_counts = true\npixel_centres = true"),
        )
        .unwrap();
        let back: toml::Table = env
            .parameters()
            .into_iter()
            .map(|(k, v)| (k, toml::Value::try_from(v).unwrap()))
            .collect();
        assert_eq!(Method::from_params("env", &back).unwrap(), env);
        let alpha = Method::from_params(
            "env",
            &table("strategy = \"alpha\"\nspp = 32\nalpha_samples = 8"),
        )
        .unwrap();
        let back: toml::Table = alpha
            .parameters()
            .into_iter()
            .map(|(k, v)| (k, toml::Value::try_from(v).unwrap()))
            .collect();
        assert_eq!(back["alpha_samples"].as_integer(), Some(8));
        assert_eq!(Method::from_params("env", &back).unwrap(), alpha);
        let e = Method::from_params("env", &table("strategy = \"mis\"")).unwrap_err();
        assert!(e.to_string().contains("expected one of \"dynamic\""), "{e}");
        let e = Method::from_params("env", &table("face_resolution = 0")).unwrap_err();
        assert!(e.to_string().starts_with("env: face_resolution = 0"), "{e}");
    }

    #[test]
    fn bad_parameters_name_method_key_and_value() {
        let e = Method::from_params("ir", &table("vpls = 0")).unwrap_err();
        assert_eq!(e.to_string(), "ir: vpls = 0: must be in 1..=1048576");
        let e = Method::from_params("ir", &table("absorption = \"sometimes\"")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "ir: absorption = \"sometimes\": expected one of \"fractional\", \"roulette\""
        );
        let e = Method::from_params("reference", &table("vpls = 4")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("reference: vpls = 4: unknown parameter"),
            "{e}"
        );
        let e = Method::from_params("ir", &table("clamp = -1.0")).unwrap_err();
        assert!(e.to_string().contains("clamp = -1.0"), "{e}");
        let e = Method::from_params("bir", &table("clamp = \"sometimes\"")).unwrap_err();
        assert!(e.to_string().contains("clamp = \"sometimes\""), "{e}");
        let e = Method::from_params("ir", &table("compensate = 1")).unwrap_err();
        assert!(e.to_string().contains("compensate = 1"), "{e}");
        let e = Method::from_params("bidir", &table("")).unwrap_err();
        assert!(e.to_string().contains("unknown method `bidir`"), "{e}");
    }
}
