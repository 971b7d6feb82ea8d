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

/// GPU time per pass name summed over many submissions (a progressive render's frames).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassTotals {
    /// (name, summed GPU ms or None without timestamps, times the pass ran), first-seen order.
    pub passes: Vec<(String, Option<f64>, u32)>,
    pub wall_ms: f64,
}

impl PassTotals {
    pub fn add(&mut self, timings: &Timings) {
        self.wall_ms += timings.wall_ms;
        for p in &timings.passes {
            match self.passes.iter_mut().find(|(n, _, _)| *n == p.name) {
                Some(entry) => {
                    entry.1 = entry.1.zip(p.gpu_ms).map(|(a, b)| a + b);
                    entry.2 += 1;
                }
                None => self.passes.push((p.name.clone(), p.gpu_ms, 1)),
            }
        }
    }

    pub fn total_gpu_ms(&self) -> Option<f64> {
        self.passes.iter().map(|p| p.1).sum()
    }
}

impl fmt::Display for PassTotals {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let width = self
            .passes
            .iter()
            .map(|p| p.0.len())
            .max()
            .unwrap_or(0)
            .max(10);
        for (name, ms, count) in &self.passes {
            match ms {
                Some(ms) => writeln!(
                    f,
                    "  {name:<width$}  {ms:>10.3} ms GPU  ({count} runs, {:.3} ms each)",
                    ms / *count as f64
                )?,
                None => writeln!(
                    f,
                    "  {name:<width$}  {:>10} (no timestamps, {count} runs)",
                    "-"
                )?,
            }
        }
        if let Some(total) = self.total_gpu_ms() {
            writeln!(f, "  {:<width$}  {total:>10.3} ms GPU", "all passes")?;
        }
        write!(
            f,
            "  {:<width$}  {:>10.3} ms wall clock (submissions)",
            "wall", self.wall_ms
        )
    }
}
