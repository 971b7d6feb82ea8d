//! Restricted-CDF sampling of a light-field image (Lu 14 Section 4.3.3-4.3.5), in f64: the CPU
//! mirror the GPU kernels of method `lightfield` follow, and the place where the pdf each
//! sampler actually realises is derived and tested.
//!
//! An image C is piecewise constant over W x H texels, texel (i, j) covering s in [i, i + 1)
//! and t in [j, j + 1) (texel units). A window [s0, s1] x [t0, t1] (Eq. 4.11's restricted
//! domain) is sampled in two ways:
//!
//! - `Windowed` (pbrt-v4's WindowedPiecewiseConstant2D): s from the marginal of the window
//!   itself, F(s) = the integral of C over [s0, s] x [t0, t1], read from the summed-area table
//!   (exact: the table of a piecewise-constant image is bilinear within a texel); then t from
//!   column s's CDF restricted to [t0, t1] (Eq. 4.12, second line). The realised pdf is
//!   p(s, t) = C(s, t) / A with A the window's integral: Eq. 4.14 holds.
//! - `Affine` (Lu's Eq. 4.12 as written): s from the precomputed marginal of the whole image,
//!   M(s) = the integral of C over [0, s] x [0, H], restricted affinely to [s0, s1]; then t as
//!   above. The marginal then weighs column s by its whole-image mass m(s) where the window
//!   holds only w(s) of it, so the realised pdf is
//!   p(s, t) = m(s) / (M(s1) - M(s0)) * C(s, t) / w(s),
//!   which equals C / A only when w(s) / m(s) is the same for every column of the window.
//!   Dividing by C / A with this sampler is biased (tested below); a column with w(s) = 0 but
//!   m(s) > 0 is drawn and wastes its sample.
//!
//! Inverting a piecewise-linear CDF on integer knots: binary search over the knots, or Lu's
//! modified secant search (Section 4.4): interpolate linearly between the bracket's ends, test
//! the knot interval the guess falls in, and shrink the bracket to one side of it; it stops
//! when the bracket is one interval (the CDF's linear piece), so both give the exact answer.

/// Which marginal draws s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marginal {
    /// The window's own marginal, from the summed-area table: pdf C / A.
    Windowed,
    /// The whole image's marginal restricted affinely (Lu's Eq. 4.12): pdf as derived above.
    Affine,
}

/// How a CDF over integer knots is inverted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Search {
    Binary,
    /// Lu's modified secant (false-position) search.
    Secant,
}

/// An image's sampling tables: per column the cumulative sum over t, the whole-image marginal
/// over s, and the summed-area table.
#[derive(Clone, Debug)]
pub struct ImageTables {
    pub width: usize,
    pub height: usize,
    /// C, row-major: texel (i, j) at j * width + i.
    pub texels: Vec<f64>,
    /// Column i's cumulative sums at the row knots 0..=H: column_cdf[i * (H + 1) + j].
    column_cdf: Vec<f64>,
    /// M at the column knots 0..=W.
    marginal: Vec<f64>,
    /// The summed-area table at the knots: sat[j * (W + 1) + i] = the integral of C over
    /// [0, i] x [0, j].
    sat: Vec<f64>,
}

/// A drawn point, its texel, and how many search steps the two inversions took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Draw {
    pub s: f64,
    pub t: f64,
    pub texel: (usize, usize),
    pub steps: u32,
}

/// The window [s0, s1] x [t0, t1], clamped to the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    pub s0: f64,
    pub s1: f64,
    pub t0: f64,
    pub t1: f64,
}

impl Window {
    pub fn clamped(self, width: usize, height: usize) -> Window {
        let c = |x: f64, hi: usize| x.clamp(0.0, hi as f64);
        Window {
            s0: c(self.s0.min(self.s1), width),
            s1: c(self.s0.max(self.s1), width),
            t0: c(self.t0.min(self.t1), height),
            t1: c(self.t0.max(self.t1), height),
        }
    }
}

/// Inverts a non-decreasing function given at integer knots lo..=hi (value(k)) for `target`
/// in [value(lo), value(hi)): the knot interval [k, k + 1) holding it (value(k) <= target <
/// value(k + 1), empty intervals skipped) and the steps taken.
pub fn invert(
    value: impl Fn(usize) -> f64,
    lo: usize,
    hi: usize,
    target: f64,
    search: Search,
) -> (usize, u32) {
    let (mut lo, mut hi) = (lo, hi);
    let mut steps = 0;
    while hi - lo > 1 {
        steps += 1;
        let mid = match search {
            Search::Binary => (lo + hi) / 2,
            Search::Secant => {
                let (a, b) = (value(lo), value(hi));
                let x = lo as f64 + (target - a) / (b - a) * (hi - lo) as f64;
                let k = (x.floor() as usize).clamp(lo, hi - 1);
                if value(k) <= target && target < value(k + 1) {
                    return (k, steps);
                }
                // The bracket shrinks by at least one knot.
                if target < value(k) {
                    hi = k;
                    continue;
                }
                k + 1
            }
        };
        if target < value(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (lo, steps)
}

impl ImageTables {
    pub fn new(width: usize, height: usize, texels: Vec<f64>) -> ImageTables {
        assert_eq!(texels.len(), width * height);
        let mut column_cdf = vec![0.0; width * (height + 1)];
        let mut marginal = vec![0.0; width + 1];
        for i in 0..width {
            for j in 0..height {
                column_cdf[i * (height + 1) + j + 1] =
                    column_cdf[i * (height + 1) + j] + texels[j * width + i];
            }
            marginal[i + 1] = marginal[i] + column_cdf[i * (height + 1) + height];
        }
        let mut sat = vec![0.0; (width + 1) * (height + 1)];
        for j in 1..=height {
            for i in 1..=width {
                sat[j * (width + 1) + i] = texels[(j - 1) * width + i - 1]
                    + sat[(j - 1) * (width + 1) + i]
                    + sat[j * (width + 1) + i - 1]
                    - sat[(j - 1) * (width + 1) + i - 1];
            }
        }
        ImageTables {
            width,
            height,
            texels,
            column_cdf,
            marginal,
            sat,
        }
    }

    /// Column i's integral over [0, j] (row knot j).
    pub fn column_knot(&self, i: usize, j: usize) -> f64 {
        self.column_cdf[i * (self.height + 1) + j]
    }

    /// M at column knot i: the integral over [0, i] x [0, H].
    pub fn marginal_knot(&self, i: usize) -> f64 {
        self.marginal[i]
    }

    /// The summed-area table at knot (i, j): the integral over [0, i] x [0, j].
    pub fn sat_knot(&self, i: usize, j: usize) -> f64 {
        self.sat[j * (self.width + 1) + i]
    }

    pub fn texel(&self, i: usize, j: usize) -> f64 {
        self.texels[j * self.width + i]
    }

    /// The integral of C over [0, s] x [0, t]: the summed-area table, bilinear in a texel.
    pub fn sat(&self, s: f64, t: f64) -> f64 {
        let (w, h) = (self.width, self.height);
        let s = s.clamp(0.0, w as f64);
        let t = t.clamp(0.0, h as f64);
        let (i, j) = (
            (s.floor() as usize).min(w.saturating_sub(1)),
            (t.floor() as usize).min(h.saturating_sub(1)),
        );
        let (fs, ft) = (s - i as f64, t - j as f64);
        let at = |a: usize, b: usize| self.sat[b * (w + 1) + a];
        let lower = at(i, j) * (1.0 - fs) + at(i + 1, j) * fs;
        let upper = at(i, j + 1) * (1.0 - fs) + at(i + 1, j + 1) * fs;
        lower * (1.0 - ft) + upper * ft
    }

    /// A: the integral of C over the window (Eq. 4.14), from the summed-area table.
    pub fn window_integral(&self, w: Window) -> f64 {
        (self.sat(w.s1, w.t1) - self.sat(w.s0, w.t1) - self.sat(w.s1, w.t0) + self.sat(w.s0, w.t0))
            .max(0.0)
    }

    /// Column i's cumulative integral over [0, t].
    fn column(&self, i: usize, t: f64) -> f64 {
        let h = self.height;
        let t = t.clamp(0.0, h as f64);
        let j = (t.floor() as usize).min(h - 1);
        let base = i * (h + 1);
        self.column_cdf[base + j] + (t - j as f64) * self.texels[j * self.width + i]
    }

    /// M(s): the whole image's marginal, piecewise linear.
    fn marginal_at(&self, s: f64) -> f64 {
        let w = self.width;
        let s = s.clamp(0.0, w as f64);
        let i = (s.floor() as usize).min(w - 1);
        self.marginal[i] + (s - i as f64) * (self.marginal[i + 1] - self.marginal[i])
    }

    /// w(i): column i's integral over [t0, t1].
    pub fn windowed_column(&self, i: usize, w: Window) -> f64 {
        (self.column(i, w.t1) - self.column(i, w.t0)).max(0.0)
    }

    /// m(i): column i's integral over the whole image.
    pub fn whole_column(&self, i: usize) -> f64 {
        self.marginal[i + 1] - self.marginal[i]
    }

    /// Draws a point of the window from (u1, u2) in [0, 1)^2; None when the window holds
    /// nothing (A = 0) or, with the affine marginal, when the drawn column holds nothing in
    /// the window (a wasted sample).
    pub fn draw(
        &self,
        window: Window,
        u: (f64, f64),
        marginal: Marginal,
        search: Search,
    ) -> Option<Draw> {
        let w = window.clamped(self.width, self.height);
        if w.s1 <= w.s0 || w.t1 <= w.t0 {
            return None;
        }
        // s: a knot-indexed CDF over the window's columns, then linear in the column.
        let first = w.s0.floor() as usize;
        let last = (w.s1.ceil() as usize).clamp(first + 1, self.width);
        // Knot k of the search is min(max(first + k, s0), s1).
        let knot = |k: usize| ((first + k) as f64).clamp(w.s0, w.s1);
        let f = |s: f64| match marginal {
            Marginal::Windowed => {
                self.sat(s, w.t1) - self.sat(s, w.t0) - self.sat(w.s0, w.t1) + self.sat(w.s0, w.t0)
            }
            Marginal::Affine => self.marginal_at(s) - self.marginal_at(w.s0),
        };
        let total = f(w.s1);
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = u.0 * total;
        let (k, steps_s) = invert(|k| f(knot(k)), 0, last - first, target, search);
        let (a, b) = (knot(k), knot(k + 1));
        let (fa, fb) = (f(a), f(b));
        let s = if fb > fa {
            a + (target - fa) / (fb - fa) * (b - a)
        } else {
            a
        };
        let i = (first + k).min(self.width - 1);
        // t: column i restricted to [t0, t1].
        let below = self.column(i, w.t0);
        let mass = self.column(i, w.t1) - below;
        if mass.is_nan() || mass <= 0.0 {
            return None;
        }
        let first_t = w.t0.floor() as usize;
        let last_t = (w.t1.ceil() as usize).clamp(first_t + 1, self.height);
        let knot_t = |k: usize| ((first_t + k) as f64).clamp(w.t0, w.t1);
        let g = |t: f64| self.column(i, t) - below;
        let target_t = u.1 * mass;
        let (kt, steps_t) = invert(|k| g(knot_t(k)), 0, last_t - first_t, target_t, search);
        let (a, b) = (knot_t(kt), knot_t(kt + 1));
        let (ga, gb) = (g(a), g(b));
        let t = if gb > ga {
            a + (target_t - ga) / (gb - ga) * (b - a)
        } else {
            a
        };
        let j = (first_t + kt).min(self.height - 1);
        Some(Draw {
            s: s.clamp(w.s0, w.s1),
            t: t.clamp(w.t0, w.t1),
            texel: (i, j),
            steps: steps_s + steps_t,
        })
    }

    /// The density (per unit of s t) with which `draw` produces a point in texel (i, j) of
    /// the window (0 outside it).
    pub fn pdf(&self, window: Window, texel: (usize, usize), marginal: Marginal) -> f64 {
        let w = window.clamped(self.width, self.height);
        let (i, j) = texel;
        let c = self.texel(i, j);
        let a = self.window_integral(w);
        if (a.is_nan() || a <= 0.0) || (c.is_nan() || c <= 0.0) {
            return 0.0;
        }
        match marginal {
            Marginal::Windowed => c / a,
            Marginal::Affine => {
                let restricted = self.marginal_at(w.s1) - self.marginal_at(w.s0);
                let column = self.windowed_column(i, w);
                if (column.is_nan() || column <= 0.0) || (restricted.is_nan() || restricted <= 0.0)
                {
                    return 0.0;
                }
                self.whole_column(i) / restricted * c / column
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 24 x 16 test image: a smooth ramp, a bright block, a black band of columns and a
    /// black band of rows.
    fn image() -> ImageTables {
        let (w, h) = (24, 16);
        let mut texels = vec![];
        for j in 0..h {
            for i in 0..w {
                let mut c = 0.2 + 0.05 * i as f64 + 0.1 * ((j * 7 + i * 3) % 5) as f64;
                if (8..11).contains(&i) && (3..7).contains(&j) {
                    c += 20.0;
                }
                if (14..16).contains(&i) || j == 12 {
                    c = 0.0;
                }
                texels.push(c);
            }
        }
        ImageTables::new(w, h, texels)
    }

    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut x = seed.wrapping_mul(0x9e3779b97f4a7c15) | 1;
        move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn windows() -> Vec<Window> {
        vec![
            Window {
                s0: 0.0,
                s1: 24.0,
                t0: 0.0,
                t1: 16.0,
            },
            Window {
                s0: 2.3,
                s1: 19.6,
                t0: 1.7,
                t1: 14.2,
            },
            // At the border, partly outside the image (clamped).
            Window {
                s0: -3.0,
                s1: 5.5,
                t0: 10.4,
                t1: 20.0,
            },
            // Small, inside a texel's neighbourhood, straddling the black columns.
            Window {
                s0: 12.6,
                s1: 17.2,
                t0: 4.1,
                t1: 5.9,
            },
            Window {
                s0: 21.2,
                s1: 24.0,
                t0: 0.0,
                t1: 3.3,
            },
        ]
    }

    #[test]
    fn the_summed_area_table_integrates_exactly() {
        let im = image();
        let mut next = rng(3);
        for _ in 0..200 {
            let w = Window {
                s0: next() * 24.0,
                s1: next() * 24.0,
                t0: next() * 16.0,
                t1: next() * 16.0,
            }
            .clamped(24, 16);
            // Brute force: per texel, C times the overlap area.
            let mut sum = 0.0;
            for j in 0..16 {
                for i in 0..24 {
                    let ds = (w.s1.min(i as f64 + 1.0) - w.s0.max(i as f64)).max(0.0);
                    let dt = (w.t1.min(j as f64 + 1.0) - w.t0.max(j as f64)).max(0.0);
                    sum += im.texel(i, j) * ds * dt;
                }
            }
            let a = im.window_integral(w);
            assert!(
                (a - sum).abs() <= 1e-9 * sum.max(1.0),
                "{w:?}: {a} against {sum}"
            );
        }
    }

    /// Both samplers against the pdfs derived above, for windows of several sizes and
    /// positions (borders included): the histogram of 100,000 draws over the window's
    /// texels by a chi-square test against the pdf integrated over each texel's part of the
    /// window; draws always inside the window, never in a zero texel; and the derived pdf
    /// integrating to 1 over the window (up to the affine sampler's wasted columns).
    #[test]
    fn both_samplers_follow_their_derived_pdf() {
        let im = image();
        for (k, window) in windows().into_iter().enumerate() {
            let w = window.clamped(24, 16);
            for marginal in [Marginal::Windowed, Marginal::Affine] {
                let mut next = rng(10 + k as u64);
                let n = 100_000;
                let mut counts = vec![0u32; 24 * 16];
                let mut drawn = 0;
                for _ in 0..n {
                    let Some(d) = im.draw(window, (next(), next()), marginal, Search::Secant)
                    else {
                        continue;
                    };
                    drawn += 1;
                    assert!(
                        d.s >= w.s0 && d.s <= w.s1 && d.t >= w.t0 && d.t <= w.t1,
                        "{d:?} outside {w:?}"
                    );
                    assert!(
                        im.texel(d.texel.0, d.texel.1) > 0.0,
                        "{d:?} in a black texel"
                    );
                    counts[d.texel.1 * 24 + d.texel.0] += 1;
                }
                let mut chi2 = 0.0;
                let mut cells = 0;
                let mut total_probability = 0.0;
                for j in 0..16 {
                    for i in 0..24 {
                        let ds = (w.s1.min(i as f64 + 1.0) - w.s0.max(i as f64)).max(0.0);
                        let dt = (w.t1.min(j as f64 + 1.0) - w.t0.max(j as f64)).max(0.0);
                        let p = im.pdf(window, (i, j), marginal) * ds * dt;
                        total_probability += p;
                        let e = n as f64 * p;
                        let o = counts[j * 24 + i] as f64;
                        if e == 0.0 {
                            assert_eq!(
                                o, 0.0,
                                "{marginal:?} {w:?}: texel ({i}, {j}) has pdf 0 but {o} draws"
                            );
                            continue;
                        }
                        if e >= 5.0 {
                            chi2 += (o - e).powi(2) / e;
                            cells += 1;
                        }
                    }
                }
                let dof = (cells - 1).max(1) as f64;
                assert!(
                    chi2 / dof < 1.6,
                    "{marginal:?} {w:?}: chi^2 {chi2:.1} over {dof}"
                );
                // The windowed sampler never wastes a draw and its pdf integrates to 1; the
                // affine one loses the columns with nothing in the window.
                if marginal == Marginal::Windowed {
                    assert_eq!(drawn, n);
                    assert!(
                        (total_probability - 1.0).abs() < 1e-9,
                        "{w:?}: {total_probability}"
                    );
                } else {
                    let kept = drawn as f64 / n as f64;
                    assert!(
                        (kept - total_probability).abs() < 0.01,
                        "{w:?}: kept {kept}, pdf mass {total_probability}"
                    );
                }
            }
        }
    }

    /// Lu's Eq. 4.12 as written: with the affine (whole-image) marginal, dividing by Eq. 4.14's
    /// C / A is biased: the estimate of the integral of C g over the window (g a smooth
    /// weight, as the |s - p|^-3 and Psi factors of Eq. 4.6 are) misses the truth, while
    /// dividing by the realised pdf hits it. The windowed marginal is unbiased with C / A.
    #[test]
    fn dividing_by_c_over_a_is_biased_with_the_affine_marginal() {
        let im = image();
        // Below the bright block: its columns hold far more of their mass outside the window
        // than the others, so the whole-image marginal over-draws them.
        let window = Window {
            s0: 2.3,
            s1: 19.6,
            t0: 8.0,
            t1: 15.5,
        }
        .clamped(24, 16);
        let a = im.window_integral(window);
        let g = |s: f64, t: f64| 1.0 + 0.3 * s + 0.1 * (t - 8.0).abs();
        // The truth, exactly: C constant per texel, g integrated by a fine midpoint rule.
        let mut truth = 0.0;
        for j in 0..16 {
            for i in 0..24 {
                let (lo_s, hi_s) = (window.s0.max(i as f64), window.s1.min(i as f64 + 1.0));
                let (lo_t, hi_t) = (window.t0.max(j as f64), window.t1.min(j as f64 + 1.0));
                if hi_s <= lo_s || hi_t <= lo_t {
                    continue;
                }
                let mut sum = 0.0;
                for a in 0..32 {
                    for b in 0..32 {
                        let s = lo_s + (hi_s - lo_s) * (a as f64 + 0.5) / 32.0;
                        let t = lo_t + (hi_t - lo_t) * (b as f64 + 0.5) / 32.0;
                        sum += g(s, t);
                    }
                }
                truth += im.texel(i, j) * sum / 1024.0 * (hi_s - lo_s) * (hi_t - lo_t);
            }
        }
        let n = 400_000;
        let estimate = |marginal: Marginal, realised: bool| {
            let mut next = rng(99);
            let mut sum = 0.0;
            for _ in 0..n {
                if let Some(d) = im.draw(window, (next(), next()), marginal, Search::Binary) {
                    let c = im.texel(d.texel.0, d.texel.1);
                    let p = if realised {
                        im.pdf(window, d.texel, marginal)
                    } else {
                        c / a
                    };
                    sum += c * g(d.s, d.t) / p;
                }
            }
            sum / n as f64 / truth
        };
        let affine_true = estimate(Marginal::Affine, true);
        let affine_eq414 = estimate(Marginal::Affine, false);
        let windowed = estimate(Marginal::Windowed, false);
        eprintln!("estimate / truth: affine with its realised pdf {affine_true:.4}, affine with C / A {affine_eq414:.4}, windowed with C / A {windowed:.4}");
        assert!(
            (affine_true - 1.0).abs() < 0.01,
            "affine, realised pdf: {affine_true}"
        );
        assert!((windowed - 1.0).abs() < 0.01, "windowed, C / A: {windowed}");
        assert!(
            (affine_eq414 - 1.0).abs() > 0.03,
            "affine, C / A: {affine_eq414} (expected biased)"
        );
    }

    /// Lu's modified secant search reaches the exact knot interval (the same as binary
    /// search's) in fewer steps on average.
    #[test]
    fn secant_search_takes_fewer_steps_than_binary_search() {
        let im = image();
        let mut steps = [0u64; 2];
        let mut next = rng(5);
        for window in windows() {
            for _ in 0..20_000 {
                let u = (next(), next());
                let b = im
                    .draw(window, u, Marginal::Windowed, Search::Binary)
                    .unwrap();
                let s = im
                    .draw(window, u, Marginal::Windowed, Search::Secant)
                    .unwrap();
                assert_eq!(b.texel, s.texel);
                assert!((b.s - s.s).abs() < 1e-9 && (b.t - s.t).abs() < 1e-9);
                steps[0] += b.steps as u64;
                steps[1] += s.steps as u64;
            }
        }
        eprintln!(
            "search steps per draw (s and t): binary {:.2}, secant {:.2}",
            steps[0] as f64 / 100_000.0,
            steps[1] as f64 / 100_000.0
        );
        assert!(
            steps[1] < steps[0],
            "secant {} against binary {}",
            steps[1],
            steps[0]
        );
    }
}
