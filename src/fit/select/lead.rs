//! The order of a round's candidates when the linear model's favourite goes first
//! ([`SearchPolicy::lead_first`]), when they lie on more than one joint group (else the lead
//! could leave nothing unscreened, and its full fit would be an extra one): the candidate whose
//! linearised step leaves the least of the screen's residual — of any size, charged for its
//! parameters by the information criterion over the screen's windows
//! ([`super::screen::Screen::lead_rmse`]) — is coarse-fitted, fitted in full (on the whole
//! training set at once, from its coarse fit: the likeliest winner, and a round's winner is
//! fitted there anyway) and judged before any other candidate is coarse-fitted. Its full fit
//! waits for its coarse fit to pass the held-out screen any candidate's coarse fit passes (one
//! held-out replay: a coarse fit that lowers the held-out error not at all, or by less than a
//! confirmed linear model needs, is logged `heldout_screen`). When it is kept
//! and leaves a white training residual on every fitted joint (the floor), nothing is left that
//! a candidate of as many parameters could explain beyond noise: only its aliases — other
//! effects on exactly its joints, which the data may not tell apart from it — are still
//! screened (Occam's choice, nesting and the rival notes compare them); every other candidate
//! is left without a fit (`tried`: phase "floor").
//!
//! [`SearchPolicy::lead_first`]: super::policy::SearchPolicy::lead_first

/// Index of the lead among `predicted` (each candidate's predicted training RMSE, charged for
/// its parameters; `None` when the screen does not model it): the lowest prediction, the first in rank order on a tie;
/// `None` when no candidate is predicted.
pub(super) fn lead(predicted: &[Option<f64>]) -> Option<usize> {
    predicted
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.filter(|x| x.is_finite()).map(|x| (i, x)))
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
        .map(|(i, _)| i)
}

/// The order in which a round's candidates are coarse-fitted, in blocks that are then taken
/// best coarse fit first: the lead `[..n_lead]` alone, the one-parameter candidates
/// `[n_lead..n1]`, then the others `[n1..n0]` once the best of those was judged and left more
/// to explain than noise — at once when there are none. A candidate is never taken before its
/// block was screened: the block's sort would pass over it.
pub(super) struct Blocks {
    n_lead: usize,
    n1: usize,
    n0: usize,
    lead: bool,
    ones: bool,
    more: bool,
}

impl Blocks {
    pub(super) fn new(n_lead: usize, n1: usize, n0: usize) -> Blocks {
        Blocks { n_lead, n1, n0, lead: n_lead == 0, ones: n1 == 0, more: n1 == n0 }
    }

    /// The block to coarse-fit before candidate `ci` is taken, if any. At the floor
    /// (`at_floor`: a kept candidate left a white residual) `aliases` moves the one-parameter
    /// candidates still worth screening to the front of theirs and says how many there are;
    /// the larger candidates are not screened.
    pub(super) fn next(
        &mut self,
        ci: usize,
        at_floor: bool,
        aliases: impl FnOnce() -> usize,
    ) -> Option<std::ops::Range<usize>> {
        if !self.lead {
            self.lead = true;
            return Some(0..self.n_lead);
        }
        if !self.ones {
            self.ones = true;
            let n = if at_floor { aliases() } else { self.n1 - self.n_lead };
            if n > 0 {
                return Some(self.n_lead..self.n_lead + n);
            }
        }
        if !self.more && !at_floor && ci >= self.n1.min(1) {
            self.more = true;
            return Some(self.n1..self.n0);
        }
        None
    }
}

/// Moves the items of `v` for which `keep` holds to the front, each part in its order;
/// returns how many were kept.
pub(super) fn keep_first<T>(v: &mut [T], keep: impl Fn(&T) -> bool) -> usize {
    let mut n = 0;
    for i in 0..v.len() {
        if keep(&v[i]) {
            v[n..=i].rotate_right(1);
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::{Blocks, keep_first, lead};

    #[test]
    fn the_lead_is_the_lowest_prediction_first_in_rank_on_a_tie() {
        assert_eq!(lead(&[Some(3.0), None, Some(1.0), Some(1.0)]), Some(2));
        assert_eq!(lead(&[None, Some(f64::NAN)]), None);
        assert_eq!(lead(&[]), None);
    }

    #[test]
    fn kept_items_move_to_the_front_in_order() {
        let mut v = [1, 2, 3, 4, 5, 6];
        assert_eq!(keep_first(&mut v, |x| x % 3 == 0), 2);
        assert_eq!(v, [3, 6, 1, 2, 4, 5]);
        let mut e: [i32; 0] = [];
        assert_eq!(keep_first(&mut e, |_| true), 0);
    }

    /// Takes the candidates one by one as the round does, screening each block when
    /// [`Blocks::next`] gives it; returns, per candidate, whether its block had been screened
    /// when it was taken.
    fn screened_when_taken(n_lead: usize, n1: usize, n0: usize) -> Vec<bool> {
        let mut b = Blocks::new(n_lead, n1, n0);
        let mut screened = vec![false; n0];
        (0..n0)
            .map(|ci| {
                if let Some(r) = b.next(ci, false, || 0) {
                    assert!(r.start >= ci || r.is_empty(), "block {r:?} starts before {ci}");
                    screened[r].iter_mut().for_each(|s| *s = true);
                }
                screened[ci]
            })
            .collect()
    }

    #[test]
    fn no_candidate_is_taken_before_its_block_is_screened() {
        // A lead of two parameters and no one-parameter candidates (n1 = n_lead = 1): the others
        // are screened right after the lead, before the first of them is taken.
        assert_eq!(screened_when_taken(1, 1, 5), [true; 5]);
        for n0 in 0..6 {
            for n1 in 0..=n0 {
                for n_lead in 0..=n1.min(1) {
                    let s = screened_when_taken(n_lead, n1, n0);
                    assert!(s.iter().all(|&x| x), "lead {n_lead}, n1 {n1}, n0 {n0}: {s:?}");
                }
            }
        }
        // At the floor, only the aliases the closure counts are screened, never the larger ones.
        let mut b = Blocks::new(1, 4, 6);
        assert_eq!(b.next(0, false, || 0), Some(0..1));
        assert_eq!(b.next(1, true, || 2), Some(1..3));
        assert_eq!(b.next(3, true, || 0), None);
        assert_eq!(b.next(4, true, || 0), None);
    }
}
