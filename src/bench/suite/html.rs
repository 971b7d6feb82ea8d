//! report.html: the suite's report as one self-contained page (docs/DESIGN.md "Benchmarks"):
//! per scene its chart (the SVG of charts/, whose points' tooltips hold run, time and
//! relMSE; a click opens the run in the viewer), its runs' table (sortable by any column) and an
//! image viewer (assets/report/viewer.js) comparing any run with the reference or another run.
//!
//! The viewer and its images' encoding: crate::html::viewer.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context as _, Result};

use crate::html::viewer::{self, ViewerData};
use crate::html::{escape, json_string};
use crate::image::{exr, Image};

use super::output::chart;
use super::results::{RunRecord, Status, SuiteResults};

/// The EXR the runner writes beside a thumbnail `images/NAME.png`: `images/NAME.exr`.
pub fn exr_of(png: &str) -> String {
    match png.strip_suffix(".png") {
        Some(stem) => format!("{stem}.exr"),
        None => format!("{png}.exr"),
    }
}

fn figure(v: Option<f64>, digits: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.digits$e}"),
        _ => "-".into(),
    }
}

/// The page for the suite in `out` (its images/ read for the viewers).
pub fn page(out: &Path, results: &SuiteResults) -> Result<String> {
    let mut body = String::new();
    let mut data = String::from("{");
    for (k, scene) in results.scenes().iter().enumerate() {
        let runs: Vec<&RunRecord> = results
            .runs
            .iter()
            .filter(|r| &r.scene == scene && r.status == Status::Ok && r.image.is_some())
            .collect();
        // The viewer's images: the reference first (the default B), then each run's. One that
        // cannot be read (a merged shard's, an older run's) is left out with a warning.
        let mut images: Vec<(String, Image)> = Vec::new();
        let mut wanted: Vec<(String, String)> = Vec::new();
        if let Some(r) = results.references.get(scene) {
            wanted.push(("reference".into(), exr_of(&r.image)));
        }
        for r in &runs {
            let exr = exr_of(r.image.as_deref().expect("filtered"));
            wanted.push((format!("{} {}", r.label, r.budget), exr));
        }
        // Images left out, with why: listed under the table.
        let mut left_out: Vec<String> = Vec::new();
        for (name, exr) in wanted {
            match read(&out.join(&exr)) {
                Ok(im) => images.push((name, im)),
                Err(e) => {
                    log::warn!("report.html leaves out {name}: {e:#}");
                    left_out.push(format!("{name}: its image could not be read ({e:#})"));
                }
            }
        }
        // One size per viewer: the first image's (the reference's where there is one).
        if let Some((_, first)) = images.first() {
            let size = (first.width, first.height);
            images.retain(|(name, im)| {
                let same = (im.width, im.height) == size;
                if !same {
                    let why = format!(
                        "{name}: its image is {}x{}, the scene's {}x{}",
                        im.width, im.height, size.0, size.1
                    );
                    log::warn!("report.html leaves out {why}");
                    left_out.push(why);
                }
                same
            });
        }
        let reference = results.references.contains_key(scene)
            && images.first().is_some_and(|(n, _)| n == "reference");
        if reference && images.len() > 1 {
            log::info!(
                "report.html: HDR-FLIP of {} runs on {scene}",
                images.len() - 1
            );
        }
        let viewer = ViewerData::still(images, reference.then_some(0), true)?;
        let factor = viewer.factor;
        let _ = write!(
            data,
            "{}{}:{}",
            if k > 0 { "," } else { "" },
            json_string(&format!("scene{k}")),
            viewer.json()
        );
        let _ = writeln!(body, "<section class=\"scene\" id=\"scene{k}\">");
        let _ = writeln!(body, "<h2>{}</h2>", escape(scene));
        let _ = writeln!(
            body,
            "<div class=\"chart\">{}</div>",
            // Each chart's plot group has an id of its own in the page (the SVG files' is
            // `plot`, which src/bench/chart/read.rs finds them by).
            chart(results, scene)
                .to_svg()
                .replace("<g id=\"plot\"", &format!("<g id=\"scene{k}-plot\""))
        );
        body += &table(&runs);
        // The runs with no image, and why (report.md has them in its table too).
        let mut absent: Vec<String> = results
            .runs
            .iter()
            .filter(|r| &r.scene == scene && !(r.status == Status::Ok && r.image.is_some()))
            .map(|r| {
                format!(
                    "<li>{} {}: {}{}</li>",
                    escape(&r.label),
                    escape(&r.budget),
                    r.status.as_str(),
                    if r.note.is_empty() {
                        String::new()
                    } else {
                        format!(", {}", escape(&r.note))
                    }
                )
            })
            .collect();
        absent.extend(left_out.iter().map(|w| format!("<li>{}</li>", escape(w))));
        if !absent.is_empty() {
            let _ = writeln!(
                body,
                "<p class=\"absent\">Runs with no image:</p><ul class=\"absent\">{}</ul>",
                absent.concat()
            );
        }
        if factor > 1 {
            let _ = writeln!(
                body,
                "<p class=\"note\">The viewer's images are averaged over {factor}x{factor} \
                 pixel blocks, so that the page stays under {} MB for this scene; the EXRs \
                 in images/ are full size.</p>",
                viewer::VIEWER_BYTES >> 20
            );
        }
        if !viewer.names.is_empty() {
            body += viewer::MARKUP;
        }
        body += "</section>\n";
    }
    data.push('}');
    Ok(format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{title}</title><style>{style}{STYLE}</style></head><body>\n\
         <h1>{title}</h1>\n<p>{description}</p>\n{body}\
         <script>{script}</script>\n<script>const IRAD_DATA = {data};\n{PAGE_JS}</script>\n\
         </body></html>\n",
        title = escape(&format!("Benchmark suite {}", results.suite)),
        description = escape(results.description.trim()),
        style = viewer::STYLE,
        script = viewer::VIEWER_JS,
    ))
}

fn read(path: &Path) -> Result<Image> {
    exr::read(path).with_context(|| format!("reading {} for report.html", path.display()))
}

/// The scene's runs as a table whose header sorts it (PAGE_JS).
fn table(runs: &[&RunRecord]) -> String {
    let mut t = String::from(
        "<table class=\"runs\"><thead><tr><th>★</th><th>method</th><th>budget</th>\
         <th data-numeric>GPU ms</th><th data-numeric>relMSE</th><th data-numeric>lowest</th>\
         <th data-numeric>highest</th><th data-numeric>seeds</th><th data-numeric>bias</th>\
         <th data-numeric>outliers</th></tr></thead><tbody>\n",
    );
    for r in runs {
        let m = r.metrics;
        let _ =
            writeln!(
            t,
            "<tr data-run=\"{}\" data-image=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&r.id),
            escape(&format!("{} {}", r.label, r.budget)),
            if r.pareto { "★" } else { "" },
            escape(&r.label),
            escape(&r.budget),
            r.gpu_ms.map(|t| format!("{t:.2}")).unwrap_or_else(|| "-".into()),
            figure(m.map(|m| m.rel_mse), 3),
            figure(r.rel_mse_min, 3),
            figure(r.rel_mse_max, 3),
            r.scored,
            m.map(|m| format!("{:.2}%", 100.0 * m.bias)).unwrap_or_else(|| "-".into()),
            m.map(|m| format!("{:.3}%", 100.0 * m.outliers)).unwrap_or_else(|| "-".into()),
        );
    }
    t + "</tbody></table>\n"
}

const STYLE: &str = "table.runs{border-collapse:collapse;margin:1em 0}\
table.runs td,table.runs th{border:1px solid #ccc;padding:2px 6px;text-align:right}\
table.runs th{cursor:pointer;background:#f4f4f4}\
table.runs tr.selected{background:#ffe9a8}\
circle.point{cursor:pointer}\
.hover-tip{position:absolute;background:#fffbe6;border:1px solid #aa9;padding:3px 6px;font-size:12px;pointer-events:none}";

/// Wires each scene's viewer, table and chart: a click on a run's row or chart point shows it
/// as A; a click on a header sorts the table by that column.
const PAGE_JS: &str = r#"
const tip = document.createElement("div");
tip.className = "hover-tip";
tip.hidden = true;
document.body.appendChild(tip);
for (const section of document.querySelectorAll("section.scene")) {
  const data = IRAD_DATA[section.id];
  const root = section.querySelector(".viewer");
  const names = data ? data.names : [];
  let viewer = null;
  if (root && names.length > 0) {
    // A: the first run; B: the reference (first).
    viewer = new IradViewer.Viewer(root, data, { a: names[names.length > 1 ? 1 : 0], b: names[0] });
    root.viewer = viewer;
  }
  const show = (name) => {
    if (!viewer || !names.includes(name)) return;
    root.focus();
    viewer.setA(name);
    for (const tr of section.querySelectorAll("tr[data-image]")) {
      tr.classList.toggle("selected", tr.dataset.image === name);
    }
  };
  const rows = [...section.querySelectorAll("tbody tr")];
  for (const tr of rows) tr.addEventListener("click", () => show(tr.dataset.image));
  // Hover: the run's figures from its row (relMSE with its spread over the seeds, GPU time).
  for (const circle of section.querySelectorAll("circle.point")) {
    const tr = rows.find((r) => r.dataset.run === circle.dataset.run);
    circle.addEventListener("click", () => {
      if (tr) show(tr.dataset.image);
    });
    circle.addEventListener("mouseenter", (e) => {
      if (!tr) return;
      const c = [...tr.children].map((td) => td.textContent);
      tip.textContent = `${c[1]} ${c[2]}: relMSE ${c[4]} (${c[5]} .. ${c[6]} over ${c[7]} seeds), ${c[3]} ms GPU${c[0] ? ", best at its time" : ""}`;
      tip.style.left = `${e.pageX + 12}px`;
      tip.style.top = `${e.pageY + 12}px`;
      tip.hidden = false;
    });
    circle.addEventListener("mouseleave", () => (tip.hidden = true));
  }
  section.querySelectorAll("table.runs th").forEach((th, col) => {
    th.addEventListener("click", () => {
      const numeric = th.hasAttribute("data-numeric");
      const text = (tr) => tr.children[col].textContent;
      const number = (tr) => (text(tr) === "-" ? Infinity : parseFloat(text(tr)));
      // Numbers by value; text with its digits as numbers (spp=4 before spp=16).
      const order = numeric
        ? (a, b) => number(a) - number(b)
        : (a, b) => text(a).localeCompare(text(b), undefined, { numeric: true });
      const up = th.dataset.sorted !== "up";
      th.parentElement.querySelectorAll("th").forEach((h) => delete h.dataset.sorted);
      th.dataset.sorted = up ? "up" : "down";
      const body = th.closest("table").querySelector("tbody");
      [...body.children]
        .sort((a, b) => (order(a, b) || 0) * (up ? 1 : -1))
        .forEach((tr) => body.appendChild(tr));
    });
  });
}
"#;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::html::half_base64;

    /// The page holds each scene's chart, its runs' table and, for the viewer, the reference's
    /// and each run's image as half floats, the reference first.
    #[test]
    fn the_page_embeds_the_chart_table_and_images() {
        use super::super::results::tests::run;
        let out = std::env::temp_dir().join(format!("irad-html-{}", std::process::id()));
        std::fs::create_dir_all(out.join("images")).unwrap();
        let image = |v: f32| Image {
            width: 3,
            height: 2,
            pixels: vec![[v; 3]; 6],
        };
        exr::write(&out.join("images/s.reference.exr"), &image(1.0)).unwrap();
        exr::write(&out.join("images/run.exr"), &image(0.5)).unwrap();
        let mut r = run("s", "gpu", 10.0, 0.1);
        r.label = "ir".into();
        r.budget = "vpls=64".into();
        r.image = Some("images/run.png".into());
        let mut results = super::super::results::tests::suite_results(vec![r]);
        results.references.insert(
            "s".into(),
            super::super::results::tests::reference_summary("images/s.reference.png"),
        );
        let page = page(&out, &results).unwrap();
        assert!(page.contains("<section class=\"scene\" id=\"scene0\">"));
        assert!(page.contains("<svg"), "the chart");
        assert!(page.contains("<g id=\"scene0-plot\"") && !page.contains("id=\"plot\""));
        assert!(page.contains("<tr data-run=\"s/10/0.1\" data-image=\"ir vpls=64\">"));
        let reference = format!(
            "{{\"width\":3,\"height\":2,\"rgb\":\"{}\"}}",
            half_base64(&image(1.0))
        );
        let run_image = format!(
            "{{\"width\":3,\"height\":2,\"rgb\":\"{}\",\"flip\":\"",
            half_base64(&image(0.5))
        );
        let (a, b) = (
            page.find(&reference).unwrap(),
            page.find(&run_image).unwrap(),
        );
        assert!(a < b, "the reference first");
        assert!(page.contains("\"names\":[\"reference\",\"ir vpls=64\"]"));
        assert!(page.contains("IradViewer"));
        assert!(
            page.contains("\"reference\":\"reference\""),
            "FLIP's reference"
        );
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn the_exr_sits_beside_its_thumbnail() {
        assert_eq!(exr_of("images/a-b.png"), "images/a-b.exr");
    }
}
