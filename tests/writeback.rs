//! `fit --write-model` writes the fitted values where the model really lives (a Menagerie-style
//! scene that includes the robot file), and `--write-actuators` writes a Python snippet that
//! parses. Expected values: the damping hidden by `synth` (chosen here), and the input model's own
//! compiled values (which the written model must differ from).

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::{kept, load, root};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_modellint"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("modellint_writeback_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `$MODELLINT_SHARED_DATA`, else the first `shared/data` beside the crate or an ancestor.
fn shared_data() -> Option<PathBuf> {
    if let Some(d) =
        std::env::var_os("MODELLINT_SHARED_DATA").map(PathBuf::from).filter(|d| d.is_dir())
    {
        return Some(d);
    }
    root().ancestors().skip(1).take(3).map(|a| a.join("shared/data")).find(|d| d.is_dir())
}

fn run(cmd: &mut Command) -> (Option<i32>, String, String) {
    let o = cmd.output().unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// synth (hidden viscous damping `truth` on joints matching `glob`) → fit → --write-model into
/// `out_dir` (another directory than the model's). Returns the fitted model path and fit JSON.
fn synth_fit_write(
    model: &Path,
    glob: &str,
    truth: f64,
    work: &Path,
    extra: &[&str],
) -> (PathBuf, serde_json::Value, String) {
    let recs = work.join("recordings");
    let (c, _, e) = run(bin()
        .arg("synth")
        .arg(model)
        .args([
            "--effects",
            &format!("viscous_damping@{glob}={truth}"),
            "--joints",
            glob,
            "--episodes",
            "4",
            "--duration",
            "2",
        ])
        .args(extra)
        .arg("--out")
        .arg(&recs));
    assert_eq!(c, Some(0), "synth: {e}");
    let out = work.join("out").join("fitted.xml");
    let (c, stdout, stderr) = run(bin()
        .arg("fit")
        .arg(model)
        .arg(recs.join("episodes"))
        .args([
            "--effects",
            "viscous_damping",
            "--joints",
            glob,
            "--format",
            "json",
            "--write-model",
        ])
        .arg(&out)
        .arg("--write-actuators")
        .arg(work.join("out").join("act.toml")));
    assert_eq!(c, Some(0), "fit: {stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    (out, v, stderr)
}

fn check_written(
    scene: &Path,
    robot_file: &Path,
    out: &Path,
    v: &serde_json::Value,
    stderr: &str,
    joints: &[&str],
    truth: f64,
) {
    let dir = out.parent().unwrap();
    let stem = robot_file.file_stem().unwrap().to_string_lossy();
    let copy = dir.join(format!("fitted_{stem}.xml"));
    assert!(copy.is_file(), "no copy of the robot file; stderr: {stderr}");
    // The scene's include now points at the copy; the original files are untouched.
    let scene_out = std::fs::read_to_string(out).unwrap();
    assert!(scene_out.contains(&format!("file=\"fitted_{stem}.xml\"")), "{scene_out}");
    // What stderr said is in the JSON: a warning in `warnings`, anything else (notes, the files
    // written) in `notes`.
    let list = |k: &str| -> Vec<String> {
        v[k].as_array().unwrap().iter().map(|w| w.as_str().unwrap().to_string()).collect()
    };
    let (warnings, notes) = (list("warnings"), list("notes"));
    for line in stderr.lines().filter_map(|l| l.strip_prefix("modellint: ")) {
        let (line, key) = match line.strip_prefix("warning: ") {
            Some(w) => (w, &warnings),
            None => (line.strip_prefix("note: ").unwrap_or(line), &notes),
        };
        assert!(key.iter().any(|w| w == line), "stderr line `{line}` not in the JSON {key:?}");
    }
    assert!(notes.iter().any(|w| w.contains(&copy.display().to_string())), "{notes:?}");
    // MuJoCo loads the written model; the fitted joints' damping differs from the input's and is
    // the hidden value.
    let before = load(scene);
    let after = load(out);
    for j in joints {
        let b = before.joint(j).unwrap().damping;
        let a = after.joint(j).unwrap().damping;
        assert!((a - b).abs() > 0.1 * truth, "{j}: damping {b} → {a} unchanged");
        assert!((a - truth).abs() < 0.1 * truth, "{j}: written damping {a}, hidden {truth}");
        let fitted = v["missing_physics"][0]["params"]["damping"].as_f64().unwrap();
        assert!((a - fitted).abs() < 1e-5, "{j}: written {a}, fitted {fitted}");
    }
    // Every other joint is as it was.
    for (jb, ja) in before.joints.iter().zip(&after.joints) {
        if !joints.contains(&jb.name.as_str()) {
            assert_eq!((jb.damping, jb.armature), (ja.damping, ja.armature), "{}", jb.name);
        }
    }
}

/// A scene that includes the robot file, meshes under `assets/` (meshdir), output elsewhere.
#[test]
fn write_model_edits_the_included_robot_file_and_rebases_assets() {
    let work = tmp("include");
    let m = work.join("model");
    std::fs::create_dir_all(m.join("assets")).unwrap();
    // A tetrahedron mesh: only loadable if meshdir is rebased correctly in the written copy.
    std::fs::write(
        m.join("assets/tet.obj"),
        "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let arm = std::fs::read_to_string(root().join("fixtures/gap/arm3.xml")).unwrap();
    let robot = arm
        .replace("<compiler angle=\"radian\" autolimits=\"true\"/>", "<compiler angle=\"radian\" autolimits=\"true\" meshdir=\"assets\"/>\n  <asset><mesh name=\"tet\" file=\"tet.obj\"/></asset>")
        .replacen("<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"1\"/>", "<geom type=\"mesh\" mesh=\"tet\" mass=\"1\"/>", 1);
    assert_ne!(robot, arm, "fixture edit did not apply");
    std::fs::write(m.join("arm.xml"), &robot).unwrap();
    std::fs::write(m.join("scene.xml"), "<mujoco model=\"scene\">\n  <include file=\"arm.xml\"/>\n  <worldbody><light pos=\"0 0 2\"/></worldbody>\n</mujoco>\n").unwrap();
    let (out, v, stderr) = synth_fit_write(&m.join("scene.xml"), "elbow_pitch", 0.6, &work, &[]);
    check_written(
        &m.join("scene.xml"),
        &m.join("arm.xml"),
        &out,
        &v,
        &stderr,
        &["elbow_pitch"],
        0.6,
    );
    assert_eq!(
        std::fs::read_to_string(m.join("arm.xml")).unwrap(),
        robot,
        "the original robot file was changed"
    );
    let copy = std::fs::read_to_string(out.parent().unwrap().join("fitted_arm.xml")).unwrap();
    assert!(copy.contains("meshdir=\"../model/assets\""), "{copy}");
    let _ = std::fs::remove_dir_all(&work);
}

/// The Booster T1 from MuJoCo Menagerie: scene.xml includes t1.xml; hidden knee damping.
#[test]
fn write_model_on_the_booster_t1_scene() {
    let Some(data) = shared_data() else {
        eprintln!("skipping: ../shared/data is absent (Booster T1 scene)");
        return;
    };
    let scene = data.join("models/booster_t1/scene.xml");
    if !scene.is_file() {
        eprintln!("skipping: {} is absent", scene.display());
        return;
    }
    let work = tmp("t1");
    let (out, v, stderr) = synth_fit_write(&scene, "*Knee*", 2.0, &work, &["--suspend", "0.5"]);
    check_written(
        &scene,
        &data.join("models/booster_t1/t1.xml"),
        &out,
        &v,
        &stderr,
        &["Left_Knee_Pitch", "Right_Knee_Pitch"],
        2.0,
    );
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn write_model_refuses_urdf() {
    let model = root().join("fixtures/rules/urdf-mjcf-drift/urdf/valid.urdf");
    let robot = load(&model);
    let work = tmp("urdf");
    let e = modellint::fit::writemodel::write_model(&model, &robot, &[], &work.join("o.xml"))
        .unwrap_err();
    assert!(e.contains("is URDF"), "{e}");
    assert!(!work.join("o.xml").exists());
    let _ = std::fs::remove_dir_all(&work);
}

/// A fit whose every kept effect has no MJCF form (a load-dependent or Stribeck friction) writes
/// the input model unchanged but for its paths, and says so: not "fitted model written".
#[test]
fn write_model_says_when_nothing_of_the_fit_has_an_mjcf_form() {
    let model = root().join("fixtures/gap/arm3.xml");
    let robot = load(&model);
    let work = tmp("no-mjcf-form");
    let sel = vec![kept(
        "stribeck_friction",
        "elbow_pitch",
        &[("static", 0.2), ("dynamic", 0.1), ("v_stribeck", 0.1)],
    )];
    let w =
        modellint::fit::writemodel::write_model(&model, &robot, &sel, &work.join("o.xml")).unwrap();
    assert!(!w.changed);
    assert!(
        w.notes.iter().any(|n| n.contains("nothing of the fit has an MJCF form")
            && n.contains("stribeck_friction on elbow_pitch")),
        "{:?}",
        w.notes
    );
    let written = load(&work.join("o.xml"));
    assert_eq!(written.mj.dof_frictionloss(), robot.mj.dof_frictionloss());
    // A damping beside it is written: the model changed.
    let sel2 = [sel, vec![kept("viscous_damping", "elbow_pitch", &[("damping", 0.02)])]].concat();
    let w = modellint::fit::writemodel::write_model(&model, &robot, &sel2, &work.join("o2.xml"))
        .unwrap();
    assert!(w.changed, "{:?}", w.notes);
    let _ = std::fs::remove_dir_all(&work);
}

/// The Isaac Lab snippet of `--write-actuators` is valid Python for every effect it mentions.
#[test]
fn actuator_snippet_parses_as_python() {
    let robot = load(&root().join("fixtures/gap/arm3.xml"));
    let selected = vec![
        kept("armature", "elbow_pitch", &[("armature", 0.001489)]),
        kept("viscous_damping", "elbow_pitch", &[("damping", 0.018939)]),
        kept("coulomb_friction", "wrist_pitch", &[("frictionloss", 0.12)]),
        kept("torque_limit", "wrist_pitch", &[("effort_limit", 3.5)]),
        kept("action_delay", "shoulder_pitch", &[("delay_s", 0.02)]),
        kept("backlash", "shoulder_pitch", &[("width", 0.01)]),
        kept("gain_error", "elbow_pitch", &[("kp_scale", 0.8), ("kd_scale", 1.2)]),
    ];
    let work = tmp("snippet");
    let files =
        modellint::fit::writeback::write_actuators(&work.join("act.toml"), &robot, &selected)
            .unwrap();
    let py = files
        .iter()
        .find(|p| p.extension().is_some_and(|x| x == "py"))
        .expect("a .py file")
        .clone();
    let text = std::fs::read_to_string(&py).unwrap();
    // arm3: timestep 0.001 s → a 0.02 s delay is 20 physics steps.
    assert!(text.contains("min_delay=20, max_delay=20"), "{text}");
    assert!(text.contains("armature=0.001489,"), "{text}");
    // `stiffness` and `damping` are required fields: every joint's entry has its servo's gains,
    // the fitted gain error's scaled ones where one was kept (arm3: kp 50, kv 1.5).
    let entry = |j: &str| {
        let at = text.find(&format!("\"{j}\": ImplicitActuatorCfg(")).expect(j);
        text[at..at + text[at..].find("    ),").unwrap()].to_string()
    };
    let elbow = entry("elbow_pitch");
    assert!(elbow.contains("stiffness=40,") && elbow.contains("damping=1.8,"), "{elbow}");
    let wrist = entry("wrist_pitch");
    assert!(wrist.contains("stiffness=50,") && wrist.contains("damping=1.5,"), "{wrist}");
    assert!(
        toml::from_str::<toml::Value>(&std::fs::read_to_string(work.join("act.toml")).unwrap())
            .is_ok()
    );
    match Command::new("python3")
        .arg("-c")
        .arg("import ast, sys; ast.parse(open(sys.argv[1]).read())")
        .arg(&py)
        .output()
    {
        Ok(o) => assert!(
            o.status.success(),
            "not valid Python:\n{text}\n{}",
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(_) => eprintln!("skipping: python3 not found; the snippet was not parsed"),
    }
    let _ = std::fs::remove_dir_all(&work);
}

/// Each effect's MJCF write-back on arm3 (timestep 1 ms; `<position>` servos with kp 50, kv 1.5
/// from the default class): the attributes it sets, and the notes for what MJCF cannot hold.
#[test]
fn mjcf_write_back_of_each_expressible_effect() {
    let path = root().join("fixtures/gap/arm3.xml");
    let robot = load(&path);
    let xml = std::fs::read_to_string(&path).unwrap();
    let selected = vec![
        kept("action_delay", "shoulder_pitch", &[("delay_s", 0.0204)]),
        kept("torque_limit", "wrist_pitch", &[("effort_limit", 3.5)]),
        kept("gain_error", "elbow_pitch", &[("kp_scale", 0.8), ("kd_scale", 1.2)]),
        kept("viscous_damping", "elbow_pitch", &[("damping", 0.25)]),
        kept("backlash", "shoulder_pitch", &[("backlash_rad", 0.01)]),
    ];
    let (out, warnings) = modellint::fit::writeback::edit_mjcf(&xml, &robot, &selected).unwrap();
    let line = |name: &str, tag: &str| {
        out.lines()
            .find(|l| l.contains(&format!("<{tag} ")) && l.contains(&format!("name=\"{name}\"")))
            .unwrap_or_else(|| panic!("no <{tag} name=\"{name}\"> in\n{out}"))
            .to_string()
    };
    // 0.0204 s at 1 ms steps: 20 samples of MuJoCo's actuator delay buffer.
    let shoulder = line("shoulder_pitch", "position");
    assert!(
        shoulder.contains("delay=\"0.0204\"") && shoulder.contains("nsample=\"20\""),
        "{shoulder}"
    );
    let wrist = line("wrist_pitch", "position");
    assert!(
        wrist.contains("forcelimited=\"true\"") && wrist.contains("forcerange=\"-3.5 3.5\""),
        "{wrist}"
    );
    // Gains from the compiled servo: 50 × 0.8 and 1.5 × 1.2.
    let elbow = line("elbow_pitch", "position");
    assert!(elbow.contains("kp=\"40\"") && elbow.contains("kv=\"1.8\""), "{elbow}");
    assert!(line("elbow_pitch", "joint").contains("damping=\"0.25\""), "{out}");
    assert_eq!(
        warnings,
        vec!["backlash on shoulder_pitch: not expressible in MJCF; see --write-actuators"]
    );
}

/// A gain error cannot be written on a servo that is not a `<position>` one: one note per gain.
#[test]
fn gain_error_on_a_torque_motor_is_not_written() {
    let work = tmp("motor");
    let path = work.join("motor.xml");
    let xml = r#"<mujoco>
  <worldbody>
    <body name="link">
      <joint name="j" type="hinge" axis="0 1 0"/>
      <geom type="capsule" size="0.02" fromto="0 0 0 0.2 0 0" mass="0.5"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="m" joint="j"/>
  </actuator>
</mujoco>
"#;
    std::fs::write(&path, xml).unwrap();
    let robot = load(&path);
    let sel = vec![kept("gain_error", "j", &[("kp_scale", 0.8), ("kd_scale", 1.2)])];
    let (out, warnings) = modellint::fit::writeback::edit_mjcf(xml, &robot, &sel).unwrap();
    assert_eq!(out, xml);
    assert_eq!(warnings, vec!["gain_error on j: actuator is not a position servo; not written"; 2]);
    let _ = std::fs::remove_dir_all(&work);
}

/// One contact: (geoms, solref, sliding friction, condim, solimp's first value).
type Contact = ([i32; 2], [f64; 2], f64, i32, f64);

/// The contacts MuJoCo makes in `m` at its first keyframe, as MuJoCo's own collision code
/// combines them.
fn contacts_of(m: &mut mujoco_rs::prelude::MjModel) -> Vec<Contact> {
    use mujoco_rs::prelude::*;
    let mut d = MjData::new(m);
    d.forward();
    // solimp to 9 decimals: the written text holds the mixed value's shortest form.
    let r9 = |x: f64| (x * 1e9).round() / 1e9;
    d.contact().iter().map(|c| (c.geom, c.solref, c.friction[0], c.dim, r9(c.solimp[0]))).collect()
}

/// `ground_contact` on a foot pressed into a floor: in the model copy and in the written MJCF
/// (compiled again by MuJoCo), the foot–floor contact has the fitted time constant, damping
/// ratio and impedance (solimp's dmin and width), while its friction (the floor's larger 1.0,
/// not the foot's 0.5), condim and the rest of its solimp stay what they were; the fit starts
/// from the contact as MuJoCo mixes it; a body off the ground is no candidate.
#[test]
fn ground_contact_is_written_on_the_foot_and_keeps_the_rest_of_the_contact() {
    use modellint::fit::effects::{self, Applied, JointTarget};
    let work = tmp("ground_contact");
    let path = work.join("foot.xml");
    let xml = r#"<mujoco>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1" friction="1.0 0.005 0.0001" solimp="0.8 0.95 0.001"/>
    <body name="foot" pos="0 0 0.019">
      <joint name="z" type="slide" axis="0 0 1"/>
      <geom name="sole" type="box" size="0.1 0.04 0.02" mass="1" friction="0.5 0.005 0.0001"/>
      <body name="arm" pos="0 0 0.3">
        <joint name="lift" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.2"/>
      </body>
    </body>
  </worldbody>
  <keyframe><key qpos="0 0"/></keyframe>
</mujoco>
"#;
    std::fs::write(&path, xml).unwrap();
    let robot = load(&path);
    let e = effects::by_id("ground_contact").expect("registered");
    let foot = JointTarget::of(&robot, "z").unwrap();
    assert!(e.acts_on(&foot) && foot.ground.len() == 1, "{:?}", foot.ground);
    assert!(!e.acts_on(&JointTarget::of(&robot, "lift").unwrap()), "the arm touches no ground");
    let nominal = contacts_of(&mut robot.mj.clone());
    assert!(!nominal.is_empty(), "the sole does not touch the floor");
    for c in &nominal {
        assert_eq!((c.1, c.2, c.3), ([0.02, 1.0], 1.0, 3), "{c:?}");
    }
    // Equal priority: MuJoCo mixes the two geoms' solimp (0.9 and 0.8 at first touch).
    let dmin = nominal[0].4;
    assert!(dmin > 0.8 && dmin < 0.9, "{dmin}");
    let start = e.initial(&robot.mj, &foot);
    assert_eq!(start[..2], [0.02, 1.0]);
    assert!((start[2] - dmin).abs() < 1e-9 && start[3] == 0.001, "{start:?}");
    let p = [0.011, 0.7, 0.5, 0.005];
    let applied = [Applied { effect: e, joints: vec!["z".into()], params: p.to_vec() }];
    let fitted = contacts_of(&mut effects::model_with(&robot, &applied));
    let want: Vec<_> = nominal.iter().map(|c| (c.0, [0.011, 0.7], c.2, c.3, 0.5)).collect();
    assert_eq!(fitted, want);
    let named = [("timeconst", p[0]), ("dampratio", p[1]), ("dmin", p[2]), ("width", p[3])];
    let sel = vec![kept("ground_contact", "z", &named)];
    let (out, warnings) = modellint::fit::writeback::edit_mjcf(xml, &robot, &sel).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let written = work.join("written.xml");
    std::fs::write(&written, &out).unwrap();
    let mut m = load(&written).mj.clone();
    assert_eq!(contacts_of(&mut m), want, "{out}");
    let sole = out.lines().find(|l| l.contains("name=\"sole\"")).unwrap();
    assert!(sole.contains("solref=\"0.011 0.7\"") && sole.contains("priority=\"1\""), "{sole}");
    assert!(sole.contains("solimp=\"0.5 0.95 0.005 "), "{sole}");
    let _ = std::fs::remove_dir_all(&work);
}
