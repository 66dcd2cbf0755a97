//! The held-out gate: whether a change is beyond noise ([`verdict`], at the strength a [`Gate`]
//! asks), and whether a fit sits on a parameter bound ([`at_bound`]).

use crate::fit::effects::{Applied, JointTarget, model_with};
use crate::fit::stats::improvement_beyond_noise;

use super::Errors;
use super::engine::Engine;
use super::policy::SearchPolicy;

/// How strong a held-out comparison must be ([`SearchPolicy::gate`] and its variants).
#[derive(Debug, Clone, Copy)]
pub(super) struct Gate {
    /// z of the paired per-window test [standard errors].
    pub(super) z: f64,
    /// Relative improvement that passes without the z test (∞: never) [fraction].
    pub(super) decisive: f64,
    /// A window counts as improved or worsened beyond this relative change [fraction].
    pub(super) window_change: f64,
}

impl SearchPolicy {
    /// The gate between two fitted sets: `z_decision`, decisive improvements pass.
    pub(super) fn gate(&self) -> Gate {
        self.gate_z(self.z_decision)
    }

    /// The gate of a round's candidates: `z` ([`SearchPolicy::z_needed`]).
    pub(super) fn gate_z(&self, z: f64) -> Gate {
        Gate { z, decisive: self.decisive_improvement, window_change: self.window_change }
    }

    /// Only the paired z test (is a change worse beyond noise?).
    pub(super) fn noise_gate(&self) -> Gate {
        Gate { decisive: f64::INFINITY, ..self.gate() }
    }
}

/// Held-out comparison of `after` against `before` on the windows of `group`.
pub(super) struct Verdict {
    /// Mean ± s.e. of the paired per-window RMSE improvement [rad].
    pub(super) mean: f64,
    pub(super) se: f64,
    /// Relative held-out RMSE improvement over all fitted joints.
    pub(super) rel: f64,
    pub(super) significant: bool,
}

/// `significant`: the paired per-window improvement (absolute, or of the log error) exceeds
/// `gate.z` standard errors, or the improvement is decisive (relative ≥ `gate.decisive` over
/// all joints or over the group's windows, with more than twice as many windows improved as
/// worsened).
pub(super) fn verdict(before: &Errors, after: &Errors, group: &[String], gate: Gate) -> Verdict {
    let Gate { z, decisive, window_change } = gate;
    let on = |w: &[(String, f64)]| {
        w.iter().filter(|(j, _)| group.contains(j)).map(|(_, v)| *v).collect::<Vec<f64>>()
    };
    let (wb, wa) = (on(&before.windows), on(&after.windows));
    let (mean, se, _) = improvement_beyond_noise(&wb, &wa);
    let ln = |w: &[f64]| w.iter().map(|v| v.max(1e-12).ln()).collect::<Vec<f64>>();
    let (lmean, lse, _) = improvement_beyond_noise(&ln(&wb), &ln(&wa));
    let beyond = |m: f64, s: f64| m > 0.0 && m > z * s;
    let rel = (before.rmse() - after.rmse()) / before.rmse().max(1e-300);
    let (mut up, mut down) = (0usize, 0usize);
    // A window counts as improved or worsened when it changes by more than `window_change` (a
    // limit reached a few times leaves the other windows of a lightly damped servo changed by
    // less, either way).
    for (b, a) in wb.iter().zip(&wa) {
        let tol = window_change * b.abs();
        if b - a > tol {
            up += 1;
        } else if a - b > tol {
            down += 1;
        }
    }
    // Decisive on the group's own windows: a limit reached at the steps of one knee of twelve
    // joints halves that knee's held-out error but only 48 % of the whole (the other eleven sit
    // at the noise floor).
    let rms = |w: &[f64]| (w.iter().map(|v| v * v).sum::<f64>() / w.len().max(1) as f64).sqrt();
    let rel_group = (rms(&wb) - rms(&wa)) / rms(&wb).max(1e-300);
    let decisive_ok = rel.max(rel_group) >= decisive && up > 2 * down;
    Verdict { mean, se, rel, significant: beyond(mean, se) || beyond(lmean, lse) || decisive_ok }
}

/// A fitted parameter this close to a bound sits on it [fraction of the range, of ln p on a
/// log scale].
const AT_BOUND: f64 = 5e-3;
/// The same to a lower bound where the effect is absent: the line search's resolution [fraction].
const AT_ABSENT: f64 = 2e-4;

/// `true` when a fitted parameter of `a` sits on its bound (within 0.5 % of the range, of ln p
/// for an effect searched on a log scale — a 0.25 N·m torque limit is not at the 0.05 N·m
/// bound): the effect was stretched to explain something else.
///
/// A lower bound where the effect is absent (the value it starts from, e.g. no friction in a
/// model without any) is not a limit the data push against: a small effect sits near it. There
/// the tolerance is the 1-D search's resolution (0.02 % of the range): Coulomb friction of
/// 0.02 N·m on [0, 5] N·m is a small friction, not a fit stuck at zero (with 0.5 % it counted
/// as on its bound, and a worse interior rival won the round).
pub(super) fn at_bound(engine: &Engine, base: &[Applied], a: &Applied) -> bool {
    let Some(t) = JointTarget::of(engine.robot, &a.joints[0]) else { return false };
    let m0 = model_with(engine.robot, base);
    let (lo, hi) = a.effect.bounds(&m0, &t);
    let start = a.effect.initial(&m0, &t);
    let log = a.effect.log_search() && a.effect.fitted() == 1;
    (0..a.effect.fitted().min(a.params.len())).any(|k| {
        let absent_lo = start.get(k).is_some_and(|&s| s == lo[k]);
        let (p, lo, hi) = if log && lo[k] > 0.0 && a.params[k] > 0.0 {
            (a.params[k].ln(), lo[k].ln(), hi[k].ln())
        } else {
            (a.params[k], lo[k], hi[k])
        };
        let tol = AT_BOUND * (hi - lo);
        let tol_lo = if absent_lo { AT_ABSENT * (hi - lo) } else { tol };
        p <= lo + tol_lo || p >= hi - tol
    })
}

/// Whether `applied` replays the held-out `heldout` closer than `rival` beyond noise: the gate
/// between two fitted sets ([`SearchPolicy::gate`]) on every recorded joint's windows, as an
/// effect must pass against the set without it. `None` when either replay fails.
pub fn beats_beyond_noise(
    engine: &Engine,
    heldout: &[crate::sim2real::recording::Recording],
    rival: &[Applied],
    applied: &[Applied],
) -> Option<bool> {
    let (b, a) = (engine.errors(heldout, rival)?, engine.errors(heldout, applied)?);
    let mut joints: Vec<String> = Vec::new();
    for j in heldout.iter().flat_map(|r| &r.joints) {
        if !joints.contains(&j.name) {
            joints.push(j.name.clone());
        }
    }
    Some(verdict(&b, &a, &joints, engine.opts.policy.gate()).significant)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::{CoulombFriction, Effect, TorqueLimit, ViscousDamping};

    /// A torque limit is searched on ln T, and "on the bound" is judged there too: 0.25 N·m (a
    /// hobby servo's limit) is inside [0.05, 50], 0.0505 and 49.5 are on it.
    #[test]
    fn log_scale_bound_for_a_torque_limit() {
        use crate::fit::effects::{by_id, hinge_recording, hinge_robot};
        let dir = std::env::temp_dir().join(format!("modellint-bound-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let robot = hinge_robot(&dir, "m.xml", "", "", r#"kp="5""#);
        let rec = hinge_recording(vec![0.0, 0.01, 0.02], vec![0.0; 3]);
        let opts = super::super::FitOptions::default();
        let engine = Engine::new(&robot, std::slice::from_ref(&rec), &opts);
        let limit = |v: f64| Applied {
            effect: by_id(TorqueLimit.id()).unwrap(),
            joints: vec!["j".into()],
            params: vec![v, 1e4, 1e4],
        };
        assert!(!at_bound(&engine, &[], &limit(0.25)));
        assert!(!at_bound(&engine, &[], &limit(2.0)));
        assert!(at_bound(&engine, &[], &limit(0.0505)));
        assert!(at_bound(&engine, &[], &limit(49.5)));
        // A linear-scale parameter keeps the linear rule: damping on its lower bound.
        let damping = Applied {
            effect: by_id(ViscousDamping.id()).unwrap(),
            joints: vec!["j".into()],
            params: vec![0.0],
        };
        assert!(at_bound(&engine, &[], &damping));
        // Where the effect is absent (no friction in the model: the lower bound), a small
        // friction is not on the bound; one at the 1-D search's resolution is.
        let friction = |v: f64| Applied {
            effect: by_id(CoulombFriction.id()).unwrap(),
            joints: vec!["j".into()],
            params: vec![v],
        };
        assert!(!at_bound(&engine, &[], &friction(0.02)));
        assert!(at_bound(&engine, &[], &friction(0.0005)));
        assert!(at_bound(&engine, &[], &friction(4.99)));
        std::fs::remove_dir_all(&dir).ok();
    }

    fn errs(w: &[f64]) -> Errors {
        let sse: f64 = w.iter().map(|v| v * v * 10.0).sum();
        Errors {
            sse,
            n: 10 * w.len(),
            windows: w.iter().map(|v| ("a".to_string(), *v)).collect(),
            eps: vec![],
        }
    }

    #[test]
    fn verdict_paired_decisive_and_noise() {
        let g = vec!["a".to_string()];
        // Consistent 10 % improvement in every window: significant by the paired test.
        let before: Vec<f64> = (0..16).map(|i| 1.0 + 0.05 * (i % 3) as f64).collect();
        let after: Vec<f64> = before.iter().map(|v| 0.9 * v).collect();
        assert!(
            verdict(&errs(&before), &errs(&after), &g, SearchPolicy::default().gate()).significant
        );
        // A saturation event: 3 of 16 windows improve 20-fold, the rest are unchanged. The
        // paired tests fail (too few informative windows), the decisive path accepts.
        let mut before = vec![1.0; 16];
        let mut after = vec![1.0; 16];
        for (i, big) in [(2, 40.0), (7, 25.0), (11, 60.0)] {
            before[i] = big;
            after[i] = 1.0;
        }
        assert!(
            !verdict(&errs(&before), &errs(&after), &g, SearchPolicy::default().noise_gate())
                .significant
        );
        assert!(
            verdict(&errs(&before), &errs(&after), &g, SearchPolicy::default().gate()).significant
        );
        // Noise: as many windows worse as better, tiny mean change: not significant.
        let before: Vec<f64> = (0..16).map(|i| 1.0 + 0.01 * ((i * 7) % 5) as f64).collect();
        let after: Vec<f64> = before
            .iter()
            .enumerate()
            .map(|(i, v)| v + if i % 2 == 0 { 0.01 } else { -0.011 })
            .collect();
        assert!(
            !verdict(&errs(&before), &errs(&after), &g, SearchPolicy::default().gate()).significant
        );
        // A big improvement on one window and worse on most others is not decisive.
        let mut after = before.clone();
        after[0] = 0.0;
        for v in after.iter_mut().skip(1).take(8) {
            *v *= 1.05;
        }
        let mut b2 = before.clone();
        b2[0] = 10.0;
        assert!(
            !verdict(&errs(&b2), &errs(&after), &g, SearchPolicy::default().gate()).significant
        );
    }

    /// Windows of several joints: `(joint, value)`.
    fn errs_of(w: &[(&str, f64)]) -> Errors {
        Errors {
            sse: w.iter().map(|(_, v)| v * v * 10.0).sum(),
            n: 10 * w.len(),
            windows: w.iter().map(|(j, v)| (j.to_string(), *v)).collect(),
            eps: vec![],
        }
    }

    #[test]
    fn decisive_on_the_group_not_diluted_by_joints_at_the_floor() {
        // A knee whose 16 windows have a floor of 1 and three saturation events (error 5),
        // which the effect removes, among eleven joints at the floor of 1 that it does not
        // touch. Over all joints the RMSE falls by under 50 %; on the knee by 62 %.
        let mut before = Vec::new();
        let mut after = Vec::new();
        for j in 0..12 {
            let name = if j == 0 { "knee" } else { "other" };
            for i in 0..16 {
                let big = j == 0 && [3, 8, 13].contains(&i);
                before.push((name, if big { 5.0 } else { 1.0 }));
                after.push((name, 1.0));
            }
        }
        let (b, a) = (errs_of(&before), errs_of(&after));
        let knee = vec!["knee".to_string()];
        let v = verdict(&b, &a, &knee, SearchPolicy::default().gate());
        assert!(v.rel < 0.5, "overall {:.3}", v.rel);
        assert!(v.significant);
        // The same change judged over every joint's windows is not decisive.
        let all = vec!["knee".to_string(), "other".to_string()];
        assert!(!verdict(&b, &a, &all, SearchPolicy::default().gate()).significant);
        // Nor on the knee when it worsens as many windows as it improves.
        let mut worse = after.clone();
        for (i, w) in worse.iter_mut().take(16).enumerate() {
            if ![3, 8, 13].contains(&i) && i % 2 == 0 {
                w.1 = 1.1;
            }
        }
        assert!(!verdict(&b, &errs_of(&worse), &knee, SearchPolicy::default().gate()).significant);
    }
}
