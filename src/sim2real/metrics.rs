//! The seed study's metrics (Booster T1 sim-to-real gap study, eqs 2–9) and the resampling
//! helpers they need.
//!
//! * MAE, RMSE, max |error| (eqs 2–4): [`error_stats`], pooled over many joints/episodes with
//!   [`Accum`] (sums of |e| and e² over all samples, so pooled numbers are exact).
//! * Pearson correlation (eq 5): [`pearson`].
//! * Gap scores (eqs 6–9): [`gap_scores`] with [`GapConstants`].
//!
//! Note on the paper's own numbers: with its reported velocity RMSE of 0.649 rad/s, eq 7 gives
//! G_dyn = 0.3245 (and G_overall = 0.440), not the 0.065 (0.362) printed in its table;
//! 0.065 corresponds to a velocity RMSE of 0.13 rad/s. G_kin = 0.300 and G_ctrl = 0.743 do follow
//! from its figures. This module implements the equations as written.

use serde::Serialize;

/// Normalisers and weights of eqs 6–9.
#[derive(Debug, Clone, Serialize)]
pub struct GapConstants {
    /// ε_pos^max of eq 6 [rad].
    pub eps_pos: f64,
    /// ε_vel^max of eq 7 [rad/s].
    pub eps_vel: f64,
    pub w_kin: f64,
    pub w_dyn: f64,
    pub w_ctrl: f64,
}

impl Default for GapConstants {
    fn default() -> Self {
        GapConstants { eps_pos: 0.5, eps_vel: 2.0, w_kin: 0.4, w_dyn: 0.3, w_ctrl: 0.3 }
    }
}

/// MAE, RMSE and max |sim − real| over `n` samples. With `n == 0` the three are NaN
/// (serialised as `null`).
#[derive(Debug, Clone, Serialize)]
pub struct ErrorStats {
    pub mae: f64,
    pub rmse: f64,
    pub max: f64,
    pub n: usize,
}

/// Eqs 2–4 over the common length of `sim` and `real`. A NaN in either propagates into all
/// three statistics (a simulation that blew up must not look accurate).
pub fn error_stats(sim: &[f64], real: &[f64]) -> ErrorStats {
    let mut a = Accum::default();
    a.add(sim, real);
    a.finish()
}

/// Running sums for pooled error statistics: pooled MAE = Σ|e| / N over all samples of all
/// added series (not a mean of per-series MAEs).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Accum {
    pub sum_abs: f64,
    pub sum_sq: f64,
    pub max: f64,
    pub n: usize,
    nan: bool,
}

impl Accum {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the errors `sim[i] − real[i]` over the common length.
    pub fn add(&mut self, sim: &[f64], real: &[f64]) {
        for (s, r) in sim.iter().zip(real) {
            self.push(s - r);
        }
    }

    /// Adds one error value.
    pub fn push(&mut self, e: f64) {
        let a = e.abs();
        if a.is_nan() {
            self.nan = true;
        } else if a > self.max {
            self.max = a;
        }
        self.sum_abs += a;
        self.sum_sq += e * e;
        self.n += 1;
    }

    /// Pools another accumulator into this one (e.g. from parallel workers).
    pub fn merge(&mut self, other: &Accum) {
        self.sum_abs += other.sum_abs;
        self.sum_sq += other.sum_sq;
        self.max = self.max.max(other.max);
        self.n += other.n;
        self.nan |= other.nan;
    }

    pub fn finish(&self) -> ErrorStats {
        if self.n == 0 {
            return ErrorStats { mae: f64::NAN, rmse: f64::NAN, max: f64::NAN, n: 0 };
        }
        let n = self.n as f64;
        ErrorStats {
            mae: self.sum_abs / n,
            rmse: (self.sum_sq / n).sqrt(),
            max: if self.nan { f64::NAN } else { self.max },
            n: self.n,
        }
    }
}

/// Pearson correlation (eq 5) over the common length; `None` when fewer than two samples,
/// either series is constant (zero variance), or a value is not finite.
pub fn pearson(a: &[f64], b: &[f64]) -> Option<f64> {
    let n = a.len().min(b.len());
    if n < 2 {
        return None;
    }
    let (a, b) = (&a[..n], &b[..n]);
    if a.iter().chain(b).any(|x| !x.is_finite()) {
        return None;
    }
    let constant = |x: &[f64]| x.iter().all(|v| *v == x[0]);
    if constant(a) || constant(b) {
        return None;
    }
    let ma = a.iter().sum::<f64>() / n as f64;
    let mb = b.iter().sum::<f64>() / n as f64;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (dx, dy) = (x - ma, y - mb);
        sab += dx * dy;
        saa += dx * dx;
        sbb += dy * dy;
    }
    if saa <= 0.0 || sbb <= 0.0 {
        return None;
    }
    Some((sab / (saa.sqrt() * sbb.sqrt())).clamp(-1.0, 1.0))
}

/// Eqs 6–9.
#[derive(Debug, Clone, Serialize)]
pub struct GapScores {
    pub kinematic: f64,
    pub dynamic: f64,
    pub control: f64,
    pub overall: f64,
}

/// G_kin = min(1, pos_rmse/ε_pos), G_dyn = min(1, vel_rmse/ε_vel), G_ctrl = 1 − ρ̄,
/// G = w_kin·G_kin + w_dyn·G_dyn + w_ctrl·G_ctrl. As in eq 8, G_ctrl is not clamped: it lies in
/// [0, 2], above 1 for anti-correlated trajectories.
pub fn gap_scores(pos_rmse: f64, vel_rmse: f64, mean_corr: f64, c: &GapConstants) -> GapScores {
    let kinematic = (pos_rmse / c.eps_pos).min(1.0);
    let dynamic = (vel_rmse / c.eps_vel).min(1.0);
    let control = 1.0 - mean_corr;
    let overall = c.w_kin * kinematic + c.w_dyn * dynamic + c.w_ctrl * control;
    GapScores { kinematic, dynamic, control, overall }
}

/// Linear interpolation of `x(t)` onto the grid `t[0] + k/rate_hz`, k = 0, 1, … while the grid
/// time does not exceed `t.last()` (within 1e-9 of a step). `t` must be increasing. Returns
/// empty vectors for empty or mismatched input or a non-positive rate.
pub fn resample_uniform(t: &[f64], x: &[f64], rate_hz: f64) -> (Vec<f64>, Vec<f64>) {
    if t.is_empty() || t.len() != x.len() || !rate_hz.is_finite() || rate_hz <= 0.0 {
        return (Vec::new(), Vec::new());
    }
    let t0 = t[0];
    let span = t[t.len() - 1] - t0;
    if span.is_nan() || span < 0.0 {
        return (Vec::new(), Vec::new());
    }
    let steps = (span * rate_hz + 1e-9).floor() as usize;
    let mut tu = Vec::with_capacity(steps + 1);
    let mut xu = Vec::with_capacity(steps + 1);
    let mut j = 0;
    for k in 0..=steps {
        let tq = (t0 + k as f64 / rate_hz).min(t[t.len() - 1]);
        while j + 2 < t.len() && t[j + 1] <= tq {
            j += 1;
        }
        tu.push(tq);
        xu.push(lerp(t, x, j, tq));
    }
    (tu, xu)
}

fn lerp(t: &[f64], x: &[f64], j: usize, tq: f64) -> f64 {
    if j + 1 >= t.len() {
        return x[j];
    }
    let dt = t[j + 1] - t[j];
    if dt <= 0.0 {
        return x[j];
    }
    let a = ((tq - t[j]) / dt).clamp(0.0, 1.0);
    x[j] + a * (x[j + 1] - x[j])
}

/// Zero-order hold: the value in force at `tq`, i.e. `x[i]` for the last `t[i] <= tq`. Before
/// `t[0]` the first value is returned; NaN for empty input. `t` must be increasing.
pub fn zoh_at(t: &[f64], x: &[f64], tq: f64) -> f64 {
    let n = t.len().min(x.len());
    if n == 0 {
        return f64::NAN;
    }
    let i = t[..n].partition_point(|&ti| ti <= tq);
    x[i.saturating_sub(1)]
}

/// Linear interpolation at `tq`, holding the end values outside `[t[0], t.last()]`; NaN for
/// empty input. `t` must be increasing.
pub fn interp_at(t: &[f64], x: &[f64], tq: f64) -> f64 {
    let n = t.len().min(x.len());
    if n == 0 {
        return f64::NAN;
    }
    let i = t[..n].partition_point(|&ti| ti <= tq);
    if i == 0 {
        return x[0];
    }
    if i >= n {
        return x[n - 1];
    }
    lerp(&t[..n], &x[..n], i - 1, tq)
}

/// Median of the positive finite sample intervals (`None` when there is none).
pub fn median_interval(t: &[f64]) -> Option<f64> {
    let mut dts: Vec<f64> =
        t.windows(2).map(|w| w[1] - w[0]).filter(|d| d.is_finite() && *d > 0.0).collect();
    if dts.is_empty() {
        return None;
    }
    dts.sort_by(f64::total_cmp);
    Some(dts[dts.len() / 2])
}

/// An interval longer than this many median intervals is a gap (dropped rows or a pause).
pub const GAP_FACTOR: f64 = 1.5;

/// Whether `t` has a gap ([`GAP_FACTOR`]).
pub fn has_gap(t: &[f64]) -> bool {
    median_interval(t).is_some_and(|h| t.windows(2).any(|w| w[1] - w[0] > GAP_FACTOR * h))
}

/// Which samples a replay reproduces from known commands: `false` for the samples after a gap
/// (an interval longer than 1.5× the median) up to `horizon` seconds past its end. The command
/// in force during a gap is unknown (a dropped row may have held a step); the joint's response
/// to it lasts about one closed-loop settling time, so those samples are not evidence about the
/// model. All `true` for regular recordings or `horizon <= 0`.
pub fn gap_mask(t: &[f64], horizon: f64) -> Vec<bool> {
    let mut m = vec![true; t.len()];
    let Some(h) = median_interval(t).filter(|_| horizon > 0.0) else { return m };
    let mut until = f64::NEG_INFINITY;
    for i in 1..t.len() {
        if t[i] - t[i - 1] > GAP_FACTOR * h {
            until = t[i] + horizon;
        }
        if t[i] < until {
            m[i] = false;
        }
    }
    m
}

/// Rows a gap may hide before it is treated as a pause rather than dropped rows.
pub const MAX_FILLED_ROWS: usize = 4;

/// Dropped rows of a held signal (a command): an interval longer than 1.5× the median sample
/// interval, and at most [`MAX_FILLED_ROWS`] + 1 medians long, is taken to have lost
/// `round(interval / median) − 1` rows at evenly spaced times. Their values are linearly
/// interpolated between the rows around the gap, so that a zero-order hold of the result holds
/// each estimated row for its share of the gap instead of holding the row before the gap for
/// all of it. Longer intervals (a pause) and everything else are returned unchanged, and so is a
/// trace with fewer than 3 samples or a non-finite neighbour. `t` must be increasing.
pub fn fill_dropped_rows(t: &[f64], x: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = t.len().min(x.len());
    let Some(h) = median_interval(&t[..n]).filter(|_| n >= 3) else {
        return (t[..n].to_vec(), x[..n].to_vec());
    };
    let (mut tu, mut xu) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 0..n {
        tu.push(t[i]);
        xu.push(x[i]);
        if i + 1 == n {
            break;
        }
        let gap = t[i + 1] - t[i];
        let rows = (gap / h).round() as usize;
        if gap.is_nan()
            || gap <= GAP_FACTOR * h
            || !(2..=MAX_FILLED_ROWS + 1).contains(&rows)
            || !x[i].is_finite()
            || !x[i + 1].is_finite()
        {
            continue;
        }
        for r in 1..rows {
            let a = r as f64 / rows as f64;
            tu.push(t[i] + a * gap);
            xu.push(x[i] + a * (x[i + 1] - x[i]));
        }
    }
    (tu, xu)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gap_mask_covers_the_horizon_after_each_gap_only() {
        let t = [0.0, 0.01, 0.02, 0.04, 0.05, 0.06, 0.07, 0.20, 0.21];
        let m = gap_mask(&t, 0.025);
        assert_eq!(m, vec![true, true, true, false, false, false, true, false, false]);
        assert!(gap_mask(&t, 0.0).iter().all(|&b| b));
        assert!(gap_mask(&[0.0, 0.01, 0.02, 0.03], 0.1).iter().all(|&b| b));
        assert!(gap_mask(&[], 0.1).is_empty());
        assert!(has_gap(&t) && !has_gap(&[0.0, 0.01, 0.02, 0.03]) && !has_gap(&[]));
    }

    #[test]
    fn dropped_rows_are_filled_pauses_and_regular_rows_are_not() {
        // 10 ms rows; the row at 0.03 is missing; a 0.2 s pause after 0.06.
        let t = [0.0, 0.01, 0.02, 0.04, 0.05, 0.06, 0.26, 0.27];
        let x = [0.0, 1.0, 2.0, 4.0, 5.0, 6.0, 26.0, 27.0];
        let (tu, xu) = fill_dropped_rows(&t, &x);
        assert_eq!(tu.len(), t.len() + 1);
        assert!((tu[3] - 0.03).abs() < 1e-12 && (xu[3] - 3.0).abs() < 1e-12);
        assert_eq!(&tu[4..], &t[3..]);
        // The held value inside the gap is the estimated row, not the row before the gap.
        assert_eq!(zoh_at(&tu, &xu, 0.035), 3.0);
        assert_eq!(zoh_at(&t, &x, 0.035), 2.0);
        // The pause (20 medians) is held, not ramped.
        assert_eq!(zoh_at(&tu, &xu, 0.16), 6.0);
        // Regular and short inputs are unchanged.
        let (a, b) = fill_dropped_rows(&[0.0, 0.01, 0.02], &[1.0, 2.0, 3.0]);
        assert_eq!((a, b), (vec![0.0, 0.01, 0.02], vec![1.0, 2.0, 3.0]));
        assert_eq!(fill_dropped_rows(&[0.0, 0.5], &[1.0, 2.0]).0.len(), 2);
        assert!(fill_dropped_rows(&[], &[]).0.is_empty());
        // A non-finite neighbour is not interpolated through.
        let (tn, _) = fill_dropped_rows(&[0.0, 0.01, 0.03, 0.04], &[0.0, f64::NAN, 3.0, 4.0]);
        assert_eq!(tn.len(), 4);
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn error_stats_by_hand() {
        let s = error_stats(&[1.0, 2.0, 3.0, 4.0], &[1.0, 1.0, 5.0, 4.0]);
        assert_eq!(s.n, 4);
        assert!(close(s.mae, 0.75, 1e-15));
        assert!(close(s.rmse, (5.0f64 / 4.0).sqrt(), 1e-15));
        assert_eq!(s.max, 2.0);
        let e = error_stats(&[], &[]);
        assert!(e.n == 0 && e.mae.is_nan() && e.rmse.is_nan() && e.max.is_nan());
        let nan = error_stats(&[f64::NAN, 1.0], &[0.0, 0.0]);
        assert!(nan.mae.is_nan() && nan.rmse.is_nan() && nan.max.is_nan());
    }

    #[test]
    fn pooled_accum_is_exact_not_mean_of_means() {
        let mut a = Accum::new();
        a.add(&[1.0], &[0.0]); // one sample, error 1
        a.add(&[0.0, 0.0, 0.0], &[0.0, 0.0, 0.0]); // three samples, error 0
        let s = a.finish();
        assert_eq!(s.n, 4);
        assert!(close(s.mae, 0.25, 1e-15)); // mean of MAEs would be 0.5
        assert!(close(s.rmse, 0.5, 1e-15));
        let mut b = Accum::new();
        b.push(-3.0);
        let mut m = a.clone();
        m.merge(&b);
        let s = m.finish();
        assert_eq!((s.n, s.max), (5, 3.0));
        assert!(close(s.mae, 4.0 / 5.0, 1e-15));
    }

    #[test]
    fn pearson_cases() {
        let a = [1.0, 2.0, 3.0, 4.0];
        assert!(close(pearson(&a, &[2.0, 4.0, 6.0, 8.0]).unwrap_or(0.0), 1.0, 1e-12));
        assert!(close(pearson(&a, &[8.0, 6.0, 4.0, 2.0]).unwrap_or(0.0), -1.0, 1e-12));
        // offset does not change correlation (Proposition 1)
        assert!(close(pearson(&a, &[11.0, 12.0, 13.0, 14.0]).unwrap_or(0.0), 1.0, 1e-12));
        let r = pearson(&[1.0, 2.0, 3.0], &[1.0, 3.0, 2.0]).unwrap_or(f64::NAN);
        assert!(close(r, 0.5, 1e-12));
        assert_eq!(pearson(&a, &[0.1; 4]), None);
        assert_eq!(pearson(&[0.1, 0.1, 0.1], &[1.0, 2.0, 3.0]), None);
        assert_eq!(pearson(&[1.0], &[1.0]), None);
    }

    #[test]
    fn gap_scores_follow_equations_6_to_9() {
        let c = GapConstants::default();
        // The paper's aggregate figures: pos RMSE 0.150 rad, vel RMSE 0.649 rad/s, mean ρ 0.257.
        let g = gap_scores(0.150, 0.649, 0.257, &c);
        assert!(close(g.kinematic, 0.300, 1e-12));
        assert!(close(g.control, 0.743, 1e-12));
        assert!(close(g.dynamic, 0.3245, 1e-12)); // eq 7; the paper's table says 0.065
        assert!(close(g.overall, 0.4 * 0.3 + 0.3 * 0.3245 + 0.3 * 0.743, 1e-12));
        // The table's G_dyn = 0.065 (vel RMSE 0.13) reproduces its overall 0.362.
        let g = gap_scores(0.150, 0.13, 0.257, &c);
        assert!(close(g.dynamic, 0.065, 1e-12));
        assert!(close(g.overall, 0.362, 5e-4));
        // clamping of eqs 6-7, none on eq 8
        let g = gap_scores(3.0, 9.0, -0.5, &c);
        assert_eq!((g.kinematic, g.dynamic, g.control), (1.0, 1.0, 1.5));
    }

    #[test]
    fn resampling_and_lookups() {
        let t = [0.0, 0.004, 0.011, 0.02, 0.031];
        let x: Vec<f64> = t.iter().map(|v| 3.0 * v - 1.0).collect();
        let (tu, xu) = resample_uniform(&t, &x, 100.0);
        assert_eq!(tu.len(), 4);
        for (a, b) in tu.iter().zip(&xu) {
            assert!(close(*b, 3.0 * a - 1.0, 1e-12));
        }
        assert!(close(tu[3], 0.03, 1e-15));
        let (tu, _) = resample_uniform(&[0.0, 0.1], &[0.0, 1.0], 10.0);
        assert_eq!(tu.len(), 2);
        assert!(resample_uniform(&t, &x[..3], 100.0).0.is_empty());
        assert!(resample_uniform(&t, &x, 0.0).0.is_empty());

        let v = [10.0, 20.0, 30.0, 40.0, 50.0];
        assert_eq!(zoh_at(&t, &v, -1.0), 10.0);
        assert_eq!(zoh_at(&t, &v, 0.0), 10.0);
        assert_eq!(zoh_at(&t, &v, 0.0039), 10.0);
        assert_eq!(zoh_at(&t, &v, 0.004), 20.0);
        assert_eq!(zoh_at(&t, &v, 0.025), 40.0);
        assert_eq!(zoh_at(&t, &v, 9.0), 50.0);
        assert!(zoh_at(&[], &[], 0.0).is_nan());
        assert!(close(interp_at(&t, &v, 0.002), 15.0, 1e-12));
        assert!(close(interp_at(&t, &v, 0.0255), 45.0, 1e-12));
        assert_eq!(interp_at(&t, &v, 0.011), 30.0);
        assert_eq!(interp_at(&t, &v, -5.0), 10.0);
        assert_eq!(interp_at(&t, &v, 5.0), 50.0);
    }
}
