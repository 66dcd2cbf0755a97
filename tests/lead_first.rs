//! `SearchPolicy::lead_first`: the candidate the linearised screen predicts best (of any size,
//! charged for its parameters) is fitted and judged before the others are coarse-fitted; when it
//! leaves a white residual on every joint, only other effects on exactly its joints are still
//! screened. Recordings from modellint's own recording loop (`src/synth/`: its MuJoCo loop,
//! controller and recorder) of the three-joint arm with a viscous damping of 0.4 N·m·s hidden on
//! the elbow, and from a simulator outside modellint (`../shared/data/recordings/
//! independent_arm2`, a servo gain error on the elbow: two parameters); the model without it is
//! fitted blind (every effect). The tests check the search's bookkeeping (which candidates get a
//! fit), and that the truth is found.

mod common;

use common::{hidden, load, root, synth_recordings};
use modellint::fit::effects;
use modellint::fit::select::{FitOptions, FitOutcome, Phase, SearchPolicy, fit};
use modellint::sim2real::recording::read_csv;
use modellint::synth::Settings;

const JOINTS: [&str; 3] = ["shoulder_pitch", "elbow_pitch", "wrist_pitch"];

fn run(lead_first: bool) -> FitOutcome {
    let robot = load(&root().join("fixtures/gap/arm3.xml"));
    let joints: Vec<String> = JOINTS.iter().map(|s| s.to_string()).collect();
    let s =
        Settings { episodes: 8, duration_s: 4.0, amplitude: 0.5, seed: 7, ..Settings::default() };
    let recs = synth_recordings(
        "lead_first_damping",
        &robot,
        &joints,
        &[hidden("viscous_damping", "elbow_pitch", &[0.4])],
        &s,
    );
    let opts = FitOptions {
        policy: SearchPolicy { max_rounds: 1, lead_first, ..Default::default() },
        ..Default::default()
    };
    fit(&robot, &recs, &opts)
}

/// The truth is found either way; with the policy on, no one-parameter candidate on another
/// joint group is coarse-fitted after the lead left a white residual (they are logged as
/// "floor", without parameters), while with it off such candidates are screened.
#[test]
fn a_lead_at_the_floor_leaves_only_its_aliases_to_screen() {
    for on in [true, false] {
        let out = run(on);
        for t in &out.tried {
            eprintln!(
                "  lead_first {on}: {:?} {} {:?} {:?}",
                t.phase, t.effect, t.joints, t.params
            );
        }
        let first = out.selected.first().expect("something selected");
        assert_eq!(
            (first.effect.as_str(), &first.joints[..]),
            ("viscous_damping", &["elbow_pitch".to_string()][..])
        );
        assert!((first.values[0] / 0.4 - 1.0).abs() < 0.05, "damping {:?}", first.values);
        let round0: Vec<_> = out.tried.iter().filter(|t| t.round == 0).collect();
        let one_param = |e: &str| effects::by_id(e).is_some_and(|e| e.fitted() == 1);
        // One-parameter candidates on another group than the winner's that got a fit (coarse
        // or full) in round 0.
        let elsewhere_fitted = round0
            .iter()
            .filter(|t| one_param(&t.effect) && t.joints != first.joints && !t.params.is_empty())
            .count();
        let elsewhere_floor = round0
            .iter()
            .filter(|t| one_param(&t.effect) && t.joints != first.joints && t.phase == Phase::Floor)
            .count();
        if on {
            assert_eq!(round0.first().map(|t| (t.kept, t.phase)), Some((true, Phase::Add)));
            assert_eq!(elsewhere_fitted, 0, "screened away from the lead's joints");
            assert!(elsewhere_floor > 0, "nothing left at the floor");
        } else {
            assert!(elsewhere_fitted > 0, "the policy off screens every candidate");
        }
    }
}

/// A lead of two parameters: on the independent arm's elbow with a servo gain error (kp × 0.7,
/// kd × 1.3), the gain error's linear step leaves the least of the residual, also charged for
/// its second parameter. It is fitted and judged first and leaves a white residual, so no
/// candidate on another joint group gets a fit. (With one-parameter leads only, the elbow's
/// damping led, and every candidate of both sizes on both groups was coarse-fitted before the
/// gain error.) Skips visibly when ../shared is absent.
#[test]
fn a_two_parameter_lead_at_the_floor_leaves_only_its_aliases_to_screen() {
    let d = root().join("../shared/data/recordings/independent_arm2/arm2.elbow.gain_error");
    if !d.join("nominal.xml").is_file() {
        eprintln!("skipping: {} is absent", d.display());
        return;
    }
    let robot = load(&d.join("nominal.xml"));
    let recs: Vec<_> = (0..4)
        .map(|i| read_csv(&d.join(format!("episodes/ep_{i:02}.csv"))).expect("csv"))
        .collect();
    let opts = FitOptions {
        policy: SearchPolicy { max_rounds: 1, ..Default::default() },
        ..Default::default()
    };
    let out = fit(&robot, &recs, &opts);
    for t in &out.tried {
        eprintln!("  {:?} {} {:?} {:?}", t.phase, t.effect, t.joints, t.params);
    }
    let first = out.selected.first().expect("something selected");
    assert_eq!(
        (first.effect.as_str(), &first.joints[..]),
        ("gain_error", &["elbow".to_string()][..])
    );
    let (kp, kd) = (first.params["kp_scale"], first.params["kd_scale"]);
    assert!((kp / 0.7 - 1.0).abs() < 0.05 && (kd / 1.3 - 1.0).abs() < 0.05, "kp {kp}, kd {kd}");
    let round0: Vec<_> = out.tried.iter().filter(|t| t.round == 0).collect();
    let lead = round0.first().expect("round 0 tried something");
    assert_eq!((lead.effect.as_str(), lead.kept, lead.phase), ("gain_error", true, Phase::Add));
    let elsewhere_fitted =
        round0.iter().filter(|t| t.joints != first.joints && !t.params.is_empty()).count();
    let elsewhere_floor =
        round0.iter().filter(|t| t.joints != first.joints && t.phase == Phase::Floor).count();
    assert_eq!(elsewhere_fitted, 0, "screened away from the lead's joints");
    assert!(elsewhere_floor > 0, "nothing left at the floor");
}
