//! `irad methods [NAME]`: the methods, or one method's settings with their defaults and
//! ranges, from the settings tables every other way of setting a method reads.

use anyhow::Result;

use irad::methods::lights::Support;
use irad::methods::settings::{describe_needs, Kind};
use irad::methods::Registry;

use super::method_flags::flag;

#[derive(clap::Args)]
pub struct MethodsArgs {
    /// A method: list its settings (default: list the methods).
    name: Option<String>,
}

pub fn run(args: &MethodsArgs) -> Result<()> {
    let Some(name) = &args.name else {
        println!("methods (`irad methods NAME` lists one's settings):");
        for e in Registry::builtin().entries() {
            println!("  {:<12}{}", e.name(), e.summary());
        }
        println!();
        println!(
            "what each renders (yes; needs: a scene without it is declined; - declined) and the \
             flag of its count, the work `irad render` and a suite's budgets set:"
        );
        println!(
            "  {:<12}{:<14}{:<13}{:<11}{:<14}luminaires",
            "method", "count flag", "environment", "emissive", "point, spot"
        );
        for e in Registry::builtin().entries() {
            let l = e.lights();
            println!(
                "  {:<12}{:<14}{:<13}{:<11}{:<14}{}",
                e.name(),
                flag(e.count_key()),
                support(l.environment),
                support(l.area),
                support(l.point),
                support(l.luminaires)
            );
        }
        return Ok(());
    };
    let entry = Registry::builtin().get(name)?;
    let (settings, about) = (entry.docs(), entry.summary());
    println!("{name}: {about}");
    println!(
        "across animation frames it keeps {}",
        entry.across_frames().describe()
    );
    println!(
        "settings: `irad render --method {name} --FLAG VALUE` (a switch: `--FLAG` or \
         `--FLAG=false`), or `KEY = VALUE` in a suite's params"
    );
    for s in &settings {
        let range = s.kind.range();
        println!();
        let value = match s.kind {
            Kind::Switch => "[=true|false]".to_string(),
            kind => format!(" {}", kind.value_name()),
        };
        println!(
            "  {}{value}  (suite: {})  default {}{}",
            flag(s.key),
            s.key,
            s.default,
            if range.is_empty() {
                String::new()
            } else {
                format!(", {range}")
            }
        );
        for line in wrap(s.help, 88) {
            println!("      {line}");
        }
        if !s.needs.is_empty() {
            let only = format!(
                "Only {} (refused beside other values).",
                describe_needs(s.needs)
            );
            for line in wrap(&only, 88) {
                println!("      {line}");
            }
        }
    }
    Ok(())
}

/// A kind of light's support as the methods table writes it.
fn support(s: Support) -> &'static str {
    match s {
        Support::Renders => "yes",
        Support::Needs(_) => "needs",
        Support::Declines(_) => "-",
    }
}

/// `text` in lines of at most `width` characters, broken at spaces.
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        if !line.is_empty() && line.len() + 1 + word.len() > width {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}
