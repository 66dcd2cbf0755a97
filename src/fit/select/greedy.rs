//! One greedy round of the selection: diagnose the residual, build the candidate (effect, joint
//! group) list, fit and gate each candidate, and keep the winner.

use rayon::prelude::*;

use crate::fit::diagnose::diagnose;
use crate::fit::effects::{self, Applied, Effect};
use crate::fit::stats::{bic, bic_pieces};

use super::before_full::short_of_keep;
use super::coarse::{self, Coarse};
use super::discretisation::{Judged, beyond_discretisation};
use super::engine::shape_key;
use super::extension;
use super::groups::{Cand, candidate_list, has_group, partner, same_data, sorted_pair};
use super::heldout_linear::out_of;
use super::joint_floor;
use super::lead;
use super::pair_first::{EarlyPair, early_pair, rivals};
use super::pairs::{joint_pairs, pair_lookahead, refitted_at_floor};
use super::policy::Phase;
use super::reach::Reach;
use super::rival::{Beaten, RoundAt, judge_beaten};
use super::screen::{HeldoutScreen, Screen, screen_data};
use super::secant_bar;
use super::trust::{heldout_columns, with_pair_starts};
use super::verdict::{at_bound, verdict};
use super::winner::{beaten_at_coarse, on_whole_set, refine, rival_notes};
use super::{Errors, FitOutcome, Search, Selected, Tried, set_uncertainty};

/// One greedy round: diagnose, fit the candidates, keep the best that passes the held-out gate.
/// Returns `true` when an effect was added.
pub(super) fn greedy_round(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let Search { engine, train, heldout, allowed } = *s;
    let opts = engine.opts;
    let robot = engine.robot;
    let applied = out.applied.clone();
    let Some(tr_err) = engine.errors_held(train, &applied) else {
        out.warnings.push("the training replay diverged with the current model; stopping".into());
        return false;
    };
    // The last round's winner was judged at the floor with these effects, and the set's
    // training error is no higher now: nothing is left to explain.
    if let Some((kept, rmse)) = out.at_floor.take()
        && kept == shape_key(&[], &applied)
        && tr_err.rmse() <= rmse
    {
        out.stopped_at_floor = true;
        return false;
    }
    // Nothing left to explain: on every fitted joint the training residual is (nearly) white,
    // at the floor that noise, quantisation and command reconstruction impose on this dataset.
    let floors = engine.floors(train, &applied, &tr_err);
    if round == 0 {
        out.floors = floors.clone();
    }
    if floors.iter().all(|f| f.reached(opts.policy.white_ratio)) {
        out.stopped_at_floor = true;
        return false;
    }
    // Only now the held-out set and the screen's data (a round at the floor needs neither).
    let Some(ho_err) = engine.errors_held(heldout, &applied) else {
        out.warnings.push("the held-out replay diverged with the current model; stopping".into());
        return false;
    };
    // The screen's data (the stretch of every training episode where the residual is largest):
    // the training set itself when that is short (one slice: coarse and full fits share the memo).
    let short_set = engine.screen_set(train, &applied, || screen_data(engine, train, &tr_err));
    let short = if same_data(&short_set, train) { train } else { &short_set[..] };
    let Some(sh_err) = engine.errors_held(short, &applied) else {
        out.warnings.push("the training replay diverged with the current model; stopping".into());
        return false;
    };
    let diag = diagnose(robot, train, &tr_err.eps, &engine.joints, allowed, opts.gap_mask_s);
    let covered = |id: &str, j: &str| {
        applied.iter().any(|a| a.effect.id() == id && a.joints.iter().any(|x| x == j))
    };
    // Re-rank the diagnosis by the linearised (Gauss–Newton) explained residual: the
    // residual projected on the simulated sensitivity to a probe step of the effect
    // ([`Screen`]), which also predicts every candidate group below.
    let mut diag = diag;
    let at = (short, &applied[..], &sh_err);
    let screen = Screen::build_after(engine, at, &mut diag, &covered, &out.diagnosis);
    for c in diag.iter_mut().filter(|c| covered(c.effect, &c.joint)) {
        c.explained_rms = 0.0;
    }
    diag.sort_by(|a, b| b.explained_rms.total_cmp(&a.explained_rms));
    if round == 0 {
        out.diagnosis = diag.clone();
    }
    // Candidate (effect, group) list, best first.
    let mut cands = candidate_list(engine, &diag, &applied, allowed);
    if cands.is_empty() {
        return false;
    }
    // One-parameter candidates first, in rank order; then the multi-parameter ones.
    cands.sort_by_key(|(e, ..)| e.fitted() >= 2);
    let z = opts.policy.z_needed(cands.len());
    // After round 0, none whose joints are all at their floor ([`joint_floor`]).
    if joint_floor::leave_at_floor(
        &mut cands,
        (&floors, opts.policy.white_ratio, round),
        &screen,
        out,
    ) {
        return false;
    }
    // After round 0, the held-out set's own linear model ([`heldout_out`]) of the candidates it
    // may leave out ([`heldout_columns`]), an effect's probed when first asked ([`out_of`]).
    let ho_diag = (round > 0).then(|| heldout_columns(engine, &screen, &cands, &diag));
    let mut ho_screen = ho_diag.and_then(|d| HeldoutScreen::new((heldout, &applied, &ho_err), d));
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let bic_before = bic(tr_err.n, tr_err.sse, k_before);
    // Each kept candidate: its record, whether it sits on a bound, its held-out errors, its log
    // index and its training BIC counted per window ([`bic_pieces`]).
    let mut accepted: Vec<(Selected, bool, Errors, usize, f64)> = Vec::new();
    // Every single fit of the round, for the joint pairs when no single one passes.
    let mut fitted: Vec<Applied> = Vec::new();
    // The rivals beaten at their coarse fit, judged at the round's end ([`rival`]).
    let mut beaten: Vec<Beaten> = Vec::new();
    // The screen: a coarse fit (`screen_evals` rollouts of the training set) of every candidate
    // of one size (one parameter; then more), those candidates in parallel. Only a candidate
    // whose coarse training improvement reaches `screen_share` of the round's best improvement
    // so far (coarse or full) is fitted in full (the others: phase "screen"); the full fit goes
    // on from the coarse one. Once a kept candidate leaves a white residual, the larger ones
    // are not fitted at all (phase "floor").
    // Gains are relative (1 − RMSE after / before) so that the screen's, on its shorter data,
    // and a full fit's, on the whole training set, compare.
    let rel =
        |f: f64, before: f64| if f.is_finite() { 1.0 - f / before } else { f64::NEG_INFINITY };
    let (base_train, base_short) = (tr_err.rmse(), sh_err.rmse());
    let gain = |f: f64| rel(f, base_short);
    let mut best_gain = 0.0f64;
    let mut coarse: Vec<Coarse> = vec![None; cands.len()];
    // The one-parameter candidates are `cands[..n1]`, the others `cands[n1..n0]`; mirror
    // completions come after `n0`.
    let n0 = cands.len();
    let mut n1 = cands.iter().take_while(|(e, ..)| e.fitted() < 2).count();
    // The linear model's favourite first, alone ([`lead`]), whatever its size: `cands[..n_lead]`
    // (a lead of more parameters joins the one-parameter block at its front).
    let predicted_rmse: Vec<Option<f64>> =
        cands.iter().map(|(e, g, _)| screen.lead_rmse_beside(engine, &applied, (*e, g))).collect();
    let n_lead = match lead::lead(&predicted_rmse) {
        // Only when the lead at the floor would leave some candidate unscreened.
        Some(i) if opts.policy.lead_first && cands.iter().any(|c| c.1 != cands[i].1) => {
            n1 += usize::from(i >= n1);
            cands[..=i].rotate_right(1);
            1
        }
        _ => 0,
    };
    let mut blocks = lead::Blocks::new(n_lead, n1, n0);
    // The groups of the kept candidates that left a white training residual: once there is
    // one, a candidate not yet screened is screened only on one of those groups (an alias).
    let mut floored_groups: Vec<Vec<String>> = Vec::new();
    // Fewest parameters of a kept candidate whose training residual is white on every joint.
    let mut floor_k: Option<usize> = None;
    // The lowest training RMSE of those, relative to the round's start.
    let mut floor_train: Option<f64> = None;
    // The log indices of the kept candidates that left a white training residual.
    let mut floored: Vec<usize> = Vec::new();
    // The log index of the lead's fit on the whole training set.
    let mut lead_logged: Option<usize> = None;
    // The first model at the floor's reach on the probes' data ([`Reach`]).
    let mut reach: Option<Reach> = None;
    // The lead's early pair look-ahead, once tried ([`pair_first`]).
    let mut early_tried: Option<Option<EarlyPair>> = None;
    // The candidates left without a coarse fit by round 0's trust ([`trust_out`]) or by the
    // held-out linear model ([`heldout_out`]), with the largest training gain their linear model
    // allows; and why (the phase logged) with the held-out reach (NaN for round 0's trust).
    let mut trusted_out: Vec<(&'static dyn Effect, Vec<String>, f64)> = Vec::new();
    let mut out_why: Vec<(Phase, f64)> = Vec::new();
    let mut ci = 0;
    while ci < cands.len() {
        // The coarse fits of a size's candidates, which are then taken best first
        // ([`lead::Blocks`]); after a lead at the floor only its aliases are screened.
        let block = blocks.next(ci, floor_k.is_some(), || {
            lead::keep_first(&mut cands[n_lead..n1], |(_, g, _)| floored_groups.contains(g))
        });
        if let Some(range) = block {
            engine.report(
                round,
                Phase::Screen,
                Some((ci + 1, cands.len(), format!("coarse fits of {} candidates", range.len()))),
            );
            // After round 0, a candidate whose linear model round 0 confirmed is taken at its
            // word ([`trust_out`]): no coarse fit when it could not reach the bar; nor one whose
            // held-out linear optimum could not pass the gate ([`heldout_out`]), nor a smooth one
            // of several parameters whose held-out optimum at its start could not lower the
            // held-out RMSE by the trust's edge of the bar ([`super::start_bound`],
            // `heldout_bound`). Neither is the
            // plain variant of a candidate on its joints: the richer model is judged from the
            // plain one's coarse fit ([`coarse::deferred`]); without it, it is coarse-fitted
            // whole on the screen's data (KR8's Stribeck friction on the hip: 337 replayed s).
            let cut = (opts.policy.screen_share * best_gain).max(opts.policy.min_rel_improvement);
            let (ho, block) =
                ((&screen, &mut ho_screen), (&cands[..], &coarse[..], &cands[range.clone()]));
            let set = (round, cut, best_gain > 0.0);
            let out_of = out_of(s, set, ho, (short, &applied, &ho_err), &covered, block);
            // (The reach's coarse fits on the probes' data are booked apart: `Phase::Reach`.)
            engine.report(round, Phase::Reach, None);
            let far: Vec<Option<(Vec<f64>, f64)>> = cands[range.clone()]
                .par_iter()
                .map(|(e, g, _)| match coarse::deferred(s, (*e, g), &cands, &coarse) {
                    Some(_) => None,
                    None => reach.as_ref()?.out_of_reach(s, Some(&screen), (*e, g)),
                })
                .collect();
            engine.report(round, Phase::Screen, None);
            // (A replayed point that reaches the bar a fit set admits the candidate; before any
            // did, the block's secant coarse fits set it, [`secant_bar`].)
            let admits = if best_gain > 0.0 { cut } else { f64::INFINITY };
            let at = (short, &applied[..]);
            let block = (&cands[..], &coarse[..], range.clone());
            let fits = secant_bar::block_fits(s, &screen, at, block, (&out_of, &far), admits);
            for ((c, f), o) in cands[range.clone()].iter().zip(&fits).zip(&out_of) {
                if let Some((upper, why, reach)) = o
                    && f.0.is_empty()
                    && f.1.is_infinite()
                {
                    trusted_out.push((c.0, c.1.clone(), *upper));
                    out_why.push((*why, *reach));
                }
                // Round 0's record of which linear models its coarse fits confirm.
                let pred = screen.predict(c.0.id(), &c.1).map(|p| gain(p.train_rmse));
                if round == 0
                    && let Some(want) = pred
                    && !f.0.is_empty()
                    && f.1.is_finite()
                {
                    let ok = coarse::agrees(gain(f.1), want, &opts.policy);
                    engine.note_trust((c.0, &c.1), ok);
                }
            }
            for f in fits.iter().filter(|f| !coarse::is_deferred(f)) {
                best_gain = best_gain.max(gain(f.1));
            }
            let mut both: Vec<(Cand, (Vec<f64>, f64))> =
                cands[range.clone()].iter().cloned().zip(fits).collect();
            both.sort_by(|a, b| a.1.1.total_cmp(&b.1.1));
            for (k, (c, f)) in both.into_iter().enumerate() {
                cands[range.start + k] = c;
                coarse[range.start + k] = Some(f);
            }
            // Once both sizes are screened, the candidates not yet fitted are taken best coarse
            // fit first, whatever their size: a two-parameter candidate that explains nearly
            // everything is fitted before the one-parameter ones that explain half, which the
            // floor screen then leaves out when it reached the floor.
            if range.start > ci {
                let mut rest: Vec<(Cand, Coarse)> =
                    cands[ci..n0].iter().cloned().zip(coarse[ci..n0].iter().cloned()).collect();
                rest.sort_by(|a, b| {
                    let f = |x: &Coarse| x.as_ref().map_or(f64::INFINITY, |c| c.1);
                    f(&a.1).total_cmp(&f(&b.1))
                });
                for (k, (c, f)) in rest.into_iter().enumerate() {
                    cands[ci + k] = c;
                    coarse[ci + k] = f;
                }
            }
        }
        // The lead kept short of the floor: its pairs with the best coarse-fitted rivals are
        // judged before any rival's full fit ([`pair_first`]); a pair kept raises the bar.
        if early_tried.is_none()
            && n_lead == 1
            && ci == 1
            && floor_k.is_none()
            && let [(lead_sel, _, _, i, _)] = accepted.as_slice()
            && Some(*i) == lead_logged
        {
            let bar = (opts.policy.screen_share * best_gain).max(opts.policy.min_rel_improvement);
            let rivals = rivals((&cands[ci..], &coarse[ci..]), |f| gain(f) >= bar);
            let at = (short, &applied[..]);
            early_tried = Some(early_pair(s, at, lead_sel, &rivals, &ho_err, (z, round), out));
            // The pair (at the floor) is judged as a kept candidate there is: only aliases on
            // its joints (of at most its parameters) are still screened.
            if let Some(Some(p)) = &early_tried {
                best_gain = best_gain.max(gain(p.short_rmse));
                let (k, group) = p.floored(&engine.joints);
                (floor_k, floor_train) = (Some(k), Some(p.train_rmse / base_train));
                floored_groups.push(group);
                reach = Reach::new(engine, short, &applied, &p.set);
            }
        }
        let (e, group, ev) = cands[ci].clone();
        engine.report(
            round,
            Phase::Add,
            Some((ci + 1, cands.len(), format!("{} on {}", e.id(), group.join(",")))),
        );
        ci += 1;
        let predicted = screen.predict(e.id(), &group);
        let not_tested = |phase, p: Vec<f64>, f: f64| Tried {
            predicted,
            ..Tried::not_tested(round, phase, e.id(), &group, p, f)
        };
        // A kept candidate already left a white training residual: one with more parameters
        // cannot explain more, and Occam's choice would not take it (`tried`: phase "floor").
        let unscreened = coarse.get(ci - 1).is_none_or(|c| c.is_none());
        let deferred =
            coarse.get(ci - 1).cloned().flatten().is_some_and(|c| coarse::is_deferred(&c));
        if floor_k.is_some_and(|k| {
            e.fitted() > k || (unscreened && n_lead > 0 && !floored_groups.contains(&group))
        }) && !(deferred && coarse::plain_fitted(s, (short, &applied), (e, &group)))
        {
            out.tried.push(not_tested(Phase::Floor, vec![], f64::NAN));
            continue;
        }
        // Left without a coarse fit: its linear model, trusted, cannot reach the bar, or its
        // held-out linear optimum the gate (logged with that reach as its held-out improvement).
        if let Some(k) = trusted_out.iter().position(|(x, g, _)| x.id() == e.id() && *g == group) {
            let (why, reach) = out_why[k];
            let t = not_tested(why, vec![], f64::NAN);
            out.tried.push(Tried { heldout_improvement: reach, ..t });
            continue;
        }
        // Not coarse-fitted on the screen's data: first judged on the probes' data ([`Reach`]).
        let judged = coarse.get(ci - 1).cloned().flatten().is_some_and(|c| c.1.is_finite())
            && (!deferred || coarse::plain_fitted(s, (short, &applied), (e, &group)));
        let far = reach.as_ref().filter(|_| !judged);
        if let Some(r) = far
            && let Some((p, f)) = r.out_of_reach(s, Some(&screen), (e, &group))
        {
            out.tried.push(not_tested(r.phase, p, f));
            continue;
        }
        // Either the coarse fit or the linearised step must reach the share: a coarse grid can
        // miss a narrow basin (a torque limit) that the linear step sees, and the linear step
        // misses what is far from linear (a resonance moved by damping). The step counts as
        // replayed ([`coarse::replayed_step`], one replay of the screen's data); a coarse fit
        // past it goes on from it. After round 0 also a non-smooth effect's: its column (a finite
        // difference across a kink) can promise a gain that no parameter gives; in round 0 it is
        // taken as it is (a heavy knee's torque limit is admitted by its column alone, its
        // replayed step gaining too little).
        let reaches = |g: f64| g > 0.0 && g >= opts.policy.screen_share * best_gain;
        // A deferred candidate judged from its plain variant's coarse fit: the best point that
        // judgement simulated stands in for its linear step ([`coarse::when_taken`]).
        let mut stepped = None;
        let (mut cp, mut cf) = match coarse.get(ci - 1).cloned().flatten() {
            Some(c) if coarse::is_deferred(&c) => {
                // (An SSE on the screen's data whose RMSE would reach the bar.)
                let n = sh_err.n.max(1) as f64;
                let bar = |sse: f64| reaches(gain((sse / n).sqrt()));
                let taken = (short, &applied[..]);
                match coarse::when_taken(s, &screen, taken, (e, &group), (&cands, &coarse), &bar) {
                    Some((c, step)) => {
                        stepped = step;
                        c
                    }
                    None => {
                        out.tried.push(not_tested(Phase::Screen, vec![], f64::NAN));
                        continue;
                    }
                }
            }
            Some(c) => c,
            // A candidate added during the round (a mirror completion).
            None => engine.fit_budget(short, &applied, e, &group, opts.policy.screen_evals),
        };
        let mut linear_gain = predicted.map_or(f64::NEG_INFINITY, |p| gain(p.train_rmse));
        if let Some((sp, sf)) = stepped {
            linear_gain = gain(sf);
            if sf < cf {
                (cp, cf) = (sp, sf);
            }
        } else if (e.smooth() || round > 0) && !reaches(gain(cf)) && reaches(linear_gain) {
            let step = coarse::replayed_step(engine, &screen, (short, &applied), (e, &group));
            if let Some((sp, sf)) = step {
                linear_gain = gain(sf);
                if sf < cf {
                    (cp, cf) = (sp, sf);
                }
            }
        }
        if cp.is_empty() || !(reaches(gain(cf)) || reaches(linear_gain)) {
            out.tried.push(not_tested(Phase::Screen, cp.clone(), cf));
            // Its coarse fit still starts a joint pair fit (gain error + delay: neither alone
            // explains much) — when it explains something: at least `min_rel_improvement` of
            // the screen's data (a member that explains nothing alone starts no pair).
            if !cp.is_empty() && gain(cf) >= opts.policy.min_rel_improvement {
                fitted.push(Applied { effect: e, joints: group.clone(), params: cp });
            }
            continue;
        }
        // Once a kept candidate leaves a white training residual, another can only win Occam's
        // choice below by coming close to it: one whose coarse fit leaves `floor_screen_ratio`
        // times its training error cannot (`tried`: phase "floor_screen").
        if floor_train.is_some_and(|ft| cf / base_short > opts.policy.floor_screen_ratio * ft) {
            out.tried.push(not_tested(Phase::FloorScreen, cp, cf));
            continue;
        }
        // A richer model of a loss is fitted only where its plain variant's fit leaves its
        // signature ([`extension`]); its coarse fit still starts a joint pair.
        if extension::adds_nothing(s, short, &applied, (e, &group)) {
            if gain(cf) >= opts.policy.min_rel_improvement {
                fitted.push(Applied { effect: e, joints: group.clone(), params: cp.clone() });
            }
            out.tried.push(not_tested(Phase::Screen, cp, cf));
            continue;
        }
        // A full fit goes on from the coarse fit on the same training data; it is not made
        // where the coarse fit (one held-out replay) shows it cannot be kept ([`short_of_keep`]:
        // the held-out screen, `heldout_screen`; after round 0 the finer-step test at the
        // trust's edge, `discretisation_screen`, and a several-parameter one's held-out
        // Gauss–Newton optimum, `heldout_bound`). The lead too. Not a candidate that only its
        // linear step admits (a coarse fit can miss the narrow basin the full fit finds). One
        // that a kept candidate of the round beats decisively on held-out there is judged at
        // its coarse fit, not fitted in full ([`beaten_at_coarse`]; `tried`: "add_coarse").
        let whole = n_lead == 1 && ci == 1;
        let mut at_coarse = false;
        let mut ho_c = None;
        if reaches(gain(cf)) && !cp.is_empty() {
            let mut t = applied.clone();
            t.push(Applied { effect: e, joints: group.clone(), params: cp.clone() });
            ho_c = engine.errors(heldout, &t);
            let gains = (predicted.map(|p| gain(p.train_rmse)), gain(cf));
            let at = (gains, opts.policy.gate_z(z), round);
            let fl = (&floors[..], if whole { train } else { short });
            if let Some((why, h)) =
                short_of_keep(s, (&applied, &t), (&ho_err, ho_c.as_ref()), at, fl, out)
            {
                // (Its coarse fit still starts a joint pair fit, as a screened one's does.)
                if gain(cf) >= opts.policy.min_rel_improvement {
                    fitted.push(Applied { effect: e, joints: group.clone(), params: cp.clone() });
                }
                out.tried.push(Tried { heldout_improvement: h, ..not_tested(why, cp, cf) });
                continue;
            }
            let best = accepted
                .iter()
                .filter(|a| !a.1)
                .min_by(|a, b| a.0.heldout_rmse_after.total_cmp(&b.0.heldout_rmse_after));
            at_coarse = ho_c.as_ref().zip(best).is_some_and(|(h, b)| {
                beaten_at_coarse((&b.2, &b.0.joints), (h, &group), &opts.policy)
            });
        }
        // The full fit runs on the screen's data too (its cost does not grow with the log's
        // length); the held-out gate and the training BIC below use all data, and the round's
        // winner is refined on the whole training set ([`refine`]).
        // The lead, the likeliest winner, is fitted on the whole training set at once from its
        // coarse fit: the round's winner is fitted there anyway ([`refine`]).
        let start = (cf < base_short).then_some(cp.as_slice());
        let data = if whole { train } else { short };
        if whole {
            engine.report(round, Phase::LeadFit, None);
        }
        let (p, fit_rmse) = if at_coarse {
            (cp.clone(), cf)
        } else {
            engine.fit_from(data, &applied, (e, &group), start)
        };
        engine.report(round, Phase::Judge, None);
        let phase = if at_coarse { Phase::AddCoarse } else { Phase::Add };
        if p.is_empty() || !fit_rmse.is_finite() {
            continue;
        }
        // Gains compare on the screen's data: the lead's, fitted on the whole training set, is
        // measured there by one replay (the stretches of largest residual gain more than the
        // whole set does, and a lower bar lets more candidates into a full fit).
        let short_rmse = if whole && !std::ptr::eq(short, train) {
            let mut t = applied.clone();
            t.push(Applied { effect: e, joints: group.clone(), params: p.clone() });
            engine.errors(short, &t).map_or(f64::NAN, |x| x.rmse())
        } else {
            fit_rmse
        };
        best_gain = best_gain.max(gain(short_rmse));
        // A rival beaten at its coarse fit (not one a mirror completes) is logged with its
        // held-out verdict there, and judged at the round's end only where the pair
        // look-ahead could pair it ([`rival`]).
        let mirrored = matches!(group.as_slice(), [j] if partner(j, &engine.joints).is_some());
        if let Some(h) = ho_c.as_ref().filter(|_| at_coarse && !mirrored) {
            let v = verdict(&ho_err, h, &group, opts.policy.gate_z(z));
            let (heldout_improvement, significant) = (v.rel, v.significant);
            let t = not_tested(phase, p.clone(), f64::NAN);
            let logged = out.log(Tried { heldout_improvement, significant, ..t });
            beaten.push(Beaten { cand: (e, group, ev), params: p, predicted, logged });
            continue;
        }
        let full = whole.then(|| p.clone());
        // (One that leaves the whole training set worse explains nothing: logged without a
        // held-out test.)
        let Some((p, tr_a)) = on_whole_set(s, &applied, (e, &group), p.clone(), base_train) else {
            out.tried.push(not_tested(phase, p, f64::NAN));
            continue;
        };
        fitted.push(Applied { effect: e, joints: group.clone(), params: p.clone() });
        let mut trial = applied.clone();
        trial.push(Applied { effect: e, joints: group.clone(), params: p.clone() });
        let Some(ho_a) = engine.errors(heldout, &trial) else { continue };
        let train_rmse = tr_a.rmse();
        let bic_after = bic(tr_a.n, tr_a.sse, k_before + e.fitted());
        // Paired test on the windows of the candidate's joints (others barely move).
        let v = verdict(&ho_err, &ho_a, &group, opts.policy.gate_z(z));
        let keep =
            v.significant && v.rel >= opts.policy.min_rel_improvement && bic_after < bic_before;
        let judged = Judged {
            base: &applied,
            trial: &trial,
            gate: opts.policy.gate_z(z),
            floors: &floors,
            round,
        };
        let keep = keep && beyond_discretisation(engine, heldout, &judged, out);
        let logged = out.log(Tried {
            round,
            phase,
            effect: e.id().into(),
            joints: group.clone(),
            params: p.clone(),
            train_rmse,
            heldout_improvement: v.rel,
            significant: v.significant,
            bic_decreased: bic_after < bic_before,
            kept: false,
            predicted,
            simulated_s: None,
        });
        if full.as_ref() == Some(&p) {
            lead_logged = Some(logged);
        }
        // The lead beside effects kept in earlier rounds on its joints, each fitted without it,
        // is judged at the floor with them re-fitted together ([`refitted_at_floor`]); the
        // next round measures the floor again unless the round keeps that set.
        // (Not one judged at its coarse fit: a kept one leaves under half its held-out error, so
        // it is no answer at the floor, and its floors would cost three training replays.)
        let white = keep && !at_coarse && engine.at_floor(train, &trial, &tr_a);
        let refitted = (keep && !white && n_lead == 1 && ci == 1)
            .then(|| refitted_at_floor(s, short, &applied, &trial[applied.len()]))
            .flatten();
        if white || refitted.is_some() {
            if white {
                floored.push(logged);
            }
            floored_groups.push(group.clone());
            if reach.as_ref().is_none_or(|r| !r.at_floor()) {
                reach = Reach::new(engine, short, &applied, &trial).or(reach);
            }
            floor_k = Some(floor_k.map_or(e.fitted(), |k| k.min(e.fitted())));
            let r = refitted.unwrap_or(tr_a.rmse()) / base_train;
            floor_train = Some(floor_train.map_or(r, |t: f64| t.min(r)));
        }
        // Beside a kept lead above the floor, a candidate not yet coarse-fitted is first
        // judged on the probes' data against the screen's bar ([`Reach::beside_lead`]).
        if keep && whole && reach.is_none() {
            let bar = base_short * (1.0 - opts.policy.screen_share * best_gain);
            reach = Reach::beside_lead(engine, (short, &sh_err), &applied, bar);
        }
        if keep {
            // Mirror completion: a kept one-joint candidate is also fitted on its left/right
            // pair, which then competes with it on held-out (the diagnosis ranks the two sides
            // separately and can miss the partner of an effect both sides have).
            if let [j] = group.as_slice()
                && let Some(p) = partner(j, &engine.joints)
                && !covered(e.id(), &p)
                && let g = sorted_pair(j, p)
                && effects::alike_over(robot, e, &g)
                && !has_group(&cands, e.id(), &g)
            {
                let mut ev2 = ev.clone();
                ev2.insert("mirror_completion".into(), 1.0);
                cands.push((e, g, ev2));
            }
            let a = trial.last().expect("pushed");
            let bound = at_bound(engine, &applied, a);
            let m = tr_a.windows.len();
            let window_bic = bic_pieces(m, tr_a.n, tr_a.sse, k_before + e.fitted());
            accepted.push((
                Selected::new(a, ev, &v, ho_err.rmse(), ho_a.rmse(), (bic_before, bic_after)),
                bound,
                ho_a,
                logged,
                window_bic,
            ));
        }
    }
    // The early pair stands unless a single fitted after it is one it would not replace.
    if let Some(Some(p)) = early_tried
        && accepted
            .iter()
            .all(|(s, ..)| p.heldout_rmse < opts.policy.pair_gain * s.heldout_rmse_after)
    {
        for (mut p, a) in p.take(out) {
            out.applied.push(a);
            engine.report(round, Phase::RoundErrors, None);
            set_uncertainty(engine, train, &mut p, &out.applied, &mut out.warnings);
            out.selected.push(p);
        }
        return true;
    }
    let kept_all: Vec<(usize, Selected)> =
        accepted.iter().map(|(s, _, _, i, _)| (*i, s.clone())).collect();
    // A candidate with a parameter on its bound only wins when no interior one is kept.
    if accepted.iter().any(|(_, b, ..)| !b) {
        accepted.retain(|(_, b, ..)| !b);
    }
    let Some(ib) = (0..accepted.len()).min_by(|&a, &b| {
        accepted[a].0.heldout_rmse_after.total_cmp(&accepted[b].0.heldout_rmse_after)
    }) else {
        // A joint pair starts from its members' coarse fits: those left out by their trusted
        // linear model that could start one are coarse-fitted now, as the screen would have.
        let at = (short, &applied[..]);
        let fitted = with_pair_starts(engine, &screen, at, &trusted_out, fitted, gain);
        return joint_pairs(
            engine,
            (short, train, heldout),
            (&applied, &fitted),
            (&tr_err, &ho_err),
            &floors,
            z,
            round,
            out,
        );
    };
    // Occam: the simplest candidate within 5 % of the best held-out RMSE that the best does not
    // beat beyond noise (paired test, z = 2) and whose training BIC is not higher (the training
    // set is larger than the held-out one: a better fit that pays for its parameters there is
    // not noise).
    let (best_s, _, best_e, ..) = &accepted[ib];
    let equivalent = |i: usize| {
        let (s, _, e, ..) = &accepted[i];
        if i == ib {
            return true;
        }
        let group: Vec<String> = s.joints.iter().chain(&best_s.joints).cloned().collect();
        s.heldout_rmse_after <= best_s.heldout_rmse_after * engine.opts.policy.simpler_within
            && s.bic_after <= best_s.bic_after
            && !verdict(e, best_e, &group, engine.opts.policy.noise_gate()).significant
    };
    let win = (0..accepted.len())
        .filter(|&i| equivalent(i))
        .min_by(|&a, &b| {
            let ka = effects::by_id(&accepted[a].0.effect).map_or(9, |e| e.fitted());
            let kb = effects::by_id(&accepted[b].0.effect).map_or(9, |e| e.fitted());
            ka.cmp(&kb)
                .then(accepted[a].0.heldout_rmse_after.total_cmp(&accepted[b].0.heldout_rmse_after))
        })
        .expect("the best is equivalent to itself");
    let same: Vec<bool> = (0..accepted.len()).map(equivalent).collect();
    // An equivalent candidate that holds the winner as a special case on the same joints
    // ([`Effect::nests`]: Stribeck friction around Coulomb friction) wins when its extra
    // parameters pay for themselves on the training set, counted per window: the held-out
    // set can be too short to tell the two apart. (A light pendulum with a Stribeck curve,
    // static 0.06 / sliding 0.03 N·m: Coulomb friction 4.61 mrad held-out, Stribeck 4.71 —
    // one 5 s episode whose error is where the joint came to rest — while on the five
    // training episodes Stribeck left 2.68 mrad against 3.80.)
    let nests_winner = |i: usize| {
        let (w, c) = (&accepted[win].0, &accepted[i].0);
        c.joints == w.joints
            && effects::by_id(&c.effect).and_then(|e| e.nests()) == Some(w.effect.as_str())
    };
    let win = (0..accepted.len())
        .filter(|&i| same[i] && nests_winner(i) && accepted[i].4 < accepted[win].4)
        .min_by(|&a, &b| accepted[a].4.total_cmp(&accepted[b].4))
        .unwrap_or(win);
    let logged = accepted[win].3;
    let mut accepted: Vec<Selected> = accepted.into_iter().map(|(s, ..)| s).collect();
    let rivals = rival_notes(&accepted, win, &same);
    let mut w = accepted.swap_remove(win);
    if !std::ptr::eq(short, train) && lead_logged != Some(logged) {
        engine.report(round, Phase::Refine, None);
        w = refine(s, &applied, w, (&tr_err, &ho_err), z);
    }
    let at = RoundAt { applied: &applied, errs: (&tr_err, &ho_err), floors: &floors, z, round };
    let kept_all = judge_beaten(s, &at, (kept_all, &w), beaten, out);
    if let Some(pair) = pair_lookahead(s, &applied, &kept_all, &w, (z, round), false, out) {
        for (mut p, a) in pair {
            out.applied.push(a);
            engine.report(round, Phase::RoundErrors, None);
            set_uncertainty(engine, train, &mut p, &out.applied, &mut out.warnings);
            out.selected.push(p);
        }
        return true;
    }
    out.tried[logged].kept = true;
    out.notes.extend(rivals);
    let e = effects::by_id(&w.effect).expect("known");
    out.applied.push(Applied { effect: e, joints: w.joints.clone(), params: w.values.clone() });
    // The winner left a white residual: the next round stops there without measuring the
    // floors again (the re-fit on the whole training set only lowered its error).
    out.at_floor = floored
        .contains(&logged)
        .then(|| (shape_key(&[], &out.applied), out.tried[logged].train_rmse));
    engine.report(round, Phase::RoundErrors, None);
    set_uncertainty(engine, train, &mut w, &out.applied, &mut out.warnings);
    out.selected.push(w);
    true
}
