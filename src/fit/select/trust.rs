//! Later rounds from round 0's work: round 0 records which candidates' linear models its coarse
//! fits confirmed ([`super::engine::Engine::note_trust`]); after it, such a candidate whose
//! prediction on the round's residual cannot reach the round's bar is not coarse-fitted
//! ([`trust_out`]), and one that could start a joint pair is coarse-fitted only when the round
//! ends in the joint pairs ([`with_pair_starts`]). Within a round, a coarse fit that confirms
//! its candidate's linear model stands for the full fit's held-out gain ([`heldout_needed`]);
//! after round 0 a smooth candidate's coarse fit, where its full fit's descent starts, must pass
//! the held-out gate at the trust's edge to be fitted in full ([`heldout_short`]).
//! After round 0 every candidate is also judged on the held-out set's own linear model before
//! any coarse fit ([`heldout_out`]): the most any value of its parameters could lower the
//! held-out error, to first order and at the trust's edge, must reach the gate.

use crate::fit::effects::{self, Applied, Effect, JointTarget, model_with};
use crate::sim2real::recording::Recording;

use crate::fit::diagnose::Candidate;

use super::Errors;
use super::coarse;
use super::groups::Cand;
use super::policy::SearchPolicy;
use super::screen::Screen;
use super::verdict::{Gate, verdict};

/// The relative held-out improvement (over the candidate's joints, [`super::verdict`]) that a
/// candidate's coarse fit must exceed to be fitted in full, from the linear model's predicted
/// training gain `want` and the coarse fit's achieved gain `got` (both relative, on the
/// screen's data). When the coarse fit confirms the linear model ([`coarse::agrees`]: between
/// `linear_trust` and its inverse times the prediction), the prediction is the full fit's
/// optimum to within that trust: the full fit gains at most 1 / `linear_trust` times what the
/// coarse fit gained, on training and likewise on held-out, so a coarse fit lowering the
/// held-out RMSE by less than `linear_trust` × `min_rel_improvement` leaves a full fit short of
/// the gate's `min_rel_improvement`. Otherwise (no prediction, or one the coarse fit does not
/// confirm: the full fit may go well past it) 0: only a coarse fit that does not lower the
/// held-out error at all is not fitted in full.
pub(super) fn heldout_needed(want: Option<f64>, got: f64, pol: &SearchPolicy) -> f64 {
    match want {
        Some(w) if coarse::agrees(got, w, pol) => pol.linear_trust * pol.min_rel_improvement,
        _ => 0.0,
    }
}

/// Whether a candidate's coarse fit, replayed on the held-out set (`ho_c`; `None`: the replay
/// failed), leaves its full fit short of the held-out gate, so that none is made (`tried`:
/// `heldout_screen`): the coarse fit does not lower the round's held-out RMSE (`ho_err`, over
/// the candidate's joints `group`) by more than [`heldout_needed`] asks (from the predicted
/// and achieved training gains `want`, `got`); or, when the full fit would continue the coarse
/// fit's own descent along one line (`descent`, [`one_line_descent`]), the coarse fit does not
/// pass the round's `gate` at the trust's edge ([`at_trust_edge`]).
pub(super) fn heldout_short(
    (ho_err, ho_c): (&Errors, Option<&Errors>),
    group: &[String],
    (want, got): (Option<f64>, f64),
    (gate, descent): (Gate, bool),
    pol: &SearchPolicy,
) -> bool {
    let Some(h) = ho_c else { return true };
    verdict(ho_err, h, group, gate).rel <= heldout_needed(want, got, pol)
        || (descent && !at_trust_edge((ho_err, h), group, gate, pol))
}

/// Whether the full fit of `e` continues its coarse fit's own descent along one line, so that
/// [`heldout_short`] may judge it at the trust's edge: after round 0 (in round 0 a coarse fit
/// that fails the edge can still be the round's answer), a smooth effect (its coarse fit is
/// secant Gauss–Newton on the screen's data, which its full fit goes on with by
/// Levenberg–Marquardt on the same data) of one fitted parameter. Not one of several: its coarse
/// fit (a confirmed linear step or a few Levenberg–Marquardt iterations) is a point its full fit
/// can leave in another direction — on BAM's XL330 with kp 400 held out, round 2's motor
/// constants (two parameters) stood short of the edge at a coarse fit that confirmed its linear
/// model, and its full fit passed the gate (held-out 8.9 % lower) and was kept.
pub(super) fn one_line_descent(e: &dyn Effect, round: usize) -> bool {
    round > 0 && e.smooth() && e.fitted() == 1
}

/// Whether `after` passes the held-out `gate` against `before` on `group`'s windows with every
/// bar taken at the trust's edge: `linear_trust` × the gate's z and decisive improvement, and a
/// relative improvement of `linear_trust` × `min_rel_improvement` — the gate a point passes
/// when a fit that goes on from it moves each of the gate's measures (the paired per-window
/// improvement, its log, the relative improvement) at most 1 / `linear_trust` times further,
/// as a confirmed coarse fit's training gain is taken to move ([`heldout_needed`]). (After the
/// true effect, chainsim's round-1 smooth full fits — KR7's ankle armature, KR8's action delays
/// and gain error — moved none of them by more than 3 % of its value at the coarse fit.)
pub(super) fn at_trust_edge(
    (before, after): (&Errors, &Errors),
    group: &[String],
    gate: Gate,
    pol: &SearchPolicy,
) -> bool {
    let lt = pol.linear_trust;
    let edge = Gate { z: lt * gate.z, decisive: lt * gate.decisive, ..gate };
    let v = verdict(before, after, group, edge);
    v.significant && v.rel >= lt * pol.min_rel_improvement
}

/// After round 0, the largest relative gain (on the screen's data) that the linear model of `e`
/// on `g` allows when round 0's coarse fit confirmed that model ([`Engine::trusted`]: the gain it
/// achieved was between `linear_trust` and its inverse times the predicted one) and this round's
/// prediction divided by `linear_trust` stays below `cut` (the round's bar so far, at least
/// `min_rel_improvement`); `None` (coarse-fitted as usual) otherwise. Such a candidate's coarse
/// fit, at most that gain, could admit it to no full fit: the bar only rises during the round,
/// and a gain below `min_rel_improvement` starts no joint pair.
///
/// [`Engine::trusted`]: super::engine::Engine
pub(super) fn trust_out(
    engine: &super::Engine,
    screen: &Screen,
    (e, g): (&'static dyn Effect, &[String]),
    cut: f64,
) -> Option<f64> {
    if engine.trusted((e, g)) != Some(true) {
        return None;
    }
    let p = screen.predict(e.id(), g)?;
    let base = screen.base_rmse();
    let upper = (1.0 - p.train_rmse / base) / engine.opts.policy.linear_trust;
    (base > 0.0 && upper.is_finite() && upper < cut).then_some(upper)
}

/// After round 0, the largest relative held-out improvement (over every fitted joint, the
/// gate's measure, [`super::verdict`]) that `e` on `g` could make at any value of its
/// parameters by the linear model of the held-out set `ho` (a [`Screen`] built on the held-out
/// recordings: its columns probed on their stretches of largest residual), taken at the trust's
/// edge: 1 / `linear_trust` times the gain of the held-out least-squares step — the held-out
/// optimum, not the training step, so a training fit that went anywhere could not do better
/// to that trust — as a pair's fit is judged before any pair replay
/// ([`super::pair_screen`]). `Some` (the candidate is not coarse-fitted: whatever its training
/// fit, it could not pass the held-out gate's `min_rel_improvement`) when that stays below
/// `min_rel_improvement` and the linear model is confirmed for the candidate
/// ([`heldout_confirmed`]); `None` (screened as usual) otherwise, or when the held-out set has
/// no column for a joint of `g`. A group whose members start its one parameter apart
/// ([`starts_apart`]: a leg's armature of 0.04, 0.03 and 0.012 kg·m²) is judged on the linear
/// model of its one shared value ([`Screen::line_gain`]: each member moved from its own start
/// to that value; the summed columns would model every member moved by one step from its own
/// start, a direction no shared value takes), its optimum and its confirming step that model's
/// (chainsim's KR6 and KR7, round 1: the armature group's shared value cannot lower the held-out
/// RMSE at all — its best, 0.015 and 0.018 kg·m², leaves it 119 % and 93 % higher —, and its
/// training step replayed on the held-out probes' data confirms that: 113 % higher for 123 %
/// predicted, 106 % for 101 %; its coarse fit had cost 60 replayed s and left the screen's data
/// 79 % and 47 % worse).
pub(super) fn heldout_out(
    engine: &super::Engine,
    (screen, ho): (&Screen, &Screen),
    (heldout, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> Option<f64> {
    let pol = &engine.opts.policy;
    let apart = starts_apart(engine, applied, (e, g));
    // The held-out optimum's RMSE: of the group's shared value where its members start apart.
    let optimum = match &apart {
        Some(a) => ho.base_rmse() * (1.0 - ho.line_gain(e.id(), g, a, None)?.0),
        None => ho.predict(e.id(), g)?.train_rmse,
    };
    let reach =
        heldout_reach(optimum, ho.base_rmse(), pol).filter(|r| *r < pol.min_rel_improvement)?;
    let at = (heldout, applied);
    heldout_confirmed(engine, (screen, ho), at, (e, g), apart.as_deref()).then_some(reach)
}

/// Whether the linear model of `e` on `g` is confirmed where [`heldout_out`] would take it at
/// its word (a linearised step is a poor judge of a lightly damped servo, or of a kink): round
/// 0's coarse fit confirmed its training model ([`Engine::trusted`]; not for a group whose
/// members start apart, `apart` its starts: round 0 tested the summed columns), or the
/// training linear step (`screen`'s least-squares step of every probed parameter, where the
/// training fit goes to first order; of the shared value, [`Screen::line_gain`], for such a
/// group), replayed once on the held-out set's probes' data (what `ho` was probed
/// on), changes that data's RMSE as `ho`'s columns predict for that step ([`Screen::gain_at`])
/// by the same test ([`confirms`]: the secant coarse fit's and round 0's). `false` when that
/// step is no step (a zero step or one held at the bounds: nothing to replay) or a replay
/// fails.
///
/// [`Engine::trusted`]: super::engine::Engine
fn heldout_confirmed(
    engine: &super::Engine,
    (screen, ho): (&Screen, &Screen),
    (heldout, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    apart: Option<&[f64]>,
) -> bool {
    if apart.is_none() && engine.trusted((e, g)) == Some(true) {
        return true;
    }
    let confirmed = || {
        let probes = engine.probe_set_held(heldout, applied)?;
        // The training step: the shared value's least-squares value where the members start
        // apart (from the first member's start, which the group's value starts at).
        let x = match apart {
            Some(a) => vec![screen.line_gain(e.id(), g, a, None)?.1 - a.first()?],
            None => screen.steps(e.id(), g)?.1,
        };
        let (p, f) = engine.at_linear_step(&probes, applied, (e, g), &x)?;
        let base = engine.score(&probes, applied);
        // The step as replayed (inside the bounds) from the effect's start.
        let t = JointTarget::of(engine.robot, g.first()?)?;
        let p0 = e.initial(&model_with(engine.robot, applied), &t);
        let step: Vec<f64> = p.iter().zip(&p0).map(|(a, b)| a - b).collect();
        let want = match apart {
            Some(a) => ho.line_gain(e.id(), g, a, Some(*p.first()?))?.0,
            None => ho.gain_at(e.id(), g, &step)?,
        };
        Some(base > 0.0 && confirms(1.0 - f / base, want, &engine.opts.policy))
    };
    confirmed().unwrap_or(false)
}

/// The starts of `e`'s one fitted parameter on the members of the group `g` (on the model of
/// `applied`) when they differ ([`Screen::line_gain`]: the group's shared value then moves each
/// member by its own amount, which the summed columns of [`Screen::predict`] do not model);
/// `None` when they are one value, `e` fits more than one parameter, or a member is no joint.
pub(super) fn starts_apart(
    engine: &super::Engine,
    applied: &[Applied],
    (e, g): (&dyn Effect, &[String]),
) -> Option<Vec<f64>> {
    if e.fitted() != 1 || g.len() < 2 {
        return None;
    }
    let m0 = model_with(engine.robot, applied);
    let starts = g
        .iter()
        .map(|j| e.initial(&m0, &JointTarget::of(engine.robot, j)?).first().copied())
        .collect::<Option<Vec<f64>>>()?;
    starts.iter().any(|a| *a != starts[0]).then_some(starts)
}

/// Whether a replayed relative gain `got` confirms the `want` a linear model predicted, by the
/// trust's test ([`coarse::agrees`]) — a loss (a negative gain: the step makes the data worse)
/// as its size: between `linear_trust` and its inverse times the predicted loss.
fn confirms(got: f64, want: f64, pol: &SearchPolicy) -> bool {
    coarse::agrees(got, want, pol) || coarse::agrees(-got, -want, pol)
}

/// [`heldout_out`]'s reach: the relative gain from `base` to the held-out linear optimum
/// `optimum` [rad RMSE], divided by `linear_trust`; `None` when not finite or `base` is not
/// positive.
fn heldout_reach(optimum: f64, base: f64, pol: &SearchPolicy) -> Option<f64> {
    let reach = (1.0 - optimum / base) / pol.linear_trust;
    (base > 0.0 && reach.is_finite()).then_some(reach)
}

/// The largest training gain the linear model of `e` on `g` allows at the trust's edge
/// (∞ without a prediction): what [`with_pair_starts`] asks of a candidate left out by
/// [`heldout_out`] to start a joint pair.
pub(super) fn train_reach(screen: &Screen, (e, g): (&dyn Effect, &[String]), lt: f64) -> f64 {
    screen.predict(e.id(), g).map_or(f64::INFINITY, |p| {
        let base = screen.base_rmse();
        let upper = (1.0 - p.train_rmse / base) / lt;
        if upper.is_finite() { upper } else { f64::INFINITY }
    })
}

/// Whether `e` is the plain variant ([`Effect::plain_variant`]) of another candidate on `g`:
/// such a candidate is left out by neither [`trust_out`] nor [`heldout_out`], the richer model
/// being judged from its coarse fit ([`coarse::deferred`]); without it the richer one is
/// coarse-fitted whole on the screen's data.
pub(super) fn plain_needed(cands: &[Cand], (e, g): (&dyn Effect, &[String])) -> bool {
    cands.iter().any(|(x, h, _)| h == g && x.plain_variant().is_some_and(|p| p.id() == e.id()))
}

/// The diagnosis entries the held-out linear model is probed on after round 0 ([`heldout_out`]):
/// those on the joints of a candidate of that effect that [`heldout_out`] may leave out — not
/// [`plain_needed`], and not left out by round 0's trust ([`trust_out`]) at the lowest bar a
/// round has (`min_rel_improvement`). Each column is its joint's alone (a probe's change on its
/// own limb, [`Screen::build`]), so leaving the others out changes none of these.
pub(super) fn heldout_columns(
    engine: &super::Engine,
    screen: &Screen,
    cands: &[Cand],
    diag: &[Candidate],
) -> Vec<Candidate> {
    let small = engine.opts.policy.min_rel_improvement;
    let open: Vec<&Cand> = cands
        .iter()
        .filter(|(e, g, _)| {
            !plain_needed(cands, (*e, g)) && trust_out(engine, screen, (*e, g), small).is_none()
        })
        .collect();
    let wanted =
        |c: &&Candidate| open.iter().any(|(e, g, _)| e.id() == c.effect && g.contains(&c.joint));
    diag.iter().filter(wanted).cloned().collect()
}

/// `fitted` with the coarse fits of the candidates of `out_of` ([`trust_out`]) that could start
/// a joint pair: a linear model allowing at least `min_rel_improvement`, and a mimicking
/// partner ([`effects::mimicking_pairs`]) on the same joints fitted or also left out. Each is
/// coarse-fitted as the screen would have, and joins when its gain (`gain`) reaches
/// `min_rel_improvement`, as a screened candidate's coarse fit does.
pub(super) fn with_pair_starts(
    engine: &super::Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    out_of: &[(&'static dyn Effect, Vec<String>, f64)],
    mut fitted: Vec<Applied>,
    gain: impl Fn(f64) -> f64,
) -> Vec<Applied> {
    let small = engine.opts.policy.min_rel_improvement;
    let pairs = effects::mimicking_pairs();
    let partner = |a: &str, b: &str| {
        pairs.iter().any(|(x, y)| (x.id() == a && y.id() == b) || (x.id() == b && y.id() == a))
    };
    let starts: Vec<(&'static dyn Effect, &Vec<String>)> = out_of
        .iter()
        .filter(|(e, g, upper)| {
            *upper >= small
                && (fitted.iter().any(|f| f.joints == *g && partner(e.id(), f.effect.id()))
                    || out_of
                        .iter()
                        .any(|(x, h, u)| h == g && *u >= small && partner(e.id(), x.id())))
        })
        .map(|(e, g, _)| (*e, g))
        .collect();
    for (e, g) in starts {
        let (p, f) = coarse::fit(engine, screen, (short, applied), (e, g));
        if !p.is_empty() && gain(f) >= small {
            fitted.push(Applied { effect: e, joints: g.clone(), params: p });
        }
    }
    fitted
}

#[cfg(test)]
mod tests {
    use super::{confirms, heldout_needed, heldout_reach, heldout_short, one_line_descent};
    use crate::fit::select::{Errors, SearchPolicy};

    /// The edge judges a one-line descent only: after round 0, a smooth effect of one fitted
    /// parameter; never in round 0, never a non-smooth one, never a smooth one of several (its
    /// full fit can leave the coarse fit in another direction). The registry holds both kinds
    /// of smooth effect, so each side of the test is exercised.
    #[test]
    fn only_a_one_parameter_smooth_fit_after_round_0_is_a_one_line_descent() {
        let all = crate::fit::effects::all();
        assert!(all.iter().all(|e| !one_line_descent(*e, 0)));
        for e in all.iter() {
            assert_eq!(one_line_descent(*e, 1), e.smooth() && e.fitted() == 1, "{}", e.id());
            assert_eq!(one_line_descent(*e, 3), one_line_descent(*e, 1), "{}", e.id());
        }
        assert!(all.iter().any(|e| e.smooth() && e.fitted() == 1));
        assert!(all.iter().any(|e| e.smooth() && e.fitted() > 1 && !one_line_descent(*e, 1)));
        assert!(all.iter().any(|e| !e.smooth() && e.fitted() == 1 && !one_line_descent(*e, 1)));
    }

    /// Held-out errors of eight windows of one joint `a` (10 samples each).
    fn errs(w: &[f64]) -> Errors {
        Errors {
            sse: w.iter().map(|v| v * v * 10.0).sum(),
            n: 10 * w.len(),
            windows: w.iter().map(|v| ("a".to_string(), *v)).collect(),
            eps: vec![],
        }
    }

    /// Windows of error 1 lowered by `m` ± `s` (alternating): a paired improvement of mean `m`
    /// and standard error s / √7.
    fn lowered(m: f64, s: f64) -> Errors {
        errs(&(0..8).map(|i| 1.0 - m - if i % 2 == 1 { s } else { -s }).collect::<Vec<f64>>())
    }

    /// After round 0 a smooth candidate's coarse fit must pass the round's gate at the trust's
    /// edge (z and decisive improvement × `linear_trust`, a relative improvement of
    /// `linear_trust` × `min_rel_improvement`) to be fitted in full; any other, only lower the
    /// held-out error (or, confirmed, by the trusted share). A paired z of 1.7 (KR8's gain error
    /// group in round 1: 1.69 for a round z of 2.95) is short of 0.75 × 2.95 = 2.21; 2.5 is not.
    #[test]
    fn a_descent_is_fitted_in_full_only_when_its_start_passes_the_gate_at_the_trust_edge() {
        let pol = SearchPolicy::default();
        let (g, before) = (vec!["a".to_string()], errs(&[1.0; 8]));
        let gate = pol.gate_z(2.95);
        let lt = pol.linear_trust;
        assert!((lt * 2.95 - 2.2125).abs() < 1e-12, "{lt}");
        let z = |m: f64, s: f64| m * 7f64.sqrt() / s;
        let short = |after: &Errors, descent: bool| {
            heldout_short((&before, Some(after)), &g, (None, 0.05), (gate, descent), &pol)
        };
        // Noise-level: z 1.7 (about 2 % lower) — short of the edge, not of "lower at all".
        let weak = lowered(0.02, 0.02 * 7f64.sqrt() / 1.7);
        assert!((z(0.02, 0.02 * 7f64.sqrt() / 1.7) - 1.7).abs() < 1e-9);
        assert!(short(&weak, true) && !short(&weak, false));
        // z 2.5: past the edge though short of the gate itself — a full fit may get there.
        let near = lowered(0.02, 0.02 * 7f64.sqrt() / 2.5);
        assert!(!short(&near, true) && !short(&near, false));
        // Consistently 1.2 % lower: beyond noise but short of 0.75 × 2 % relative.
        let small = lowered(0.012, 1e-4);
        assert!(short(&small, true) && !short(&small, false));
        // Consistently 10 % lower: fitted in full either way.
        let clear = lowered(0.1, 0.01);
        assert!(!short(&clear, true) && !short(&clear, false));
        // One window 60 % lower, the others unchanged (5 % of the whole, z 1; KR7's ankle
        // armature in round 1: 11 %, z 0.1): short of the edge; fitted in full without it.
        let mut w = [1.0; 8];
        w[3] = 0.4;
        let one = errs(&w);
        assert!(short(&one, true) && !short(&one, false));
        // Worse on held-out, or no replay: short either way.
        let worse = lowered(-0.05, 0.01);
        assert!(short(&worse, false) && short(&worse, true));
        let none = heldout_short((&before, None), &g, (None, 0.05), (gate, false), &pol);
        assert!(none);
    }

    /// The held-out reach is the held-out linear optimum's relative gain at the trust's edge:
    /// a candidate is left out only when even that stays below the gate's improvement.
    #[test]
    fn the_heldout_reach_is_the_linear_optimum_at_the_trust_edge() {
        let pol = SearchPolicy::default();
        let (lt, small) = (pol.linear_trust, pol.min_rel_improvement);
        // 1 % of the held-out RMSE at the optimum: 1.33 % at the trust's edge, short of 2 %.
        let r = heldout_reach(0.99, 1.0, &pol).expect("finite");
        assert!((r - 0.01 / lt).abs() < 1e-12 && r < small, "{r}");
        // Just short of and just past trust × the gate's improvement.
        assert!(heldout_reach(1.0 - 0.99 * lt * small, 1.0, &pol).unwrap() < small);
        assert!(heldout_reach(1.0 - 1.01 * lt * small, 1.0, &pol).unwrap() > small);
        // A column that explains nothing reaches nothing; no base, no reach.
        assert_eq!(heldout_reach(2.0, 2.0, &pol), Some(0.0));
        assert_eq!(heldout_reach(1.0, 0.0, &pol), None);
        assert_eq!(heldout_reach(f64::NAN, 1.0, &pol), None);
    }

    /// A replay confirms the held-out linear model like a coarse fit its training one: a gain
    /// within the trust of the predicted one, a loss within the trust of the predicted loss,
    /// both below the gate's improvement; not a gain where a loss was predicted, nor one far
    /// from the prediction.
    #[test]
    fn a_replay_confirms_a_predicted_gain_or_loss_within_the_trust() {
        let pol = SearchPolicy::default();
        let (lt, small) = (pol.linear_trust, pol.min_rel_improvement);
        assert!(confirms(0.1, 0.1, &pol) && confirms(0.1 * lt, 0.1, &pol));
        assert!(!confirms(0.99 * lt * 0.1, 0.1, &pol) && !confirms(0.1 / (0.99 * lt), 0.1, &pol));
        assert!(confirms(-0.1, -0.1, &pol) && confirms(-0.099 / lt, -0.1, &pol));
        assert!(!confirms(-0.1 / (0.99 * lt), -0.1, &pol) && !confirms(-0.05, -0.1, &pol));
        assert!(confirms(0.5 * small, -0.5 * small, &pol));
        assert!(!confirms(0.1, -0.1, &pol) && !confirms(-0.1, 0.1, &pol));
        assert!(!confirms(f64::NAN, 0.1, &pol));
    }

    /// A coarse fit that achieved its linear model's gain (within the trust) must lower the
    /// held-out error by the gate's improvement scaled by the trust; one short of or past its
    /// prediction, or without one, only by something.
    #[test]
    fn only_a_confirmed_coarse_fit_must_lower_the_heldout_error_by_the_trusted_share() {
        let pol = SearchPolicy::default();
        let (lt, small) = (pol.linear_trust, pol.min_rel_improvement);
        let bar = lt * small;
        assert!(bar > 0.0 && bar < small, "{bar}");
        // Confirmed: 0.0755 achieved for 0.0825 predicted (chainsim KR8's knee inertia).
        assert_eq!(heldout_needed(Some(0.0825), 0.0755, &pol), bar);
        // At the trust's edges, both ways.
        assert_eq!(heldout_needed(Some(0.1), 0.1 * lt, &pol), bar);
        assert_eq!(heldout_needed(Some(0.1 * lt), 0.1, &pol), bar);
        // Past its prediction (a full fit may go further still) and short of it.
        assert_eq!(heldout_needed(Some(0.05), 0.1043, &pol), 0.0);
        assert_eq!(heldout_needed(Some(0.1385), 0.0667, &pol), 0.0);
        // No linear model.
        assert_eq!(heldout_needed(None, 0.1, &pol), 0.0);
    }
}
