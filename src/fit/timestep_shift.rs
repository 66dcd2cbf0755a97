//! How much of a fitted value is the model's timestep.
//!
//! Recordings of hardware move in continuous time (or a simulator's finer step); a parameter
//! fitted by replaying them at the model's timestep also absorbs the model's discretisation,
//! and its standard error (the data's scatter at that step) does not include that bias: a
//! two-joint arm's elbow damping, truly 0.35 N·m·s/rad, fitted at 2 ms against a recording at
//! 0.5 ms came out 11 % high with a ± that excluded the truth.
//!
//! When the search counts the timestep as floor (the recordings are closer to the finer replay,
//! [`crate::fit::select::Floor::discretisation`]), or a kept effect fitted a time shorter than
//! the model's step (a delay below one step is the size of the integrator's own lag behind
//! continuous time, which no floor sees once the delay has taken it up), the kept effects are
//! re-fitted, told, at the timestep check's finer step ([`crate::sim2real::replay::REFINE`]
//! times finer), and the change of every parameter from the reported value is given as a
//! systematic error beside the ±. No threshold: every kept parameter is listed with its shift
//! in units of its s.e. The re-fit costs a told fit at the finer step (several times the
//! search's own replays on a pendulum), which is why it does not run on every fit.
//!
//! An effect whose re-fit at the finer step is within [`Z_ABSENT`](crate::fit::absent::Z_ABSENT) standard errors of the model
//! as given ([`within_uncertainty`], the rule for any kept effect) was the timestep, not missing
//! physics: [`split_off`] moves it to a note (a 0.9 ms delay on a leg whose 2 ms model lags its
//! 0.5 ms recording by 0.9 ms: 0.0 ms at 0.5 ms).
//!
//! What the re-fit replays is added to the search's cost (phase `timestep_shift`), so
//! `search.simulated_s` is the whole run's.

use crate::fit::absent::within_uncertainty;
use crate::fit::select::{FitOptions, FitOutcome, SearchCost, Selected, chord, fit};

/// The phase the re-fit's replays are booked to.
const PHASE: &str = "timestep_shift";
use crate::model::Robot;
use crate::sim2real::recording::Recording;

/// One kept parameter as reported (fitted at the model's timestep) and re-fitted at the finer one.
#[derive(Debug, Clone)]
pub struct Shift {
    pub effect: String,
    pub joints: Vec<String>,
    pub param: String,
    /// The parameter's unit (`Param::unit`; empty for a dimensionless one).
    pub unit: String,
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
    /// Recording seconds the re-fit replayed.
    pub simulated_s: f64,
    /// Chord Gauss–Newton steps of the re-fit ([`chord::refit`]); `None`: a told fit.
    pub chord_steps: Option<usize>,
    /// The kept effects (effect, joints) whose re-fit at the finer step is the model as given
    /// within [`Z_ABSENT`](crate::fit::absent::Z_ABSENT) standard errors, with their values at
    /// the finer step.
    pub timestep_only: Vec<(String, Vec<String>, String)>,
}

/// The shifts of `out`'s kept parameters between the model's timestep and a finer one; `None`
/// when nothing is kept, neither the floors nor a fitted time shorter than the step point at
/// the timestep, or the model's actuators have a MuJoCo `delay` (its history buffer is sized
/// for the model's timestep).
/// Whenever the re-fit ran, its cost is added to `out.cost` ([`add_cost`]).
pub fn measure(
    robot: &Robot,
    recs: &[Recording],
    opts: &FitOptions,
    out: &mut FitOutcome,
) -> Option<TimestepShift> {
    let dt = robot.opt.timestep;
    let delayed = robot.mj.actuator_history().iter().any(|h| h[0] > 0);
    let in_floor = out.floors.iter().any(|f| f.discretisation > 0.0);
    if out.selected.is_empty() || !(dt > 0.0) || delayed || !(in_floor || shorter_than(out, dt)) {
        return None;
    }
    let fine_dt = dt / crate::sim2real::replay::REFINE;
    let mut fine = robot.clone();
    fine.mj.opt_mut().timestep = fine_dt;
    fine.opt.timestep = fine_dt;
    let (at_fine, chord_steps) = refit(&fine, recs, opts, out);
    let mut shifts = Vec::new();
    let mut timestep_only = Vec::new();
    for x in &out.selected {
        let Some(y) = at_fine.iter().find(|y| y.effect == x.effect && y.joints == x.joints) else {
            continue;
        };
        if within_uncertainty(&fine, y).is_some() {
            timestep_only.push((x.effect.clone(), x.joints.clone(), values(y)));
        }
        for (k, v) in &x.params {
            if let Some(w) = y.params.get(k) {
                shifts.push(Shift {
                    effect: x.effect.clone(),
                    joints: x.joints.clone(),
                    param: k.clone(),
                    unit: crate::fit::effects::by_id(&x.effect)
                        .and_then(|e| e.params().iter().find(|p| p.name == k))
                        .map_or(String::new(), |p| p.unit.to_string()),
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
    let simulated_s = out.cost.simulated_s_by_phase.get(PHASE).copied().unwrap_or(0.0);
    Some(TimestepShift {
        timestep: dt,
        fine_timestep: fine_dt,
        shifts,
        simulated_s,
        timestep_only,
        chord_steps,
    })
}

/// The kept effects re-fitted with `fine` (the model at the finer step), as the search's
/// `selected` records with the values and standard errors there, and the number of chord steps
/// when the re-fit was [`chord::refit`]. That runs first, from the final standard errors'
/// Jacobian when it belongs to the kept set as it is; when it does not confirm, the kept
/// effects are fitted told at the finer step, each from its answer. Every replay is added to
/// `out.cost` ([`add_cost`]).
fn refit(
    fine: &Robot,
    recs: &[Recording],
    opts: &FitOptions,
    out: &mut FitOutcome,
) -> (Vec<Selected>, Option<usize>) {
    let o = FitOptions { progress: None, ..opts.clone() };
    let jac =
        out.jacobian.take().filter(|j| format!("{:?}", j.applied) == format!("{:?}", out.applied));
    if let Some(j) = &jac {
        let (c, cost) = chord::refit(fine, &out.train, &o, j);
        add_cost(&mut out.cost, &cost);
        if let Some(c) = c {
            let at_fine = out
                .selected
                .iter()
                .filter_map(|x| {
                    let i = c
                        .applied
                        .iter()
                        .position(|a| a.effect.id() == x.effect && a.joints == x.joints)?;
                    let mut y = x.clone();
                    y.values = c.applied[i].params.clone();
                    let names = c.applied[i].effect.params().iter().map(|d| d.name.to_string());
                    y.params = names
                        .clone()
                        .zip(y.values.iter().copied())
                        .take(c.applied[i].effect.fitted())
                        .collect();
                    y.stderr = names.zip(c.stderr[i].0.iter().copied()).collect();
                    Some(y)
                })
                .collect();
            out.jacobian = jac;
            return (at_fine, Some(c.steps));
        }
    }
    out.jacobian = jac;
    let told = out.selected.iter().map(|s| (s.effect.clone(), s.joints.clone())).collect();
    // Each re-fit starts at its answer at the model's step: the finer step moves it a little.
    let told_start = out.selected.iter().map(|s| s.values.clone()).collect();
    let b = fit(fine, recs, &FitOptions { told, told_start, ..o });
    add_cost(&mut out.cost, &b.cost);
    (b.selected, None)
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
    cost.book_after(PHASE, r.rollouts, r.simulated_s);
}

/// Some kept effect has a fitted time (a parameter in seconds) shorter than `dt`.
fn shorter_than(out: &FitOutcome, dt: f64) -> bool {
    out.selected.iter().any(|s| {
        crate::fit::effects::by_id(&s.effect).is_some_and(|e| {
            e.params()
                .iter()
                .take(e.fitted())
                .any(|d| d.unit == "s" && s.params.get(d.name).is_some_and(|v| v.abs() < dt))
        })
    })
}

/// Moves the kept effects that re-fit at the finer step to the model as given
/// ([`TimestepShift::timestep_only`]) out of `selected`; returns their notes (in order).
pub fn split_off(s: &TimestepShift, selected: &mut Vec<Selected>) -> Vec<String> {
    let mut notes = Vec::new();
    selected.retain(|x| {
        let Some((_, _, at_fine)) =
            s.timestep_only.iter().find(|(e, j, _)| *e == x.effect && *j == x.joints)
        else {
            return true;
        };
        notes.push(format!(
            "{} on {}: {} at the model's {:.3} ms step, {at_fine} re-fitted at {:.3} ms — within {} standard errors of the model as given there, so it is the timestep, not missing physics (it stays in the fitted replay)",
            x.effect,
            x.joints.join(","),
            values(x),
            1e3 * s.timestep,
            1e3 * s.fine_timestep,
            crate::fit::absent::Z_ABSENT
        ));
        false
    });
    notes
}

/// `name = value ± se, …` of a fit's parameters.
fn values(x: &Selected) -> String {
    let shown: Vec<String> = x
        .params
        .iter()
        .map(|(k, v)| match x.stderr.get(k) {
            Some(se) if se.is_finite() => format!("{k} = {v:.4} ± {se:.2e}"),
            _ => format!("{k} = {v:.4}"),
        })
        .collect();
    shown.join(", ")
}

/// The note: each parameter's value at both timesteps and the shift between them, in the
/// parameter's own unit and in its s.e. (not as a % of the finer value, which is meaningless
/// when that value is near zero).
pub fn note(s: &TimestepShift) -> String {
    let list: Vec<String> = s
        .shifts
        .iter()
        .map(|x| {
            let d = x.coarse - x.fine;
            let u = if x.unit.is_empty() { String::new() } else { format!(" {}", x.unit) };
            let se = if x.stderr.is_finite() && x.stderr > 0.0 {
                format!("{:.1}× its s.e. {:.2e}{u}", d.abs() / x.stderr, x.stderr)
            } else {
                "s.e. unknown".to_string()
            };
            format!(
                "{} {} on {}: {:.4} at {:.3} ms, {:.4} at {:.3} ms (shift {:+.2e}{u}, {se})",
                x.effect,
                x.param,
                x.joints.join(","),
                x.coarse,
                1e3 * s.timestep,
                x.fine,
                1e3 * s.fine_timestep,
                d
            )
        })
        .collect();
    let how = match s.chord_steps {
        Some(n) => format!(
            "by {n} Gauss–Newton step{} from the reported values with their Jacobian at the \
             model's step",
            if n == 1 { "" } else { "s" }
        ),
        None => "told".to_string(),
    };
    format!(
        "the fitted values absorb the model's timestep: the recordings move in finer time than \
         its {:.3} ms step, and the kept effects re-fitted ({how}) at {:.3} ms give: {}. The \
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
                unit: "kg".into(),
                coarse: 0.44,
                fine: 0.40,
                stderr: 0.01,
            }],
            simulated_s: 515.0,
            timestep_only: Vec::new(),
            chord_steps: Some(2),
        };
        let n = note(&s);
        assert!(
            n.contains("e p on elbow: 0.4400 at 2.000 ms, 0.4000 at 0.500 ms (shift +4.00e-2 kg, 4.0× its s.e. 1.00e-2 kg)"),
            "{n}"
        );
        assert!(n.contains("515 s of recording replayed"), "{n}");
        assert!(n.contains("re-fitted (by 2 Gauss–Newton steps from the reported values"), "{n}");
    }

    fn kept(effect: &str, delay: f64) -> Selected {
        Selected {
            effect: effect.into(),
            joints: vec!["knee".into()],
            params: [("delay_s".to_string(), delay)].into(),
            stderr: [("delay_s".to_string(), 2e-5)].into(),
            identifiable: true,
            unidentified: vec![],
            evidence: Default::default(),
            heldout_improvement: 0.1,
            heldout_rmse_before: 1.0,
            heldout_rmse_after: 0.9,
            window_improvement: 0.0,
            window_improvement_se: 0.0,
            bic_before: 0.0,
            bic_after: 0.0,
            values: vec![delay],
        }
    }

    #[test]
    fn an_effect_that_is_the_model_as_given_at_the_finer_step_leaves_the_list_with_a_note() {
        let s = TimestepShift {
            timestep: 0.002,
            fine_timestep: 0.0005,
            shifts: vec![],
            simulated_s: 100.0,
            chord_steps: None,
            timestep_only: vec![(
                "action_delay".into(),
                vec!["knee".into()],
                "delay_s = 0.0000 ± 5.93e-6".into(),
            )],
        };
        let mut selected = vec![kept("action_delay", 0.00088), kept("other", 0.01)];
        let notes = split_off(&s, &mut selected);
        assert_eq!(selected.len(), 1);
        assert_eq!(selected[0].effect, "other");
        assert_eq!(notes.len(), 1);
        assert!(
            notes[0].contains("delay_s = 0.0009 ± 2.00e-5 at the model's 2.000 ms step, delay_s = 0.0000 ± 5.93e-6 re-fitted at 0.500 ms"),
            "{}",
            notes[0]
        );
        assert!(notes[0].contains("it is the timestep, not missing physics"), "{}", notes[0]);
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
        assert_eq!(cost.simulated_s_by_round.get("end"), Some(&141.0));
        assert_eq!(cost.rollouts_by_round.get("end"), Some(&30));
    }
}
