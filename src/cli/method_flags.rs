//! `irad render`'s method flags, built from the methods' settings tables
//! (src/methods/settings.rs): `--` + each key with `_` written `-`, once across the methods,
//! grouped under a help heading per method (flags several methods take under one heading, their
//! help per method). The chosen method then reads the flags given through its own table, so
//! the CLI and suite files share every name, default and range, and a flag the method does not
//! take is an error.

use anyhow::{anyhow, bail, Result};
use clap::parser::ValueSource;
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};

use irad::methods::settings::{Kind, SettingDoc};
use irad::methods::{Method, ParamError, Registry};

/// The method flags given on the command line, as (key, text).
#[derive(Clone, Debug, Default)]
pub struct MethodFlags {
    pub given: Vec<(&'static str, String)>,
}

/// A key's flag: `--max-depth` for `max_depth`.
pub fn flag(key: &str) -> String {
    format!("--{}", key.replace('_', "-"))
}

/// Every method's settings, in the registry's order.
fn all_settings() -> Vec<(&'static str, Vec<SettingDoc>)> {
    Registry::builtin()
        .entries()
        .iter()
        .map(|e| (e.name(), e.docs()))
        .collect()
}

/// Each key once, in order of first appearance, with the methods that take it.
fn keys() -> Vec<(&'static str, Vec<(&'static str, SettingDoc)>)> {
    let mut keys: Vec<(&'static str, Vec<(&'static str, SettingDoc)>)> = Vec::new();
    for (method, docs) in all_settings() {
        for doc in docs {
            match keys.iter_mut().find(|(k, _)| *k == doc.key) {
                Some((_, takers)) => takers.push((method, doc)),
                None => keys.push((doc.key, vec![(method, doc)])),
            }
        }
    }
    keys
}

/// `[default: D; RANGE]`, with each method's default where they differ.
fn default_and_range(takers: &[(&str, &SettingDoc)]) -> String {
    let first = takers[0].1;
    let defaults = match takers.iter().all(|(_, d)| d.default == first.default) {
        true => first.default.clone(),
        false => takers
            .iter()
            .map(|(m, d)| format!("{} {m}", d.default))
            .collect::<Vec<_>>()
            .join(", "),
    };
    match first.kind.range() {
        r if r.is_empty() => format!("[default: {defaults}]"),
        r => format!("[default: {defaults}; {r}]"),
    }
}

/// The methods that take a key grouped by the same help text and range, in order.
fn groups<'a>(
    takers: &'a [(&'static str, SettingDoc)],
) -> Vec<Vec<(&'static str, &'a SettingDoc)>> {
    let mut groups: Vec<Vec<(&str, &SettingDoc)>> = Vec::new();
    for (method, doc) in takers {
        match groups
            .iter_mut()
            .find(|g| g[0].1.help == doc.help && g[0].1.kind == doc.kind)
        {
            Some(g) => g.push((method, doc)),
            None => groups.push(vec![(method, doc)]),
        }
    }
    groups
}

/// The `--help` text of a key: per group of methods with the same text, its methods, text,
/// defaults and range.
fn long_help(takers: &[(&'static str, SettingDoc)]) -> String {
    let groups = groups(takers);
    groups
        .iter()
        .map(|g| {
            let methods: Vec<&str> = g.iter().map(|(m, _)| *m).collect();
            let text = format!("{} {}", g[0].1.help, default_and_range(g));
            match takers.len() {
                1 => text,
                _ => format!("{}: {text}", methods.join(", ")),
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The `-h` text of a key: its first sentence, or the methods that take it.
fn short_help(takers: &[(&'static str, SettingDoc)]) -> String {
    let groups = groups(takers);
    // A sentence ends at ". " before a capital ("ch. 5", "Eq. 7" go on).
    let first_sentence = |text: &str| {
        let end = text
            .match_indices(". ")
            .find(|(i, _)| text[i + 2..].starts_with(|c: char| c.is_ascii_uppercase()));
        match end {
            Some((i, _)) => text[..=i].to_string(),
            None => text.to_string(),
        }
    };
    match groups.as_slice() {
        [g] => format!("{} {}", first_sentence(g[0].1.help), default_and_range(g)),
        _ => {
            let methods: Vec<&str> = takers.iter().map(|(m, _)| *m).collect();
            format!("{}: see --help", methods.join(", "))
        }
    }
}

/// The heading of flags several methods take.
pub const SHARED_HEADING: &str = "Settings of several methods";

impl Args for MethodFlags {
    fn augment_args(mut cmd: Command) -> Command {
        for (key, takers) in keys() {
            let heading = match takers.as_slice() {
                [(method, _)] => format!("Settings of --method {method}"),
                _ => SHARED_HEADING.to_string(),
            };
            let kind = takers[0].1.kind;
            let value_name = match takers.iter().all(|(_, d)| d.kind == kind) {
                true => kind.value_name(),
                false => match kind {
                    Kind::Choice(_) => "NAME".into(),
                    k => k.value_name(),
                },
            };
            let mut arg = Arg::new(key)
                .long(flag(key).trim_start_matches('-').to_string())
                .value_name(value_name)
                .help(short_help(&takers))
                .long_help(long_help(&takers))
                .help_heading(heading)
                .action(ArgAction::Set);
            arg = match kind {
                Kind::Switch => arg
                    .num_args(0..=1)
                    .require_equals(true)
                    .default_missing_value("true"),
                // `--seed -1` and `--clamp -inf` reach the table's checks, which name the flag,
                // the value and what it takes, not clap's "unexpected argument '-i'" or its tip
                // to write `-- -1`.
                Kind::Count { .. } | Kind::Number | Kind::Clamp => arg.allow_hyphen_values(true),
                Kind::Choice(_) => arg,
            };
            cmd = cmd.arg(arg);
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for MethodFlags {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let given = keys()
            .into_iter()
            .filter(|(key, _)| m.value_source(key) == Some(ValueSource::CommandLine))
            .filter_map(|(key, _)| m.get_one::<String>(key).map(|v| (key, v.clone())))
            .collect();
        Ok(MethodFlags { given })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

/// The switch flag (`--shadows`) that `value` follows in `args`, where `value` looks like a
/// switch's value given after a space (`--two-bounce off`), which clap takes as the scene: not
/// a flag, not an existing file, not a `.toml` path.
pub fn switch_before(args: &[String], value: &str) -> Option<String> {
    let looks_like_a_value = !value.starts_with('-')
        && !value.ends_with(".toml")
        && !std::path::Path::new(value).exists();
    if !looks_like_a_value {
        return None;
    }
    let switches: Vec<String> = keys()
        .into_iter()
        .filter(|(_, takers)| takers.iter().all(|(_, d)| d.kind == Kind::Switch))
        .map(|(key, _)| flag(key))
        .collect();
    args.windows(2)
        .find(|w| w[1] == value && switches.contains(&w[0]))
        .map(|w| w[0].clone())
}

/// `--flag=VALUE` for a switch given `value` after a space: true or false where `value` reads
/// as one (on, no, 0, ...), else both.
pub fn switch_written(flag: &str, value: &str) -> String {
    match value.to_ascii_lowercase().as_str() {
        "true" | "on" | "yes" | "y" | "1" => format!("`{flag}=true`"),
        "false" | "off" | "no" | "n" | "0" => format!("`{flag}=false`"),
        _ => format!("`{flag}=true` or `{flag}=false`"),
    }
}

/// A tip for a switch given its value after a space (`--shadows false`), which clap takes as
/// the scene: the value goes after `=`.
pub fn switch_tip(args: &[String]) -> Option<String> {
    args.iter().find_map(|value| {
        switch_before(args, value).map(|flag| {
            format!(
                "tip: {flag} is a switch and takes its value after `=`: {}",
                switch_written(&flag, value)
            )
        })
    })
}

impl MethodFlags {
    /// `method` with the flags given over its defaults; a flag it does not take, a value out of
    /// its range or a setting that does not apply is an error naming the flag and the method.
    pub fn method(&self, method: &str) -> Result<Method> {
        let docs = Method::settings(method)?;
        let mut given = Vec::new();
        for (key, text) in &self.given {
            let flag = flag(key);
            let Some(doc) = docs.iter().find(|d| d.key == *key) else {
                let takes: Vec<String> = docs.iter().map(|d| self::flag(d.key)).collect();
                bail!(
                    "{flag} does not apply to --method {method} (it takes {}; `irad methods {method}` explains them)",
                    takes.join(", ")
                );
            };
            let value = doc
                .kind
                .parse_text(text)
                .map_err(|problem| anyhow!("{flag} {text}: {problem} (--method {method})"))?;
            given.push((*key, text.clone(), value));
        }
        Method::from_values(method, &given).map_err(|e| match e {
            ParamError::Value {
                key,
                value,
                problem,
                ..
            } => anyhow!("{} {value}: {problem} (--method {method})", flag(&key)),
            e => e.into(),
        })
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use crate::cli::{Cli, Command};

    /// `irad render --method METHOD FLAGS...`'s method.
    fn cli(method: &str, flags: &[String]) -> Result<Method> {
        let mut argv = vec!["irad".to_string(), "render".into(), "--method".into()];
        argv.push(method.into());
        argv.extend(flags.iter().cloned());
        match Cli::try_parse_from(argv)?.command {
            Command::Render(args) => args.method(),
            _ => unreachable!("a render command"),
        }
    }

    /// A suite file's `params` with `key = toml` read for `method`.
    fn suite(method: &str, key: &str, toml: &str) -> Result<Method, ParamError> {
        let table: toml::Table = toml::from_str(&format!("{key} = {toml}")).unwrap();
        Method::from_params(method, &table)
    }

    /// Values to try for a kind, as flag text and as TOML: its edges, one past them, and a
    /// value of the wrong type.
    fn samples(kind: Kind) -> Vec<(String, String)> {
        let same = |t: &str| (t.to_string(), t.to_string());
        let quoted = |t: &str| (t.to_string(), format!("\"{t}\""));
        match kind {
            Kind::Count { min, max } => {
                let mut v = vec![same(&min.to_string()), same(&max.to_string())];
                v.push(same(&(min as i64 - 1).to_string()));
                v.push(same(&(max as i64 + 1).to_string()));
                v.push(quoted("x"));
                v
            }
            Kind::Number => vec![same("0"), same("2.5"), same("-1"), quoted("x")],
            Kind::Switch => vec![same("true"), same("false"), quoted("yes")],
            Kind::Choice(names) => {
                let mut v: Vec<_> = names.iter().map(|n| quoted(n)).collect();
                v.push(quoted("bogus"));
                v
            }
            Kind::Clamp => vec![
                quoted("auto"),
                same("0"),
                same("3.5"),
                same("-1"),
                quoted("x"),
            ],
        }
    }

    /// Every method's settings, walked through the CLI and a suite file, have the same names,
    /// defaults and ranges (docs/DESIGN.md "Settings tables"): each flag and key gives the same
    /// method or the same problem, and another method's settings are refused by both.
    #[test]
    fn cli_flags_and_suite_keys_are_the_same_settings() {
        let all_keys: Vec<&str> = keys().into_iter().map(|(k, _)| k).collect();
        let mut compared = 0;
        for method in Registry::builtin().names() {
            // The defaults.
            let default = Method::from_params(method, &toml::Table::new()).unwrap();
            assert_eq!(cli(method, &[]).unwrap(), default, "{method} defaults");
            let docs = Method::settings(method).unwrap();
            for doc in &docs {
                // The shown default, given explicitly, changes nothing; an unset one is
                // described in words and left out of the record.
                match doc.kind.parse_text(&doc.default) {
                    Ok(_) => assert_eq!(
                        cli(method, &[format!("{}={}", flag(doc.key), doc.default)]).unwrap(),
                        default,
                        "{method} {} = {}: the shown default is the settings' default",
                        doc.key,
                        doc.default
                    ),
                    Err(_) => assert!(
                        !default.parameters().contains_key(doc.key),
                        "{method} {}: unset by default",
                        doc.key
                    ),
                }
                for (text, toml) in samples(doc.kind) {
                    let from_cli = cli(method, &[format!("{}={text}", flag(doc.key))]);
                    let from_suite = suite(method, doc.key, &toml);
                    match (&from_cli, &from_suite) {
                        (Ok(a), Ok(b)) => assert_eq!(a, b, "{method} {} = {text}", doc.key),
                        (Err(a), Err(ParamError::Value { problem, .. })) => {
                            // Where the flag text has no type to get wrong ("x" for a
                            // number), both still refuse; the problem reads the same.
                            let a = a.to_string();
                            assert!(
                                a.contains(problem.as_str()) || problem.starts_with("expected"),
                                "{method} {} = {text}: CLI `{a}`, suite `{problem}`",
                                doc.key
                            );
                        }
                        (a, b) => panic!("{method} {} = {text}: CLI {a:?}, suite {b:?}", doc.key),
                    }
                    compared += 1;
                }
            }
            // Every other method's settings are refused by both.
            for key in all_keys
                .iter()
                .filter(|k| !docs.iter().any(|d| d.key == **k))
            {
                let (_, takers) = keys().into_iter().find(|(k, _)| k == key).unwrap();
                let (text, toml) = samples(takers[0].1.kind).remove(0);
                let e = cli(method, &[format!("{}={text}", flag(key))]).unwrap_err();
                assert!(
                    e.to_string().starts_with(&format!(
                        "{} does not apply to --method {method}",
                        flag(key)
                    )),
                    "{e}"
                );
                let e = suite(method, key, &toml).unwrap_err();
                assert!(e.to_string().contains("unknown parameter"), "{e}");
            }
        }
        assert!(compared > 250, "{compared} values compared");
    }
}
