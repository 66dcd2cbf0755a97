//! A told fit (`fit --told EFFECT@JOINTS`): no search — the named effects are fitted on the
//! training set (one after another, then jointly, then dry friction re-fitted on short windows
//! as the blind search's kept friction is: `reshoot`), and each is judged on the held-out set
//! against the set without it. What `mujoco.sysid` does when it is told the parameters; the
//! speed benchmark's reference for a blind search.

use std::collections::BTreeMap;

use crate::fit::effects::{self, Applied};
use crate::fit::stats::bic;

use super::policy::Phase;
use super::polish::fit_jointly;
use super::reshoot::reshoot_friction;
use super::verdict::verdict;
use super::{FitOutcome, Search, Selected, Tried};

/// Fits `told` (effect id, joint group) into `out.applied` and records each in `out.selected`
/// with its held-out comparison.
pub(super) fn fit_told(s: &Search, told: &[(String, Vec<String>)], out: &mut FitOutcome) {
    let Search { engine, train, heldout, .. } = *s;
    for (i, (id, joints)) in told.iter().enumerate() {
        engine.report(
            0,
            Phase::Told,
            Some((i + 1, told.len(), format!("{id} on {}", joints.join(",")))),
        );
        let Some(effect) = effects::by_id(id) else {
            out.warnings.push(format!("--told: unknown effect `{id}`"));
            continue;
        };
        let start = engine.opts.told_start.get(i).filter(|x| !x.is_empty());
        let (p, f) = engine.fit_from(train, &out.applied, (effect, joints), start.map(|x| &x[..]));
        if p.is_empty() || !f.is_finite() {
            out.warnings.push(format!("--told {id}@{}: the fit failed", joints.join(",")));
            continue;
        }
        out.applied.push(Applied { effect, joints: joints.clone(), params: p });
    }
    if out.applied.len() >= 2 {
        out.applied = fit_jointly(engine, train, std::mem::take(&mut out.applied), 0);
    }
    // The blind search's end for its kept effects: the start model with the sticking effects
    // (`--start-estimate`), then dry friction re-fitted on short windows (multiple shooting),
    // kept when the held-out replay is closer beyond noise. Single shooting bends a dry
    // friction to the start error of a joint that sticks.
    engine.set_start_model(&out.applied);
    if engine.opts.shooting_s.is_none() {
        reshoot_friction(s, train, 0, out);
    }
    let (Some(h_all), Some(t_all)) =
        (engine.errors(heldout, &out.applied), engine.errors(train, &out.applied))
    else {
        out.warnings.push("--told: the replay with the fitted effects diverged".into());
        out.applied.clear();
        return;
    };
    let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
    let gate = engine.opts.policy.gate();
    for i in 0..out.applied.len() {
        let a = out.applied[i].clone();
        let mut without = out.applied.clone();
        without.remove(i);
        let (Some(h_wo), Some(t_wo)) =
            (engine.errors(heldout, &without), engine.errors(train, &without))
        else {
            continue;
        };
        let v = verdict(&h_wo, &h_all, &a.joints, gate);
        let bics =
            (bic(t_wo.n, t_wo.sse, k_all - a.effect.fitted()), bic(t_all.n, t_all.sse, k_all));
        let sel = Selected::new(
            &a,
            BTreeMap::from([("told".to_string(), 1.0)]),
            &v,
            h_wo.rmse(),
            h_all.rmse(),
            bics,
        );
        out.log(Tried {
            round: 0,
            phase: Phase::Told,
            effect: a.effect.id().into(),
            joints: a.joints.clone(),
            params: a.params.iter().take(a.effect.fitted()).copied().collect(),
            train_rmse: t_all.rmse(),
            heldout_improvement: v.rel,
            significant: v.significant,
            bic_decreased: bics.1 < bics.0,
            kept: true,
            predicted: None,
            simulated_s: None,
        });
        out.selected.push(sel);
    }
}
