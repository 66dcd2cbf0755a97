//! Servo identification with the general fit engine (no servo-specific mode): a synthetic
//! recovery of external-load friction held out by a metadata key (no data needed), and the
//! leave-one-gain-out experiment on the 16 real BAM XL330 logs from the CLI (skipped with a
//! visible message when ../shared/data is absent; ~37 min wall on 2 cores shared with other
//! builds, 21 min CPU).

use std::collections::BTreeMap;
use std::path::PathBuf;

use modellint::fit::effects::{self, Applied};
use modellint::fit::select::{FitOptions, fit};
use modellint::model::{Robot, source::SourceMap};
use modellint::sim2real::bam::xl330_kp_si;
use modellint::sim2real::recording::{JointTrace, Recording};
use modellint::sim2real::replay::ReplayOptions;

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

/// A synthetic servo log: goal steps then a sweep, ~200 Hz irregular timestamps, torque off for
/// the last second; `q` is left at 0 (simulated later).
fn synthetic_log(kp: f64, seed: f64) -> Recording {
    let n = 1000;
    let t: Vec<f64> = (0..n)
        .map(|i| i as f64 * 0.005 + 0.001 * ((i as f64 * 1.3 + seed).sin()).powi(2))
        .collect();
    let goal: Vec<f64> = t
        .iter()
        .map(|&x| {
            let step = if (x * 0.8 + seed * 0.1).fract() < 0.5 { 1.2 } else { -0.9 };
            if x < 2.5 { step } else { 1.2 * (1.5 * x * x * 0.3 + seed).sin() }
        })
        .collect();
    let mut j = JointTrace::new("servo", vec![0.0; n]);
    j.q_cmd = Some(goal);
    j.qd = Some(vec![0.0; n]);
    j.kp = Some(vec![xl330_kp_si(kp, 7.4); n]);
    j.enabled = Some(t.iter().map(|&x| x < 4.0).collect());
    let mut meta = BTreeMap::new();
    meta.insert("kp".to_string(), kp.to_string());
    Recording {
        source: format!("synthetic_{kp}_{seed}.json").into(),
        meta,
        control_rate_hz: None,
        control_t0_s: None,
        t,
        joints: vec![j],
        base: None,
    }
}

#[test]
fn synthetic_external_load_friction_is_recovered_on_a_held_out_gain() {
    let robot = rig();
    let mu = 0.4;
    let truth = vec![Applied {
        effect: effects::by_id("external_load_friction").expect("registered"),
        joints: vec!["servo".into()],
        params: vec![mu],
    }];
    let mut recs: Vec<Recording> = [(100.0, 0.0), (200.0, 1.0), (400.0, 2.0), (400.0, 3.0)]
        .iter()
        .map(|&(kp, s)| synthetic_log(kp, s))
        .collect();
    let eps = effects::simulate(&robot, &recs, &truth, &ReplayOptions::default());
    for (r, e) in recs.iter_mut().zip(eps) {
        let e = e.expect("simulates");
        assert!(e.diverged.is_none());
        r.joints[0].q = e.q_sim[0].clone();
        r.joints[0].qd = Some(e.qd_sim[0].clone());
    }
    let opts = FitOptions {
        holdout_by: Some(("kp".into(), "400".into())),
        effects: ["external_load_friction", "coulomb_friction", "torque_off_braking"]
            .map(String::from)
            .to_vec(),
        ..Default::default()
    };
    let out = fit(&robot, &recs, &opts);
    assert_eq!((out.train.len(), out.heldout.len()), (2, 2), "{}", out.split_note);
    let got: Vec<(&str, Vec<f64>)> =
        out.selected.iter().map(|s| (s.effect.as_str(), s.values.clone())).collect();
    eprintln!("selected {got:?}; tried {}", out.tried.len());
    assert_eq!(got.first().map(|g| g.0), Some("external_load_friction"), "{got:?}");
    let v = got[0].1[0];
    assert!((v - mu).abs() < 0.05 * mu, "mu_ext {v} vs {mu}");
}

/// Held-out position MAE of the leave-one-gain-out run, averaged over the 16 logs, as measured
/// and reported in README and docs/examples/bam-xl330.md (the old servo-specific mode gave
/// 3.09°; BAM's own M3 model 3.96°, fitted on all logs, not held out).
const HELD_OUT_DEG: f64 = 2.94;

#[test]
fn bam_logs_leave_one_gain_out_from_the_cli() {
    let Some(dir) = shared_bam() else {
        eprintln!(
            "SKIPPED bam_logs_leave_one_gain_out_from_the_cli: ../shared/data/recordings/bam_xl330 \
             is absent (set MODELLINT_SHARED_DATA)"
        );
        return;
    };
    let t0 = std::time::Instant::now();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg("fit")
        .arg(root().join("fixtures/bam_xl330/rig.xml"))
        .arg(&dir)
        .args(["--holdout-by", "kp", "--format", "json", "--quiet"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let folds = v["folds"].as_array().expect("folds");
    assert_eq!(folds.len(), 4, "one fold per firmware gain");
    assert_eq!(v["episodes"], 16);
    let before = v["position_mae_before"].as_f64().expect("before").to_degrees();
    let after = v["position_mae_after"].as_f64().expect("after").to_degrees();
    for f in folds {
        eprintln!(
            "kp {}: {:.2}° → {:.2}° with {}",
            f["value"],
            f["position_mae_before"].as_f64().unwrap_or(f64::NAN).to_degrees(),
            f["position_mae_after"].as_f64().unwrap_or(f64::NAN).to_degrees(),
            f["selected"]
        );
    }
    eprintln!("held-out MAE {before:.2}° → {after:.2}° in {:.0} s", t0.elapsed().as_secs_f64());
    // The nominal rig, and the fit within 5 % of the figure the docs report (which keeps it at
    // or below the old servo mode's 3.09°).
    assert!((before - 10.36).abs() < 0.2, "nominal {before:.2}°");
    assert!(after <= HELD_OUT_DEG * 1.05, "held-out {after:.2}° vs {HELD_OUT_DEG}°");
}
