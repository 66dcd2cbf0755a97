//! A richer model of a loss whose plain variant is kept on its joints, judged as a swap of
//! that fit before its coarse fit.
//!
//! After a round kept Coulomb friction on some joints, Stribeck or load-dependent friction on
//! the same joints ([`Effect::plain_variant`]) is a candidate of the next round. Screened as
//! any candidate it is stacked on the kept fit and coarse-fitted whole (a simplex of
//! 2 (k − 1) × `screen_evals` replays on the probes' data); yet the model it would be kept as
//! holds the kept fit as a special case ([`Effect::absorb`]), and that fit — made in full on the
//! whole training set — is where its own fit would start. So it is first judged as a swap: the
//! kept plain fit taken over by the richer model, with the kept entry taken out, is the start
//! of the judgement a friction extension gets from its plain variant's fit in the round that
//! fits both ([`super::extension`]: that start, the effect's further starts, the Gauss–Newton
//! step at the best of them), made on the probes' data. It is staged: the level first, then
//! the shape. The level is the kept fit in the richer model's own form (Stribeck friction at
//! static = sliding = the kept Coulomb level; load-dependent friction at the kept level with no
//! load term), which is not the kept fit itself — Coulomb friction is MuJoCo's soft
//! `frictionloss`, Stribeck friction exact stiction — and can gain on the round's model by its
//! form alone (on chainsim's KR3, whose friction is exact stiction). The shape is what the
//! extra parameters add: the further starts and the step. The bar is the one a non-smooth
//! coarse fit is judged by on the probes' data ([`super::coarse`]): when no point gains
//! `min_rel_improvement` there against the better of the round's model and the level, the
//! extra parameters have found nothing where the model is most wrong (a form that only
//! replaces the kept fit at its level is not the extension's physics, and the kept plain model
//! stands as the simpler one, as Occam's nesting rule asks). The candidate is then logged
//! `screen` at the screen data's base RMSE (no gain) with its parameters' defaults, which add
//! nothing to the kept fit. Otherwise it is coarse-fitted as before.
//!
//! [`Effect::plain_variant`]: crate::fit::effects::Effect::plain_variant
//! [`Effect::absorb`]: crate::fit::effects::Effect::absorb

use crate::fit::effects::{Applied, Effect};
use crate::sim2real::recording::Recording;

use super::coarse::finds_nothing_on_probes;
use super::{Search, extension};

/// The coarse fit that stands for `e` on `g` (its parameters' defaults at `short`'s base RMSE
/// with `applied`) when its plain variant is kept on exactly `g` in `applied` and, judged as a
/// swap of that fit on the probes' data (see the module docs), its shape gains nothing there
/// beyond the round's model and the level; `None`
/// — coarse-fit it — otherwise, and whenever the test cannot be made.
pub(super) fn adds_nothing_to_kept(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> Option<(Vec<f64>, f64)> {
    let plain = e.plain_variant()?;
    let i = applied.iter().position(|a| a.effect.id() == plain.id() && a.joints == g)?;
    let mut base = applied.to_vec();
    let kept = base.remove(i);
    let x0 = extension::taken_over(s, &base, (e, g), (plain, &kept.params))?;
    let mut level = base.clone();
    level.push(Applied { effect: e, joints: g.to_vec(), params: x0 });
    let references = [applied.to_vec(), level];
    if !finds_nothing_on_probes(s, short, (&base, &references), (e, g), &kept.params) {
        return None;
    }
    let f = s.engine.score(short, applied);
    f.is_finite().then(|| (e.params().iter().map(|d| d.default).collect(), f))
}

#[cfg(test)]
mod tests {
    use super::adds_nothing_to_kept;
    use crate::fit::effects::{
        Applied, CoulombFriction, Effect, LoadDependentFriction, StribeckFriction,
    };
    use crate::fit::select::{Engine, FitOptions, Search};
    use crate::sim2real::recording::Recording;

    /// The pendulum servo recorded by the synth (3 × 3 s, seed 11) with `hidden`.
    fn pendulum(hidden: (&'static str, Vec<f64>)) -> (crate::model::Robot, Vec<Recording>) {
        crate::synth::recorded::pendulum(Some(hidden), 3, 11)
    }

    /// Kept Coulomb friction at `level` on the servo.
    fn kept(level: f64) -> Vec<Applied> {
        let joints = vec!["servo".to_string()];
        vec![Applied { effect: &CoulombFriction, joints, params: vec![level] }]
    }

    /// Seconds of recording in `recs`.
    fn seconds(recs: &[Recording]) -> f64 {
        recs.iter().map(|r| r.t.last().unwrap_or(&0.0) - r.t.first().unwrap_or(&0.0)).sum()
    }

    /// Beside a kept Coulomb fit at the recorded level, neither friction extension finds
    /// anything on the probes' data: each stands at the base RMSE with its defaults, for
    /// replays of the probes' data alone. Where the recordings hold a breakaway (static
    /// friction 2.5–4 × the sliding level, at two Stribeck velocities) the swap of the same
    /// kept fit finds it and the candidate is coarse-fitted (`None`). Not judged: no kept plain
    /// variant, or one kept on other joints (here: none of the candidate's).
    #[test]
    fn an_extension_beside_its_kept_plain_fit_is_judged_as_a_swap() {
        let opts = FitOptions::default();
        let allowed: Vec<String> =
            crate::fit::effects::all().iter().map(|e| e.id().into()).collect();
        let g = vec!["servo".to_string()];
        let cases: [(&'static str, Vec<f64>, f64, bool); 4] = [
            (CoulombFriction.id(), vec![0.08], 0.08, true),
            (CoulombFriction.id(), vec![0.05], 0.05, true),
            (StribeckFriction.id(), vec![0.2, 0.08, 0.05], 0.08, false),
            (StribeckFriction.id(), vec![0.2, 0.05, 0.1], 0.05, false),
        ];
        for (id, truth, level, nothing) in cases {
            let (robot, recs) = pendulum((id, truth.clone()));
            let engine = Engine::new(&robot, &recs, &opts);
            let s = Search { engine: &engine, train: &recs, heldout: &recs, allowed: &allowed };
            let applied = kept(level);
            let probes = engine.probe_set(&recs, &applied, || vec![recs[1].clone()]);
            let base = engine.score(&recs, &applied);
            let _ = engine.errors_held(&probes, &applied).expect("replay");
            for e in [&StribeckFriction as &'static dyn Effect, &LoadDependentFriction] {
                let before = engine.rollout_stats().simulated_s;
                let got = adds_nothing_to_kept(&s, (&recs, &applied), (e, &g));
                let cost = engine.rollout_stats().simulated_s - before;
                let n = cost / seconds(&probes);
                assert!((n - n.round()).abs() < 1e-6, "{} {id}: {cost} s", e.id());
                if nothing {
                    let defaults: Vec<f64> = e.params().iter().map(|d| d.default).collect();
                    assert_eq!(got, Some((defaults, base)), "{} on {id} {truth:?}", e.id());
                } else if e.id() == StribeckFriction.id() {
                    assert_eq!(got, None, "{} on {id} {truth:?}", e.id());
                }
            }
            // Not a swap: nothing kept, or the plain variant kept on another joint set.
            let other = [Applied { joints: vec![], ..applied[0].clone() }];
            for a in [&[][..], &other[..]] {
                assert_eq!(adds_nothing_to_kept(&s, (&recs, a), (&StribeckFriction, &g)), None);
            }
        }
    }
}
