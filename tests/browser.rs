//! The HTML viewer in a real browser (docs/DESIGN.md "Looking at results"): Debian's chromium, headless, driven over WebDriver (tests/common/webdriver.rs)
//! through pages `irad compare --html` writes from EXRs with known values. Each view's
//! screenshot is checked where its layout says each thing should be, the values the readout
//! shows against the EXRs, and the console for errors. The screenshots stay in
//! target/tmp/browser/ for a person to look at. The suite's report.html is opened by
//! tests/bench_suite.rs's quick suite test (`check_report` below).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::json;

use irad::image::{exr, Image};

use crate::common::webdriver::{Browser, Screenshot};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("irad-browser-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Where the screenshots are kept: target/tmp/browser/NAME.png.
fn keep(shot: &Screenshot, name: &str) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("browser");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{name}.png")), &shot.png).unwrap();
}

fn irad(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_irad"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "irad {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn image(width: u32, height: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Image {
    let mut pixels = Vec::new();
    for y in 0..height {
        for x in 0..width {
            pixels.push(f(x, y));
        }
    }
    Image {
        width,
        height,
        pixels,
    }
}

fn pixel(im: &Image, x: u32, y: u32) -> [f32; 3] {
    im.pixels[(y * im.width + x) as usize]
}

/// What the viewer draws for `v` at `stops` with the sRGB curve: the half float's value,
/// exposed, encoded and rounded to 8 bits.
fn srgb8(v: [f32; 3], stops: f32) -> [u8; 3] {
    v.map(|c| {
        let c = half::f16::from_f32(c).to_f32() * 2f32.powf(stops);
        let e = if c <= 0.0031308 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (255.0 * e.clamp(0.0, 1.0)).round() as u8
    })
}

fn close(got: [u8; 3], want: [u8; 3], what: &str) {
    assert!(
        got.iter()
            .zip(want)
            .all(|(&g, w)| (g as i32 - w as i32).abs() <= 2),
        "{what}: drawn {got:?}, expected {want:?}"
    );
}

/// The readout's values of `key` ("a" or "b") against the EXR's pixel, within half precision.
fn readout_matches(b: &Browser, root: &str, key: &str, want: [f32; 3]) {
    let text = b.js(
        &format!("return document.querySelector('{root} .readout').dataset.{key};"),
        json!([]),
    );
    let got: Vec<f32> = text
        .as_str()
        .unwrap_or_else(|| panic!("no readout {key}: {text}"))
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(got.len(), 3, "readout {key}: {text}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g - w).abs() <= w.abs() * 2f32.powi(-11),
            "readout {key}: {got:?}, the EXR holds {want:?}"
        );
    }
}

fn data(b: &Browser, css: &str, key: &str) -> String {
    b.js(
        &format!("return document.querySelector('{css}').dataset.{key};"),
        json!([]),
    )
    .as_str()
    .unwrap_or_default()
    .to_string()
}

fn text(b: &Browser, css: &str) -> String {
    b.js(
        &format!("return document.querySelector('{css}').textContent;"),
        json!([]),
    )
    .as_str()
    .unwrap_or_default()
    .to_string()
}

fn assert_no_console_errors(b: &Browser, when: &str) {
    let errors = b.console_errors();
    assert!(errors.is_empty(), "console errors {when}: {errors:?}");
}

/// `inner` lies inside `outer` (rectangles x, y, width, height).
fn inside(inner: [f64; 4], outer: [f64; 4]) -> bool {
    inner[0] >= outer[0]
        && inner[1] >= outer[1]
        && inner[0] + inner[2] <= outer[0] + outer[2]
        && inner[1] + inner[3] <= outer[1] + outer[3]
}

const VIEWPORT: [f64; 4] = [0.0, 0.0, 1000.0, 1000.0];

/// Two EXRs with a value per pixel, compared with `--html`: the split and its slider, the
/// exposure, zoom to one pixel and its values, each error map with its colour bar, FLIP and
/// the A/B flip key.
#[test]
fn the_viewer_compares_two_exrs_in_chromium() {
    let dir = temp_dir("still");
    // 32 x 24 fits the 640 x 480 canvas at 20 screen pixels an image pixel.
    let a = image(32, 24, |x, y| {
        [0.05 + 0.02 * x as f32, 0.1 + 0.03 * y as f32, 0.4]
    });
    let r = image(32, 24, |x, y| {
        [0.6, 0.3 + 0.01 * x as f32, 0.05 + 0.02 * y as f32]
    });
    exr::write(&dir.join("test.exr"), &a).unwrap();
    exr::write(&dir.join("reference.exr"), &r).unwrap();
    let stem = dir.join("cmp");
    irad(&[
        "compare",
        dir.join("test.exr").to_str().unwrap(),
        dir.join("reference.exr").to_str().unwrap(),
        "-o",
        stem.to_str().unwrap(),
        "--html",
    ]);
    let Some(b) = Browser::start(1000, 1000) else {
        return;
    };
    b.open(&dir.join("cmp.html"));
    assert_no_console_errors(&b, "loading the page");
    let root = "#viewer0 .viewer";
    // Layout: the controls above the canvas, the colour bar and readout below it, all in view.
    let canvas = b.find(&format!("{root} canvas.view"));
    let c = b.rect(&canvas);
    assert_eq!(
        (c[2], c[3]),
        (642.0, 482.0),
        "640 x 480 and a 1-pixel border"
    );
    let controls = b.rect(&b.find(&format!("{root} .controls")));
    let bar = b.rect(&b.find(&format!("{root} canvas.bar")));
    let readout = b.rect(&b.find(&format!("{root} .readout")));
    assert!(
        controls[1] + controls[3] <= c[1],
        "controls above the image"
    );
    assert!(
        bar[1] >= c[1] + c[3] && readout[1] >= bar[1] + bar[3],
        "bar, then readout"
    );
    for (what, rect) in [("controls", controls), ("image", c), ("bar", bar)] {
        assert!(inside(rect, VIEWPORT), "{what} {rect:?} in the page's view");
    }
    // Canvas point (x, y) on the page; image pixel (x / 20, y / 20).
    let at = |x: f64, y: f64| (c[0] + 1.0 + x, c[1] + 1.0 + y);
    let split = b.screenshot();
    keep(&split, "compare-split");
    let (px, py) = at(110.0, 210.0);
    close(
        split.at(px, py),
        srgb8(pixel(&a, 5, 10), 0.0),
        "A left of the split",
    );
    let (px, py) = at(510.0, 210.0);
    close(
        split.at(px, py),
        srgb8(pixel(&r, 25, 10), 0.0),
        "B right of it",
    );
    // Nothing drawn in the bar outside the error maps.
    assert_eq!(split.at(bar[0] + 5.0, bar[1] + 5.0), [255, 255, 255]);

    // The slider towards a quarter (a range input's ends are inset by half its thumb, so the
    // click lands near 21): A left of value% of the canvas, B right of it.
    let slider = b.rect(&b.find(&format!("{root} input.split")));
    b.click_at(slider[0] + 0.25 * slider[2], slider[1] + slider[3] / 2.0);
    let value: f64 = b
        .js(
            &format!("return document.querySelector('{root} input.split').value;"),
            json!([]),
        )
        .as_str()
        .unwrap()
        .parse()
        .unwrap();
    assert!((15.0..=35.0).contains(&value), "the slider at {value}");
    let line = 6.4 * value;
    let moved = b.screenshot();
    keep(&moved, "compare-slider");
    let (left, right) = ((line / 20.0) as u32 - 2, (line / 20.0) as u32 + 2);
    let (px, py) = at(20.0 * left as f64 + 10.0, 210.0);
    close(
        moved.at(px, py),
        srgb8(pixel(&a, left, 10), 0.0),
        "A left of the moved split",
    );
    let (px, py) = at(20.0 * right as f64 + 10.0, 210.0);
    close(
        moved.at(px, py),
        srgb8(pixel(&r, right, 10), 0.0),
        "B right of it",
    );
    // The same pixel showed A before the move.
    close(
        split.at(px, py),
        srgb8(pixel(&a, right, 10), 0.0),
        "A there before",
    );

    // Exposure +1 stop by the key `e` twice (half a stop each), the viewer focused by a click.
    let (px, py) = at(90.0, 210.0);
    b.click_at(px, py);
    b.keys("ee");
    assert_eq!(text(&b, &format!("{root} .exposure-value")), "+1.0 stops");
    let exposed = b.screenshot();
    keep(&exposed, "compare-exposure");
    close(
        exposed.at(px, py),
        srgb8(pixel(&a, 4, 10), 1.0),
        "A at +1 stop",
    );

    // Zoom three notches about image pixel (4, 10): 160 screen pixels a pixel, that pixel
    // still under the cursor, its values in the readout equal to the EXRs'.
    for _ in 0..3 {
        b.wheel_at(px, py, -100);
    }
    b.move_to(px, py);
    let zoom: f64 = b
        .js(
            &format!("return document.querySelector('{root}').viewer.scale;"),
            json!([]),
        )
        .as_f64()
        .unwrap();
    assert_eq!(zoom, 160.0);
    assert_eq!(data(&b, &format!("{root} .readout"), "x"), "4");
    assert_eq!(data(&b, &format!("{root} .readout"), "y"), "10");
    readout_matches(&b, root, "a", pixel(&a, 4, 10));
    readout_matches(&b, root, "b", pixel(&r, 4, 10));
    let zoomed = b.screenshot();
    keep(&zoomed, "compare-zoomed");
    // The pixel fills 160 x 160 screen pixels about the cursor (it sat at the pixel's centre),
    // up to the split's line (at canvas x 6.4 value, right of the cursor's 90).
    assert!(line > 125.0, "the split's line at {line}");
    let want = srgb8(pixel(&a, 4, 10), 1.0);
    for (dx, dy) in [(-70.0, -70.0), (30.0, -70.0), (-70.0, 70.0), (30.0, 70.0)] {
        close(
            zoomed.at(px + dx, py + dy),
            want,
            "the zoomed pixel's block",
        );
    }
    b.click(&b.find(&format!("{root} button.fit")));

    // The error maps: relMSE (black to white), signed (blue, black, red), FLIP (black to
    // white), each with its bar, and the signed map's colour where A is darker or brighter.
    let choose = |select: &str, value: &str| {
        b.click(&b.find(&format!("{root} select.{select} option[value=\"{value}\"]")));
    };
    let bar_at = |shot: &Screenshot, t: f64| shot.at(bar[0] + 1.0 + t * 637.0, bar[1] + 4.0);
    choose("mode", "relmse");
    let relmse = b.screenshot();
    keep(&relmse, "compare-relmse");
    assert_eq!(data(&b, root, "mode"), "relmse");
    close(bar_at(&relmse, 0.0), [0, 0, 0], "relMSE bar's low end");
    close(
        bar_at(&relmse, 1.0),
        [255, 255, 255],
        "relMSE bar's high end",
    );
    choose("mode", "signed");
    let signed = b.screenshot();
    keep(&signed, "compare-signed");
    close(bar_at(&signed, 0.0), [64, 140, 255], "signed bar's low end");
    close(bar_at(&signed, 1.0), [255, 51, 26], "signed bar's high end");
    let luminance = |v: [f32; 3]| 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
    for (x, y) in [(2u32, 2u32), (30, 22)] {
        let (ya, yb) = (luminance(pixel(&a, x, y)), luminance(pixel(&r, x, y)));
        let (px, py) = at(20.0 * x as f64 + 10.0, 20.0 * y as f64 + 10.0);
        let [red, _, blue] = signed.at(px, py);
        assert_eq!(
            red > blue,
            ya > yb,
            "signed error at ({x}, {y}): A {ya} against B {yb}"
        );
    }
    choose("mode", "flipmap");
    let flip = b.screenshot();
    keep(&flip, "compare-flip-map");
    assert_eq!(
        text(&b, &format!("{root} .note")),
        "",
        "FLIP against the reference"
    );
    close(bar_at(&flip, 1.0), [255, 255, 255], "FLIP bar's high end");
    let (px, py) = at(310.0, 230.0);
    assert_ne!(flip.at(px, py), [64, 64, 64], "a FLIP map is drawn");
    // Against another image than the reference there is no FLIP map, and the page says why.
    choose("b", "test.exr");
    assert!(text(&b, &format!("{root} .note")).contains("against reference.exr"));
    choose("b", "reference.exr");

    // F flips between A and B.
    b.click_at(px, py);
    b.keys("f");
    assert_eq!(data(&b, root, "shown"), "reference.exr");
    let shown_b = b.screenshot();
    keep(&shown_b, "compare-flip-b");
    close(
        shown_b.at(px, py),
        srgb8(pixel(&r, 15, 11), 1.0),
        "F shows B",
    );
    b.keys("f");
    assert_eq!(data(&b, root, "shown"), "test.exr");
    close(
        b.screenshot().at(px, py),
        srgb8(pixel(&a, 15, 11), 1.0),
        "F again shows A",
    );
    assert_no_console_errors(&b, "after every view");
    drop(b);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Two folders of frames compared with `--html`: the player steps, plays and pauses, the
/// readout follows the frame, and the error plot marks the current frame.
#[test]
fn the_viewer_plays_a_sequence_in_chromium() {
    let dir = temp_dir("sequence");
    let (tests, references) = (dir.join("test"), dir.join("reference"));
    std::fs::create_dir_all(&tests).unwrap();
    std::fs::create_dir_all(&references).unwrap();
    // 16 x 12 at 40 screen pixels an image pixel; the error grows frame by frame.
    let frames: Vec<(Image, Image)> = (0..4)
        .map(|k| {
            let r = image(16, 12, |x, y| {
                [
                    0.2 + 0.02 * x as f32,
                    0.3,
                    0.1 + 0.01 * y as f32 + 0.05 * k as f32,
                ]
            });
            let t = image(16, 12, |x, y| {
                let v = pixel(&r, x, y);
                let e = 1.0 + 0.1 * (k + 1) as f32 * if (x + y) % 2 == 0 { 1.0 } else { -1.0 };
                [v[0] * e, v[1] * e, v[2] * e]
            });
            (t, r)
        })
        .collect();
    for (k, (t, r)) in frames.iter().enumerate() {
        exr::write(&tests.join(format!("frame_{k:04}.exr")), t).unwrap();
        exr::write(&references.join(format!("frame_{k:04}.exr")), r).unwrap();
    }
    let out = dir.join("cmp");
    irad(&[
        "compare",
        tests.to_str().unwrap(),
        references.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--html",
        "--no-flip",
    ]);
    let Some(b) = Browser::start(1000, 1000) else {
        return;
    };
    b.open(&out.join("compare.html"));
    assert_no_console_errors(&b, "loading the sequence");
    let root = "#viewer0 .viewer";
    let c = b.rect(&b.find(&format!("{root} canvas.view")));
    let controls = b.rect(&b.find(&format!("{root} .sequence")));
    let plot = b.rect(&b.find(&format!("{root} canvas.plot")));
    assert!(
        controls[1] + controls[3] <= plot[1] && plot[1] + plot[3] <= c[1],
        "player, plot, image"
    );
    assert!(inside(c, VIEWPORT) && inside(plot, VIEWPORT));
    assert_eq!(
        text(&b, &format!("{root} .frame-label")),
        "frame 0 (1 of 4)"
    );
    // The plot's marker: the column of its red line.
    let marker = |shot: &Screenshot| -> f64 {
        let y = plot[1] + 10.0;
        (0..plot[2] as u32)
            .map(|dx| plot[0] + dx as f64)
            .find(|&x| shot.at(x, y) == [208, 48, 32])
            .unwrap_or_else(|| panic!("no marker in the plot"))
    };
    let first = b.screenshot();
    keep(&first, "sequence-frame0");
    let x0 = marker(&first);
    let (px, py) = (c[0] + 1.0 + 40.0 * 3.5, c[1] + 1.0 + 40.0 * 5.5);
    b.click_at(px, py);
    // Step with the arrow key, then the next button; the readout follows the frame.
    b.keys("\u{E014}");
    assert_eq!(data(&b, root, "frame"), "1");
    readout_matches(&b, root, "a", pixel(&frames[1].0, 3, 5));
    readout_matches(&b, root, "b", pixel(&frames[1].1, 3, 5));
    b.click(&b.find(&format!("{root} .sequence button.next")));
    assert_eq!(data(&b, root, "frame"), "2");
    let third = b.screenshot();
    keep(&third, "sequence-frame2");
    let x2 = marker(&third);
    assert!(x2 > x0 + 100.0, "the marker moved right: {x0} to {x2}");
    close(
        third.at(px, py),
        srgb8(pixel(&frames[2].0, 3, 5), 0.0),
        "frame 2's image",
    );
    // Play until the frame changes, then pause.
    b.click(&b.find(&format!("{root} .sequence button.play")));
    assert_eq!(data(&b, root, "playing"), "true");
    let start = Instant::now();
    while data(&b, root, "frame") == "2" {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "playing did not change the frame"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    b.click(&b.find(&format!("{root} .sequence button.play")));
    assert_eq!(data(&b, root, "playing"), "false");
    let paused = data(&b, root, "frame");
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(data(&b, root, "frame"), paused, "paused");
    // The scrubber's left end is frame 0.
    let scrubber = b.rect(&b.find(&format!("{root} input.scrubber")));
    b.click_at(scrubber[0] + 2.0, scrubber[1] + scrubber[3] / 2.0);
    assert_eq!(data(&b, root, "frame"), "0");
    assert_no_console_errors(&b, "after playing");
    drop(b);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A suite's report.html (tests/bench_suite.rs runs the quick suite): each scene's chart, table
/// and viewer in order; a hover on a chart point shows its run's figures, a click shows its
/// image as A and marks its row; a header sorts the table; no console errors.
pub fn check_report(report: &Path, scenes: usize) {
    let Some(b) = Browser::start(1200, 1000) else {
        return;
    };
    b.open(report);
    assert_no_console_errors(&b, "loading report.html");
    let count = b
        .js(
            "return document.querySelectorAll('section.scene').length;",
            json!([]),
        )
        .as_u64()
        .unwrap();
    assert_eq!(count as usize, scenes);
    for k in 0..scenes {
        let section = format!("#scene{k}");
        let chart = b.rect(&b.find(&format!("{section} .chart svg")));
        let table = b.rect(&b.find(&format!("{section} table.runs")));
        let canvas = b.find(&format!("{section} canvas.view"));
        let view = b.rect(&canvas);
        assert!(
            chart[1] + chart[3] <= table[1] && table[1] + table[3] <= view[1],
            "chart, table, viewer"
        );
        // Bring the chart into view, hover and click its first point.
        b.js(
            "document.querySelector(arguments[0]).scrollIntoView();",
            json!([format!("{section} .chart")]),
        );
        let point = b.find(&format!("{section} circle.point"));
        let p = b.rect(&point);
        b.js(
            "document.querySelector('.hover-tip').hidden = true;",
            json!([]),
        );
        b.move_to(p[0] + p[2] / 2.0, p[1] + p[3] / 2.0);
        let tip = b.js(
            "const t = document.querySelector('.hover-tip'); return t.hidden ? '' : t.textContent;",
            json!([]),
        );
        let tip = tip.as_str().unwrap_or_default().to_string();
        // The point's own run: its row's method and budget, relMSE, spread, seeds and time.
        let cells = b.js(
            "const r = [...document.querySelectorAll(arguments[0] + ' tbody tr')].find(r => r.dataset.run === arguments[1].dataset.run); return [r.children[1].textContent, r.children[2].textContent, r.children[7].textContent];",
            json!([section, {crate::common::webdriver::ELEMENT: point}]),
        );
        let expected = format!(
            "{} {}: relMSE",
            cells[0].as_str().unwrap(),
            cells[1].as_str().unwrap()
        );
        assert!(
            tip.starts_with(&expected),
            "hover: {tip:?}, expected {expected:?}"
        );
        let seeds = format!("over {} seeds", cells[2].as_str().unwrap());
        assert!(
            tip.contains(&seeds) && tip.contains("ms GPU"),
            "hover: {tip:?}"
        );
        b.click_at(p[0] + p[2] / 2.0, p[1] + p[3] / 2.0);
        let run = b.js(
            "return document.querySelector(arguments[0]).dataset.run;",
            json!([format!("{section} circle.point")]),
        );
        let row = b.js(
            "const r = document.querySelector(arguments[0] + ' tr.selected'); return r ? [r.dataset.run, r.dataset.image] : null;",
            json!([section]),
        );
        assert_eq!(row[0], run, "the clicked point's row is marked");
        let a = b.js(
            "return document.querySelector(arguments[0] + ' .viewer').viewer.a;",
            json!([section]),
        );
        assert_eq!(a, row[1], "its image is A");
        if k == 0 {
            let shot = b.screenshot();
            keep(&shot, "report-scene0");
            // The viewer draws something other than its background at its centre.
            b.js(
                "document.querySelector(arguments[0]).scrollIntoView();",
                json!([format!("{section} .viewer")]),
            );
            let view = b.rect(&canvas);
            let shot = b.screenshot();
            keep(&shot, "report-scene0-viewer");
            assert_ne!(
                shot.at(view[0] + view[2] / 2.0, view[1] + view[3] / 2.0),
                [32, 32, 32]
            );
        }
    }
    // A header sorts its table: relMSE ascending, then descending.
    let header = b.find("#scene0 table.runs th:nth-child(5)");
    b.js(
        "arguments[0].scrollIntoView();",
        json!([{crate::common::webdriver::ELEMENT: header}]),
    );
    let column = || -> Vec<f64> {
        let values = b.js(
            "return [...document.querySelectorAll('#scene0 table.runs tbody tr')].map(r => parseFloat(r.children[4].textContent));",
            json!([]),
        );
        values
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap_or(f64::INFINITY))
            .collect()
    };
    b.click(&header);
    let up = column();
    assert!(
        up.windows(2).all(|w| w[0] <= w[1]),
        "sorted by relMSE: {up:?}"
    );
    b.click(&header);
    let down = column();
    assert!(
        down.windows(2).all(|w| w[0] >= w[1]),
        "sorted by relMSE, descending: {down:?}"
    );
    assert_no_console_errors(&b, "using report.html");
}
