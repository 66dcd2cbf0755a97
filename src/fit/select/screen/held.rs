//! The held-out set's linear model after round 0 ([`super::super::trust::heldout_out`]), made
//! one effect at a time when the search first asks about a candidate of that effect: an effect
//! whose every candidate the round takes without it (round 0's trust leaves it out, it is the
//! plain variant of a richer candidate, or it waits for the plain variant's fit) is not probed
//! on the held-out set at all. Each effect's model is made from the same probes' data and
//! base replay, and independently of every other effect's ([`Probes::model`]): the same
//! model as one made for every effect at once.

use std::collections::BTreeSet;

use crate::fit::diagnose::Candidate;
use crate::fit::effects::Applied;
use crate::sim2real::recording::Recording;

use super::super::{Engine, Errors};
use super::{Probes, Screen};

/// The held-out set's screen of the diagnosis entries `diag`, its effects' models made on
/// demand ([`HeldoutScreen::ensure`]).
pub(in crate::fit::select) struct HeldoutScreen<'a> {
    heldout: &'a [Recording],
    applied: &'a [Applied],
    ho_err: &'a Errors,
    diag: Vec<Candidate>,
    /// The probes' data and its base replay, made with the first effect's model.
    probes: Option<Probes<'a>>,
    screen: Option<Screen>,
    /// The effects whose model was made (or found to have no column).
    done: BTreeSet<&'static str>,
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
            done: BTreeSet::new(),
        })
    }

    /// Makes the model of every effect of `ids` not made yet that has an entry here (in the
    /// order of their ids, as [`Screen::build`]).
    pub(in crate::fit::select) fn ensure(
        &mut self,
        engine: &Engine,
        ids: &[&'static str],
        covered: &(dyn Fn(&str, &str) -> bool + Sync),
    ) {
        let mut todo: Vec<&'static str> = ids
            .iter()
            .copied()
            .filter(|id| !self.done.contains(id) && self.diag.iter().any(|c| c.effect == *id))
            .collect();
        todo.sort_unstable();
        todo.dedup();
        if todo.is_empty() {
            return;
        }
        let (heldout, applied, ho_err) = (self.heldout, self.applied, self.ho_err);
        let probes =
            self.probes.get_or_insert_with(|| Probes::new(engine, heldout, applied, ho_err));
        let screen = self.screen.get_or_insert_with(|| probes.screen());
        for id in todo {
            self.done.insert(id);
            if let Some(m) = probes.model(engine, id, &mut self.diag, covered) {
                screen.models.insert(id, m);
            }
        }
    }

    /// The screen of the effects made so far (`None` before the first).
    pub(in crate::fit::select) fn screen(&self) -> Option<&Screen> {
        self.screen.as_ref()
    }

    /// The effects whose model was made so far.
    #[cfg(test)]
    pub(in crate::fit::select) fn made(&self) -> Vec<&'static str> {
        self.done
            .iter()
            .copied()
            .filter(|id| self.screen().is_some_and(|s| s.models.contains_key(id)))
            .collect()
    }
}
