//! How much of a fitted value is the model's timestep.
//!
//! Recordings of hardware move in continuous time (or a simulator's finer step); a parameter
//! fitted by replaying them at the model's timestep also absorbs the model's discretisation,
//! and its standard error (the data's scatter at that step) does not include that bias: a
//! two-joint arm's elbow damping, truly 0.35 N·m·s/rad, fitted at 2 ms against a recording at
//! 0.5 ms came out 11 % high with a ± that excluded the truth.
//!
//! When the search counts the timestep as floor (the recordings are closer to the finer replay,
//! [`crate::fit::select::Floor::discretisation`]), the kept effects are re-fitted, told, at the
//! timestep check's finer step ([`crate::sim2real::replay::REFINE`] times finer), and the
//! change of every parameter from the reported value is given as a systematic error beside the
//! ±. No threshold: every kept parameter is listed with its shift in units of its s.e. What the
//! re-fit replays is added to the search's cost (phase `timestep_shift`), so `search.simulated_s`
//! is the whole run's.

use crate::fit::select::{FitOptions, FitOutcome, SearchCost, fit};
use crate::model::Robot;
use crate::sim2real::recording::Recording;

/// One kept parameter as reported (fitted at the model's timestep) and re-fitted at the finer one.
#[derive(Debug, Clone)]
pub struct Shift {
    pub effect: String,
    pub joints: Vec<String>,
    pub param: String,
    /// The reported value (the search's, at the model's timestep).
    pub coarse: f64,
    /// Told fit at the finer timestep.
    pub fine: f64,
    /// The reported standard error.
    pub stderr: f64,
}

/// The told re-fit of the kept effects at the finer timestep.
#[derive(Debug, Clone)]
pub struct TimestepShift {
    pub timestep: f64,
    pub fine_timestep: f64,
    pub shifts: Vec<Shift>,
    /// Recording seconds the told re-fit replayed.
    pub simulated_s: f64,
}

/// The shifts of `out`'s kept parameters between the model's timestep and a finer one; `None`
/// when nothing is kept, the search did not count the timestep as floor, or the model's
/// actuators have a MuJoCo `delay` (its history buffer is sized for the model's timestep).
/// Whenever the re-fit ran, its cost is added to `out.cost` ([`add_cost`]).
pub fn measure(
    robot: &Robot,
    recs: &[Recording],
    opts: &FitOptions,
    out: &mut FitOutcome,
) -> Option<TimestepShift> {
    let dt = robot.opt.timestep;
    let delayed = robot.mj.actuator_history().iter().any(|h| h[0] > 0);
    if out.selected.is_empty()
        || !out.floors.iter().any(|f| f.discretisation > 0.0)
        || !(dt > 0.0)
        || delayed
    {
        return None;
    }
    let fine_dt = dt / crate::sim2real::replay::REFINE;
    let mut fine = robot.clone();
    fine.mj.opt_mut().timestep = fine_dt;
    fine.opt.timestep = fine_dt;
    let told = out.selected.iter().map(|s| (s.effect.clone(), s.joints.clone())).collect();
    let o = FitOptions { told, progress: None, ..opts.clone() };
    let b = fit(&fine, recs, &o);
    add_cost(&mut out.cost, &b.cost);
    let mut shifts = Vec::new();
    for x in &out.selected {
        let Some(y) = b.selected.iter().find(|y| y.effect == x.effect && y.joints == x.joints)
        else {
            continue;
        };
        for (k, v) in &x.params {
            if let Some(w) = y.params.get(k) {
                shifts.push(Shift {
                    effect: x.effect.clone(),
                    joints: x.joints.clone(),
                    param: k.clone(),
                    coarse: *v,
                    fine: *w,
                    stderr: x.stderr.get(k).copied().unwrap_or(f64::NAN),
                });
            }
        }
    }
    if shifts.is_empty() {
        return None;
    }
    let simulated_s = b.cost.rollouts.simulated_s;
    Some(TimestepShift { timestep: dt, fine_timestep: fine_dt, shifts, simulated_s })
}

/// Adds the told re-fit's cost `refit` (all its phases) to the search's `cost`, as phase
/// `timestep_shift`.
fn add_cost(cost: &mut SearchCost, refit: &SearchCost) {
    cost.simulations += refit.simulations;
    let (c, r) = (&mut cost.rollouts, &refit.rollouts);
    c.rollouts += r.rollouts;
    c.batches += r.batches;
    c.seconds += r.seconds;
    c.simulated_s += r.simulated_s;
    *cost.rollouts_by_phase.entry("timestep_shift").or_default() += r.rollouts;
    let s = cost.simulated_s_by_phase.entry("timestep_shift").or_default();
    *s = ((*s + r.simulated_s) * 10.0).round() / 10.0;
}

/// The note: each parameter's value at both timesteps, the change in % and in its s.e.
pub fn note(s: &TimestepShift) -> String {
    let list: Vec<String> = s
        .shifts
        .iter()
        .map(|x| {
            let d = x.coarse - x.fine;
            let rel = if x.fine != 0.0 {
                format!("{:+.1} % of the finer value, ", 100.0 * d / x.fine.abs())
            } else {
                String::new()
            };
            let se = if x.stderr.is_finite() && x.stderr > 0.0 {
                format!("{:.1}× its s.e. {:.2e}", d.abs() / x.stderr, x.stderr)
            } else {
                "s.e. unknown".to_string()
            };
            format!(
                "{} {} on {}: {:.4} at {:.3} ms, {:.4} at {:.3} ms ({rel}{se})",
                x.effect,
                x.param,
                x.joints.join(","),
                x.coarse,
                1e3 * s.timestep,
                x.fine,
                1e3 * s.fine_timestep
            )
        })
        .collect();
    format!(
        "the fitted values absorb the model's timestep: the recordings move in finer time than \
         its {:.3} ms step, and the kept effects re-fitted (told) at {:.3} ms give: {}. The \
         difference is a systematic error the ± (the data's scatter at the model's step) does \
         not include; a smaller timestep in the model removes it ({:.0} s of recording \
         replayed for this check)",
        1e3 * s.timestep,
        1e3 * s.fine_timestep,
        list.join("; "),
        s.simulated_s
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_note_gives_both_values_the_change_and_its_standard_errors() {
        let s = TimestepShift {
            timestep: 0.002,
            fine_timestep: 0.0005,
            shifts: vec![Shift {
                effect: "e".into(),
                joints: vec!["elbow".into()],
                param: "p".into(),
                coarse: 0.44,
                fine: 0.40,
                stderr: 0.01,
            }],
            simulated_s: 515.0,
        };
        let n = note(&s);
        assert!(
            n.contains("e p on elbow: 0.4400 at 2.000 ms, 0.4000 at 0.500 ms (+10.0 % of the finer value, 4.0× its s.e. 1.00e-2)"),
            "{n}"
        );
        assert!(n.contains("515 s of recording replayed"), "{n}");
    }

    /// The re-fit's replays are the run's: every counter of the search's cost grows by the
    /// re-fit's, and the phase `timestep_shift` holds them.
    #[test]
    fn the_refit_cost_is_added_to_the_search_cost() {
        use crate::fit::rollout::RolloutStats;
        let stats = |rollouts, batches, simulated_s| RolloutStats {
            rollouts,
            batches,
            seconds: 0.0,
            simulated_s,
        };
        let mut cost = SearchCost {
            simulations: 10,
            rollouts: stats(100, 0, 700.0),
            simulated_s_by_phase: [("add", 700.0)].into(),
            ..SearchCost::default()
        };
        let refit = SearchCost {
            simulations: 3,
            rollouts: stats(30, 4, 141.04),
            simulated_s_by_phase: [("told", 141.04)].into(),
            ..SearchCost::default()
        };
        add_cost(&mut cost, &refit);
        assert_eq!(cost.simulations, 13);
        assert_eq!(cost.rollouts.rollouts, 130);
        assert_eq!(cost.rollouts.batches, 4);
        assert!((cost.rollouts.simulated_s - 841.04).abs() < 1e-9);
        assert_eq!(cost.simulated_s_by_phase.get("timestep_shift"), Some(&141.0));
        assert_eq!(cost.rollouts_by_phase.get("timestep_shift"), Some(&30));
        assert_eq!(cost.simulated_s_by_phase.get("add"), Some(&700.0));
    }
}
