//! Images out of irad (docs/DESIGN.md "Outputs"): float RGB frames, EXR in and out, PNG through a
//! tone map, the JSON sidecar, and the error metrics every accuracy figure uses.

pub mod error_maps;
pub mod exr;
pub mod flip;
pub mod metrics;
pub mod png;
pub mod preview;
pub mod sidecar;
pub mod tonemap;

pub use metrics::{
    compare, compare_sequence, compare_with_flip, Metrics, MetricsError, SequenceMetrics,
    SequenceScore,
};
pub use sidecar::{output_paths, write_all, OutputFiles, PassRecord, RenderRecord};

/// A linear RGB image, row 0 at the top, `pixels[y * width + x]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Mean of each channel, in f64.
    pub fn mean(&self) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
        }
        let n = self.pixels.len().max(1) as f64;
        s.map(|v| v / n)
    }
}
