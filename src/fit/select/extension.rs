//! A richer model of a loss fitted only when the plain model's fit leaves its signature.
//!
//! A friction model that elaborates a plain one ([`Effect::plain_variant`]: Stribeck or
//! load-dependent friction around Coulomb friction) and holds it as a special case
//! ([`Effect::absorb`]) is, at the plain model's fit taken over, the plain fit itself (up to
//! how each is applied: Coulomb friction is MuJoCo's soft `frictionloss`, Stribeck friction
//! exact stiction — on KR2 the first leaves 27 % less squared error at the same level). Its extra
//! parameters can only win where the residual that fit leaves has their shape. So before its
//! full fit (a simplex of 2 (k − 1) × `max_evals` replays) the extension is judged from there:
//! one replay per fitted parameter gives its finite-difference columns, the
//! least-squares (Gauss–Newton) step on them is predicted and simulated, and the model's own
//! further starts ([`Effect::nested_alternatives`]) are replayed; the columns and the step are
//! taken at the best of these starts (the plain fit taken over or a further start), since
//! extra parameters that act only where the plain fit rarely goes (a breakaway felt only at
//! rest) have nearly flat columns at the plain fit. When none of these lowers the
//! information criterion counted per window ([`bic_pieces`]) below the plain fit's — its extra
//! parameters buy nothing there — the full fit is left out (`tried`: phase "screen").
//!
//! What provably replays as a point replayed already is not replayed ([`Effect::idle`]: a
//! parameter the simulation does not depend on at a point). The plain fit taken over by
//! Stribeck friction has static = sliding level, where the velocity scale shapes a breakaway
//! of zero height: that parameter's column there is exactly zero, and where the plain level is
//! zero every further start (a multiple of it, at another velocity scale) is the same point.
//! The judgement's decisions are those of every replay made.
//!
//! [`Effect::plain_variant`]: crate::fit::effects::Effect::plain_variant
//! [`Effect::absorb`]: crate::fit::effects::Effect::absorb
//! [`Effect::nested_alternatives`]: crate::fit::effects::Effect::nested_alternatives
//! [`Effect::idle`]: crate::fit::effects::Effect::idle
//! [`bic_pieces`]: crate::fit::stats::bic_pieces

use rayon::prelude::*;

use crate::fit::effects::{self, Applied, Effect, JointTarget, model_with};
use crate::fit::stats::bic_pieces;
use crate::sim2real::recording::Recording;

use super::Search;
use super::screen::combine;

/// `true` when `effect` on `group` elaborates a plain variant that the search may fit, holds it
/// as a special case (checked before anything is fitted), and on `short` (the round's screen data, with `applied` kept) nothing
/// near the plain variant's full fit taken over pays for the extra parameters (see the module
/// docs). `false` — fit it in full — otherwise, and whenever the test cannot be made.
pub(super) fn adds_nothing(
    s: &Search,
    short: &[Recording],
    applied: &[Applied],
    (effect, group): (&'static dyn Effect, &[String]),
) -> bool {
    let engine = s.engine;
    let Some(plain) = nested_plain(s, effect, group) else { return false };
    // The plain variant's full fit on the same data and joints (the memo's answer when the
    // round already fitted it, as it does before the richer model in rank order).
    let (pp, _) = engine.fit_one(short, applied, plain, group);
    if pp.is_empty() {
        return false;
    }
    let mut plain_set = applied.to_vec();
    plain_set.push(Applied { effect: plain, joints: group.to_vec(), params: pp.clone() });
    let Some(e_plain) = engine.errors(short, &plain_set) else { return false };
    let k_base: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let m = e_plain.windows.len();
    let criterion = |sse: f64, kk: usize| bic_pieces(m, e_plain.n, sse, k_base + kk);
    let to_beat = criterion(e_plain.sse, plain.fitted());
    if !to_beat.is_finite() {
        return false;
    }
    let beats = |sse: f64| sse.is_finite() && criterion(sse, effect.fitted()) < to_beat;
    !improves_on(s, (short, applied), (effect, group), (plain, &pp), (&beats, true)).0
}

/// `false` when `effect` on `group` elaborates a plain variant that the search may fit and
/// holds it as a special case, and no point the module's judgement replays or predicts from
/// the plain variant's coarse fit `pp` taken over (that start, the effect's further starts, the
/// Gauss–Newton step on its columns, simulated and predicted) leaves an SSE on `short` for which
/// `reaches` holds. `true` — coarse-fit it — otherwise, and whenever the test cannot be made;
/// with the simulated point of least error (its parameters and RMSE on `short`), which stands
/// in for the candidate's linear step.
///
/// A deferred candidate ([`super::coarse::deferred`]) whose plain variant's coarse fit did not
/// reach the round's bar for a full fit is judged so before its own coarse fit: its extra
/// parameters could only lift it over the bar where the residual the plain fit leaves has
/// their shape.
pub(super) fn could_reach(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    (effect, group): (&'static dyn Effect, &[String]),
    pp: &[f64],
    reaches: &dyn Fn(f64) -> bool,
) -> (bool, Option<(Vec<f64>, f64)>) {
    let Some(plain) = nested_plain(s, effect, group) else { return (true, None) };
    if pp.len() != plain.params().len() {
        return (true, None);
    }
    improves_on(s, (short, applied), (effect, group), (plain, pp), (reaches, true))
}

/// [`could_reach`] on `data` that counts only the points it simulates (the starts and the
/// Gauss–Newton step, which is simulated whatever its prediction): `false` when no simulated
/// point leaves an SSE for which `gains` holds, `true` otherwise or when the test cannot be made.
pub(super) fn finds_any(
    s: &Search,
    (data, applied): (&[Recording], &[Applied]),
    (effect, group): (&'static dyn Effect, &[String]),
    pp: &[f64],
    gains: &dyn Fn(f64) -> bool,
) -> bool {
    let Some(plain) = nested_plain(s, effect, group) else { return true };
    pp.len() != plain.params().len()
        || improves_on(s, (data, applied), (effect, group), (plain, pp), (gains, false)).0
}

/// The start of `effect` on `group` (beside `applied`, on `train`) that its plain variant's
/// full fit gives, taken over ([`taken_over`]): where the search may fit the plain variant
/// and `effect` holds it as a special case, the richer model there replays as the plain fit
/// (up to how each is applied) and its own full fit starts from it. `None` otherwise, or when
/// that fit fails. Costs the plain variant's fit (a one-parameter line search, memoised).
pub(super) fn plain_start(
    s: &Search,
    (train, applied): (&[Recording], &[Applied]),
    (effect, group): (&'static dyn Effect, &[String]),
) -> Option<Vec<f64>> {
    let plain = nested_plain(s, effect, group)?;
    let (pp, f) = s.engine.fit_one(train, applied, plain, group);
    if pp.is_empty() || !f.is_finite() {
        return None;
    }
    taken_over(s, applied, (effect, group), (plain, &pp))
}

/// The plain variant of `effect` when the search may fit it on `group` and `effect` holds it as
/// a special case ([`Effect::absorb`]).
fn nested_plain(
    s: &Search,
    effect: &'static dyn Effect,
    group: &[String],
) -> Option<&'static dyn Effect> {
    let plain = effect.plain_variant()?;
    if !s.allowed.iter().any(|id| id == plain.id()) || group.is_empty() {
        return None;
    }
    let zero: Vec<f64> = effect.params().iter().map(|d| d.default).collect();
    effect.absorb(plain, &zero, &vec![0.0; plain.params().len()])?;
    Some(plain)
}

/// The plain variant's fit `pp` on `group` (beside `applied`) taken over by `effect` from its
/// parameters' defaults ([`Effect::absorb`]); `None` when `effect` does not hold it.
pub(super) fn taken_over(
    s: &Search,
    applied: &[Applied],
    (effect, group): (&'static dyn Effect, &[String]),
    (plain, pp): (&'static dyn Effect, &[f64]),
) -> Option<Vec<f64>> {
    let zero: Vec<f64> = effect.params().iter().map(|d| d.default).collect();
    let t = JointTarget::of(s.engine.robot, group.first()?)?;
    let m0 = model_with(s.engine.robot, applied);
    let delta: Vec<f64> = pp.iter().zip(plain.initial(&m0, &t)).map(|(a, b)| a - b).collect();
    effect.absorb(plain, &zero, &delta)
}

/// The extension's points near the plain variant's fit taken over, replayed on one dataset: the
/// plain fit taken over by the richer model (from its parameters' defaults) and the model's own
/// further starts from it, each's SSE and RMSE (infinite where the replay failed), and how many
/// of the first parameters are fitted (`k`) inside the box `lo`..`hi`.
struct Near {
    starts: Vec<Vec<f64>>,
    errs: Vec<(f64, f64)>,
    best: usize,
    k: usize,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl Near {
    /// The starts of `effect` on `group` from the plain variant's fit `pp` (see [`Near`]),
    /// replayed on `data` with `applied`; `None` when the fit cannot be taken over.
    fn at(
        s: &Search,
        (data, applied): (&[Recording], &[Applied]),
        (effect, group): (&'static dyn Effect, &[String]),
        (plain, pp): (&'static dyn Effect, &[f64]),
    ) -> Option<Near> {
        let engine = s.engine;
        let t = JointTarget::of(engine.robot, &group[0])?;
        let m0 = model_with(engine.robot, applied);
        let x0 = taken_over(s, applied, (effect, group), (plain, pp))?;
        let (lo, hi) = effect.bounds(&m0, &t);
        let k = effect.fitted().min(x0.len()).min(lo.len());
        if k == 0 {
            return None;
        }
        let clamp = |a: &[f64]| -> Vec<f64> {
            a.iter()
                .enumerate()
                .map(|(i, v)| if i < k { v.clamp(lo[i], hi[i]) } else { *v })
                .collect()
        };
        let x0 = clamp(&x0);
        let mut starts = vec![x0.clone()];
        starts.extend(
            effect.nested_alternatives(&x0).iter().filter(|a| a.len() >= k).map(|a| clamp(a)),
        );
        // A start that provably replays as an earlier one replayed ([`same_replay`]) is not.
        let mut first: Vec<usize> = Vec::with_capacity(starts.len());
        for i in 0..starts.len() {
            let same = |&j: &usize| first[j] == j && same_replay(effect, &starts[j], &starts[i]);
            let f = (0..i).find(same).unwrap_or(i);
            first.push(f);
        }
        let own: Vec<(f64, f64)> = (0..starts.len())
            .into_par_iter()
            .map(|i| {
                if first[i] != i {
                    return (f64::NAN, f64::NAN);
                }
                engine
                    .errors(data, &with(applied, (effect, group), &starts[i]))
                    .map_or((f64::INFINITY, f64::INFINITY), |e| (e.sse, e.rmse()))
            })
            .collect();
        let errs: Vec<(f64, f64)> = first.iter().map(|&j| own[j]).collect();
        let best = (0..starts.len()).fold(0, |b, i| if errs[i].0 < errs[b].0 { i } else { b });
        Some(Near { starts, errs, best, k, lo, hi })
    }

    /// The least SSE of the starts.
    fn least_sse(&self) -> f64 {
        self.errs[self.best].0
    }

    /// The Gauss–Newton model at the best start on `data`: one replay per fitted parameter
    /// gives its finite-difference column, and the least-squares combination of the columns
    /// ([`combine`]) the SSE it explains of that start's residual and its step. `None` when a
    /// replay fails or a parameter cannot move.
    fn gauss_newton(
        &self,
        s: &Search,
        (data, applied): (&[Recording], &[Applied]),
        (effect, group): (&'static dyn Effect, &[String]),
    ) -> Option<(f64, Vec<f64>)> {
        let engine = s.engine;
        let resid = |p: &[f64]| {
            engine.residuals(data, &with(applied, (effect, group), p), &engine.joints, usize::MAX)
        };
        let (xb, (lo, hi)) = (&self.starts[self.best], (&self.lo, &self.hi));
        let rb = resid(xb)?;
        let cols: Vec<Option<Vec<f64>>> = (0..self.k)
            .into_par_iter()
            .map(|i| {
                let v = effects::probe_step(xb[i], lo[i], hi[i]);
                let h = v - xb[i];
                if h == 0.0 {
                    return None;
                }
                // A parameter idle at the start: its column is exactly zero, as a replay gives.
                if effect.idle(xb, i) {
                    return Some(vec![0.0; rb.len()]);
                }
                let mut x = xb.clone();
                x[i] = v;
                let r1 = resid(&x)?;
                // Residuals are real − sim: the column of the simulation is −Δr / h.
                (r1.len() == rb.len())
                    .then(|| r1.iter().zip(&rb).map(|(b, a)| (a - b) / h).collect())
            })
            .collect();
        let cols = cols.into_iter().collect::<Option<Vec<Vec<f64>>>>()?;
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let b: Vec<f64> = cols.iter().map(|c| dot(c, &rb)).collect();
        let g: Vec<Vec<f64>> =
            cols.iter().map(|x| cols.iter().map(|y| dot(x, y)).collect()).collect();
        Some(combine(&b, &g))
    }
}

/// Whether `effect` replays exactly (bit for bit) at `b` as at `a`: the two are equal, or
/// differ in one parameter that is idle at `a` ([`Effect::idle`]: the simulation does not
/// depend on it while the others hold their values, which are `b`'s). Only one parameter:
/// each of two idle alone at `a` need not be idle together.
///
/// [`Effect::idle`]: crate::fit::effects::Effect::idle
fn same_replay(effect: &dyn Effect, a: &[f64], b: &[f64]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut apart = (0..a.len()).filter(|&i| a[i].to_bits() != b[i].to_bits());
    match (apart.next(), apart.next()) {
        (None, _) => true,
        (Some(i), None) => effect.idle(a, i),
        _ => false,
    }
}

/// `applied` with `effect` on `group` at `p`.
fn with(
    applied: &[Applied],
    (effect, group): (&'static dyn Effect, &[String]),
    p: &[f64],
) -> Vec<Applied> {
    let mut set = applied.to_vec();
    set.push(Applied { effect, joints: group.to_vec(), params: p.to_vec() });
    set
}

/// The least SSE on `data` (with `applied`) that the judgement's linear model near the plain
/// variant's fit `pp` taken over by `effect` allows ([`Near`]: that start and the effect's
/// further starts replayed; the Gauss–Newton model of every fitted parameter's column at the
/// best of them): the least of the starts' SSEs and of the best start's SSE less what its
/// columns explain. The columns are the extension's own parameters moved one at a time at that
/// start, so they hold the shape of every extra parameter whatever the screen probed
/// ([`super::ext_bound`] bounds the judgement by it). `None` when the effect does not hold the
/// plain variant, or a replay fails.
pub(super) fn linear_least(
    s: &Search,
    (data, applied): (&[Recording], &[Applied]),
    (effect, group): (&'static dyn Effect, &[String]),
    pp: &[f64],
) -> Option<f64> {
    let plain = nested_plain(s, effect, group)?;
    if pp.len() != plain.params().len() {
        return None;
    }
    let near = Near::at(s, (data, applied), (effect, group), (plain, pp))?;
    let (explained, _) = near.gauss_newton(s, (data, applied), (effect, group))?;
    let sse_b = near.least_sse();
    let least = sse_b.min((sse_b - explained).max(0.0));
    least.is_finite().then_some(least)
}

/// Whether some point near the plain variant's fit `pp` taken over by `effect` leaves an SSE
/// on `short` for which `beats` holds: that start and the effect's further starts replayed,
/// the Gauss–Newton step on the columns at the best of them predicted (when `predicted`: its
/// predicted SSE counts too) and simulated (see the module docs), and the simulated point of
/// least SSE (its parameters and RMSE on `short`). `true` whenever the test cannot be made.
fn improves_on(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    (effect, group): (&'static dyn Effect, &[String]),
    (plain, pp): (&'static dyn Effect, &[f64]),
    (beats, predicted): (&dyn Fn(f64) -> bool, bool),
) -> (bool, Option<(Vec<f64>, f64)>) {
    const UNTESTED: (bool, Option<(Vec<f64>, f64)>) = (true, None);
    let engine = s.engine;
    let data = (short, applied);
    let Some(near) = Near::at(s, data, (effect, group), (plain, pp)) else { return UNTESTED };
    let (best, k) = (near.best, near.k);
    let mut least =
        Some((near.starts[best].clone(), near.errs[best].1)).filter(|p| p.1.is_finite());
    if near.errs.iter().any(|&(f, _)| beats(f)) {
        return (true, least);
    }
    // The columns of its fitted parameters at the best of the starts. Where the extra
    // parameters act only in a regime the plain fit barely enters (exact stiction's static
    // excess acts only at rest), their columns at the plain fit are nearly flat and the step
    // stays near it; from the best start the step reaches the level. KR2 (Stribeck truth):
    // from (c, c, 0.1) the step explains 5 % of that start's residual, predicted SSE 9.4e-3
    // against the 5.4e-3 that beats the plain fit's BIC; from (2c, c, 0.05) 24 %, 4.5e-3.
    let (xb, sse_b) = (&near.starts[best], near.least_sse());
    let Some((explained, step)) = near.gauss_newton(s, data, (effect, group)) else {
        return UNTESTED;
    };
    if predicted && beats(sse_b - explained) {
        return (true, least);
    }
    // The linear model does not ask for it; its step is simulated all the same (a kink's
    // column can under-state what the step does).
    let (lo, hi) = (&near.lo, &near.hi);
    let x1: Vec<f64> = xb
        .iter()
        .enumerate()
        .map(|(i, v)| if i < k { (v + step[i]).clamp(lo[i], hi[i]) } else { *v })
        .collect();
    let (sse1, rmse1) = engine
        .errors(short, &with(applied, (effect, group), &x1))
        .map_or((f64::INFINITY, f64::INFINITY), |e| (e.sse, e.rmse()));
    if sse1 < sse_b && rmse1.is_finite() {
        least = Some((x1, rmse1));
    }
    (beats(sse1), least)
}

#[cfg(test)]
mod tests {
    use super::{Near, could_reach, plain_start, with};
    use crate::fit::effects::{CoulombFriction, Effect, StribeckFriction, probe_step};
    use crate::fit::select::{Engine, FitOptions, Search};
    use crate::sim2real::recording::Recording;

    /// Judged from a plain Coulomb level of zero (on a servo whose recordings hold Coulomb
    /// friction), Stribeck friction's starts — the level taken over and the further starts at
    /// other velocity scales — are one point, and there the velocity scale's column is zero: the
    /// judgement replays that point, the two levels' columns and the step, at most four replays
    /// where every point replayed would be seven. What it skips is what a replay gives: every
    /// start, and the start with its velocity scale moved to its probe value, replayed by a
    /// fresh engine, leave the same error to the last bit.
    #[test]
    fn points_that_provably_replay_alike_are_replayed_once() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((CoulombFriction.id(), vec![0.05])), 3, 11);
        let opts = FitOptions::default();
        let allowed: Vec<String> =
            crate::fit::effects::all().iter().map(|e| e.id().into()).collect();
        let g = ["servo".to_string()];
        let cand = (&StribeckFriction as &'static dyn Effect, &g[..]);
        let secs = |r: &[Recording]| r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>();
        let engine = Engine::new(&robot, &recs, &opts);
        let s = Search { engine: &engine, train: &recs, heldout: &recs, allowed: &allowed };
        let _ = engine.errors_held(&recs, &[]).expect("replay");
        let before = engine.rollout_stats().simulated_s;
        let (could, _) = could_reach(&s, (&recs, &[]), cand, &[0.0], &|_| false);
        let cost = engine.rollout_stats().simulated_s - before;
        assert!(!could);
        assert!(cost <= 4.0 * secs(&recs) + 1e-6, "{cost} s for {} s a replay", secs(&recs));
        let near = Near::at(&s, (&recs, &[]), cand, (&CoulombFriction, &[0.0])).expect("starts");
        let scales: Vec<f64> = near.starts.iter().map(|p| p[2]).collect();
        assert!(near.starts.len() == 4 && scales.iter().any(|&v| v != scales[0]), "{scales:?}");
        let fresh = Engine::new(&robot, &recs, &opts);
        let sse = |p: &[f64]| fresh.errors(&recs, &with(&[], cand, p)).expect("replay").sse;
        let x0 = &near.starts[0];
        assert!(x0[0] == 0.0 && x0[1] == 0.0, "{x0:?}");
        for p in &near.starts {
            assert_eq!(sse(p).to_bits(), sse(x0).to_bits(), "{p:?}");
        }
        let mut moved = x0.clone();
        moved[2] = probe_step(x0[2], near.lo[2], near.hi[2]);
        assert!(moved[2] != x0[2] && sse(&moved).to_bits() == sse(x0).to_bits());
        // A level of some height: its starts are apart (each replayed).
        let near = Near::at(&s, (&recs, &[]), cand, (&CoulombFriction, &[0.05])).expect("starts");
        assert!(near.errs.iter().skip(1).all(|e| e.0 != near.errs[0].0), "{:?}", near.errs);
    }

    /// The pair look-ahead's start of Stribeck friction on a servo whose recordings hold
    /// Coulomb friction 0.05 N·m is Coulomb friction's full fit taken over — both levels at
    /// that fit, the velocity scale at its default — and costs exactly what that fit costs on a
    /// fresh engine: no replay with Stribeck friction (its own full fit is a simplex of whole-set
    /// replays). Where Coulomb friction may not be fitted, there is no such start.
    #[test]
    fn an_extension_starts_from_its_plain_fit_taken_over_at_no_cost_of_its_own() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((CoulombFriction.id(), vec![0.05])), 3, 11);
        let opts = FitOptions::default();
        let all: Vec<String> = crate::fit::effects::all().iter().map(|e| e.id().into()).collect();
        let g = ["servo".to_string()];
        let cand = (&StribeckFriction as &'static dyn Effect, &g[..]);
        let engine = Engine::new(&robot, &recs, &opts);
        let s = Search { engine: &engine, train: &recs, heldout: &recs, allowed: &all };
        let start = plain_start(&s, (&recs, &[]), cand).expect("a start");
        let cost = engine.rollout_stats().simulated_s;
        let fresh = Engine::new(&robot, &recs, &opts);
        let (c, f) = fresh.fit_one(&recs, &[], &CoulombFriction, &g);
        assert!(f.is_finite() && (c[0] - 0.05).abs() < 0.02, "{c:?}");
        assert!((cost - fresh.rollout_stats().simulated_s).abs() < 1e-9, "{cost} s");
        let default_vs = StribeckFriction.params()[2].default;
        assert_eq!(start, vec![c[0], c[0], default_vs], "{start:?} from {c:?}");
        let no_plain: Vec<String> =
            all.iter().filter(|id| *id != CoulombFriction.id()).cloned().collect();
        let s = Search { engine: &engine, train: &recs, heldout: &recs, allowed: &no_plain };
        assert!(plain_start(&s, (&recs, &[]), cand).is_none());
    }
}
