//! The pair look-ahead's linear screen: what two candidates fitted together can explain, from
//! their single fits, before any joint fit.
//!
//! Each member's single fit moved the simulation from the model without it; that change on the
//! screen's data is a secant column of the member (one replay per member). The least-squares
//! combination of a pair's two columns predicts the pair's joint fit: two columns that are
//! nearly orthogonal add up (the greedy rounds find the second member after the first), two
//! that mimic each other explain what their difference does. The look-ahead fits pairs
//! coarsely in the order of these predictions, and leaves out a pair whose prediction cannot
//! come within `pair_full_fit_within` of the best coarse fit so far (on arm2's delay + Coulomb
//! pair, the predictions of the twelve pairs were within 15 % of their coarse fits but one).

use std::collections::HashMap;

use rayon::prelude::*;

use crate::fit::effects::Applied;
use crate::sim2real::recording::Recording;

use super::engine::{Engine, set_key};
use super::screen::combine;

/// For each pair `(a, b)` of `sets` added to `applied`, the training RMSE on `short` that the
/// linear model of its members' single fits predicts (see the module docs); `None` where a
/// replay failed or the columns do not line up (the pair is then fitted).
pub(super) fn predicted(
    engine: &Engine,
    short: &[Recording],
    applied: &[Applied],
    sets: &[(Applied, Applied)],
) -> Vec<Option<f64>> {
    let Some(r0) = engine.residuals(short, applied, &engine.joints, usize::MAX) else {
        return vec![None; sets.len()];
    };
    let key = |a: &Applied| set_key(short, std::slice::from_ref(a));
    let mut members: Vec<&Applied> = Vec::new();
    for (a, b) in sets {
        for m in [a, b] {
            if !members.iter().any(|x| key(x) == key(m)) {
                members.push(m);
            }
        }
    }
    // Each member's column: the change its single fit makes to the simulation (r0 − r).
    let cols: HashMap<String, Vec<f64>> = members
        .par_iter()
        .filter_map(|m| {
            let mut set = applied.to_vec();
            set.push((*m).clone());
            let r = engine.residuals(short, &set, &engine.joints, usize::MAX)?;
            (r.len() == r0.len()).then(|| (key(m), r0.iter().zip(&r).map(|(x, y)| x - y).collect()))
        })
        .collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let ss = dot(&r0, &r0);
    let n = r0.len().max(1) as f64;
    sets.iter()
        .map(|(a, b)| {
            let (ca, cb) = (cols.get(&key(a))?, cols.get(&key(b))?);
            let g = vec![vec![dot(ca, ca), dot(ca, cb)], vec![dot(cb, ca), dot(cb, cb)]];
            let (explained, _) = combine(&[dot(ca, &r0), dot(cb, &r0)], &g);
            Some(((ss - explained).max(0.0) / n).sqrt())
        })
        .collect()
}
