//! Recordings of a robot with its own physics (`bench/independent_py/chainsim.py`: a numpy
//! planar chain, no MuJoCo; committed in `fixtures/independent_py/`, see its README): the
//! three-joint leg with a 0.6 kg payload composed into its shank by hand must come out as a
//! `link_mass` on the knee with the payload's mass within 10 % and its place within 10 % of the
//! link's length; one leg standing on a pinned foot (the chain rooted at the foot, the trunk on
//! top, held up by the servos) with the trunk's centre of mass moved must come out as a
//! `com_offset` on the hip's child body, the trunk, both components within 10 % of the shift;
//! a battery off the trunk's axis must come out as one `link_mass` on the hip, its mass and
//! its place along and across the trunk within 10 %;
//! one armature behind every motor of the leg must come out as one group on all three joints;
//! a gear play behind the knee's motor must come out as backlash on the knee;
//! a gear play behind every motor must come out as one backlash group on all three joints;
//! the shank's moment of inertia doubled must come out as a `link_inertia` on the knee within
//! 10 %;
//! the same robots with nothing concealed must give nothing. Every expected value is read from the simulator's `truth.json`.

mod common;

use common::indep::{TruthBody, assert_nothing, assert_payload_found, fit, found, truth};

/// The candidates a round after round 0 left out because each of their joints was at its floor
/// (`joint_floor`), checked against the fit's own report: never in round 0, never fitted or
/// kept, and never on a joint the report lists as above its floor (`unexplained`: the training
/// residual of the fitted model more than `white_ratio` of its floor; the model of round 1's
/// base when a later round keeps nothing).
fn joint_floor_entries(v: &serde_json::Value) -> Vec<serde_json::Value> {
    let above: Vec<&str> =
        v["unexplained"].as_array().unwrap().iter().filter_map(|u| u["joint"].as_str()).collect();
    let out: Vec<serde_json::Value> = v["tried"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|t| t["phase"] == "joint_floor")
        .cloned()
        .collect();
    for t in &out {
        assert!(t["round"].as_u64() >= Some(1), "left out in round 0: {t}");
        assert!(t["kept"] == false && t["params"].as_array().is_some_and(|p| p.is_empty()));
        let joints = t["joints"].as_array().unwrap();
        assert!(
            joints.iter().all(|j| !above.contains(&j.as_str().unwrap())),
            "left out on a joint above its floor ({above:?}): {t}"
        );
    }
    out
}

fn own_physics(truth: &serde_json::Value) {
    assert_eq!(truth["simulator"], "chainsim.py", "not the own-physics simulator's recording");
}

#[test]
fn a_payload_composed_by_the_robots_own_physics_is_found_on_the_knee() {
    let truth = truth("KR1_shank_payload");
    own_physics(&truth);
    assert_payload_found(&fit("KR1_shank_payload", &[]), &TruthBody::of(&truth, "shank"), "knee");
}

/// One armature on every joint (0.06 kg·m² behind each motor; the model says 0.04, 0.03 and
/// 0.012) comes out as one group on all three joints, within 10 % of the truth's value, and
/// nothing else (before the all-joint group was a candidate for joints the model gives values of
/// their own, it came out as a hip group and a knee + ankle group).
#[test]
fn one_armature_on_every_joint_is_found_as_one_group() {
    let truth = truth("KR8_all_armature");
    own_physics(&truth);
    let joints = &truth["effects"]["joints"];
    let value = joints["knee"]["armature"].as_f64().unwrap();
    for j in ["hip_pitch", "ankle"] {
        assert_eq!(joints[j]["armature"].as_f64(), Some(value), "not one value on every joint");
    }
    let v = fit("KR8_all_armature", &[]);
    assert_eq!(
        found(&v),
        [("armature".into(), r#"["hip_pitch","knee","ankle"]"#.into())],
        "{:?}",
        found(&v)
    );
    let a = v["missing_physics"][0]["params"]["armature"].as_f64().unwrap();
    assert!((a - value).abs() <= 0.1 * value, "armature {a} for {value}");
    // Stribeck and load-dependent friction hold Coulomb friction as a special case: where
    // Coulomb friction's coarse fit on the same joints did not reach the round's bar for a full
    // fit (logged `screen`), the richer model is judged from that fit taken over (a few replays)
    // instead of a coarse fit of its own, and on this leg nothing there reaches the bar: it is
    // logged `screen` without parameters.
    let tried = v["tried"].as_array().unwrap();
    let mut judged = 0;
    for t in tried {
        let effect = t["effect"].as_str().unwrap();
        if !["stribeck_friction", "load_dependent_friction"].contains(&effect) {
            continue;
        }
        let plain_screened = tried.iter().any(|p| {
            p["effect"] == "coulomb_friction"
                && p["round"] == t["round"]
                && p["joints"] == t["joints"]
                && p["phase"] == "screen"
        });
        if plain_screened {
            judged += 1;
            assert!(
                t["phase"] == "screen" && t["params"].as_array().is_some_and(|p| p.is_empty()),
                "{effect} on {} fitted although Coulomb friction was screened out: {t}",
                t["joints"]
            );
        }
    }
    assert!(judged > 0, "no friction extension beside a screened Coulomb friction");
    // Beside the kept armature group (round 0's lead, 1.3-1.4 x above the floor on two joints)
    // a rival is first coarse-fitted on the probes' 2 s; one that leaves more squared residual
    // there than the screen's bar allows on all of its 10 s could not reach the bar, and is
    // logged `reach_screen` with that fit, without a coarse fit on the screen's data. On this
    // leg the probes hold over half the screen's residual, and most rivals are out of reach.
    let round0 = |phase: &str| {
        tried.iter().filter(|t| t["round"] == 0 && t["phase"] == phase).collect::<Vec<_>>()
    };
    let out = round0("reach_screen");
    assert!(out.len() >= 10, "{} rivals out of reach beside the kept lead", out.len());
    for t in &out {
        assert!(
            t["params"].as_array().is_some_and(|p| !p.is_empty())
                && t["train_rmse"].as_f64().is_some_and(f64::is_finite),
            "a rival out of reach without its probes' fit: {t}"
        );
    }
    assert!(round0("screen").is_empty(), "rivals coarse-fitted on the screen's data in round 0");
    // Beside the kept group (round 1), a candidate whose coarse fit gains too little and whose
    // linear step alone would admit it to a full fit has that step replayed once first, also a
    // non-smooth one: the columns of a torque limit, a gear play and an external-load friction
    // (finite differences across a kink) promised 7-20 % of the screen's residual, the replays
    // gained none, and none of them is fitted in full.
    let kinks: Vec<_> = tried
        .iter()
        .filter(|t| {
            t["round"] == 1
                && ["torque_limit", "backlash", "external_load_friction"]
                    .contains(&t["effect"].as_str().unwrap())
        })
        .collect();
    assert!(!kinks.is_empty(), "no non-smooth candidate in round 1");
    for t in kinks {
        assert_ne!(t["phase"], "add", "fitted in full on its linear step alone: {t}");
    }
    // Beside the kept group the hip's residual is within `white_ratio` of its floor (the knee's
    // and the ankle's are not): round 1 screens no candidate on the hip alone (`joint_floor`,
    // without a fit), and screens the group and the other joints as before.
    let at_floor = joint_floor_entries(&v);
    assert!(
        at_floor.iter().any(|t| t["joints"] == serde_json::json!(["hip_pitch"])),
        "round 1 screened the hip, at its floor: {at_floor:?}"
    );
    assert!(tried.iter().any(|t| t["round"] == 1
        && t["phase"] != "joint_floor"
        && t["joints"] == serde_json::json!(["hip_pitch", "knee", "ankle"])));
    // A body on the hip's link loads every joint between it and the base: its candidates are
    // screened as before, the hip at its floor or not.
    let bodies = ["com_offset", "link_mass", "link_inertia"];
    assert!(at_floor.iter().all(|t| !bodies.contains(&t["effect"].as_str().unwrap())));
    assert!(tried.iter().any(|t| t["round"] == 1
        && bodies.contains(&t["effect"].as_str().unwrap())
        && t["joints"] == serde_json::json!(["hip_pitch"])));
    // Round 1's lead (the first candidate it screens) is fitted in full only once its coarse fit
    // lowers the held-out error, as every other candidate's must: the hip's `com_offset`, whose
    // full fit (134 replayed s) left the held-out error 0.9 % worse, is left out by its held-out
    // linear optimum (`heldout_linear`) or stops at its coarse fit's held-out replay
    // (`heldout_screen`).
    let lead =
        tried.iter().find(|t| t["round"] == 1 && t["phase"] != "joint_floor").expect("a round 1");
    assert!(
        ["heldout_screen", "heldout_linear"].contains(&lead["phase"].as_str().unwrap_or(""))
            || lead["heldout_improvement"].as_f64().is_some_and(|h| h > 0.0),
        "round 1's lead fitted in full although it explains nothing held out: {lead}"
    );
}

/// A gear play of 0.04 rad (total) behind the knee's motor — in the simulator the servo drives
/// a rotor (the knee's armature) that pushes the link through the play — comes out as backlash
/// on the knee alone, within 10 % of the truth's play (4,467 recording seconds replayed, 344 of
/// them the timestep check's re-fit).
#[test]
fn a_gear_play_behind_the_knee_motor_is_found_as_backlash_on_the_knee() {
    let truth = truth("KR6_knee_backlash");
    own_physics(&truth);
    let play = truth["effects"]["joints"]["knee"]["backlash"].as_f64().unwrap();
    let v = fit("KR6_knee_backlash", &[]);
    assert_eq!(found(&v), [("backlash".into(), r#"["knee"]"#.into())], "{:?}", found(&v));
    let b = v["missing_physics"][0]["params"]["backlash_rad"].as_f64().unwrap();
    assert!((b - play).abs() <= 0.1 * play, "backlash {b} for {play}");
    // The kept play leaves the knee above its floor. The other candidate kept in round 0, the
    // knee's gain error, is kept at its coarse fit only (below): the look-ahead does not pair it
    // with the play (no mimicking pair, no group with an exception), and no pair of round 0 is
    // fitted, coarsely or in full (paired, its coarse fit left the held-out error 15 % above the
    // play's alone).
    let tried = v["tried"].as_array().unwrap();
    let pairs: Vec<_> = tried
        .iter()
        .filter(|t| t["round"] == 0 && t["effect"].as_str().unwrap().contains('+'))
        .collect();
    assert!(pairs.is_empty(), "round 0 fitted pairs: {pairs:?}");
    // The knee's gain error, replayed on the held-out episode at its coarse fit, leaves over
    // twice the kept play's held-out error (0.40 against 0.85 of it removed, most windows
    // worse): a full fit going on from there could not come near the play. It is judged at its
    // coarse fit (`add_coarse`, still gated), and the play is round 0's only candidate fitted in
    // full.
    let round0 = |phase: &str| {
        tried.iter().filter(|t| t["round"] == 0 && t["phase"] == phase).collect::<Vec<_>>()
    };
    let full = round0("add");
    assert!(full.iter().all(|t| t["effect"] == "backlash"), "rivals fitted in full: {full:?}");
    let coarse = round0("add_coarse");
    assert!(
        coarse.iter().any(|t| t["effect"] == "gain_error"
            && t["params"].as_array().is_some_and(|p| !p.is_empty())
            && t["heldout_improvement"].as_f64().is_some_and(|h| h > 0.0)),
        "the gain error not judged at its coarse fit: {coarse:?}"
    );
    // ... and, nothing it could pair with kept (no delay, no Coulomb friction on the knee), it
    // is not judged further: no replay on the whole training set.
    assert!(
        coarse.iter().filter(|t| t["effect"] == "gain_error").all(|t| t["train_rmse"].is_null()),
        "the unpaired gain error judged further: {coarse:?}"
    );
    // The knee's play absorbs part of the model's timestep, so its value is re-fitted, told, at
    // a finer step (a note says how many seconds that replayed): those replays are the run's
    // cost, in `search.simulated_s` and by phase as `timestep_shift`.
    let notes = v["notes"].as_array().unwrap();
    let check =
        notes.iter().filter_map(|n| n.as_str()).find(|n| n.contains("replayed for this check"));
    let search = &v["search"];
    let phases = search["simulated_s_by_phase"].as_object().unwrap();
    let by_phase: f64 = phases.values().map(|x| x.as_f64().unwrap()).sum();
    let total = search["simulated_s"].as_f64().unwrap();
    assert!(
        (by_phase - total).abs() <= 0.1 * phases.len() as f64,
        "{by_phase} by phase, {total} in all"
    );
    // Round 0, once the play set the bar, leaves out the smooth one-parameter rivals whose
    // linear step the probes' data confirms and whose prediction at the trust's edge cannot
    // reach the bar (the knee's action delay among them); round 1 (the play kept, the residual
    // still above the floors) takes round 0's confirmed linear models at their word: candidates
    // whose prediction cannot reach the round's bar are not coarse-fitted again. Both are logged
    // `trust_screen`, and none of them is kept.
    let trusted: Vec<_> = tried.iter().filter(|t| t["phase"] == "trust_screen").collect();
    let in_round = |r: u64| trusted.iter().filter(|t| t["round"].as_u64() == Some(r)).count();
    assert!(in_round(1) > 0, "round 1 re-screened every candidate");
    assert!(
        trusted
            .iter()
            .any(|t| t["round"] == 0 && t["effect"] == "action_delay" && t["joints"][0] == "knee"),
        "round 0 coarse-fitted every rival: {trusted:?}"
    );
    assert!(trusted.iter().all(|t| t["kept"] == false));
    // Nor is one whose held-out linear optimum, at the trust's edge, cannot lower the held-out
    // error by the gate's 2 % (`heldout_linear`, its reach logged as `heldout_improvement`)
    // once a replay of its training step on the held-out probes' data confirmed that linear
    // model: the knee's armature, which round 1's training columns rank first, among them (7
    // of round 1's 29 candidates; with round 0's trust, 14 are left out without a coarse fit).
    let ho: Vec<_> = tried.iter().filter(|t| t["phase"] == "heldout_linear").collect();
    assert!(
        ho.len() + in_round(1) >= 11,
        "round 1 coarse-fitted what the held-out set rules out: {ho:?}"
    );
    // Not Coulomb friction where its Stribeck extension is a candidate: the extension is judged
    // from the plain variant's coarse fit, and without it is coarse-fitted whole.
    let stribeck = |t: &&serde_json::Value| {
        tried.iter().any(|x| x["effect"] == "stribeck_friction" && x["joints"] == t["joints"])
    };
    assert!(!ho.iter().any(|t| t["effect"] == "coulomb_friction" && stribeck(t)), "{ho:?}");
    // (A reach below zero: no value lowers the held-out error — the armature group on all three
    // joints, whose one shared value moves each member from its own start, at best leaves it
    // higher.)
    assert!(ho.iter().all(|t| t["round"].as_u64() >= Some(1)
        && t["kept"] == false
        && t["heldout_improvement"].as_f64().is_some_and(|h| h.is_finite() && h < 0.02)));
    assert!(
        ho.iter().all(|t| t["heldout_improvement"].as_f64() >= Some(0.0)
            || (t["effect"] == "armature" && t["joints"].as_array().is_some_and(|j| j.len() > 1))),
        "{ho:?}"
    );
    assert!(ho.iter().any(|t| t["effect"] == "armature" && t["joints"][0] == "knee"), "{ho:?}");
    // Those held-out probes and replays are booked to round 1, whose cost they cut.
    let r1 = search["simulated_s_by_round_phase"]["1"].as_object().unwrap();
    assert!(r1.get("heldout_linear").and_then(|x| x.as_f64()).is_some_and(|s| s > 0.0), "{r1:?}");
    // The same seconds by round: the greedy rounds' and what ran after them ("end").
    let rounds = search["simulated_s_by_round"].as_object().unwrap();
    let by_round: f64 = rounds.values().map(|x| x.as_f64().unwrap()).sum();
    assert!(
        (by_round - total).abs() <= 0.1 * rounds.len() as f64,
        "{by_round} by round, {total} in all: {rounds:?}"
    );
    assert!(rounds.contains_key("0") && rounds.contains_key("end"), "{rounds:?}");
    let shift = phases.get("timestep_shift").and_then(|x| x.as_f64());
    assert!(check.is_some(), "no timestep check: {notes:?}");
    assert!(shift.is_some_and(|s| s > 0.0), "the timestep check's re-fit not counted: {phases:?}");
    // The re-fit at the finer step goes from the answer by Gauss–Newton steps with the final
    // standard errors' Jacobian (their secant updates cross the play's kinks; no told fit),
    // and lands within 10 % of the play the recordings were made with.
    let check = check.unwrap();
    assert!(check.contains("Gauss–Newton step"), "the re-fit fell back to a told fit: {check}");
    let fine: f64 = check
        .split_once(" at 1.000 ms, ")
        .and_then(|(_, rest)| rest.split_once(" at 0.250 ms"))
        .and_then(|(x, _)| x.parse().ok())
        .unwrap_or_else(|| panic!("{check}"));
    assert!((fine - play).abs() <= 0.1 * play, "re-fitted at 0.25 ms: {fine} for {play}; {check}");
}

/// A gear play of 0.03 rad (total) behind every motor comes out as one backlash group on all
/// three joints, within 10 % of the truth's play. The group leaves every joint above its floor;
/// its rivals of round 0 are kept at their coarse fits only (`add_coarse`) and the look-ahead
/// pairs none of them with it but the hip's own play (the group with an exception on the hip),
/// whose coarse fit leaves 0.2 % less than the group alone on the screen's data, short of
/// `pair_gain`: no pair is fitted in full (`pair`; two were, 2,861 of the run's 7,460 replayed
/// seconds, held out within 1 % of the group alone).
#[test]
fn a_gear_play_behind_every_motor_is_found_as_one_backlash_group() {
    let truth = truth("KR7_all_backlash");
    own_physics(&truth);
    let joints = &truth["effects"]["joints"];
    let play = joints["knee"]["backlash"].as_f64().unwrap();
    for j in ["hip_pitch", "ankle"] {
        assert_eq!(joints[j]["backlash"].as_f64(), Some(play), "not one play on every joint");
    }
    let v = fit("KR7_all_backlash", &[]);
    assert_eq!(
        found(&v),
        [("backlash".into(), r#"["hip_pitch","knee","ankle"]"#.into())],
        "{:?}",
        found(&v)
    );
    let b = v["missing_physics"][0]["params"]["backlash_rad"].as_f64().unwrap();
    assert!((b - play).abs() <= 0.1 * play, "backlash {b} for {play}");
    // Every joint stays above its floor beside the play (its rigid flank, the rotor's soft
    // one): round 1 leaves no candidate out for its joints being at the floor.
    let at_floor = joint_floor_entries(&v);
    assert!(at_floor.is_empty(), "candidates left out on joints above their floor: {at_floor:?}");
    let tried = v["tried"].as_array().unwrap();
    let full: Vec<_> = tried.iter().filter(|t| t["phase"] == "pair").collect();
    assert!(full.is_empty(), "pairs fitted in full: {full:?}");
    let rounds0 =
        |phase: &str| tried.iter().filter(|t| t["round"] == 0 && t["phase"] == phase).count();
    assert!(rounds0("add_coarse") > 0, "no rival kept at its coarse fit: nothing to test");
    let screened: Vec<_> = tried
        .iter()
        .filter(|t| t["phase"] == "pair_screen" && t["effect"] == "backlash+backlash")
        .collect();
    assert!(!screened.is_empty(), "the group's exception on the hip not screened: {tried:?}");
    // A rival at its coarse fit is judged further (its whole-set replay: a training RMSE) only
    // where the look-ahead could pair it, and not where every pair it could form is one the
    // look-ahead leaves out by its linear screen: the hip's play, the group's exception, whose
    // one pair (logged `pair_screen` above) is so left out, is not; nor is the gain error on all
    // three joints, whose mimicking partners (a delay, Coulomb friction) the screen left out
    // beside a winner of one parameter.
    let coarse0 = |effect: &str, n: usize| {
        tried
            .iter()
            .find(|t| {
                t["round"] == 0
                    && t["phase"] == "add_coarse"
                    && t["effect"] == effect
                    && t["joints"].as_array().is_some_and(|j| j.len() == n)
            })
            .unwrap_or_else(|| panic!("no {effect} on {n} joints at its coarse fit: {tried:?}"))
    };
    let hip = coarse0("backlash", 1);
    assert!(hip["train_rmse"].is_null(), "the hip's play judged: {hip}");
    assert!(hip["heldout_improvement"].as_f64().is_some(), "no held-out verdict: {hip}");
    let hip_pair = |t: &&serde_json::Value| {
        t["round"] == 0 && t["params"].as_array().is_some_and(|p| p.first() == hip["params"].get(0))
    };
    assert!(screened.iter().any(hip_pair), "the hip's pair not screened in round 0: {screened:?}");
    let gain = coarse0("gain_error", 3);
    assert!(gain["train_rmse"].is_null(), "the unpaired gain error judged: {gain}");
    assert!(gain["heldout_improvement"].as_f64().is_some(), "no held-out verdict: {gain}");
    // Round 0's judging replays (`judge`): the lead's whole-set and held-out replays and its
    // floors (at most three training replays: reconstruction, timestep at dt / 2 and, when its
    // decision needs it, dt / 4); no rival at its coarse fit is judged.
    // Seconds from the recordings' own clocks (ep_03 is declared held out).
    let dir = common::indep::case("KR7_all_backlash").join("episodes");
    let secs = |f: &str| {
        let text = std::fs::read_to_string(dir.join(f)).expect("episode");
        let t: Vec<f64> = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .filter_map(|l| l.split(',').next()?.parse().ok())
            .collect();
        t.last().unwrap() - t[0]
    };
    let (train, held) =
        (secs("ep_00.csv") + secs("ep_01.csv") + secs("ep_02.csv"), secs("ep_03.csv"));
    let judge = v["search"]["simulated_s_by_round_phase"]["0"]["judge"].as_f64().unwrap();
    let bound = 5.0 * train + held;
    assert!(judge <= bound, "round 0 judged for {judge} s, above {bound} s");
}

/// The same leg with nothing concealed gives nothing: it moves in continuous time (RK4 at
/// 4 kHz) against a model stepped at 1 ms, and the model's own discretisation (the replay's
/// distance from its continuous-time limit, extrapolated from replays at 1, ½ and ¼ ms) is
/// floor, not physics. (Counted from the ¼ ms replay alone it came out as a 0.81 ms action
/// delay on all three joints.)
#[test]
fn the_own_physics_leg_without_a_payload_gives_nothing() {
    assert_nothing(&fit("KR0_leg_none", &[]));
}

/// `case`'s trunk centre-of-mass shift comes out as one `com_offset` on the hip (the trunk is
/// its child body), both components within 10 % of the shift, nothing left unexplained.
fn assert_trunk_shift_found(case: &str) {
    let truth = truth(case);
    own_physics(&truth);
    let trunk = TruthBody::of(&truth, "trunk");
    let (along, across) = trunk.com_shift();
    let v = fit(case, &[]);
    assert_eq!(found(&v), [("com_offset".into(), r#"["hip_pitch"]"#.into())], "{:?}", found(&v));
    let p = &v["missing_physics"][0]["params"];
    let (a, c) = (p["along"].as_f64().unwrap(), p["across"].as_f64().unwrap());
    let tol = 0.1 * along.hypot(across);
    assert!(
        (a - along).abs() <= tol && (c - across).abs() <= tol,
        "({a}, {c}) for ({along}, {across})"
    );
    assert_eq!(v["unexplained"].as_array().map(Vec::len), Some(0), "{}", v["unexplained"]);
}

/// The trunk's centre of mass 4 cm forward and 3 cm down, on a leg standing on its foot: the
/// legs carry the trunk, so the shift loads every joint and is found on the trunk's joint.
#[test]
fn a_trunk_centre_of_mass_moved_is_found_when_the_leg_carries_the_trunk() {
    assert_trunk_shift_found("KSR1_trunk_com_shift");
}

/// The same shift on the longer stance log (6 × 5 s), found blind. On an upright trunk a shift
/// along the link changes only gravity's stiffness and one across it tilts the load: ranked by
/// its `along` column alone the hip's com_offset came fifth in the screen, out of the round's
/// four candidates, and the search explained the trunk with a gain error on all three joints
/// and a com_offset on the knee. Ranked by the best combination of its two columns it is first.
#[test]
fn a_trunk_centre_of_mass_moved_is_found_blind_on_the_longer_stance() {
    assert_trunk_shift_found("KS1_trunk_com_shift");
}

/// A 1.5 kg battery 8 cm behind the standing leg's trunk and 12 cm above its centre (off the
/// trunk's axis) comes out blind as one `link_mass` on the hip (the trunk is its child body):
/// its mass within 10 %, its place along and across the trunk within 10 % of the trunk's
/// length, and each component of the composite first moment about the hip — all that gravity
/// sees of the body in the joints' plane; across the trunk it is the battery's alone — within
/// 10 %; nothing else, nothing left unexplained. With the point
/// mass on the trunk's axis only (before `across`), the same recordings came out as a link_mass
/// and a com_offset on the hip, two effects for one battery.
#[test]
fn a_battery_off_the_trunks_axis_is_found_blind_as_one_point_mass() {
    let truth = truth("KSR2_trunk_battery");
    own_physics(&truth);
    let trunk = TruthBody::of(&truth, "trunk");
    let v = fit("KSR2_trunk_battery", &[]);
    let listed = assert_payload_found(&v, &trunk, "hip_pitch");
    let (mass, along, across) = trunk.payload_place();
    let m0 = trunk.b["nominal_mass"].as_f64().unwrap();
    let c0 = trunk.com.iter().map(|x| x * x).sum::<f64>().sqrt();
    let p = &listed["params"];
    let (dm, a, c) = (
        p["added_mass"].as_f64().unwrap(),
        p["offset"].as_f64().unwrap(),
        p["across"].as_f64().unwrap(),
    );
    // The composite body's first moment about the joint, along and across the trunk.
    let moment = |m: f64, a: f64, c: f64| (m0 * c0 + m * (c0 + a), m * c);
    let (want, got) = (moment(mass, along, across), moment(dm, a, c));
    assert!(
        (got.0 - want.0).abs() <= 0.1 * want.0.abs()
            && (got.1 - want.1).abs() <= 0.1 * want.1.abs(),
        "first moment {got:?} for {want:?} kg·m"
    );
    assert_eq!(v["unexplained"].as_array().map(Vec::len), Some(0), "{}", v["unexplained"]);
}

/// The shank's moment of inertia about the knee's axis through its centre of mass doubled
/// (mass and centre of mass kept), found blind: `link_inertia` on the knee within 10 % of the
/// truth's scale, and no armature (on the knee alone it would add only the knee's diagonal
/// entry of the mass matrix; the shank's moment also loads the hip). The only other effect the
/// fit may keep is a sub-millisecond action delay on all three joints, the discretisation
/// stand-in of the other chainsim cases.
#[test]
fn a_doubled_shank_inertia_is_found_blind_on_the_knee() {
    let truth = truth("KR11_shank_inertia");
    own_physics(&truth);
    let scale = truth["resolved"]["_bodies"]["shank"]["inertia_scale"][1].as_f64().unwrap();
    let v = fit("KR11_shank_inertia", &[]);
    let listed = v["missing_physics"].as_array().unwrap();
    let inertia: Vec<_> = listed.iter().filter(|m| m["effect"] == "link_inertia").collect();
    assert_eq!(inertia.len(), 1, "{:?}", found(&v));
    assert_eq!(inertia[0]["joints"].to_string(), r#"["knee"]"#);
    let s = inertia[0]["params"]["inertia_scale"].as_f64().unwrap();
    assert!((s - scale).abs() <= 0.1 * scale, "inertia scale {s} for {scale}");
    for m in listed.iter().filter(|m| m["effect"] != "link_inertia") {
        let d = m["params"]["delay_s"].as_f64();
        assert!(m["effect"] == "action_delay" && d.is_some_and(|d| d < 1e-3), "{:?}", found(&v));
    }
}

#[test]
fn the_standing_leg_without_a_shift_gives_nothing() {
    own_physics(&truth("KSR0_stance_none"));
    assert_nothing(&fit("KSR0_stance_none", &[]));
}

/// Stribeck friction on the light pendulum servo (static 0.06, sliding 0.03 N·m, v_s 0.2 rad/s;
/// the simulator's sign is tanh(q̇/0.005), RK4 at 4 kHz) comes out blind as Stribeck friction
/// on the servo alone, its static and sliding levels within 10 %. Fails with a replay friction
/// smoothed by a fixed tanh(q̇/0.02) (static +13 %, v_s −31 %); with exact stiction static and
/// sliding are +4 % and +3 %. v_s is not asserted here: at the model's 1 ms step it comes out
/// 21 % low (0.158, standard error 0.028), the step's own (see the next test).
#[test]
fn a_stribeck_curve_on_a_light_servo_is_found_with_its_levels() {
    let truth = truth("KR2_pend_stribeck");
    own_physics(&truth);
    let s = &truth["effects"]["joints"]["servo"]["stribeck"];
    let v = fit("KR2_pend_stribeck", &[]);
    assert_eq!(found(&v), [("stribeck_friction".into(), r#"["servo"]"#.into())], "{:?}", found(&v));
    let p = &v["missing_physics"][0]["params"];
    for key in ["static", "dynamic"] {
        let (got, want) = (p[key].as_f64().unwrap(), s[key].as_f64().unwrap());
        assert!((got - want).abs() <= 0.1 * want, "{key} {got} for {want}");
    }
}

/// The Stribeck curve's velocity scale comes out low because of the model's 1 ms step, not the
/// friction model: MuJoCo's semi-implicit Euler leads continuous time by half a step. Told on
/// KR2 with the nominal model's timestep set to 0.25 ms, v_s is within 10 % of the truth (0.188;
/// 0.176 at 0.5 ms, 0.158 at 1 ms: linear in the step, 0.200 extrapolated) and the static and
/// sliding levels within 2 %. Fails if the exact-stiction hook's curve is wrong, or if the bias
/// has another cause that a finer step does not remove.
#[test]
fn the_stribeck_velocity_comes_out_right_at_a_finer_model_step() {
    let truth = truth("KR2_pend_stribeck");
    own_physics(&truth);
    let s = &truth["effects"]["joints"]["servo"]["stribeck"];
    let d = common::indep::case("KR2_pend_stribeck");
    let xml = std::fs::read_to_string(d.join("nominal.xml")).unwrap();
    let fine = xml.replace("timestep=\"0.001\"", "timestep=\"0.00025\"");
    assert_ne!(fine, xml, "the nominal model states its 1 ms timestep");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("kr2_fine_step");
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("nominal.xml");
    std::fs::write(&model, fine).unwrap();
    let v =
        common::indep::fit_at(&model, &d.join("episodes"), &["--told", "stribeck_friction@servo"]);
    let p = &v["missing_physics"][0]["params"];
    for (key, tol) in [("static", 0.02), ("dynamic", 0.02), ("v_stribeck", 0.1)] {
        let (got, want) = (p[key].as_f64().unwrap(), s[key].as_f64().unwrap());
        assert!((got - want).abs() <= tol * want, "{key} {got} for {want}");
    }
}
