//! A method with its settings, as one value: `Method` pairs a registered method's entry
//! (registry.rs) with its settings struct, built from named parameters by the method's
//! settings table (src/methods/settings.rs: suite files, the CLI's flags and records share it),
//! says when the method declines a scene, and runs through `Renderers` (renderers.rs).

use std::any::Any;
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use crate::scene::Scene;

use super::across_frames::AcrossFrames;
use super::interface::RenderMethod;
use super::lights;
use super::registry::{self, MethodEntry, Registry};
use super::settings::{ParamError, SettingDoc, Value};

/// A method and all its settings.
#[derive(Clone)]
pub struct Method {
    entry: &'static dyn MethodEntry,
    /// `entry`'s method's `Settings`.
    settings: Arc<dyn Any + Send + Sync>,
}

impl Method {
    /// `M` with `settings`.
    ///
    /// Panics where `M`'s table lacks the Count rows `seed` and `M::COUNT` (as
    /// `Registry::with`).
    pub fn new<M: RenderMethod>(settings: M::Settings) -> Method {
        super::interface::assert_table::<M>();
        Method {
            entry: registry::entry::<M>(),
            settings: Arc::new(settings),
        }
    }

    /// The settings, where this is method `M`.
    pub fn settings_of<M: RenderMethod>(&self) -> Option<&M::Settings> {
        (self.entry.method_type() == std::any::TypeId::of::<M>())
            .then(|| self.settings.downcast_ref())
            .flatten()
    }

    /// Whether this is method `M`.
    pub fn is<M: RenderMethod>(&self) -> bool {
        self.settings_of::<M>().is_some()
    }

    /// The method's registry entry: its constants, table and render.
    pub fn entry(&self) -> &'static dyn MethodEntry {
        self.entry
    }

    pub(crate) fn settings_any(&self) -> &dyn Any {
        &*self.settings
    }

    pub fn name(&self) -> &'static str {
        self.entry.name()
    }

    pub fn seed(&self) -> u32 {
        self.entry.seed(self.settings_any())
    }

    /// The same method and settings with another seed.
    pub fn with_seed(&self, seed: u32) -> Method {
        Method {
            entry: self.entry,
            settings: self.entry.with_seed(self.settings_any(), seed),
        }
    }

    /// Samples as the method counts them, for progress: samples per pixel, or frames
    /// (`count_key()`'s value).
    pub fn samples(&self) -> u64 {
        self.entry.count(self.settings_any()) as u64
    }

    /// The parameter a time budget calibrates (`time_ms` in a suite): the reference's `spp`,
    /// every other method's `frames` (`RenderMethod::COUNT`); `samples()` reads it.
    pub fn count_key(&self) -> &'static str {
        self.entry.count_key()
    }

    /// What the method keeps from one animation frame to the next with these settings
    /// (`RenderMethod::across_frames`).
    pub fn across_frames(&self) -> AcrossFrames {
        self.entry.across_frames_with(self.settings_any())
    }

    /// The same method and settings with `count_key()` set to `count`.
    pub fn with_count(&self, count: u32) -> Method {
        Method {
            entry: self.entry,
            settings: self.entry.with_count(self.settings_any(), count),
        }
    }

    /// Work in units that scale a method's cost at a fixed resolution, for time estimates:
    /// samples per pixel, or frames times light paths.
    pub fn work(&self) -> f64 {
        self.entry.work(self.settings_any())
    }

    /// The method's settings by the keys of its table, sorted, unset ones and the seed (a
    /// record's own field) left out, so a record's parameters can be fed back to
    /// `from_params`.
    pub fn parameters(&self) -> BTreeMap<String, serde_json::Value> {
        let mut p = self.parameters_with_seed();
        p.remove("seed");
        p
    }

    fn parameters_with_seed(&self) -> BTreeMap<String, serde_json::Value> {
        self.entry.parameters(self.settings_any())
    }

    /// irad's method `name` with `params` (a suite file's table) over its defaults:
    /// `Registry::builtin().from_params`.
    pub fn from_params(name: &str, params: &toml::Table) -> Result<Method, ParamError> {
        Registry::builtin().from_params(name, params)
    }

    /// irad's method `name` with `given` (the CLI's flags) over its defaults:
    /// `Registry::builtin().from_values`.
    pub fn from_values(name: &str, given: &[(&str, String, Value)]) -> Result<Method, ParamError> {
        Registry::builtin().from_values(name, given)
    }

    /// The settings irad's method `name` takes, with their defaults, in table order.
    pub fn settings(name: &str) -> Result<Vec<SettingDoc>, ParamError> {
        Registry::builtin().settings(name)
    }

    /// Why this method cannot render `scene`, in one line, or None when it can.
    pub fn declines(&self, scene: &Scene) -> Option<String> {
        lights::declines(self.name(), &self.entry.lights(), scene)
    }

    /// Sizes this method's settings make on `scene` that a device with
    /// maxStorageBufferRange `limit` cannot hold, in the user's words.
    pub fn fits(&self, scene: &Scene, limit: u64) -> Result<(), String> {
        self.entry.fits(self.settings_any(), scene, limit)
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Method) -> bool {
        self.name() == other.name()
            && self.entry.method_type() == other.entry.method_type()
            && self.entry.equal(self.settings_any(), other.settings_any())
    }
}

impl fmt::Debug for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}(", self.name())?;
        self.entry.debug(self.settings_any(), f)?;
        write!(f, ")")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::reference::{Reference, ReferenceSettings};
    use crate::methods::settings::{Kind, Need};
    use crate::methods::{bundles, envmap, lightfield};

    /// Each strategy's name, written `STRATEGY_` + upper case with `-` as `_`, is defined in
    /// its kernel as the strategy's code (`as u32`): the Rust names and the GLSL codes are
    /// one list.
    #[test]
    fn strategy_codes_are_the_kernels_defines() {
        fn check(file: &str, codes: &[(&str, u32)]) {
            let path = format!("{}/glsl/{file}", env!("CARGO_MANIFEST_DIR"));
            let text = std::fs::read_to_string(&path).unwrap();
            for (name, code) in codes {
                let define = format!(
                    "#define STRATEGY_{} {code}u",
                    name.to_uppercase().replace('-', "_")
                );
                assert!(text.contains(&define), "{path}: no `{define}`");
            }
        }
        let env: Vec<_> = envmap::Strategy::ALL
            .iter()
            .map(|s| (s.name(), s.code()))
            .collect();
        check("envmap/shade_env.comp", &env);
        let lf: Vec<_> = lightfield::Strategy::ALL
            .iter()
            .map(|&s| (s.name(), s as u32))
            .collect();
        check("include/luminaire.glsl", &lf);
        let b: Vec<_> = bundles::Strategy::ALL
            .iter()
            .map(|&s| (s.name(), s as u32))
            .collect();
        check("bundles/shade_bundle_paths.comp", &b);
    }

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
            Method::new::<Reference>(ReferenceSettings {
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
            Method::new::<Reference>(ReferenceSettings {
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
        assert_eq!(
            e.to_string(),
            "reference: alpha_frames = 32: applies with max_depth = 1, not 1024 (the default)"
        );
    }

    #[test]
    fn bir_parameters_read_back() {
        let bir = Method::from_params(
            "bir",
            &table("vpls = 64\nframes = 3\nstrategy = \"both\"\npool = 7\nlight_samples = 2\nconnections = 3\ndepth = 5\nratio = 3\nfloor = 0.5\npower_samples = 9\nbatch = 32\nlight_cdf = false\nadaptive = false"),
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
            &table("iterations = 5\nframes = 2\nstrategy = \"mis\"\nheuristic = \"power\"\ntwo_bounce = true\ntwo_bounce_clamp = 3.5\ncompensate = false\nglossy = \"clamp\"\ncontribution_clamp = 2.5\nlights = \"roulette\"\ndirections = \"environment\"\nenv_offset = 0.25\nrebuild_tables = \"every-frame\"\npixel_centres = true"),
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

    /// A flag's text as a suite file writes the same value.
    fn toml_of(kind: Kind, text: &str) -> toml::Value {
        match kind {
            Kind::Count { .. } => toml::Value::Integer(text.parse().unwrap()),
            Kind::Number => toml::Value::Float(text.parse().unwrap()),
            Kind::Switch => toml::Value::Boolean(text.parse().unwrap()),
            Kind::Choice(_) => toml::Value::String(text.into()),
            Kind::Clamp if text == "auto" => toml::Value::String(text.into()),
            Kind::Clamp => toml::Value::Float(text.parse().unwrap()),
        }
    }

    /// Values to give a setting, as flag texts: every name and switch value, the low end and
    /// top of a count's range, a few numbers and clamps.
    fn tries(kind: Kind) -> Vec<String> {
        let texts: Vec<String> = match kind {
            Kind::Count { min, max } => [min as u64, min as u64 + 1, min as u64 + 2, max as u64]
                .iter()
                .filter(|&&n| n <= max as u64)
                .map(|n| n.to_string())
                .collect(),
            Kind::Number => vec!["0".into(), "0.5".into(), "3".into()],
            Kind::Switch => vec!["true".into(), "false".into()],
            Kind::Choice(names) => names.iter().map(|n| n.to_string()).collect(),
            Kind::Clamp => vec!["auto".into(), "0".into(), "2.5".into()],
        };
        let mut unique = texts;
        unique.dedup();
        unique
    }

    /// Two values as texts are the same value (`16` and `16.0`).
    fn same(a: &str, b: &str) -> bool {
        a == b || matches!((a.parse::<f64>(), b.parse::<f64>()), (Ok(x), Ok(y)) if x == y)
    }

    /// Whether `need` holds for a setting given as `own`, the others' values by `value` (flag
    /// texts): the tables' conditions read here on their own, not through `Need::holds`.
    fn holds(need: Need, own: &str, value: &dyn Fn(&str) -> Option<String>) -> bool {
        match need {
            Need::OneOf(key, values) => {
                value(key).is_some_and(|v| values.iter().any(|x| same(x, &v)))
            }
            Need::Not(key, x) => value(key).is_some_and(|v| !same(x, &v)),
            Need::Unset(key) => value(key).is_none(),
            Need::AtMost(key) => {
                own.parse::<u64>().unwrap() <= value(key).unwrap().parse::<u64>().unwrap()
            }
            Need::Any(needs) => needs.iter().any(|n| holds(*n, own, value)),
        }
    }

    /// Every setting with a condition, given at each of its values other than the default
    /// beside each value of every other setting (alone, and with the values its conditions
    /// name given too, so that each condition is reached), is refused exactly where a given
    /// setting's conditions do not hold, by suite params and CLI values alike, with the same
    /// key and problem; where it is accepted the two agree and the record reads back.
    #[test]
    fn settings_are_refused_exactly_where_their_conditions_say() {
        let mut checked = 0;
        for method in Registry::builtin().names() {
            let docs = Method::settings(method).unwrap();
            let kind = |key: &str| docs.iter().find(|d| d.key == key).unwrap().kind;
            let defaults = Method::from_params(method, &toml::Table::new())
                .unwrap()
                .parameters_with_seed();
            for row in docs.iter().filter(|d| !d.needs.is_empty()) {
                // The values the row's conditions name, given explicitly.
                let enabling: Vec<(&str, String)> = row
                    .needs
                    .iter()
                    .filter_map(|n| match n {
                        Need::OneOf(key, values) => Some((*key, values[0].to_string())),
                        _ => None,
                    })
                    .collect();
                // Values that break each alternative of an `Any`, so that it can fail too.
                let mut disabling: Vec<(&str, String)> = Vec::new();
                for need in row.needs {
                    if let Need::Any(alternatives) = need {
                        for alternative in *alternatives {
                            match alternative {
                                Need::Not(key, v) => disabling.push((key, v.to_string())),
                                Need::OneOf(key, values) => disabling.push((
                                    key,
                                    tries(kind(key))
                                        .into_iter()
                                        .find(|t| !values.contains(&t.as_str()))
                                        .unwrap(),
                                )),
                                n => panic!("{method} {}: no test values for {n:?}", row.key),
                            }
                        }
                    }
                }
                let (mut refused, mut accepted) = (0, 0);
                for own in tries(row.kind).into_iter().filter(|t| *t != row.default) {
                    for other in docs.iter().filter(|d| d.key != row.key) {
                        for text in tries(other.kind) {
                            for base in [&[][..], &enabling[..], &disabling[..]] {
                                let mut given: Vec<(&str, String)> = base
                                    .iter()
                                    .filter(|(k, _)| *k != other.key)
                                    .cloned()
                                    .collect();
                                given.push((row.key, own.clone()));
                                given.push((other.key, text.clone()));
                                let value = |key: &str| match given.iter().find(|g| g.0 == key) {
                                    Some((_, t)) => Some(t.clone()),
                                    None => defaults.get(key).map(|v| match v {
                                        serde_json::Value::String(s) => s.clone(),
                                        v => v.to_string(),
                                    }),
                                };
                                let failing: Vec<&str> = given
                                    .iter()
                                    .filter(|(key, t)| {
                                        let needs =
                                            docs.iter().find(|d| d.key == *key).unwrap().needs;
                                        !needs.iter().all(|n| holds(*n, t, &value))
                                    })
                                    .map(|(key, _)| *key)
                                    .collect();
                                let params: toml::Table = given
                                    .iter()
                                    .map(|(k, t)| (k.to_string(), toml_of(kind(k), t)))
                                    .collect();
                                let values: Vec<(&str, String, Value)> = given
                                    .iter()
                                    .map(|(k, t)| (*k, t.clone(), kind(k).parse_text(t).unwrap()))
                                    .collect();
                                let case = format!("{method} {given:?}");
                                match (
                                    Method::from_params(method, &params),
                                    Method::from_values(method, &values),
                                ) {
                                    (Ok(a), Ok(b)) => {
                                        assert!(
                                            failing.is_empty(),
                                            "{case}: accepted, but {failing:?} do not apply"
                                        );
                                        assert_eq!(a, b, "{case}");
                                        let back: toml::Table = a
                                            .parameters()
                                            .into_iter()
                                            .map(|(k, v)| (k, toml::Value::try_from(v).unwrap()))
                                            .collect();
                                        assert_eq!(
                                            Method::from_params(method, &back)
                                                .unwrap()
                                                .with_seed(a.seed()),
                                            a,
                                            "{case}: record"
                                        );
                                        accepted += 1;
                                    }
                                    (
                                        Err(ParamError::Value {
                                            key: k1,
                                            problem: p1,
                                            ..
                                        }),
                                        Err(ParamError::Value {
                                            key: k2,
                                            problem: p2,
                                            ..
                                        }),
                                    ) => {
                                        assert!(
                                            failing.contains(&k1.as_str()),
                                            "{case}: {k1} refused ({p1}), failing {failing:?}"
                                        );
                                        assert_eq!((&k1, &p1), (&k2, &p2), "{case}");
                                        refused += 1;
                                    }
                                    (a, b) => panic!("{case}: suite {a:?}, CLI {b:?}"),
                                }
                                checked += 1;
                            }
                        }
                    }
                }
                assert!(
                    refused > 0 && accepted > 0,
                    "{method} {}: {refused} refused, {accepted} accepted",
                    row.key
                );
            }
        }
        assert!(checked > 5000, "{checked} cases");
    }

    /// The settings a probe found silently ignored, each refused with its reason: deleting
    /// any one condition from the tables fails this.
    #[test]
    fn settings_ignored_beside_others_are_refused() {
        let cases = [
            ("env", "strategy = \"latlong\"\nlight_only = true", "light_only = true: applies with strategy = \"dynamic\" or \"uniform-faces\", not \"latlong\""),
            ("env", "strategy = \"brdf\"\ninteger_counts = true", "integer_counts = true: applies with strategy = \"dynamic\" or \"uniform-faces\", not \"brdf\""),
            ("env", "strategy = \"alpha\"\nlight_only = true", "light_only = true: applies with strategy = \"dynamic\" or \"uniform-faces\", not \"alpha\""),
            ("env", "strategy = \"latlong\"\nshared_samples = true", "shared_samples = true: applies with strategy = \"dynamic\", \"uniform-faces\" or \"alpha\", not \"latlong\""),
            ("env", "strategy = \"hierarchical\"\nface_resolution = 64", "face_resolution = 64: applies with strategy = \"dynamic\", \"uniform-faces\" or \"alpha\", not \"hierarchical\""),
            ("env", "strategy = \"cosine\"\nrebuild_tables = \"every-frame\"", "rebuild_tables = \"every-frame\": applies with strategy = \"dynamic\", \"uniform-faces\", \"latlong\", \"hierarchical\" or \"alpha\", not \"cosine\""),
            ("env", "strategy = \"brdf\"\nalpha_samples = 4", "alpha_samples = 4: applies with strategy = \"alpha\", not \"brdf\""),
            ("env", "alpha_samples = 4", "alpha_samples = 4: applies with strategy = \"alpha\", not \"dynamic\" (the default)"),
            ("env", "strategy = \"alpha\"\nspp = 8\nalpha_samples = 9", "alpha_samples = 9: must be at most spp = 8"),
            ("bundles", "directions = \"uniform\"\nenv_offset = 0.5", "env_offset = 0.5: applies with directions = \"environment\", not \"uniform\""),
            ("bundles", "directions = \"uniform\"\nrebuild_tables = \"every-frame\"", "rebuild_tables = \"every-frame\": applies with directions = \"environment\", not \"uniform\""),
            ("bundles", "strategy = \"vpl\"\nheuristic = \"power\"", "heuristic = \"power\": applies with strategy = \"mis\", not \"vpl\""),
            ("bundles", "strategy = \"bundle\"\nheuristic = \"balance\"", "heuristic = \"balance\": applies with strategy = \"mis\", not \"bundle\""),
            ("bundles", "two_bounce = false\ntwo_bounce_clamp = 2.0", "two_bounce_clamp = 2.0: applies with two_bounce = true, not false"),
            ("bundles", "two_bounce = false\ncompensate = false", "compensate = false: applies with two_bounce = true, not false"),
            ("bundles", "two_bounce_clamp = 0\ncompensate = false", "compensate = false: applies with two_bounce_clamp other than 0"),
            ("bundles", "glossy = \"clamp\"\nroughness_m = 4.0", "roughness_m = 4.0: applies with glossy = \"roughness\", not \"clamp\""),
            ("bundles", "glossy = \"none\"\ncontribution_clamp = 4.0", "contribution_clamp = 4.0: applies with glossy = \"clamp\", not \"none\""),
            ("bir", "strategy = \"standard\"\nadaptive = false", "adaptive = false: applies with strategy = \"both\", not \"standard\""),
            ("bir", "ratio = 0\nadaptive = false", "adaptive = false: applies with ratio other than 0"),
            ("bir", "strategy = \"standard\"\npool = 8", "pool = 8: applies with strategy = \"reverse\" or \"both\", not \"standard\""),
            ("bir", "strategy = \"standard\"\nlight_samples = 8", "light_samples = 8: applies with strategy = \"reverse\" or \"both\", not \"standard\""),
            ("bir", "strategy = \"standard\"\nconnections = 8", "connections = 8: applies with strategy = \"reverse\" or \"both\", not \"standard\""),
            ("bir", "strategy = \"standard\"\ndepth = 2", "depth = 2: applies with strategy = \"reverse\" or \"both\", not \"standard\""),
            ("bir", "ratio = 0\npower_samples = 2", "power_samples = 2: applies with ratio other than 0"),
            ("bir", "ratio = 0\nlight_cdf = false\nfloor = 0.5", "floor = 0.5: applies with ratio other than 0 or light_cdf = true"),
            ("bir", "clamp = 0.0\ncompensate = true", "compensate = true: applies with clamp other than 0"),
            ("ir", "clamp = 0\ncompensate = false", "compensate = false: applies with clamp other than 0"),
            ("lightfield", "strategy = \"brute-force\"\nk_max = 8", "k_max = 8: applies with strategy = \"restricted\", \"uniform\" or \"precomputed\", not \"brute-force\""),
            ("lightfield", "strategy = \"brute-force\"\nsearch = \"binary\"", "search = \"binary\": applies with strategy = \"restricted\" or \"precomputed\", not \"brute-force\""),
            ("lightfield", "strategy = \"uniform\"\nsearch = \"binary\"", "search = \"binary\": applies with strategy = \"restricted\" or \"precomputed\", not \"uniform\""),
            ("lightfield", "shadows = false\naveraged_visibility = true", "averaged_visibility = true: applies with shadows = true, not false"),
            ("reference", "max_depth = 2\nalpha_frames = 8", "alpha_frames = 8: applies with max_depth = 1, not 2"),
            ("reference", "max_depth = 1\nalpha_frames = 8\nroulette_depth = 1", "roulette_depth = 1: applies with alpha_frames unset, not 8"),
        ];
        for (method, params, problem) in cases {
            let e = Method::from_params(method, &table(params)).unwrap_err();
            assert_eq!(e.to_string(), format!("{method}: {problem}"));
            let docs = Method::settings(method).unwrap();
            let values: Vec<(&str, String, Value)> = table(params)
                .iter()
                .map(|(k, v)| {
                    let doc = docs.iter().find(|d| d.key == k).unwrap();
                    let text = v.as_str().map_or_else(|| v.to_string(), str::to_string);
                    (doc.key, text.clone(), doc.kind.parse_text(&text).unwrap())
                })
                .collect();
            match Method::from_values(method, &values).unwrap_err() {
                ParamError::Value { problem: p, .. } => {
                    assert!(problem.ends_with(&p), "{method} {params}: CLI {p}")
                }
                e => panic!("{method} {params}: {e}"),
            }
        }
    }

    /// The conditions name settings of their own table, with values those settings take, and
    /// env's cube-map strategies are the ones that sample the cube map.
    #[test]
    fn conditions_name_settings_and_values_of_their_table() {
        fn check(method: &str, docs: &[SettingDoc], need: Need) {
            let kind = |key: &str| {
                docs.iter()
                    .find(|d| d.key == key)
                    .unwrap_or_else(|| panic!("{method}: no setting {key}"))
                    .kind
            };
            match need {
                Need::OneOf(key, values) => {
                    for v in values {
                        kind(key).parse_text(v).unwrap();
                    }
                }
                Need::Not(key, v) => {
                    kind(key).parse_text(v).unwrap();
                }
                Need::Unset(key) => assert!(
                    kind(key)
                        .parse_text(&docs.iter().find(|d| d.key == key).unwrap().default)
                        .is_err(),
                    "{method}: {key} is never unset"
                ),
                Need::AtMost(key) => assert!(matches!(kind(key), Kind::Count { .. })),
                Need::Any(needs) => needs.iter().for_each(|n| check(method, docs, *n)),
            }
        }
        for method in Registry::builtin().names() {
            let docs = Method::settings(method).unwrap();
            for doc in &docs {
                doc.needs.iter().for_each(|n| check(method, &docs, *n));
            }
        }
        let cube: Vec<&str> = envmap::Strategy::ALL
            .iter()
            .filter(|s| s.uses_cube())
            .map(|s| s.name())
            .collect();
        assert_eq!(cube, envmap::CUBE_STRATEGIES);
    }
}
