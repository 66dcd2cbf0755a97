//! A candidate's coarse fit on the screen's data: what it is, when it can wait, and the
//! screen's linear step replayed where it alone would admit a candidate to a full fit.
//!
//! What a coarse fit costs: a smooth candidate goes on from the screen's linear step, which one
//! replay confirms or not (secant steps for one parameter, [`confirmed_step`] for more); a
//! non-smooth one (a grid, a simplex) is fitted on the probes' data, a fifth of the screen's,
//! and replayed once on the screen's ([`on_probes`]; not when it found nothing there). Only
//! where that check fails is the coarse fit of `screen_evals` replays of the screen's data made
//! — for a smooth candidate, only where the Gauss–Newton model at the replayed point could
//! still reach the round's bar and that model's step, replayed, neither confirms its predicted
//! gain nor reaches the bar ([`super::further`]).

use crate::fit::effects::{Applied, Effect, model_with};
use crate::sim2real::recording::Recording;

use super::at_base::AtBase;
use super::engine::Engine;
use super::groups::{Cand, same_data};
use super::policy::SearchPolicy;
use super::screen::Screen;
use super::{Search, ext_bound, extension, further};

/// A point of a candidate's parameters and its training RMSE on the screen's data.
pub(super) type Point = (Vec<f64>, f64);

/// A candidate's coarse fit: its parameters and training RMSE on the screen's data.
pub(super) type Coarse = Option<Point>;

/// The coarse fit of `e` on `g` on `short` (`screen_evals` replays): a smooth one-parameter
/// candidate goes on from the screen's linear step by secant steps (one replay each); a smooth
/// one of several parameters from its linear step when one replay confirms it
/// ([`confirmed_step`]); a non-smooth one is fitted on the probes' data of `short`
/// ([`on_probes`]) when the screen holds them.
pub(super) fn fit(
    engine: &Engine,
    screen: &Screen,
    data: (&[Recording], &[Applied]),
    cand: (&'static dyn Effect, &[String]),
) -> (Vec<f64>, f64) {
    fit_to(engine, screen, data, cand, f64::INFINITY)
}

/// [`fit`] in a round whose bar for a full fit is a gain of `bar` on `short` (relative to its
/// base RMSE; infinite before a fit set it): a smooth candidate whose step is not confirmed
/// is then fitted on the probes' data too, and a point of the probes' fit whose replay on
/// `short` reaches the bar admits the candidate, and stands ([`on_probes`]).
pub(super) fn fit_to(
    engine: &Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    bar: f64,
) -> (Vec<f64>, f64) {
    let linear = secant(engine, screen, (short, applied), (e, g));
    let probes = || on_probes(engine, (short, applied), (e, g), bar);
    // (A smooth one only once a fit set the bar it is judged against: before, its coarse fit
    // starts the round's lead's full fit, as it did.)
    let cheap = || {
        if e.smooth() {
            confirmed_step(engine, screen, (short, applied), (e, g))
                .or_else(|| bar.is_finite().then(probes).flatten())
        } else {
            probes()
        }
    };
    linear
        .or_else(cheap)
        .unwrap_or_else(|| engine.fit_budget(short, applied, e, g, engine.opts.policy.screen_evals))
}

/// A smooth one-parameter candidate's coarse fit on `short`: the screen's linear step, then
/// secant steps ([`Engine::fit_secant`]); `None` where those do not apply.
///
/// [`Engine::fit_secant`]: super::engine::Engine
pub(super) fn secant(
    engine: &Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> Option<(Vec<f64>, f64)> {
    let p = screen.predict(e.id(), g)?;
    let gain = 1.0 - p.train_rmse / screen.base_rmse();
    engine.fit_secant(short, applied, (e, g), (p.step, gain))
}

/// The screen's linear step of a smooth candidate the secant steps do not take (more than one
/// parameter, every one probed: [`Effect::stepped`]; or a group whose members start apart),
/// replayed once on `short` ([`replayed_step`]): its parameters and RMSE when the gain it
/// achieves confirms the one its linear model predicted ([`agrees`]) — the linearisation error
/// measured where the fit would start; `None` (a coarse fit of `screen_evals` replays follows)
/// when it does not, or the step is zero.
fn confirmed_step(
    engine: &Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> Option<(Vec<f64>, f64)> {
    // (Only where the linear model steps every fitted parameter: one of the first parameters
    // alone can explain nothing that it and the others together explain.)
    if e.stepped().max(e.screened()) < e.fitted() {
        return None;
    }
    let (pred, x) = screen.steps(e.id(), g)?;
    let want = 1.0 - pred.train_rmse / screen.base_rmse();
    let (p, f) = engine.at_linear_step(short, applied, (e, g), &x)?;
    let base = engine.score(short, applied);
    agrees(1.0 - f / base, want, &engine.opts.policy).then_some((p, f))
}

/// The coarse fit of `e` on `g` made on the probes' data of `short` (the stretches of largest
/// residual inside it, [`SearchPolicy::probe_seconds`] in all, held when the round's screen
/// was built on `applied`) and replayed once on `short`: its parameters and RMSE on `short`.
/// A coarse fit admits a candidate to a full fit (by its gain on `short`, which is what every
/// gain of the round is measured on) and starts that fit; the shape of the residual it needs is
/// where the residual is largest, the data the probes' columns rank on. The fit stands when its
/// gain on `short` agrees with its gain on the probes' data ([`agrees`]: the probes' fit is the
/// model, `short` the check, as for the secant step). A fit that finds less than
/// `min_rel_improvement` on the probes' data — nothing where the model is most wrong — is not
/// replayed on `short`: it is logged at `short`'s base RMSE (no gain), which is what the check
/// accepts it for (both below `min_rel_improvement`) and what a coarse fit on `short` gave on
/// the chain cases (its gain there was at most 0.3 %, or the replay made `short` worse and the
/// fit on `short` found nothing). Otherwise (a descent along what only
/// the probes' stretches show, or one that explains more of the rest) the coarse fit on `short`
/// is made as before and the better of the two kept — but not for a smooth candidate whose
/// Gauss–Newton model at that point on `short` (one replay per free parameter) predicts no gain
/// reaching the round's bar ([`further::Model::least`]): the fit on `short`, which steps by that
/// model, would end below the bar too, and the point stands (on the backlash leg KR7, the hip's
/// gain error: 29 % replayed, 32 % the most its model allows, a bar of 34 %). Where the model
/// can reach the bar, its Gauss–Newton step ([`further::Model::step`], the step the fit's first
/// iteration there would take) is replayed once and stands as the coarse fit when its gain on
/// the point confirms the model's prediction ([`agrees`]) or it reaches the bar; else the fit
/// on `short` starts from the best of the step, the point and the effect's start (on the
/// armature leg KR8, round 1: the knee's point mass and the gain error on every joint, 7.9 %
/// and 6.6 % replayed for 8.0 % and 6.3 % predicted, the fits' 7.7 % and 6.7 %: the round's
/// screen replays 297 s instead of 417). The fit's `screen_evals` replays cost the
/// probes' seconds instead of the screen's (2 s for 10 s by default), and the replay on `short`
/// none when the fit stays at a start that changes nothing ([`Effect::neutral_start`]). `None`
/// when the probes' data is not held or is `short` itself, or a fit there fails.
///
/// [`SearchPolicy::probe_seconds`]: super::policy::SearchPolicy::probe_seconds
fn on_probes(
    engine: &Engine,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    bar: f64,
) -> Option<(Vec<f64>, f64)> {
    let probes = engine.probe_set_held(short, applied)?;
    if same_data(&probes, short) {
        return None;
    }
    let pol = &engine.opts.policy;
    let (p, fp) = engine.fit_budget(&probes, applied, e, g, pol.screen_evals);
    let (base_p, base_s) = (engine.score(&probes, applied), engine.score(short, applied));
    if p.is_empty() || !fp.is_finite() || !(base_p > 0.0) || !(base_s > 0.0) {
        return None;
    }
    // Nothing found where the model is most wrong (less than `min_rel_improvement` there): no
    // gain on `short` either, logged at its base RMSE without the replay.
    if 1.0 - fp / base_p < pol.min_rel_improvement {
        return Some((p, base_s));
    }
    let m0 = model_with(engine.robot, applied);
    let at = AtBase::new(engine, short, applied, (e, g), &m0);
    let fs = engine.score(short, &at.set(applied, g, p.clone()));
    if fs.is_finite() && agrees(1.0 - fs / base_s, 1.0 - fp / base_p, pol) {
        return Some((p, fs));
    }
    // A point that reaches the round's bar on `short` admits the candidate whatever a fit
    // there would add (its full fit goes on from it).
    if fs.is_finite() && 1.0 - fs / base_s >= bar {
        return Some((p, fs));
    }
    // A smooth one whose Gauss–Newton model at that point cannot reach the bar either: a
    // coarse fit on `short` would end below it too, and is not made ([`further`]).
    let model = (e.smooth() && bar.is_finite() && fs.is_finite())
        .then(|| further::model_at(engine, (short, applied), (e, g), (&p, fs)))
        .flatten();
    if model.as_ref().is_some_and(|m| 1.0 - m.least / base_s < bar) {
        return Some((p, fs));
    }
    let Some((x, want)) = model.and_then(|m| m.step) else {
        // (A non-smooth one-parameter candidate's grid on `short` goes on from the probes'
        // grid point: the grid around it, the whole grid when that holds no minimum of it.)
        let (q, fq) = if e.smooth() {
            engine.fit_budget(short, applied, e, g, pol.screen_evals)
        } else {
            engine.fit_budget_from(short, applied, (e, g), pol.screen_evals, &p)
        };
        return Some(if fs < fq || q.is_empty() { (p, fs) } else { (q, fq) });
    };
    // Else that model's Gauss–Newton step, replayed once: it stands where it gains on the point
    // what the model predicted ([`agrees`]) or reaches the bar; else the coarse fit on `short`
    // starts from the best of the step, the point and the effect's start.
    let fx = engine.score(short, &at.set(applied, g, x.clone()));
    let (got, pred) = (1.0 - fx / fs, 1.0 - want / fs);
    if fx < fs && (agrees(got, pred, pol) || 1.0 - fx / base_s >= bar) {
        return Some((x, fx));
    }
    let best = if fx < fs { (x, fx) } else { (p, fs) };
    let from = (best.1 < base_s).then_some(best.0.as_slice());
    let (q, fq) = match from {
        Some(b) => engine.fit_budget_from(short, applied, (e, g), pol.screen_evals, b),
        None => engine.fit_budget(short, applied, e, g, pol.screen_evals),
    };
    Some(if best.1 < fq || q.is_empty() { best } else { (q, fq) })
}

/// Whether a relative improvement `got` confirms the `want` a model of it predicted: between
/// `linear_trust` and its inverse times it, or both below `min_rel_improvement` (the secant
/// coarse fit's test, [`Engine::fit_secant`]).
///
/// [`Engine::fit_secant`]: super::engine::Engine
pub(super) fn agrees(got: f64, want: f64, pol: &SearchPolicy) -> bool {
    let small = pol.min_rel_improvement;
    (want.abs() < small && got.abs() < small)
        || (want > 0.0 && got >= pol.linear_trust * want && got * pol.linear_trust <= want)
}

/// A richer model of a loss whose plain variant ([`Effect::plain_variant`]) is a candidate on
/// the same joints in `cands`, coarse-fitted already, waits for its own coarse fit: it is
/// judged first from the plain variant's full fit ([`extension::adds_nothing`]), where its fit
/// starts anyway. Its stand-in (no parameters, the plain variant's coarse RMSE, which the
/// plain fit taken over reaches) orders it right after the plain variant.
pub(super) fn deferred(
    s: &Search,
    (e, g): (&'static dyn Effect, &[String]),
    cands: &[Cand],
    coarse: &[Coarse],
) -> Option<(Vec<f64>, f64)> {
    let f = plain_coarse(s, (e, g), cands, coarse)?.1;
    f.is_finite().then(|| (vec![], f))
}

/// The coarse fit of the plain variant of `e` (one the search may fit) on `g`, when that is a
/// candidate in `cands` and was coarse-fitted.
fn plain_coarse(
    s: &Search,
    (e, g): (&'static dyn Effect, &[String]),
    cands: &[Cand],
    coarse: &[Coarse],
) -> Option<(Vec<f64>, f64)> {
    let plain = e.plain_variant()?;
    if !s.allowed.iter().any(|id| id == plain.id()) {
        return None;
    }
    let i = cands.iter().position(|(p, pg, _)| p.id() == plain.id() && pg.as_slice() == g)?;
    coarse.get(i)?.clone().filter(|c| !is_deferred(c))
}

/// Whether a coarse fit is [`deferred`]'s stand-in (a fit that failed has an infinite RMSE).
pub(super) fn is_deferred(c: &(Vec<f64>, f64)) -> bool {
    c.0.is_empty() && c.1.is_finite()
}

/// A deferred candidate when it is taken: `None` (logged without a fit) when the plain variant
/// was fitted in full on the screen's data and its fit leaves nothing the extension's extra
/// parameters pay for ([`extension::adds_nothing`]), or when it was not and nothing near its
/// coarse fit taken over reaches the round's bar for a full fit (`reaches`, of an SSE on the
/// screen's data; [`extension::could_reach`]: its coarse fit could not admit it either, unless
/// the extra parameters explain what the plain fit leaves); else its coarse fit, as any
/// other candidate's, and in the second case the best point that judgement simulated, which
/// stands in for its linear step (the step of its columns there, replayed).
pub(super) fn when_taken(
    s: &Search,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    (cands, coarse): (&[Cand], &[Coarse]),
    reaches: &dyn Fn(f64) -> bool,
) -> Option<(Point, Option<Point>)> {
    let mut stepped = None;
    if plain_fitted(s, (short, applied), (e, g)) {
        if extension::adds_nothing(s, short, applied, (e, g)) {
            return None;
        }
    } else if let Some((pp, _)) = plain_coarse(s, (e, g), cands, coarse) {
        if nothing_on_probes(s, (short, applied), (e, g), &pp) {
            return None;
        }
        if ext_bound::short_of_bar(s, (short, applied), (e, g), &pp, reaches) {
            return None;
        }
        let (could, least) = extension::could_reach(s, (short, applied), (e, g), &pp, reaches);
        if !could {
            return None;
        }
        stepped = least;
    }
    Some((fit(s.engine, screen, (short, applied), (e, g)), stepped))
}

/// Whether the judgement of a deferred candidate from its plain variant's coarse fit `pp`
/// ([`extension::could_reach`]: that fit taken over, the effect's further starts, the
/// Gauss–Newton step at the best of them), made on the probes' data of `short` instead of on
/// `short`, finds nothing there: no point it simulates gains `min_rel_improvement` on the
/// probes' data against the base there ([`extension::finds_any`]; the step is simulated, its
/// prediction not counted). It has then found nothing where the model is most wrong, as a
/// non-smooth candidate's coarse fit that gains as little there ([`on_probes`]), and
/// is not judged on `short` (it cannot reach the round's bar there: logged `screen`). The
/// judgement's replays cost the probes' seconds instead of the screen's (2 s for 10 s by
/// default); where it finds something it is made on `short` as before. `false` when the
/// probes' data is not held or is `short` itself, the base's replay there fails, or the test
/// cannot be made.
fn nothing_on_probes(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    pp: &[f64],
) -> bool {
    finds_nothing_on_probes(s, short, (applied, &[applied.to_vec()]), (e, g), pp)
}

/// [`nothing_on_probes`] with the points simulated on `base` and their gains measured against
/// the least RMSE of the `references` on the probes' data of `short` (held for the first
/// reference, the round's model): for a deferred candidate the one reference is `base`; a swap
/// of a kept plain fit ([`super::swap`]) simulates its points without that fit and measures
/// them against the round's model and the kept fit taken over.
pub(super) fn finds_nothing_on_probes(
    s: &Search,
    short: &[Recording],
    (base, references): (&[Applied], &[Vec<Applied>]),
    (e, g): (&'static dyn Effect, &[String]),
    pp: &[f64],
) -> bool {
    let engine = s.engine;
    let Some(held) = references.first() else { return false };
    let Some(probes) = engine.probe_set_held(short, held).filter(|p| !same_data(p, short)) else {
        return false;
    };
    let errs: Option<Vec<_>> = references.iter().map(|r| engine.errors(&probes, r)).collect();
    let Some(r) = errs
        .and_then(|v| v.into_iter().min_by(|a, b| a.rmse().total_cmp(&b.rmse())))
        .filter(|b| b.n > 0 && b.rmse() > 0.0)
    else {
        return false;
    };
    let (n, rmse0) = (r.n as f64, r.rmse());
    let min = engine.opts.policy.min_rel_improvement;
    let gains = |sse: f64| 1.0 - (sse / n).sqrt() / rmse0 >= min;
    !extension::finds_any(s, (&probes, base), (e, g), pp, &gains)
}

/// Whether the plain variant of `e` was fitted in full on `g` on the screen's data this round.
/// A deferred candidate whose plain variant was is judged from that fit even once a kept
/// candidate left a white residual: its extra parameters are fitted only where they pay
/// ([`extension::adds_nothing`]), as Occam's nesting rule asks of them.
pub(super) fn plain_fitted(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> bool {
    e.plain_variant().is_some_and(|p| s.engine.fit_known(short, applied, p, g).is_some())
}

/// The screen's linear step of `e` on `g` replayed on `short` (one replay; none when the
/// candidate's coarse fit began there): its parameters and RMSE. Where only the linear model
/// would admit a smooth candidate to a full fit, the step as simulated stands in for the
/// prediction. (Not a non-smooth one: a torque limit's column is that of a kink, and its step
/// can miss a narrow basin that the full fit finds — a heavy knee's 60 N·m limit.)
pub(super) fn replayed_step(
    engine: &Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> Option<(Vec<f64>, f64)> {
    let (_, x) = screen.steps(e.id(), g)?;
    engine.at_linear_step(short, applied, (e, g), &x)
}

#[cfg(test)]
#[path = "coarse_gain_tests.rs"]
mod gain_tests;

#[cfg(test)]
#[path = "coarse_step_tests.rs"]
mod step_tests;

#[cfg(test)]
mod tests {
    use super::{agrees, nothing_on_probes, on_probes};
    use crate::fit::diagnose::diagnose;
    use crate::fit::effects::{Backlash, CoulombFriction, Effect, GainError, StribeckFriction};
    use crate::fit::select::screen::Screen;
    use crate::fit::select::{Engine, FitOptions, Search, SearchPolicy};
    use crate::sim2real::recording::Recording;

    /// The pendulum servo with a gear play of 0.04 rad, recorded by the synth (3 × 3 s).
    fn pendulum_with_play() -> (crate::model::Robot, Vec<Recording>) {
        pendulum(Some(0.04))
    }

    /// The options with a linear trust of 1: no gain is confirmed on the screen's data but a
    /// replay's own.
    fn trusting_no_linear_step() -> FitOptions {
        let policy = SearchPolicy { linear_trust: 1.0, ..SearchPolicy::default() };
        FitOptions { policy, ..FitOptions::default() }
    }

    /// Recording seconds of a dataset.
    fn seconds(r: &[Recording]) -> f64 {
        r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>()
    }

    /// The pendulum servo, with a gear play of `play` rad when given, recorded by the synth
    /// (3 × 3 s).
    fn pendulum(play: Option<f64>) -> (crate::model::Robot, Vec<Recording>) {
        crate::synth::recorded::pendulum(play.map(|w| (Backlash.id(), vec![w])), 3, 7)
    }

    /// A non-smooth candidate's coarse fit runs on the probes' data and is replayed once on the
    /// screen's: the play is found as the grid on the screen's data finds it, for the probes'
    /// seconds per replay instead of the screen's.
    #[test]
    fn a_non_smooth_coarse_fit_runs_on_the_probes_data() {
        let (robot, recs) = pendulum_with_play();
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let g = vec!["servo".to_string()];
        // Not held: no screen made the probes' data on this base.
        assert!(on_probes(&engine, (&recs, &[]), (&Backlash, &g), f64::INFINITY).is_none());
        let probes = engine.probe_set(&recs, &[], || vec![recs[1].clone()]);
        let base = engine.errors_held(&recs, &[]).expect("replay").rmse();
        let _ = engine.errors_held(&probes, &[]).expect("replay");
        let before = engine.rollout_stats().simulated_s;
        let (p, f) =
            on_probes(&engine, (&recs, &[]), (&Backlash, &g), f64::INFINITY).expect("fitted");
        let cost = engine.rollout_stats().simulated_s - before;
        // The play explains most of the residual, at the grid's point of the truth.
        assert!((p[0] - 0.04).abs() < 1e-9 && f < 0.5 * base, "{p:?}: {f} of {base}");
        let budget = opts.policy.screen_evals as f64 * seconds(&probes) + seconds(&recs);
        assert!(cost <= budget + 1e-9, "{cost} s replayed for {budget}");
        // The coarse fit on the screen's data finds the same, for more.
        let before = engine.rollout_stats().simulated_s;
        let (q, fq) = engine.fit_budget(&recs, &[], &Backlash, &g, opts.policy.screen_evals);
        assert_eq!((q, fq), (p, f));
        assert!(engine.rollout_stats().simulated_s - before > cost);
    }

    /// A non-smooth candidate that explains nothing on the probes' data (a play where the
    /// recordings have none) is not replayed on the screen's data: it costs the probes' fit
    /// alone and is logged at the screen's base RMSE, no gain.
    #[test]
    fn a_non_smooth_coarse_fit_that_finds_nothing_on_the_probes_is_not_replayed() {
        let (robot, recs) = pendulum(None);
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let g = vec!["servo".to_string()];
        let probes = engine.probe_set(&recs, &[], || vec![recs[1].clone()]);
        let base = engine.errors_held(&recs, &[]).expect("replay").rmse();
        let base_p = engine.errors_held(&probes, &[]).expect("replay").rmse();
        let before = engine.rollout_stats().simulated_s;
        let (p, f) =
            on_probes(&engine, (&recs, &[]), (&Backlash, &g), f64::INFINITY).expect("fitted");
        let cost = engine.rollout_stats().simulated_s - before;
        assert_eq!(f, base, "{p:?}");
        // What the fit found on the probes' data is below the smallest improvement kept.
        let (_, fp) = engine.fit_budget(&probes, &[], &Backlash, &g, opts.policy.screen_evals);
        assert!(1.0 - fp / base_p < opts.policy.min_rel_improvement, "{fp} of {base_p}");
        // Only the probes' fit was replayed, nothing of the screen's data.
        let budget = opts.policy.screen_evals as f64 * seconds(&probes);
        assert!(cost <= budget + 1e-9, "{cost} s replayed for {budget}");
    }

    /// Where the probes' fit, replayed on the screen's data, does not confirm the gain it made on
    /// the probes (here: a trust of 1, which confirms no gain but itself), the coarse fit on the
    /// screen's data follows — unless that replay reaches the round's bar: the point admits the
    /// candidate and stands, for no more than its one replay of the screen's data.
    #[test]
    fn a_probes_fit_whose_replay_reaches_the_bar_stands() {
        let (robot, recs) = pendulum_with_play();
        let opts = trusting_no_linear_step();
        let engine = Engine::new(&robot, &recs, &opts);
        let g = vec!["servo".to_string()];
        let probes = engine.probe_set(&recs, &[], || vec![recs[1].clone()]);
        let base = engine.score(&recs, &[]);
        let base_p = engine.score(&probes, &[]);
        let (q, fq) = engine.fit_budget(&probes, &[], &Backlash, &g, opts.policy.screen_evals);
        let m0 = super::model_with(&robot, &[]);
        let neutral = crate::fit::select::engine::neutral_params(&robot, &m0, (&Backlash, &g));
        let at = crate::fit::select::engine::with_candidate(
            &[],
            (&Backlash, &g),
            q.clone(),
            neutral.as_deref(),
        );
        let fs = engine.score(&recs, &at);
        let (reached, want) = (1.0 - fs / base, 1.0 - fq / base_p);
        assert!(reached > opts.policy.min_rel_improvement && reached != want, "{reached} {want}");
        // Its replay reaches the bar: the probes' fit stands, no fit on the screen's data.
        let before = engine.rollout_stats().simulated_s;
        let got = on_probes(&engine, (&recs, &[]), (&Backlash, &g), reached);
        assert_eq!(got, Some((q.clone(), fs)));
        assert!(engine.rollout_stats().simulated_s - before <= seconds(&recs) + 1e-9);
        // Just short of it: the coarse fit on the screen's data is made.
        let before = engine.rollout_stats().simulated_s;
        let _ = on_probes(&engine, (&recs, &[]), (&Backlash, &g), reached + 1e-9);
        assert!(engine.rollout_stats().simulated_s - before >= seconds(&recs));
    }

    /// Where the probes' fit of a non-smooth one-parameter candidate does not confirm its gain on
    /// the screen's data (a trust of 1) and no bar admits it, the coarse fit on the screen's
    /// data goes on from the probes' grid point: only the grid points around it are replayed
    /// (three beside the one replayed already, of the grid's five others), and it finds what
    /// the whole grid there finds (a fresh engine's coarse fit on the screen's data).
    #[test]
    fn a_non_smooth_fallback_replays_the_grid_around_the_probes_point() {
        let (robot, recs) = pendulum_with_play();
        let opts = trusting_no_linear_step();
        let engine = Engine::new(&robot, &recs, &opts);
        let g = vec!["servo".to_string()];
        let evals = opts.policy.screen_evals;
        let probes = engine.probe_set(&recs, &[], || vec![recs[1].clone()]);
        let _ = engine.errors_held(&recs, &[]).expect("replay");
        let _ = engine.errors_held(&probes, &[]).expect("replay");
        let (q, _) = engine.fit_budget(&probes, &[], &Backlash, &g, evals);
        let before = engine.rollout_stats().simulated_s;
        let got = on_probes(&engine, (&recs, &[]), (&Backlash, &g), f64::INFINITY).expect("fit");
        let cost = engine.rollout_stats().simulated_s - before;
        // The probes' point replayed on the screen's data, then three more points of the grid.
        assert!(cost <= 4.0 * seconds(&recs) + 1e-9, "{cost} s replayed for {}", seconds(&recs));
        assert!(
            cost >= 2.0 * seconds(&recs) - 1e-9,
            "{cost} s replayed: no fit on the screen's data"
        );
        let fresh = Engine::new(&robot, &recs, &opts);
        let whole = fresh.fit_budget(&recs, &[], &Backlash, &g, evals);
        assert_eq!(got, whole, "from the probes' point {q:?}");
    }

    /// A smooth candidate whose probes' fit, replayed on the screen's data, neither confirms its
    /// gain there nor reaches the bar (a gain error under a trust of 1) is coarse-fitted on the
    /// screen's data only when the Gauss–Newton model at that point could reach the bar
    /// ([`further::least_rmse`]): above the model's reach the probes' point stands, for one
    /// replay per parameter of the screen's data; below it the model's step and what follows
    /// (`coarse_step_tests.rs`) improve on the point.
    #[test]
    fn a_smooth_candidate_beyond_its_models_reach_is_not_fitted_on_the_screens_data() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((GainError.id(), vec![0.9, 1.4])), 3, 7);
        let policy = SearchPolicy { linear_trust: 1.0, ..SearchPolicy::default() };
        let opts = FitOptions { policy, ..FitOptions::default() };
        let engine = Engine::new(&robot, &recs, &opts);
        let g = vec!["servo".to_string()];
        let probes = engine.probe_set(&recs, &[], || vec![recs[1].clone()]);
        let base = engine.errors_held(&recs, &[]).expect("replay").rmse();
        let _ = engine.errors_held(&probes, &[]).expect("replay");
        let (q, _) = engine.fit_budget(&probes, &[], &GainError, &g, opts.policy.screen_evals);
        let m0 = super::model_with(&robot, &[]);
        let neutral = crate::fit::select::engine::neutral_params(&robot, &m0, (&GainError, &g));
        let at = crate::fit::select::engine::with_candidate(
            &[],
            (&GainError, &g),
            q.clone(),
            neutral.as_deref(),
        );
        let fs = engine.score(&recs, &at);
        let most = super::further::least_rmse(&engine, (&recs, &[]), (&GainError, &g), (&q, fs))
            .expect("modelled");
        let (reached, reach) = (1.0 - fs / base, 1.0 - most / base);
        assert!(reach > reached + 1e-3, "the model adds {reach} to {reached}");
        // Above the model's reach: the point stands, no fit on the screen's data.
        let before = engine.rollout_stats().simulated_s;
        let got = on_probes(&engine, (&recs, &[]), (&GainError, &g), reach + 1e-3);
        assert_eq!(got, Some((q.clone(), fs)));
        assert!(engine.rollout_stats().simulated_s - before <= 2.0 * seconds(&recs) + 1e-9);
        // Within it: more is replayed on the screen's data, and found.
        let before = engine.rollout_stats().simulated_s;
        let bar = 0.5 * (reached + reach);
        let (_, f) = on_probes(&engine, (&recs, &[]), (&GainError, &g), bar).expect("fitted");
        assert!(engine.rollout_stats().simulated_s - before >= seconds(&recs) - 1e-6);
        assert!(f < fs, "{f} from the point's {fs}");
    }

    /// The pendulum servo, with a Coulomb friction of `friction` N·m when given, recorded by
    /// the synth (3 × 3 s).
    fn pendulum_with_friction(friction: Option<f64>) -> (crate::model::Robot, Vec<Recording>) {
        crate::synth::recorded::pendulum(friction.map(|c| (CoulombFriction.id(), vec![c])), 3, 11)
    }

    /// A friction extension deferred on its plain variant's coarse fit is first judged on the
    /// probes' data: where the recordings hold no friction, no point of that judgement gains
    /// there, and it costs the probes' seconds alone (no replay of the screen's data); where
    /// they hold the friction, the plain fit taken over gains there and the judgement goes on
    /// on the screen's data.
    #[test]
    fn a_deferred_extension_that_finds_nothing_on_the_probes_is_not_judged_further() {
        let opts = FitOptions::default();
        let allowed: Vec<String> =
            crate::fit::effects::all().iter().map(|e| e.id().into()).collect();
        let g = vec!["servo".to_string()];
        for (friction, nothing) in [(None, true), (Some(0.08), false)] {
            let (robot, recs) = pendulum_with_friction(friction);
            let engine = Engine::new(&robot, &recs, &opts);
            let s = Search { engine: &engine, train: &recs, heldout: &recs, allowed: &allowed };
            // Not held: no screen made the probes' data on this base.
            assert!(!nothing_on_probes(&s, (&recs, &[]), (&StribeckFriction, &g), &[0.08]));
            let probes = engine.probe_set(&recs, &[], || vec![recs[1].clone()]);
            let _ = engine.errors_held(&recs, &[]).expect("replay");
            let before = engine.rollout_stats().simulated_s;
            let _ = engine.errors_held(&probes, &[]).expect("replay");
            let one = engine.rollout_stats().simulated_s - before;
            let before = engine.rollout_stats().simulated_s;
            // The plain variant's fit at the truth (or at that level where there is none).
            let got = nothing_on_probes(&s, (&recs, &[]), (&StribeckFriction, &g), &[0.08]);
            let cost = engine.rollout_stats().simulated_s - before;
            assert_eq!(got, nothing, "friction {friction:?}");
            // Every replay was of the probes' data: a whole number of its replays.
            let n = cost / one;
            assert!(one > 0.0 && n >= 1.0 && (n - n.round()).abs() < 1e-6, "{cost} s for {one} s");
        }
    }

    /// A smooth candidate whose linear step does not confirm (here: a gain error under a trust
    /// of 1, which confirms no gain but itself) is coarse-fitted on the probes' data once a fit
    /// set the round's bar, as a non-smooth one, and that fit, replayed once on the screen's
    /// data, stands where it reaches the bar: the step's replay and that one are all it costs
    /// of the screen's data. Before a bar is set (the round's lead) it is coarse-fitted on the
    /// screen's data, as it was.
    #[test]
    fn a_smooth_coarse_fit_without_a_confirmed_step_runs_on_the_probes_data() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((GainError.id(), vec![0.9, 1.4])), 3, 7);
        let policy = SearchPolicy { linear_trust: 1.0, ..SearchPolicy::default() };
        let opts = FitOptions { policy, ..FitOptions::default() };
        let engine = Engine::new(&robot, &recs, &opts);
        let g = vec!["servo".to_string()];
        let evals = opts.policy.screen_evals;
        let base = engine.errors_held(&recs, &[]).expect("replay");
        let allowed = vec![GainError.id().to_string()];
        let mut diag =
            diagnose(&robot, &recs, &base.eps, &engine.joints, &allowed, opts.gap_mask_s);
        let screen = Screen::build(&engine, &recs, &[], &base, &mut diag, &|_, _| false);
        let probes = engine.probe_set_held(&recs, &[]).expect("made by the screen");
        let (q, _) = engine.fit_budget(&probes, &[], &GainError, &g, evals);
        let bar = opts.policy.min_rel_improvement;
        let before = engine.rollout_stats().simulated_s;
        let (p, f) = super::fit_to(&engine, &screen, (&recs, &[]), (&GainError, &g), bar);
        let cost = engine.rollout_stats().simulated_s - before;
        assert_eq!(p, q, "the probes' fit stands");
        assert!(1.0 - f / base.rmse() >= bar, "{f} of {}", base.rmse());
        assert!(cost <= 2.0 * seconds(&recs) + 1e-9, "{cost} s replayed");
        // No bar yet: the coarse fit on the screen's data.
        let before = engine.rollout_stats().simulated_s;
        let (p0, _) = super::fit(&engine, &screen, (&recs, &[]), (&GainError, &g));
        assert!(engine.rollout_stats().simulated_s - before > 2.0 * seconds(&recs));
        assert_eq!(p0, engine.fit_budget(&recs, &[], &GainError, &g, evals).0);
    }

    #[test]
    fn a_gain_agrees_within_the_linear_trust_or_when_both_are_small() {
        let pol = SearchPolicy::default();
        assert!(agrees(0.3, 0.35, &pol) && agrees(0.35, 0.3, &pol));
        assert!(!agrees(0.2, 0.35, &pol) && !agrees(0.5, 0.35, &pol));
        assert!(agrees(0.01, -0.01, &pol) && !agrees(-0.1, -0.1, &pol));
        assert!(!agrees(0.05, 0.01, &pol));
    }
}
