//! `irad bench merge <dirs...>`: combines the output folders of a suite's shards (run on any
//! number of machines by any batch system) into one folder with one results.json, CSV, set of
//! charts and report, as if the suite had run in one go. Parts must come from the same suite
//! (equal suite hash: same suite text, same scene contents); a run recorded by two parts is
//! an error, and missing runs leave the merged results marked incomplete. Parts measured on
//! different devices, drivers or irad versions are refused unless allowed: their GPU times
//! do not share an axis (when allowed, each device gets its own lines and Pareto marks).

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};

use super::output;
use super::results::SuiteResults;

/// Merges the results in `parts` into `out` (which must not be one of them).
pub fn merge(parts: &[PathBuf], out: &Path, allow_mixed_devices: bool) -> Result<SuiteResults> {
    if parts.is_empty() {
        bail!("nothing to merge: name the output folders of the shards");
    }
    let out_abs = fs::canonicalize(out).ok();
    let mut merged: Option<SuiteResults> = None;
    let mut seen: BTreeMap<usize, PathBuf> = BTreeMap::new();
    let mut devices: Vec<String> = Vec::new();
    let mut loaded = Vec::new();
    for part in parts {
        if out_abs.is_some() && fs::canonicalize(part).ok() == out_abs {
            bail!(
                "{}: the merge output cannot be one of its parts",
                part.display()
            );
        }
        let results = SuiteResults::read(&part.join("results.json"))?;
        if let Some(m) = &merged {
            if m.suite_hash != results.suite_hash {
                bail!(
                    "{}: suite `{}` (hash {}) is not the suite of {} (`{}`, hash {}): parts must come from the same suite file and scenes",
                    part.display(),
                    results.suite,
                    results.suite_hash,
                    parts[0].display(),
                    m.suite,
                    m.suite_hash
                );
            }
        }
        for r in &results.runs {
            if let Some(other) = seen.insert(r.index, part.clone()) {
                bail!(
                    "run {} ({}) is in both {} and {}: merge each shard once",
                    r.index,
                    r.id,
                    other.display(),
                    part.display()
                );
            }
        }
        let device = format!(
            "{} (driver {}, irad {})",
            results.device, results.driver, results.irad_version
        );
        if !devices.contains(&device) {
            if !devices.is_empty() && !allow_mixed_devices {
                bail!(
                    "{}: measured on {device}, but {} on {}: GPU times of different devices, drivers or builds are not comparable (pass --allow-mixed-devices to merge them anyway, each device charted apart)",
                    part.display(),
                    parts[0].display(),
                    devices[0]
                );
            }
            devices.push(device);
        }
        match &mut merged {
            None => merged = Some(results.clone()),
            Some(m) => {
                m.runs.extend(results.runs.iter().cloned());
                m.references.extend(results.references.clone());
                m.complete &= results.complete;
            }
        }
        loaded.push((part.clone(), results));
    }
    let mut merged = merged.expect("at least one part");
    merged.shard = None;
    merged.runs.sort_by_key(|r| r.index);
    merged.runs_planned = merged.runs_in_suite;
    merged.complete = merged.complete && merged.runs.len() == merged.runs_in_suite;
    if devices.len() > 1 {
        merged.device = format!("mixed: {}", devices.join("; "));
        merged.driver = "see each run".into();
    }
    merged.mark_pareto();

    output::prepare(out)?;
    for (part, _) in &loaded {
        let images = part.join("images");
        let entries =
            fs::read_dir(&images).with_context(|| format!("reading {}", images.display()))?;
        for entry in entries {
            let entry = entry.with_context(|| format!("reading {}", images.display()))?;
            let to = out.join("images").join(entry.file_name());
            fs::copy(entry.path(), &to).with_context(|| {
                format!("copying {} to {}", entry.path().display(), to.display())
            })?;
        }
    }
    output::write(out, &merged)?;
    Ok(merged)
}
