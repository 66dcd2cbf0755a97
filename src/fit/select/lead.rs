//! The order of a round's candidates when the linear model's favourite goes first
//! ([`SearchPolicy::lead_first`]), when they lie on more than one joint group (else the lead
//! could leave nothing unscreened, and its full fit would be an extra one): the candidate whose
//! linearised step leaves the least of the screen's residual — of any size, charged for its
//! parameters by the information criterion over the screen's windows
//! ([`super::screen::Screen::lead_rmse`]) — is coarse-fitted, fitted in full (on the whole
//! training set at once, from its coarse fit: the likeliest winner, and a round's winner is
//! fitted there anyway) and judged before any other candidate is coarse-fitted. When it is kept
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
    use super::{keep_first, lead};

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
}
