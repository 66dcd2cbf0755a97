//! Statistics helpers for parameter fits: linearised uncertainty from a
//! Jacobian, bootstrap spread, information criteria and a paired test for
//! "did the fit improve held-out error beyond noise".
//!
//! All functions are total: degenerate input (empty, ragged, too few
//! residuals, non-finite values) never panics; it yields infinite standard
//! errors / `false` flags / NaN criteria instead.

use nalgebra::DMatrix;
use serde::Serialize;

/// Linearised (Gauss–Newton) parameter uncertainty.
#[derive(Debug, Clone, Serialize)]
pub struct ParamUncertainty {
    /// Standard error of each parameter, in the parameter's own units.
    /// `f64::INFINITY` when the parameter is not determined by the data.
    pub stderr: Vec<f64>,
    /// `false` when the parameter cannot be pinned down by the data: its
    /// standard error exceeds half of its bounds range, or it participates in
    /// a near-null direction of the Jacobian.
    pub identifiable: Vec<bool>,
    /// Ratio of the largest to the smallest singular value of the Jacobian
    /// (`f64::INFINITY` if the smallest is zero or the input is degenerate).
    pub condition_number: f64,
}

impl ParamUncertainty {
    /// Raises each finite standard error to `wider[i]` where that is larger (a cluster-robust
    /// error beside the pooled one), with the same identifiability rule as
    /// [`uncertainty_from_jacobian`]: an error above half the parameter's range.
    pub fn widen(&mut self, wider: &[f64], ranges: &[f64]) {
        for (i, &w) in wider.iter().enumerate().take(self.stderr.len()) {
            if self.stderr[i].is_finite() && w > self.stderr[i] {
                self.stderr[i] = w;
                if beyond_range(w, ranges.get(i).copied()) {
                    self.identifiable[i] = false;
                }
            }
        }
    }
}

/// Whether a standard error exceeds [`RANGE_FRACTION`] of a finite, positive parameter range.
fn beyond_range(stderr: f64, range: Option<f64>) -> bool {
    range.is_some_and(|r| r.is_finite() && r > 0.0 && stderr > RANGE_FRACTION * r)
}

/// Relative singular-value cutoff below which a direction counts as null.
pub const NULL_SV_REL: f64 = 1e-8;
/// A parameter whose component in a null singular vector exceeds this (in
/// absolute value, vectors being unit-norm) is considered unidentifiable.
const NULL_COMPONENT: f64 = 0.05;
/// A parameter whose stderr exceeds this fraction of its range is unidentifiable.
pub const RANGE_FRACTION: f64 = 0.5;

fn degenerate_uncertainty(n_params: usize) -> ParamUncertainty {
    ParamUncertainty {
        stderr: vec![f64::INFINITY; n_params],
        identifiable: vec![false; n_params],
        condition_number: f64::INFINITY,
    }
}

/// Parameter standard errors from the Jacobian of the residuals at the
/// solution.
///
/// `jac` is `n_resid x n_params` (row per residual, as returned by
/// `levenberg_marquardt`), `residuals` are the residuals at the solution,
/// `ranges[j]` is `hi_j - lo_j` of parameter `j` (non-finite or non-positive
/// entries, or missing entries, disable the range check for that parameter).
///
/// Covariance is `s^2 (J^T J)^+` with `s^2 = RSS / (n - p)`, the
/// pseudo-inverse taken through the SVD of `J`, discarding singular values
/// below `1e-8 * max`.
pub fn uncertainty_from_jacobian(
    jac: &[Vec<f64>],
    residuals: &[f64],
    n_params: usize,
    ranges: &[f64],
) -> ParamUncertainty {
    let m = jac.len();
    let p = n_params;
    if p == 0 {
        return ParamUncertainty {
            stderr: vec![],
            identifiable: vec![],
            condition_number: f64::INFINITY,
        };
    }
    if m <= p
        || residuals.len() != m
        || jac.iter().any(|row| row.len() != p || row.iter().any(|v| !v.is_finite()))
        || residuals.iter().any(|v| !v.is_finite())
    {
        return degenerate_uncertainty(p);
    }
    let j = DMatrix::from_fn(m, p, |r, c| jac[r][c]);
    let rss: f64 = residuals.iter().map(|r| r * r).sum();
    let s2 = rss / (m - p) as f64;

    let svd = j.svd(false, true);
    let Some(v_t) = svd.v_t.as_ref() else {
        return degenerate_uncertainty(p);
    };
    let sv = &svd.singular_values; // length p (min(m,p) = p)
    let smax = sv.iter().cloned().fold(0.0_f64, f64::max);
    let smin = sv.iter().cloned().fold(f64::INFINITY, f64::min);
    if smax.is_nan() || smax <= 0.0 {
        return degenerate_uncertainty(p);
    }
    let condition_number = if smin > 0.0 { smax / smin } else { f64::INFINITY };
    let cutoff = NULL_SV_REL * smax;

    let mut stderr = vec![0.0; p];
    let mut identifiable = vec![true; p];
    for (k, &s) in sv.iter().enumerate() {
        // Row k of V^T is the k-th right singular vector.
        for jj in 0..p {
            let vjk = v_t[(k, jj)];
            if s > cutoff {
                stderr[jj] += vjk * vjk / (s * s);
            } else if vjk.abs() > NULL_COMPONENT {
                identifiable[jj] = false;
            }
        }
    }
    for jj in 0..p {
        if !identifiable[jj] {
            // The pseudo-inverse would report a finite (meaningless) value.
            stderr[jj] = f64::INFINITY;
            continue;
        }
        stderr[jj] = (s2 * stderr[jj]).sqrt();
        if beyond_range(stderr[jj], ranges.get(jj).copied()) {
            identifiable[jj] = false;
        }
        if !stderr[jj].is_finite() {
            identifiable[jj] = false;
        }
    }
    ParamUncertainty { stderr, identifiable, condition_number }
}

/// Cluster-robust ("sandwich") standard errors: `c (JᵀJ)⁺ (Σ_g s_g s_gᵀ) (JᵀJ)⁺` with
/// `s_g = J_gᵀ r_g` the score of cluster `g` (the rows whose `cluster` id is `g`) and the
/// small-sample factor `c = G/(G − 1) · (n − 1)/(n − p)`. With one cluster per recorded episode
/// it holds when the residuals are not independent within an episode (a replay's model error
/// is smooth; a stick/slip that flips keeps an episode off for seconds) and when episodes
/// disagree about a parameter — which `s²(JᵀJ)⁺` cannot see. For independent residuals it
/// agrees with `s²(JᵀJ)⁺` on average. `None` for fewer than two clusters, fewer rows than
/// parameters, ragged or non-finite input.
pub fn cluster_robust_stderr(
    jac: &[Vec<f64>],
    residuals: &[f64],
    cluster: &[usize],
    n_params: usize,
) -> Option<Vec<f64>> {
    let (m, p) = (jac.len(), n_params);
    if p == 0
        || m <= p
        || residuals.len() != m
        || cluster.len() != m
        || jac.iter().any(|row| row.len() != p || row.iter().any(|v| !v.is_finite()))
        || residuals.iter().any(|v| !v.is_finite())
    {
        return None;
    }
    let mut ids: Vec<usize> = cluster.to_vec();
    ids.sort_unstable();
    ids.dedup();
    let g = ids.len();
    if g < 2 {
        return None;
    }
    let j = DMatrix::from_fn(m, p, |r, c| jac[r][c]);
    let jtj = j.transpose() * &j;
    let smax = jtj.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    if !(smax > 0.0) {
        return None;
    }
    let a = jtj.pseudo_inverse(NULL_SV_REL * NULL_SV_REL * smax).ok()?;
    let mut scores = DMatrix::<f64>::zeros(p, g);
    for (row, (&c, &r)) in cluster.iter().zip(residuals).enumerate() {
        let k = ids.binary_search(&c).ok()?;
        for q in 0..p {
            scores[(q, k)] += jac[row][q] * r;
        }
    }
    let meat = &scores * scores.transpose();
    let c = g as f64 / (g - 1) as f64 * (m - 1) as f64 / (m - p) as f64;
    let cov = &a * meat * &a * c;
    let se: Vec<f64> = (0..p).map(|q| cov[(q, q)].max(0.0).sqrt()).collect();
    se.iter().all(|v| v.is_finite()).then_some(se)
}

/// Variance inflation for serially correlated residuals, modelled as AR(1): `(1 + ρ)/(1 − ρ)`
/// with ρ the lag-1 autocorrelation of `r` (clamped to [0, 0.99]; 1 for fewer than 3 finite
/// samples). `s²(JᵀJ)⁺` assumes independent residuals; a replay's residuals are a smooth model
/// error plus white noise, and n correlated samples carry the information of about
/// n (1 − ρ)/(1 + ρ) independent ones.
pub fn ar1_variance_inflation(r: &[f64]) -> f64 {
    let v: Vec<f64> = r.iter().copied().filter(|x| x.is_finite()).collect();
    if v.len() < 3 {
        return 1.0;
    }
    let ss: f64 = v.iter().map(|x| x * x).sum();
    if ss <= 0.0 {
        return 1.0;
    }
    let rho = (v.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / ss).clamp(0.0, 0.99);
    (1.0 + rho) / (1.0 - rho)
}

/// Standard deviation (n−1 denominator) of each parameter across bootstrap
/// refits. `samples[i]` is the parameter vector of refit `i`; rows whose
/// length differs from the first row are ignored, as are non-finite entries
/// (failed refits). A parameter with fewer than two finite samples gets
/// `f64::INFINITY`.
pub fn bootstrap_stderr(samples: &[Vec<f64>]) -> Vec<f64> {
    let Some(first) = samples.first() else {
        return vec![];
    };
    let p = first.len();
    (0..p)
        .map(|j| {
            let vals: Vec<f64> = samples
                .iter()
                .filter(|s| s.len() == p)
                .map(|s| s[j])
                .filter(|v| v.is_finite())
                .collect();
            if vals.len() < 2 {
                return f64::INFINITY;
            }
            let n = vals.len() as f64;
            let mean = vals.iter().sum::<f64>() / n;
            let var = vals.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
            var.sqrt()
        })
        .collect()
}

fn log_mse(n: usize, rss: f64) -> f64 {
    // Guard rss == 0 (perfect fit) so that models stay comparable.
    let rss = if rss.is_finite() { rss.max(f64::MIN_POSITIVE) } else { rss };
    (n as f64) * (rss / n as f64).ln()
}

/// Akaike information criterion for Gaussian residuals: `n ln(rss/n) + 2k`.
/// NaN when `n == 0` or `rss` is NaN/negative.
pub fn aic(n: usize, rss: f64, k: usize) -> f64 {
    if n == 0 || rss.is_nan() || rss < 0.0 {
        return f64::NAN;
    }
    log_mse(n, rss) + 2.0 * k as f64
}

/// The residual `real − sim` in runs of consecutive scored, finite samples (what
/// [`white_floor`] takes): a sample left out ends a run.
pub fn residual_runs(scored: &[bool], real: &[f64], sim: &[f64]) -> Vec<Vec<f64>> {
    let mut out = vec![vec![]];
    for ((s, a), b) in scored.iter().zip(real).zip(sim) {
        let e = a - b;
        if *s && e.is_finite() {
            out.last_mut().expect("one").push(e);
        } else if !out.last().expect("one").is_empty() {
            out.push(vec![]);
        }
    }
    out
}

/// The residual's white floor: per run of consecutive samples `runs`, the mean square `ms` of
/// the residual and its white part `white = mean((r[i+1] − r[i])²) / 2`. Sensor noise and
/// quantisation change from sample to sample; a missing effect leaves an error that changes
/// smoothly over many samples. `ms / white` ≈ 1 means nothing is left to explain; a model error
/// makes it grow with (error / noise)². Returns (ms, white).
pub fn white_floor(runs: &[Vec<f64>]) -> (f64, f64) {
    let (mut s2, mut n2, mut d2, mut nd) = (0.0, 0usize, 0.0, 0usize);
    for r in runs {
        for (i, &x) in r.iter().enumerate() {
            s2 += x * x;
            n2 += 1;
            if i > 0 {
                let d = x - r[i - 1];
                d2 += d * d;
                nd += 1;
            }
        }
    }
    if n2 == 0 || nd == 0 {
        return (0.0, 0.0);
    }
    (s2 / n2 as f64, d2 / nd as f64 / 2.0)
}

/// Bayesian information criterion for Gaussian residuals: `n ln(rss/n) + k ln n`.
/// NaN when `n == 0` or `rss` is NaN/negative.
pub fn bic(n: usize, rss: f64, k: usize) -> f64 {
    if n == 0 || rss.is_nan() || rss < 0.0 {
        return f64::NAN;
    }
    log_mse(n, rss) + k as f64 * (n as f64).ln()
}

/// [`bic`] with `m` independent pieces of evidence instead of `n`: `m ln(rss/n) + k ln m`.
/// A rollout's residual is smooth: the samples of one (episode, window, joint) share one model
/// error and are not `n` independent draws, so the plain BIC charges a parameter `ln n` against
/// a likelihood counted `n` times, and any systematic difference, however small next to the
/// error, reads as evidence. Counted per window, a parameter must buy a relative drop in the
/// residual of about `ln m / m` (1.4 % at 432 windows). NaN when `m` or `n` is 0 or `rss` is
/// NaN/negative.
pub fn bic_pieces(m: usize, n: usize, rss: f64, k: usize) -> f64 {
    if m == 0 || n == 0 || rss.is_nan() || rss < 0.0 {
        return f64::NAN;
    }
    m as f64 * (rss.max(f64::MIN_POSITIVE) / n as f64).ln() + k as f64 * (m as f64).ln()
}

/// Paired comparison of per-window errors on held-out data, before vs after a
/// fit. Returns `(mean of before−after, standard error of that mean,
/// significant)` where `significant` means `mean > 0 && mean > 2·stderr`.
/// Pairs with a non-finite member are skipped; extra entries of the longer
/// slice are ignored. With fewer than two pairs the stderr is infinite and the
/// result is not significant.
pub fn improvement_beyond_noise(before: &[f64], after: &[f64]) -> (f64, f64, bool) {
    let d: Vec<f64> = before
        .iter()
        .zip(after)
        .filter(|(b, a)| b.is_finite() && a.is_finite())
        .map(|(b, a)| b - a)
        .collect();
    if d.is_empty() {
        return (0.0, f64::INFINITY, false);
    }
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    if d.len() < 2 {
        return (mean, f64::INFINITY, false);
    }
    let var = d.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    let se = (var / n).sqrt();
    let significant = mean > 0.0 && mean > 2.0 * se;
    (mean, se, significant)
}

#[cfg(test)]
mod ar1_tests {
    use super::*;
    use crate::fit::optim::seeded_rng;

    #[test]
    fn ar1_inflation_is_one_for_white_noise_and_large_for_smooth_residuals() {
        let mut rng = seeded_rng(3);
        let white: Vec<f64> = (0..20_000).map(|_| rng.normal_complement()).collect();
        let f = ar1_variance_inflation(&white);
        assert!((f - 1.0).abs() < 0.05, "{f}");
        // AR(1) with φ = 0.9: (1 + 0.9)/(1 − 0.9) = 19.
        let mut x = 0.0;
        let ar: Vec<f64> = (0..20_000)
            .map(|_| {
                x = 0.9 * x + rng.normal_complement();
                x
            })
            .collect();
        let f = ar1_variance_inflation(&ar);
        assert!((f - 19.0).abs() < 3.0, "{f}");
        assert_eq!(ar1_variance_inflation(&[1.0, 2.0]), 1.0);
        assert_eq!(ar1_variance_inflation(&[0.0; 10]), 1.0);
        // Alternating residuals (ρ < 0) are not deflated.
        assert_eq!(ar1_variance_inflation(&[1.0, -1.0, 1.0, -1.0]), 1.0);
    }
}

#[cfg(test)]
mod white_tests {
    use super::white_floor;

    #[test]
    fn white_noise_is_at_its_floor_and_a_smooth_error_is_not() {
        // Deterministic pseudo-noise: uniform in [-1, 1) (variance 1/3).
        let mut x = 12345u64;
        let mut u = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        };
        let noise: Vec<f64> = (0..20000).map(|_| u()).collect();
        let (ms, w) = white_floor(std::slice::from_ref(&noise));
        assert!((ms - 1.0 / 3.0).abs() < 0.01 && (ms / w - 1.0).abs() < 0.05, "{ms} {w}");
        // A slow sine of the noise's amplitude on top: the white part stays, the mean square
        // grows by A²/2.
        let a = 1.0;
        let r: Vec<f64> =
            noise.iter().enumerate().map(|(i, n)| n + a * (i as f64 * 0.01).sin()).collect();
        let (ms, w) = white_floor(&[r]);
        assert!((w - 1.0 / 3.0).abs() < 0.02, "{w}");
        assert!((ms - (1.0 / 3.0 + 0.5)).abs() < 0.03, "{ms}");
        assert_eq!(white_floor(&[]), (0.0, 0.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    #[test]
    fn linear_regression_stderr_matches_closed_form() {
        // y = a + b t, J = [1, t]; cov = s^2 (J^T J)^-1 analytically.
        let t: Vec<f64> = (0..10).map(|i| i as f64).collect();
        let res: Vec<f64> = vec![0.1, -0.2, 0.05, 0.3, -0.1, -0.15, 0.2, -0.05, 0.0, 0.1];
        let jac: Vec<Vec<f64>> = t.iter().map(|&ti| vec![1.0, ti]).collect();
        let u = uncertainty_from_jacobian(&jac, &res, 2, &[100.0, 100.0]);
        let n = 10.0;
        let rss: f64 = res.iter().map(|r| r * r).sum();
        let s2 = rss / (n - 2.0);
        let st: f64 = t.iter().sum();
        let stt: f64 = t.iter().map(|x| x * x).sum();
        let det = n * stt - st * st;
        let se_a = (s2 * stt / det).sqrt();
        let se_b = (s2 * n / det).sqrt();
        assert!(close(u.stderr[0], se_a, 1e-10), "{} vs {}", u.stderr[0], se_a);
        assert!(close(u.stderr[1], se_b, 1e-10), "{} vs {}", u.stderr[1], se_b);
        assert_eq!(u.identifiable, vec![true, true]);
        // Condition number = sqrt(cond(J^T J)).
        let tr = n + stt;
        let disc = ((n - stt).powi(2) + 4.0 * st * st).sqrt();
        let cond = ((tr + disc) / (tr - disc)).sqrt();
        assert!(close(u.condition_number, cond, 1e-8));
    }

    #[test]
    fn widen_takes_the_larger_error_and_rechecks_the_range() {
        let mut u = ParamUncertainty {
            stderr: vec![0.1, 0.1, f64::INFINITY, 0.3],
            identifiable: vec![true, true, false, true],
            condition_number: 1.0,
        };
        // Range 1: 0.2 stays identifiable, 0.6 > half the range does not; an infinite error
        // stays infinite; a smaller robust error changes nothing.
        u.widen(&[0.2, 0.6, 0.1, 0.05], &[1.0, 1.0, 1.0, 1.0]);
        assert_eq!(u.stderr[..2], [0.2, 0.6]);
        assert_eq!(u.identifiable[..2], [true, false]);
        assert!(u.stderr[2].is_infinite() && !u.identifiable[2]);
        assert_eq!((u.stderr[3], u.identifiable[3]), (0.3, true));
        // An unbounded range never flags.
        u.widen(&[0.2, 0.6, 0.1, 100.0], &[1.0, 1.0, 1.0, f64::INFINITY]);
        assert_eq!((u.stderr[3], u.identifiable[3]), (100.0, true));
    }

    #[test]
    fn cluster_robust_stderr_by_hand() {
        // One parameter (a mean), J = 1: se² = c Σ_g (Σ r_g)² / n², c = G/(G−1) (n−1)/(n−p).
        let jac = vec![vec![1.0]; 6];
        let ids = [0, 0, 0, 1, 1, 1];
        // Two episodes that disagree: +1 throughout, −1 throughout. Scores ±3, c = 2 · 5/5:
        // se² = 2 · 18 / 36 = 1. The classical s²(JᵀJ)⁻¹ = (6/5)/6 sees only 0.45.
        let r = [1.0, 1.0, 1.0, -1.0, -1.0, -1.0];
        let se = cluster_robust_stderr(&jac, &r, &ids, 1).expect("two clusters");
        assert!(close(se[0], 1.0, 1e-12), "{se:?}");
        let classical = uncertainty_from_jacobian(&jac, &r, 1, &[]).stderr[0];
        assert!(close(classical, (0.2f64).sqrt(), 1e-12), "{classical}");
        // Alternating within each episode: scores +1, −1: se² = 2 · 2 / 36.
        let r = [1.0, -1.0, 1.0, -1.0, 1.0, -1.0];
        let se = cluster_robust_stderr(&jac, &r, &ids, 1).expect("two clusters");
        assert!(close(se[0], (4.0f64 / 36.0).sqrt(), 1e-12), "{se:?}");
        // Cluster ids need not be contiguous numbers.
        let se2 = cluster_robust_stderr(&jac, &r, &[7, 7, 7, 42, 42, 42], 1).expect("two");
        assert!(close(se2[0], se[0], 1e-12));
        // Two parameters y = a + b t, clusters t < 2 and t ≥ 2 (J rows [1, t], t = 0..4),
        // residuals (1, −1, 0, 1): (JᵀJ)⁻¹ = [[14, −6], [−6, 4]]/20, scores (0, −1) and
        // (1, 3), meat [[1, 3], [3, 10]], c = 2 · 3/2 = 3.
        let jac: Vec<Vec<f64>> = (0..4).map(|t| vec![1.0, t as f64]).collect();
        let se = cluster_robust_stderr(&jac, &[1.0, -1.0, 0.0, 1.0], &[0, 0, 1, 1], 2)
            .expect("two clusters");
        // A = inv/20 with inv = [[14, −6], [−6, 4]]: A M A = inv M inv / 400.
        let inv = [[14.0, -6.0], [-6.0, 4.0]];
        let meat = [[1.0, 3.0], [3.0, 10.0]];
        let mut im = [[0.0; 2]; 2];
        for i in 0..2 {
            for k in 0..2 {
                im[i][k] = (0..2).map(|l| inv[i][l] * meat[l][k]).sum();
            }
        }
        for q in 0..2 {
            let v: f64 = (0..2).map(|l| im[q][l] * inv[l][q]).sum::<f64>() / 400.0 * 3.0;
            assert!(close(se[q], v.sqrt(), 1e-10), "{q}: {} vs {}", se[q], v.sqrt());
        }
        // One cluster, too few rows, NaN: no estimate.
        let ones = vec![vec![1.0]; 3];
        assert!(cluster_robust_stderr(&ones, &[1.0, 2.0, 3.0], &[0, 0, 0], 1).is_none());
        assert!(cluster_robust_stderr(&ones[..1], &[1.0], &[0], 1).is_none());
        assert!(cluster_robust_stderr(&ones, &[1.0, f64::NAN, 3.0], &[0, 1, 1], 1).is_none());
    }

    #[test]
    fn collinear_parameters_are_unidentifiable() {
        // Columns 0 and 1 identical: only their sum is determined; column 2 is fine.
        let jac: Vec<Vec<f64>> = (0..20)
            .map(|i| {
                let t = i as f64 * 0.1;
                vec![t.sin(), t.sin(), 1.0]
            })
            .collect();
        let res: Vec<f64> = (0..20).map(|i| if i % 2 == 0 { 0.01 } else { -0.01 }).collect();
        let u = uncertainty_from_jacobian(&jac, &res, 3, &[1.0, 1.0, 1.0]);
        assert_eq!(u.identifiable, vec![false, false, true]);
        assert!(u.stderr[0].is_infinite() && u.stderr[1].is_infinite());
        assert!(u.stderr[2].is_finite() && u.stderr[2] < 0.01);
        assert!(u.condition_number > 1e8);
    }

    #[test]
    fn weak_parameter_flagged_by_range() {
        // Column 1 is tiny -> large stderr relative to its range of 1.0.
        let jac: Vec<Vec<f64>> =
            (0..30).map(|i| vec![1.0, 1e-4 * ((i as f64) * 0.7).cos()]).collect();
        let res: Vec<f64> = (0..30).map(|i| 0.05 * ((i as f64) * 1.3).sin()).collect();
        let u = uncertainty_from_jacobian(&jac, &res, 2, &[1.0, 1.0]);
        assert!(u.identifiable[0]);
        assert!(!u.identifiable[1]);
        assert!(u.stderr[1] > 0.5 && u.stderr[1].is_finite());
        // Without a usable range the parameter counts as identifiable (finite stderr, non-null).
        let u2 = uncertainty_from_jacobian(&jac, &res, 2, &[]);
        assert!(u2.identifiable[1]);
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let u = uncertainty_from_jacobian(&[], &[], 2, &[]);
        assert_eq!(u.stderr, vec![f64::INFINITY; 2]);
        assert_eq!(u.identifiable, vec![false; 2]);
        assert!(u.condition_number.is_infinite());
        // Fewer residuals than parameters.
        let u = uncertainty_from_jacobian(&[vec![1.0, 2.0]], &[0.1], 2, &[1.0, 1.0]);
        assert_eq!(u.identifiable, vec![false; 2]);
        // Ragged / NaN.
        let u = uncertainty_from_jacobian(
            &[vec![1.0], vec![1.0, 2.0], vec![0.0, 1.0]],
            &[0.1, 0.2, 0.3],
            2,
            &[],
        );
        assert_eq!(u.identifiable, vec![false; 2]);
        let u = uncertainty_from_jacobian(
            &[vec![f64::NAN, 1.0], vec![1.0, 2.0], vec![0.0, 1.0]],
            &[0.1, 0.2, 0.3],
            2,
            &[],
        );
        assert_eq!(u.identifiable, vec![false; 2]);
        // All-zero Jacobian.
        let u = uncertainty_from_jacobian(&[vec![0.0], vec![0.0]], &[0.1, 0.2], 1, &[]);
        assert_eq!(u.identifiable, vec![false]);
        let u = uncertainty_from_jacobian(&[vec![]], &[0.0], 0, &[]);
        assert!(u.stderr.is_empty());
        assert!(bootstrap_stderr(&[]).is_empty());
        assert_eq!(bootstrap_stderr(&[vec![1.0, 2.0]]), vec![f64::INFINITY; 2]);
        assert!(aic(0, 1.0, 1).is_nan());
        assert!(bic(0, 1.0, 1).is_nan());
        assert!(aic(10, 0.0, 1).is_finite());
        assert_eq!(improvement_beyond_noise(&[], &[]), (0.0, f64::INFINITY, false));
        let (m, se, sig) = improvement_beyond_noise(&[2.0], &[1.0, 5.0]);
        assert_eq!((m, se, sig), (1.0, f64::INFINITY, false));
    }

    #[test]
    fn bootstrap_std_dev() {
        let s = vec![
            vec![1.0, 10.0],
            vec![2.0, 10.0],
            vec![3.0, 10.0],
            vec![4.0, 10.0],
            vec![f64::NAN, 10.0],
            vec![9.0],
        ];
        let sd = bootstrap_stderr(&s);
        // Sample std of 1,2,3,4 = sqrt(5/3).
        assert!(close(sd[0], (5.0f64 / 3.0).sqrt(), 1e-12));
        assert_eq!(sd[1], 0.0);
    }

    #[test]
    fn information_criteria_values() {
        let n = 100;
        let rss = 2.5;
        let base = 100.0 * (0.025f64).ln();
        assert!(close(aic(n, rss, 3), base + 6.0, 1e-12));
        assert!(close(bic(n, rss, 3), base + 3.0 * (100f64).ln(), 1e-12));
        // Adding a parameter that halves nothing is penalised.
        assert!(aic(n, rss, 4) > aic(n, rss, 3));
        // Halving RSS beats one extra parameter.
        assert!(bic(n, rss / 2.0, 4) < bic(n, rss, 3));
    }

    #[test]
    fn paired_improvement() {
        let before = [1.0, 1.2, 0.9, 1.1, 1.05, 0.95];
        let after = [0.8, 1.0, 0.75, 0.85, 0.9, 0.8];
        let (m, se, sig) = improvement_beyond_noise(&before, &after);
        let d = [0.2, 0.2, 0.15, 0.25, 0.15, 0.15];
        let mean = d.iter().sum::<f64>() / 6.0;
        let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / 5.0;
        assert!(close(m, mean, 1e-12));
        assert!(close(se, (var / 6.0).sqrt(), 1e-12));
        assert!(sig);
        // Noisy, no consistent improvement.
        let after2 = [0.7, 1.5, 0.6, 1.4, 1.0, 1.0];
        let (m2, se2, sig2) = improvement_beyond_noise(&before, &after2);
        assert!(m2.abs() < 2.0 * se2);
        assert!(!sig2);
        // Consistent degradation is never significant.
        let (_, _, sig3) = improvement_beyond_noise(&after, &before);
        assert!(!sig3);
    }
}
