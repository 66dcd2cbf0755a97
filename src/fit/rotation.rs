//! Leave-one-value-out cross-validation (`fit --holdout-by KEY`): each value of a metadata key
//! (e.g. the firmware gain `kp` of BAM servo logs) is held out in turn, the whole selection runs
//! on the other episodes, and every held-out episode is scored before → after by its
//! whole-episode position MAE. Rendering is in [`crate::fit::report`] (`rotation_text`,
//! `rotation_json`).

use std::time::Instant;

use crate::fit::effects::{Applied, simulate};
use crate::fit::select::{FitOptions, FitOutcome, fit};
use crate::model::Robot;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::Episode;

/// One held-out episode: source file name, position MAE before and after the fit [rad].
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeMae {
    pub name: String,
    pub before: f64,
    pub after: f64,
}

/// One fold: the value held out, the selection on the other episodes, its held-out episodes.
pub struct Fold {
    pub value: String,
    pub outcome: FitOutcome,
    pub heldout: Vec<EpisodeMae>,
    /// Feet whose orientation this fold's kept effects leave above their joints' floors on its
    /// held-out episodes ([`crate::fit::contact`]), as in a single fit.
    pub feet: Vec<crate::fit::contact::FootResidual>,
    /// Joints whose training residual this fold's kept effects leave above their floors
    /// ([`crate::fit::unexplained`]), as in a single fit.
    pub unexplained: Vec<crate::fit::unexplained::Unexplained>,
    pub seconds: f64,
}

impl Fold {
    /// Mean held-out MAE (before, after) over this fold's episodes [rad].
    pub fn mean(&self) -> (f64, f64) {
        mean_mae(self.heldout.iter())
    }
}

/// Mean (before, after) MAE over `eps` [rad] (NaN when empty).
pub fn mean_mae<'a>(eps: impl Iterator<Item = &'a EpisodeMae>) -> (f64, f64) {
    let (mut b, mut a, mut n) = (0.0, 0.0, 0usize);
    for e in eps {
        b += e.before;
        a += e.after;
        n += 1;
    }
    if n == 0 { (f64::NAN, f64::NAN) } else { (b / n as f64, a / n as f64) }
}

/// The fold holding out the episodes whose metadata `key` equals `value`: the selection with
/// `opts` (its `holdout_by` replaced) and the held-out MAE before → after, on every recorded
/// joint but `unscored` (`--no-command`: replayed, not scored). A kept effect within its
/// uncertainty of the model as given moves from `selected` to a note, a body effect at the bound
/// of its search to a warning ([`crate::fit::absent`]); a foot whose held-out orientation the
/// kept effects leave above its joints' floors is named in a warning and in `feet`
/// ([`crate::fit::contact`]), on the scored joints as a single fit does; so is a joint whose
/// training residual is left above its floor (`unexplained`, [`crate::fit::unexplained`]).
/// Errors: no held-out episode,
/// or a held-out replay that fails.
pub fn fold(
    robot: &Robot,
    recs: &[Recording],
    opts: &FitOptions,
    key: &str,
    value: &str,
    unscored: &[String],
) -> Result<Fold, String> {
    let ts = Instant::now();
    let o = FitOptions { holdout_by: Some((key.to_string(), value.to_string())), ..opts.clone() };
    let mut out = fit(robot, recs, &o);
    // As in a single fit: a kept effect at the model's own value within its uncertainty is not
    // missing physics (a note; it stays in the fitted replay).
    let within = crate::fit::absent::split_off(robot, &mut out.selected);
    out.notes.extend(within);
    out.warnings.extend(crate::fit::absent::split_off_at_bound(robot, &mut out.selected));
    let rivals = crate::fit::floor_rival::split_off(robot, recs, &o, &mut out, unscored);
    out.warnings.extend(rivals);
    if out.heldout.is_empty() {
        return Err(format!("{key} = {value}: no held-out episode"));
    }
    let sim = |applied: &[Applied]| -> Result<Vec<Episode>, String> {
        simulate(robot, &out.heldout, applied, &o.replay)
            .into_iter()
            .map(|e| e.map_err(|e| e.to_string()))
            .collect()
    };
    let (eps_b, eps_a) = (sim(&[])?, sim(&out.applied)?);
    let mae = |eps: &[Episode]| -> Vec<f64> {
        out.heldout.iter().zip(eps).map(|(r, e)| episode_mae(r, e, unscored)).collect()
    };
    let (before, after) = (mae(&eps_b), mae(&eps_a));
    // The feet's contact residual on the held-out episodes as scored (without the joints left
    // out by --no-command), as `fit` without a rotation reports it.
    let feet = match (
        crate::sim2real::input::scored_view(&out.heldout, &eps_b, unscored),
        crate::sim2real::input::scored_view(&out.heldout, &eps_a, unscored),
    ) {
        (Some((recs, b)), Some((_, a))) => crate::fit::contact::unexplained_feet(
            robot,
            (&recs, &b, &a),
            &out.applied,
            o.policy.white_ratio,
        ),
        _ => vec![],
    };
    out.warnings.extend(feet.iter().map(|f| f.message()));
    let unexplained = crate::fit::unexplained::unexplained(&out.floors, o.policy.white_ratio);
    out.warnings.extend(unexplained.iter().map(|u| u.message()));
    let heldout = out
        .heldout
        .iter()
        .zip(before.iter().zip(&after))
        .map(|(r, (b, a))| EpisodeMae {
            name: r.source.file_name().map_or_else(
                || r.source.display().to_string(),
                |f| f.to_string_lossy().into_owned(),
            ),
            before: *b,
            after: *a,
        })
        .collect();
    Ok(Fold {
        value: value.to_string(),
        outcome: out,
        heldout,
        feet,
        unexplained,
        seconds: ts.elapsed().as_secs_f64(),
    })
}

/// Whole-episode position MAE over every recorded joint but `skip`, and every sample [rad] (a
/// sample the simulation did not reach counts as 1 rad).
pub fn episode_mae(rec: &Recording, ep: &Episode, skip: &[String]) -> f64 {
    let mut sum = 0.0;
    let mut n = 0usize;
    for (k, j) in rec.joints.iter().enumerate() {
        if skip.contains(&j.name) {
            continue;
        }
        for (r, s) in j.q.iter().zip(&ep.q_sim[k]) {
            if r.is_finite() {
                sum += if s.is_finite() { (r - s).abs() } else { 1.0 };
                n += 1;
            }
        }
    }
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(b: f64, a: f64) -> EpisodeMae {
        EpisodeMae { name: "x".into(), before: b, after: a }
    }

    /// The mean over episodes, by hand: (1 + 3) / 2 and (0.5 + 1.5) / 2.
    #[test]
    fn mean_of_the_episodes() {
        let v = [e(1.0, 0.5), e(3.0, 1.5)];
        assert_eq!(mean_mae(v.iter()), (2.0, 1.0));
        assert!(mean_mae([].iter()).0.is_nan());
    }

    /// A sample the simulation did not reach counts as 1 rad; a NaN recorded sample not at all.
    #[test]
    fn episode_mae_counts_unreached_samples() {
        use crate::sim2real::recording::JointTrace;
        let t = vec![0.0, 0.01, 0.02, 0.03];
        let j = JointTrace::new("a", vec![0.1, 0.2, f64::NAN, 0.4]);
        let rec = Recording {
            source: "r.csv".into(),
            meta: Default::default(),
            control_rate_hz: None,
            control_t0_s: None,
            t: t.clone(),
            joints: vec![j],
            base: None,
        };
        let ep = Episode {
            t,
            joints: vec!["a".into()],
            q_sim: vec![vec![0.1, 0.25, 0.3, f64::NAN]],
            qd_sim: vec![vec![0.0; 4]],
            diverged: None,
            peaks: Default::default(),
        };
        // |0| + |−0.05| + 1 over three counted samples.
        assert!((episode_mae(&rec, &ep, &[]) - 1.05 / 3.0).abs() < 1e-12);
    }
}
