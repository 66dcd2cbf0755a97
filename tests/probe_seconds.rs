//! `SearchPolicy::probe_seconds`: the linearised screen's probes replay only the stretches of
//! the screen's data where its residual is largest. Recordings from modellint's own recording
//! loop (`src/synth/`: its MuJoCo loop, controller and recorder) of Asimov's legs hung on a
//! stand with a viscous damping of 3 N·m·s hidden on both knees; the model without it is fitted
//! blind (every effect, one round) with the probes on the default stretches and on the whole
//! screen's data (`probe_seconds` = `screen_seconds`, the probes as they were). With the
//! shorter probes the same candidate must rank first, both knees' damping rank high, the same
//! lead be fitted first with the same predicted step, and the same effect be found, for fewer
//! replayed seconds.

mod common;

use common::{hidden, load, root, synth_recordings};
use modellint::fit::select::{FitOptions, FitOutcome, Phase, SearchPolicy, fit};
use modellint::synth::Settings;

fn run(probe_seconds: f64) -> FitOutcome {
    let robot = load(&root().join("models/asimov.xml"));
    let joints: Vec<String> = robot
        .joints
        .iter()
        .filter(|j| j.name.contains("hip") || j.name.contains("knee") || j.name.contains("ankle"))
        .map(|j| j.name.clone())
        .collect();
    assert_eq!(joints.len(), 12, "Asimov's leg joints: {joints:?}");
    let s = Settings {
        episodes: 4,
        duration_s: 6.0,
        amplitude: 0.15,
        suspend_m: 0.5,
        heldout: 1,
        seed: 7,
        ..Settings::default()
    };
    let recs = synth_recordings(
        &format!("probe_seconds_{probe_seconds}"),
        &robot,
        &joints,
        &[
            hidden("viscous_damping", "left_knee", &[3.0]),
            hidden("viscous_damping", "right_knee", &[3.0]),
        ],
        &s,
    );
    let opts = FitOptions {
        policy: SearchPolicy { max_rounds: 1, probe_seconds, ..Default::default() },
        ..Default::default()
    };
    fit(&robot, &recs, &opts)
}

#[test]
fn short_probes_rank_and_find_as_the_whole_screen_does_for_fewer_replayed_seconds() {
    let full_s = SearchPolicy::default().screen_seconds;
    let short_s = SearchPolicy::default().probe_seconds;
    assert!(short_s < full_s, "the default probes are shorter than the screen's data");
    let (short, full) = (run(short_s), run(full_s));
    let top = |o: &FitOutcome| -> Vec<(String, String)> {
        let n = SearchPolicy::default().candidates_per_round;
        o.diagnosis.iter().take(n).map(|c| (c.effect.to_string(), c.joint.clone())).collect()
    };
    eprintln!("short: {:?}\nfull:  {:?}", top(&short), top(&full));
    assert_eq!(top(&short)[0], top(&full)[0], "the round's top candidate");
    // Both knees' damping rank high (within the window a mirror partner must rank in).
    let window = SearchPolicy::default().rank_window();
    for o in [&short, &full] {
        for knee in ["left_knee", "right_knee"] {
            let at =
                o.diagnosis.iter().position(|c| c.effect == "viscous_damping" && c.joint == knee);
            assert!(at.is_some_and(|i| i < window), "{knee} ranks {at:?}");
        }
    }
    // The same effect found, with the same value.
    for o in [&short, &full] {
        let s = o.selected.first().expect("something selected");
        assert_eq!(s.effect, "viscous_damping");
        assert_eq!(s.joints, ["left_knee", "right_knee"]);
        assert!((s.values[0] / 3.0 - 1.0).abs() < 0.02, "damping {:?}", s.values);
    }
    assert!((short.selected[0].values[0] / full.selected[0].values[0] - 1.0).abs() < 1e-3);
    // The first candidate fitted in full (the lead) and its predicted linear step.
    let lead = |o: &FitOutcome| {
        let t = o.tried.iter().find(|t| t.phase == Phase::Add).expect("a full fit");
        (t.effect.clone(), t.joints.clone(), t.predicted.map(|p| p.step))
    };
    let (ls, lf) = (lead(&short), lead(&full));
    eprintln!("lead short {ls:?}, full {lf:?}");
    assert_eq!((&ls.0, &ls.1), (&lf.0, &lf.1));
    let (ss, sf) = (ls.2.expect("predicted"), lf.2.expect("predicted"));
    assert!((ss / sf - 1.0).abs() < 0.1, "predicted step {ss} against {sf}");
    // The probes' replayed seconds.
    let diag = |o: &FitOutcome| o.cost.simulated_s_by_phase.get("diagnose").copied().unwrap_or(0.0);
    eprintln!("diagnose replayed: short {} s, full {} s", diag(&short), diag(&full));
    assert!(diag(&short) < 0.6 * diag(&full), "{} against {}", diag(&short), diag(&full));
}
