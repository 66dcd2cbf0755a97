use super::*;
use crate::fit::effects::{Applied, by_id, inertial, model_with};

fn selected(effect: &str, joint: &str, values: &[f64]) -> Selected {
    let e = by_id(effect).unwrap();
    Selected {
        effect: effect.into(),
        joints: vec![joint.into()],
        params: e.params().iter().zip(values).map(|(d, v)| (d.name.to_string(), *v)).collect(),
        stderr: BTreeMap::new(),
        identifiable: true,
        unidentified: vec![],
        evidence: BTreeMap::new(),
        heldout_improvement: 0.5,
        heldout_rmse_before: 1.0,
        heldout_rmse_after: 0.5,
        window_improvement: 0.0,
        window_improvement_se: 0.0,
        bic_before: 0.0,
        bic_after: 0.0,
        values: values.to_vec(),
    }
}

const ARM: &str = r#"<mujoco>
  <worldbody>
    <body name="upper">
      <joint name="shoulder" type="hinge" axis="0 1 0"/>
      <inertial pos="0 0 -0.15" mass="1.2" fullinertia="0.01 0.0105 0.001 0.0002 0 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.03"/>
      <body name="fore" pos="0 0 -0.3">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.025" mass="0.8"/>
      </body>
    </body>
  </worldbody>
  <actuator><position joint="shoulder" kp="60"/><position joint="elbow" kp="30"/></actuator>
</mujoco>
"#;

/// The body effects' `<inertial>` — replacing one given with `fullinertia`, inserted where the
/// geoms gave the mass — compiles (MuJoCo reading the text) to the mass, centre of mass and
/// inertia tensor the fit simulated, to the 9 digits written; a joint effect beside them is
/// written as before.
#[test]
fn body_effects_are_written_as_the_inertial_the_fit_simulated() {
    let dir = std::env::temp_dir().join(format!("modellint-wb-body-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("arm.xml");
    std::fs::write(&path, ARM).unwrap();
    let load = |p: &std::path::Path| {
        let mut map = crate::model::source::SourceMap::default();
        crate::model::load(&mut map, p, None).unwrap()
    };
    let robot = load(&path);
    let sel = vec![
        selected("link_mass", "shoulder", &[0.5, 0.05]),
        selected("link_mass", "elbow", &[0.3, 0.07]),
        selected("com_offset", "elbow", &[0.02, -0.01]),
        selected("armature", "elbow", &[0.02]),
    ];
    let (text, warnings) = edit_mjcf(ARM, &robot, &sel).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(text.matches("<inertial").count(), 2, "{text}");
    assert!(!text.contains("fullinertia"), "{text}");
    assert!(text.contains(r#"armature="0.02""#));
    let out = dir.join("out.xml");
    std::fs::write(&out, &text).unwrap();
    let written = load(&out);
    let applied: Vec<Applied> = sel
        .iter()
        .map(|s| Applied {
            effect: by_id(&s.effect).unwrap(),
            joints: s.joints.clone(),
            params: s.values.clone(),
        })
        .collect();
    let fitted = model_with(&robot, &applied);
    for b in 1..=2 {
        let (m0, c0, i0) = inertial::read(&robot.mj, b).unwrap();
        let (m1, c1, i1) = inertial::read(&fitted, b).unwrap();
        let (m2, c2, i2) = inertial::read(&written.mj, b).unwrap();
        assert!((m1 - m0).abs() > 0.2, "body {b} changed by the fit");
        assert!((m2 - m1).abs() < 1e-8 * m1, "body {b}: mass {m2} vs {m1}");
        assert!((c2 - c1).norm() < 1e-8, "body {b}: com {c2:?} vs {c1:?} (nominal {c0:?})");
        assert!((i2 - i1).norm() < 1e-8 * i1.norm(), "body {b}: inertia {i2} vs {i1} ({i0})");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A fitted joint stiffness is written with `springref` at the keyframe position it was fitted
/// about (MuJoCo's spring otherwise pulls towards 0), in the file's angle unit; compiled, the
/// written model's `qpos_spring` is the keyframe's.
#[test]
fn a_fitted_stiffness_is_written_with_its_springref_at_the_keyframe() {
    let dir = std::env::temp_dir().join(format!("modellint-wb-spring-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for compiler in [r#"<compiler angle="radian"/>"#, ""] {
        let xml = ARM.replace("<mujoco>", &format!("<mujoco>{compiler}")).replace(
            "</actuator>",
            r#"</actuator><keyframe><key qpos="0.5 -1.2" ctrl="0.5 -1.2"/></keyframe>"#,
        );
        let path = dir.join("arm.xml");
        std::fs::write(&path, &xml).unwrap();
        let load = |p: &std::path::Path| {
            let mut map = crate::model::source::SourceMap::default();
            crate::model::load(&mut map, p, None).unwrap()
        };
        let robot = load(&path);
        let sel = vec![selected("joint_stiffness", "elbow", &[3.0])];
        let (text, warnings) = edit_mjcf(&xml, &robot, &sel).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert!(text.contains(r#"stiffness="3""#), "{text}");
        let out = dir.join("out.xml");
        std::fs::write(&out, &text).unwrap();
        let written = load(&out);
        let j = written.joint("elbow").unwrap();
        let spring = written.mj.qpos_spring()[j.qposadr];
        // keyframe qpos is in radians whatever the compiler's angle unit
        assert!((spring - -1.2).abs() < 1e-6, "{compiler}: qpos_spring {spring}\n{text}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A body effect's component the output reports as not identified is written as the model has
/// it (its nominal value), not at the value the fitted replay keeps; the others as fitted; a
/// note and a comment beside the `<inertial>` say so, and the actuator TOML lists it.
#[test]
fn an_unidentified_body_component_is_written_as_the_model_has_it() {
    let dir = std::env::temp_dir().join(format!("modellint-wb-unid-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("arm.xml");
    std::fs::write(&path, ARM).unwrap();
    let load = |p: &std::path::Path| {
        let mut map = crate::model::source::SourceMap::default();
        crate::model::load(&mut map, p, None).unwrap()
    };
    let robot = load(&path);
    let mut s = selected("com_offset", "elbow", &[0.02, -0.01]);
    s.unidentified = vec!["along".into()];
    s.identifiable = false;
    let (text, warnings) = edit_mjcf(ARM, &robot, std::slice::from_ref(&s)).unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("com_offset on elbow: not identified, written as the model has it: along = 0 m (the fitted replay keeps 0.02)"), "{warnings:?}");
    assert!(text.contains("<!-- modellint fit: com_offset on elbow: not identified"), "{text}");
    let out = dir.join("out.xml");
    std::fs::write(&out, &text).unwrap();
    let written = load(&out);
    let at = |p: &[f64]| {
        let a = [Applied {
            effect: by_id("com_offset").unwrap(),
            joints: s.joints.clone(),
            params: p.to_vec(),
        }];
        inertial::read(&model_with(&robot, &a), 2).unwrap().1
    };
    let c = inertial::read(&written.mj, 2).unwrap().1;
    let (nominal, fitted) = (at(&[0.0, -0.01]), at(&[0.02, -0.01]));
    assert!((c - nominal).norm() < 1e-8, "written {c:?}, along at the model's {nominal:?}");
    assert!((c - fitted).norm() > 0.019, "not the fitted replay's along {fitted:?}");
    assert!((c - inertial::read(&robot.mj, 2).unwrap().1).norm() > 0.009, "across is written");
    let toml = actuators_toml(std::slice::from_ref(&s));
    assert!(toml.contains("unidentified = [\"along\"]"), "{toml}");
    std::fs::remove_dir_all(&dir).ok();
}
