//! Log-log charts as SVG for `irad bench suite`: per scene, relMSE (y) against GPU time in ms
//! (x), one line per method, each of its budgets a labelled point. `read_svg` reads the drawn
//! points and the axis mapping back, so tests check what was drawn, not how.
//!
//! std only; the SVG is self-contained (no fonts, scripts or files beyond itself). A point that
//! cannot sit on a log axis (zero, negative, NaN, infinite) is listed in a note under the chart
//! rather than dropped silently.
//!
//! `frames` draws a suite's per-frame chart (a value over animation frames, linear x).
//!
//! One job per file: this one holds the chart's types; `layout` places things (the decades
//! the axes span, the tick labels, the point labels, text widths); `svg` writes the chart
//! (`Chart::to_svg`); `read` reads an SVG it wrote back (`read_svg`, for tests).

mod frames;
mod layout;
mod read;
mod svg;

pub use frames::{read_frames_svg, FrameChart, FrameSeries};
pub use read::read_svg;

/// One measured run: `x` and `y` go on log axes; `label` is its budget as printed beside the
/// point ("vpls=64 frames=4"); `run_id` ties the point to the run's record.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    /// The spread behind `y` where it is a mean over seeds: the lowest and highest of the
    /// values averaged, drawn as a vertical bar through the point (left out where either end
    /// cannot sit on the log axis).
    pub y_range: Option<(f64, f64)>,
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
    /// Lines printed under the chart after its own notes (on points it could not chart):
    /// what the chart leaves out and why.
    pub notes: Vec<String>,
    /// A horizontal line across the plot at this y, where positive and finite: the reference's
    /// own relMSE, below which no run's figure can be read (its noise floor).
    pub floor: Option<f64>,
}

/// A point as drawn, read back from an SVG written by `to_svg`.
#[derive(Debug, Clone, PartialEq)]
pub struct PlottedPoint {
    pub series: String,
    pub run_id: String,
    pub label: String,
    pub x: f64,
    pub y: f64,
    /// The bar drawn through the point, as values (low, high) and pixel rows (top, bottom
    /// end: `cy` of high, of low).
    pub bar: Option<((f64, f64), (f64, f64))>,
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

/// Whether a point can sit on the log axes: both values positive and finite. Others are
/// listed in a note under the chart.
fn chartable(p: &Point) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.x > 0.0 && p.y > 0.0
}

/// Charts the tests of `svg` and `read` draw.
#[cfg(test)]
mod fixtures {
    use super::{Chart, Point, Series};

    pub(super) fn point(x: f64, y: f64, label: &str, run_id: &str) -> Point {
        Point {
            x,
            y,
            y_range: None,
            label: label.into(),
            run_id: run_id.into(),
        }
    }

    pub(super) fn chart(series: Vec<Series>) -> Chart {
        Chart {
            title: "cornell-box".into(),
            x_label: "GPU time (ms)".into(),
            y_label: "relMSE".into(),
            series,
            notes: Vec::new(),
            floor: None,
        }
    }

    pub(super) fn sample() -> Chart {
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

    pub(super) fn count(s: &str, pat: &str) -> usize {
        s.matches(pat).count()
    }

    pub(super) fn assert_well_formed(svg: &str) {
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
}
