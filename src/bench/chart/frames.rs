//! A value over animation frames as SVG, for a suite's frame-time runs: frame number on a
//! linear x axis, the value (relMSE) on a log y axis, one line per series (a method at one
//! frame budget). Each circle carries its series, frame and value as data attributes
//! (`data-series`, `data-frame`, `data-y`), which `read_frames_svg` reads back for tests. A
//! value that cannot sit on the log axis is left out of its line and counted in a note.

use std::fmt::Write as _;

use super::layout::{
    decade_label, decade_range, labelled_decades, text_width, FONT, LEGEND_STEP, RADIUS,
};
use super::svg::{esc, style};

/// One line: a name and (frame, value) points.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameSeries {
    pub name: String,
    pub points: Vec<(u32, f64)>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct FrameChart {
    pub title: String,
    pub y_label: String,
    pub series: Vec<FrameSeries>,
}

/// The canvas's width at least (it widens for a long legend).
const MIN_WIDTH: f64 = 720.0;
const LEFT: f64 = 72.0;
const TOP: f64 = 44.0;
const RIGHT: f64 = 500.0;
const BOTTOM: f64 = 400.0;

impl FrameChart {
    pub fn to_svg(&self) -> String {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        let all = || self.series.iter().flat_map(|s| &s.points);
        let (y0, y1) = decade_range(all().map(|p| p.1).filter(|v| ok(*v)));
        let (f0, f1) = all().fold((u32::MAX, 0), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
        let (f0, f1) = if f0 > f1 {
            (0, 1)
        } else {
            (f0, f1.max(f0 + 1))
        };
        let x_at = |f: u32| LEFT + (RIGHT - LEFT) * f64::from(f - f0) / f64::from(f1 - f0);
        let y_at = |v: f64| BOTTOM - (BOTTOM - TOP) * (v.log10() - y0) / (y1 - y0);
        let legend_rows = self.series.len() as f64;
        let legend = self
            .series
            .iter()
            .map(|s| text_width(&s.name, FONT))
            .fold(0.0, f64::max);
        let width = MIN_WIDTH.max(RIGHT + 42.0 + legend + 8.0);
        let height = (BOTTOM + 60.0).max(TOP + 20.0 + legend_rows * LEGEND_STEP);
        let mut s = String::new();
        let mut line = |t: String| {
            s.push_str(&t);
            s.push('\n');
        };
        line(format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="{FONT}">"#
        ));
        line(format!(
            r#"<rect width="{width}" height="{height}" fill="white"/>"#
        ));
        line(format!(
            r#"<text x="{}" y="24" text-anchor="middle" font-size="14">{}</text>"#,
            (LEFT + RIGHT) / 2.0,
            esc(&self.title)
        ));
        line(format!(
            r#"<g id="plot" data-frame-min="{f0}" data-frame-max="{f1}" data-y-log-min="{y0}" data-y-log-max="{y1}">"#
        ));
        for k in labelled_decades(y0, y1) {
            let y = y_at(10f64.powi(k as i32));
            line(format!(
                r##"<line x1="{LEFT}" y1="{y:.2}" x2="{RIGHT}" y2="{y:.2}" stroke="#ddd"/>"##
            ));
            line(format!(
                r#"<text x="{}" y="{:.2}" text-anchor="end">{}</text>"#,
                LEFT - 6.0,
                y + 4.0,
                decade_label(k)
            ));
        }
        // Frame ticks: every frame up to 12, else about 10 evenly.
        let step = ((f1 - f0) / 10).max(1);
        let mut f = f0;
        while f <= f1 {
            let x = x_at(f);
            line(format!(
                r##"<line x1="{x:.2}" y1="{BOTTOM}" x2="{x:.2}" y2="{}" stroke="#000"/>"##,
                BOTTOM + 5.0
            ));
            line(format!(
                r#"<text x="{x:.2}" y="{}" text-anchor="middle">{f}</text>"#,
                BOTTOM + 18.0
            ));
            f += step;
        }
        line(format!(
            r##"<rect x="{LEFT}" y="{TOP}" width="{}" height="{}" fill="none" stroke="#000"/>"##,
            RIGHT - LEFT,
            BOTTOM - TOP
        ));
        let mut left_out = 0;
        for (i, series) in self.series.iter().enumerate() {
            let (colour, dash) = style(i);
            let mut points: Vec<(u32, f64)> = series.points.clone();
            points.sort_by_key(|p| p.0);
            left_out += points.iter().filter(|p| !ok(p.1)).count();
            points.retain(|p| ok(p.1));
            line(format!(
                r#"<g class="series" data-series="{}">"#,
                esc(&series.name)
            ));
            let path: Vec<String> = points
                .iter()
                .map(|&(f, v)| format!("{:.2},{:.2}", x_at(f), y_at(v)))
                .collect();
            if path.len() > 1 {
                line(format!(
                    r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>"#,
                    path.join(" ")
                ));
            }
            for &(f, v) in &points {
                line(format!(
                    r#"<circle cx="{:.2}" cy="{:.2}" r="{RADIUS}" fill="{colour}" data-series="{}" data-frame="{f}" data-y="{v}"/>"#,
                    x_at(f),
                    y_at(v),
                    esc(&series.name)
                ));
            }
            line("</g>".into());
            let ly = TOP + 10.0 + i as f64 * LEGEND_STEP;
            line(format!(
                r#"<line x1="{}" y1="{ly}" x2="{}" y2="{ly}" stroke="{colour}" stroke-width="2"{dash}/>"#,
                RIGHT + 16.0,
                RIGHT + 36.0
            ));
            line(format!(
                r#"<text x="{}" y="{}">{}</text>"#,
                RIGHT + 42.0,
                ly + 4.0,
                esc(&series.name)
            ));
        }
        line("</g>".into());
        line(format!(
            r#"<text x="{}" y="{}" text-anchor="middle">animation frame</text>"#,
            (LEFT + RIGHT) / 2.0,
            BOTTOM + 38.0
        ));
        line(format!(
            r#"<text x="16" y="{}" text-anchor="middle" transform="rotate(-90 16 {})">{}</text>"#,
            (TOP + BOTTOM) / 2.0,
            (TOP + BOTTOM) / 2.0,
            esc(&self.y_label)
        ));
        if left_out > 0 {
            line(format!(
                r#"<text x="{LEFT}" y="{}">{left_out} point(s) not positive and finite, left out</text>"#,
                BOTTOM + 54.0
            ));
        }
        line("</svg>".into());
        let _ = write!(s, "");
        s
    }
}

/// The points of an SVG `FrameChart::to_svg` wrote: (series, frame, value), in drawing order.
pub fn read_frames_svg(svg: &str) -> Vec<(String, u32, f64)> {
    let attr = |tag: &str, key: &str| -> Option<String> {
        let start = tag.find(&format!(" {key}=\""))? + key.len() + 3;
        let end = start + tag[start..].find('"')?;
        Some(tag[start..end].to_string())
    };
    svg.lines()
        .filter(|l| l.trim_start().starts_with("<circle"))
        .filter_map(|l| {
            Some((
                attr(l, "data-series")?
                    .replace("&lt;", "<")
                    .replace("&gt;", ">")
                    .replace("&quot;", "\"")
                    .replace("&apos;", "'")
                    .replace("&amp;", "&"),
                attr(l, "data-frame")?.parse().ok()?,
                attr(l, "data-y")?.parse().ok()?,
            ))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_chart_draws_each_finite_point_and_reads_back() {
        let chart = FrameChart {
            title: "cornell-circling <frames>".into(),
            y_label: "relMSE".into(),
            series: vec![
                FrameSeries {
                    name: "pt frame_ms=2".into(),
                    points: vec![(3, 0.2), (4, 0.1), (5, f64::NAN)],
                },
                FrameSeries {
                    name: "pt & co".into(),
                    points: vec![(3, 0.01), (4, 0.02), (5, 0.03)],
                },
            ],
        };
        let svg = chart.to_svg();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        let points = read_frames_svg(&svg);
        assert_eq!(points.len(), 5, "{points:?}");
        assert!(points.contains(&("pt & co".into(), 5, 0.03)));
        assert!(svg.contains("1 point(s) not positive and finite"));
        assert!(svg.contains("&lt;frames&gt;"));
    }
}
