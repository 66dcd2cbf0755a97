//! Whether a candidate can come near a model at the floor, judged on the probes' data.
//!
//! Once a kept candidate left a white training residual (the floor), another candidate on its
//! joints (an alias, or a simpler effect the simplification would swap in) can at best tie it:
//! Occam's choice takes it only within `simpler_within` of it on held-out, and the floor screen
//! fits it in full only when its coarse fit comes within `floor_screen_ratio` of it. A
//! candidate that comes that close on the whole data comes as close on the probes' data — the
//! stretches where the round's base model is most wrong, [`SearchPolicy::probe_seconds`] in
//! all, where what the model at the floor explains shows most — and a coarse fit made on those
//! alone can only fit them better than one made on more data. So the candidate is first
//! coarse-fitted there (its memo is shared by every later screen on the same base), and the
//! model at the floor is replayed there once; a candidate whose coarse fit leaves more than
//! `floor_screen_ratio` × the floor model's RMSE on the probes' data is out of reach (`tried`:
//! phase "floor_screen", with that fit) and is not coarse-fitted on the screen's data; the
//! others go on exactly as before. On a three-joint leg whose shank inertia is missing, the
//! 9 aliases of the lead cost 30 replays of the screen's 10 s without it, and replays of 2 s
//! with it.
//!
//! [`SearchPolicy::probe_seconds`]: super::policy::SearchPolicy::probe_seconds

use std::sync::Arc;

use crate::fit::effects::{Applied, Effect};
use crate::sim2real::recording::Recording;

use super::coarse;
use super::engine::Engine;
use super::groups::same_data;
use super::screen::Screen;

/// The probes' data of a base model and the bar a candidate's coarse fit there must reach.
pub(super) struct Reach {
    probes: Arc<Vec<Recording>>,
    base: Vec<Applied>,
    /// `floor_screen_ratio` × the floor model's RMSE on the probes' data [rad].
    bar: f64,
}

impl Reach {
    /// The reach of the model `at_floor` (the base `base` with the candidates it kept) on the
    /// probes' data of the screen's data `short` with `base`; `None` when the probes' data is
    /// not held (no screen was built on that base) or is the screen's data itself, or when the
    /// replay fails.
    pub(super) fn new(
        engine: &Engine,
        short: &[Recording],
        base: &[Applied],
        at_floor: &[Applied],
    ) -> Option<Reach> {
        let probes = engine.probe_set_held(short, base)?;
        if same_data(&probes, short) {
            return None;
        }
        let rmse = engine.errors(&probes, at_floor)?.rmse();
        let bar = engine.opts.policy.floor_screen_ratio * rmse;
        bar.is_finite().then(|| Reach { probes, base: base.to_vec(), bar })
    }

    /// `Some` (the candidate's coarse fit on the probes' data: parameters and RMSE) when `e`
    /// on `g` is out of reach; `None` when it may come near. The coarse fit is the screen's
    /// ([`coarse::fit`]: from the linear step when `screen` models it, else a budget of
    /// `screen_evals` replays), remembered by the engine.
    pub(super) fn out_of_reach(
        &self,
        engine: &Engine,
        screen: Option<&Screen>,
        (e, g): (&'static dyn Effect, &[String]),
    ) -> Option<(Vec<f64>, f64)> {
        let data = (&self.probes[..], &self.base[..]);
        let (p, f) = match screen {
            Some(s) => coarse::fit(engine, s, data, (e, g)),
            None => engine.fit_budget(data.0, data.1, e, g, engine.opts.policy.screen_evals),
        };
        (p.is_empty() || !f.is_finite() || f > self.bar).then_some((p, f))
    }
}
