//! A point judged to replay as the base does so to the last bit, and a fit does not replay it.

use super::AtBase;
use crate::fit::effects::{
    ActionDelay, Applied, Effect, GainError, JointTarget, TorqueLimit, hinge_recording,
    hinge_robot, model_with, simulate,
};
use crate::fit::select::{Engine, FitOptions};
use crate::model::Robot;
use crate::sim2real::recording::Recording;

/// A servo (kp 50, kv 2; `force`: its gear and force range) stepped by 0.1 rad and back: its
/// force peaks inside the torque limit's range (0.05–50 N·m), under the integrator `option`.
fn case(name: &str, option: &str, force: &str) -> (Robot, Vec<Recording>) {
    let dir = std::env::temp_dir().join(format!("modellint-atbase-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let robot = hinge_robot(&dir, name, option, "", &format!(r#"kp="50" kv="2" {force}"#));
    let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.005).collect();
    let cmd: Vec<f64> = t
        .iter()
        .map(|&t| {
            if t < 0.1 {
                0.0
            } else if t < 0.5 {
                0.1
            } else {
                -0.05
            }
        })
        .collect();
    (robot, vec![hinge_recording(t, cmd)])
}

/// `start` with its first parameter at `v`.
fn at(start: &[f64], v: f64) -> Vec<f64> {
    let mut p = start.to_vec();
    p[0] = v;
    p
}

/// Torque limits from 0.05 to 50 N·m: every one judged to replay as the base replays, replayed
/// anyway, gives the base's trajectory bit for bit, and every limit at or below the servo's peak
/// force (taken from a replay of its own) is replayed; limits above the peak are judged so.
/// Nothing is judged before the base replay of the data was counted, with a hook of the base
/// on the joint, when two parameters move, or for an effect without a judgement beyond its
/// neutral start (a gain error).
#[test]
fn a_point_judged_to_replay_as_the_base_does_so_to_the_last_bit() {
    let g = vec!["j".to_string()];
    for (name, option, force) in [
        ("euler.xml", "", ""),
        (
            "implicit.xml",
            r#"integrator="implicitfast""#,
            r#"gear="2" forcelimited="true" forcerange="-30 30""#,
        ),
    ] {
        let (robot, recs) = case(name, option, force);
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let m0 = model_with(&robot, &[]);
        let t = JointTarget::of(&robot, "j").unwrap();
        let start = TorqueLimit.initial(&m0, &t);
        let before = AtBase::new(&engine, &recs, &[], (&TorqueLimit, &g), &m0);
        assert!(!before.replays_base(&at(&start, 49.0)), "{name}: no base replay counted yet");
        let _ = engine.errors(&recs, &[]).expect("base replay");
        let judge = AtBase::new(&engine, &recs, &[], (&TorqueLimit, &g), &m0);
        let base = simulate(&robot, &recs, &[], &opts.replay).remove(0).unwrap();
        let peak = base.peaks.servo[0];
        assert!(peak > 2.0 && peak < 40.0, "{name}: peak {peak}");
        let mut judged = 0;
        for i in 0..=24 {
            let v = 0.05 * 1000f64.powf(i as f64 / 24.0);
            let p = at(&start, v);
            let same = judge.replays_base(&p);
            assert_eq!(judge.set(&[], &g, p.clone()).is_empty(), same);
            let limit = Applied { effect: &TorqueLimit, joints: g.clone(), params: p };
            let ep = simulate(&robot, &recs, &[limit], &opts.replay).remove(0).unwrap();
            if same {
                assert!(ep.q_sim == base.q_sim, "{name}: limit {v} judged, replay differs");
                judged += 1;
            }
            assert!(v > peak || !same, "{name}: limit {v} at or below the peak {peak} judged");
        }
        assert!((3..25).contains(&judged), "{name}: {judged} of 25 judged");
        // Two parameters moved: not judged.
        let mut two = at(&start, 49.0);
        two[1] *= 0.5;
        assert!(!judge.replays_base(&two), "{name}: two parameters moved");
        // A hook of the base on the joint: its servo torque is not MuJoCo's actuator force.
        let hooked = vec![Applied { effect: &ActionDelay, joints: g.clone(), params: vec![0.01] }];
        let _ = engine.errors(&recs, &hooked).expect("hooked base replay");
        let m1 = model_with(&robot, &hooked);
        let under = AtBase::new(&engine, &recs, &hooked, (&TorqueLimit, &g), &m1);
        assert!(!under.replays_base(&at(&start, 49.0)), "{name}: hooked base");
        // A gain error: its neutral start only.
        let gain = AtBase::new(&engine, &recs, &[], (&GainError, &g), &m0);
        let g0 = GainError.initial(&m0, &t);
        assert!(gain.replays_base(&g0) && !gain.replays_base(&at(&g0, 1.1)), "{name}: {g0:?}");
    }
}

/// A torque limit's line search on ln(effort) replays only its grid points at or below the
/// servo's peak force, and ends where a replay of every grid point (on an engine of its own,
/// each scored as a set of its own) puts the grid's first minimum: the same point and RMSE, bit
/// for bit.
#[test]
fn a_line_search_replays_no_point_that_replays_as_the_base() {
    let (robot, recs) = case("line.xml", "", "");
    let g = vec!["j".to_string()];
    let opts = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &opts);
    let _ = engine.errors(&recs, &[]).expect("base replay");
    let before = engine.simulations();
    let n = 6;
    let (p, f) = engine.fit_budget(&recs, &[], &TorqueLimit, &g, n);
    let replayed = engine.simulations() - before;
    let m0 = model_with(&robot, &[]);
    let t = JointTarget::of(&robot, "j").unwrap();
    let (start, (lo, hi)) = (TorqueLimit.initial(&m0, &t), TorqueLimit.bounds(&m0, &t));
    let (a, c) = (lo[0].ln(), hi[0].ln());
    let grid: Vec<f64> = (0..n)
        .map(|i| (a + (c - a) * i as f64 / (n - 1) as f64).exp().clamp(lo[0], hi[0]))
        .collect();
    let other = Engine::new(&robot, &recs, &opts);
    let scores: Vec<f64> = grid
        .iter()
        .map(|&v| {
            let limit = Applied { effect: &TorqueLimit, joints: g.clone(), params: at(&start, v) };
            other.score(&recs, &[limit])
        })
        .collect();
    let best = (0..n).fold(0, |b, i| if scores[i] < scores[b] { i } else { b });
    assert_eq!((p[0], f), (grid[best], scores[best]), "grid {grid:?}: {scores:?}");
    let peak = simulate(&robot, &recs, &[], &opts.replay).remove(0).unwrap().peaks.servo[0];
    let below = grid.iter().filter(|&&v| v <= peak).count();
    assert!(below < n, "every grid point below the peak {peak}: {grid:?}");
    assert_eq!(replayed, below, "peak {peak}, grid {grid:?}");
}
