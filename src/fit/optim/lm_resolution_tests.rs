//! The resolution stop's standard errors and the stop itself, on least-squares problems whose
//! answer and standard error are known in closed form: residuals `σ zᵢ − gᵢ (p − p*)` (white
//! noise `z` of size σ, sensitivities `g`), minimised at `p̂ = p* + Σ gᵢσzᵢ / Σ gᵢ²` with the
//! standard error `σ / √Σ gᵢ²`.

use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::DMatrix;

use super::model_optimum;
use crate::fit::optim::lm::tests::{ROLLOUT_RESOLUTION, rollout_opts as rollout};
use crate::fit::optim::{
    Bounds, ROLLOUT_REL_STEP, ROLLOUT_SHORT_STEP, levenberg_marquardt, seeded_rng,
};
use crate::fit::stats::ar1_variance_inflation;

const M: usize = 400;
const SIGMA: f64 = 0.2;

/// The noise `σ z`, the sensitivities `g`, and for the true value `p_star` the minimiser `p̂`
/// and its standard error.
fn problem(seed: u64, p_star: f64) -> (Vec<f64>, Vec<f64>, f64, f64) {
    let mut rng = seeded_rng(seed);
    let noise: Vec<f64> = (0..M).map(|_| SIGMA * rng.normal()).collect();
    let g: Vec<f64> = (0..M).map(|i| 1.0 + 0.5 * (0.37 * i as f64).sin()).collect();
    let gg: f64 = g.iter().map(|v| v * v).sum();
    let p_hat = p_star + g.iter().zip(&noise).map(|(g, e)| g * e).sum::<f64>() / gg;
    (noise, g, p_hat, SIGMA / gg.sqrt())
}

fn residual(noise: &[f64], g: &[f64], q: f64, p_star: f64) -> Vec<f64> {
    noise.iter().zip(g).map(|(e, g)| e - g * (q - p_star)).collect()
}

fn column(g: &[f64]) -> DMatrix<f64> {
    DMatrix::from_fn(g.len(), 1, |i, _| -g[i])
}

/// The model's optimum is the least-squares answer from any point of a linear residual, and
/// its standard error the noise's — the same 60 standard errors away as at the minimum — where
/// the one measured on the residual at the point (its sum of squares and its AR(1) inflation)
/// is many times longer there: the misfit the parameter explains is not noise.
#[test]
fn the_standard_error_is_the_noises_at_the_models_optimum_wherever_the_point_is() {
    let (noise, g, p_hat, se) = problem(5, 0.4);
    let j = column(&g);
    let at = |p: f64| model_optimum(&j, &residual(&noise, &g, p, 0.4), &[false]).expect("model");
    let (near, far) = (at(p_hat + 0.05 * se), at(p_hat + 60.0 * se));
    assert!((near.step[0] + 0.05 * se).abs() < 1e-9 * se, "{near:?}");
    assert!((far.step[0] + 60.0 * se).abs() < 1e-9 * se, "{far:?}");
    assert!((far.se[0] / near.se[0] - 1.0).abs() < 1e-9, "{near:?} {far:?}");
    assert!(near.se[0] > 0.85 * se && near.se[0] < 1.3 * se, "{} for {se}", near.se[0]);
    // The standard error of the residual at the far point (lm80's stop).
    let r = residual(&noise, &g, p_hat + 60.0 * se, 0.4);
    let s2 = r.iter().map(|v| v * v).sum::<f64>() / (M - 1) as f64 * ar1_variance_inflation(&r);
    let gg: f64 = g.iter().map(|v| v * v).sum();
    assert!((s2 / gg).sqrt() > 10.0 * se, "{} for {se}", (s2 / gg).sqrt());
}

/// A misfit the model cannot explain (a slow wave orthogonal to the sensitivity, 3 σ in
/// amplitude) stays in the predicted residual: the standard error is never below the noise's,
/// and longer than without it. A parameter held at a bound has neither step nor error and
/// counts as located.
#[test]
fn a_misfit_the_model_cannot_explain_does_not_shrink_the_standard_error() {
    for seed in [1, 2, 3] {
        let (noise, g, p_hat, se) = problem(seed, 0.4);
        let gg: f64 = g.iter().map(|v| v * v).sum();
        let wave: Vec<f64> = (0..M).map(|i| (i as f64 * 0.08).sin()).collect();
        let wg: f64 = wave.iter().zip(&g).map(|(w, g)| w * g).sum();
        let misfit: Vec<f64> =
            wave.iter().zip(&g).map(|(w, g)| 3.0 * SIGMA * (w - wg / gg * g)).collect();
        let p = p_hat + 2.0 * se;
        let clean = residual(&noise, &g, p, 0.4);
        let with: Vec<f64> = clean.iter().zip(&misfit).map(|(a, b)| a + b).collect();
        let j = column(&g);
        let a = model_optimum(&j, &clean, &[false]).expect("model");
        let b = model_optimum(&j, &with, &[false]).expect("model");
        assert!((b.step[0] - a.step[0]).abs() < 1e-9 * se, "{a:?} {b:?}");
        assert!(b.se[0] >= a.se[0] && b.se[0] >= se, "seed {seed}: {b:?} {a:?} noise's {se}");
    }
    // Two parameters, the second held: the first's answer alone.
    let (noise, g, p_hat, se) = problem(4, 0.4);
    let j = DMatrix::from_fn(M, 2, |i, c| if c == 0 { -g[i] } else { (i as f64).cos() });
    let m = model_optimum(&j, &residual(&noise, &g, p_hat, 0.4), &[false, true]).expect("model");
    assert!(m.step[0].abs() < 1e-9 * se && m.step[1] == 0.0 && m.se[1] == 0.0, "{m:?}");
    assert!(m.within(&[0.05 * m.se[0], 0.0], 0.1) && !m.within(&[0.2 * m.se[0], 0.0], 0.1));
    assert!(model_optimum(&j, &residual(&noise, &g, p_hat, 0.4), &[true, true]).is_none());
}

/// The problem seen through a staircase `q(p) = Δ ⌊p / Δ⌋` of treads `Δ` of a twentieth of a
/// standard error (a replayed error that does not change below a scale: a stick/slip, a
/// contact made a sample later), the minimiser 0.3 of a tread into its tread. From a start
/// 1.6 treads above it (0.08 standard errors, 0.9 into the next tread) the Gauss–Newton step
/// (0.7 of a tread, above the rollout's `short_step`) stays on the start's tread and is
/// rejected; it and the model's
/// optimum lie within the resolution, so the fit ends at its start — the start's residual, one
/// Jacobian column and that trial — within that fraction of a standard error of the answer.
/// Without the stop the damping ladder replays shorter steps on the same tread and widens the
/// difference. From 60 and 25 standard errors away it still reaches the answer, to the
/// resolution and a tread.
#[test]
fn lm_stops_where_a_rejected_step_and_its_models_optimum_lie_within_the_resolution() {
    let (noise, g, c, se) = problem(5, 0.0);
    let tread = 0.05 * se;
    let k = (0.3 / tread).round();
    // `p* = (k + 0.3) Δ − c` puts the minimiser at (k + 0.3) Δ.
    let p_star = (k + 0.3) * tread - c;
    let p_hat = (k + 0.3) * tread;
    let stairs = |p: &[f64]| residual(&noise, &g, tread * (p[0] / tread).floor(), p_star);
    let evals = AtomicUsize::new(0);
    let counted = |p: &[f64]| {
        evals.fetch_add(1, Ordering::Relaxed);
        stairs(p)
    };
    let b = Bounds { lo: vec![0.0], hi: vec![1.0] };
    let x0 = (k + 1.9) * tread;
    let fit = levenberg_marquardt(&counted, &[x0], &b, &rollout(ROLLOUT_RESOLUTION));
    assert!(fit.converged && fit.x == vec![x0], "{fit:?}");
    assert_eq!(evals.load(Ordering::Relaxed), 3, "{fit:?}");
    assert!((fit.x[0] - p_hat).abs() <= ROLLOUT_RESOLUTION * se, "{fit:?} {p_hat} {se}");
    evals.store(0, Ordering::Relaxed);
    let plain = levenberg_marquardt(&counted, &[x0], &b, &rollout(0.0));
    assert!(evals.load(Ordering::Relaxed) > 3, "{plain:?}");
    for x0 in [p_hat + 60.0 * se, p_hat - 25.0 * se] {
        let fit = levenberg_marquardt(&stairs, &[x0], &b, &rollout(ROLLOUT_RESOLUTION));
        let off = (fit.x[0] - p_hat).abs();
        assert!(fit.converged && off <= ROLLOUT_RESOLUTION * se + tread, "{x0}: {fit:?} {off}");
    }
}

/// Far from the minimum a rejected step says nothing about where it is: a trial whose replay
/// goes wrong (the first trial, 60 standard errors from the start, replayed with an error of
/// 50 σ added to every sample) does not end the fit — the model's optimum is 60 standard errors
/// away — and the fit still reaches the answer. (A stop on the parabola through that replay,
/// with the standard error of the residual at the start, AR(1)-inflated, ends there: the
/// parabola's vertex is 0.2 standard errors along the step, that standard error 12.)
#[test]
fn a_rejected_step_far_from_the_models_optimum_does_not_stop_the_fit() {
    let (noise, g, p_hat, se) = problem(7, 0.4);
    let evals = AtomicUsize::new(0);
    let r = |p: &[f64]| {
        let n = evals.fetch_add(1, Ordering::Relaxed);
        let mut v = residual(&noise, &g, p[0], 0.4);
        if n == 2 {
            v.iter_mut().for_each(|x| *x += 50.0 * SIGMA);
        }
        v
    };
    let b = Bounds { lo: vec![0.0], hi: vec![1.0] };
    let fit = levenberg_marquardt(&r, &[p_hat + 60.0 * se], &b, &rollout(ROLLOUT_RESOLUTION));
    assert!(evals.load(Ordering::Relaxed) > 3);
    assert!((fit.x[0] - p_hat).abs() <= ROLLOUT_RESOLUTION * se, "{fit:?} {p_hat} {se}");
}

/// At its start (a re-fit from a coarse fit's point), a step too short for the Jacobian to
/// resolve is not replayed; where it and the model's optimum lie within the resolution (0.05
/// standard errors, the box ten times wider than above: under `short_step` of the difference),
/// the start is the answer without the difference widened — the start's residual and one column,
/// where the fit without the stop differences again at 5 %. Half a standard error out (the box a
/// hundred times wider: still under `short_step`) the optimum is beyond the resolution, and the
/// difference is widened as before.
#[test]
fn a_short_first_step_within_the_resolution_is_not_differenced_again() {
    let (noise, g, p_hat, se) = problem(9, 0.4);
    let evals = AtomicUsize::new(0);
    let r = |p: &[f64]| {
        evals.fetch_add(1, Ordering::Relaxed);
        residual(&noise, &g, p[0], 0.4)
    };
    for (hi, off, with, without) in [(10.0, 0.05, 2, 3), (100.0, 0.5, 3, 3)] {
        let b = Bounds { lo: vec![0.0], hi: vec![hi] };
        let x0 = p_hat + off * se;
        assert!(off * se / hi < ROLLOUT_SHORT_STEP * ROLLOUT_REL_STEP, "{hi} {off}");
        for (res, n) in [(ROLLOUT_RESOLUTION, with), (0.0, without)] {
            evals.store(0, Ordering::Relaxed);
            let fit = levenberg_marquardt(&r, &[x0], &b, &rollout(res));
            // (At the start, up to the unit box's rounding.)
            let at_start = (fit.x[0] - x0).abs() <= 1e-12 * hi;
            assert!(fit.converged && at_start, "{hi} {res}: {fit:?} from {x0}");
            assert_eq!(evals.load(Ordering::Relaxed), n, "box {hi}, resolution {res}");
        }
    }
}
