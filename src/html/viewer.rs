//! The image viewer of every irad page (assets/report/viewer.js; docs/DESIGN.md "Looking at
//! results"): its data, one or more named images per frame, and its markup.
//!
//! The images reach the page as half floats (RGB, little-endian, base64): lossless enough for
//! exposure (11 bits of mantissa, a range to 65504), a third of the bytes of f32 and decoded by
//! a lookup table in the page, where an EXR decoder in JavaScript would need a library and its
//! licence. HDR-FLIP maps (src/image/flip.rs, a CPU port; a JavaScript one would be a second
//! copy to keep equal) are computed here against the viewer's reference and travel as one byte
//! a pixel (FLIP is in [0, 1]; 1/255 steps are finer than its colour ramp shows).

use std::fmt::Write as _;

use anyhow::Result;

use crate::image::flip::{self, DEFAULT_PIXELS_PER_DEGREE};
use crate::image::{metrics, preview, Image};

use super::{base64, escape, half_base64, json_string};

/// The viewer's script, shared by every page.
pub const VIEWER_JS: &str = include_str!("../../assets/report/viewer.js");

/// The most base64 one viewer's images may take in a page; past it they are embedded
/// box-filtered down by the smallest integer factor that fits (the page says so).
pub const VIEWER_BYTES: usize = 24 << 20;

/// A per-pixel HDR-FLIP map in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
}

/// One frame of a viewer (a still has one).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewerFrame {
    /// The frame's number, as the scrubber shows it (0 for a still).
    pub number: u32,
    /// One image per name of the viewer, in its order.
    pub images: Vec<Image>,
    /// Each image's HDR-FLIP map against the reference, where one was computed.
    pub flip: Vec<Option<FlipMap>>,
    /// The relMSE of the first image that is not the reference against it: the sequence's
    /// per-frame error plot.
    pub rel_mse: Option<f64>,
}

/// What one viewer shows: named images, frame by frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewerData {
    pub names: Vec<String>,
    /// The index of the reference among `names`, where there is one: B by default, and what
    /// FLIP maps and the error plot are against.
    pub reference: Option<usize>,
    /// Playback's frames a second.
    pub fps: f32,
    pub frames: Vec<ViewerFrame>,
}

impl ViewerData {
    /// A viewer of frames (each `(number, images in the order of names)`), with each image's
    /// FLIP map against the reference where `with_flip` and the relMSE of the first other image
    /// against it.
    pub fn new(
        names: Vec<String>,
        reference: Option<usize>,
        fps: f32,
        frames: Vec<(u32, Vec<Image>)>,
        with_flip: bool,
    ) -> Result<ViewerData> {
        let test = (0..names.len()).find(|&i| Some(i) != reference);
        let mut out = Vec::with_capacity(frames.len());
        for (number, images) in frames {
            assert_eq!(images.len(), names.len(), "an image per name");
            let mut flips = vec![None; images.len()];
            let mut rel_mse = None;
            if let Some(r) = reference {
                let reference_image = &images[r];
                for (i, image) in images.iter().enumerate() {
                    if i == r
                        || (image.width, image.height)
                            != (reference_image.width, reference_image.height)
                    {
                        continue;
                    }
                    if Some(i) == test {
                        rel_mse = metrics::compare(image, reference_image)
                            .ok()
                            .map(|m| m.rel_mse);
                    }
                    if with_flip {
                        // A non-finite image has no FLIP map (its NaN/Inf count says why).
                        if let Ok(f) =
                            flip::hdr_flip(reference_image, image, DEFAULT_PIXELS_PER_DEGREE)
                        {
                            flips[i] = Some(FlipMap {
                                width: f.width,
                                height: f.height,
                                values: f.error_map,
                            });
                        }
                    }
                }
            }
            out.push(ViewerFrame {
                number,
                images,
                flip: flips,
                rel_mse,
            });
        }
        Ok(ViewerData {
            names,
            reference,
            fps,
            frames: out,
        })
    }

    /// The smallest integer factor whose box filter brings the embedded images under
    /// VIEWER_BYTES (1 where they fit).
    pub fn factor(&self) -> u32 {
        // 8 base64 bytes a pixel for half RGB, 4/3 for a FLIP byte.
        let bytes: usize = self
            .frames
            .iter()
            .map(|f| {
                f.images.iter().map(|im| 8 * im.pixels.len()).sum::<usize>()
                    + f.flip
                        .iter()
                        .flatten()
                        .map(|m| m.values.len() * 4 / 3)
                        .sum::<usize>()
            })
            .sum();
        (1..)
            .find(|f: &usize| bytes / (f * f) <= VIEWER_BYTES)
            .expect("some factor fits") as u32
    }

    /// The viewer's data as the JSON object viewer.js reads, images box-filtered by `factor`.
    pub fn json(&self, factor: u32) -> String {
        let mut s = String::from("{\"names\":[");
        for (i, n) in self.names.iter().enumerate() {
            let _ = write!(s, "{}{}", if i > 0 { "," } else { "" }, json_string(n));
        }
        let _ = write!(
            s,
            "],\"reference\":{},\"fps\":{},\"factor\":{factor},\"frames\":[",
            match self.reference {
                Some(r) => json_string(&self.names[r]),
                None => "null".into(),
            },
            if self.fps.is_finite() && self.fps > 0.0 {
                self.fps
            } else {
                10.0
            }
        );
        for (k, frame) in self.frames.iter().enumerate() {
            let rel_mse = match frame.rel_mse {
                Some(e) if e.is_finite() => format!("{e:e}"),
                _ => "null".into(),
            };
            let _ = write!(
                s,
                "{}{{\"number\":{},\"relmse\":{rel_mse},\"images\":{{",
                if k > 0 { "," } else { "" },
                frame.number
            );
            for (i, (name, image)) in self.names.iter().zip(&frame.images).enumerate() {
                let image = scaled(image, factor);
                let _ = write!(
                    s,
                    "{}{}:{{\"width\":{},\"height\":{},\"rgb\":\"{}\"",
                    if i > 0 { "," } else { "" },
                    json_string(name),
                    image.width,
                    image.height,
                    half_base64(&image)
                );
                if let Some(map) = &frame.flip[i] {
                    let _ = write!(s, ",\"flip\":\"{}\"", flip_base64(map, factor));
                }
                s.push('}');
            }
            s.push_str("}}");
        }
        s + "]}"
    }
}

fn scaled(image: &Image, factor: u32) -> std::borrow::Cow<'_, Image> {
    match factor {
        0 | 1 => std::borrow::Cow::Borrowed(image),
        f => std::borrow::Cow::Owned(preview::downscale(image, f)),
    }
}

/// A FLIP map as one byte a pixel (round(255 v)), box-filtered by `factor`, in base64.
pub fn flip_base64(map: &FlipMap, factor: u32) -> String {
    let image = Image {
        width: map.width,
        height: map.height,
        pixels: map.values.iter().map(|&v| [v; 3]).collect(),
    };
    let image = scaled(&image, factor);
    let bytes: Vec<u8> = image
        .pixels
        .iter()
        .map(|p| (p[0].clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    base64(&bytes)
}

/// A viewer's controls and canvases; viewer.js finds them under `.viewer` and adds the
/// sequence's controls where there are frames.
pub const MARKUP: &str = r#"<div class="viewer">
 <div class="controls">A <select class="a"></select> B <select class="b"></select>
 <select class="mode"></select>
 exposure <input class="exposure" type="range" min="-8" max="8" step="0.5" value="0"><span class="exposure-value">+0.0 stops</span>
 tone <select class="tone"><option value="srgb">sRGB</option><option value="gamma22">gamma 2.2</option><option value="aces">ACES</option><option value="linear">linear</option></select>
 split <input class="split" type="range" min="0" max="100" value="50"> <button class="flip">flip (F)</button> <button class="fit">fit</button></div>
 <canvas class="view" width="640" height="480"></canvas><br><canvas class="bar" width="640" height="30"></canvas>
 <div class="note"></div>
 <div class="readout"></div>
</div>
"#;

/// The viewer's style; pages add their own.
pub const STYLE: &str = "body{font-family:sans-serif;margin:1em 2em}\
canvas.view{border:1px solid #888;cursor:crosshair;display:block}\
canvas.plot{border:1px solid #ccc;cursor:pointer;display:block}\
.viewer:focus{outline:2px solid #8ab}\
.viewer .note{color:#a40;min-height:1.2em;font-size:13px}\
.sequence{margin:4px 0}\
.readout{font-family:monospace;font-size:12px;min-height:1.2em}";

/// A page of one viewer: `title`, `intro` (HTML) and the viewer of `data`, which shows the
/// image named `a` against the reference (or the second image) first.
pub fn page(title: &str, intro: &str, data: &ViewerData) -> String {
    let factor = data.factor();
    let note = if factor > 1 {
        format!(
            "<p class=\"scaled\">The images are averaged over {factor}x{factor} pixel blocks, so \
             that the page stays under {} MB; the EXRs are full size.</p>\n",
            VIEWER_BYTES >> 20
        )
    } else {
        String::new()
    };
    format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{title}</title><style>{STYLE}</style></head><body>\n\
         <h1>{title}</h1>\n{intro}\n{note}<section id=\"viewer0\">{MARKUP}</section>\n\
         <script>{VIEWER_JS}</script>\n<script>const IRAD_DATA = {data};\n\
         const root = document.querySelector(\"#viewer0 .viewer\");\n\
         root.viewer = new IradViewer.Viewer(root, IRAD_DATA);</script>\n</body></html>\n",
        title = escape(title),
        data = data.json(factor),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(v: f32) -> Image {
        Image {
            width: 4,
            height: 2,
            pixels: vec![[v; 3]; 8],
        }
    }

    /// A sequence viewer's frames carry their numbers, each run's relMSE against the
    /// reference and FLIP maps of the images that are not the reference.
    #[test]
    fn frames_carry_their_numbers_errors_and_flip_maps() {
        let names = vec!["render".to_string(), "reference".to_string()];
        let frames = vec![
            (3, vec![image(1.5), image(1.0)]),
            (4, vec![image(1.0), image(1.0)]),
        ];
        let data = ViewerData::new(names, Some(1), 24.0, frames, true).unwrap();
        assert_eq!(
            data.frames[0].rel_mse.map(|e| (e * 1e4).round()),
            Some((0.25f64 / 1.01 * 1e4).round())
        );
        assert_eq!(data.frames[1].rel_mse, Some(0.0));
        assert!(data.frames[0].flip[0].is_some() && data.frames[0].flip[1].is_none());
        assert!(data.frames[1].flip[0]
            .as_ref()
            .unwrap()
            .values
            .iter()
            .all(|&v| v == 0.0));
        let json: serde_json::Value = serde_json::from_str(&data.json(1)).unwrap();
        assert_eq!(json["reference"], "reference");
        assert_eq!(json["fps"], 24.0);
        assert_eq!(json["frames"][1]["number"], 4);
        assert_eq!(json["frames"][1]["relmse"], 0.0);
        assert_eq!(
            json["frames"][0]["images"]["reference"]["rgb"],
            half_base64(&image(1.0))
        );
        assert!(json["frames"][0]["images"]["reference"]
            .get("flip")
            .is_none());
        // FLIP of equal images: eight zero bytes.
        assert_eq!(
            json["frames"][1]["images"]["render"]["flip"],
            base64(&[0; 8])
        );
    }

    /// Past the byte cap the images are embedded box-filtered, and the page says so.
    #[test]
    fn large_viewers_are_box_filtered_under_the_cap() {
        let big = Image {
            width: 2048,
            height: 1024,
            pixels: vec![[0.5; 3]; 2048 * 1024],
        };
        let data = ViewerData::new(
            vec!["a".into(), "b".into()],
            None,
            10.0,
            vec![(0, vec![big.clone(), big])],
            false,
        )
        .unwrap();
        // 2 x 2 Mpx x 8 bytes = 32 MiB: halved each way.
        assert_eq!(data.factor(), 2);
        let html = page("t", "", &data);
        assert!(html.contains("averaged over 2x2 pixel blocks"));
        assert!(html.contains("\"width\":1024,\"height\":512"));
    }
}
