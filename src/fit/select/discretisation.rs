//! The held-out gate at a finer timestep: an effect that only makes up for the model's own time
//! discretisation is reported as a note, not as missing physics.
//!
//! A real robot moves in continuous time; MuJoCo steps its model at `dt` (semi-implicit Euler
//! or another fixed-step method), which on a lightly damped servo looks like a sub-millisecond
//! action delay or a little armature. A candidate that passed the held-out gate at `dt` is
//! judged again with both sides replayed at `dt / r²` ([`SearchPolicy::discretisation_refine`]),
//! where the integration error is a
//! fraction of what it is at `dt`: an effect that is physics still improves the held-out
//! recordings beyond noise there; one that absorbed the integration error does not (an
//! action delay shorter than the integrator's equivalent phase lag makes the finer replay
//! worse). The test does not wait for the discretisation floor
//! ([`Engine::discretisation_floor`]) to show a part: an effect fitted at `dt` can absorb the
//! discretisation unevenly over the joints, and the floor then reads zero (a leg with one
//! armature of 0.06 on all joints, recorded in near-continuous time: the group fitted 0.0612 at
//! 1 ms; at 0.25 ms hip and knee came 20 % closer to the recordings and the ankle 38 % farther,
//! and the hip's remaining integrator lag was kept as a 0.47 ms action delay). On recordings
//! made at the model's own step a smooth effect that is physics still passes there: the finer
//! replay moves both sides alike. A non-smooth one (a torque limit, load-dependent friction)
//! changes its events with the step, and takes the test only when the floor shows a timestep
//! part (on synthetic recordings at the model's step both failed it).
//!
//! [`Engine::discretisation_floor`]: super::engine::Engine::discretisation_floor
//! [`SearchPolicy::discretisation_refine`]: super::policy::SearchPolicy::discretisation_refine

use crate::fit::effects::{Applied, num};
use crate::sim2real::recording::Recording;

use super::engine::Engine;
use super::policy::Phase;
use super::verdict::{Gate, Verdict, verdict};
use super::{FitOutcome, Floor, Tried};

/// What [`beyond_discretisation`] judges: the round's base set, the base with the candidate
/// (the entries after the base: one effect, or a pair kept together), the gate the candidate
/// passed and the round's floors.
pub(super) struct Judged<'a> {
    pub(super) base: &'a [Applied],
    pub(super) trial: &'a [Applied],
    pub(super) gate: Gate,
    pub(super) floors: &'a [Floor],
    pub(super) round: usize,
}

/// `true` when the candidate (the entries of `j.trial` after `j.base`: one effect or a pair),
/// which passed the held-out gate at the model's timestep, is physics beyond the model's time
/// discretisation: it also passes `j.gate` (and `min_rel_improvement`) with both sides
/// replayed on `heldout` at `dt / r²`, or none of its effects is smooth ([`Effect::smooth`]:
/// a limit, a stick, a dead band) and the floors show no timestep part. Otherwise the attempt
/// is logged (phase `discretisation`) and a note says so.
///
/// [`Effect::smooth`]: crate::fit::effects::Effect::smooth
pub(super) fn beyond_discretisation(
    engine: &Engine,
    heldout: &[Recording],
    j: &Judged,
    out: &mut FitOutcome,
) -> bool {
    let cands = &j.trial[j.base.len().min(j.trial.len())..];
    finer_step_holds(engine, heldout, (j.base, cands), j, None, out)
}

/// The same test for the pair look-ahead's pair (the entries of `j.trial` after `j.base`),
/// which replaces the round's winner `single` only when it beats it: both replayed at
/// `dt / r²`, the pair must still improve the held-out recordings over the base with `single`
/// alone by `j.gate` (and `min_rel_improvement`), as it did at `dt`. A partner that only takes
/// up the model's time discretisation beside the winner does not. Otherwise logged (phase
/// `discretisation`) with a note; the winner stays.
pub(super) fn pair_beyond_discretisation(
    engine: &Engine,
    heldout: &[Recording],
    single: &Applied,
    j: &Judged,
    out: &mut FitOutcome,
) -> bool {
    let mut before = j.base.to_vec();
    before.push(single.clone());
    let cands = &j.trial[j.base.len().min(j.trial.len())..];
    finer_step_holds(engine, heldout, (&before, cands), j, Some(single), out)
}

/// [`beyond_discretisation`] with the set compared against `before` (the round's base, or the
/// base with the winner a pair would replace: `single`) and the candidates `cands`.
fn finer_step_holds(
    engine: &Engine,
    heldout: &[Recording],
    (before_set, cands): (&[Applied], &[Applied]),
    j: &Judged,
    single: Option<&Applied>,
    out: &mut FitOutcome,
) -> bool {
    let Some(first) = cands.first() else { return true };
    if !cands.iter().any(|c| c.effect.smooth()) && !j.floors.iter().any(|f| f.discretisation > 0.0)
    {
        return true;
    }
    // Not measurable at the finer step: the gate at `dt` stands.
    let Some(v) = at_finer_step(engine, heldout, (before_set, j.trial), first, j.gate) else {
        return true;
    };
    if v.significant && v.rel >= engine.opts.policy.min_rel_improvement {
        return true;
    }
    let ids: Vec<&str> = cands.iter().map(|c| c.effect.id()).collect();
    out.log(Tried {
        round: j.round,
        phase: Phase::Discretisation,
        effect: ids.join("+"),
        joints: first.joints.clone(),
        params: cands.iter().flat_map(|c| c.params.iter().copied()).collect(),
        train_rmse: f64::NAN,
        heldout_improvement: v.rel,
        significant: v.significant,
        bic_decreased: false,
        kept: false,
        predicted: None,
        simulated_s: None,
    });
    note_within(engine, cands, single, v.rel, out);
    false
}

/// The held-out verdict (`gate`, on `first`'s joints) of `trial` against `before_set`, both
/// replayed on `heldout` at `dt / r²`; `None` when either replay fails.
fn at_finer_step(
    engine: &Engine,
    heldout: &[Recording],
    (before_set, trial): (&[Applied], &[Applied]),
    first: &Applied,
    gate: Gate,
) -> Option<Verdict> {
    let r = engine.opts.policy.discretisation_refine.max(2);
    let k = (r * r) as u32;
    let before = engine.errors_at(heldout, before_set, k)?;
    let after = engine.errors_at(heldout, trial, k)?;
    Some(verdict(&before, &after, &first.joints, gate))
}

/// Before the full fit of a one-line descent ([`super::trust::one_line_descent`]: after round 0,
/// a smooth candidate of one fitted parameter, whose full fit goes on from its coarse fit along
/// the same line), the finer-step test on its coarse fit (the entry of `j.trial` after
/// `j.base`) with every bar at the trust's edge ([`super::trust::at_trust_edge`]: `j.gate`'s z and
/// decisive improvement, and `min_rel_improvement`, × `linear_trust`): a full fit moves each
/// measure at most 1 / `linear_trust` times further than the coarse fit, so a coarse fit short
/// of the edge at `dt / r²` leaves the full fit short of the gate there, and the full fit cannot
/// be kept ([`beyond_discretisation`] would stop it after its fit). `Some` (the relative held-out
/// improvement at the finer step; the note is added) when it is short; `None` when it passes
/// or cannot be measured.
pub(super) fn coarse_within_discretisation(
    engine: &Engine,
    heldout: &[Recording],
    j: &Judged,
    out: &mut FitOutcome,
) -> Option<f64> {
    let cands = &j.trial[j.base.len().min(j.trial.len())..];
    let first = cands.first()?;
    let pol = &engine.opts.policy;
    let lt = pol.linear_trust;
    let edge = Gate { z: lt * j.gate.z, decisive: lt * j.gate.decisive, ..j.gate };
    let v = at_finer_step(engine, heldout, (j.base, j.trial), first, edge)?;
    if v.significant && v.rel >= lt * pol.min_rel_improvement {
        return None;
    }
    note_within(engine, cands, None, v.rel, out);
    Some(v.rel)
}

/// The note that `cands` (beside the winner `single`, when a pair's partner) are within the
/// model's time discretisation: `rel`, their relative held-out improvement at the finer step.
/// One note per effect and joint group.
fn note_within(
    engine: &Engine,
    cands: &[Applied],
    single: Option<&Applied>,
    rel: f64,
    out: &mut FitOutcome,
) {
    let r = engine.opts.policy.discretisation_refine.max(2);
    let k = (r * r) as u32;
    let dt = engine.robot.mj.opt().timestep;
    // Beside a winner, the note names the partner (the winner stays).
    let winner = |c: &Applied| {
        single.is_some_and(|s| s.effect.id() == c.effect.id() && s.joints == c.joints)
    };
    let named: Vec<&Applied> = match cands.iter().filter(|c| !winner(c)).collect::<Vec<_>>() {
        v if v.is_empty() => cands.iter().collect(),
        v => v,
    };
    let params: Vec<String> = named
        .iter()
        .flat_map(|c| c.effect.params().iter().zip(&c.params))
        .map(|(d, v)| format!("{} {}", d.name, num(*v)))
        .collect();
    let ids: Vec<&str> = named.iter().map(|c| c.effect.id()).collect();
    let (what, verb) =
        if ids.len() == 1 { (ids[0].to_string(), "is") } else { (ids.join(" and "), "are") };
    let (what, over) = match single {
        Some(s) => {
            (format!("{what} beside {}", s.effect.id()), format!(" over {} alone", s.effect.id()))
        }
        None => (what, String::new()),
    };
    let note = format!(
        "{what} on {} ({}) {verb} within the model's time discretisation at dt = {} s, not \
         reported as missing physics: replayed at dt / {k} it does not improve the held-out \
         recordings beyond noise{over} ({:+.1} %); a finer timestep would resolve it",
        named[0].joints.join(","),
        params.join(", "),
        num(dt),
        100.0 * rel,
    );
    // One note per effect and joint group (a later round may fit it again).
    let head = format!("{what} on {} (", named[0].joints.join(","));
    if !out.notes.iter().any(|n| n.starts_with(&head) && n.contains("time discretisation")) {
        out.notes.push(note);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::{ActionDelay, Effect, ViscousDamping};
    use crate::sim2real::commands::pseudo_sign;
    use crate::sim2real::recording::JointTrace;

    /// A servo too stiff for its model's 5 ms step (ω·dt ≈ 0.27), with `damping` on its joint.
    fn servo(damping: f64) -> String {
        format!(
            r#"<mujoco><option gravity="0 0 0" timestep="0.005" integrator="implicitfast"/>
  <worldbody><body><joint name="j" type="hinge" axis="0 1 0" damping="{damping}"/>
<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/></body></worldbody>
  <actuator><position joint="j" kp="20" kv="0.3"/></actuator></mujoco>"#
        )
    }

    /// Four episodes of `real` stepped by hand at 5 ms / 16 (nearly continuous time), one row
    /// at each 100 Hz tick with that tick's command (a new level every 0.2–0.3 s) and a small
    /// reading noise.
    fn record(real: &crate::model::Robot) -> Vec<Recording> {
        let mut m = real.mj.clone();
        m.opt_mut().timestep = 0.005 / 16.0;
        (0..4)
            .map(|e| {
                let ticks = 300usize;
                let cmd: Vec<f64> =
                    (0..ticks).map(|k| 0.4 * ((k / (20 + 5 * e) + e) as f64 * 2.3).sin()).collect();
                let mut d = mujoco_rs::prelude::MjData::new(&m);
                let (mut q, mut qd) = (Vec::new(), Vec::new());
                for (k, c) in cmd.iter().enumerate() {
                    q.push(d.qpos()[0] + 2e-4 * pseudo_sign((e * 1000 + k) as u64));
                    qd.push(d.qvel()[0]);
                    d.ctrl_mut()[0] = *c;
                    for _ in 0..32 {
                        d.step();
                    }
                }
                let mut j = JointTrace::new("j", q);
                j.q_cmd = Some(cmd);
                j.qd = Some(qd);
                Recording {
                    source: format!("ep{e}.csv").into(),
                    meta: Default::default(),
                    control_rate_hz: Some(100.0),
                    control_t0_s: Some(0.0),
                    t: (0..ticks).map(|k| k as f64 * 0.01).collect(),
                    joints: vec![j],
                    base: None,
                }
            })
            .collect()
    }

    /// On recordings in continuous time, an action delay fitted at the model's 5 ms step passes
    /// the held-out gate there (it stands in for the integrator's phase lag) but not at dt / 4:
    /// it is a note, not physics. A missing joint damping passes at both.
    #[test]
    fn a_delay_standing_in_for_the_timestep_is_a_note_and_damping_is_physics() {
        use crate::sim2real::replay::tests::robot_from_xml;
        let (nominal, dir) = robot_from_xml("disc-gate", &servo(0.02));
        let (clean, dir2) = robot_from_xml("disc-gate-clean", &servo(0.02));
        let (damped, dir3) = robot_from_xml("disc-gate-damped", &servo(0.3));
        let opts = super::super::FitOptions { estimate_start: false, ..Default::default() };
        // `timing`: recordings of the same commands whose floors say whether the recordings
        // move in finer time than the model (a large missing damping leaves a residual beyond
        // what the timestep explains, and a damping fitted at dt absorbs part of the timestep's
        // error: with either, the floor has no timestep part; the clean recordings have one).
        let judge = |recs: &[Recording], timing: &[Recording], effect: &'static dyn Effect| {
            let (train, heldout) = recs.split_at(3);
            let engine = Engine::new(&nominal, recs, &opts);
            let (p, _) = engine.fit_one(train, &[], effect, &["j".to_string()]);
            let trial = vec![Applied { effect, joints: vec!["j".into()], params: p }];
            let t = &timing[..3];
            let floors = engine.floors(t, &[], &engine.errors(t, &[]).expect("replay"));
            let gate = opts.policy.gate();
            let before = engine.errors(heldout, &[]).expect("replay");
            let after = engine.errors(heldout, &trial).expect("replay");
            let at_dt = verdict(&before, &after, &trial[0].joints, gate).significant;
            let mut out = FitOutcome::empty(String::new());
            let j = Judged { base: &[], trial: &trial, gate, floors: &floors, round: 0 };
            let beyond = beyond_discretisation(&engine, heldout, &j, &mut out);
            // The same test before a full fit, at the trust's edge, on this point.
            let mut early = FitOutcome::empty(String::new());
            let short = coarse_within_discretisation(&engine, heldout, &j, &mut early);
            assert_eq!(short.is_some(), !early.notes.is_empty(), "{:?}", early.notes);
            assert!(early.tried.is_empty(), "{:?}", early.tried);
            (floors[0].discretisation, trial[0].params[0], at_dt, beyond, (out, short))
        };
        let clean = record(&clean);
        let (disc, delay, at_dt, beyond, (out, short)) = judge(&clean, &clean, &ActionDelay);
        assert!(disc > 0.0, "no discretisation part");
        assert!(delay > 0.0 && at_dt, "delay {delay} does not pass at dt: nothing to test");
        assert!(!beyond, "delay {delay} kept");
        // Short at the edge too: its full fit from this point would not be made.
        assert!(short.is_some_and(|r| r < 0.02), "delay {delay} passes at the edge: {short:?}");
        assert_eq!(out.notes.len(), 1, "{:?}", out.notes);
        assert!(out.notes[0].contains("within the model's time discretisation at dt = 0.005 s"));
        assert!(out.tried.iter().any(|t| t.phase == Phase::Discretisation && !t.kept));
        let (disc, damping, at_dt, beyond, (out, short)) =
            judge(&record(&damped), &clean, &ViscousDamping);
        assert!(disc > 0.0 && at_dt, "damping {damping}: part {disc}, passes at dt {at_dt}");
        assert!(beyond && out.notes.is_empty(), "damping {damping}: {:?}", out.notes);
        assert!(short.is_none(), "damping {damping} stopped before its full fit: {short:?}");
        for d in [dir, dir2, dir3] {
            std::fs::remove_dir_all(&d).ok();
        }
    }

    /// The same test holds for a pair of effects kept together when no single one passes
    /// (`joint_pairs`): on recordings in continuous time, a gain error and an action delay
    /// fitted at the model's 5 ms step stand in for the integrator's lag together; the pair
    /// is not kept, and the note names the member that is within the discretisation.
    #[test]
    fn a_pair_standing_in_for_the_timestep_is_not_kept() {
        use crate::fit::effects::GainError;
        use crate::sim2real::replay::tests::robot_from_xml;
        let (nominal, dir) = robot_from_xml("disc-pair", &servo(0.02));
        let (clean, dir2) = robot_from_xml("disc-pair-clean", &servo(0.02));
        let recs = record(&clean);
        let opts = super::super::FitOptions { estimate_start: false, ..Default::default() };
        let (train, heldout) = recs.split_at(3);
        let engine = Engine::new(&nominal, &recs, &opts);
        let j = vec!["j".to_string()];
        let single = |effect: &'static dyn Effect| {
            let (p, _) = engine.fit_one(train, &[], effect, &j);
            Applied { effect, joints: j.clone(), params: p }
        };
        let fitted = vec![single(&GainError), single(&ActionDelay)];
        let tr = engine.errors(train, &[]).expect("replay");
        let ho = engine.errors(heldout, &[]).expect("replay");
        let floors = engine.floors(train, &[], &tr);
        let mut out = FitOutcome::empty(String::new());
        let kept = super::super::pairs::joint_pairs(
            &engine,
            (train, train, heldout),
            (&[], &fitted),
            (&tr, &ho),
            &floors,
            opts.policy.z_decision,
            0,
            &mut out,
        );
        let pair = out.tried.iter().find(|t| t.phase == Phase::JointPair).expect("pair tried");
        // The pair passes the held-out gate at dt (else there is nothing to test here)…
        assert!(pair.significant && pair.heldout_improvement > 0.0, "{:?}", out.tried);
        // …but is not kept: a member does not improve the recordings at dt / 4.
        assert!(
            !kept && out.applied.is_empty(),
            "kept {:?} {:?} {:?}",
            out.applied.iter().map(|a| (a.effect.id(), a.params.clone())).collect::<Vec<_>>(),
            out.tried,
            floors
        );
        assert!(out.tried.iter().any(|t| t.phase == Phase::Discretisation), "{:?}", out.tried);
        assert!(out.notes.iter().any(|n| n.contains("time discretisation")), "{:?}", out.notes);
        for d in [dir, dir2] {
            std::fs::remove_dir_all(&d).ok();
        }
    }

    /// The pair look-ahead's test: beside a winner, a partner that only takes up the model's
    /// step does not beat the winner alone at dt / 4, and a partner that is physics does. On
    /// recordings in continuous time of a servo with a missing damping: an action delay fitted
    /// beside the damping is a note naming the delay beside the damping; the damping fitted
    /// beside a delay (the winner standing in for it) passes.
    #[test]
    fn a_partner_standing_in_for_the_timestep_does_not_replace_the_winner() {
        use crate::sim2real::replay::tests::robot_from_xml;
        let (nominal, dir) = robot_from_xml("disc-partner", &servo(0.02));
        let (clean, dir2) = robot_from_xml("disc-partner-clean", &servo(0.02));
        let (damped, dir3) = robot_from_xml("disc-partner-damped", &servo(0.3));
        let recs = record(&damped);
        let opts = super::super::FitOptions { estimate_start: false, ..Default::default() };
        let (train, heldout) = recs.split_at(3);
        let engine = Engine::new(&nominal, &recs, &opts);
        let j = vec!["j".to_string()];
        let fit = |base: &[Applied], effect: &'static dyn Effect| {
            let (p, _) = engine.fit_one(train, base, effect, &j);
            Applied { effect, joints: j.clone(), params: p }
        };
        // Floors of the clean recordings: a timestep part (not needed for smooth effects).
        let timing = record(&clean);
        let floors = engine.floors(&timing[..3], &[], &engine.errors(&timing[..3], &[]).unwrap());
        let judge = |winner: &'static dyn Effect, partner: &'static dyn Effect| {
            let w = fit(&[], winner);
            let p = fit(std::slice::from_ref(&w), partner);
            let trial = vec![w.clone(), p];
            let gate = opts.policy.gate();
            let jd = Judged { base: &[], trial: &trial, gate, floors: &floors, round: 0 };
            let mut out = FitOutcome::empty(String::new());
            let kept = pair_beyond_discretisation(&engine, heldout, &w, &jd, &mut out);
            (kept, trial, out)
        };
        let (kept, trial, out) = judge(&ViscousDamping, &ActionDelay);
        assert!(!kept, "delay beside damping kept: {:?}", trial);
        assert_eq!(out.notes.len(), 1, "{:?}", out.notes);
        assert!(
            out.notes[0].starts_with("action_delay beside viscous_damping on j (delay_s")
                && out.notes[0].contains("over viscous_damping alone"),
            "{:?}",
            out.notes
        );
        let (kept, trial, out) = judge(&ActionDelay, &ViscousDamping);
        assert!(kept && out.notes.is_empty(), "damping beside a delay: {trial:?} {:?}", out.notes);
        for d in [dir, dir2, dir3] {
            std::fs::remove_dir_all(&d).ok();
        }
    }
}
