//! `modellint fit`: for each effect, recordings generated from the model WITH the effect are
//! fitted with the model WITHOUT it; the effect must be selected first, on the right joint, with
//! its parameters recovered, and the held-out error must drop. A control with nothing missing
//! must select nothing.

use std::path::{Path, PathBuf};

use modellint::fit::effects::{self, Applied};
use modellint::fit::select::{FitOptions, fit};
use modellint::fit::synth::{SynthOptions, generate};
use modellint::model::{Robot, source::SourceMap};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load(path: &Path) -> Robot {
    let mut map = SourceMap::default();
    modellint::model::load(&mut map, path, None).expect("model loads")
}

const JOINTS: [&str; 3] = ["shoulder_pitch", "elbow_pitch", "wrist_pitch"];

/// Fits data generated with `effect(params)` on the elbow; checks selection and recovery
/// (`tol[i]` relative, or absolute when `abs[i]`).
fn check(effect: &str, truth: &[f64], tol: &[(f64, bool)], allowed: &[&str]) {
    let robot = load(&root().join("fixtures/gap/arm3.xml"));
    let e = effects::by_id(effect).unwrap();
    let joints: Vec<String> = JOINTS.iter().map(|s| s.to_string()).collect();
    let hidden =
        vec![Applied { effect: e, joints: vec!["elbow_pitch".into()], params: truth.to_vec() }];
    let recs =
        generate(&robot, &joints, &hidden, 8, &SynthOptions::default(), 7).expect("generate");
    let opts = FitOptions {
        effects: allowed.iter().map(|s| s.to_string()).collect(),
        max_rounds: 1,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let out = fit(&robot, &recs, &opts);
    eprintln!(
        "{effect}: {:.1} s; diagnosis top: {:?}",
        t0.elapsed().as_secs_f64(),
        out.diagnosis
            .iter()
            .take(4)
            .map(|c| (c.effect, c.joint.as_str(), c.explained_rms))
            .collect::<Vec<_>>()
    );
    for t in &out.tried {
        eprintln!("  tried {t:?}");
    }
    let rank = out.diagnosis.iter().position(|c| c.effect == effect && c.joint == "elbow_pitch");
    assert!(rank.is_some_and(|r| r < 3), "{effect}: diagnosis rank {rank:?}");
    let first = out
        .selected
        .first()
        .unwrap_or_else(|| panic!("{effect}: nothing selected; tried {:?}", out.tried));
    assert_eq!(first.effect, effect, "first selected: {first:?}");
    assert_eq!(first.joints, vec!["elbow_pitch".to_string()]);
    for (i, (&t, &(tl, abs))) in truth.iter().zip(tol).enumerate().take(e.fitted()) {
        let got = first.values[i];
        let err = if abs { (got - t).abs() } else { (got - t).abs() / t.abs() };
        eprintln!(
            "  {} truth {t} fitted {got} (error {err:.4}{})",
            e.params()[i].name,
            if abs { " abs" } else { " rel" }
        );
        assert!(err <= tl, "{effect} {}: truth {t}, fitted {got}", e.params()[i].name);
    }
    assert!(first.heldout_improvement > 0.2, "held-out improvement {}", first.heldout_improvement);
}

#[test]
fn action_delay_recovered_within_one_step() {
    check("action_delay", &[0.025], &[(0.001, true)], &[]);
}

#[test]
fn coulomb_friction_recovered() {
    check("coulomb_friction", &[0.15], &[(0.1, false)], &[]);
}

#[test]
fn viscous_damping_recovered() {
    check("viscous_damping", &[0.4], &[(0.1, false)], &[]);
}

#[test]
fn armature_recovered() {
    check("armature", &[0.04], &[(0.1, false)], &[]);
}

#[test]
fn position_offset_recovered() {
    check("position_offset", &[0.05], &[(0.1, false)], &[]);
}

#[test]
fn gain_error_recovered() {
    check("gain_error", &[0.6, 1.0], &[(0.1, false), (0.1, false)], &[]);
}

#[test]
fn stribeck_friction_recovered() {
    check("stribeck_friction", &[0.3, 0.1, 0.2], &[(0.1, false), (0.1, false), (0.1, false)], &[]);
}

#[test]
fn torque_limit_recovered() {
    check("torque_limit", &[1.0, 1e4, 1e4], &[(0.1, false)], &[]);
}

#[test]
fn backlash_recovered() {
    check("backlash", &[0.04], &[(0.1, false)], &[]);
}

#[test]
fn joint_stiffness_recovered() {
    check("joint_stiffness", &[2.0], &[(0.1, false)], &[]);
}

#[test]
fn load_dependent_friction_recovered() {
    check("load_dependent_friction", &[0.05, 0.1], &[(0.1, false), (0.1, false)], &[]);
}

#[test]
fn nothing_missing_selects_nothing() {
    let robot = load(&root().join("fixtures/gap/arm3.xml"));
    let joints: Vec<String> = JOINTS.iter().map(|s| s.to_string()).collect();
    let recs =
        generate(&robot, &joints, &[], 8, &SynthOptions { noise: 5e-4, ..Default::default() }, 11)
            .expect("generate");
    let out = fit(&robot, &recs, &FitOptions { max_rounds: 1, ..Default::default() });
    for t in &out.tried {
        eprintln!("  tried {t:?}");
    }
    assert!(
        out.selected.is_empty(),
        "selected {:?}",
        out.selected.iter().map(|s| (&s.effect, &s.joints)).collect::<Vec<_>>()
    );
}

#[test]
fn cli_json_write_model_and_actuators() {
    let model = root().join("fixtures/gap/arm3.xml");
    let robot = load(&model);
    let joints: Vec<String> = JOINTS.iter().map(|s| s.to_string()).collect();
    let hidden = vec![Applied {
        effect: effects::by_id("armature").unwrap(),
        joints: vec!["wrist_pitch".into()],
        params: vec![0.04],
    }];
    let recs = generate(
        &robot,
        &joints,
        &hidden,
        6,
        &SynthOptions { duration_s: 4.0, ..Default::default() },
        3,
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("modellint_fit_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (i, r) in recs.iter().enumerate() {
        std::fs::write(
            dir.join(format!("ep{i:02}.csv")),
            modellint::sim2real::recording::write_csv(r),
        )
        .unwrap();
    }
    let out_xml = dir.join("fitted.xml");
    let out_toml = dir.join("act.toml");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args([
            "fit",
            model.to_str().unwrap(),
            dir.to_str().unwrap(),
            "--format",
            "json",
            "--effects",
            "armature,viscous_damping,action_delay",
            "--holdout",
            "3",
        ])
        .arg("--write-model")
        .arg(&out_xml)
        .arg("--write-actuators")
        .arg(&out_toml)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mp = v["missing_physics"].as_array().unwrap();
    assert_eq!(mp[0]["effect"], "armature", "{v:#}");
    assert_eq!(mp[0]["joints"][0], "wrist_pitch");
    let a = mp[0]["params"]["armature"].as_f64().unwrap();
    assert!((a - 0.04).abs() < 0.004, "armature {a}");
    assert!(
        v["before"]["position_rmse"].as_f64().unwrap()
            > 2.0 * v["after"]["position_rmse"].as_f64().unwrap()
    );
    for k in ["position_mae", "correlation_mean", "gap_overall", "per_joint"] {
        assert!(v["after"].get(k).is_some(), "after block lacks {k}");
    }
    // The written model: only the wrist joint element changed, and it loads with the new value.
    let orig = std::fs::read_to_string(&model).unwrap();
    let new = std::fs::read_to_string(&out_xml).unwrap();
    let changed: Vec<(&str, &str)> =
        orig.lines().zip(new.lines()).filter(|(a, b)| a != b).collect();
    assert_eq!(changed.len(), 1, "{changed:?}");
    assert!(changed[0].1.contains("<joint name=\"wrist_pitch\" armature=\"0.0"), "{changed:?}");
    let fitted = load(&out_xml);
    assert!((fitted.joint("wrist_pitch").unwrap().armature - a).abs() < 1e-5);
    assert!(std::fs::read_to_string(&out_toml).unwrap().contains("id = \"armature\""));
    // Bad input: exit 2 with a message naming the known effects / the glob.
    let bad = |extra: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
            .args(["fit", model.to_str().unwrap(), dir.to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).to_string())
    };
    let (c, e) = bad(&["--effects", "magic"]);
    assert!(c == Some(2) && e.contains("unknown effect `magic`") && e.contains("armature"), "{e}");
    let (c, e) = bad(&["--joints", "knee*"]);
    assert!(c == Some(2) && e.contains("matches no recorded joint"), "{e}");
    // Text output and HTML reports.
    let rep = dir.join("report");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args([
            "fit",
            model.to_str().unwrap(),
            dir.to_str().unwrap(),
            "--effects",
            "armature",
            "--holdout",
            "3",
            "--report",
        ])
        .arg(&rep)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.starts_with("missing physics\n  armature")
            && text.contains("wrist_pitch")
            && text.contains("gap score"),
        "{text}"
    );
    let page = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(
        page.contains("sim before")
            && page.contains("sim after")
            && page.contains("Missing physics"),
        "one fit page with before and after"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn mjcf_edit_replaces_and_adds_attributes() {
    use modellint::fit::select::Selected;
    let model = root().join("fixtures/gap/arm3.xml");
    let robot = load(&model);
    let xml = std::fs::read_to_string(&model).unwrap();
    let sel = |effect: &str, joint: &str, values: Vec<f64>| Selected {
        effect: effect.into(),
        joints: vec![joint.into()],
        params: Default::default(),
        stderr: Default::default(),
        identifiable: true,
        evidence: Default::default(),
        heldout_improvement: 0.5,
        heldout_rmse_before: 0.0,
        heldout_rmse_after: 0.0,
        window_improvement: 0.0,
        window_improvement_se: 0.0,
        bic_before: 0.0,
        bic_after: 0.0,
        values,
    };
    let s = vec![
        sel("action_delay", "elbow_pitch", vec![0.02]),
        sel("viscous_damping", "elbow_pitch", vec![0.3]),
        sel("coulomb_friction", "elbow_pitch", vec![0.1]),
        sel("torque_limit", "shoulder_pitch", vec![2.0, 1e4, 1e4]),
        sel("gain_error", "wrist_pitch", vec![0.5, 2.0]),
    ];
    let (out, _w) = modellint::fit::writeback::edit_mjcf(&xml, &robot, &s).unwrap();
    assert!(
        out.contains("<joint name=\"elbow_pitch\" damping=\"0.3\" frictionloss=\"0.1\"/>"),
        "{out}"
    );
    assert!(
        out.contains(
            "<position name=\"elbow_pitch\" joint=\"elbow_pitch\" delay=\"0.02\" nsample=\"20\"/>"
        ),
        "{out}"
    );
    assert!(out.contains("<position name=\"shoulder_pitch\" joint=\"shoulder_pitch\" forcelimited=\"true\" forcerange=\"-2 2\"/>"), "{out}");
    assert!(
        out.contains("<position name=\"wrist_pitch\" joint=\"wrist_pitch\" kp=\"25\" kv=\"3\"/>"),
        "{out}"
    );
    // MuJoCo 3.17 accepts the delay syntax and the values.
    let tmp = std::env::temp_dir().join(format!("modellint_fit_edit_{}.xml", std::process::id()));
    std::fs::write(&tmp, &out).unwrap();
    let r2 = load(&tmp);
    let _ = std::fs::remove_file(&tmp);
    let el = r2.actuators.iter().find(|a| a.name == "elbow_pitch").unwrap();
    assert!((el.delay - 0.02).abs() < 1e-12, "delay {}", el.delay);
    assert!((r2.joint("elbow_pitch").unwrap().frictionloss - 0.1).abs() < 1e-12);
    // Everything else byte for byte.
    let strip = |s: &str| {
        s.lines()
            .filter(|l| !l.contains("name=\"elbow_pitch\"") && !l.contains("<position"))
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    assert_eq!(strip(&xml), strip(&out));
}

#[test]
fn synth_then_fit_end_to_end() {
    // `modellint synth` (88 Hz jittered sampling, quantisation, drops) → `modellint fit`.
    let dir = std::env::temp_dir().join(format!("modellint_synth_{}", std::process::id()));
    let model = root().join("fixtures/gap/arm3.xml");
    let bin = env!("CARGO_BIN_EXE_modellint");
    let o = std::process::Command::new(bin)
        .args([
            "synth",
            model.to_str().unwrap(),
            "--effects",
            "position_offset@shoulder*=0.05",
            "--episodes",
            "5",
            "--duration",
            "4",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        std::fs::read_to_string(dir.join("truth.json")).unwrap().contains("\"offset_rad\": 0.05")
    );
    let o = std::process::Command::new(bin)
        .args([
            "fit",
            model.to_str().unwrap(),
            dir.join("episodes").to_str().unwrap(),
            "--format",
            "json",
            "--effects",
            "position_offset,armature,viscous_damping",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mp = &v["missing_physics"][0];
    assert_eq!(mp["effect"], "position_offset", "{v:#}");
    assert_eq!(mp["joints"][0], "shoulder_pitch");
    let off = mp["params"]["offset_rad"].as_f64().unwrap();
    assert!((off - 0.05).abs() < 0.005, "offset {off}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn synth_suspend_holds_the_base_above_the_keyframe() {
    let dir = std::env::temp_dir().join(format!("modellint_synth_suspend_{}", std::process::id()));
    let model = root().join("models/asimov.xml");
    let bin = env!("CARGO_BIN_EXE_modellint");
    let run = |extra: &[&str]| {
        std::process::Command::new(bin)
            .args([
                "synth",
                model.to_str().unwrap(),
                "--effects",
                "armature@*knee*=0.05",
                "--joints",
                "*knee*",
                "--episodes",
                "1",
                "--duration",
                "0.5",
                "--out",
            ])
            .arg(&dir)
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&["--duration=0"]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--duration"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = run(&["--suspend=-1"]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--suspend"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = run(&["--suspend", "0.5"]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_dir(dir.join("episodes"))
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "csv"))
        .unwrap();
    let rec = modellint::sim2real::recording::read_csv(&csv).unwrap();
    let robot = load(&model);
    let free = robot.joints.iter().find(|j| j.jtype == modellint::model::JointType::Free).unwrap();
    let z_key = robot.key.qpos[free.qposadr + 2];
    let b = rec.base.as_ref().expect("base columns");
    assert!(
        b.pos.iter().all(|p| (p[2] - z_key - 0.5).abs() < 1e-9),
        "base z {} vs key {z_key}",
        b.pos[0][2]
    );
    assert!(
        std::fs::read_to_string(dir.join("truth.json")).unwrap().contains("\"suspend_m\": 0.5")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn motor_family_is_fitted_as_one_group() {
    // The same armature error on all three joints of one motor family: the family group (one
    // shared parameter) must win over any single joint.
    let robot = load(&root().join("fixtures/gap/arm3.xml"));
    let joints: Vec<String> = JOINTS.iter().map(|s| s.to_string()).collect();
    let hidden = vec![Applied {
        effect: effects::by_id("armature").unwrap(),
        joints: joints.clone(),
        params: vec![0.03],
    }];
    let recs = generate(
        &robot,
        &joints,
        &hidden,
        8,
        &SynthOptions { duration_s: 4.0, ..Default::default() },
        21,
    )
    .unwrap();
    let families = joints.iter().map(|j| (j.clone(), "m1".to_string())).collect();
    let opts = FitOptions {
        effects: vec!["armature".into(), "viscous_damping".into()],
        max_rounds: 1,
        families,
        ..Default::default()
    };
    let out = fit(&robot, &recs, &opts);
    let first = out.selected.first().expect("selected");
    assert_eq!(first.effect, "armature");
    assert_eq!(first.joints.len(), 3, "{:?}", first.joints);
    assert!((first.values[0] - 0.03).abs() < 0.003, "{:?}", first.values);
}

#[test]
fn multiple_shooting_windows_recover_delay() {
    let robot = load(&root().join("fixtures/gap/arm3.xml"));
    let joints: Vec<String> = JOINTS.iter().map(|s| s.to_string()).collect();
    let hidden = vec![Applied {
        effect: effects::by_id("action_delay").unwrap(),
        joints: vec!["shoulder_pitch".into()],
        params: vec![0.03],
    }];
    let recs = generate(
        &robot,
        &joints,
        &hidden,
        8,
        &SynthOptions { duration_s: 4.0, ..Default::default() },
        5,
    )
    .unwrap();
    let opts = FitOptions {
        effects: vec!["action_delay".into(), "viscous_damping".into()],
        max_rounds: 1,
        shooting_s: Some(1.0),
        ..Default::default()
    };
    let out = fit(&robot, &recs, &opts);
    let first = out.selected.first().expect("selected");
    assert_eq!(
        (first.effect.as_str(), first.joints[0].as_str()),
        ("action_delay", "shoulder_pitch")
    );
    assert!((first.values[0] - 0.03).abs() <= 0.001, "{:?}", first.values);
}

#[test]
fn two_effects_on_two_joints_are_both_found() {
    let robot = load(&root().join("fixtures/gap/arm3.xml"));
    let joints: Vec<String> = JOINTS.iter().map(|s| s.to_string()).collect();
    let hidden = vec![
        Applied {
            effect: effects::by_id("armature").unwrap(),
            joints: vec!["elbow_pitch".into()],
            params: vec![0.04],
        },
        Applied {
            effect: effects::by_id("action_delay").unwrap(),
            joints: vec!["wrist_pitch".into()],
            params: vec![0.02],
        },
    ];
    let recs = generate(
        &robot,
        &joints,
        &hidden,
        8,
        &SynthOptions { duration_s: 4.0, ..Default::default() },
        9,
    )
    .unwrap();
    let out = fit(&robot, &recs, &FitOptions { max_rounds: 3, ..Default::default() });
    let got: Vec<(String, String, f64)> =
        out.selected.iter().map(|s| (s.effect.clone(), s.joints.join(","), s.values[0])).collect();
    eprintln!("{got:?}");
    let find = |e: &str, j: &str| got.iter().find(|g| g.0 == e && g.1 == j).map(|g| g.2);
    let a = find("armature", "elbow_pitch").expect("armature found");
    let d = find("action_delay", "wrist_pitch").expect("delay found");
    assert!((a - 0.04).abs() < 0.004 && (d - 0.02).abs() <= 0.001, "{got:?}");
    assert!(got.len() <= 3, "spurious effects: {got:?}");
}
