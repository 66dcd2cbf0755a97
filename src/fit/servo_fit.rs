//! Servo identification on BAM-style logs: whole-log replay of the [`ServoHook`] model, a
//! per-log position-MAE objective, bounded fits (CMA-ES or Nelder–Mead from [`super::optim`]),
//! linearised standard errors and BIC ([`super::stats`]), and greedy forward selection of
//! effects with a held-out gate. Reusable by the general fit engine: everything takes a rig
//! [`Robot`], a list of [`ServoLog`]s and index sets for training and evaluation.

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;

use super::optim::{Bounds, CmaesOpts, NelderMeadOpts, cmaes, nelder_mead};
use super::servo::{Effect, EffectSet, ServoParams, simulate};
use super::stats::{bic, uncertainty_from_jacobian};
use crate::model::Robot;
use crate::sim2real::input::{expand_inputs, read_recording};
use crate::sim2real::recording::Recording;

/// Error [rad] charged to a sample the simulation did not reach (diverged episode).
const DIVERGED_ERROR: f64 = 1.0;

/// One servo log with its nominal model parameters.
#[derive(Debug, Clone)]
pub struct ServoLog {
    pub name: String,
    pub kp: f64,
    pub trajectory: String,
    pub rec: Recording,
    pub base: ServoParams,
}

/// Loads every BAM log of `dir` (sorted by file name).
pub fn load_logs(dir: &Path) -> Result<Vec<ServoLog>, String> {
    let files = expand_inputs(&[dir.to_path_buf()]).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for f in files {
        let rec = read_recording(&f).map_err(|e| e.to_string())?;
        let base = ServoParams::for_recording(&rec)
            .ok_or_else(|| format!("{}: not a BAM log (meta kp/vin/mass/length)", f.display()))?;
        out.push(ServoLog {
            name: f.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
            kp: base.kp_firmware,
            trajectory: rec.meta.get("trajectory").cloned().unwrap_or_default(),
            rec,
            base,
        });
    }
    Ok(out)
}

/// Simulated minus recorded position at every sample of `log` (non-reached samples get
/// [`DIVERGED_ERROR`]).
pub fn log_residuals(robot: &Robot, log: &ServoLog, p: &ServoParams) -> Vec<f64> {
    let real = &log.rec.joints[0].q;
    match simulate(robot, &log.rec, p) {
        Ok(ep) => ep.q_sim[0]
            .iter()
            .zip(real)
            .map(|(s, r)| if s.is_finite() { s - r } else { DIVERGED_ERROR })
            .collect(),
        Err(_) => vec![DIVERGED_ERROR; real.len()],
    }
}

pub fn mae(r: &[f64]) -> f64 {
    r.iter().map(|x| x.abs()).sum::<f64>() / r.len().max(1) as f64
}

/// Per-log residuals of the model `set`/`x` on the logs `idx` (parallel over logs).
pub fn residuals(
    robot: &Robot,
    logs: &[ServoLog],
    idx: &[usize],
    set: &EffectSet,
    x: &[f64],
) -> Vec<Vec<f64>> {
    idx.par_iter().map(|&i| log_residuals(robot, &logs[i], &set.apply(&logs[i].base, x))).collect()
}

/// Objective: mean over the logs `idx` of the whole-log position MAE [rad].
pub fn objective(
    robot: &Robot,
    logs: &[ServoLog],
    idx: &[usize],
    set: &EffectSet,
    x: &[f64],
) -> f64 {
    let r = residuals(robot, logs, idx, set, x);
    r.iter().map(|v| mae(v)).sum::<f64>() / r.len().max(1) as f64
}

#[derive(Debug, Clone, Copy, serde::Serialize)]
pub enum Optimiser {
    Cmaes,
    NelderMead,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct FitOpts {
    pub optimiser: Optimiser,
    /// Objective evaluations per fit (one evaluation = all training logs).
    pub max_evals: usize,
    /// Effects forward selection may add, in this order of consideration.
    pub candidates: Vec<Effect>,
    pub seed: u64,
    /// Evaluations of the final refit of the chosen set (0: none).
    pub polish_evals: usize,
}

impl Default for FitOpts {
    fn default() -> Self {
        FitOpts {
            optimiser: Optimiser::NelderMead,
            max_evals: 80,
            candidates: Effect::ALL.to_vec(),
            seed: 7,
            polish_evals: 200,
        }
    }
}

/// A fitted model and its assessment.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FitResult {
    pub effects: Vec<Effect>,
    pub param_names: Vec<&'static str>,
    pub param_units: Vec<&'static str>,
    pub x: Vec<f64>,
    pub stderr: Vec<f64>,
    /// Mean per-log MAE on the training logs [rad].
    pub train_mae: f64,
    /// BIC of the training residuals (Gaussian, n = training samples).
    pub bic: f64,
    /// Per held-out log MAE [rad], in `test` order.
    pub test_mae_per_log: Vec<f64>,
    pub test_mae: f64,
    pub evals: usize,
    pub seconds: f64,
}

/// Minimises the training objective of `set` from `x0`.
pub fn fit_set(
    robot: &Robot,
    logs: &[ServoLog],
    train: &[usize],
    set: &EffectSet,
    x0: &[f64],
    o: &FitOpts,
) -> (Vec<f64>, f64, usize) {
    if set.n_params() == 0 {
        return (vec![], objective(robot, logs, train, set, &[]), 1);
    }
    let specs = set.specs();
    let b = Bounds {
        lo: specs.iter().map(|s| s.lo).collect(),
        hi: specs.iter().map(|s| s.hi).collect(),
    };
    let f = |x: &[f64]| objective(robot, logs, train, set, x);
    let r = match o.optimiser {
        Optimiser::Cmaes => cmaes(
            &f,
            x0,
            &b,
            &CmaesOpts {
                max_evals: o.max_evals,
                sigma0: 0.2,
                popsize: None,
                seed: o.seed,
                ftol: 1e-7,
            },
        ),
        Optimiser::NelderMead => nelder_mead(
            &f,
            x0,
            &b,
            &NelderMeadOpts { max_evals: o.max_evals, xtol: 1e-4, ftol: 1e-7, initial_step: 0.15 },
        ),
    };
    (r.x, r.f, r.evals)
}

/// Training BIC, standard errors (finite-difference Jacobian of the training residual vector)
/// and held-out MAE of `set` at `x`.
pub fn assess(
    robot: &Robot,
    logs: &[ServoLog],
    train: &[usize],
    test: &[usize],
    set: &EffectSet,
    x: &[f64],
) -> FitResult {
    let specs = set.specs();
    let flat = |r: Vec<Vec<f64>>| r.into_iter().flatten().collect::<Vec<f64>>();
    let r_train = residuals(robot, logs, train, set, x);
    let train_mae = r_train.iter().map(|v| mae(v)).sum::<f64>() / r_train.len().max(1) as f64;
    let r0 = flat(r_train);
    let rss: f64 = r0.iter().map(|e| e * e).sum();
    let k = set.n_params();
    let stderr = if k == 0 {
        vec![]
    } else {
        // Central differences, columns in parallel.
        let cols: Vec<Vec<f64>> = (0..k)
            .into_par_iter()
            .map(|j| {
                let h = 1e-3 * (specs[j].hi - specs[j].lo);
                let mut xp = x.to_vec();
                let mut xm = x.to_vec();
                xp[j] = (x[j] + h).min(specs[j].hi);
                xm[j] = (x[j] - h).max(specs[j].lo);
                let d = xp[j] - xm[j];
                let rp = flat(residuals(robot, logs, train, set, &xp));
                let rm = flat(residuals(robot, logs, train, set, &xm));
                rp.iter().zip(&rm).map(|(a, b)| (a - b) / d).collect()
            })
            .collect();
        let jac: Vec<Vec<f64>> =
            (0..r0.len()).map(|i| cols.iter().map(|c| c[i]).collect()).collect();
        let ranges: Vec<f64> = specs.iter().map(|s| s.hi - s.lo).collect();
        uncertainty_from_jacobian(&jac, &r0, k, &ranges).stderr
    };
    let r_test = residuals(robot, logs, test, set, x);
    let test_mae_per_log: Vec<f64> = r_test.iter().map(|v| mae(v)).collect();
    let test_mae = test_mae_per_log.iter().sum::<f64>() / test_mae_per_log.len().max(1) as f64;
    FitResult {
        effects: set.0.clone(),
        param_names: specs.iter().map(|s| s.name).collect(),
        param_units: specs.iter().map(|s| s.unit).collect(),
        x: x.to_vec(),
        stderr,
        train_mae,
        bic: bic(r0.len(), rss, k),
        test_mae_per_log,
        test_mae,
        evals: 0,
        seconds: 0.0,
    }
}

/// One tried candidate of a forward-selection round.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Trial {
    pub round: usize,
    pub effect: Effect,
    pub train_mae: f64,
    pub bic: f64,
    pub test_mae: f64,
    pub accepted: bool,
    /// Fitted parameters of the whole set (current effects + this one).
    pub x: Vec<f64>,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct FoldReport {
    pub held_out_kp: f64,
    pub train: Vec<usize>,
    pub test: Vec<usize>,
    pub nominal: FitResult,
    pub chosen: FitResult,
    pub trials: Vec<Trial>,
    pub seconds: f64,
}

/// Greedy forward selection: start from the nominal model; each round fits every remaining
/// candidate added to the current set (warm-started from the current optimum with the new
/// effect at its starting value; when that does not lower the training error the effect is
/// set to its neutral value, so adding an effect never worsens training), ranks them by training
/// BIC and accepts the first whose BIC is below the current one *and* whose held-out MAE
/// improves; stops when none qualifies. Candidates that did not lower the BIC are dropped for
/// the following rounds. The chosen set is finally refitted with `polish_evals` evaluations
/// (kept only when the training objective improves).
pub fn forward_select(
    robot: &Robot,
    logs: &[ServoLog],
    train: &[usize],
    test: &[usize],
    o: &FitOpts,
    progress: &(dyn Fn(&str) + Sync),
) -> FoldReport {
    let t0 = Instant::now();
    let mut set = EffectSet(vec![]);
    let mut x: Vec<f64> = vec![];
    let nominal = assess(robot, logs, train, test, &set, &x);
    progress(&format!(
        "  nominal: train {:.2}°  held-out {:.2}°  BIC {:.0}",
        nominal.train_mae.to_degrees(),
        nominal.test_mae.to_degrees(),
        nominal.bic
    ));
    let mut cur = nominal.clone();
    let mut trials = Vec::new();
    let mut remaining = o.candidates.clone();
    let mut round = 0;
    while !remaining.is_empty() {
        round += 1;
        let mut cands: Vec<(Effect, FitResult)> = Vec::new();
        for &e in &remaining {
            let ts = Instant::now();
            let mut s2 = set.clone();
            s2.0.push(e);
            let mut x0 = x.clone();
            x0.extend(e.params().iter().map(|p| p.init));
            let (mut xf, f, evals) = fit_set(robot, logs, train, &s2, &x0, o);
            if !(f < cur.train_mae) {
                // No training improvement from the exploratory start: the effect at its
                // neutral value reproduces the current model.
                xf = x.clone();
                xf.extend(e.params().iter().map(|p| p.neutral));
            }
            let mut r = assess(robot, logs, train, test, &s2, &xf);
            r.evals = evals;
            r.seconds = ts.elapsed().as_secs_f64();
            progress(&format!(
                "  round {round} +{:<11} train {:.2}°  held-out {:.2}°  BIC {:.0}  ({} evals, {:.1} s)",
                e.name(),
                r.train_mae.to_degrees(),
                r.test_mae.to_degrees(),
                r.bic,
                evals,
                r.seconds
            ));
            cands.push((e, r));
        }
        cands.sort_by(|a, b| a.1.bic.total_cmp(&b.1.bic));
        let pick = cands.iter().position(|(_, r)| r.bic < cur.bic && r.test_mae < cur.test_mae);
        for (k, (e, r)) in cands.iter().enumerate() {
            trials.push(Trial {
                round,
                effect: *e,
                train_mae: r.train_mae,
                bic: r.bic,
                test_mae: r.test_mae,
                accepted: Some(k) == pick,
                x: r.x.clone(),
            });
        }
        let cur_bic = cur.bic;
        let keep: Vec<Effect> =
            cands.iter().filter(|(_, r)| r.bic < cur_bic).map(|(e, _)| *e).collect();
        let Some(k) = pick else { break };
        let (e, r) = cands.swap_remove(k);
        progress(&format!("  → keep {} (held-out {:.2}°)", e.name(), r.test_mae.to_degrees()));
        set.0.push(e);
        x = r.x.clone();
        cur = r;
        remaining.retain(|&c| c != e && keep.contains(&c));
    }
    if o.polish_evals > 0 && !set.0.is_empty() {
        let ts = Instant::now();
        let p = FitOpts { max_evals: o.polish_evals, ..o.clone() };
        let (xf, f, evals) = fit_set(robot, logs, train, &set, &x, &p);
        if f < cur.train_mae {
            let mut r = assess(robot, logs, train, test, &set, &xf);
            r.evals = evals;
            r.seconds = ts.elapsed().as_secs_f64();
            progress(&format!(
                "  polish: train {:.2}°  held-out {:.2}°  BIC {:.0}  ({} evals, {:.1} s)",
                r.train_mae.to_degrees(),
                r.test_mae.to_degrees(),
                r.bic,
                evals,
                r.seconds
            ));
            cur = r;
        }
    }
    FoldReport {
        held_out_kp: test.first().map_or(f64::NAN, |&i| logs[i].kp),
        train: train.to_vec(),
        test: test.to_vec(),
        nominal,
        chosen: cur,
        trials,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// Training/held-out split holding out the logs of firmware gain `kp`.
pub fn split_by_kp(logs: &[ServoLog], kp: f64) -> (Vec<usize>, Vec<usize>) {
    (0..logs.len()).partition(|&i| logs[i].kp != kp)
}

/// Distinct firmware gains of the logs, ascending.
pub fn gains(logs: &[ServoLog]) -> Vec<f64> {
    let mut g: Vec<f64> = logs.iter().map(|l| l.kp).collect();
    g.sort_by(f64::total_cmp);
    g.dedup();
    g
}
