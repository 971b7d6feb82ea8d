//! Writes a chart as SVG: the plot with its gridlines, ticks and frame, one group of line and
//! circles per series (each circle carrying its point's values as data attributes, which
//! `read_svg` reads back), the labels `layout` placed, the axis titles, the legend and the
//! notes on points left out. Text is escaped for XML.

use std::fmt::Write as _;

use super::layout::{
    decade_label, decade_range, labelled_decades, place_labels, text_width, Rect, BOTTOM, FONT,
    HEIGHT, LABEL_FONT, LEFT, LEGEND_STEP, MAX_DECADES_FOR_MINOR, NOTE_STEP, RADIUS, RIGHT, TOP,
    WIDTH,
};
use super::{chartable, Axes, Chart, Point};

/// Okabe & Ito's colour-blind-safe palette, yellow last: it is the hardest to see on white.
const PALETTE: [&str; 8] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442",
];

/// Series i's colour, and past the palette's length a dash pattern so no two series look alike.
pub(super) fn style(i: usize) -> (&'static str, &'static str) {
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

/// `s` as XML text or a double-quoted attribute value.
pub(super) fn esc(s: &str) -> String {
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

/// A point's spread bar (low, high) where both ends can sit on the log axis.
fn bar(p: &Point) -> Option<(f64, f64)> {
    p.y_range
        .filter(|&(lo, hi)| lo > 0.0 && hi >= lo && hi.is_finite())
}

impl Chart {
    /// The chart as a self-contained SVG document.
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
        let (y_log_min, y_log_max) = decade_range(charted.iter().flatten().flat_map(|p| {
            let (lo, hi) = bar(p).unwrap_or((p.y, p.y));
            [p.y, lo, hi]
        }));
        // The floor where it falls on the points' axis; else a note (a reference far more
        // converged than the runs would stretch the axis over empty decades).
        let floor_value = self.floor.filter(|f| f.is_finite() && *f > 0.0 && any);
        let floor = floor_value.filter(|f| (y_log_min..=y_log_max).contains(&f.log10()));
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
        if let (Some(f), None) = (floor_value, floor) {
            notes.push(format!(
                "the reference's own relMSE, {f:.2e}, is {} the plotted range",
                if f.log10() < y_log_min {
                    "below"
                } else {
                    "above"
                }
            ));
        }
        notes.extend(self.notes.iter().cloned());

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

        // The reference's noise floor: a dotted grey line with its label at the right.
        if let Some(f) = floor {
            let (_, y) = axes.to_px(10f64.powf(axes.x_log_min), f);
            out.line(format_args!(
                r##"<g class="floor" data-y="{f}"><line x1="{LEFT:.3}" y1="{y:.3}" x2="{RIGHT:.3}" y2="{y:.3}" stroke="#888888" stroke-width="1" stroke-dasharray="2,3"/><text x="{:.3}" y="{:.3}" text-anchor="end" font-size="{LABEL_FONT}" fill="#666666">reference's own relMSE {f:.2e}</text></g>"##,
                RIGHT - 4.0,
                y - 4.0
            ));
        }

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
                if let Some((lo, hi)) = bar(p) {
                    let (_, y_lo) = axes.to_px(p.x, lo);
                    let (_, y_hi) = axes.to_px(p.x, hi);
                    out.line(format_args!(
                        r#"<line class="spread" x1="{cx:.3}" y1="{y_hi:.3}" x2="{cx:.3}" y2="{y_lo:.3}" stroke-width="1.5" data-run="{}" data-low="{lo}" data-high="{hi}"/>"#,
                        esc(&p.run_id),
                    ));
                }
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
        let xs = labelled_decades(axes.x_log_min, axes.x_log_max);
        let ys = labelled_decades(axes.y_log_min, axes.y_log_max);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::chart::fixtures::{assert_well_formed, chart, count, point, sample};
    use crate::bench::chart::{read_svg, Series};

    /// The reference's noise floor is a line across the plot at its value where it falls on
    /// the points' axis, else a note; a chart without points draws none.
    #[test]
    fn the_noise_floor_is_a_line_at_its_value() {
        let mut c = chart(vec![Series {
            name: "pt".into(),
            points: vec![point(2.0, 0.1, "a", "a"), point(8.0, 0.02, "b", "b")],
        }]);
        c.floor = Some(0.05);
        let svg = c.to_svg();
        assert_well_formed(&svg);
        assert!(svg.contains(r#"<g class="floor" data-y="0.05">"#), "{svg}");
        assert!(svg.contains("reference's own relMSE 5.00e-2"));
        let (axes, plotted) = read_svg(&svg).unwrap();
        assert_eq!(plotted.len(), 2);
        // Far below the points: a note, the axis left as the points set it.
        c.floor = Some(1e-7);
        let far = c.to_svg();
        assert!(!far.contains("class=\"floor\""));
        assert!(far.contains("1.00e-7, is below the plotted range"), "{far}");
        assert_eq!(read_svg(&far).unwrap().0, axes);
        let empty = Chart {
            floor: Some(1e-4),
            ..chart(vec![])
        };
        assert!(!empty.to_svg().contains("class=\"floor\""));
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

    /// A point that is a mean over seeds carries a bar from the lowest to the highest value,
    /// drawn at the point's x, the axes widened to hold it; a bar whose low end cannot sit on
    /// the log axis is left out, the point kept.
    #[test]
    fn a_mean_over_seeds_is_drawn_with_its_range() {
        let mut a = point(10.0, 0.02, "t=2s", "a");
        a.y_range = Some((0.005, 0.2));
        let mut b = point(20.0, 0.01, "t=8s", "b");
        b.y_range = Some((0.0, 0.03));
        let svg = chart(vec![Series {
            name: "bir".into(),
            points: vec![a, b],
        }])
        .to_svg();
        let (axes, plotted) = read_svg(&svg).unwrap();
        assert_eq!(plotted.len(), 2);
        let at = |run: &str| plotted.iter().find(|p| p.run_id == run).unwrap().clone();
        let ((low, high), (top, bottom)) = at("a").bar.expect("a's bar");
        assert_eq!((low, high), (0.005, 0.2));
        let (_, y_low) = axes.to_px(10.0, 0.005);
        let (_, y_high) = axes.to_px(10.0, 0.2);
        assert!((top - y_high).abs() < 1e-3 && (bottom - y_low).abs() < 1e-3);
        assert!(
            top < at("a").cy && at("a").cy < bottom,
            "the bar passes through the point"
        );
        assert!(axes.y_log_min <= 0.005f64.log10() && 0.2f64.log10() <= axes.y_log_max);
        assert_eq!(at("b").bar, None);
        assert_eq!(count(&svg, "class=\"spread\""), 1);
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
    #[ignore]
    fn write_sample_chart() {
        std::fs::write("/tmp/chart-sample.svg", sample().to_svg()).unwrap();
    }
}
