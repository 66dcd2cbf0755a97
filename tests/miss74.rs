//! The classes of issue 45 the thirteenth and fourteenth rounds left open, end to end from the
//! CLI on fixtures written from the class: which joints a finding names is worked out here from
//! the fixtures' written text (each joint's attributes and its motor's limit), not read from the
//! tool.

mod common;

use common::lint::{findings, message, of, real_robot_files};
use common::xml_text::{attr, tags};

const DF: &str = "fixtures/rules/drive-friction-mismatch/";

/// The joint list a finding names after `which` ("on 4 (" or "none on 2 ("), unquoted.
fn named(msg: &str, which: &str) -> Vec<String> {
    let i = msg.find(which).unwrap_or_else(|| panic!("{which} in {msg}")) + which.len();
    let list = &msg[i..i + msg[i..].find(')').unwrap()];
    list.split(", ").map(|s| s.trim_matches('`').to_string()).collect()
}

/// The arm: the joints whose motor has ctrlrange -20 20 form the family; those without a
/// written frictionloss are the ones named "none".
#[test]
fn mjcf_joints_of_one_motor_without_its_friction_are_named() {
    let file = format!("{DF}invalid_mjcf_arm_friction_partly.xml");
    let text = std::fs::read_to_string(&file).unwrap();
    let family: Vec<&str> = tags(&text, "motor")
        .into_iter()
        .filter(|m| attr(m, "ctrlrange") == Some("-20 20"))
        .filter_map(|m| attr(m, "joint"))
        .collect();
    let joints = tags(&text, "joint");
    let written = |j: &str| {
        joints.iter().any(|t| attr(t, "name") == Some(j) && attr(t, "frictionloss").is_some())
    };
    let none: Vec<&str> = family.iter().copied().filter(|j| !written(j)).collect();
    let with: Vec<&str> = family.iter().copied().filter(|j| written(j)).collect();
    assert!(!none.is_empty() && with.len() >= 2, "the fixture must hold both");
    let all = findings(&file);
    let f = of(&all, "drive-friction-mismatch");
    assert_eq!(f.len(), 1, "{f:#?}");
    let msg = message(f[0]);
    assert!(msg.contains(&format!("the {} joints", family.len())), "{msg}");
    assert!(msg.contains("`frictionloss` 0.3 N·m"), "{msg}");
    assert_eq!(named(msg, &format!("none on {} (", none.len())), none);
    assert_eq!(named(msg, &format!("on {} (", with.len())), with);
}

/// The servo dog (URDF): all twelve joints state effort 2.5; the joints whose `<dynamics>`
/// writes no damping are the ones named "none", and the friction written on every joint is not
/// reported.
#[test]
fn urdf_joints_of_one_servo_without_its_damping_are_named() {
    let file = format!("{DF}invalid_urdf_servo_damping_partly.urdf");
    let text = std::fs::read_to_string(&file).unwrap();
    let mut with = Vec::new();
    let mut none = Vec::new();
    for (i, _) in text.match_indices("<joint name=\"") {
        let body = &text[i..i + text[i..].find("</joint>").unwrap()];
        let name = attr(body, "name").unwrap();
        assert_eq!(attr(body, "effort"), Some("2.5"), "{body}");
        let dynamics = tags(body, "dynamics");
        assert!(dynamics.iter().all(|d| attr(d, "friction") == Some("0.1")), "{body}");
        if dynamics.iter().any(|d| attr(d, "damping").is_some()) {
            with.push(name);
        } else {
            none.push(name);
        }
    }
    let all = findings(&file);
    let f = of(&all, "drive-friction-mismatch");
    assert_eq!(f.len(), 1, "{f:#?}");
    let msg = message(f[0]);
    assert!(msg.contains("`damping` 0.05 N·m·s/rad"), "{msg}");
    assert_eq!(named(msg, &format!("none on {} (", none.len())), none);
    // The "on N (…)" list shows the first six, then "…".
    let shown = named(msg, &format!("on {} (", with.len()));
    assert_eq!(shown[..6], with[..6]);
    assert_eq!(shown.len(), 7, "{shown:?}");
}

/// With the spec, one motor family `leg_drive` holds the joints its patterns name (`*_hip_*`,
/// `*_knee`), though the knees' force limits (60 N·m) are not the hips' (80): the joints of the
/// family without a written frictionloss are named. The same file linted without its spec has
/// no family of three that differs (four hips, all with friction; two knees): nothing.
#[test]
fn a_spec_family_spans_derated_force_limits() {
    let file = format!("{DF}invalid_spec_family_friction_partly.xml");
    let text = std::fs::read_to_string(&file).unwrap();
    let spec =
        std::fs::read_to_string(format!("{DF}invalid_spec_family_friction_partly.toml")).unwrap();
    assert!(spec.contains("[joints.\"*_hip_*\"]") && spec.contains("[joints.\"*_knee\"]"));
    let joints = tags(&text, "joint");
    let family: Vec<&str> = joints
        .iter()
        .filter_map(|t| attr(t, "name"))
        .filter(|n| n.contains("_hip_") || n.ends_with("_knee"))
        .collect();
    let written = |j: &str| {
        joints.iter().any(|t| attr(t, "name") == Some(j) && attr(t, "frictionloss").is_some())
    };
    let none: Vec<&str> = family.iter().copied().filter(|j| !written(j)).collect();
    let all = findings(&file);
    let f = of(&all, "drive-friction-mismatch");
    assert_eq!(f.len(), 1, "{f:#?}");
    let msg = message(f[0]);
    assert!(msg.contains(&format!("the {} joints", family.len())), "{msg}");
    assert!(msg.contains("the spec's motor `leg_drive`"), "{msg}");
    assert_eq!(named(msg, &format!("none on {} (", none.len())), none);

    let dir = std::env::temp_dir().join(format!("miss74-nospec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let copy = dir.join("legs.xml");
    std::fs::write(&copy, &text).unwrap();
    let all = findings(copy.to_str().unwrap());
    std::fs::remove_dir_all(&dir).ok();
    assert!(of(&all, "drive-friction-mismatch").is_empty(), "{all:#?}");
}

/// Differences with a reason (other motors, a class of its own, a wheel, a passive joint,
/// identified values all above zero, a coupled linkage), one dynamics on every servo joint, and
/// the real robots: nothing.
#[test]
fn explained_differences_and_real_robots_are_not_reported() {
    let mut files = vec![
        format!("{DF}valid_mjcf_differences_explained.xml"),
        format!("{DF}valid_urdf_servo_one_dynamics.urdf"),
    ];
    files.extend(real_robot_files());
    for file in files {
        let all = findings(&file);
        let f = of(&all, "drive-friction-mismatch");
        assert!(f.is_empty(), "{file}: {f:#?}");
    }
}
