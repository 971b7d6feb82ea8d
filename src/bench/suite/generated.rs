//! Generated scene families in a suite: a `[[scene]]` with `path = "generated:many-lights"` and
//! `lights = N` (or a list of counts) stands for the hall `scripts/generate-many-lights.py
//! --lights N` writes, one scene per count, named `many-lights-N`. The generator is
//! deterministic, so each hall is generated once into a cache folder (`out/generated` unless
//! the loader is told otherwise), keyed by the count and a hash of the script, and loaded from
//! there like any scene file; the suite's scene list, hash and runs then treat the members as
//! ordinary scenes. Each member records its generator and count (`Generated`), which the report
//! charts against (report.rs, "Light count").

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde::{Deserialize, Serialize};

use crate::scene::hash::fnv1a64;

/// A suite scene's path names a generator with this prefix: `generated:many-lights`.
pub const PREFIX: &str = "generated:";

/// A generator: a script of the source tree that writes a scene with a given light count.
pub struct Generator {
    /// As the suite names it after `generated:`; its members are `<name>-<lights>`.
    pub name: &'static str,
    /// The script, relative to the source tree irad was built from; run as
    /// `python3 SCRIPT --out DIR --lights N`.
    pub script: &'static str,
    /// The scene file it writes, relative to `--out`.
    pub scene: &'static str,
    /// The largest count it takes (the smallest is 1).
    pub max_lights: u32,
}

/// The generators a suite can name.
pub const GENERATORS: &[Generator] = &[Generator {
    name: "many-lights",
    script: "scripts/generate-many-lights.py",
    scene: "many-lights/scene.toml",
    max_lights: 1 << 20,
}];

/// A member of a generated family: which generator made it, with how many lights (the
/// generator's count: the hall's emissive quads, two triangles each).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Generated {
    pub generator: String,
    pub lights: u32,
}

impl Generated {
    /// The member's scene name: `many-lights-1024`.
    pub fn scene_name(&self) -> String {
        format!("{}-{}", self.generator, self.lights)
    }

    /// The member's path as results and messages show it: `generated:many-lights lights=1024`.
    pub fn path(&self) -> String {
        format!("{PREFIX}{} lights={}", self.generator, self.lights)
    }
}

/// The generator `name` (after `generated:`), or a message listing those there are.
pub fn generator(name: &str) -> Result<&'static Generator, String> {
    GENERATORS.iter().find(|g| g.name == name).ok_or_else(|| {
        let names: Vec<String> = GENERATORS
            .iter()
            .map(|g| format!("{PREFIX}{}", g.name))
            .collect();
        format!("no such generator: the generators are {}", names.join(", "))
    })
}

/// The default cache of generated scenes: out/generated.
pub fn default_folder() -> PathBuf {
    Path::new("out").join("generated")
}

/// The script of `g` in the source tree irad was built from.
pub fn script_path(g: &Generator) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(g.script)
}

/// The scene file of `g` with `lights` lights under `folder`, generated there first unless an
/// earlier run left it: `<folder>/<name>-<lights>-<hash of the script>/`. Generated under a
/// temporary name and renamed into place, so a reader never sees half a scene and two suites
/// generating the same member at once both end with one whole copy.
pub fn scene_file(g: &Generator, lights: u32, folder: &Path) -> Result<PathBuf, String> {
    let script = script_path(g);
    let text = fs::read(&script).map_err(|e| {
        format!(
            "cannot read the generator {} ({e}): irad runs it from the source tree it was built \
             in",
            script.display()
        )
    })?;
    let dir = folder.join(format!("{}-{lights}-{:016x}", g.name, fnv1a64(&text)));
    let scene = dir.join(g.scene);
    if scene.is_file() {
        return Ok(scene);
    }
    fs::create_dir_all(folder).map_err(|e| format!("cannot create {}: {e}", folder.display()))?;
    remove_abandoned(folder, &format!(".{}-{lights}.", g.name));
    let tmp = folder.join(format!(
        ".{}-{lights}.{}",
        g.name,
        super::references::unique_suffix()
    ));
    log::info!(
        "generating {PREFIX}{} with {lights} lights into {} (once: later suites reuse it)",
        g.name,
        dir.display()
    );
    let run = Command::new("python3")
        .arg(&script)
        .arg("--out")
        .arg(&tmp)
        .arg("--lights")
        .arg(lights.to_string())
        .output();
    let generated = match run {
        Err(e) => Err(format!(
            "cannot run python3 ({e}), which runs the generator {} (install it: apt-get \
             install python3)",
            script.display()
        )),
        Ok(o) if !o.status.success() => Err(format!(
            "python3 {} --out {} --lights {lights} failed ({}): {}",
            script.display(),
            tmp.display(),
            o.status,
            String::from_utf8_lossy(&o.stderr).trim()
        )),
        Ok(_) => Ok(()),
    };
    if let Err(e) = generated {
        let _ = fs::remove_dir_all(&tmp);
        return Err(e);
    }
    if let Err(e) = fs::rename(&tmp, &dir) {
        // Another suite put the same member in place meanwhile: use its copy.
        let _ = fs::remove_dir_all(&tmp);
        if !scene.is_file() {
            return Err(format!(
                "cannot rename {} to {}: {e}",
                tmp.display(),
                dir.display()
            ));
        }
    }
    if !scene.is_file() {
        return Err(format!(
            "the generator ran but wrote no {}",
            scene.display()
        ));
    }
    Ok(scene)
}

/// Removes the temporary folders under `folder` named `<prefix><host>.<pid>.<time>.tmp`
/// (`unique_suffix`) that a generation on this host left when it was stopped: their process is
/// gone. Another host's, or a running process's, are left alone.
fn remove_abandoned(folder: &Path, prefix: &str) {
    let Ok(entries) = fs::read_dir(folder) else {
        return;
    };
    if !Path::new("/proc/self").exists() {
        return; // no way to tell a running process here
    }
    let mine = format!("{prefix}{}.", super::references::host_name());
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = name.strip_prefix(&mine) else {
            continue;
        };
        let pid = rest.split('.').next().unwrap_or_default();
        let gone = name.ends_with(".tmp")
            && pid.parse::<u32>().is_ok_and(|pid| {
                pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists()
            });
        if gone {
            log::info!(
                "removing {}, left by a stopped generation",
                entry.path().display()
            );
            let _ = fs::remove_dir_all(entry.path());
        }
    }
}

/// The counts of a `lights` value: one count or a list of them, each in 1..=`max`, none twice.
/// Err: (the field, the value, the problem).
pub fn counts(value: &toml::Value, max: u32) -> Result<Vec<u32>, (String, String, String)> {
    let one = |v: &toml::Value, at: &str| -> Result<u32, (String, String, String)> {
        match v.as_integer() {
            Some(n) if (1..=i64::from(max)).contains(&n) => Ok(n as u32),
            _ => Err((
                at.to_string(),
                v.to_string(),
                format!("a light count is an integer from 1 to {max}"),
            )),
        }
    };
    match value {
        toml::Value::Array(list) => {
            if list.is_empty() {
                return Err((
                    String::new(),
                    "[]".into(),
                    "names no count: give one or more".into(),
                ));
            }
            let mut out: Vec<u32> = Vec::new();
            for (k, v) in list.iter().enumerate() {
                let n = one(v, &format!("[{k}]"))?;
                if out.contains(&n) {
                    return Err((
                        format!("[{k}]"),
                        n.to_string(),
                        "listed twice: each count is one scene".into(),
                    ));
                }
                out.push(n);
            }
            Ok(out)
        }
        v => one(v, "").map(|n| vec![n]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_take_one_or_a_list_and_refuse_the_rest() {
        let v = |s: &str| -> toml::Value {
            format!("x = {s}").parse::<toml::Table>().unwrap()["x"].clone()
        };
        assert_eq!(counts(&v("1024"), 1 << 20), Ok(vec![1024]));
        assert_eq!(
            counts(&v("[1, 4096, 1048576]"), 1 << 20),
            Ok(vec![1, 4096, 1 << 20])
        );
        let err = |s: &str| counts(&v(s), 1 << 20).unwrap_err();
        assert_eq!(err("0").0, "");
        assert!(err("0").2.contains("from 1 to 1048576"));
        assert_eq!(err("[16, 1048577]").0, "[1]");
        assert_eq!(err("[16, 1048577]").1, "1048577");
        assert_eq!(err("[16, \"a\"]").1, "\"a\"");
        assert_eq!(err("2.5").1, "2.5");
        assert!(err("[]").2.contains("names no count"));
        let twice = err("[16, 32, 16]");
        assert_eq!((twice.0.as_str(), twice.1.as_str()), ("[2]", "16"));
        assert!(twice.2.contains("listed twice"));
    }

    #[test]
    fn a_stopped_generation_is_cleaned_up_and_a_running_one_kept() {
        let folder = std::env::temp_dir().join(format!("irad-abandoned-{}", std::process::id()));
        let _ = fs::remove_dir_all(&folder);
        let host = crate::bench::suite::references::host_name();
        // No process has pid u32::MAX - 1 (Linux's pid_max is at most 2^22).
        let stopped = format!(".many-lights-64.{host}.{}.1.tmp", u32::MAX - 1);
        let running = format!(".many-lights-64.{host}.{}.1.tmp", std::process::id());
        let other_host = format!(".many-lights-64.elsewhere-{host}.{}.1.tmp", u32::MAX - 1);
        let other_count = format!(".many-lights-128.{host}.{}.1.tmp", u32::MAX - 1);
        for name in [&stopped, &running, &other_host, &other_count] {
            fs::create_dir_all(folder.join(name).join("many-lights")).unwrap();
        }
        remove_abandoned(&folder, ".many-lights-64.");
        assert!(!folder.join(&stopped).exists());
        for kept in [&running, &other_host, &other_count] {
            assert!(folder.join(kept).exists(), "{kept}");
        }
        fs::remove_dir_all(&folder).unwrap();
    }

    #[test]
    fn members_are_named_by_generator_and_count() {
        let m = Generated {
            generator: "many-lights".into(),
            lights: 4096,
        };
        assert_eq!(m.scene_name(), "many-lights-4096");
        assert_eq!(m.path(), "generated:many-lights lights=4096");
        assert!(generator("many-lights").is_ok());
        let e = generator("hall").err().unwrap();
        assert!(e.contains("generated:many-lights"), "{e}");
    }
}
