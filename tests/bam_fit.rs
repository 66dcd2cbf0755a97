//! Servo identification: a synthetic recovery test (no data needed) and a reduced held-out fold
//! on the 16 real BAM XL330 logs (skipped with a message when ../shared/data is absent).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use modellint::fit::servo::{Effect, EffectSet, ServoParams, simulate};
use modellint::fit::servo_fit::{self, FitOpts, Optimiser, ServoLog};
use modellint::model::{Robot, source::SourceMap};
use modellint::sim2real::recording::{JointTrace, Recording};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn rig() -> Robot {
    let mut map = SourceMap::default();
    modellint::model::load(&mut map, &root().join("fixtures/bam_xl330/rig.xml"), None)
        .expect("rig loads")
}

/// `$MODELLINT_SHARED_DATA`, else the first `shared/data` beside the crate or an ancestor.
fn shared_bam() -> Option<PathBuf> {
    let d = match std::env::var_os("MODELLINT_SHARED_DATA") {
        Some(d) => PathBuf::from(d),
        None => root()
            .ancestors()
            .skip(1)
            .take(3)
            .map(|a| a.join("shared/data"))
            .find(|d| d.is_dir())?,
    };
    let d = d.join("recordings/bam_xl330");
    d.is_dir().then_some(d)
}

/// A synthetic log: goal steps and sweeps, ~200 Hz irregular timestamps, with `q` simulated
/// by the servo model `truth`.
fn synthetic_log(
    robot: &Robot,
    kp: f64,
    truth_of: impl Fn(ServoParams) -> ServoParams,
    seed: f64,
) -> ServoLog {
    let n = 1000;
    let t: Vec<f64> = (0..n)
        .map(|i| i as f64 * 0.005 + 0.001 * ((i as f64 * 1.3 + seed).sin()).powi(2))
        .collect();
    let goal: Vec<f64> = t
        .iter()
        .map(|&x| {
            let step = if (x * 0.8 + seed * 0.1).fract() < 0.5 { 0.6 } else { -0.4 };
            if x < 2.5 { step } else { 1.2 * (1.5 * x * x * 0.3 + seed).sin() }
        })
        .collect();
    let mut j = JointTrace::new("servo", vec![0.0; n]);
    j.q_cmd = Some(goal);
    j.qd = Some(vec![0.0; n]);
    let mut meta = BTreeMap::new();
    for (k, v) in [("kp", kp), ("vin", 7.4), ("mass", 0.49), ("length", 0.1)] {
        meta.insert(k.to_string(), v.to_string());
    }
    meta.insert("trajectory".into(), "synthetic".into());
    let mut rec = Recording {
        source: "synthetic.json".into(),
        meta,
        control_rate_hz: Some(1000.0),
        control_t0_s: None,
        t,
        joints: vec![j],
        base: None,
    };
    let base = ServoParams::for_recording(&rec).unwrap();
    let ep = simulate(robot, &rec, &truth_of(base)).unwrap();
    assert!(ep.diverged.is_none());
    rec.joints[0].q = ep.q_sim[0].clone();
    rec.joints[0].qd = Some(ep.qd_sim[0].clone());
    ServoLog { name: format!("synthetic_{kp}"), kp, trajectory: "synthetic".into(), rec, base }
}

#[test]
fn synthetic_coulomb_and_armature_are_recovered() {
    let robot = rig();
    let (fc, arm) = (0.045, 0.0062);
    let truth = |mut p: ServoParams| {
        p.coulomb = fc;
        p.armature = arm;
        p
    };
    let logs: Vec<ServoLog> = [(200.0, 0.0), (800.0, 1.0)]
        .iter()
        .map(|&(kp, s)| synthetic_log(&robot, kp, truth, s))
        .collect();
    let set = EffectSet(vec![Effect::Armature, Effect::Coulomb]);
    let o = FitOpts {
        optimiser: Optimiser::NelderMead,
        max_evals: 200,
        candidates: vec![],
        seed: 1,
        polish_evals: 0,
    };
    let x0: Vec<f64> = set.specs().iter().map(|s| s.init).collect();
    let idx = [0usize, 1];
    let (x, f, evals) = servo_fit::fit_set(&robot, &logs, &idx, &set, &x0, &o);
    eprintln!(
        "recovered armature {:.5} (true {arm}), Fc {:.4} (true {fc}); MAE {:.4}°, {evals} evals",
        x[0],
        x[1],
        f.to_degrees()
    );
    assert!((x[0] - arm).abs() < 0.1 * arm, "armature {} vs {arm}", x[0]);
    assert!((x[1] - fc).abs() < 0.1 * fc, "Fc {} vs {fc}", x[1]);
}

fn load(dir: &Path) -> Vec<ServoLog> {
    servo_fit::load_logs(dir).expect("logs load")
}

#[test]
fn bam_held_out_fold_beats_nominal() {
    let Some(dir) = shared_bam() else {
        eprintln!(
            "SKIPPED bam_held_out_fold_beats_nominal: ../shared/data/recordings/bam_xl330 is absent"
        );
        return;
    };
    let robot = rig();
    let logs = load(&dir);
    assert_eq!(logs.len(), 16);
    // Hold out kp 400 (an interpolation fold); a reduced candidate list and budget.
    let (train, test) = servo_fit::split_by_kp(&logs, 400.0);
    let o = FitOpts {
        optimiser: Optimiser::NelderMead,
        max_evals: 40,
        candidates: vec![Effect::Coulomb, Effect::Armature, Effect::LoadMotor],
        seed: 3,
        polish_evals: 0,
    };
    let f = servo_fit::forward_select(&robot, &logs, &train, &test, &o, &|s| eprintln!("{s}"));
    let (nom, fit) = (f.nominal.test_mae.to_degrees(), f.chosen.test_mae.to_degrees());
    eprintln!(
        "held-out kp 400: nominal {nom:.2}°, fitted {fit:.2}° with {:?} in {:.0} s",
        f.chosen.effects, f.seconds
    );
    assert!(fit < 0.8 * nom, "fitted {fit:.2}° vs nominal {nom:.2}°");
    assert!(f.chosen.effects.iter().any(|e| e.is_friction()), "{:?}", f.chosen.effects);
}
