//! Method settings, defined once. Each method's settings struct comes with a table of
//! `Setting` rows (next to the struct, in the method's module): the key, its kind and range,
//! its help, and how to read and write it in the struct. The defaults are the struct's
//! `Default`. Suite files (`Method::from_params`), records (`Method::parameters`), `irad
//! render`'s flags (the CLI builds them from the tables: `--` + the key with `_` written `-`)
//! and `irad methods` all read these tables, so a name, a default, a range or a help text
//! cannot differ between them.
//!
//! A row may apply only beside certain values of the others (`needs`: light_only only with
//! strategy dynamic or uniform-faces). `build` checks that in one place, after every given
//! value is set, for every given key, so a setting given where the method would ignore it is
//! refused by name on the CLI and in suites alike, whatever the table's order; records leave
//! such settings out.
//!
//! Why a table of rows and not serde or clap `Args` per method: a suite file is TOML and the
//! CLI is flags, and the two need the same checks with errors that name the method, key and
//! value; serde would give the TOML side (with its own error texts) and clap the CLI side,
//! each with its own copy of the ranges. A row is plain data both sides walk, and its
//! accessors keep the settings structs as the methods use them (enums, not strings).

use std::collections::BTreeMap;
use std::fmt;

use thiserror::Error;

use crate::methods::compensation::VplClamp;

/// What a setting takes, with its range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// A whole number in `min..=max`.
    Count { min: u32, max: u32 },
    /// A finite number >= 0.
    Number,
    /// true or false; on the CLI a bare `--flag` is true and `--flag=false` false.
    Switch,
    /// One of these names.
    Choice(&'static [&'static str]),
    /// A VPL clamp: "auto" or a finite number >= 0 (0: unclamped).
    Clamp,
}

/// A setting's value, checked against its `Kind`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Count(u32),
    Number(f32),
    Switch(bool),
    /// One of its `Kind::Choice` names.
    Name(&'static str),
    Clamp(VplClamp),
}

/// One setting of one method's settings struct `S`.
pub struct Setting<S> {
    /// The suite file's key; the CLI flag is `--` + the key with `_` written `-`.
    pub key: &'static str,
    pub kind: Kind,
    /// What it does, for `irad render --help`, `irad methods` and docs/commands.md.
    pub help: &'static str,
    /// The value in `s`; None where it is unset (then records leave it out and
    /// `unset` says what that means).
    pub get: fn(&S) -> Option<Value>,
    /// Sets the value (checked against `kind`) in `s`, which holds the defaults and the
    /// settings before this one in the table (whether it applies is `needs`' business).
    pub set: fn(&mut S, Value),
    /// What the default is where `get` of the default struct gives None.
    pub unset: &'static str,
    /// Where the setting applies: every one of these holds, read on the settings once every
    /// given value is set. Given where one does not hold, the setting is refused.
    pub needs: &'static [Need],
}

/// A condition on the other settings under which a setting applies. Values are written as a
/// flag takes them: names unquoted, `true`/`false`, numbers in digits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Need {
    /// The setting `key` has one of these values.
    OneOf(&'static str, &'static [&'static str]),
    /// The setting `key` does not have this value.
    Not(&'static str, &'static str),
    /// The setting `key` is unset (`get` gives None).
    Unset(&'static str),
    /// The setting itself is at most the count `key` (both counts).
    AtMost(&'static str),
    /// At least one of these holds.
    Any(&'static [Need]),
}

impl<S> Setting<S> {
    pub const fn new(
        key: &'static str,
        kind: Kind,
        help: &'static str,
        get: fn(&S) -> Option<Value>,
        set: fn(&mut S, Value),
    ) -> Setting<S> {
        Setting {
            key,
            kind,
            help,
            get,
            set,
            unset: "",
            needs: &[],
        }
    }

    /// The same setting with what its unset default means.
    pub const fn unset(self, unset: &'static str) -> Setting<S> {
        Setting { unset, ..self }
    }

    /// The same setting, applying only where all of `needs` hold.
    pub const fn needs(self, needs: &'static [Need]) -> Setting<S> {
        Setting { needs, ..self }
    }
}

/// `setting`, applying only where all of `needs` hold: `Setting::needs` as a function, whose
/// argument takes the table's element type, so the rows' closures need no type annotations.
pub const fn with_needs<S>(needs: &'static [Need], setting: Setting<S>) -> Setting<S> {
    setting.needs(needs)
}

/// A setting as `irad methods` and the CLI show it, without its accessors.
#[derive(Clone, Debug, PartialEq)]
pub struct SettingDoc {
    pub key: &'static str,
    pub kind: Kind,
    pub help: &'static str,
    /// The default as text (a value, or the `unset` text).
    pub default: String,
    /// Where it applies (`Setting::needs`).
    pub needs: &'static [Need],
}

/// A parameter a method cannot take: `method: key = value: problem`.
#[derive(Debug, Error, PartialEq)]
pub enum ParamError {
    #[error("unknown method `{name}` (methods: {known})")]
    UnknownMethod {
        name: String,
        /// The registry's methods, listed.
        known: String,
    },
    #[error("{method}: {key} = {value}: {problem}")]
    Value {
        method: String,
        key: String,
        /// As it was written: TOML (strings quoted) or the flag's text.
        value: String,
        problem: String,
    },
}

impl fmt::Display for Value {
    /// The value as a flag takes it (names unquoted).
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Value::Count(n) => write!(f, "{n}"),
            Value::Number(x) => write!(f, "{x}"),
            Value::Switch(b) => write!(f, "{b}"),
            Value::Name(s) => write!(f, "{s}"),
            Value::Clamp(VplClamp::Auto) => write!(f, "auto"),
            Value::Clamp(VplClamp::Fixed(b)) => write!(f, "{b}"),
        }
    }
}

impl Value {
    /// The value in a record's parameters (and so in a suite file).
    pub fn to_json(self) -> serde_json::Value {
        match self {
            Value::Count(n) => n.into(),
            Value::Number(x) => x.into(),
            Value::Switch(b) => b.into(),
            Value::Name(s) => s.into(),
            Value::Clamp(VplClamp::Auto) => "auto".into(),
            Value::Clamp(VplClamp::Fixed(b)) => b.into(),
        }
    }

    pub fn count(self) -> u32 {
        match self {
            Value::Count(n) => n,
            v => unreachable!("{v:?} checked as a count"),
        }
    }

    pub fn number(self) -> f32 {
        match self {
            Value::Number(x) => x,
            v => unreachable!("{v:?} checked as a number"),
        }
    }

    pub fn switch(self) -> bool {
        match self {
            Value::Switch(b) => b,
            v => unreachable!("{v:?} checked as a switch"),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Value::Name(s) => s,
            v => unreachable!("{v:?} checked as a name"),
        }
    }

    pub fn clamp(self) -> VplClamp {
        match self {
            Value::Clamp(c) => c,
            v => unreachable!("{v:?} checked as a clamp"),
        }
    }
}

impl Kind {
    /// A suite file's value, checked; Err(problem).
    pub fn check_toml(self, v: &toml::Value) -> Result<Value, String> {
        match self {
            Kind::Count { min, max } => match v.as_integer() {
                Some(i) if i >= min as i64 && i <= max as i64 => Ok(Value::Count(i as u32)),
                Some(_) => Err(format!("must be in {min}..={max}")),
                None => Err("expected an integer".into()),
            },
            Kind::Number => {
                let x = match v {
                    toml::Value::Float(f) => *f,
                    toml::Value::Integer(i) => *i as f64,
                    _ => return Err("expected a number".into()),
                };
                finite_non_negative(x).map(Value::Number)
            }
            Kind::Switch => v
                .as_bool()
                .map(Value::Switch)
                .ok_or_else(|| "expected true or false".into()),
            Kind::Choice(names) => v
                .as_str()
                .and_then(|s| names.iter().find(|n| **n == s))
                .map(|n| Value::Name(n))
                .ok_or_else(|| self.expected()),
            Kind::Clamp => match v {
                toml::Value::String(s) if s == "auto" => Ok(Value::Clamp(VplClamp::Auto)),
                toml::Value::Float(_) | toml::Value::Integer(_) => Kind::Number
                    .check_toml(v)
                    .map(|x| Value::Clamp(VplClamp::Fixed(x.number())))
                    .map_err(|_| CLAMP_EXPECTED.into()),
                _ => Err(CLAMP_EXPECTED.into()),
            },
        }
    }

    /// A flag's text, checked; Err(problem).
    pub fn parse_text(self, text: &str) -> Result<Value, String> {
        let t = text.trim();
        match self {
            Kind::Count { min, max } => match t.parse::<i128>() {
                Ok(i) if i >= min as i128 && i <= max as i128 => Ok(Value::Count(i as u32)),
                Ok(_) => Err(format!("must be in {min}..={max}")),
                Err(_) => Err(format!("expected a whole number in {min}..={max}")),
            },
            Kind::Number => match t.parse::<f64>() {
                Ok(x) => finite_non_negative(x).map(Value::Number),
                Err(_) => Err("expected a number".into()),
            },
            Kind::Switch => match t {
                "true" => Ok(Value::Switch(true)),
                "false" => Ok(Value::Switch(false)),
                _ => Err("expected true or false".into()),
            },
            Kind::Choice(names) => names
                .iter()
                .find(|n| **n == t)
                .map(|n| Value::Name(n))
                .ok_or_else(|| self.expected()),
            Kind::Clamp if t == "auto" => Ok(Value::Clamp(VplClamp::Auto)),
            Kind::Clamp => t
                .parse::<f64>()
                .ok()
                .and_then(|x| finite_non_negative(x).ok())
                .map(|b| Value::Clamp(VplClamp::Fixed(b)))
                .ok_or_else(|| CLAMP_EXPECTED.into()),
        }
    }

    fn expected(self) -> String {
        match self {
            Kind::Choice(names) => {
                let quoted: Vec<String> = names.iter().map(|c| format!("\"{c}\"")).collect();
                format!("expected one of {}", quoted.join(", "))
            }
            _ => unreachable!("only choices list names"),
        }
    }

    /// The flag's value name in help: N, X, true|false, the names, auto|B.
    pub fn value_name(self) -> String {
        match self {
            Kind::Count { .. } => "N".into(),
            Kind::Number => "X".into(),
            Kind::Switch => "true|false".into(),
            Kind::Choice(names) => names.join("|"),
            Kind::Clamp => "auto|B".into(),
        }
    }

    /// The range in help: `1..=65536`, `>= 0`, or empty where the value name says it.
    pub fn range(self) -> String {
        match self {
            Kind::Count { min, max } => format!("{min}..={max}"),
            Kind::Number => ">= 0".into(),
            Kind::Clamp => "auto or >= 0".into(),
            Kind::Switch | Kind::Choice(_) => String::new(),
        }
    }
}

/// What a clamp takes, for every value it refuses.
const CLAMP_EXPECTED: &str = "expected \"auto\" or a finite number >= 0";

fn finite_non_negative(x: f64) -> Result<f32, String> {
    if x.is_finite() && x >= 0.0 && x <= f32::MAX as f64 {
        // -0 as 0, so that a need on "0" (a clamp of 0) sees it.
        Ok(x as f32 + 0.0)
    } else {
        Err("must be a finite number >= 0".into())
    }
}

/// `S`'s defaults with `given` (key, value as written, checked value) set in table order, then
/// each given setting's `needs` checked on the result. Keys not in the table must have been
/// refused before.
pub fn build<S: Default>(
    method: &str,
    table: &[Setting<S>],
    given: &[(&str, String, Value)],
) -> Result<S, ParamError> {
    let mut s = S::default();
    let find = |key: &str| given.iter().find(|g| g.0 == key);
    for setting in table {
        if let Some((_, _, value)) = find(setting.key) {
            (setting.set)(&mut s, *value);
        }
    }
    for setting in table {
        if let Some((key, shown, _)) = find(setting.key) {
            applies(table, setting, &s, |k| find(k).is_some()).map_err(|problem| {
                ParamError::Value {
                    method: method.into(),
                    key: key.to_string(),
                    value: shown.clone(),
                    problem,
                }
            })?;
        }
    }
    Ok(s)
}

/// Whether `row` applies in `s`: Err(problem) for the first of its needs that does not hold,
/// naming what it needs and what the setting it reads is (`given(key)`: set explicitly, or
/// "the default").
fn applies<S>(
    table: &[Setting<S>],
    row: &Setting<S>,
    s: &S,
    given: impl Fn(&str) -> bool,
) -> Result<(), String> {
    let value_of = |key: &str| table.iter().find(|r| r.key == key).and_then(|r| (r.get)(s));
    let is = |key: &str| match value_of(key) {
        Some(v) if given(key) => shown(v),
        Some(v) => format!("{} (the default)", shown(v)),
        None => "unset".into(),
    };
    for need in row.needs {
        if !need.holds((row.get)(s), &value_of) {
            return Err(match need {
                Need::OneOf(key, _) => format!("applies with {}, not {}", need.describe(), is(key)),
                Need::AtMost(key) => format!("must be at most {key} = {}", is(key)),
                Need::Unset(key) => format!("applies with {key} unset, not {}", is(key)),
                Need::Not(..) | Need::Any(_) => format!("applies with {}", need.describe()),
            });
        }
    }
    Ok(())
}

impl Need {
    /// Whether it holds for a setting of value `own`, the others' values by `value_of(key)`.
    pub fn holds(self, own: Option<Value>, value_of: &dyn Fn(&str) -> Option<Value>) -> bool {
        match self {
            Need::OneOf(key, values) => {
                value_of(key).is_some_and(|v| values.contains(&v.to_string().as_str()))
            }
            Need::Not(key, value) => value_of(key).is_some_and(|v| v.to_string() != value),
            Need::Unset(key) => value_of(key).is_none(),
            Need::AtMost(key) => match (own, value_of(key)) {
                (Some(Value::Count(a)), Some(Value::Count(b))) => a <= b,
                _ => true,
            },
            Need::Any(needs) => needs.iter().any(|n| n.holds(own, value_of)),
        }
    }

    /// What it asks for, as a suite file writes values: `strategy = "dynamic" or "alpha"`,
    /// `clamp other than 0`, `at most spp`.
    pub fn describe(self) -> String {
        match self {
            Need::OneOf(key, values) => {
                let values: Vec<String> = values.iter().map(|v| shown_text(v)).collect();
                format!("{key} = {}", one_of(&values))
            }
            Need::Not(key, value) => format!("{key} other than {}", shown_text(value)),
            Need::Unset(key) => format!("{key} unset"),
            Need::AtMost(key) => format!("at most {key}"),
            Need::Any(needs) => {
                let each: Vec<String> = needs.iter().map(|n| n.describe()).collect();
                each.join(" or ")
            }
        }
    }
}

/// A setting's needs in words, for help: `with strategy = "alpha" and at most spp`.
pub fn describe_needs(needs: &[Need]) -> String {
    needs
        .iter()
        .map(|n| match n {
            Need::AtMost(_) => n.describe(),
            _ => format!("with {}", n.describe()),
        })
        .collect::<Vec<_>>()
        .join(" and ")
}

/// `a`, `a or b`, `a, b or c`.
fn one_of(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    }
}

/// A value as a suite file writes it: names quoted.
fn shown(v: Value) -> String {
    match v {
        Value::Name(s) => format!("\"{s}\""),
        Value::Clamp(VplClamp::Auto) => "\"auto\"".into(),
        v => v.to_string(),
    }
}

/// A need's value text as a suite file writes it: names quoted, switches and numbers not.
fn shown_text(text: &str) -> String {
    match text {
        "true" | "false" => text.into(),
        t if t.parse::<f64>().is_ok() => t.into(),
        t => format!("\"{t}\""),
    }
}

/// A suite file's parameter table read into `S`: unknown keys and bad values are errors
/// naming the method, key and value.
pub fn from_toml<S: Default>(
    method: &str,
    table: &[Setting<S>],
    params: &toml::Table,
) -> Result<S, ParamError> {
    let mut given = Vec::new();
    for (key, v) in params {
        let error = |problem: String| ParamError::Value {
            method: method.into(),
            key: key.clone(),
            value: v.to_string(),
            problem,
        };
        let Some(setting) = table.iter().find(|s| s.key == key) else {
            let known: Vec<&str> = table.iter().map(|s| s.key).collect();
            return Err(error(format!(
                "unknown parameter (known: {})",
                known.join(", ")
            )));
        };
        let value = setting.kind.check_toml(v).map_err(error)?;
        given.push((setting.key, v.to_string(), value));
    }
    build(method, table, &given)
}

/// `s`'s settings by key, sorted, unset ones and ones that do not apply beside the others
/// left out (so the map reads back through `build`).
pub fn values<S>(table: &[Setting<S>], s: &S) -> BTreeMap<String, serde_json::Value> {
    table
        .iter()
        .filter(|row| applies(table, row, s, |_| true).is_ok())
        .filter_map(|row| (row.get)(s).map(|v| (row.key.to_string(), v.to_json())))
        .collect()
}

/// The table's rows with `S`'s defaults, for help.
pub fn docs<S: Default>(table: &[Setting<S>]) -> Vec<SettingDoc> {
    let d = S::default();
    table
        .iter()
        .map(|row| SettingDoc {
            key: row.key,
            kind: row.kind,
            help: row.help,
            default: (row.get)(&d).map_or_else(|| row.unset.to_string(), |v| v.to_string()),
            needs: row.needs,
        })
        .collect()
}

/// A fieldless enum's names, written once: `ALL` lists the variants (in the order given),
/// `NAMES` their names in the same order (a setting's `Kind::Choice`), `name()` and
/// `from_name()` read them.
macro_rules! named_choices {
    ($ty:ident { $($variant:ident => $name:literal),+ $(,)? }) => {
        impl $ty {
            pub const ALL: [$ty; [$($name),+].len()] = [$($ty::$variant),+];
            pub const NAMES: &'static [&'static str] = &[$($name),+];

            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name),+
                }
            }

            /// The variant named `name`, if any.
            pub fn from_name(name: &str) -> Option<$ty> {
                Self::ALL.iter().copied().find(|v| v.name() == name)
            }
        }
    };
}
pub(crate) use named_choices;

/// A setting that is the struct's field `$field` as it is: `Count` (u32), `Number` (f32) or
/// `Switch` (bool), the `Value` variant of its `Kind`.
/// `field_setting!(..., needs: &[...])`: the same, applying only where the needs hold.
macro_rules! field_setting {
    ($key:literal, $field:ident, $kind:expr, $variant:ident, $help:expr, needs: $needs:expr $(,)?) => {
        $crate::methods::settings::with_needs(
            $needs,
            $crate::methods::settings::field_setting!($key, $field, $kind, $variant, $help),
        )
    };
    ($key:literal, $field:ident, $kind:expr, $variant:ident, $help:expr $(,)?) => {
        $crate::methods::settings::Setting::new(
            $key,
            $kind,
            $help,
            |s| Some($crate::methods::settings::Value::$variant(s.$field)),
            |s, v| match v {
                $crate::methods::settings::Value::$variant(x) => s.$field = x,
                v => unreachable!("{v:?} checked against {}", $key),
            },
        )
    };
}
pub(crate) use field_setting;

/// Settings several methods share, on fields of the same name (`pixel_centres`: `pixels`;
/// `clamp` and `compensate`: `clamp`); `frames` and `light_sampler` take the method's help;
/// `common_settings!(name, needs: &[...])` applies only where the needs hold.
macro_rules! common_settings {
    ($name:ident, needs: $needs:expr) => {
        $crate::methods::settings::with_needs(
            $needs,
            $crate::methods::settings::common_settings!($name),
        )
    };
    (seed) => {
        $crate::methods::settings::field_setting!(
            "seed",
            seed,
            $crate::methods::settings::SEED,
            Count,
            "Seed of every random and quasi-random number: same seed, same device, same bits.",
        )
    };
    (frames, $help:expr) => {
        $crate::methods::settings::field_setting!(
            "frames",
            frames,
            $crate::methods::settings::FRAMES,
            Count,
            $help,
        )
    };
    (shadows) => {
        $crate::methods::settings::field_setting!(
            "shadows",
            shadows,
            $crate::methods::settings::Kind::Switch,
            Switch,
            "Shadow rays; false counts every sample as visible, as in the thesis's timings: for \
             timing comparisons only, the image is wrong wherever light is occluded.",
        )
    };
    (light_sampler, $help:expr) => {
        $crate::methods::settings::Setting::new(
            "light_sampler",
            $crate::methods::settings::Kind::Choice($crate::methods::paths::LightSampler::NAMES),
            $help,
            |s| Some($crate::methods::settings::Value::Name(s.light_sampler.name())),
            |s, v| {
                s.light_sampler = $crate::methods::paths::LightSampler::from_name(v.name())
                    .expect("a checked name");
            },
        )
    };
    (pixel_centres) => {
        $crate::methods::settings::Setting::new(
            "pixel_centres",
            $crate::methods::settings::Kind::Switch,
            "Sample every pixel at its centre instead of over its area (no antialiasing): for \
             comparing methods without pixel-footprint noise (use it for the reference too).",
            |s| {
                Some($crate::methods::settings::Value::Switch(
                    s.pixels == $crate::methods::gbuffer::PixelSampling::Centres,
                ))
            },
            |s, v| {
                s.pixels = $crate::methods::gbuffer::PixelSampling::from_centres(v.switch());
            },
        )
    };
    (rebuild_tables) => {
        $crate::methods::settings::Setting::new(
            "rebuild_tables",
            $crate::methods::settings::Kind::Choice($crate::methods::rebuild::TableRebuild::NAMES),
            "Build the sampling tables derived from the map or atlas once for a still input \
             and per frame for a sequence, or every frame as Lu 14's dynamic pipeline does \
             (for timing it; the same image bits for a still input).",
            |s| Some($crate::methods::settings::Value::Name(s.rebuild.name())),
            |s, v| {
                s.rebuild = $crate::methods::rebuild::TableRebuild::from_name(v.name())
                    .expect("a checked name");
            },
        )
    };
    (clamp) => {
        $crate::methods::settings::Setting::new(
            "clamp",
            $crate::methods::settings::Kind::Clamp,
            "Clamp the VPL gather's geometry term cos cos / d^2 at b (Keller's weak \
             singularity: no spikes next to VPLs). auto: b = N / A for N surface VPLs per frame \
             over the scene's area A (pi VPLs expected within 1 / sqrt(b) of a point); a number \
             sets b; 0 leaves the term unclamped. The b used is in the JSON's stats.",
            |s| Some($crate::methods::settings::Value::Clamp(s.clamp.clamp)),
            |s, v| {
                s.clamp.clamp = v.clamp();
            },
        )
    };
    (compensate) => {
        $crate::methods::settings::Setting::new(
            "compensate",
            $crate::methods::settings::Kind::Switch,
            "With a clamp, add back exactly what it removed by short paths from the shading \
             point (Kollig and Keller 2004; unbiased), or leave the clamp's bias (false).",
            |s| Some($crate::methods::settings::Value::Switch(s.clamp.compensate)),
            |s, v| {
                s.clamp.compensate = v.switch();
            },
        )
    };
    (direct_spp) => {
        $crate::methods::settings::field_setting!(
            "direct_spp",
            direct_spp,
            $crate::methods::settings::Kind::Count {
                min: 1,
                max: $crate::methods::direct::MAX_DIRECT_SPP,
            },
            Count,
            "Direct-light samples per pixel and frame, each from its own camera ray at a new \
             subpixel position, so direct light and the pixel footprint get this many samples \
             per expensive frame while the VPL gather shades one position \
             (docs/methods/ir.md \"Budgets\").",
        )
    };
}
pub(crate) use common_settings;

/// The range of `seed`.
pub const SEED: Kind = Kind::Count {
    min: 0,
    max: u32::MAX,
};
/// The range of every `frames`.
pub const FRAMES: Kind = Kind::Count {
    min: 1,
    max: u32::MAX,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_and_text_agree_on_every_kind() {
        let kinds = [
            Kind::Count { min: 2, max: 9 },
            Kind::Number,
            Kind::Switch,
            Kind::Choice(&["a", "b-c"]),
            Kind::Clamp,
        ];
        let cases: &[(&str, &str)] = &[
            ("2", "2"),
            ("9", "9"),
            ("10", "10"),
            ("1", "1"),
            ("-1", "-1"),
            ("0.5", "0.5"),
            ("true", "true"),
            ("false", "false"),
            ("\"a\"", "a"),
            ("\"b-c\"", "b-c"),
            ("\"d\"", "d"),
            ("\"auto\"", "auto"),
            ("nan", "NaN"),
            ("inf", "inf"),
        ];
        for kind in kinds {
            for (toml_text, flag_text) in cases {
                let t: toml::Table = toml::from_str(&format!("v = {toml_text}")).unwrap();
                let from_toml = kind.check_toml(&t["v"]);
                let from_text = kind.parse_text(flag_text);
                // Where TOML has a type the flag text lacks (the integer 2 read as a number),
                // both accept or both refuse.
                assert_eq!(
                    from_toml.is_ok(),
                    from_text.is_ok(),
                    "{kind:?}: {toml_text} -> {from_toml:?}, {flag_text} -> {from_text:?}"
                );
                if let (Ok(a), Ok(b)) = (from_toml, from_text) {
                    assert_eq!(a, b, "{kind:?} {toml_text}");
                }
            }
        }
    }
}
