//! Whether a candidate can reach a bar, judged on the probes' data before any coarse fit on
//! the screen's data.
//!
//! **At the floor.** Once a kept candidate left a white training residual (the floor), another
//! candidate on its joints (an alias, or a simpler effect the simplification would swap in) can
//! at best tie it: Occam's choice takes it only within `simpler_within` of it on held-out, and
//! the floor screen fits it in full only when its coarse fit comes within `floor_screen_ratio`
//! of it. A candidate that comes that close on the whole data comes as close on the probes'
//! data — the stretches where the round's base model is most wrong,
//! [`SearchPolicy::probe_seconds`] in all, where what the model at the floor explains shows
//! most — and a coarse fit made on those alone can only fit them better than one made on more
//! data. So the candidate is first coarse-fitted there (its memo is shared by every later
//! screen on the same base), and the model at the floor is replayed there once; a candidate
//! whose coarse fit leaves more than `floor_screen_ratio` × the floor model's RMSE on the
//! probes' data is out of reach (`tried`: phase "floor_screen", with that fit) and is not
//! coarse-fitted on the screen's data; the others go on exactly as before. On a three-joint
//! leg whose shank inertia is missing, the 9 aliases of the lead cost 30 replays of the
//! screen's 10 s without it, and replays of 2 s with it.
//!
//! **Beside a kept lead above the floor** ([`Reach::beside_lead`]). The screen fits a
//! candidate in full only when its coarse fit on the screen's data leaves at most the bar
//! b = RMSE₀ (1 − `screen_share` × the round's best gain), a squared residual of n_s b² on the
//! screen's n_s samples; the kept lead's gain sets the bar before the others are screened, and
//! the bar only falls as the round goes on. The probes' stretches lie inside the screen's
//! data, so the same parameters leave at most n_s b² on the probes' n_p samples, and a coarse
//! fit made on those alone leaves no more: a candidate whose coarse fit on the probes' data
//! leaves more than n_s b² (an RMSE above b √(n_s / n_p) there) could not have reached the
//! bar, and is logged `reach_screen` with that fit. This needs no constant and no assumption
//! that gains carry over from one dataset to the other; what it assumes is that a probe's
//! replay, started from its stretch's recorded state, leaves no more residual on its samples
//! than the screen's replay leaves there after running from the start of its own, longer
//! stretch (as a rule it leaves less: the drift is reset). It prunes only where the probes
//! hold a large part of the screen's residual: on the chain leg whose three motors all lack
//! rotor inertia the probes hold 57 % of it on 20 % of the samples, and 27 of the 29 rivals of
//! the kept all-joint group are out of reach; on the leg with a gear play behind its motors
//! they hold 12–18 % (the play's drift, which a replay from a recorded state resets), and none
//! is.
//! A candidate whose linear prediction reaches b is admitted by the screen on that
//! prediction, and is never judged here.
//!
//! **A richer model of a loss** whose plain variant is out of reach on the same joints is
//! judged from the plain variant's fit there ([`Reach::extension_out`]), in either mode: on
//! that leg, the two Stribeck and two load-dependent frictions cost 5–7 replays of the probes'
//! data each where their own coarse fits take 12–25, and are out of reach as those find.
//!
//! [`SearchPolicy::probe_seconds`]: super::policy::SearchPolicy::probe_seconds

use std::sync::Arc;

use crate::fit::effects::{Applied, Effect};
use crate::sim2real::recording::Recording;

use super::coarse;
use super::engine::Engine;
use super::extension;
use super::groups::same_data;
use super::policy::Phase;
use super::reach_model;
use super::screen::Screen;
use super::{Errors, Search};

/// The probes' data of a base model and the bar a candidate's coarse fit there must reach.
pub(super) struct Reach {
    probes: Arc<Vec<Recording>>,
    base: Vec<Applied>,
    /// The RMSE on the probes' data above which a candidate is out of reach [rad].
    bar: f64,
    /// The scored samples of the probes' data (an RMSE `bar` there is a squared residual of
    /// `n` × `bar`²).
    n: usize,
    /// Beside a kept lead: the screen's bar (an RMSE on the screen's data [rad]) that a
    /// candidate's linear prediction may reach, which then admits it as the screen would.
    screen_bar: Option<f64>,
    /// How an out-of-reach candidate is logged.
    pub(super) phase: Phase,
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
        let at = engine.errors(&probes, at_floor)?;
        let bar = engine.opts.policy.floor_screen_ratio * at.rmse();
        bar.is_finite().then(|| Reach {
            probes,
            base: base.to_vec(),
            bar,
            n: at.n,
            screen_bar: None,
            phase: Phase::FloorScreen,
        })
    }

    /// The reach of the round's screen beside a kept lead that is not at the floor: a
    /// candidate is fitted in full only when its coarse fit on the screen's data `short`
    /// (whose base residual is `sh_err`) leaves at most `screen_bar` RMSE there, that is at
    /// most n_s × `screen_bar`² of squared residual. The probes' data is part of the screen's
    /// data, so the same parameters leave at most that much on the probes' samples alone, and
    /// a coarse fit made on them alone leaves no more: a candidate whose coarse fit on the
    /// probes' data leaves more squared residual than that cannot reach the bar. `None` as
    /// [`Reach::new`], or when no candidate could be out of reach (the bar above the base's
    /// own residual on the probes' data).
    pub(super) fn beside_lead(
        engine: &Engine,
        (short, sh_err): (&[Recording], &Errors),
        base: &[Applied],
        screen_bar: f64,
    ) -> Option<Reach> {
        let probes = engine.probe_set_held(short, base)?;
        if same_data(&probes, short) {
            return None;
        }
        let p_err = engine.errors(&probes, base).filter(|p| p.n > 0 && sh_err.n > 0)?;
        let bar = (sh_err.n as f64 * screen_bar * screen_bar / p_err.n.max(1) as f64).sqrt();
        (bar.is_finite() && bar < p_err.rmse()).then(|| Reach {
            probes,
            base: base.to_vec(),
            bar,
            n: p_err.n,
            screen_bar: Some(screen_bar),
            phase: Phase::ReachScreen,
        })
    }

    /// Whether this reach was measured at the floor.
    pub(super) fn at_floor(&self) -> bool {
        self.screen_bar.is_none()
    }

    /// `Some` (the candidate's coarse fit on the probes' data: parameters and RMSE) when `e`
    /// on `g` is out of reach; `None` when it may come near. The coarse fit is the screen's
    /// ([`coarse::fit`]: from the linear step when `screen` models it, else a budget of
    /// `screen_evals` replays), remembered by the engine. Beside a lead, a candidate whose
    /// linear prediction reaches the screen's bar is never out of reach (the screen admits it
    /// on that prediction). A richer model of a loss whose plain variant is out of reach is
    /// first judged from the plain variant's fit there ([`Reach::extension_out`]); beside a
    /// lead, a smooth one of several parameters by the Gauss–Newton model at its replayed
    /// linear step ([`reach_model::beyond`]).
    pub(super) fn out_of_reach(
        &self,
        s: &Search,
        screen: Option<&Screen>,
        (e, g): (&'static dyn Effect, &[String]),
    ) -> Option<(Vec<f64>, f64)> {
        if let Some(sb) = self.screen_bar
            && screen.and_then(|s| s.predict(e.id(), g)).is_some_and(|p| p.train_rmse <= sb)
        {
            return None;
        }
        if let Some(judged) = self.extension_out(s, screen, (e, g)) {
            return Some(judged);
        }
        // Beside a lead, a smooth rival of several parameters whose Gauss–Newton model at its
        // replayed linear step cannot reach the bar ([`reach_model`]).
        if self.screen_bar.is_some()
            && let Some(sc) = screen
            && let Some(judged) =
                reach_model::beyond(s.engine, sc, (&self.probes, &self.base), (e, g), self.bar)
        {
            return Some(judged);
        }
        let (p, f) = self.fit(s.engine, screen, (e, g));
        self.out((p, f))
    }

    /// The coarse fit on the probes' data that judges `e` on `g` (see [`Reach::out_of_reach`]).
    fn fit(
        &self,
        engine: &Engine,
        screen: Option<&Screen>,
        (e, g): (&'static dyn Effect, &[String]),
    ) -> (Vec<f64>, f64) {
        let data = (&self.probes[..], &self.base[..]);
        match screen {
            Some(s) => coarse::fit(engine, s, data, (e, g)),
            None => engine.fit_budget(data.0, data.1, e, g, engine.opts.policy.screen_evals),
        }
    }

    /// `Some` (the fit) when a coarse fit `(p, f)` on the probes' data is out of reach.
    fn out(&self, (p, f): (Vec<f64>, f64)) -> Option<(Vec<f64>, f64)> {
        // (Beside a lead, a fit that failed on the probes' data proves nothing: the screen
        // judges the candidate.)
        let failed = p.is_empty() || !f.is_finite();
        let out = if self.at_floor() { failed || f > self.bar } else { !failed && f > self.bar };
        out.then_some((p, f))
    }

    /// A richer model of a loss ([`Effect::plain_variant`]: Stribeck, load-dependent or
    /// external-load friction around Coulomb friction) holds its plain variant as a special
    /// case, so at the plain variant's fit taken over it leaves what that fit leaves; its extra
    /// parameters can only bring it nearer where the residual there has their shape. When the
    /// plain variant on the same joints (not in the base there) is out of reach — its coarse
    /// fit on the probes' data, the one its own judgement makes, remembered — the richer model
    /// is judged from that fit as a deferred candidate is judged from the plain variant's
    /// coarse fit on the screen's data ([`extension::could_reach`]: that fit taken over, the
    /// model's further starts, the Gauss–Newton step on its columns at the best of them,
    /// predicted and simulated), here on the probes' data against this reach's bar: `Some`
    /// (the point of least error it simulated, and that RMSE) when no point reaches the bar,
    /// which costs k + 2 or so replays of the probes' data instead of the richer model's own
    /// coarse fit (a simplex of up to 25 on the three-parameter Stribeck friction). `None` —
    /// its own coarse fit judges it — when the plain variant is within reach, its fit failed,
    /// or the test cannot be made.
    ///
    /// [`Effect::plain_variant`]: crate::fit::effects::Effect::plain_variant
    fn extension_out(
        &self,
        s: &Search,
        screen: Option<&Screen>,
        (e, g): (&'static dyn Effect, &[String]),
    ) -> Option<(Vec<f64>, f64)> {
        let plain = e.plain_variant()?;
        let in_base = |j: &String| {
            self.base.iter().any(|a| a.effect.id() == plain.id() && a.joints.contains(j))
        };
        if !s.allowed.iter().any(|id| id == plain.id()) || g.iter().any(in_base) {
            return None;
        }
        let (pp, _) = self.out(self.fit(s.engine, screen, (plain, g)))?;
        let sse_bar = self.n as f64 * self.bar * self.bar;
        let reaches = |sse: f64| sse <= sse_bar;
        let data = (&self.probes[..], &self.base[..]);
        match extension::could_reach(s, data, (e, g), &pp, &reaches) {
            (false, Some((p, f))) if f.is_finite() => Some((p, f)),
            _ => None,
        }
    }
}

#[cfg(test)]
#[path = "reach_tests.rs"]
mod tests;
