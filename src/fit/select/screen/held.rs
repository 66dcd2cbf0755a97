//! The held-out set's linear model after round 0 ([`super::super::trust::heldout_out`]), made
//! as the search asks about candidates: a candidate's columns are probed when a block of the
//! screen first asks about it, the probe simulations of its effect that hold one of its joints
//! (one candidate joint of every limb at once, as the whole screen groups them), so that an
//! effect whose every candidate the round takes without it (round 0's trust leaves it out, it
//! is the plain variant of a richer candidate, or it waits for the plain variant's fit) is not
//! probed on the held-out set at all, nor a joint no candidate asked about holds. Every column
//! comes from the same probes' data, base replay and probe simulation as in a screen of every
//! effect at once ([`Screen::build`]), and a group's prediction uses its own joints' columns
//! alone: the same predictions.

use std::collections::{BTreeMap, BTreeSet};

use crate::fit::diagnose::Candidate;
use crate::fit::effects::Applied;
use crate::sim2real::recording::Recording;

use super::super::{Engine, Errors};
use super::probe::Probe;
use super::{Probes, Screen, batches};

mod line;

/// One effect's probes made so far: by diagnosis entry its best probes, and which probe
/// simulations ([`batches`]) were made.
type Made = (BTreeMap<usize, Vec<Option<Probe>>>, BTreeSet<usize>);

/// One effect's probe simulations ([`batches`]) and which of them are still to make.
type Work = (&'static str, Vec<Vec<usize>>, Vec<usize>);

/// The held-out set's screen of the diagnosis entries `diag`, its columns probed on demand
/// ([`HeldoutScreen::ensure`]).
pub(in crate::fit::select) struct HeldoutScreen<'a> {
    heldout: &'a [Recording],
    applied: &'a [Applied],
    ho_err: &'a Errors,
    diag: Vec<Candidate>,
    /// The probes' data and its base replay, made with the first column.
    probes: Option<Probes<'a>>,
    screen: Option<Screen>,
    made: BTreeMap<&'static str, Made>,
}

impl<'a> HeldoutScreen<'a> {
    /// The held-out set `heldout` (`ho_err` its residual with `applied`) to be probed on the
    /// entries `diag`; `None` when there are none.
    pub(in crate::fit::select) fn new(
        (heldout, applied, ho_err): (&'a [Recording], &'a [Applied], &'a Errors),
        diag: Vec<Candidate>,
    ) -> Option<HeldoutScreen<'a>> {
        (!diag.is_empty()).then(|| HeldoutScreen {
            heldout,
            applied,
            ho_err,
            diag,
            probes: None,
            screen: None,
            made: BTreeMap::new(),
        })
    }

    /// Probes every column the candidates `asked` (effect, joints) need that is not probed yet:
    /// each probe simulation of the effect that holds an entry on one of their joints; then
    /// the effect's model is made again from all its columns so far (effects in the order of
    /// their ids, as [`Screen::build`]).
    pub(in crate::fit::select) fn ensure(
        &mut self,
        engine: &Engine,
        asked: &[(&'static str, &[String])],
        covered: &(dyn Fn(&str, &str) -> bool + Sync),
    ) {
        let mut ids: Vec<&'static str> = asked.iter().map(|a| a.0).collect();
        ids.sort_unstable();
        ids.dedup();
        // Per effect, its probe simulations and which of them are still to make.
        let mut work: Vec<Work> = Vec::new();
        for id in ids {
            let all = batches(engine, id, &self.diag, covered);
            let joints: Vec<&String> =
                asked.iter().filter(|a| a.0 == id).flat_map(|a| a.1.iter()).collect();
            let done = self.made.get(id).map(|m| &m.1);
            let need: Vec<usize> = (0..all.len())
                .filter(|b| done.is_none_or(|d| !d.contains(b)))
                .filter(|&b| all[b].iter().any(|&i| joints.contains(&&self.diag[i].joint)))
                .collect();
            if !need.is_empty() {
                work.push((id, all, need));
            }
        }
        if work.is_empty() {
            return;
        }
        let (heldout, applied, ho_err) = (self.heldout, self.applied, self.ho_err);
        let probes =
            self.probes.get_or_insert_with(|| Probes::new(engine, heldout, applied, ho_err));
        let screen = self.screen.get_or_insert_with(|| probes.screen());
        for (id, all, need) in work {
            let these: Vec<Vec<usize>> = need.iter().map(|&b| all[b].clone()).collect();
            let found = probes.probe(engine, id, &self.diag, &these);
            let made = self.made.entry(id).or_default();
            made.0.extend(found);
            made.1.extend(need);
            match probes.assemble(engine, id, &mut self.diag, covered, &made.0) {
                Some(m) => screen.models.insert(id, m),
                None => screen.models.remove(id),
            };
        }
    }

    /// The screen of the columns probed so far (`None` before the first).
    pub(in crate::fit::select) fn screen(&self) -> Option<&Screen> {
        self.screen.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::HeldoutScreen;
    use crate::fit::diagnose::{Candidate, diagnose};
    use crate::fit::effects::{CoulombFriction, Effect, ViscousDamping};
    use crate::fit::select::screen::Screen;
    use crate::fit::select::{Engine, FitOptions};
    use crate::model::Robot;
    use crate::sim2real::recording::Recording;

    /// The diagnosis of `recs` with the `allowed` effects, a screen of every effect at once on
    /// an engine of its own, and the recording seconds that screen replayed.
    fn whole_screen(
        robot: &Robot,
        recs: &[Recording],
        opts: &FitOptions,
        allowed: &[String],
    ) -> (Vec<Candidate>, Screen, f64) {
        let no = |_: &str, _: &str| false;
        let whole = Engine::new(robot, recs, opts);
        let base = whole.errors_held(recs, &[]).expect("replay");
        let diag = diagnose(robot, recs, &base.eps, &whole.joints, allowed, opts.gap_mask_s);
        let start = whole.rollout_stats().simulated_s;
        let all = Screen::build(&whole, recs, &[], &base, &mut diag.clone(), &no);
        (diag, all, whole.rollout_stats().simulated_s - start)
    }

    /// The held-out screen probes an effect only when asked about one of its candidates, once,
    /// and its model is the one a screen of every effect at once makes: the same predictions,
    /// bit for bit, for the effect asked about; none for one not asked about; the probes of the
    /// effect asked about (and the probes' base replay) are all it replays.
    #[test]
    fn the_held_out_screen_probes_an_effect_when_asked_and_as_a_whole_screen_would() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((ViscousDamping.id(), vec![0.05])), 3, 7);
        let opts = FitOptions::default();
        let allowed = vec![ViscousDamping.id().to_string(), CoulombFriction.id().to_string()];
        let no = |_: &str, _: &str| false;
        let (diag, all, full) = whole_screen(&robot, &recs, &opts, &allowed);
        assert_eq!(diag.len(), 2, "{diag:?}");
        // On demand, on a fresh engine (no replay remembered).
        let engine = Engine::new(&robot, &recs, &opts);
        let base = engine.errors_held(&recs, &[]).expect("replay");
        let before = engine.rollout_stats().simulated_s;
        let mut ho = HeldoutScreen::new((&recs, &[], &base), diag.clone()).expect("entries");
        assert!(ho.screen().is_none());
        let g = vec![diag[0].joint.clone()];
        ho.ensure(&engine, &[], &no);
        assert!(ho.screen().is_none());
        assert_eq!(engine.rollout_stats().simulated_s, before, "nothing replayed before asked");
        ho.ensure(&engine, &[(ViscousDamping.id(), &g[..])], &no);
        let one = engine.rollout_stats().simulated_s - before;
        let s = ho.screen().expect("made");
        let (a, b) = (s.predict(ViscousDamping.id(), &g), all.predict(ViscousDamping.id(), &g));
        let (a, b) = (a.expect("modelled"), b.expect("modelled"));
        assert!(a.train_rmse == b.train_rmse && a.step == b.step, "{a:?} vs {b:?}");
        assert!(s.predict(CoulombFriction.id(), &g).is_none());
        assert!(one > 0.0 && one < full - 1e-6, "{one} s of {full}");
        // Asked again: nothing more; the other effect then, as the whole screen made it.
        ho.ensure(&engine, &[(ViscousDamping.id(), &g[..])], &no);
        assert_eq!(engine.rollout_stats().simulated_s - before, one);
        let both = [(CoulombFriction.id(), &g[..]), (ViscousDamping.id(), &g[..])];
        ho.ensure(&engine, &both, &no);
        let s = ho.screen().expect("made");
        let (a, b) = (s.predict(CoulombFriction.id(), &g), all.predict(CoulombFriction.id(), &g));
        let (a, b) = (a.expect("modelled"), b.expect("modelled"));
        assert!(a.train_rmse == b.train_rmse && a.step == b.step, "{a:?} vs {b:?}");
        let twice = engine.rollout_stats().simulated_s - before;
        assert!((twice - full).abs() < 1e-6, "{twice} s, whole {full}");
    }

    /// On a chain of three joints, a candidate asked about on one joint has that joint's
    /// column probed alone (one probe simulation); a group asked about later adds its other
    /// joints' columns; every prediction is the whole screen's, bit for bit, and once every
    /// joint is asked about the held-out screen has replayed what the whole one did.
    #[test]
    fn the_held_out_screen_probes_only_the_joints_asked_about() {
        use crate::model::source::SourceMap;
        use crate::sim2real::recording::read_csv;
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fixtures/independent_py/KR0_leg_none");
        let robot = crate::model::load(&mut SourceMap::default(), &dir.join("nominal.xml"), None)
            .expect("fixture");
        let recs: Vec<_> = ["ep_00.csv", "ep_01.csv"]
            .iter()
            .map(|f| read_csv(&dir.join("episodes").join(f)).expect("read"))
            .collect();
        let opts = FitOptions::default();
        let allowed = vec![ViscousDamping.id().to_string()];
        let no = |_: &str, _: &str| false;
        let (diag, all, full) = whole_screen(&robot, &recs, &opts, &allowed);
        let joints: Vec<String> = diag.iter().map(|c| c.joint.clone()).collect();
        assert_eq!(joints.len(), 3, "{joints:?}");
        let engine = Engine::new(&robot, &recs, &opts);
        let base = engine.errors_held(&recs, &[]).expect("replay");
        let before = engine.rollout_stats().simulated_s;
        let mut ho = HeldoutScreen::new((&recs, &[], &base), diag.clone()).expect("entries");
        let id = ViscousDamping.id();
        let same = |s: &Screen, g: &[String]| {
            let (a, b) = (s.predict(id, g).expect("modelled"), all.predict(id, g).expect("all"));
            assert!(a.train_rmse == b.train_rmse && a.step == b.step, "{g:?}: {a:?} vs {b:?}");
        };
        let one = joints[1..2].to_vec();
        ho.ensure(&engine, &[(id, &one[..])], &no);
        let first = engine.rollout_stats().simulated_s - before;
        let s = ho.screen().expect("made");
        same(s, &one);
        assert!(s.predict(id, &joints[..1]).is_none() && s.predict(id, &joints).is_none());
        // The probes' base replay and one probe: a third of the three probes and less.
        assert!(first > 0.0 && first < full - 1e-6, "{first} s of {full}");
        ho.ensure(&engine, &[(id, &joints[..])], &no);
        let s = ho.screen().expect("made");
        same(s, &joints);
        for j in &joints {
            same(s, std::slice::from_ref(j));
        }
        let twice = engine.rollout_stats().simulated_s - before;
        assert!((twice - full).abs() < 1e-6, "{twice} s, whole {full}");
    }
}
