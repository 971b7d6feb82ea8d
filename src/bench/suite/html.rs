//! report.html: the suite's report as one self-contained page (docs/DESIGN.md "Benchmarks"):
//! per scene its chart (the SVG of charts/, whose points' tooltips hold run, time and
//! relMSE; a click opens the run in the viewer), its runs' table (sortable by any column) and an
//! image viewer (assets/report/viewer.js) comparing any run with the reference or another run.
//!
//! The images reach the page as half floats (RGB, little-endian, base64) read from the EXRs the
//! runner writes beside each thumbnail (`exr_of`): lossless enough for exposure (11 bits of
//! mantissa, a range to 65504), a third of the bytes of f32 and decoded by a lookup table in
//! the page, where an EXR decoder in JavaScript would need a library and its licence.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context as _, Result};

use crate::image::{exr, Image};

use super::output::chart;
use super::results::{RunRecord, Status, SuiteResults};

const VIEWER_JS: &str = include_str!("../../../assets/report/viewer.js");

/// The EXR the runner writes beside a thumbnail `images/NAME.png`: `images/NAME.exr`.
pub fn exr_of(png: &str) -> String {
    match png.strip_suffix(".png") {
        Some(stem) => format!("{stem}.exr"),
        None => format!("{png}.exr"),
    }
}

/// `image` as half-float RGB, little-endian, in base64. Finite values past the half floats'
/// range are clamped to its largest (65504), so a firefly stays a bright finite pixel.
pub fn half_base64(image: &Image) -> String {
    let mut bytes = Vec::with_capacity(6 * image.pixels.len());
    let most = f32::from(half::f16::MAX);
    for p in &image.pixels {
        for c in p {
            let v = if c.is_finite() {
                c.clamp(-most, most)
            } else {
                *c
            };
            bytes.extend_from_slice(&half::f16::from_f32(v).to_bits().to_le_bytes());
        }
    }
    base64(&bytes)
}

/// `s` as a JSON string safe inside a `<script>` element (no `<`, so no `</script>`).
fn json_string(s: &str) -> String {
    serde_json::to_string(s)
        .expect("a string serializes")
        .replace('<', "\\u003c")
}

/// The most base64 one scene's images may take in the page; past it they are embedded
/// box-filtered down by the smallest integer factor that fits (the viewer says so).
const SCENE_BYTES: usize = 24 << 20;

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
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
        for (name, exr) in wanted {
            match read(&out.join(&exr)) {
                Ok(im) => images.push((name, im)),
                Err(e) => log::warn!("report.html leaves out {name}: {e:#}"),
            }
        }
        let pixels: usize = images.iter().map(|(_, im)| im.pixels.len()).sum();
        let factor = (1..)
            .find(|f: &usize| 8 * pixels / (f * f) <= SCENE_BYTES)
            .expect("some factor fits");
        if factor > 1 {
            for (_, im) in images.iter_mut() {
                *im = crate::image::preview::downscale(im, factor as u32);
            }
        }
        let _ = write!(
            data,
            "{}{:?}:{{",
            if k > 0 { "," } else { "" },
            format!("scene{k}")
        );
        for (i, (name, im)) in images.iter().enumerate() {
            let _ = write!(
                data,
                "{}{}:{{\"width\":{},\"height\":{},\"rgb\":\"{}\"}}",
                if i > 0 { "," } else { "" },
                json_string(name),
                im.width,
                im.height,
                half_base64(im)
            );
        }
        data.push('}');
        let _ = writeln!(body, "<section class=\"scene\" id=\"scene{k}\">");
        let _ = writeln!(body, "<h2>{}</h2>", escape(scene));
        let _ = writeln!(
            body,
            "<div class=\"chart\">{}</div>",
            chart(results, scene).to_svg()
        );
        body += &table(&runs);
        if factor > 1 {
            let _ = writeln!(
                body,
                "<p class=\"note\">The viewer's images are averaged over {factor}x{factor} \
                 pixel blocks, so that the page stays under {} MB for this scene; the EXRs \
                 in images/ are full size.</p>",
                SCENE_BYTES >> 20
            );
        }
        if !images.is_empty() {
            body += VIEWER_MARKUP;
        }
        body += "</section>\n";
    }
    data.push('}');
    Ok(format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{title}</title><style>{STYLE}</style></head><body>\n\
         <h1>{title}</h1>\n<p>{description}</p>\n{body}\
         <script>{VIEWER_JS}</script>\n<script>const IRAD_DATA = {data};\n{PAGE_JS}</script>\n\
         </body></html>\n",
        title = escape(&format!("Benchmark suite {}", results.suite)),
        description = escape(results.description.trim()),
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

const VIEWER_MARKUP: &str = r#"<div class="viewer">
 <div class="controls">A <select class="a"></select> B <select class="b"></select>
 <select class="mode"><option value="split">split</option><option value="flip">flip</option><option value="relmse">relMSE</option><option value="signed">signed error</option></select>
 exposure <input class="exposure" type="range" min="-8" max="8" step="0.5" value="0"><span class="exposure-value">+0.0 stops</span>
 tone <select class="tone"><option value="srgb">sRGB</option><option value="gamma22">gamma 2.2</option><option value="aces">ACES</option><option value="linear">linear</option></select>
 split <input class="split" type="range" min="0" max="100" value="50"> <button class="flip">flip (F)</button> <button class="fit">fit</button></div>
 <canvas class="view" width="640" height="480"></canvas><br><canvas class="bar" width="640" height="30"></canvas>
 <div class="readout"></div>
</div>
"#;

const STYLE: &str = "body{font-family:sans-serif;margin:1em 2em}\
table.runs{border-collapse:collapse;margin:1em 0}\
table.runs td,table.runs th{border:1px solid #ccc;padding:2px 6px;text-align:right}\
table.runs th{cursor:pointer;background:#f4f4f4}\
table.runs tr.selected{background:#ffe9a8}\
canvas.view{border:1px solid #888;cursor:crosshair}\
.readout{font-family:monospace;font-size:12px;min-height:1.2em}\
circle.point{cursor:pointer}";

/// Wires each scene's viewer, table and chart: a click on a run's row or chart point shows it
/// as A; a click on a header sorts the table by that column.
const PAGE_JS: &str = r#"
for (const section of document.querySelectorAll("section.scene")) {
  const images = {};
  const raw = IRAD_DATA[section.id] || {};
  for (const name of Object.keys(raw)) {
    // Decoded when first shown.
    images[name] = () => IradViewer.decodeImage(raw[name].rgb, raw[name].width, raw[name].height);
  }
  const root = section.querySelector(".viewer");
  const names = Object.keys(images);
  let viewer = null;
  if (root && names.length > 0) {
    viewer = new IradViewer.Viewer(root, images, { a: names[names.length > 1 ? 1 : 0], b: names[0] });
    section.viewer = viewer;
  }
  const show = (name) => {
    if (!viewer || !images[name]) return;
    root.focus();
    viewer.a = name;
    root.querySelector("select.a").value = name;
    viewer.draw();
    for (const tr of section.querySelectorAll("tr[data-image]")) {
      tr.classList.toggle("selected", tr.dataset.image === name);
    }
  };
  const rows = [...section.querySelectorAll("tbody tr")];
  for (const tr of rows) tr.addEventListener("click", () => show(tr.dataset.image));
  for (const circle of section.querySelectorAll("circle.point")) {
    circle.addEventListener("click", () => {
      const tr = rows.find((r) => r.dataset.run === circle.dataset.run);
      if (tr) show(tr.dataset.image);
    });
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
        assert!(page.contains("<tr data-run=\"s/10/0.1\" data-image=\"ir vpls=64\">"));
        let reference = format!(
            "\"reference\":{{\"width\":3,\"height\":2,\"rgb\":\"{}\"}}",
            half_base64(&image(1.0))
        );
        let run_image = format!(
            "\"ir vpls=64\":{{\"width\":3,\"height\":2,\"rgb\":\"{}\"}}",
            half_base64(&image(0.5))
        );
        let (a, b) = (
            page.find(&reference).unwrap(),
            page.find(&run_image).unwrap(),
        );
        assert!(a < b, "the reference first");
        assert!(page.contains("IradViewer"));
        std::fs::remove_dir_all(&out).unwrap();
    }

    /// A run's name cannot end the page's script, and a firefly past the half floats' range
    /// stays finite.
    #[test]
    fn names_and_values_are_embedded_safely() {
        let key = json_string("spp=4 </script><b>\"x\"");
        assert!(!key.contains('<'), "{key}");
        assert_eq!(
            serde_json::from_str::<String>(&key).unwrap(),
            "spp=4 </script><b>\"x\""
        );
        let firefly = Image {
            width: 1,
            height: 1,
            pixels: vec![[1e6, f32::NAN, -1e6]],
        };
        // 65504 = 0x7bff, NaN stays NaN (0x7e00), -65504 = 0xfbff.
        assert_eq!(
            half_base64(&firefly),
            base64(&[0xff, 0x7b, 0x00, 0x7e, 0xff, 0xfb])
        );
    }

    #[test]
    fn base64_matches_the_standard_alphabet_and_padding() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
        assert_eq!(base64(&[0xff, 0xfe, 0xfd]), "//79");
    }

    #[test]
    fn half_floats_keep_exposure_precision() {
        let im = Image {
            width: 1,
            height: 1,
            pixels: vec![[1.0, 0.5, 1000.25]],
        };
        // 1.0 = 0x3c00, 0.5 = 0x3800, 1000.25 rounds to 1000 (0x63d0): 11 bits of mantissa.
        let b64 = half_base64(&im);
        assert_eq!(b64, base64(&[0x00, 0x3c, 0x00, 0x38, 0xd0, 0x63]));
        assert_eq!(exr_of("images/a-b.png"), "images/a-b.exr");
    }
}
