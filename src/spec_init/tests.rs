//! Unit tests of the template's pieces (names, globs, TOML values).
use super::*;

#[test]
fn common_ends_stop_at_word_boundaries() {
    assert_eq!(common_ends("left_knee", "right_knee"), (0, 5));
    assert_eq!(common_ends("Hip_Pitch_Right", "Hip_Pitch_Left"), (10, 0));
    assert_eq!(common_ends("FL_calf", "FR_calf"), (0, 5));
    assert_eq!(common_ends("l_hip_r", "r_hip_r"), (0, 6));
}

#[test]
fn pair_globs_match_exactly_their_pair() {
    let all: Vec<String> =
        ["left_knee", "right_knee", "left_knee2", "waist"].iter().map(|s| s.to_string()).collect();
    assert_eq!(globs(&["left_knee", "right_knee"], &all), vec!["{left,right}_knee"]);
    assert_eq!(globs(&["waist"], &all), vec!["waist"]);
    let odd: Vec<String> = ["a[1]".to_string()].to_vec();
    let g = globs(&["a[1]"], &odd);
    let m = Glob::new(&g[0]).unwrap().compile_matcher();
    assert!(m.is_match("a[1]"));
}

#[test]
fn toml_values_parse() {
    assert_eq!(num(65.0), "65.0");
    assert_eq!(num(39.4), "39.4");
    let v: toml::Value = toml::from_str(&format!("x = {}", quote("a\"b\\c"))).unwrap();
    assert_eq!(v["x"].as_str(), Some("a\"b\\c"));
}

/// A model of hinge legs named `names`, each driven by a position actuator of the same gains.
fn legs(names: &[&str], tag: &str) -> Robot {
    let bodies: String = names
        .iter()
        .map(|n| {
            format!(
                r#"<body name="b_{n}" pos="0 0 -0.1"><joint name="{n}" axis="0 1 0" range="-1 1"/><geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.5"/></body>"#
            )
        })
        .collect();
    let acts: String = names
        .iter()
        .map(|n| format!(r#"<position joint="{n}" kp="40" kv="1" forcerange="-20 20"/>"#))
        .collect();
    let xml = format!(
        r#"<mujoco><worldbody><body name="base"><freejoint/><geom type="box" size="0.1 0.1 0.05" mass="3"/>{bodies}</body></worldbody><actuator>{acts}</actuator></mujoco>"#
    );
    let dir =
        std::env::temp_dir().join(format!("modellint-spec-init-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("legs.xml");
    std::fs::write(&path, xml).expect("write the test model");
    let mut map = crate::model::source::SourceMap::default();
    crate::model::load(&mut map, &path, None).expect("load the test model")
}

#[test]
fn sides_pair_as_lint_pairs_them() {
    // A biped's leg-side prefixes: `LL_` ↔ `LR_`, one group per joint pair.
    let biped = legs(&["LL_HFE", "LR_HFE", "LL_KFE", "LR_KFE"], "biped");
    let groups = pair_up(&biped, &[1, 2, 3, 4]); // joint 0 is the free joint
    assert_eq!(groups, vec![vec!["LL_HFE", "LR_HFE"], vec!["LL_KFE", "LR_KFE"]]);
    assert_eq!(words(&biped, "LR_KFE"), words(&biped, "LL_KFE"));
    // A quadruped's left-rear leg `LR_` is not a biped's right leg (there is no `LL_`).
    let quad = legs(&["LF_KFE", "LR_KFE", "RF_KFE", "RR_KFE"], "quad");
    let groups = pair_up(&quad, &[1, 2, 3, 4]);
    assert_eq!(groups, vec![vec!["LF_KFE", "RF_KFE"], vec!["LR_KFE"], vec!["RR_KFE"]]);
}

#[test]
fn families_take_their_classes_leading_words_not_generic_joint_words() {
    let c = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    // A class and its variant (Menagerie UR5e's size3 and size3_limited) name one family.
    assert_eq!(class_stem(&c(&["size3", "size3_limited"])), "size3");
    assert_eq!(class_stem(&c(&["hip"])), "hip");
    assert_eq!(class_stem(&c(&["arm", "leg"])), "");
    // Joints that share only the word `joint` are named by what else they share, or their
    // effort limit: never "joint".
    let arm = legs(&["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint"], "arm");
    let fam = |joints: Vec<usize>| Family {
        name: String::new(),
        effort: Some(20.0),
        armature: 0.0,
        joints,
        classes: vec![],
        servo: None,
        torque_driven: false,
    };
    let mut fams = vec![fam(vec![1, 2, 3])];
    name_families(&arm, &mut fams);
    assert_eq!(fams[0].name, "effort_20");
    let mut fams = vec![fam(vec![1, 2])];
    name_families(&arm, &mut fams);
    assert_eq!(fams[0].name, "shoulder");
}

#[test]
fn a_tendon_actuators_torque_limit_goes_through_its_coefficients() {
    // A 2F-85-like split: forcerange ±5 N on a fixed tendon with coefficient 0.5 on each
    // finger joint puts 5 × 0.5 = 2.5 N·m on each joint (hand-computed), not 5.
    let finger = |n: &str, x: &str| {
        format!(
            r#"<body name="{n}" pos="{x} 0 -0.03"><joint name="{n}" axis="0 1 0" range="0 0.8"/><geom type="capsule" fromto="0 0 0 0 0 -0.05" size="0.01" mass="0.1"/></body>"#
        )
    };
    let xml = format!(
        r#"<mujoco><worldbody><body name="palm"><geom type="box" size="0.05 0.05 0.02" mass="0.5"/>{}{}</body></worldbody><tendon><fixed name="split"><joint joint="left" coef="0.5"/><joint joint="right" coef="0.5"/></fixed></tendon><actuator><general name="fingers" tendon="split" forcerange="-5 5" ctrlrange="0 255" gainprm="0.3137" biasprm="0 -100 -10" biastype="affine"/></actuator></mujoco>"#,
        finger("left", "0.03"),
        finger("right", "-0.03")
    );
    let dir =
        std::env::temp_dir().join(format!("modellint-spec-init-{}-tendon", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("split.xml");
    std::fs::write(&path, xml).expect("write the test model");
    let mut map = crate::model::source::SourceMap::default();
    let robot = crate::model::load(&mut map, &path, None).expect("load the test model");
    let fams = families(&robot);
    assert!(!fams.is_empty());
    for f in &fams {
        assert_eq!(f.effort, Some(2.5), "{f:?}");
    }
}

#[test]
fn a_joint_an_equality_ties_to_a_motor_is_not_passive() {
    // A hand-written leg: the ankle follows the knee by `<equality><joint>` (a URDF mimic),
    // the toe is free (a real passive joint). Only the toe is written `passive = true`.
    let link = |n: &str, inner: &str| {
        format!(
            r#"<body name="{n}" pos="0 0 -0.2"><joint name="{n}" axis="0 1 0" range="-1 1"/><geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.5"/>{inner}</body>"#
        )
    };
    let xml = format!(
        r#"<mujoco><worldbody><body name="base"><geom type="box" size="0.05 0.05 0.05" mass="1"/>{}</body></worldbody><equality><joint joint1="ankle" joint2="knee" polycoef="0 -0.5 0 0 0"/></equality><actuator><position name="hip" joint="hip" kp="40"/><position name="knee" joint="knee" kp="40"/></actuator></mujoco>"#,
        link("hip", &link("knee", &link("ankle", &link("toe", ""))))
    );
    let dir =
        std::env::temp_dir().join(format!("modellint-spec-init-{}-mimic", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("mimic.xml");
    std::fs::write(&path, xml).expect("write the test model");
    let mut map = crate::model::source::SourceMap::default();
    let robot = crate::model::load(&mut map, &path, None).expect("load the test model");
    let names: Vec<&str> = passive(&robot).iter().map(|&j| robot.joints[j].name.as_str()).collect();
    assert_eq!(names, ["toe"]);
    let spec = template(&robot, "mimic.xml");
    assert!(spec.contains("[joints.\"toe\"]\npassive = true"), "{spec}");
    assert_eq!(spec.matches("passive = true").count(), 1, "{spec}");
}
