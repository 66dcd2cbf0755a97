//! The classes the twentieth audit round (issue 45) found, end to end from the CLI on fixtures
//! written from the class: the feet, legs, joints and lengths a finding must name are worked
//! out here from the fixtures' written text (body names and sphere sizes, URDF link names and
//! `<limit>` values, tendon coefficients and joint ranges), not read from the tool.

mod common;

use common::lint::{findings, message, of, of_message, real_robot_files};
use common::xml_text::{attr, tags};

const FC: &str = "fixtures/rules/foot-collision-geometry/";
const WL: &str = "fixtures/rules/welded-legged-base/";
const PJ: &str = "fixtures/rules/placeholder-joint-limits/";
const AM: &str = "fixtures/rules/actuator-mapping/";

fn nums(s: &str) -> Vec<f64> {
    s.split_whitespace().map(|x| x.parse().unwrap()).collect()
}

fn read(p: &str) -> String {
    std::fs::read_to_string(p).unwrap()
}

/// The URDF's revolute joints in file order: (name, lower, upper, effort, velocity).
fn urdf_limits(text: &str) -> Vec<(String, f64, f64, f64, f64)> {
    let mut out = Vec::new();
    for (i, _) in text.match_indices("<joint name=\"") {
        let tag = &text[i..];
        if attr(tag, "type") != Some("revolute") {
            continue;
        }
        let body = &tag[..tag.find("</joint>").unwrap()];
        let limit = tags(body, "limit")[0];
        let v = |a: &str| attr(limit, a).unwrap().parse::<f64>().unwrap();
        out.push((
            attr(tag, "name").unwrap().to_string(),
            v("lower"),
            v("upper"),
            v("effort"),
            v("velocity"),
        ));
    }
    out
}

/// A quadruped whose legs are named by side words after the limb (`toe_front_left`,
/// `toe_back_left`, dm_control's quadruped): each toe body ends its own leg, so there are four
/// point feet and no humanoid; the one oversized toe sphere is named alone.
#[test]
fn side_word_quadruped_has_four_feet() {
    let valid = format!("{FC}valid_quadruped_side_word_legs.xml");
    let invalid = format!("{FC}invalid_quadruped_side_word_legs_radius.xml");
    for file in [&valid, &invalid] {
        let text = read(file);
        let toes: Vec<&str> =
            tags(&text, "geom").into_iter().filter(|g| attr(g, "type") == Some("sphere")).collect();
        assert_eq!(toes.len(), 4, "{file}: four toe spheres");
        let big: Vec<&str> = toes
            .iter()
            .filter(|g| nums(attr(g, "size").unwrap())[0] > 0.05)
            .map(|g| attr(g, "name").unwrap())
            .collect();
        let all = findings(file);
        let feet = of(&all, "foot-collision-geometry");
        assert!(feet.iter().all(|f| !message(f).contains("humanoid")), "{file}: {feet:?}");
        if big.is_empty() {
            assert!(feet.is_empty(), "{file}: {feet:?}");
            continue;
        }
        assert_eq!(big, ["toe_back_right"]);
        assert_eq!(feet.len(), 1, "{file}: {feet:?}");
        let m = message(feet[0]);
        for t in &toes {
            let name = attr(t, "name").unwrap();
            assert_eq!(m.contains(name), big.contains(&name), "{m}");
        }
    }
}

/// Three fingers hanging from a stage above the root link (TriFinger): named as a hand's
/// digits they are no legs, so nothing is welded, no foot rule judges their tips and no leg
/// armature is asked for; the same tree named `leg_*` is three legs.
#[test]
fn fingers_on_a_stage_are_no_legs() {
    let valid = format!("{WL}valid_fingers_on_stage.urdf");
    let invalid = format!("{WL}invalid_legs_from_raised_hub.urdf");
    let vt = read(&valid);
    let lowers = |t: &str| {
        tags(t, "link")
            .into_iter()
            .filter(|l| attr(l, "name").unwrap().contains("lower_link"))
            .count()
    };
    assert_eq!(lowers(&vt), 3);
    assert!(vt.contains("finger_upper_link_0") && !vt.contains("leg_"));
    let all = findings(&valid);
    for rule in [
        "welded-legged-base",
        "foot-collision-geometry",
        "legged-urdf-armature",
        "links-without-collision",
    ] {
        assert!(of(&all, rule).is_empty(), "{rule}: {:?}", of(&all, rule));
    }
    let it = read(&invalid);
    let n = lowers(&it);
    let all = findings(&invalid);
    let w = of(&all, "welded-legged-base");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(message(w[0]).contains(&format!("has {n} legs")), "{}", message(w[0]));
}

/// A fixed-base arm's flange roll (its chain's last joint) may stop up to `flange_max_turns`
/// (1.3) turns out; any other joint beyond one turn, or the flange past 1.3 turns, is named.
#[test]
fn flange_roll_beyond_a_turn() {
    let turn = std::f64::consts::TAU;
    for (file, named) in [
        ("valid_urdf_flange_roll_400deg.urdf", false),
        ("invalid_urdf_wrist_beyond_turn.urdf", true),
    ] {
        let path = format!("{PJ}{file}");
        let joints = urdf_limits(&read(&path));
        let last = joints.last().unwrap().0.clone();
        let expected: Vec<&str> = joints
            .iter()
            .filter(|j| {
                let far = j.1.abs().max(j.2.abs());
                let bound = if j.0 == last { 1.3 * turn } else { turn };
                far > bound + 0.01
            })
            .map(|j| j.0.as_str())
            .collect();
        assert_eq!(!expected.is_empty(), named, "{file}: {expected:?}");
        let names: Vec<&str> = joints.iter().map(|j| j.0.as_str()).collect();
        names_exactly(&path, |m| m.contains("more than a full turn"), &names, &expected);
    }
}

/// The `placeholder-joint-limits` findings of `path` whose message `case` picks: none when
/// `expected` is empty, else one naming exactly the `expected` of `joints`.
fn names_exactly(path: &str, case: impl Fn(&str) -> bool, joints: &[&str], expected: &[&str]) {
    let all = findings(path);
    let hits: Vec<_> =
        of(&all, "placeholder-joint-limits").into_iter().filter(|f| case(message(f))).collect();
    if expected.is_empty() {
        assert!(hits.is_empty(), "{path}: {hits:?}");
        return;
    }
    assert_eq!(hits.len(), 1, "{path}: {hits:?}");
    let m = message(hits[0]);
    for j in joints {
        assert_eq!(m.contains(&format!("`{j}`")), expected.contains(j), "{m}");
    }
}

/// `effort="0"` on every moving joint while the velocities state speeds: each joint with a
/// speed is named; one passive joint among motors is not judged.
#[test]
fn effort_zero_on_every_joint() {
    for (file, named) in [
        ("invalid_urdf_effort_zero_everywhere.urdf", true),
        ("valid_urdf_passive_joint_among_motors.urdf", false),
    ] {
        let path = format!("{PJ}{file}");
        let joints = urdf_limits(&read(&path));
        let all_zero = joints.iter().all(|j| j.3 == 0.0);
        assert_eq!(all_zero, named, "{file}");
        let expected: Vec<&str> =
            joints.iter().filter(|j| all_zero && j.4 > 0.0).map(|j| j.0.as_str()).collect();
        let names: Vec<&str> = joints.iter().map(|j| j.0.as_str()).collect();
        let case = |m: &str| m.starts_with("every moving joint states effort");
        names_exactly(&path, case, &names, &expected);
    }
}

/// A servo on a fixed tendon whose ctrlrange covers the tendon's whole reach and goes past
/// both ends (dm_control's quadruped `lift`) is named; one asking for exactly the reach is not.
#[test]
fn tendon_servo_past_both_ends() {
    for (file, named) in [
        ("invalid_tendon_ctrlrange_past_both_ends.xml", true),
        ("valid_tendon_ctrlrange_equals_reach.xml", false),
    ] {
        let path = format!("{AM}{file}");
        let text = read(&path);
        let range = |j: &str| {
            let tag = tags(&text, "joint")
                .into_iter()
                .find(|t| attr(t, "name") == Some(j) && attr(t, "range").is_some())
                .unwrap();
            nums(attr(tag, "range").unwrap())
        };
        let fixed = &text[text.find("<fixed").unwrap()..text.find("</fixed>").unwrap()];
        let (mut lo, mut hi) = (0.0, 0.0);
        for w in tags(fixed, "joint") {
            let c: f64 = attr(w, "coef").unwrap().parse().unwrap();
            let r = range(attr(w, "joint").unwrap());
            lo += (c * r[0]).min(c * r[1]);
            hi += (c * r[0]).max(c * r[1]);
        }
        let servo = tags(&text, "position")[0];
        let c = nums(attr(servo, "ctrlrange").unwrap());
        let past = c[0] < lo - 1e-3 && c[1] > hi + 1e-3;
        assert_eq!(past, named, "{file}: reach [{lo}, {hi}], ctrlrange {c:?}");
        let reach = of_message(&path, "actuator-mapping", "reachable length");
        assert_eq!(reach.len(), usize::from(named), "{file}: {reach:?}");
    }
}

/// The real robots (Asimov, Booster T1, Unitree H1) have none of these classes: no effort-0 or
/// flange finding, no tendon servo past its reach.
#[test]
fn real_robots_show_none_of_the_classes() {
    for file in real_robot_files() {
        let all = findings(&file);
        for f in &all {
            let m = message(f);
            assert!(!m.starts_with("every moving joint states effort"), "{file}: {m}");
            assert!(!m.contains("reachable length"), "{file}: {m}");
        }
    }
}
