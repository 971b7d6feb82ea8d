//! What a suite finds in its output folder from before. An interrupted run of the same suite
//! (same suite file and scene contents, same shard) measured on the same device, driver and
//! irad version is resumed: its recorded runs are kept and only the others render. A finished
//! run of the same suite is measured again from scratch. Anything else (another suite's or
//! shard's results, another device's interrupted run, a results.json that does not parse) is
//! refused: rerunning into it would mix two sets of figures or destroy the other's. A suite
//! refused after an edit names it: the results record the suite's text and scenes' hashes.

use std::path::Path;

use anyhow::{bail, Result};

use super::file::{suite_hash_of, RunSpec, Shard, Suite};
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
    if old.suite == suite.name && old_shard == shard && old.suite_hash != hash {
        let mut edits = edits(&old, suite);
        // Nothing named (results.json edited by hand, or written by an irad that hashed
        // suites otherwise): say so rather than leave the edit blank.
        if edits.is_empty() {
            edits.push(format!(
                "the suite file {} or a scene it names: its text differs in a way irad cannot name",
                suite.file
            ));
        }
        bail!(
            "{} holds the results of suite `{}` before an edit: {} (suite hash {}, now {hash}): choose another output folder, or remove it to replace them",
            out.display(),
            old.suite,
            edits.join("; "),
            old.suite_hash,
        );
    }
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

/// What changed between the suite that wrote `old` and `suite` (their hashes differ): each
/// scene whose contents changed, named by its file, and each suite field whose value changed,
/// with both values.
fn edits(old: &SuiteResults, suite: &Suite) -> Vec<String> {
    // Results written before the scenes were recorded still hold each run's scene hash.
    let old_hash = |name: &str| -> Option<String> {
        match old.scene_files.iter().find(|s| s.name == name) {
            Some(s) => Some(s.content_hash.clone()),
            None => old
                .runs
                .iter()
                .find(|r| r.scene == name)
                .map(|r| r.scene_hash.clone()),
        }
    };
    let mut edits: Vec<String> = suite
        .scenes
        .iter()
        .filter_map(|s| {
            let now = format!("{:016x}", s.scene.content_hash);
            let was = old_hash(&s.scene.name)?;
            (was != now).then(|| {
                format!(
                    "scene `{}` ({}) or a file it references has other contents",
                    s.scene.name, s.path
                )
            })
        })
        .collect();
    if !old.suite_text.is_empty() {
        if old.suite_text != suite.text {
            let fields = match (
                old.suite_text.parse::<toml::Table>(),
                suite.text.parse::<toml::Table>(),
            ) {
                (Ok(was), Ok(now)) => {
                    let mut fields = Vec::new();
                    diff_fields(
                        "",
                        &toml::Value::Table(was),
                        &toml::Value::Table(now),
                        &mut fields,
                    );
                    fields
                }
                _ => Vec::new(),
            };
            if fields.is_empty() {
                edits.push(format!(
                    "the suite file {} differs in comments or layout only",
                    suite.file
                ));
            }
            const SHOWN: usize = 6;
            let more = fields.len().saturating_sub(SHOWN);
            edits.extend(fields.into_iter().take(SHOWN));
            if more > 0 {
                edits.push(format!("and {more} more field(s) of {}", suite.file));
            }
        }
        return edits;
    }
    // No text recorded: the suite's hash over the old scene hashes and this text tells
    // whether the text changed, when every scene's old hash is known.
    let old_hashes: Option<Vec<u64>> = suite
        .scenes
        .iter()
        .map(|s| old_hash(&s.scene.name).and_then(|h| u64::from_str_radix(&h, 16).ok()))
        .collect();
    let text_same = old_hashes
        .is_some_and(|h| format!("{:016x}", suite_hash_of(&suite.text, h)) == old.suite_hash);
    if !text_same {
        edits.push(format!(
            "the suite file {} changed (these results predate the record of its fields, so the field is not named)",
            suite.file
        ));
    }
    edits
}

/// Appends to `out` each key path under `prefix` whose value differs between `was` and `now`:
/// "`reference.spp` was 8, now 16".
fn diff_fields(prefix: &str, was: &toml::Value, now: &toml::Value, out: &mut Vec<String>) {
    use toml::Value;
    let path = |key: &str| match prefix {
        "" => key.to_string(),
        p => format!("{p}.{key}"),
    };
    match (was, now) {
        (Value::Table(a), Value::Table(b)) => {
            for (key, va) in a {
                match b.get(key) {
                    Some(vb) => diff_fields(&path(key), va, vb, out),
                    None => out.push(format!("`{}` was {}, now absent", path(key), words(va))),
                }
            }
            for (key, vb) in b.iter().filter(|(k, _)| !a.contains_key(*k)) {
                out.push(format!("`{}` was absent, now {}", path(key), words(vb)));
            }
        }
        // Arrays of tables ([[scene]], [[method]]) entry by entry; other arrays whole.
        (Value::Array(a), Value::Array(b))
            if a.len() == b.len() && a.iter().chain(b).all(Value::is_table) =>
        {
            for (i, (va, vb)) in a.iter().zip(b).enumerate() {
                diff_fields(&format!("{prefix}[{i}]"), va, vb, out);
            }
        }
        (a, b) if a != b => out.push(format!("`{prefix}` was {}, now {}", words(a), words(b))),
        _ => {}
    }
}

/// A TOML value as a suite file writes it inline, cut short when long.
fn words(v: &toml::Value) -> String {
    let text = inline(v);
    match text.char_indices().nth(80) {
        Some((i, _)) => format!("{}...", &text[..i]),
        None => text,
    }
}

fn inline(v: &toml::Value) -> String {
    match v {
        toml::Value::Array(a) => {
            format!("[{}]", a.iter().map(inline).collect::<Vec<_>>().join(", "))
        }
        toml::Value::Table(t) => format!(
            "{{ {} }}",
            t.iter()
                .map(|(k, v)| format!("{k} = {}", inline(v)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        v => v.to_string(),
    }
}

fn shard_words(shard: Option<Shard>) -> String {
    shard.map(|s| format!(", shard {s}")).unwrap_or_default()
}

/// The runs of `old` that this run keeps: recorded ok, declined or refused (a run that failed is tried
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
        Some(count) if spec.time_ms.is_some() || spec.frame_ms.is_some() => {
            spec.method.with_count(count)
        }
        _ => spec.method.clone(),
    };
    let images_there = [&r.image, &r.error_map]
        .iter()
        .all(|i| i.as_ref().is_some_and(|i| out.join(i).is_file()));
    r.id == spec.id
        && r.scene_hash == format!("{:016x}", scene.content_hash)
        && r.seed == spec.method.seed()
        && r.time_ms == spec.time_ms
        && r.frame_ms == spec.frame_ms
        && r.parameters == method.parameters()
        && match r.status {
            Status::Ok => images_there,
            // A resumed run is on the same device, which still cannot hold the scene.
            Status::Declined | Status::Refused => true,
            Status::Error => false,
        }
}
