//! A joint recorded with positions but no command (issue 48): `gap` and `fit` exit 2 at the
//! header line naming the joint, what is missing and `--no-command`; with the flag the joint is
//! replayed but left out of the scores and of the fit, with a note; a passive joint (no
//! actuator in the model) needs no command. The recordings are written here by hand, not by
//! modellint's writer.

use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_modellint")).args(args).output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("modellint-nocmd-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const ARM3: [&str; 3] = ["shoulder_pitch", "elbow_pitch", "wrist_pitch"];

/// A 100 Hz controller logged at 100 Hz for 3 s: smooth commands per joint, the positions a
/// first-order lag of them (time constant 30 ms). `with_cmd[k]`: joint k has its q_cmd column.
fn arm3_csv(phase: f64, with_cmd: [bool; 3]) -> String {
    let mut s = String::from("# control_rate_hz: 100\n# control_t0_s: 0\nt");
    for (k, j) in ARM3.iter().enumerate() {
        s.push_str(&format!(",{j}.q"));
        if with_cmd[k] {
            s.push_str(&format!(",{j}.q_cmd"));
        }
    }
    s.push('\n');
    let mut q = [0.0f64; 3];
    for i in 0..300 {
        let t = i as f64 * 0.01;
        s.push_str(&format!("{t:.3}"));
        for k in 0..3 {
            let c = 0.3 * (1.3 * t * (1.0 + k as f64 * 0.4) + phase).sin().powi(2);
            s.push_str(&format!(",{:.6}", q[k]));
            if with_cmd[k] {
                s.push_str(&format!(",{c:.6}"));
            }
            q[k] += (c - q[k]) * (0.01 / 0.03);
        }
        s.push('\n');
    }
    s
}

fn arm3() -> String {
    root().join("fixtures/gap/arm3.xml").display().to_string()
}

/// Without the elbow's command column: exit 2 from `gap` and `fit` at the header line (line 3,
/// after two metadata lines), naming the joint, the column and the flag; nothing on stdout.
#[test]
fn a_driven_joint_without_its_command_is_an_error_at_the_header_line() {
    let d = tmpdir("err");
    let f = d.join("ep0.csv");
    std::fs::write(&f, arm3_csv(0.0, [true, false, true])).unwrap();
    let path = f.to_str().unwrap();
    for sub in ["gap", "fit"] {
        let (code, out, err) = run(&[sub, &arm3(), path]);
        assert_eq!(code, 2, "{sub}: {err}");
        assert!(out.is_empty(), "{sub}: {out}");
        assert!(err.contains(&format!("{path}:3: ")), "{sub}: no file:line in {err}");
        assert!(
            err.contains("joint 'elbow_pitch' has positions but no 'elbow_pitch.q_cmd' column")
                && err.contains("--no-command elbow_pitch"),
            "{sub}: {err}"
        );
        assert!(!err.contains("shoulder_pitch") && !err.contains("panicked"), "{sub}: {err}");
    }
    // Every joint without its command: all named in one error.
    std::fs::write(&f, arm3_csv(0.0, [false, false, false])).unwrap();
    let (code, _, err) = run(&["gap", &arm3(), path]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--no-command shoulder_pitch,elbow_pitch,wrist_pitch"), "{err}");
    // The same file with every command: runs.
    std::fs::write(&f, arm3_csv(0.0, [true; 3])).unwrap();
    let (code, _, err) = run(&["gap", &arm3(), path]);
    assert_eq!(code, 0, "{err}");
    // A pattern that names no joint of the model is refused, not ignored.
    let (code, _, err) = run(&["gap", &arm3(), path, "--no-command", "elbw"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--no-command elbw: matches no joint of the model"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

/// With `--no-command elbow_pitch`: `gap` exits 0, says in a note (stderr and JSON) that the
/// elbow is left out, and scores only the shoulder and the wrist; `fit` exits 0, fits nothing
/// on the elbow and says so in its JSON notes.
#[test]
fn no_command_leaves_the_joint_out_of_the_scores_and_the_fit() {
    let d = tmpdir("flag");
    for (i, phase) in [0.0, 0.7].iter().enumerate() {
        std::fs::write(d.join(format!("ep{i}.csv")), arm3_csv(*phase, [true, false, true]))
            .unwrap();
    }
    let dir = d.to_str().unwrap();
    let (code, out, err) =
        run(&["gap", &arm3(), dir, "--no-command", "elbow_pitch", "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("note: --no-command: left out of the scores and of the fit")
            && err.contains("elbow_pitch (no command in 2 of 2 file(s): ep0.csv, ep1.csv)"),
        "{err}"
    );
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    let joints: Vec<&str> =
        v["per_joint"].as_array().unwrap().iter().map(|j| j["name"].as_str().unwrap()).collect();
    assert_eq!(joints, ["shoulder_pitch", "wrist_pitch"], "{out}");
    // arm3's links hang side by side from a fixed base: nothing moves with the elbow.
    assert!(!err.contains("warning"), "{err}");
    assert!(v["notes"].to_string().contains("--no-command"), "{}", v["notes"]);
    // The shoulder's score is the one it has with the elbow's command recorded: the joints are
    // decoupled in arm3, and the elbow is still replayed.
    let full = d.join("full");
    std::fs::create_dir_all(&full).unwrap();
    for (i, phase) in [0.0, 0.7].iter().enumerate() {
        std::fs::write(full.join(format!("ep{i}.csv")), arm3_csv(*phase, [true; 3])).unwrap();
    }
    let (code, out_full, err) = run(&["gap", &arm3(), full.to_str().unwrap(), "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let w: serde_json::Value = serde_json::from_str(&out_full).unwrap();
    let mae = |v: &serde_json::Value, j: &str| {
        v["per_joint"].as_array().unwrap().iter().find(|x| x["name"] == j).unwrap()["mae"]
            .as_f64()
            .unwrap()
    };
    assert_eq!(mae(&v, "shoulder_pitch"), mae(&w, "shoulder_pitch"));
    assert_eq!(w["per_joint"].as_array().unwrap().len(), 3);

    let (code, out, err) = run(&[
        "fit",
        &arm3(),
        dir,
        "--no-command",
        "elbow_pitch",
        "--effects",
        "viscous_damping",
        "--holdout",
        "2",
        "--format",
        "json",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert!(v["notes"].to_string().contains("elbow_pitch (no command in 2 of 2"), "{}", v["notes"]);
    for s in v["missing_physics"].as_array().unwrap() {
        assert!(!s["joints"].to_string().contains("elbow"), "fitted on the elbow: {s}");
    }
    let before: Vec<&str> = v["before"]["per_joint"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["name"].as_str().unwrap())
        .collect();
    assert!(!before.contains(&"elbow_pitch") && !before.is_empty(), "{before:?}");
    for f in v["floor"].as_array().unwrap() {
        assert_ne!(f["joint"], "elbow_pitch", "{f}");
    }
    // Cross-validation over a metadata key: every fold leaves the elbow out of its MAE.
    for (i, run_id) in ["a", "b"].iter().enumerate() {
        let f = d.join(format!("ep{i}.csv"));
        let text = std::fs::read_to_string(&f).unwrap();
        std::fs::write(&f, format!("# run: {run_id}\n{text}")).unwrap();
    }
    let (code, out, err) = run(&[
        "fit",
        &arm3(),
        dir,
        "--no-command",
        "elbow_pitch",
        "--effects",
        "viscous_damping",
        "--holdout-by",
        "run",
        "--format",
        "json",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert_eq!(v["folds"].as_array().map(Vec::len), Some(2), "{out}");
    assert!(v["position_mae_before"].as_f64().is_some_and(f64::is_finite), "{out}");
    // Asked to fit only the elbow: nothing is left.
    let (code, _, err) =
        run(&["fit", &arm3(), dir, "--no-command", "elbow_pitch", "--joints", "elbow_pitch"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no joint left to fit"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

/// A driven arm joint and a passive pendulum hanging from it: the pendulum is recorded as
/// positions only (it has no actuator) and is scored; the arm without its command is an error.
#[test]
fn a_passive_joint_needs_no_command() {
    let d = tmpdir("passive");
    let model = d.join("arm_pendulum.xml");
    std::fs::write(
        &model,
        r#"<mujoco model="arm_pendulum">
  <option timestep="0.001"/>
  <worldbody>
    <body name="arm">
      <joint name="arm" type="hinge" axis="0 1 0" armature="0.01" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.01" mass="0.3"/>
      <body name="bob" pos="0.2 0 0">
        <joint name="pendulum" type="hinge" axis="0 1 0" damping="0.01"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.1" size="0.01" mass="0.05"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="arm" joint="arm" kp="20" kv="1"/>
  </actuator>
</mujoco>
"#,
    )
    .unwrap();
    let mut text = String::from("# control_rate_hz: 50\nt,arm.q,arm.q_cmd,pendulum.q\n");
    for i in 0..150 {
        let t = i as f64 * 0.02;
        let c = 0.2 * (2.0 * t).sin();
        text.push_str(&format!("{t:.2},{:.5},{c:.5},{:.5}\n", 0.9 * c, -0.5 * c));
    }
    let f = d.join("pend.csv");
    std::fs::write(&f, &text).unwrap();
    let (code, out, err) =
        run(&["gap", model.to_str().unwrap(), f.to_str().unwrap(), "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("--no-command"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    let joints: Vec<&str> =
        v["per_joint"].as_array().unwrap().iter().map(|j| j["name"].as_str().unwrap()).collect();
    assert_eq!(joints, ["arm", "pendulum"]);
    // The arm is driven: without its command, the error names it (not the pendulum).
    let no_arm_cmd: String = text
        .lines()
        .map(|l| {
            let mut p: Vec<&str> = l.split(',').collect();
            if p.len() == 4 {
                p.remove(2);
            }
            p.join(",") + "\n"
        })
        .collect();
    std::fs::write(&f, no_arm_cmd).unwrap();
    let (code, _, err) = run(&["gap", model.to_str().unwrap(), f.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!("{}:2: joint 'arm' has positions but no 'arm.q_cmd'", f.display()))
            && !err.contains("'pendulum'"),
        "{err}"
    );
    // Left out with the flag, the arm still carries the pendulum: a warning says that the
    // pendulum's score feels the arm replayed to its own positions (one kinematic chain).
    let (code, out, err) = run(&[
        "gap",
        model.to_str().unwrap(),
        f.to_str().unwrap(),
        "--no-command",
        "arm",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("warning: --no-command") && err.contains("(arm → pendulum)"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert!(v["warnings"].to_string().contains("arm → pendulum"), "{}", v["warnings"]);
    std::fs::remove_dir_all(&d).ok();
}

/// A BAM servo log whose entries have no `goal_position`: read as a BAM log (not as a broken
/// CSV) and refused at its first entry naming the key; some entries without it: at the first
/// of those. With `--no-command servo` nothing is left to score (the log's one joint).
#[test]
fn a_bam_log_without_goal_position_names_the_key() {
    let d = tmpdir("bam");
    let rig = root().join("fixtures/bam_xl330/rig.xml").display().to_string();
    let entry = |i: usize, goal: bool| {
        let t = 0.005 * i as f64;
        let g = if goal {
            format!(", \"goal_position\": {:.4}", 0.2 * (3.0 * t).sin())
        } else {
            String::new()
        };
        format!(
            "    {{\"timestamp\": {t:.4}, \"position\": {:.4}, \"speed\": 0.0{g}, \"torque_enable\": true}}",
            0.19 * (3.0 * t).sin()
        )
    };
    let log = |goal: &dyn Fn(usize) -> bool| {
        let e: Vec<String> = (0..400).map(|i| entry(i, goal(i))).collect();
        format!(
            "{{\"mass\": 0.49, \"length\": 0.1, \"kp\": 400, \"vin\": 7.4, \"motor\": \"xl330\",\n \"trajectory\": \"sin\",\n \"entries\": [\n{}\n]}}\n",
            e.join(",\n")
        )
    };
    let f = d.join("log.json");
    let path = f.to_str().unwrap();
    std::fs::write(&f, log(&|_| true)).unwrap();
    let (code, _, err) = run(&["gap", &rig, path]);
    assert_eq!(code, 0, "{err}");
    std::fs::write(&f, log(&|_| false)).unwrap();
    for sub in ["gap", "fit"] {
        let (code, _, err) = run(&[sub, &rig, path]);
        assert_eq!(code, 2, "{sub}: {err}");
        assert!(
            err.contains(&format!(
                "{path}:4: joint 'servo' has positions but no 'goal_position' key"
            )) && err.contains("--no-command servo"),
            "{sub}: {err}"
        );
    }
    let (code, _, err) = run(&["gap", &rig, path, "--no-command", "servo"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("nothing left to score"), "{err}");
    // Entry 7 without it (line 4 + 7).
    std::fs::write(&f, log(&|i| i != 7)).unwrap();
    let (code, _, err) = run(&["gap", &rig, path]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(&format!("{path}:11: entry 7 has no 'goal_position'")), "{err}");
    std::fs::remove_dir_all(&d).ok();
}
