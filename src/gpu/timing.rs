//! Per-pass GPU times (from timestamp queries) and the wall clock of a submission.

use std::fmt;

#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    pub name: String,
    /// None where the device's queue has no timestamps.
    pub gpu_ms: Option<f64>,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timings {
    /// In recording order; a name may repeat.
    pub passes: Vec<PassTime>,
    /// From submit to the fence signalling, on the host.
    pub wall_ms: f64,
}

impl Timings {
    /// GPU time summed over every pass named `name`.
    pub fn gpu_ms(&self, name: &str) -> Option<f64> {
        let times: Vec<Option<f64>> = self
            .passes
            .iter()
            .filter(|p| p.name == name)
            .map(|p| p.gpu_ms)
            .collect();
        if times.is_empty() {
            return None;
        }
        times.into_iter().sum()
    }

    /// GPU time summed over every pass.
    pub fn total_gpu_ms(&self) -> Option<f64> {
        self.passes.iter().map(|p| p.gpu_ms).sum()
    }
}

impl fmt::Display for Timings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let width = self
            .passes
            .iter()
            .map(|p| p.name.len())
            .max()
            .unwrap_or(0)
            .max(10);
        for p in &self.passes {
            match p.gpu_ms {
                Some(ms) => writeln!(f, "  {:<width$}  {ms:>10.3} ms GPU", p.name)?,
                None => writeln!(f, "  {:<width$}  {:>10} (no timestamps)", p.name, "-")?,
            }
        }
        write!(
            f,
            "  {:<width$}  {:>10.3} ms wall clock",
            "submit", self.wall_ms
        )
    }
}
