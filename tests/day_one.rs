//! What a new user meets on day one (issue 47, item 3): `synth` on a torque-actuated robot says
//! why it cannot drive it; docs reachable from the installed tool (`modellint docs TOPIC`); the
//! gap report's error-over-time plot; `--write-model` keeps asset paths relative when the output
//! is elsewhere on the machine.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_modellint")).args(args).output().unwrap()
}

fn tmp(base: &Path, name: &str) -> PathBuf {
    let d = base.join(format!("modellint-day1-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// arm3 with its position servos replaced by torque motors.
#[test]
fn synth_on_torque_actuators_says_why() {
    let dir = tmp(&std::env::temp_dir(), "motor");
    let arm = std::fs::read_to_string(root().join("fixtures/gap/arm3.xml")).unwrap();
    let start = arm.find("<actuator>").unwrap();
    let end = arm.find("</actuator>").unwrap() + "</actuator>".len();
    let motors = "<actuator><motor joint=\"shoulder_pitch\"/><motor joint=\"elbow_pitch\"/>\
                  <motor joint=\"wrist_pitch\"/></actuator>";
    let model = dir.join("motor.xml");
    std::fs::write(&model, format!("{}{motors}{}", &arm[..start], &arm[end..])).unwrap();
    let o = run(&["synth", model.to_str().unwrap(), "--out", dir.join("out").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("torque actuators (<motor>): shoulder_pitch, elbow_pitch, wrist_pitch"),
        "{err}"
    );
    assert!(err.contains("<position kp="), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `modellint docs TOPIC` prints the page shipped in the binary; unknown topics get the
/// nearest; messages point to the command, not to a file the wheel does not have.
#[test]
fn docs_are_printed_by_the_tool() {
    let o = run(&["docs", "recording-format"]);
    assert_eq!(o.status.code(), Some(0));
    let page = std::fs::read_to_string(root().join("docs/recording-format.md")).unwrap();
    assert_eq!(String::from_utf8_lossy(&o.stdout), page);
    let o = run(&["docs"]);
    let list = String::from_utf8_lossy(&o.stdout);
    assert!(list.contains("spec") && list.contains("fitting"), "{list}");
    let o = run(&["docs", "spek"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("did you mean: spec"));
    // A model without a spec: the note says where the spec format is documented.
    let o = run(&[root().join("fixtures/gap/arm3.xml").to_str().unwrap(), "--no-probe"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("`modellint docs spec`") && !err.contains("docs/spec.md"), "{err}");
}

/// `gap --report` draws, per worst joint, the error replayed − recorded over time.
#[test]
fn gap_report_has_an_error_over_time_plot() {
    let dir = tmp(&std::env::temp_dir(), "report");
    let model = root().join("fixtures/gap/arm3.xml");
    let ds = dir.join("ds");
    let o = run(&[
        "synth",
        model.to_str().unwrap(),
        "--episodes",
        "2",
        "--duration",
        "2",
        "--out",
        ds.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let rep = dir.join("rep");
    let o = run(&[
        "gap",
        model.to_str().unwrap(),
        ds.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(html.contains("position error, replayed − recorded") && html.contains("error [deg]"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A model with meshes under `meshdir="assets"` in the system temp directory, written back into
/// the build's own temp directory (only `/` in common): the copy's meshdir is relative
/// (`../../…/assets`), not the absolute path of this machine, and the written model loads.
#[test]
fn write_model_keeps_meshdir_relative_across_the_file_system() {
    let src = tmp(&std::env::temp_dir(), "mesh");
    let out_dir = tmp(Path::new(env!("CARGO_TARGET_TMPDIR")), "out");
    std::fs::create_dir_all(src.join("assets")).unwrap();
    std::fs::write(
        src.join("assets/tet.obj"),
        "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let arm = std::fs::read_to_string(root().join("fixtures/gap/arm3.xml")).unwrap();
    let robot = arm
        .replace(
            "<compiler angle=\"radian\" autolimits=\"true\"/>",
            "<compiler angle=\"radian\" autolimits=\"true\" meshdir=\"assets\"/>\n  \
             <asset><mesh name=\"tet\" file=\"tet.obj\"/></asset>",
        )
        .replacen(
            "<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"1\"/>",
            "<geom type=\"mesh\" mesh=\"tet\" mass=\"1\"/>",
            1,
        );
    assert_ne!(robot, arm, "fixture edit did not apply");
    let model = src.join("arm.xml");
    std::fs::write(&model, &robot).unwrap();
    let ds = src.join("ds");
    let o = run(&[
        "synth",
        model.to_str().unwrap(),
        "--effects",
        "viscous_damping@elbow*=0.5",
        "--episodes",
        "3",
        "--duration",
        "3",
        "--out",
        ds.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let out = out_dir.join("fitted.xml");
    let o = run(&[
        "fit",
        model.to_str().unwrap(),
        ds.to_str().unwrap(),
        "--quiet",
        "--effects",
        "viscous_damping",
        "--write-model",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let meshdir = text.split("meshdir=\"").nth(1).and_then(|r| r.split('"').next()).unwrap();
    assert!(meshdir.starts_with("../") && meshdir.ends_with("/assets"), "{meshdir}");
    assert_eq!(
        std::fs::canonicalize(out_dir.join(meshdir)).unwrap(),
        std::fs::canonicalize(src.join("assets")).unwrap()
    );
    let o = run(&[out.to_str().unwrap(), "--no-probe"]);
    assert_ne!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&src);
    let _ = std::fs::remove_dir_all(&out_dir);
}
