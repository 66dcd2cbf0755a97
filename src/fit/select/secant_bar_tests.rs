//! The block's secant coarse fits set the bar before its other coarse fits.

use super::{OutOf, bar, block_fits, from_gains};
use crate::fit::diagnose::diagnose;
use crate::fit::effects::{
    Backlash, CoulombFriction, Effect, ExternalLoadFriction, GainError, TorqueLimit, ViscousDamping,
};
use crate::fit::select::coarse::{self, Coarse};
use crate::fit::select::groups::Cand;
use crate::fit::select::screen::Screen;
use crate::fit::select::{Engine, FitOptions, Search, SearchPolicy};
use crate::sim2real::recording::Recording;

#[test]
fn the_secants_set_the_bar_a_fit_sets() {
    let pol = SearchPolicy::default();
    // Nothing gained (or nothing fitted): no bar.
    assert_eq!(from_gains(&[], &pol), f64::INFINITY);
    assert_eq!(from_gains(&[-0.3, 0.0, f64::NAN, f64::NEG_INFINITY], &pol), f64::INFINITY);
    // The best gain × the share ...
    let b = from_gains(&[0.2, 0.9, f64::NAN, 0.4], &pol);
    assert!((b - pol.screen_share * 0.9).abs() < 1e-12, "{b}");
    // ... never below the smallest improvement the round keeps.
    let tiny = 0.1 * pol.min_rel_improvement;
    assert_eq!(from_gains(&[tiny], &pol), pol.min_rel_improvement);
}

/// The pendulum servo with Coulomb friction `f` N·m, recorded by the synth (3 × 3 s).
fn pendulum_with_friction(f: f64) -> (crate::model::Robot, Vec<Recording>) {
    crate::synth::recorded::pendulum(Some((CoulombFriction.id(), vec![f])), 3, 11)
}

/// A round's first block on a single servo (no lead, no bar yet) whose residual is Coulomb
/// friction (of several levels): the block's fits made with the bar its secant fits set are
/// those made without a bar as far as the round's screen can tell — every candidate reaches
/// the round's bar (the best gain of the block × `screen_share`) in both or in neither, the
/// secant fit is the same fit, the gain error (two parameters) is fitted as without a bar —
/// and they replay no more recording seconds. (On these recordings the external-load
/// friction's point on the probes' data never reaches the secants' bar short of a fit on the
/// screen's data: no seconds are saved; on chainsim's KR3, round 0, 20.)
#[test]
fn a_block_fitted_against_its_secants_bar_admits_what_it_admitted_for_no_more() {
    let levels = [0.01, 0.02, 0.03, 0.05, 0.08, 0.12];
    for level in levels {
        block_against_bar(level);
    }
}

/// [`a_block_fitted_against_its_secants_bar_admits_what_it_admitted_for_no_more`] at Coulomb
/// friction `level` N·m.
fn block_against_bar(level: f64) {
    let (robot, recs) = pendulum_with_friction(level);
    let opts = FitOptions::default();
    let g = vec!["servo".to_string()];
    let effects: [&'static dyn Effect; 6] = [
        &CoulombFriction,
        &ExternalLoadFriction,
        &Backlash,
        &TorqueLimit,
        &GainError,
        &ViscousDamping,
    ];
    let allowed: Vec<String> = effects.iter().map(|e| e.id().to_string()).collect();
    let cands: Vec<Cand> = effects.iter().map(|e| (*e, g.clone(), Default::default())).collect();
    let coarse: Vec<Coarse> = vec![None; cands.len()];
    let (no_out, no_far): (Vec<OutOf>, Vec<Coarse>) =
        (vec![None; cands.len()], vec![None; cands.len()]);
    // The block's fits on a fresh engine: with the secants' bar, or each without a bar.
    let run = |barred: bool| {
        let engine = Engine::new(&robot, &recs, &opts);
        let s = Search { engine: &engine, train: &recs, heldout: &recs, allowed: &allowed };
        let base = engine.errors_held(&recs, &[]).expect("replay");
        let mut diag =
            diagnose(&robot, &recs, &base.eps, &engine.joints, &allowed, opts.gap_mask_s);
        let screen = Screen::build(&engine, &recs, &[], &base, &mut diag, &|_, _| false);
        let before = engine.rollout_stats().simulated_s;
        let fits: Vec<(Vec<f64>, f64)> = if barred {
            let block = (&cands[..], &coarse[..], 0..cands.len());
            block_fits(&s, &screen, (&recs, &[]), block, (&no_out, &no_far), f64::INFINITY)
        } else {
            let at = (&recs[..], &[][..]);
            let fit =
                |(e, g, _): &Cand| coarse::fit_to(&engine, &screen, at, (*e, g), f64::INFINITY);
            cands.iter().map(fit).collect()
        };
        let cost = engine.rollout_stats().simulated_s - before;
        let gains: Vec<f64> = fits.iter().map(|f| 1.0 - f.1 / base.rmse()).collect();
        let secant = coarse::secant(&engine, &screen, (&recs, &[]), (&CoulombFriction, &g));
        // The bars the block's secants set: with the friction in it, and without.
        let at = (&recs[..], &[][..]);
        let of = |v: &[&'static dyn Effect]| {
            let block: Vec<(&'static dyn Effect, &[String])> =
                v.iter().map(|e| (*e, &g[..])).collect();
            bar(&engine, &screen, at, &block, base.rmse())
        };
        let bars = (of(&effects), of(&effects[1..]));
        (fits, gains, cost, (secant, bars))
    };
    let (free, free_gains, free_cost, (secant, (with, without))) = run(false);
    let (barred, gains, cost, _) = run(true);
    // The friction's secant fit sets the bar as a fit of the round does; no other candidate of
    // the block has a secant fit (non-smooth, or of two parameters) but the viscous damping,
    // which gains less.
    let share = opts.policy.screen_share;
    assert!((with - share * free_gains[0]).abs() < 1e-12, "{level}: {with}");
    assert!((without - share * free_gains[5]).abs() < 1e-12, "{level}: {without}");
    // The friction's coarse fit is its secant fit, and explains most of the residual.
    let secant = secant.expect("a smooth one-parameter candidate");
    assert_eq!(free[0], secant);
    assert_eq!(barred[0], secant);
    assert!(gains[0] > 0.5, "{level}: {gains:?}");
    // The gain error (two parameters) is fitted as without a bar.
    assert_eq!(free[4], barred[4], "{level}");
    // Every candidate reaches the round's bar with the secants' bar as without it.
    let bar = |g: &[f64]| opts.policy.screen_share * g.iter().copied().fold(0.0, f64::max);
    let (b0, b1) = (bar(&free_gains), bar(&gains));
    assert_eq!(b0, b1, "{level}: {free_gains:?} / {gains:?}");
    for (i, (x, y)) in free_gains.iter().zip(&gains).enumerate() {
        assert_eq!(*x >= b0, *y >= b1, "{level}: {}: {x} / {y}", cands[i].0.id());
    }
    assert!(cost <= free_cost + 1e-9, "{level}: {cost} s replayed, {free_cost} s without the bar");
}
