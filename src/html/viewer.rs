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

use anyhow::{bail, Result};

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

/// One frame of a viewer (a still has one), its images box-filtered by the viewer's factor.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewerFrame {
    /// The frame's number, as the scrubber shows it (0 for a still).
    pub number: u32,
    /// One image per name of the viewer, in its order.
    pub images: Vec<Image>,
    /// Each image's HDR-FLIP map against the reference (computed at full size), where there
    /// is one.
    pub flip: Vec<Option<FlipMap>>,
    /// The relMSE (at full size) of the first image that is not the reference against it: the
    /// sequence's per-frame error plot.
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
    /// The box filter's size: the frames' images are stored filtered by it, so that a long
    /// sequence of large frames never sits in memory at full size.
    pub factor: u32,
    /// The full-size images' width and height.
    pub size: (u32, u32),
    /// Whether `push` computes FLIP maps.
    pub with_flip: bool,
    pub frames: Vec<ViewerFrame>,
}

impl ViewerData {
    /// A viewer of up to `frames` frames of `names`' images, each `size` pixels, with FLIP maps
    /// against the reference where `with_flip`. The box filter that keeps the page under
    /// VIEWER_BYTES is chosen here, from those counts.
    pub fn new(
        names: Vec<String>,
        reference: Option<usize>,
        fps: f32,
        frames: usize,
        size: (u32, u32),
        with_flip: bool,
    ) -> Result<ViewerData> {
        if let Some(r) = reference.filter(|&r| r >= names.len()) {
            bail!("the viewer's reference is image {r} of {}", names.len());
        }
        for (i, n) in names.iter().enumerate() {
            if names[..i].contains(n) {
                bail!("two of the viewer's images are named {n:?}");
            }
        }
        // 8 base64 bytes a pixel for half RGB, 4/3 for a FLIP byte (and 1 for the JSON's
        // rounding), over the filtered images' pixels (each side rounded up).
        let maps = match (with_flip, reference) {
            (true, Some(_)) => names.len() - 1,
            _ => 0,
        };
        let per_pixel = 8 * names.len() + maps * 4 / 3 + 1;
        let factor = (1..)
            .find(|&f: &usize| {
                let pixels = (size.0 as usize).div_ceil(f) * (size.1 as usize).div_ceil(f);
                frames.max(1) * pixels * per_pixel <= VIEWER_BYTES
            })
            .expect("some factor fits") as u32;
        Ok(ViewerData {
            names,
            reference,
            fps,
            factor,
            size,
            with_flip,
            frames: Vec::with_capacity(frames),
        })
    }

    /// A still: one frame of `images` (named), FLIP maps computed where `with_flip`.
    pub fn still(
        images: Vec<(String, Image)>,
        reference: Option<usize>,
        with_flip: bool,
    ) -> Result<ViewerData> {
        let size = images
            .first()
            .map(|(_, im)| (im.width, im.height))
            .unwrap_or((0, 0));
        let (names, images): (Vec<String>, Vec<Image>) = images.into_iter().unzip();
        let mut data = ViewerData::new(names, reference, 10.0, 1, size, with_flip)?;
        data.push(0, images)?;
        Ok(data)
    }

    /// Adds frame `number`: its images in the order of the names. Their relMSE against the
    /// reference and (where the viewer computes them) FLIP maps are taken at full size, then
    /// the images are box-filtered.
    pub fn push(&mut self, number: u32, images: Vec<Image>) -> Result<()> {
        let mut flips = vec![None; images.len()];
        if let (true, Some(r)) = (self.with_flip, self.reference) {
            self.check(number, &images)?;
            // One image per core at a time: the port is single-threaded, about a second a
            // megapixel, and a suite's scene has a map per run.
            let targets: Vec<usize> = (0..images.len()).filter(|&i| i != r).collect();
            // At most 4 at once: each holds full-size buffers of its own.
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get().min(4));
            for chunk in targets.chunks(cores) {
                std::thread::scope(|scope| {
                    let images = &images;
                    let running: Vec<_> = chunk
                        .iter()
                        .map(|&i| {
                            let job = move || {
                                flip::hdr_flip(&images[r], &images[i], DEFAULT_PIXELS_PER_DEGREE)
                            };
                            (i, scope.spawn(job))
                        })
                        .collect();
                    for (i, handle) in running {
                        // A non-finite image has no FLIP map (its NaN/Inf count says why).
                        match handle.join() {
                            Ok(Ok(f)) => {
                                flips[i] = Some(FlipMap {
                                    width: f.width,
                                    height: f.height,
                                    values: f.error_map,
                                })
                            }
                            Ok(Err(e)) => log::info!("no FLIP map of {}: {e}", self.names[i]),
                            Err(_) => {
                                log::warn!("no FLIP map of {}: its thread panicked", self.names[i])
                            }
                        }
                    }
                });
            }
        }
        self.push_with_flips(number, images, flips)
    }

    /// Adds frame `number` with FLIP maps computed elsewhere (one per image, None for the
    /// reference's).
    pub fn push_with_flips(
        &mut self,
        number: u32,
        images: Vec<Image>,
        flips: Vec<Option<FlipMap>>,
    ) -> Result<()> {
        self.check(number, &images)?;
        if flips.len() != images.len() {
            bail!(
                "frame {number}: {} FLIP maps for {} images",
                flips.len(),
                images.len()
            );
        }
        for (name, m) in self.names.iter().zip(&flips) {
            if let Some(m) = m.as_ref().filter(|m| (m.width, m.height) != self.size) {
                bail!(
                    "frame {number}: {name}'s FLIP map is {}x{}",
                    m.width,
                    m.height
                );
            }
        }
        let rel_mse = match (
            self.reference,
            (0..self.names.len()).find(|&i| Some(i) != self.reference),
        ) {
            (Some(r), Some(t)) => metrics::compare(&images[t], &images[r])
                .ok()
                .map(|m| m.rel_mse),
            _ => None,
        };
        let factor = self.factor;
        let flips = flips
            .into_iter()
            .map(|m| m.map(|m| scaled_map(m, factor)))
            .collect();
        let images = images
            .into_iter()
            .map(|im| match factor {
                1 => im,
                f => preview::downscale(&im, f),
            })
            .collect();
        self.frames.push(ViewerFrame {
            number,
            images,
            flip: flips,
            rel_mse,
        });
        Ok(())
    }

    /// One image per name, each of the viewer's size.
    fn check(&self, number: u32, images: &[Image]) -> Result<()> {
        if images.len() != self.names.len() {
            bail!(
                "frame {number}: {} images for the viewer's {} names",
                images.len(),
                self.names.len()
            );
        }
        for (name, im) in self.names.iter().zip(images) {
            if (im.width, im.height) != self.size {
                bail!(
                    "frame {number}: {name} is {}x{}, the viewer's images {}x{}",
                    im.width,
                    im.height,
                    self.size.0,
                    self.size.1
                );
            }
        }
        Ok(())
    }

    /// The viewer's data as the JSON object viewer.js reads: each frame's images as an array
    /// in the order of `names`.
    pub fn json(&self) -> String {
        let mut s = String::from("{\"names\":[");
        for (i, n) in self.names.iter().enumerate() {
            let _ = write!(s, "{}{}", if i > 0 { "," } else { "" }, json_string(n));
        }
        let _ = write!(
            s,
            "],\"reference\":{},\"fps\":{},\"factor\":{},\"size\":[{},{}],\"frames\":[",
            match self.reference {
                Some(r) => json_string(&self.names[r]),
                None => "null".into(),
            },
            if self.fps.is_finite() && self.fps > 0.0 {
                self.fps
            } else {
                10.0
            },
            self.factor,
            self.size.0,
            self.size.1
        );
        for (k, frame) in self.frames.iter().enumerate() {
            let rel_mse = match frame.rel_mse {
                Some(e) if e.is_finite() => format!("{e:e}"),
                _ => "null".into(),
            };
            let _ = write!(
                s,
                "{}{{\"number\":{},\"relmse\":{rel_mse},\"images\":[",
                if k > 0 { "," } else { "" },
                frame.number
            );
            for (i, image) in frame.images.iter().enumerate() {
                let _ = write!(
                    s,
                    "{}{{\"width\":{},\"height\":{},\"rgb\":\"{}\"",
                    if i > 0 { "," } else { "" },
                    image.width,
                    image.height,
                    half_base64(image)
                );
                if let Some(map) = &frame.flip[i] {
                    let _ = write!(s, ",\"flip\":\"{}\"", flip_base64(map));
                }
                s.push('}');
            }
            s.push_str("]}");
        }
        s + "]}"
    }
}

/// A FLIP map box-filtered by `factor`.
fn scaled_map(map: FlipMap, factor: u32) -> FlipMap {
    if factor <= 1 {
        return map;
    }
    let image = Image {
        width: map.width,
        height: map.height,
        pixels: map.values.iter().map(|&v| [v; 3]).collect(),
    };
    let image = preview::downscale(&image, factor);
    FlipMap {
        width: image.width,
        height: image.height,
        values: image.pixels.iter().map(|p| p[0]).collect(),
    }
}

/// A FLIP map as one byte a pixel (round(255 v)), in base64.
pub fn flip_base64(map: &FlipMap) -> String {
    let bytes: Vec<u8> = map
        .values
        .iter()
        .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
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
    let factor = data.factor;
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
        data = data.json(),
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
        let mut data = ViewerData::new(names, Some(1), 24.0, 2, (4, 2), true).unwrap();
        data.push(3, vec![image(1.5), image(1.0)]).unwrap();
        data.push(4, vec![image(1.0), image(1.0)]).unwrap();
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
        let json: serde_json::Value = serde_json::from_str(&data.json()).unwrap();
        assert_eq!(json["reference"], "reference");
        assert_eq!(json["fps"], 24.0);
        assert_eq!(json["frames"][1]["number"], 4);
        assert_eq!(json["frames"][1]["relmse"], 0.0);
        assert_eq!(
            json["frames"][0]["images"][1]["rgb"],
            half_base64(&image(1.0))
        );
        assert!(json["frames"][0]["images"][1].get("flip").is_none());
        // FLIP of equal images: eight zero bytes.
        assert_eq!(json["frames"][1]["images"][0]["flip"], base64(&[0; 8]));
        // A frame of another size, or with an image missing, is refused by name.
        let e = data
            .push(5, vec![image(1.0), Image::new(3, 2)])
            .unwrap_err();
        assert!(e.to_string().contains("frame 5: reference is 3x2"), "{e}");
        assert!(data.push(6, vec![image(1.0)]).is_err());
    }

    /// Past the byte cap the images are stored box-filtered, and the page says so.
    #[test]
    fn large_viewers_are_box_filtered_under_the_cap() {
        let big = Image {
            width: 2048,
            height: 1024,
            pixels: vec![[0.5; 3]; 2048 * 1024],
        };
        let data = ViewerData::still(
            vec![("a".into(), big.clone()), ("b".into(), big)],
            None,
            false,
        )
        .unwrap();
        // 2 x 2 Mpx x 8 bytes = 32 MiB: halved each way.
        assert_eq!(data.factor, 2);
        assert_eq!(data.frames[0].images[0].width, 1024);
        let html = page("t", "", &data);
        assert!(html.contains("averaged over 2x2 pixel blocks"));
        assert!(html.contains("\"width\":1024,\"height\":512"));
        // 240 frames of 1280x720: filtered as they come, by the factor the counts call for.
        let long = ViewerData::new(
            vec!["a".into(), "b".into()],
            Some(1),
            24.0,
            240,
            (1280, 720),
            true,
        )
        .unwrap();
        assert!(long.factor >= 10, "{}", long.factor);
    }
}
