//! Log-log charts as SVG for `irad bench suite`: per scene, relMSE (y) against GPU time in ms
//! (x), one line per method, each of its budgets a labelled point. `read_svg` reads the drawn
//! points and the axis mapping back, so tests check what was drawn, not how.
//!
//! std only; the SVG is self-contained (no fonts, scripts or files beyond itself). A point that
//! cannot sit on a log axis (zero, negative, NaN, infinite) is listed in a note under the chart
//! rather than dropped silently.

use std::fmt::Write as _;

/// One measured run: `x` and `y` go on log axes; `label` is its budget as printed beside the
/// point ("vpls=64 frames=4"); `run_id` ties the point to the run's record.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub label: String,
    pub run_id: String,
}

/// One method: its points are joined in order of x.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<Point>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

/// A point as drawn, read back from an SVG written by `to_svg`.
#[derive(Debug, Clone, PartialEq)]
pub struct PlottedPoint {
    pub series: String,
    pub run_id: String,
    pub label: String,
    pub x: f64,
    pub y: f64,
    pub cx: f64,
    pub cy: f64,
}

/// The axis mapping as drawn: pixel = origin + scale * (log10(value) - log_min) along each axis.
/// x grows rightwards from `left`, y upwards from `bottom` (SVG's y points down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axes {
    pub x_log_min: f64,
    pub x_log_max: f64,
    pub y_log_min: f64,
    pub y_log_max: f64,
    pub left: f64,
    pub right: f64,
    pub top: f64,
    pub bottom: f64,
}

impl Axes {
    pub fn to_px(&self, x: f64, y: f64) -> (f64, f64) {
        let sx = (self.right - self.left) / (self.x_log_max - self.x_log_min);
        let sy = (self.top - self.bottom) / (self.y_log_max - self.y_log_min);
        (
            self.left + sx * (x.log10() - self.x_log_min),
            self.bottom + sy * (y.log10() - self.y_log_min),
        )
    }
}

/// Okabe & Ito's colour-blind-safe palette, yellow last: it is the hardest to see on white.
const PALETTE: [&str; 8] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442",
];

/// Series i's colour, and past the palette's length a dash pattern so no two series look alike.
fn style(i: usize) -> (&'static str, &'static str) {
    const DASHES: [&str; 3] = [
        "",
        r#" stroke-dasharray="6 3""#,
        r#" stroke-dasharray="2 2""#,
    ];
    (
        PALETTE[i % PALETTE.len()],
        DASHES[(i / PALETTE.len()) % DASHES.len()],
    )
}

const WIDTH: f64 = 720.0;
const HEIGHT: f64 = 480.0;
const LEFT: f64 = 72.0;
const TOP: f64 = 44.0;
const RIGHT: f64 = 540.0;
const BOTTOM: f64 = 400.0;
const FONT: f64 = 12.0;
const LABEL_FONT: f64 = 11.0;
const RADIUS: f64 = 4.0;
const NOTE_STEP: f64 = 15.0;
const LEGEND_STEP: f64 = 18.0;
/// Tick labels per axis at most; more decades than this label every second (third...) one.
const MAX_TICK_LABELS: f64 = 10.0;
/// Minor ticks (2..9 x 10^k) only while a decade is wide enough to tell them apart.
const MAX_DECADES_FOR_MINOR: f64 = 8.0;

fn chartable(p: &Point) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.x > 0.0 && p.y > 0.0
}

/// Whole decades enclosing the values, at least one wide; one decade [1, 10] when empty.
fn decade_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v.log10()), hi.max(v.log10()))
    });
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, 1.0);
    }
    // + 0.0: ceil(-0.3) is -0, which would be written "-0".
    let (lo, hi) = (lo.floor() + 0.0, hi.ceil() + 0.0);
    (lo, if hi > lo { hi } else { lo + 1.0 })
}

/// 10^k as a tick label: plain decimals near 1 ("0.01", "100"), exponents beyond ("1e-5").
fn decade_label(k: i64) -> String {
    match k {
        -3..=-1 => format!("0.{}1", "0".repeat((-k - 1) as usize)),
        0..=4 => format!("1{}", "0".repeat(k as usize)),
        _ => format!("1e{k}"),
    }
}

fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Rendered width is not known without fonts; 0.6 em per character over-estimates typical
/// sans-serif text, so labels placed apart by this stay apart.
fn text_width(s: &str, font: f64) -> f64 {
    s.chars().count() as f64 * font * 0.6
}

#[derive(Clone, Copy)]
struct Rect {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

impl Rect {
    fn overlap(&self, o: &Rect) -> f64 {
        let w = self.x1.min(o.x1) - self.x0.max(o.x0);
        let h = self.y1.min(o.y1) - self.y0.max(o.y0);
        if w > 0.0 && h > 0.0 {
            w * h
        } else {
            0.0
        }
    }

    fn inside(&self, o: &Rect) -> bool {
        self.x0 >= o.x0 && self.x1 <= o.x1 && self.y0 >= o.y0 && self.y1 <= o.y1
    }

    fn area(&self) -> f64 {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }

    /// Length of the segment a-b inside this rectangle (Liang-Barsky clipping).
    fn clipped_len(&self, a: (f64, f64), b: (f64, f64)) -> f64 {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-dx, a.0 - self.x0),
            (dx, self.x1 - a.0),
            (-dy, a.1 - self.y0),
            (dy, self.y1 - a.1),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return 0.0;
                }
            } else if p < 0.0 {
                t0 = t0.max(q / p);
            } else {
                t1 = t1.min(q / p);
            }
        }
        if t1 > t0 {
            (t1 - t0) * dx.hypot(dy)
        } else {
            0.0
        }
    }
}

/// A position in the SVG's pixels.
type Px = (f64, f64);

/// Where a point's label goes: its anchor and baseline, or not drawn at all (`shown` false)
/// where every spot would cover labels already placed.
struct Placed {
    x: f64,
    y: f64,
    anchor: &'static str,
    shown: bool,
}

/// Greedy label placement: each label takes the candidate spot (right first) that overlaps the
/// labels already placed, the circles and the lines least, and stays inside the plot (outside it
/// lie the tick labels, the title and the legend). A label that would come within 3 px of
/// another on every spot is left out: overprinted text helps no one, and the circle's
/// `<title>` still holds it.
fn place_labels(
    circles: &[Px],
    labels: &[&str],
    segments: &[(Px, Px)],
    plot: Rect,
    canvas: Rect,
) -> Vec<Placed> {
    const SPOTS: [(f64, f64, &str); 8] = [
        (7.0, 4.0, "start"),
        (6.0, -6.0, "start"),
        (6.0, 14.0, "start"),
        (-7.0, 4.0, "end"),
        (-6.0, -6.0, "end"),
        (-6.0, 14.0, "end"),
        (0.0, -9.0, "middle"),
        (0.0, 17.0, "middle"),
    ];
    let circle_boxes: Vec<Rect> = circles
        .iter()
        .map(|&(x, y)| Rect {
            x0: x - RADIUS - 1.0,
            y0: y - RADIUS - 1.0,
            x1: x + RADIUS + 1.0,
            y1: y + RADIUS + 1.0,
        })
        .collect();
    let mut taken: Vec<Rect> = Vec::new();
    let mut placed = Vec::with_capacity(labels.len());
    for (&(cx, cy), label) in circles.iter().zip(labels) {
        let w = text_width(label, LABEL_FONT);
        let mut best: Option<(f64, Rect, Placed)> = None;
        for (i, &(dx, dy, anchor)) in SPOTS.iter().enumerate() {
            let (x, y) = (cx + dx, cy + dy);
            let x0 = match anchor {
                "start" => x,
                "end" => x - w,
                _ => x - 0.5 * w,
            };
            let r = Rect {
                x0,
                y0: y - 0.8 * LABEL_FONT,
                x1: x0 + w,
                y1: y + 0.25 * LABEL_FONT,
            };
            // Padded so that labels which merely touch count as overlapping.
            let padded = Rect {
                x0: r.x0 - 3.0,
                y0: r.y0 - 1.0,
                x1: r.x1 + 3.0,
                y1: r.y1 + 1.0,
            };
            let labels_hit: f64 = taken.iter().map(|t| padded.overlap(t)).sum();
            let circles_hit: f64 = circle_boxes.iter().map(|c| r.overlap(c)).sum();
            let lines_hit: f64 = segments.iter().map(|&(a, b)| r.clipped_len(a, b)).sum();
            let outside_plot = r.area() - r.overlap(&plot);
            let mut score = labels_hit
                + 4.0 * circles_hit
                + 10.0 * lines_hit
                + 4.0 * outside_plot
                + 0.1 * i as f64;
            if !r.inside(&canvas) {
                score += 1e4;
            }
            if best.as_ref().is_none_or(|(s, _, _)| score < *s) {
                let shown = !label.is_empty() && labels_hit == 0.0;
                best = Some((
                    score,
                    r,
                    Placed {
                        x,
                        y,
                        anchor,
                        shown,
                    },
                ));
            }
        }
        let (_, r, p) = best.expect("SPOTS is not empty");
        if p.shown {
            taken.push(r);
        }
        placed.push(p);
    }
    placed
}

/// An SVG being written, a line at a time.
struct Out(String);

impl Out {
    fn line(&mut self, args: std::fmt::Arguments) {
        self.0
            .write_fmt(args)
            .expect("writing to a String cannot fail");
        self.0.push('\n');
    }
}

impl Chart {
    pub fn to_svg(&self) -> String {
        // Chartable points of each series in drawing order (by x, then y).
        let charted: Vec<Vec<&Point>> = self
            .series
            .iter()
            .map(|s| {
                let mut v: Vec<&Point> = s.points.iter().filter(|p| chartable(p)).collect();
                v.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
                v
            })
            .collect();
        let any = charted.iter().any(|s| !s.is_empty());
        let (x_log_min, x_log_max) = decade_range(charted.iter().flatten().map(|p| p.x));
        let (y_log_min, y_log_max) = decade_range(charted.iter().flatten().map(|p| p.y));
        let axes = Axes {
            x_log_min,
            x_log_max,
            y_log_min,
            y_log_max,
            left: LEFT,
            right: RIGHT,
            top: TOP,
            bottom: BOTTOM,
        };
        let px: Vec<Vec<(f64, f64)>> = charted
            .iter()
            .map(|points| points.iter().map(|p| axes.to_px(p.x, p.y)).collect())
            .collect();
        let circles: Vec<(f64, f64)> = px.iter().flatten().copied().collect();
        let labels: Vec<&str> = charted.iter().flatten().map(|p| p.label.as_str()).collect();
        let segments: Vec<_> = px
            .iter()
            .flat_map(|line| line.windows(2).map(|w| (w[0], w[1])))
            .collect();
        let legend_x = RIGHT + 20.0;
        let legend_w = self
            .series
            .iter()
            .map(|s| text_width(&s.name, FONT))
            .fold(0.0, f64::max);
        let width = WIDTH.max((legend_x + 28.0 + legend_w + 10.0).ceil());
        let plot = Rect {
            x0: LEFT,
            y0: TOP,
            x1: RIGHT,
            y1: BOTTOM,
        };
        let canvas = Rect {
            x0: 0.0,
            y0: 0.0,
            x1: width,
            y1: HEIGHT,
        };
        let placed = place_labels(&circles, &labels, &segments, plot, canvas);

        let mut notes = Vec::new();
        if !any {
            notes.push("no data: no point with positive, finite values to chart".to_string());
        }
        for s in &self.series {
            for p in s.points.iter().filter(|p| !chartable(p)) {
                let mut why = Vec::new();
                if !(p.x.is_finite() && p.x > 0.0) {
                    why.push(format!("{} {}", self.x_label, p.x));
                }
                if !(p.y.is_finite() && p.y > 0.0) {
                    why.push(format!("{} {}", self.y_label, p.y));
                }
                notes.push(format!(
                    "not charted: {} ({} {}; {})",
                    p.run_id,
                    s.name,
                    p.label,
                    why.join(", ")
                ));
            }
        }
        let hidden = labels
            .iter()
            .zip(&placed)
            .filter(|(l, p)| !l.is_empty() && !p.shown)
            .count();
        if hidden > 0 {
            notes.push(format!(
                "{hidden} point label(s) left out where they would cover others; \
                 each point's tooltip holds its label"
            ));
        }

        let notes_y = BOTTOM + 62.0;
        let height = HEIGHT
            .max((notes_y + NOTE_STEP * notes.len().saturating_sub(1) as f64 + 12.0).ceil())
            .max((TOP + LEGEND_STEP * self.series.len() as f64 + 12.0).ceil());

        let mut out = Out(String::new());
        out.line(format_args!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="{FONT}">"#
        ));
        out.line(format_args!(
            r#"<rect x="0" y="0" width="{width}" height="{height}" fill="white"/>"#
        ));
        out.line(format_args!(
            r#"<text class="title" x="{:.3}" y="24" text-anchor="middle" font-size="15" font-weight="bold">{}</text>"#,
            0.5 * (LEFT + RIGHT),
            esc(&self.title)
        ));
        out.line(format_args!(
            r#"<g id="plot" data-x-log-min="{}" data-x-log-max="{}" data-y-log-min="{}" data-y-log-max="{}" data-left="{}" data-right="{}" data-top="{}" data-bottom="{}">"#,
            axes.x_log_min,
            axes.x_log_max,
            axes.y_log_min,
            axes.y_log_max,
            axes.left,
            axes.right,
            axes.top,
            axes.bottom
        ));
        self.write_axes(&mut out, &axes);

        // Lines and circles, one group per series.
        for (i, ((s, points), px)) in self.series.iter().zip(&charted).zip(&px).enumerate() {
            let (colour, dash) = style(i);
            out.line(format_args!(
                r#"<g class="series" data-series="{}" fill="{colour}" stroke="{colour}">"#,
                esc(&s.name)
            ));
            if px.len() > 1 {
                let coords: Vec<String> =
                    px.iter().map(|(x, y)| format!("{x:.3},{y:.3}")).collect();
                out.line(format_args!(
                    r#"<polyline points="{}" fill="none" stroke-width="1.5"{dash}/>"#,
                    coords.join(" ")
                ));
            }
            for (p, &(cx, cy)) in points.iter().zip(px) {
                out.line(format_args!(
                    r#"<circle class="point" cx="{cx:.3}" cy="{cy:.3}" r="{RADIUS}" stroke="white" stroke-width="1" data-series="{}" data-run="{}" data-label="{}" data-x="{}" data-y="{}"><title>{}</title></circle>"#,
                    esc(&s.name),
                    esc(&p.run_id),
                    esc(&p.label),
                    p.x,
                    p.y,
                    esc(&format!(
                        "{} {} ({}): {} {}, {} {}",
                        s.name, p.label, p.run_id, self.x_label, p.x, self.y_label, p.y
                    ))
                ));
            }
            out.line(format_args!("</g>"));
        }

        // Labels above every line, each with a white halo so a line through it stays legible.
        out.line(format_args!(
            r##"<g class="labels" font-size="{LABEL_FONT}" fill="#333333" stroke="white" stroke-width="3" stroke-linejoin="round" paint-order="stroke">"##
        ));
        for (label, p) in labels.iter().zip(&placed) {
            if p.shown {
                out.line(format_args!(
                    r#"<text x="{:.3}" y="{:.3}" text-anchor="{}">{}</text>"#,
                    p.x,
                    p.y,
                    p.anchor,
                    esc(label)
                ));
            }
        }
        out.line(format_args!("</g>"));
        if !any {
            out.line(format_args!(
                r##"<text class="no-data" x="{:.3}" y="{:.3}" text-anchor="middle" font-size="16" fill="#666666">no data</text>"##,
                0.5 * (LEFT + RIGHT),
                0.5 * (TOP + BOTTOM)
            ));
        }
        out.line(format_args!("</g>"));

        // Axis titles.
        out.line(format_args!(
            r#"<text class="x-label" x="{:.3}" y="{:.3}" text-anchor="middle">{}</text>"#,
            0.5 * (LEFT + RIGHT),
            BOTTOM + 40.0,
            esc(&self.x_label)
        ));
        let (ylx, yly) = (20.0, 0.5 * (TOP + BOTTOM));
        out.line(format_args!(
            r#"<text class="y-label" x="{ylx}" y="{yly:.3}" text-anchor="middle" transform="rotate(-90 {ylx} {yly:.3})">{}</text>"#,
            esc(&self.y_label)
        ));

        // Legend, right of the plot so it hides no point.
        out.line(format_args!(r#"<g class="legend">"#));
        for (i, s) in self.series.iter().enumerate() {
            let (colour, dash) = style(i);
            let y = TOP + 8.0 + LEGEND_STEP * i as f64;
            out.line(format_args!(
                r#"<line x1="{legend_x}" y1="{y:.3}" x2="{:.3}" y2="{y:.3}" stroke="{colour}" stroke-width="1.5"{dash}/>"#,
                legend_x + 22.0
            ));
            out.line(format_args!(
                r#"<circle cx="{:.3}" cy="{y:.3}" r="{RADIUS}" fill="{colour}" stroke="white" stroke-width="1"/>"#,
                legend_x + 11.0
            ));
            out.line(format_args!(
                r#"<text x="{:.3}" y="{:.3}">{}</text>"#,
                legend_x + 28.0,
                y + 4.0,
                esc(&s.name)
            ));
        }
        out.line(format_args!("</g>"));

        out.line(format_args!(
            r##"<g class="notes" font-size="{LABEL_FONT}" fill="#444444">"##
        ));
        for (i, note) in notes.iter().enumerate() {
            out.line(format_args!(
                r#"<text x="{LEFT}" y="{:.3}">{}</text>"#,
                notes_y + NOTE_STEP * i as f64,
                esc(note)
            ));
        }
        out.line(format_args!("</g>"));
        out.line(format_args!("</svg>"));
        out.0
    }

    /// Gridlines and tick labels at the decades, minor ticks between, and the plot's frame.
    fn write_axes(&self, out: &mut Out, axes: &Axes) {
        let decades = |lo: f64, hi: f64| {
            let step = ((hi - lo) / MAX_TICK_LABELS).ceil().max(1.0) as i64;
            (lo as i64..=hi as i64).filter(move |k| (k - lo as i64) % step == 0)
        };
        let xs: Vec<i64> = decades(axes.x_log_min, axes.x_log_max).collect();
        let ys: Vec<i64> = decades(axes.y_log_min, axes.y_log_max).collect();
        let x_at = |k: f64| axes.to_px(10f64.powf(k), 1.0).0;
        let y_at = |k: f64| axes.to_px(1.0, 10f64.powf(k)).1;

        out.line(format_args!(
            r##"<g class="grid" stroke="#dddddd" stroke-width="1">"##
        ));
        for &k in &xs {
            let x = x_at(k as f64);
            out.line(format_args!(
                r#"<line x1="{x:.3}" y1="{TOP}" x2="{x:.3}" y2="{BOTTOM}"/>"#
            ));
        }
        for &k in &ys {
            let y = y_at(k as f64);
            out.line(format_args!(
                r#"<line x1="{LEFT}" y1="{y:.3}" x2="{RIGHT}" y2="{y:.3}"/>"#
            ));
        }
        out.line(format_args!("</g>"));

        out.line(format_args!(
            r##"<g class="minor-ticks" stroke="#555555" stroke-width="1">"##
        ));
        if axes.x_log_max - axes.x_log_min <= MAX_DECADES_FOR_MINOR {
            for k in axes.x_log_min as i64..axes.x_log_max as i64 {
                for m in 2..=9 {
                    let x = x_at(k as f64 + (m as f64).log10());
                    out.line(format_args!(
                        r#"<line x1="{x:.3}" y1="{BOTTOM}" x2="{x:.3}" y2="{:.3}"/>"#,
                        BOTTOM - 3.0
                    ));
                }
            }
        }
        if axes.y_log_max - axes.y_log_min <= MAX_DECADES_FOR_MINOR {
            for k in axes.y_log_min as i64..axes.y_log_max as i64 {
                for m in 2..=9 {
                    let y = y_at(k as f64 + (m as f64).log10());
                    out.line(format_args!(
                        r#"<line x1="{LEFT}" y1="{y:.3}" x2="{:.3}" y2="{y:.3}"/>"#,
                        LEFT + 3.0
                    ));
                }
            }
        }
        out.line(format_args!("</g>"));

        out.line(format_args!(
            r##"<rect class="frame" x="{LEFT}" y="{TOP}" width="{}" height="{}" fill="none" stroke="#333333" stroke-width="1"/>"##,
            RIGHT - LEFT,
            BOTTOM - TOP
        ));

        out.line(format_args!(r##"<g class="ticks" fill="#333333">"##));
        for &k in &xs {
            out.line(format_args!(
                r#"<text x="{:.3}" y="{:.3}" text-anchor="middle">{}</text>"#,
                x_at(k as f64),
                BOTTOM + 18.0,
                decade_label(k)
            ));
        }
        for &k in &ys {
            out.line(format_args!(
                r#"<text x="{:.3}" y="{:.3}" text-anchor="end">{}</text>"#,
                LEFT - 6.0,
                y_at(k as f64) + 4.0,
                decade_label(k)
            ));
        }
        out.line(format_args!("</g>"));
    }
}

fn unescape(s: &str) -> Result<String, String> {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(amp) = rest.find('&') {
        out.push_str(&rest[..amp]);
        let after = &rest[amp + 1..];
        let semi = after
            .find(';')
            .ok_or_else(|| format!("unterminated entity in {s:?}"))?;
        let entity = &after[..semi];
        let c = match entity {
            "amp" => '&',
            "lt" => '<',
            "gt" => '>',
            "quot" => '"',
            "apos" => '\'',
            _ => {
                let code = if let Some(hex) = entity.strip_prefix("#x") {
                    u32::from_str_radix(hex, 16).ok()
                } else if let Some(dec) = entity.strip_prefix('#') {
                    dec.parse().ok()
                } else {
                    None
                };
                code.and_then(char::from_u32)
                    .ok_or_else(|| format!("unknown entity &{entity}; in {s:?}"))?
            }
        };
        out.push(c);
        rest = &after[semi + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// A start tag's name and attributes, values unescaped.
struct Tag<'a> {
    name: &'a str,
    attrs: Vec<(&'a str, String)>,
}

fn is_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | ':' | '.'))
}

impl<'a> Tag<'a> {
    /// `inner` is what lies between `<` and `>`.
    fn parse(inner: &'a str) -> Result<Self, String> {
        let body = inner.strip_suffix('/').unwrap_or(inner);
        let name_end = body
            .find(|c: char| c.is_ascii_whitespace())
            .unwrap_or(body.len());
        let name = &body[..name_end];
        if !is_name(name) {
            return Err(format!("bad tag name in <{inner}>"));
        }
        let mut attrs: Vec<(&str, String)> = Vec::new();
        let mut rest = &body[name_end..];
        loop {
            let trimmed = rest.trim_start();
            if trimmed.is_empty() {
                break;
            }
            if trimmed.len() == rest.len() {
                return Err(format!("attributes run together in <{inner}>"));
            }
            let eq = trimmed
                .find('=')
                .ok_or_else(|| format!("attribute without a value in <{inner}>"))?;
            let key = &trimmed[..eq];
            if !is_name(key) {
                return Err(format!("bad attribute name {key:?} in <{name}>"));
            }
            let quoted = trimmed[eq + 1..]
                .strip_prefix('"')
                .ok_or_else(|| format!("attribute {key} not in double quotes in <{name}>"))?;
            let end = quoted
                .find('"')
                .ok_or_else(|| format!("unterminated attribute {key} in <{name}>"))?;
            if attrs.iter().any(|(k, _)| *k == key) {
                return Err(format!("attribute {key} twice in <{name}>"));
            }
            attrs.push((key, unescape(&quoted[..end])?));
            rest = &quoted[end + 1..];
        }
        Ok(Tag { name, attrs })
    }

    fn get(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.as_str())
    }

    fn req(&self, key: &str) -> Result<&str, String> {
        self.get(key)
            .ok_or_else(|| format!("<{}> without {key}", self.name))
    }

    fn finite(&self, key: &str) -> Result<f64, String> {
        let v = self.req(key)?;
        match v.parse::<f64>() {
            Ok(f) if f.is_finite() => Ok(f),
            _ => Err(format!(
                "<{}> {key}={v:?} is not a finite number",
                self.name
            )),
        }
    }
}

/// Reads back the axes and every plotted point (in document order) from an SVG written by
/// `Chart::to_svg`. Not a general SVG parser: it knows what `to_svg` writes and refuses
/// anything malformed in it.
pub fn read_svg(svg: &str) -> Result<(Axes, Vec<PlottedPoint>), String> {
    let doc = svg.trim();
    if !doc.starts_with("<svg") && !doc.starts_with("<?xml") {
        return Err("not an SVG: it does not start with <svg or <?xml".into());
    }
    if !doc.ends_with("</svg>") {
        return Err("truncated SVG: it does not end with </svg>".into());
    }
    let mut axes = None;
    let mut points = Vec::new();
    let mut rest = doc;
    while let Some(open) = rest.find('<') {
        let after = &rest[open + 1..];
        let close = after
            .find('>')
            .ok_or_else(|| format!("unterminated tag at byte {}", doc.len() - after.len() - 1))?;
        let inner = &after[..close];
        rest = &after[close + 1..];
        if inner.starts_with(['/', '?', '!']) {
            continue;
        }
        let tag = Tag::parse(inner)?;
        match tag.name {
            "g" if tag.get("id") == Some("plot") => {
                if axes.is_some() {
                    return Err("two <g id=\"plot\"> elements".into());
                }
                let a = Axes {
                    x_log_min: tag.finite("data-x-log-min")?,
                    x_log_max: tag.finite("data-x-log-max")?,
                    y_log_min: tag.finite("data-y-log-min")?,
                    y_log_max: tag.finite("data-y-log-max")?,
                    left: tag.finite("data-left")?,
                    right: tag.finite("data-right")?,
                    top: tag.finite("data-top")?,
                    bottom: tag.finite("data-bottom")?,
                };
                if !(a.x_log_max > a.x_log_min
                    && a.y_log_max > a.y_log_min
                    && a.right > a.left
                    && a.bottom > a.top)
                {
                    return Err(format!("empty or inverted axes: {a:?}"));
                }
                axes = Some(a);
            }
            "circle" if tag.get("class") == Some("point") => {
                let x = tag.finite("data-x")?;
                let y = tag.finite("data-y")?;
                if x <= 0.0 || y <= 0.0 {
                    return Err(format!("point ({x}, {y}) drawn on a log axis"));
                }
                points.push(PlottedPoint {
                    series: tag.req("data-series")?.to_string(),
                    run_id: tag.req("data-run")?.to_string(),
                    label: tag.req("data-label")?.to_string(),
                    x,
                    y,
                    cx: tag.finite("cx")?,
                    cy: tag.finite("cy")?,
                });
            }
            _ => {}
        }
    }
    let axes = axes.ok_or("no <g id=\"plot\"> carrying the axes")?;
    Ok((axes, points))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f64, y: f64, label: &str, run_id: &str) -> Point {
        Point {
            x,
            y,
            label: label.into(),
            run_id: run_id.into(),
        }
    }

    fn chart(series: Vec<Series>) -> Chart {
        Chart {
            title: "cornell-box".into(),
            x_label: "GPU time (ms)".into(),
            y_label: "relMSE".into(),
            series,
        }
    }

    fn sample() -> Chart {
        let ir = (0..5)
            .map(|i| {
                let vpls = 16u32 << (2 * i);
                let ms = 0.8 * f64::from(vpls).powf(0.9);
                let rel = 2.0 / f64::from(vpls).sqrt();
                point(
                    ms,
                    rel,
                    &format!("vpls={vpls} frames=4"),
                    &format!("ir-{i}"),
                )
            })
            .collect();
        let pt = (0..4)
            .map(|i| {
                let spp = 1u32 << (2 * i);
                let ms = 3.0 * f64::from(spp);
                let rel = 0.9 / f64::from(spp);
                point(ms, rel, &format!("spp={spp}"), &format!("pt-{i}"))
            })
            .chain([point(0.0, 0.5, "spp=0", "pt-broken")])
            .collect();
        let rt = (0..3)
            .map(|i| {
                let spp = 1u32 << i;
                point(
                    20.0 * f64::from(spp),
                    0.02 / f64::from(spp),
                    &format!("spp={spp} rays=many"),
                    &format!("rt-{i}"),
                )
            })
            .chain([point(900.0, 0.0, "reference", "rt-ref")])
            .collect();
        chart(vec![
            Series {
                name: "instant radiosity".into(),
                points: ir,
            },
            Series {
                name: "path tracing".into(),
                points: pt,
            },
            Series {
                name: "ris <restir>".into(),
                points: rt,
            },
        ])
    }

    fn count(s: &str, pat: &str) -> usize {
        s.matches(pat).count()
    }

    fn assert_well_formed(svg: &str) {
        assert!(svg.starts_with("<svg"), "{svg}");
        assert!(svg.trim_end().ends_with("</svg>"));
        assert_eq!(count(svg, "<svg"), 1);
        assert_eq!(count(svg, "</svg>"), 1);
        assert_eq!(count(svg, "<g ") + count(svg, "<g>"), count(svg, "</g>"));
        assert_eq!(
            count(svg, "<text ") + count(svg, "<text>"),
            count(svg, "</text>")
        );
        assert_eq!(count(svg, "<title>"), count(svg, "</title>"));
        assert!(!svg.contains("<script"));
        assert!(!svg.contains("href"));
    }

    #[test]
    fn round_trip_every_point_comes_back() {
        let chart = sample();
        let svg = chart.to_svg();
        let (axes, plotted) = read_svg(&svg).unwrap();
        let expected: Vec<(&Series, &Point)> = chart
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(move |p| (s, p)))
            .filter(|(_, p)| chartable(p))
            .collect();
        assert_eq!(plotted.len(), expected.len());
        for (s, p) in expected {
            let got = plotted
                .iter()
                .find(|q| q.series == s.name && q.run_id == p.run_id)
                .unwrap_or_else(|| panic!("{} missing", p.run_id));
            assert_eq!(got.x.to_bits(), p.x.to_bits());
            assert_eq!(got.y.to_bits(), p.y.to_bits());
            assert_eq!(got.label, p.label);
            let (cx, cy) = axes.to_px(p.x, p.y);
            assert!((got.cx - cx).abs() < 1e-3, "{} {cx}", got.cx);
            assert!((got.cy - cy).abs() < 1e-3, "{} {cy}", got.cy);
            assert!(got.cx >= axes.left && got.cx <= axes.right);
            assert!(got.cy >= axes.top && got.cy <= axes.bottom);
        }
    }

    #[test]
    fn axes_are_the_decades_enclosing_the_data() {
        let svg = chart(vec![Series {
            name: "a".into(),
            points: vec![point(0.35, 0.004, "", "a"), point(120.0, 0.2, "", "b")],
        }])
        .to_svg();
        let (axes, _) = read_svg(&svg).unwrap();
        assert_eq!(
            (
                axes.x_log_min,
                axes.x_log_max,
                axes.y_log_min,
                axes.y_log_max
            ),
            (-1.0, 3.0, -3.0, 0.0)
        );
        for tick in ["0.1", "1", "10", "100", "1000", "0.001", "0.01"] {
            assert!(svg.contains(&format!(">{tick}</text>")), "tick {tick}");
        }
    }

    #[test]
    fn decade_labels_are_short() {
        let labels: Vec<String> = (-5..=5).map(decade_label).collect();
        assert_eq!(
            labels,
            ["1e-5", "1e-4", "0.001", "0.01", "0.1", "1", "10", "100", "1000", "10000", "1e5"]
        );
    }

    #[test]
    fn markup_in_text_is_escaped_and_read_back() {
        let nasty = r#"<&">' vpls=64"#;
        let mut c = chart(vec![Series {
            name: "m<&\">'".into(),
            points: vec![point(2.0, 0.1, nasty, "run<&\">'")],
        }]);
        c.title = "t<&\">'".into();
        c.y_label = "y <&>".into();
        let svg = c.to_svg();
        assert!(!svg.contains(nasty));
        assert!(!svg.contains("<&"));
        assert!(svg.contains("&lt;&amp;&quot;&gt;&apos;"));
        assert_well_formed(&svg);
        let (_, plotted) = read_svg(&svg).unwrap();
        assert_eq!(plotted.len(), 1);
        assert_eq!(plotted[0].label, nasty);
        assert_eq!(plotted[0].series, "m<&\">'");
        assert_eq!(plotted[0].run_id, "run<&\">'");
    }

    #[test]
    fn non_positive_and_non_finite_points_are_noted_not_drawn() {
        let svg = chart(vec![Series {
            name: "pt".into(),
            points: vec![
                point(1.0, 0.1, "ok", "good"),
                point(2.0, 0.0, "zero", "zero-y"),
                point(3.0, f64::NAN, "nan", "nan-y"),
                point(-1.0, 0.1, "neg", "neg-x"),
                point(f64::INFINITY, 0.1, "inf", "inf-x"),
            ],
        }])
        .to_svg();
        let (_, plotted) = read_svg(&svg).unwrap();
        assert_eq!(plotted.len(), 1);
        assert_eq!(plotted[0].run_id, "good");
        assert!(
            svg.contains("not charted: zero-y (pt zero; relMSE 0)"),
            "{svg}"
        );
        assert!(svg.contains("not charted: nan-y (pt nan; relMSE NaN)"));
        assert!(svg.contains("not charted: neg-x (pt neg; GPU time (ms) -1)"));
        assert!(svg.contains("not charted: inf-x (pt inf; GPU time (ms) inf)"));
        assert!(!svg.contains("no data"));
        assert_well_formed(&svg);
    }

    #[test]
    fn no_chartable_point_still_gives_an_svg_saying_no_data() {
        for series in [
            vec![],
            vec![Series {
                name: "pt".into(),
                points: vec![point(1.0, 0.0, "spp=1", "only")],
            }],
        ] {
            let svg = chart(series).to_svg();
            assert_well_formed(&svg);
            assert!(svg.contains("no data"));
            let (axes, plotted) = read_svg(&svg).unwrap();
            assert!(plotted.is_empty());
            assert_eq!(axes.x_log_max - axes.x_log_min, 1.0);
        }
    }

    #[test]
    fn single_point_gets_a_one_decade_axis() {
        for (x, y) in [(5.0, 0.03), (100.0, 1.0)] {
            let svg = chart(vec![Series {
                name: "ir".into(),
                points: vec![point(x, y, "vpls=64", "one")],
            }])
            .to_svg();
            let (axes, plotted) = read_svg(&svg).unwrap();
            assert_eq!(axes.x_log_max - axes.x_log_min, 1.0);
            assert_eq!(axes.y_log_max - axes.y_log_min, 1.0);
            assert!(axes.x_log_min <= x.log10() && x.log10() <= axes.x_log_max);
            assert!(axes.y_log_min <= y.log10() && y.log10() <= axes.y_log_max);
            assert_eq!(plotted.len(), 1);
            assert!(!svg.contains("<polyline"));
        }
    }

    #[test]
    fn same_x_on_two_series() {
        let svg = chart(vec![
            Series {
                name: "a".into(),
                points: vec![
                    point(10.0, 0.1, "n=1", "a1"),
                    point(20.0, 0.05, "n=2", "a2"),
                ],
            },
            Series {
                name: "b".into(),
                points: vec![point(10.0, 0.3, "n=1", "b1"), point(10.0, 0.2, "n=2", "b2")],
            },
        ])
        .to_svg();
        let (_, plotted) = read_svg(&svg).unwrap();
        assert_eq!(plotted.len(), 4);
        let at = |run: &str| plotted.iter().find(|p| p.run_id == run).unwrap().clone();
        assert_eq!(at("a1").cx, at("b1").cx);
        assert_eq!(at("b1").cx, at("b2").cx);
        assert_eq!(at("a1").series, "a");
        assert_eq!(at("b1").series, "b");
        assert!(at("b1").cy < at("b2").cy, "larger relMSE is higher up");
        assert_eq!(count(&svg, "<polyline"), 2);
    }

    #[test]
    fn points_join_in_order_of_x() {
        let svg = chart(vec![Series {
            name: "a".into(),
            points: vec![
                point(100.0, 0.01, "", "c"),
                point(1.0, 1.0, "", "a"),
                point(10.0, 0.1, "", "b"),
            ],
        }])
        .to_svg();
        let (axes, plotted) = read_svg(&svg).unwrap();
        let runs: Vec<&str> = plotted.iter().map(|p| p.run_id.as_str()).collect();
        assert_eq!(runs, ["a", "b", "c"]);
        let (x0, _) = axes.to_px(1.0, 1.0);
        let line = svg.lines().find(|l| l.starts_with("<polyline")).unwrap();
        assert!(line.contains(&format!("points=\"{x0:.3},")), "{line}");
    }

    #[test]
    fn output_is_well_formed() {
        let svg = sample().to_svg();
        assert_well_formed(&svg);
        for colour in &PALETTE[..3] {
            assert!(svg.contains(colour));
        }
        assert!(svg.contains(">instant radiosity</text>"), "legend");
    }

    #[test]
    fn read_svg_refuses_malformed_input() {
        let svg = sample().to_svg();
        assert!(read_svg("").is_err());
        assert!(read_svg("<html></html>").is_err());
        assert!(read_svg(&svg[..svg.len() / 2]).is_err());
        let no_axes = svg.replace("id=\"plot\"", "id=\"other\"");
        assert!(read_svg(&no_axes).unwrap_err().contains("axes"));
        let bad_x = svg.replacen("data-x=\"", "data-x=\"oops", 1);
        assert!(read_svg(&bad_x).unwrap_err().contains("data-x"));
        let no_run = svg.replacen("data-run=", "data-rnu=", 1);
        assert!(read_svg(&no_run).unwrap_err().contains("data-run"));
        let bad_entity = svg.replacen("data-label=\"", "data-label=\"&bogus;", 1);
        assert!(read_svg(&bad_entity).unwrap_err().contains("entity"));
        let unquoted = svg.replacen("cx=\"", "cx=", 1);
        assert!(read_svg(&unquoted).is_err());
    }

    #[test]
    fn crowded_labels_are_left_out_not_overprinted() {
        let series = (0..5)
            .map(|i| Series {
                name: format!("m{i}"),
                points: vec![point(3.0, 0.2, "vpls=64 frames=4", &format!("r{i}"))],
            })
            .collect();
        let svg = chart(series).to_svg();
        let (_, plotted) = read_svg(&svg).unwrap();
        assert_eq!(plotted.len(), 5, "every point is still drawn");
        let shown = count(&svg, ">vpls=64 frames=4</text>");
        assert!((1..5).contains(&shown), "{shown} labels shown");
        assert!(svg.contains(&format!("{} point label(s) left out", 5 - shown)));
        assert_eq!(count(&svg, "<title>m"), 5, "each point keeps its tooltip");
    }

    /// Writes the sample chart to /tmp/chart-sample.svg to look at.
    #[test]
    #[ignore]
    fn write_sample_chart() {
        std::fs::write("/tmp/chart-sample.svg", sample().to_svg()).unwrap();
    }
}
