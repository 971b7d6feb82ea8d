//! The light-count view of a suite whose scenes include a generated family (`path =
//! "generated:NAME"` with two or more `lights`, generated.rs): against the light count, log-log,
//! per method its GPU time per frame and its net relMSE x GPU time (at equal time, the ratio of
//! two methods' is their speed), and per scene the upload's CPU builds and device memory; with
//! a table of the same figures, where a count the device refuses is listed with its refusal.
//! Drawn from results.json alone (the members' `generated` and `uploads`), so a merge draws it
//! too. Nothing is drawn for a suite without a family.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::bench::chart::{Chart, Point, Series};
use crate::methods::Registry;

use super::file::file_safe;
use super::report::fixed;
use super::results::{RunRecord, SceneUpload, Status, SuiteResults};

/// One member of a family: its scene, light count and upload (None when the suite did not
/// reach it).
pub struct Member<'a> {
    pub scene: &'a str,
    pub lights: u32,
    pub upload: Option<&'a SceneUpload>,
}

/// A generated family of the suite: its generator and members, by light count.
pub struct Family<'a> {
    pub generator: &'a str,
    pub members: Vec<Member<'a>>,
}

/// The families of `results` with two or more members, in order of their generators.
pub fn families(results: &SuiteResults) -> Vec<Family<'_>> {
    let mut by: BTreeMap<&str, Vec<Member>> = BTreeMap::new();
    for s in &results.scene_files {
        if let Some(g) = &s.generated {
            by.entry(g.generator.as_str()).or_default().push(Member {
                scene: s.name.as_str(),
                lights: g.lights,
                upload: results.uploads.get(&s.name),
            });
        }
    }
    by.into_iter()
        .filter(|(_, m)| m.len() >= 2)
        .map(|(generator, mut members)| {
            members.sort_by_key(|m| m.lights);
            Family { generator, members }
        })
        .collect()
}

/// The family's charts, each with its path relative to the output folder:
/// `charts/scale/<generator>-<what>.svg`.
pub fn charts(results: &SuiteResults, family: &Family) -> Vec<(String, Chart)> {
    let g = file_safe(family.generator);
    let path = |what: &str| format!("charts/scale/{g}-{what}.svg");
    vec![
        (path("frame-ms"), frame_chart(results, family)),
        (path("cost"), cost_chart(results, family)),
        (path("build"), build_chart(family)),
        (path("memory"), memory_chart(family)),
    ]
}

/// A run's count: the one its time budget calibrated, else its method's count parameter
/// (frames, the path tracer's spp).
fn count(r: &RunRecord) -> Option<u32> {
    r.calibrated_count.or_else(|| {
        let key = Registry::builtin().get(&r.method).ok()?.count_key();
        r.parameters.get(key)?.as_u64().map(|c| c as u32)
    })
}

/// GPU ms per frame: the run's GPU time over its count.
fn frame_ms(r: &RunRecord) -> Option<f64> {
    Some(r.gpu_ms? / f64::from(count(r)?.max(1)))
}

/// Net relMSE (the reference's own taken out) x GPU ms: at equal time, lower is better and
/// the ratio of two runs' is their speed (docs/DESIGN.md "Speed at equal error").
fn cost(r: &RunRecord) -> Option<f64> {
    Some((r.metrics?.rel_mse - r.reference_rel_mse.unwrap_or(0.0)) * r.gpu_ms?)
}

/// The series a run belongs to: its label, with its budget where the label has several in the
/// family, and its device where the results mix devices.
fn series_names<'a>(results: &'a SuiteResults, family: &Family) -> Vec<(&'a RunRecord, String)> {
    let runs: Vec<&RunRecord> = results
        .runs
        .iter()
        .filter(|r| family.members.iter().any(|m| m.scene == r.scene))
        .filter(|r| r.status == Status::Ok)
        .collect();
    let mixed = results
        .runs
        .iter()
        .any(|r| r.device != results.runs[0].device);
    let budgets = |label: &str| {
        let mut b: Vec<&str> = runs
            .iter()
            .filter(|r| r.label == label)
            .map(|r| r.budget.as_str())
            .collect();
        b.sort();
        b.dedup();
        b.len()
    };
    runs.iter()
        .map(|r| {
            let mut name = r.label.clone();
            if budgets(&r.label) > 1 {
                name = format!("{name} {}", r.budget);
            }
            if mixed {
                name = format!("{name} ({})", r.device);
            }
            (*r, name)
        })
        .collect()
}

/// The light count of `scene` in the family.
fn lights_of(family: &Family, scene: &str) -> f64 {
    family
        .members
        .iter()
        .find(|m| m.scene == scene)
        .map_or(f64::NAN, |m| f64::from(m.lights))
}

/// A chart per method against the light count, `y` of each ok run.
fn method_chart(
    results: &SuiteResults,
    family: &Family,
    y: impl Fn(&RunRecord) -> Option<f64>,
    range: impl Fn(&RunRecord) -> Option<(f64, f64)>,
) -> Vec<Series> {
    let mut series: Vec<Series> = Vec::new();
    for (r, name) in series_names(results, family) {
        let point = Point {
            x: lights_of(family, &r.scene),
            y: y(r).unwrap_or(f64::NAN),
            y_range: range(r),
            label: String::new(),
            run_id: r.id.clone(),
        };
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(point),
            None => series.push(Series {
                name,
                points: vec![point],
            }),
        }
    }
    series
}

/// Notes for the members no point stands for: refused by the device, or not run yet.
fn member_notes(family: &Family) -> Vec<String> {
    family
        .members
        .iter()
        .filter_map(|m| match m.upload {
            Some(u) if u.refused.is_some() => Some(format!(
                "{} lights: refused, the device cannot hold the scene (the report says why)",
                m.lights
            )),
            Some(_) => None,
            None => Some(format!("{} lights: not run", m.lights)),
        })
        .collect()
}

fn x_label(family: &Family) -> String {
    format!("lights (generated:{}; log scale)", family.generator)
}

fn frame_chart(results: &SuiteResults, family: &Family) -> Chart {
    Chart {
        title: format!("{}: GPU time per frame by light count", family.generator),
        x_label: x_label(family),
        y_label: "GPU ms per frame (run's GPU time / its count)".into(),
        series: method_chart(results, family, frame_ms, |_| None),
        notes: member_notes(family),
        floor: None,
    }
}

fn cost_chart(results: &SuiteResults, family: &Family) -> Chart {
    let range = |r: &RunRecord| {
        let floor = r.reference_rel_mse.unwrap_or(0.0);
        let ms = r.gpu_ms?;
        Some(((r.rel_mse_min? - floor) * ms, (r.rel_mse_max? - floor) * ms))
    };
    Chart {
        title: format!("{}: net relMSE x GPU time by light count", family.generator),
        x_label: x_label(family),
        y_label: "net relMSE x GPU ms (lower is better)".into(),
        series: method_chart(results, family, cost, range),
        notes: member_notes(family),
        floor: None,
    }
}

/// A series of an upload chart: its name and its figure of a scene's upload.
type UploadFigure<'a> = (&'a str, fn(&SceneUpload) -> Option<f64>);

/// A chart of per-member figures of the uploads: a series per (name, figure).
fn upload_chart(family: &Family, title: String, y_label: &str, figures: &[UploadFigure]) -> Chart {
    let series = figures
        .iter()
        .map(|(name, f)| Series {
            name: name.to_string(),
            points: family
                .members
                .iter()
                .filter_map(|m| {
                    let u = m.upload.filter(|u| u.refused.is_none())?;
                    Some(Point {
                        x: f64::from(m.lights),
                        y: f(u).unwrap_or(f64::NAN),
                        y_range: None,
                        label: String::new(),
                        run_id: m.scene.to_string(),
                    })
                })
                .collect(),
        })
        .collect();
    Chart {
        title,
        x_label: x_label(family),
        y_label: y_label.into(),
        series,
        notes: member_notes(family),
        floor: None,
    }
}

fn build_chart(family: &Family) -> Chart {
    upload_chart(
        family,
        format!("{}: CPU builds and load by light count", family.generator),
        "CPU ms (wall)",
        &[
            ("light BVH build", |u| u.light_bvh_ms),
            ("triangle BVH build", |u| u.triangle_bvh_ms),
            ("scene load", |u| Some(u.load_ms)),
        ],
    )
}

const MIB: f64 = (1u64 << 20) as f64;

fn memory_chart(family: &Family) -> Chart {
    upload_chart(
        family,
        format!("{}: device memory by light count", family.generator),
        "MiB on the device",
        &[
            ("light data", |u| u.light_bytes.map(|b| b as f64 / MIB)),
            ("whole scene", |u| u.device_bytes.map(|b| b as f64 / MIB)),
        ],
    )
}

/// The report's section for each family: what the charts show, the charts, a table per light
/// count (upload figures, then per series GPU ms per frame and net relMSE x GPU ms) and each
/// refusal in the device's words. Empty without a family.
pub fn markdown(results: &SuiteResults) -> String {
    let mut md = String::new();
    for family in families(results) {
        let _ = writeln!(md, "## Light count: generated:{}\n", family.generator);
        let lo = family.members.first().map_or(0, |m| m.lights);
        let hi = family.members.last().map_or(0, |m| m.lights);
        let _ = writeln!(
            md,
            "The suite's {} scenes `generated:{}` with {lo} to {hi} lights, against the light \
             count, log-log: per method its GPU time per frame (the run's GPU time over its \
             count: frames, or the path tracer's samples) and its net relMSE (less the \
             reference's own) x GPU time, whose ratio between two methods is their speed at \
             equal time (a bar: the lowest to the highest image's); per scene the upload's CPU \
             builds (`GpuScene::build_ms`), the scene's load and its device memory.\n",
            family.members.len(),
            family.generator
        );
        for (path, chart) in charts(results, &family) {
            let _ = writeln!(md, "![{}]({path})\n", chart.title);
        }
        let named = series_names(results, &family);
        let mut series: Vec<&str> = Vec::new();
        for (_, name) in &named {
            if !series.contains(&name.as_str()) {
                series.push(name);
            }
        }
        md += "| lights | triangles | load ms | triangle BVH ms | light BVH ms | light data MiB | scene MiB |";
        for s in &series {
            let _ = write!(md, " {s} ms/frame | {s} net relMSE x ms |");
        }
        md += "\n|---:|---:|---:|---:|---:|---:|---:|";
        md += &"---:|---:|".repeat(series.len());
        md += "\n";
        let mut refusals = Vec::new();
        for m in &family.members {
            let u = m.upload;
            let _ = write!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} |",
                m.lights,
                u.map_or("-".into(), |u| u.triangles.to_string()),
                fixed(u.map(|u| u.load_ms), 0),
                fixed(u.and_then(|u| u.triangle_bvh_ms), 1),
                fixed(u.and_then(|u| u.light_bvh_ms), 1),
                fixed(u.and_then(|u| u.light_bytes).map(|b| b as f64 / MIB), 2),
                fixed(u.and_then(|u| u.device_bytes).map(|b| b as f64 / MIB), 2),
            );
            if let Some(why) = u.and_then(|u| u.refused.as_ref()) {
                md += &" refused |".repeat(2 * series.len());
                refusals.push(format!("- {} lights: refused: {why}", m.lights));
            } else {
                for s in &series {
                    let run = named
                        .iter()
                        .find(|(r, name)| name == s && r.scene == m.scene)
                        .map(|(r, _)| *r);
                    let _ = write!(
                        md,
                        " {} | {} |",
                        fixed(run.and_then(frame_ms), 2),
                        sci(run.and_then(cost))
                    );
                }
            }
            md += "\n";
        }
        md += "\n";
        if !refusals.is_empty() {
            md += "Sizes this device cannot hold:\n\n";
            for r in refusals {
                md += &r.replace('\n', " ");
                md += "\n";
            }
            md += "\n";
        }
    }
    md
}

fn sci(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() && x > 0.0 => format!("{x:.3e}"),
        _ => "-".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::chart::read_svg;
    use crate::bench::suite::generated::Generated;
    use crate::bench::suite::results::{tests::run, SceneFile};

    fn upload(lights: u32, refused: bool) -> SceneUpload {
        let l = f64::from(lights);
        SceneUpload {
            triangles: 2 * u64::from(lights) + 100,
            lights: 2 * u64::from(lights),
            load_ms: 0.01 * l,
            triangle_bvh_ms: (!refused).then_some(0.002 * l),
            light_bvh_ms: (!refused).then_some(0.01 * l),
            light_bytes: (!refused).then_some(150 * u64::from(lights)),
            device_bytes: (!refused).then_some(400 * u64::from(lights)),
            refused: refused.then(|| "hall.obj: too many triangles\nfor this device".into()),
        }
    }

    /// A family of 2^10, 2^12, 2^14 lights (2^14 refused by the device) with two methods at one
    /// time budget, a scene file besides; each run's GPU time over its count grows as
    /// log2(lights) for the first method and as lights^0.1 for the second.
    fn family_results() -> SuiteResults {
        let counts = [1024u32, 4096, 16384];
        let mut runs = Vec::new();
        for (i, &lights) in counts[..2].iter().enumerate() {
            let scene = format!("many-lights-{lights}");
            let l = f64::from(lights);
            for (label, ms_frame, rel) in [
                ("pt-power", l.log2(), 0.5 * l.log10()),
                ("pt-bvh", l.powf(0.1), 0.1),
            ] {
                let mut r = run(&scene, "lavapipe", 200.0, rel);
                r.index = runs.len();
                r.id = format!("{scene}/{label}/time_ms=200");
                r.label = label.into();
                r.budget = "time_ms=200".into();
                r.time_ms = Some(200.0);
                r.calibrated_count = Some((200.0 / ms_frame).round() as u32);
                r.gpu_ms = Some(ms_frame * f64::from(r.calibrated_count.unwrap()));
                r.reference_rel_mse = Some(0.001 * (i + 1) as f64);
                runs.push(r);
            }
        }
        let mut other = run("cornell-box", "lavapipe", 3.0, 0.2);
        other.index = runs.len();
        runs.push(other);
        let mut refused = run("many-lights-16384", "lavapipe", 0.0, 0.0);
        refused.index = runs.len();
        (refused.status, refused.gpu_ms, refused.metrics) = (Status::Refused, None, None);
        runs.push(refused);
        let mut scene_files: Vec<SceneFile> = counts
            .iter()
            .map(|&lights| SceneFile {
                name: format!("many-lights-{lights}"),
                path: format!("generated:many-lights lights={lights}"),
                content_hash: String::new(),
                generated: Some(Generated {
                    generator: "many-lights".into(),
                    lights,
                }),
            })
            .collect();
        scene_files.push(SceneFile {
            name: "cornell-box".into(),
            path: "embedded:cornell-box".into(),
            content_hash: String::new(),
            generated: None,
        });
        SuiteResults {
            suite: "scale".into(),
            device: "lavapipe".into(),
            scene_files,
            uploads: counts
                .iter()
                .map(|&l| (format!("many-lights-{l}"), upload(l, l == 16384)))
                .collect(),
            ..super::super::results::tests::suite_results(runs)
        }
    }

    /// The charts put each light count at its log10 along x and each figure at its log10 along
    /// y, one line per method through its counts; the refused count is a note, not a point.
    #[test]
    fn charts_are_log_log_against_the_light_count() {
        let results = family_results();
        let families = families(&results);
        assert_eq!(families.len(), 1);
        let charts = charts(&results, &families[0]);
        let paths: Vec<&str> = charts.iter().map(|(p, _)| p.as_str()).collect();
        assert_eq!(
            paths,
            [
                "charts/scale/many-lights-frame-ms.svg",
                "charts/scale/many-lights-cost.svg",
                "charts/scale/many-lights-build.svg",
                "charts/scale/many-lights-memory.svg"
            ]
        );
        let svg = charts[0].1.to_svg();
        let (axes, points) = read_svg(&svg).unwrap();
        // 1024 and 4096 lie in the decades 10^3..10^4.
        assert_eq!((axes.x_log_min, axes.x_log_max), (3.0, 4.0));
        assert_eq!(points.len(), 4);
        for p in &points {
            let (cx, cy) = axes.to_px(p.x, p.y);
            assert!((cx - p.cx).abs() < 1e-3 && (cy - p.cy).abs() < 1e-3);
            let expected = match p.series.as_str() {
                "pt-power" => p.x.log2(),
                "pt-bvh" => p.x.powf(0.1),
                s => panic!("series {s}"),
            };
            // The run's GPU time over its count: its per-frame time.
            assert!((p.y - expected).abs() < 1e-9 * expected, "{p:?}");
        }
        // Equal steps in log(lights) are equal steps along x.
        let x = |series: &str, lights: f64| {
            points
                .iter()
                .find(|p| p.series == series && p.x == lights)
                .unwrap()
                .cx
        };
        let (a, b) = (x("pt-bvh", 1024.0), x("pt-bvh", 4096.0));
        let per_decade = (axes.right - axes.left) / (axes.x_log_max - axes.x_log_min);
        assert!(
            (b - a - per_decade * 4f64.log10()).abs() < 2e-3,
            "cx is written to 3 decimals"
        );
        assert!(svg.contains("16384 lights: refused"), "{svg}");
        // net relMSE x GPU ms: the reference's own relMSE taken out.
        let (_, cost) = read_svg(&charts[1].1.to_svg()).unwrap();
        let power_4096 = cost
            .iter()
            .find(|p| p.series == "pt-power" && p.x == 4096.0)
            .unwrap();
        let run = results
            .runs
            .iter()
            .find(|r| r.id == "many-lights-4096/pt-power/time_ms=200")
            .unwrap();
        let expected = (0.5 * 4096f64.log10() - 0.002) * run.gpu_ms.unwrap();
        assert!((power_4096.y - expected).abs() < 1e-9);
        // The uploads: three series of two points each (the refused scene has no builds).
        let (_, builds) = read_svg(&charts[2].1.to_svg()).unwrap();
        assert_eq!(builds.len(), 6);
        let light_bvh = builds
            .iter()
            .find(|p| p.series == "light BVH build" && p.x == 4096.0)
            .unwrap();
        assert!((light_bvh.y - 40.96).abs() < 1e-9);
        let (_, memory) = read_svg(&charts[3].1.to_svg()).unwrap();
        let light_data = memory
            .iter()
            .find(|p| p.series == "light data" && p.x == 1024.0)
            .unwrap();
        assert!((light_data.y - 150.0 * 1024.0 / MIB).abs() < 1e-12);
    }

    /// The report's section: the charts, a row per light count, the refusal in the device's
    /// words (on one line); nothing for a suite without a family of two or more.
    #[test]
    fn the_report_lists_every_count_and_the_refusal() {
        let results = family_results();
        let md = markdown(&results);
        assert!(
            md.starts_with("## Light count: generated:many-lights\n"),
            "{md}"
        );
        assert!(md.contains("](charts/scale/many-lights-cost.svg)"));
        assert!(md.contains(
            "| lights | triangles | load ms | triangle BVH ms | light BVH ms | light data MiB | \
             scene MiB | pt-power ms/frame | pt-power net relMSE x ms | pt-bvh ms/frame | pt-bvh \
             net relMSE x ms |"
        ));
        let row = md.lines().find(|l| l.starts_with("| 1024 |")).unwrap();
        assert!(
            row.starts_with("| 1024 | 2148 | 10 | 2.0 | 10.2 | 0.15 | 0.39 | 10.00 |"),
            "{row}"
        );
        let refused = md.lines().find(|l| l.starts_with("| 16384 |")).unwrap();
        assert_eq!(refused.matches(" refused |").count(), 4, "{refused}");
        assert!(
            md.contains("- 16384 lights: refused: hall.obj: too many triangles for this device\n")
        );
        assert!(!md.contains("cornell-box"));
        // One member is no family.
        let mut one = family_results();
        one.scene_files
            .retain(|s| s.name != "many-lights-1024" && s.name != "many-lights-4096");
        assert!(families(&one).is_empty());
        assert_eq!(markdown(&one), "");
    }
}
