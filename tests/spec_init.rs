//! `modellint init-spec`: the written template loads with `--spec`, adds no finding to the model
//! it was written from, turns the spec-driven checks on, and names the rules still waiting for a
//! placeholder. Families are compared with the hand-written specs of the shared models
//! (fixtures/booster_t1.toml, fixtures/unitree_h1.toml: written from the robots' datasheets and
//! the study, not by this tool) and with the armature classes of models/asimov.xml.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn modellint(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args(args)
        .env_remove("GITHUB_ACTIONS")
        .arg("--no-cache")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn init(args: &[&str]) -> (i32, String, String) {
    let out =
        Command::new(env!("CARGO_BIN_EXE_modellint")).arg("init-spec").args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("modellint-init-spec-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// (rule, message) of every finding of a JSON run, sorted.
fn findings(args: &[&str]) -> (Vec<(String, String)>, Value, String) {
    let mut a = args.to_vec();
    a.extend(["--format", "json", "--no-probe"]);
    let (code, out, err) = modellint(&a);
    assert!(code == 0 || code == 1, "{a:?}: exit {code}\n{err}");
    let v: Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("not JSON ({e}):\n{out}"));
    let mut f: Vec<(String, String)> = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| (f["rule"].as_str().unwrap().into(), f["message"].as_str().unwrap().into()))
        .collect();
    f.sort();
    (f, v, err)
}

fn shared(model: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/models").join(model);
    if p.is_file() {
        Some(p)
    } else {
        eprintln!("skipping {model}: ../shared/data/models is absent");
        None
    }
}

/// Writes the template of `model` into a fresh directory; returns its path.
fn write_template(model: &Path, tag: &str) -> PathBuf {
    let out = tmp(tag).join("spec.toml");
    let (code, _, err) = init(&[model.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("--spec"), "the note says how to use it: {err}");
    out
}

/// The template loads, changes no finding of the model it describes, and the run says which
/// rules still wait for a placeholder instead of "no hardware spec".
fn loads_and_adds_nothing(model: &Path, spec: &Path) -> String {
    let m = model.to_str().unwrap();
    let (without, _, _) = findings(&[m]);
    let (with, v, err) = findings(&[m, "--spec", spec.to_str().unwrap()]);
    assert_eq!(v["spec"]["path"].as_str(), Some(spec.to_str().unwrap()));
    assert!(!err.contains("no hardware spec"), "{err}");
    assert_eq!(with, without, "the template must agree with the model it was written from");
    err
}

/// Joint → (family, peak torque, region) as a spec resolves them, through the spec loader.
fn resolve(model: &Path, spec: &Path) -> Resolved {
    let mut map = modellint::model::source::SourceMap::default();
    let robot = modellint::model::load(&mut map, model, None).unwrap();
    let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let s = modellint::spec::load(&mut map, spec, &names).unwrap_or_else(|e| panic!("{e}"));
    names
        .iter()
        .filter_map(|n| {
            let f = s.joint(n)?;
            let peak = f
                .motor
                .as_deref()
                .and_then(|m| s.motor(m))
                .and_then(|m| modellint::spec::v(&m.peak_torque));
            Some((n.clone(), (f.motor.clone(), peak, f.region.clone())))
        })
        .collect()
}

#[test]
fn asimov_template_turns_the_spec_checks_on() {
    // A copy without models/asimov.toml beside it.
    let dir = tmp("asimov-copy");
    std::fs::copy("models/asimov.xml", dir.join("asimov.xml")).unwrap();
    let model = &dir.join("asimov.xml");
    let spec = write_template(model, "asimov");
    let text = std::fs::read_to_string(&spec).unwrap();
    let err = loads_and_adds_nothing(model, &spec);
    assert!(err.contains("not run: missing-action-delay"), "{err}");

    // Three armature values in the file (hip 0.095625, knee/hip-yaw 0.0339552, ankle
    // 0.0565056, all at 39.4 N·m): three families, grouped as the file's classes group them.
    let r = resolve(model, &spec);
    let fam = |j: &str| r[j].0.clone().unwrap();
    let fams: std::collections::BTreeSet<String> = r.values().filter_map(|v| v.0.clone()).collect();
    assert_eq!(fams.len(), 3, "{text}");
    assert_eq!(fam("left_hip_pitch"), fam("right_hip_roll"));
    assert_eq!(fam("left_knee"), fam("right_hip_yaw"));
    assert_eq!(fam("left_ankle_pitch"), fam("right_ankle_roll"));
    assert_ne!(fam("left_hip_pitch"), fam("left_knee"));
    assert_ne!(fam("left_knee"), fam("left_ankle_roll"));
    assert!(r.values().filter(|v| v.0.is_some()).all(|v| v.1 == Some(39.4)));
    // The spring toes have no actuator: passive.
    assert!(text.contains("[joints.\"{left,right}_toe\"]\npassive = true"), "{text}");
    // Placeholders carry their unit and the model's related number.
    assert!(text.contains("# rotor_inertia = ...") && text.contains("kg·m²"), "{text}");
    assert!(text.contains("0.0565056"), "{text}");

    // Filling two placeholders turns missing-action-delay on: the file delays by 20 ms, a
    // hardware maximum of half a 50 Hz step (10 ms) makes that too long.
    let filled = text
        .replace("# control_hz = ...", "control_hz = 50.0 #")
        .replace("# action_delay_steps = [..., ...]", "action_delay_steps = [0, 0.5] #");
    std::fs::write(&spec, filled).unwrap();
    let (with, _, err) = findings(&[model.to_str().unwrap(), "--spec", spec.to_str().unwrap()]);
    assert!(
        with.iter().any(|(r, m)| r == "missing-action-delay" && m.contains("20 ms")),
        "{with:?}"
    );
    assert!(!err.contains("missing-action-delay"), "{err}");
}

#[test]
fn template_catches_a_later_change_of_the_model() {
    // Written from the model, then the left knee's actuator moved onto the passive toe in a
    // copy: the spec written before says the toe is passive.
    let dir = tmp("removed");
    let xml = std::fs::read_to_string("models/asimov.xml").unwrap();
    let copy = dir.join("robot.xml");
    std::fs::write(&copy, &xml).unwrap();
    let (code, _, err) = init(&[copy.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(dir.join("robot.toml").is_file(), "default output is <model>.toml beside the model");
    let moved = xml
        .replace("name=\"left_knee\" joint=\"left_knee\"", "name=\"left_knee\" joint=\"left_toe\"");
    assert_ne!(moved, xml);
    std::fs::write(&copy, moved).unwrap();
    let (f, v, _) = findings(&[copy.to_str().unwrap()]);
    assert!(v["spec"]["path"].as_str().unwrap().ends_with("robot.toml"), "found beside the model");
    assert!(
        f.iter().any(|(r, m)| r == "actuator-mapping"
            && m.contains("`left_toe`, which the spec marks passive")),
        "{f:?}"
    );
    // An existing file is not replaced without --force.
    let (code, _, err) = init(&[copy.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--force"), "{err}");
    let (code, _, err) = init(&[copy.to_str().unwrap(), "--force"]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn stdout_and_bad_model() {
    let (code, out, _) = init(&["models/asimov.xml", "-o", "-"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("# Hardware spec for models/asimov.xml"), "{out}");
    let dir = tmp("bad");
    let bad = dir.join("bad.xml");
    std::fs::write(
        &bad,
        "<mujoco>\n  <worldbody>\n    <body><joint type=\"hinge\" range=\"1\"/></body>\n",
    )
    .unwrap();
    let (code, _, err) = init(&[bad.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("bad.xml"), "{err}");
    assert!(!dir.join("bad.toml").exists());
}

/// Booster T1: the template's families are exactly the hand-written spec's (each at the
/// same peak torque), and its guessed regions agree.
#[test]
fn booster_t1_families_match_the_hand_written_spec() {
    let Some(model) = shared("booster_t1/scene.xml") else { return };
    let spec = write_template(&model, "t1");
    let err = loads_and_adds_nothing(&model, &spec);
    assert!(err.contains("not run: missing-action-delay"), "{err}");
    let ours = resolve(&model, &spec);
    let theirs = resolve(&model, Path::new("fixtures/booster_t1.toml"));
    same_partition(&ours, &theirs, true);
}

/// Unitree H1: every hand-written family lies inside one template family at the same peak
/// torque. (The file gives the ankle and the shoulder pitch/roll motors the same effort limit
/// and armature, so the template cannot split them; the hand-written spec names them apart
/// with the same rotor and gear.)
#[test]
fn unitree_h1_families_refine_the_hand_written_spec() {
    let Some(model) = shared("unitree_h1/scene.xml") else { return };
    let spec = write_template(&model, "h1");
    let err = loads_and_adds_nothing(&model, &spec);
    // Torque-driven joints: the PD-gain rules wait for kp/kd.
    assert!(err.contains("underdamped-pd-gains (motors.*.kp and kd"), "{err}");
    let ours = resolve(&model, &spec);
    let theirs = resolve(&model, Path::new("fixtures/unitree_h1.toml"));
    same_partition(&ours, &theirs, false);
}

type Resolved = BTreeMap<String, (Option<String>, Option<f64>, Option<String>)>;

fn same_partition(ours: &Resolved, theirs: &Resolved, exact: bool) {
    let actuated: Vec<&String> =
        theirs.iter().filter(|(_, v)| v.0.is_some()).map(|(k, _)| k).collect();
    assert!(!actuated.is_empty());
    for a in &actuated {
        let (o, t) = (&ours[*a], &theirs[*a]);
        assert_eq!(o.1, t.1, "{a}: peak torque");
        assert_eq!(o.2, t.2, "{a}: region");
        for b in &actuated {
            let same_t = theirs[*b].0 == t.0;
            let same_o = ours[*b].0 == o.0;
            if same_t {
                assert!(
                    same_o,
                    "{a} and {b} share a hand-written family but not a template family"
                );
            }
            if exact {
                assert_eq!(same_o, same_t, "{a} / {b}");
            }
        }
    }
}

/// `count` as the template's spec resolves it, per joint (through the spec loader).
fn counts(model: &Path, spec: &Path) -> BTreeMap<String, u32> {
    let mut map = modellint::model::source::SourceMap::default();
    let robot = modellint::model::load(&mut map, model, None).unwrap();
    let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let s = modellint::spec::load(&mut map, spec, &names).unwrap_or_else(|e| panic!("{e}"));
    names.iter().filter_map(|n| Some((n.clone(), s.joint(n)?.count))).collect()
}

/// A parallel ankle the model shows (two tendon actuators drive pitch and roll of each ankle):
/// count = 2 on the ankle joints, 1 on the single-motor hips and knees. A serial ankle cross
/// with one actuator per joint gets 1 and the comment that says how to tell a two-motor ankle.
#[test]
fn parallel_ankle_count_follows_the_tendon_actuators() {
    let par = Path::new("fixtures/spec_init/parallel_ankle.xml");
    let spec = write_template(par, "parallel");
    loads_and_adds_nothing(par, &spec);
    let c = counts(par, &spec);
    for side in ["left", "right"] {
        assert_eq!(c[&format!("{side}_ankle_pitch")], 2, "{c:?}");
        assert_eq!(c[&format!("{side}_ankle_roll")], 2, "{c:?}");
        assert_eq!(c[&format!("{side}_hip_pitch")], 1, "single motor: {c:?}");
        assert_eq!(c[&format!("{side}_knee")], 1, "single motor: {c:?}");
    }
    let ser = Path::new("fixtures/spec_init/serial_ankle.xml");
    let spec = write_template(ser, "serial");
    loads_and_adds_nothing(ser, &spec);
    let c = counts(ser, &spec);
    assert!(c.values().all(|&n| n == 1), "no joint has two motors in the model: {c:?}");
    let text = std::fs::read_to_string(&spec).unwrap();
    assert!(text.contains("2 if two motors in the shank drive this ankle"), "{text}");
}

/// A model with no actuator at all (a URDF: the training framework adds the drives) says
/// nothing of which joints a motor drives: the template marks none passive and leaves the
/// counts to the hardware, so it adds no finding (marked passive, every joint got "passive
/// joint has no spring" errors).
#[test]
fn a_model_without_actuators_gets_no_passive_joints() {
    let model = Path::new("fixtures/rules/urdf-mjcf-drift/urdf/valid.urdf");
    let spec = write_template(model, "urdf-no-actuators");
    let text = std::fs::read_to_string(&spec).unwrap();
    assert!(!text.contains("passive = true"), "{text}");
    assert!(text.contains("# actuated = ..."), "{text}");
    // The robot is named as the URDF names it (`<robot name="leg">`), not after the file
    // (`valid.urdf`), as an MJCF's `<mujoco model=…>` names it.
    assert!(text.contains("[robot]\nname = \"leg\"\n"), "{text}");
    loads_and_adds_nothing(model, &spec);
}

/// `init-spec scene.xml` for a scene that includes the robot file writes scene.toml, which
/// linting robot.xml alone never reads: the message says where that looks.
#[test]
fn a_scene_spec_says_where_the_included_robot_file_looks() {
    let d = tmp("scene");
    std::fs::write(
        d.join("robot.xml"),
        r#"<mujoco><worldbody><body name="arm"><joint name="hinge" axis="0 1 0" range="-1 1"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="1"/></body></worldbody><actuator><position joint="hinge" kp="10"/></actuator></mujoco>"#,
    )
    .unwrap();
    std::fs::write(
        d.join("scene.xml"),
        r#"<mujoco><include file="robot.xml"/><worldbody><geom type="plane" size="1 1 0.1"/></worldbody></mujoco>"#,
    )
    .unwrap();
    let (code, _, err) = init(&[d.join("scene.xml").to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let robot_toml = d.join("robot.toml").display().to_string();
    assert!(err.contains(&format!("reads {robot_toml} instead")), "{err}");
}
