//! What a suite finds in its output folder from before. An interrupted run of the same suite
//! (same suite file and scene contents, same shard) measured on the same device, driver and
//! irad version is resumed: its recorded runs are kept and only the others render. A finished
//! run of the same suite is measured again from scratch. Anything else (another suite's or
//! shard's results, another device's interrupted run, a results.json that does not parse) is
//! refused: rerunning into it would mix two sets of figures or destroy the other's.

use std::path::Path;

use anyhow::{bail, Result};

use super::file::{RunSpec, Shard, Suite};
use super::results::{RunRecord, Status, SuiteResults};

/// What to do with the folder's earlier results.
pub enum Previous {
    /// Nothing there, or a finished run of this suite: start afresh.
    Fresh,
    /// An interrupted run of this suite on this device: keep what it recorded.
    Resume(Box<SuiteResults>),
}

/// Decides what becomes of `out`'s earlier results (see the module's comment); `device`,
/// `driver` and `version` are this run's.
pub fn check(
    out: &Path,
    suite: &Suite,
    shard: Shard,
    measured_on: (&str, &str, &str),
) -> Result<Previous> {
    let path = out.join("results.json");
    if !path.exists() {
        return Ok(Previous::Fresh);
    }
    let old = match SuiteResults::read(&path) {
        Ok(r) => r,
        Err(e) => bail!(
            "{} holds a results.json that is not irad suite results ({e:#}): remove it or choose another output folder",
            out.display()
        ),
    };
    let hash = format!("{:016x}", suite.hash);
    let old_shard = old.shard.unwrap_or(Shard::WHOLE);
    if old.suite != suite.name || old.suite_hash != hash || old_shard != shard {
        bail!(
            "{} holds the results of suite `{}` (hash {}{}), not of `{}` (hash {hash}{}): choose another output folder, or remove it to replace them",
            out.display(),
            old.suite,
            old.suite_hash,
            shard_words(old.shard),
            suite.name,
            shard_words((shard != Shard::WHOLE).then_some(shard)),
        );
    }
    if old.complete || old.runs.is_empty() {
        return Ok(Previous::Fresh);
    }
    let (device, driver, version) = measured_on;
    if (
        old.device.as_str(),
        old.driver.as_str(),
        old.irad_version.as_str(),
    ) != (device, driver, version)
    {
        bail!(
            "{} holds an interrupted run of this suite measured on {} (driver {}, irad {}), this is {device} (driver {driver}, irad {version}): GPU times of two devices do not share an axis, so it is not resumed; choose another output folder, or remove it to start over",
            out.display(),
            old.device,
            old.driver,
            old.irad_version
        );
    }
    Ok(Previous::Resume(Box::new(old)))
}

fn shard_words(shard: Option<Shard>) -> String {
    shard.map(|s| format!(", shard {s}")).unwrap_or_default()
}

/// The runs of `old` that this run keeps: recorded ok or declined (a run that failed is tried
/// again) for a planned run with the same id, scene contents, seed and parameters (a time
/// budget's with its calibrated count), with its thumbnail and error map on disk.
pub fn kept_runs(
    old: &SuiteResults,
    suite: &Suite,
    planned: &[&RunSpec],
    out: &Path,
) -> Vec<RunRecord> {
    planned
        .iter()
        .filter_map(|spec| {
            let r = old.runs.iter().find(|r| r.index == spec.index)?;
            matches(r, suite, spec, out).then(|| r.clone())
        })
        .collect()
}

fn matches(r: &RunRecord, suite: &Suite, spec: &RunSpec, out: &Path) -> bool {
    let scene = &suite.scenes[spec.scene].scene;
    let method = match r.calibrated_count {
        Some(count) if spec.time_ms.is_some() => spec.method.with_count(count),
        _ => spec.method.clone(),
    };
    let images_there = [&r.image, &r.error_map]
        .iter()
        .all(|i| i.as_ref().is_some_and(|i| out.join(i).is_file()));
    r.id == spec.id
        && r.scene_hash == format!("{:016x}", scene.content_hash)
        && r.seed == spec.method.seed()
        && r.time_ms == spec.time_ms
        && r.parameters == method.parameters()
        && match r.status {
            Status::Ok => images_there,
            Status::Declined => true,
            Status::Error => false,
        }
}
