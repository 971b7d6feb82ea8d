//! Where things go on a chart: the canvas and plot sizes, the whole decades the axes span and
//! which of them are labelled, and the point labels, placed so they neither cover one another
//! nor the lines. Sizes are in the SVG's pixels; text widths are estimated (no fonts).

/// The canvas at least (it widens for a long legend and grows for notes), and the plot inside
/// it: pixels from the canvas's top left.
pub(super) const WIDTH: f64 = 720.0;
pub(super) const HEIGHT: f64 = 480.0;
pub(super) const LEFT: f64 = 72.0;
pub(super) const TOP: f64 = 44.0;
pub(super) const RIGHT: f64 = 540.0;
pub(super) const BOTTOM: f64 = 400.0;
/// Font sizes (text, point labels), circle radius and the spacing of notes and legend rows.
pub(super) const FONT: f64 = 12.0;
pub(super) const LABEL_FONT: f64 = 11.0;
pub(super) const RADIUS: f64 = 4.0;
pub(super) const NOTE_STEP: f64 = 15.0;
pub(super) const LEGEND_STEP: f64 = 18.0;
/// Tick labels per axis at most; more decades than this label every second (third...) one.
const MAX_TICK_LABELS: f64 = 10.0;
/// Minor ticks (2..9 x 10^k) only while a decade is wide enough to tell them apart.
pub(super) const MAX_DECADES_FOR_MINOR: f64 = 8.0;

/// Whole decades enclosing the values, at least one wide; one decade [1, 10] when empty.
pub(super) fn decade_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
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
pub(super) fn decade_label(k: i64) -> String {
    match k {
        -3..=-1 => format!("0.{}1", "0".repeat((-k - 1) as usize)),
        0..=4 => format!("1{}", "0".repeat(k as usize)),
        _ => format!("1e{k}"),
    }
}

/// The decades from 10^lo to 10^hi that get a gridline and a tick label: every one, or every
/// second (third...) one where there are more than MAX_TICK_LABELS.
pub(super) fn labelled_decades(lo: f64, hi: f64) -> Vec<i64> {
    let step = ((hi - lo) / MAX_TICK_LABELS).ceil().max(1.0) as i64;
    (lo as i64..=hi as i64)
        .filter(|k| (k - lo as i64) % step == 0)
        .collect()
}

/// Rendered width is not known without fonts; 0.6 em per character over-estimates typical
/// sans-serif text, so labels placed apart by this stay apart.
pub(super) fn text_width(s: &str, font: f64) -> f64 {
    s.chars().count() as f64 * font * 0.6
}

/// An axis-aligned box in pixels, y down.
#[derive(Clone, Copy)]
pub(super) struct Rect {
    pub(super) x0: f64,
    pub(super) y0: f64,
    pub(super) x1: f64,
    pub(super) y1: f64,
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
pub(super) struct Placed {
    pub(super) x: f64,
    pub(super) y: f64,
    pub(super) anchor: &'static str,
    pub(super) shown: bool,
}

/// Greedy label placement: each label takes the candidate spot (right first) that overlaps the
/// labels already placed, the circles and the lines least, and stays inside the plot (outside it
/// lie the tick labels, the title and the legend). A label that would come within 3 px of
/// another on every spot is left out: overprinted text helps no one, and the circle's
/// `<title>` still holds it.
pub(super) fn place_labels(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::chart::fixtures::{chart, count, point};
    use crate::bench::chart::{read_svg, Series};

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
}
