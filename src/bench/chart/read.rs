//! Reads a chart back from the SVG `Chart::to_svg` wrote: the axis mapping and every drawn
//! point, from the data attributes it puts on them. For tests (unit tests here and in `svg`,
//! and tests/bench_suite.rs), so they check what was drawn rather than how.

use super::{Axes, PlottedPoint};

/// `s` with XML's five named entities and numeric character references replaced.
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
/// anything malformed in it. For tests (here and in tests/), which check what was drawn;
/// irad itself never reads a chart.
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
    // Spread bars as read, each written just before its point's circle: run, values (low,
    // high), rows (top, bottom).
    type Bar = (String, (f64, f64), (f64, f64));
    let mut bars: Vec<Bar> = Vec::new();
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
            "line" if tag.get("class") == Some("spread") => {
                let (low, high) = (tag.finite("data-low")?, tag.finite("data-high")?);
                let rows = (tag.finite("y1")?, tag.finite("y2")?);
                bars.push((tag.req("data-run")?.to_string(), (low, high), rows));
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
                    bar: bars
                        .iter()
                        .rev()
                        .find(|b| Some(b.0.as_str()) == tag.get("data-run"))
                        .map(|b| (b.1, b.2)),
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
    use crate::bench::chart::fixtures::sample;
    use crate::bench::chart::{chartable, Point, Series};

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
}
