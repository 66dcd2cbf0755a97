//! A re-fit of an answer on the same recordings with the model at other settings (the timestep
//! check's finer step, [`crate::fit::timestep_shift`]) by Gauss–Newton steps from the answer
//! whose first Jacobian is the one its standard errors were computed from ([`Jacobian`],
//! measured at the model's own settings) and whose residual is replayed at the new settings: one
//! replay of the training set for the residual at the answer and one per step, none for a
//! derivative.
//!
//! A step is `−J⁺ r`. Each is replayed and confirmed when the training error does not grow; the
//! columns are then corrected by the step's secant (Broyden's update,
//! [`Jacobian::secant`]): a finite difference at the answer (0.1 % of a parameter's range) is
//! a poor slope for a non-smooth effect — a backlash's column across its kinks made steps
//! that shrank by a fifth each and overshot the new optimum — while the secant spans a step
//! of the size the settings move the answer. The iteration ends at the first point whose next
//! step moves every parameter by less than [`ROLLOUT_STAT_TOL`] of its standard error (the
//! statistical stop of a least-squares fit on rollouts: the data do not tell such points
//! apart), or at a point whose next step, shorter than one standard error on every parameter
//! ([`UNRESOLVED`]), the replay finds worse (KR6's backlash at 0.25 ms: 0.04131 → 0.04047 →
//! 0.03994, then a step of 0.17 s.e. 0.2 % worse: the rollout objective's ripple at the kinks);
//! its standard errors are the first Jacobian's with the new settings' residual. Any other step
//! not confirmed, a failed replay, or no such point within `screen_evals` steps (the budget of
//! a coarse fit: a settings change that moves the answer farther than that is not small)
//! answers `None`, and the caller runs the full told fit.

use crate::fit::effects::Applied;
use crate::fit::optim::ROLLOUT_STAT_TOL;
use crate::model::Robot;
use crate::sim2real::recording::Recording;

use super::{Engine, FitOptions, Jacobian, SearchCost};

/// A step shorter than this on every parameter that the replay finds worse ends the iteration
/// at the point it started from [standard errors]: points a standard error apart are what
/// the data barely tell apart.
const UNRESOLVED: f64 = 1.0;

/// The answer re-fitted by [`refit`].
#[derive(Debug, Clone)]
pub struct ChordFit {
    /// The Jacobian's set at the re-fitted values.
    pub applied: Vec<Applied>,
    /// Standard errors of each effect's fitted parameters there (by index of `applied`).
    pub stderr: Vec<(Vec<f64>, Vec<bool>)>,
    /// Steps taken (each one replay of the training set, beside the first residual's).
    pub steps: usize,
}

/// Re-fits `jac.applied` on `train` with `robot` (the search's model at other settings) from
/// `jac`, the Jacobian of its answer at the search's own settings; `None` when the chord
/// iteration does not confirm (see the module). The replays are counted either way.
pub fn refit(
    robot: &Robot,
    train: &[Recording],
    opts: &FitOptions,
    jac: &Jacobian,
) -> (Option<ChordFit>, SearchCost) {
    let held = crate::sim2real::replay::held(robot, opts.replay.base);
    let robot = held.as_ref().unwrap_or(robot);
    let engine = Engine::new(robot, train, opts);
    let fit = chord(&engine, train, jac);
    let cost = SearchCost {
        simulations: engine.simulations(),
        rollouts: engine.rollout_stats(),
        ..SearchCost::default()
    };
    (fit, cost)
}

fn chord(engine: &Engine, train: &[Recording], jac: &Jacobian) -> Option<ChordFit> {
    let budget = engine.opts.policy.screen_evals.max(1);
    let sum_sq = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    // The columns the steps are taken with: the answer's, corrected by each step's secant.
    let mut j = jac.clone();
    let mut set = jac.applied.clone();
    let mut r = engine.residuals_like(train, &set, jac)?;
    let mut ss = sum_sq(&r);
    for steps in 0..=budget {
        let se = jac.stderr(&r);
        let dx = j.step(&r)?;
        if j.within(&dx, &se, ROLLOUT_STAT_TOL) {
            return Some(ChordFit { applied: set, stderr: se, steps });
        }
        if steps == budget {
            return None;
        }
        let next = j.moved(&set, &dx);
        let r1 = engine.residuals_like(train, &next, jac)?;
        let ss1 = sum_sq(&r1);
        if !(ss1 <= ss) {
            // Worse within a standard error of the point: the objective's roughness at a scale
            // the data do not resolve (a backlash's kinks), and the point stands.
            let rough = j.within(&dx, &se, UNRESOLVED);
            return rough.then_some(ChordFit { applied: set, stderr: se, steps });
        }
        let dr: Vec<f64> = r1.iter().zip(&r).map(|(a, b)| a - b).collect();
        j.secant(&j.taken(&set, &next), &dr);
        (set, r, ss) = (next, r1, ss1);
    }
    None
}
