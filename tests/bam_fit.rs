//! Servo identification with the general fit engine (no servo-specific mode): a synthetic
//! recovery of external-load friction held out by a metadata key (no data needed), and the
//! leave-one-gain-out experiment on the 16 real BAM XL330 logs from the CLI (skipped with a
//! visible message when ../shared/data is absent): `make test` runs the kp-200 fold, the kp-400
//! fold is `#[ignore]`d as long (`bench/long_tests.sh`), `bench/bam.sh` runs the whole rotation.

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

/// One fold of the leave-one-gain-out run whose average over all 16 logs README and
/// docs/examples/bam-xl330.md report: the firmware gain `kp` held out (4 logs), the other 12
/// fitted by the ordinary `fit` from the CLI. Checks that the fold keeps friction that grows
/// with the gravity load (BAM's M2/M3 finding) and its held-out whole-log position MAE, mean
/// over the 4 logs: nominal `before` [°] (a fact of the data) and fitted at most 5 % above
/// `after` [°]. One fold keeps a test at 1–4 min CPU; `bench/bam.sh` runs the whole rotation.
fn bam_fold(kp: &str, before_deg: f64, after_deg: f64) {
    let name = format!("bam_fold_kp{kp}");
    let Some(dir) = shared_bam() else {
        eprintln!(
            "SKIPPED {name}: ../shared/data/recordings/bam_xl330 is absent (set \
             MODELLINT_SHARED_DATA)"
        );
        return;
    };
    let t0 = std::time::Instant::now();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg("fit")
        .arg(root().join("fixtures/bam_xl330/rig.xml"))
        .arg(&dir)
        .args(["--holdout-by", &format!("kp={kp}"), "--format", "json", "--quiet"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["split"]["heldout"], 4, "{}", v["split"]["note"]);
    assert_eq!(v["split"]["train"], 12, "{}", v["split"]["note"]);
    // Mean over the held-out logs of each log's whole-log MAE (how the docs average).
    let per_log = |k: &str| -> f64 {
        let eps = v[k]["per_episode"].as_array().expect("per_episode");
        assert_eq!(eps.len(), 4);
        eps.iter().map(|e| e["position_mae"].as_f64().expect("mae").to_degrees()).sum::<f64>()
            / eps.len() as f64
    };
    let (before, after) = (per_log("before"), per_log("after"));
    let kept: Vec<&str> = v["missing_physics"]
        .as_array()
        .expect("missing_physics")
        .iter()
        .map(|m| m["effect"].as_str().expect("id"))
        .collect();
    eprintln!(
        "kp {kp} held out: {before:.2}° → {after:.2}° with {kept:?} in {:.0} s",
        t0.elapsed().as_secs_f64()
    );
    assert!(kept.contains(&"external_load_friction"), "kept {kept:?}");
    assert!((before - before_deg).abs() < 0.2, "nominal {before:.2}°");
    assert!(after <= after_deg * 1.05, "held-out {after:.2}° vs {after_deg}°");
}

/// Long (ten times the kp-200 fold: the longest test of the suite): the kp-200 fold below keeps
/// the class (one held-out gain from the CLI, load friction kept, held-out MAE) in `make test`.
#[test]
#[ignore = "long (minutes on two cores): bench/long_tests.sh runs it"]
fn bam_logs_one_gain_held_out_from_the_cli() {
    bam_fold("400", 11.49, 2.55);
}

/// The fold whose screen stretch misleads: fitted on the stretch of largest residual alone,
/// the load friction runs to its bound and leaves the whole training set worse than without
/// it; its coarse fit on the whole training set starts the fold's answer (0.51).
#[test]
fn bam_logs_gain_200_held_out_keeps_the_load_friction() {
    bam_fold("200", 9.78, 2.64);
}

/// A `--holdout-by` value no log has is the user's error, said before any work: an error (not a
/// warning followed by a search report), exit 2, listing the values there are.
#[test]
fn a_holdout_value_no_log_has_is_an_error() {
    let Some(dir) = shared_bam() else {
        eprintln!("SKIPPED a_holdout_value_no_log_has_is_an_error: bam_xl330 is absent");
        return;
    };
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg("fit")
        .arg(root().join("fixtures/bam_xl330/rig.xml"))
        .arg(&dir)
        .args(["--holdout-by", "kp=300"])
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("no recording has kp = 300") && err.contains("400"), "{err}");
    assert!(!err.contains("warning") && !err.contains("search cost"), "{err}");
}
