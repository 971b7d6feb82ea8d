//! `irad bench merge <dirs...>`: combines the output folders of a suite's shards (run on any
//! number of machines by any batch system) into one folder with one results.json, CSV, set of
//! charts and report, as if the suite had run in one go. Parts must come from the same suite
//! (equal suite hash: same suite text, same scene contents); a run recorded by two parts is
//! an error, and missing runs leave the merged results marked incomplete. Parts measured on
//! different devices, drivers or irad versions are refused unless allowed: their GPU times
//! do not share an axis (when allowed, each device gets its own lines and Pareto marks).
//!
//! Every part is checked (its results, its images/ and every image its results name) before
//! anything is written. The merged folder is built under a temporary name beside the output
//! folder and renamed into place, with the output folder locked as a suite locks it, so a
//! failed merge leaves no half-built folder and a suite writing there meanwhile is refused.

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
        check_images(part, &results)?;
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
                // Each part uploads the scenes of its runs and times the CPU builds itself:
                // the first part's figures stand (sorted parts: the same merge draws the same
                // chart). A device that refused what another held is said, not hidden.
                for (scene, upload) in &results.uploads {
                    match m.uploads.get(scene) {
                        None => {
                            m.uploads.insert(scene.clone(), upload.clone());
                        }
                        Some(first) if first.refused.is_some() != upload.refused.is_some() => {
                            log::warn!(
                                "{scene}: {} by the device of {}, but not by another part's: \
                                 the merged upload figures are the first part's",
                                match upload.refused {
                                    Some(_) => "refused",
                                    None => "held",
                                },
                                part.display()
                            );
                        }
                        Some(_) => {}
                    }
                }
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

    check_target(out)?;
    let _lock = output::lock(out, &mut |holder| {
        log::warn!(
            "{}: took over the lock left by {holder}, which is no longer running",
            out.display()
        )
    })?;
    let target = fs::canonicalize(out).with_context(|| format!("resolving {}", out.display()))?;
    let (Some(parent), Some(name)) = (target.parent(), target.file_name()) else {
        bail!("{}: cannot merge into the root folder", out.display());
    };
    let name = name.to_string_lossy();
    let building = Building(parent.join(format!(".{name}.merging-{}", std::process::id())));
    if building.0.exists() {
        fs::remove_dir_all(&building.0)
            .with_context(|| format!("removing {}", building.0.display()))?;
    }
    fs::create_dir(&building.0).with_context(|| format!("creating {}", building.0.display()))?;
    output::prepare(&building.0, false)?;
    for (part, _) in &loaded {
        let images = part.join("images");
        let entries =
            fs::read_dir(&images).with_context(|| format!("reading {}", images.display()))?;
        for entry in entries {
            let entry = entry.with_context(|| format!("reading {}", images.display()))?;
            let to = building.0.join("images").join(entry.file_name());
            fs::copy(entry.path(), &to).with_context(|| {
                format!("copying {} to {}", entry.path().display(), to.display())
            })?;
        }
    }
    output::write(&building.0, &merged)?;
    // Into place: the old folder (ours, locked) aside, the new one in, the old one removed.
    let old = parent.join(format!(".{name}.replaced-{}", std::process::id()));
    fs::rename(&target, &old)
        .with_context(|| format!("renaming {} to {}", target.display(), old.display()))?;
    if let Err(e) = fs::rename(&building.0, &target) {
        let _ = fs::rename(&old, &target);
        return Err(e)
            .with_context(|| format!("renaming {} to {}", building.0.display(), target.display()));
    }
    fs::remove_dir_all(&old).with_context(|| format!("removing {}", old.display()))?;
    Ok(merged)
}

/// A folder being built; removed unless it was renamed into place.
struct Building(PathBuf);

impl Drop for Building {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

/// A part is a whole suite output folder: images/ with every image its results name.
fn check_images(part: &Path, results: &SuiteResults) -> Result<()> {
    let images = part.join("images");
    if !images.is_dir() {
        bail!(
            "{}: no images/ folder, so this is not a whole suite output folder (copy the shard's folder whole); nothing was written",
            part.display()
        );
    }
    let named = results
        .runs
        .iter()
        .flat_map(|r| [&r.image, &r.error_map].map(|i| (i, r.id.as_str())))
        .filter_map(|(i, id)| i.as_ref().map(|i| (i.as_str(), id)))
        .chain(
            results
                .references
                .iter()
                .map(|(scene, r)| (r.image.as_str(), scene.as_str())),
        );
    for (image, of) in named {
        if !part.join(image).is_file() {
            bail!(
                "{}: {image} (of {of}) is missing; nothing was written",
                part.display()
            );
        }
    }
    Ok(())
}

/// The merge replaces its output folder whole, so that folder must be new, empty or a suite's
/// output folder: nothing else in it would survive.
fn check_target(out: &Path) -> Result<()> {
    if !out.exists() {
        return Ok(());
    }
    if !out.is_dir() {
        bail!(
            "{} is not a folder: choose another output folder",
            out.display()
        );
    }
    const SUITE_FILES: &[&str] = &[
        "results.json",
        "results.csv",
        "report.md",
        "images",
        "charts",
        crate::lock::LOCK_FILE,
    ];
    for entry in fs::read_dir(out).with_context(|| format!("reading {}", out.display()))? {
        let entry = entry.with_context(|| format!("reading {}", out.display()))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        // A temporary file of an interrupted write (output.rs) is a suite's too.
        if !SUITE_FILES.contains(&name.as_str()) && !name.ends_with(".tmp") {
            bail!(
                "{} holds {name}, which is not a suite output: the merge replaces the whole folder, so choose another output folder",
                out.display()
            );
        }
    }
    Ok(())
}
