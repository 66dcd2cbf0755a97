//! The classes of issue 45 the fifteenth round left open, end to end from the CLI on fixtures
//! written from the class: which joints a finding names, and its numbers, are worked out here
//! from the fixtures' written text (ranges, `ref`, keyframes, masses, springs), not read from the
//! tool.

mod common;

use common::lint::{findings, measured, message, of, real_robot_files};
use common::xml_text::{attr, tags};

const KS: &str = "fixtures/rules/keyframe-state/";
const PF: &str = "fixtures/rules/passive-joint-friction/";

fn nums(s: &str) -> Vec<f64> {
    s.split_whitespace().map(|x| x.parse().unwrap()).collect()
}

/// Every joint of a fixture whose joints are all hinges or slides written in tree order (one
/// qpos each): (name, range if written, qpos0 = its `ref` or 0).
fn scalar_joints(text: &str) -> Vec<(String, Option<[f64; 2]>, f64)> {
    tags(text, "joint")
        .into_iter()
        .filter(|t| attr(t, "name").is_some())
        .map(|t| {
            let r = attr(t, "range").map(nums).map(|v| [v[0], v[1]]);
            let q0 = attr(t, "ref").map_or(0.0, |x| x.parse().unwrap());
            (attr(t, "name").unwrap().to_string(), r, q0)
        })
        .collect()
}

/// How far `x` lies outside `r`, and whether that is past the rule's default tolerance (2 % of
/// the range).
fn past(r: [f64; 2], x: f64) -> (f64, bool) {
    let p = (r[0] - x).max(x - r[1]);
    (p, p > 0.02 * (r[1] - r[0]).abs())
}

/// A model with keyframes whose default pose qpos0 lies past some joints' stops: each such
/// joint gets one info finding on qpos0 that names the first keyframe placing it inside (or
/// says none does), with the distance past the stop computed here; joints with no range or
/// whose range holds qpos0 get none.
#[test]
fn default_pose_past_a_stop_is_told_as_info_when_a_keyframe_exists() {
    let file = format!("{KS}invalid_default_pose_with_keyframe.xml");
    let text = std::fs::read_to_string(&file).unwrap();
    let joints = scalar_joints(&text);
    let keys: Vec<(String, Vec<f64>)> = tags(&text, "key")
        .into_iter()
        .map(|k| (attr(k, "name").unwrap().to_string(), nums(attr(k, "qpos").unwrap())))
        .collect();
    assert!(keys.len() >= 2 && keys.iter().all(|k| k.1.len() == joints.len()));
    let all = findings(&file);
    let info: Vec<_> = of(&all, "keyframe-state")
        .into_iter()
        .filter(|f| message(f).starts_with("the default pose qpos0"))
        .collect();
    assert!(info.iter().all(|f| f["severity"] == "info"), "{info:#?}");
    let mut expected = 0;
    let (mut named_key, mut named_none) = (false, false);
    for (i, (name, range, q0)) in joints.iter().enumerate() {
        let mine: Vec<_> =
            info.iter().filter(|f| message(f).contains(&format!("joint `{name}` "))).collect();
        let Some(r) = range else {
            assert!(mine.is_empty(), "{name} has no range: {mine:#?}");
            continue;
        };
        let (p, out) = past(*r, *q0);
        if !out {
            assert!(mine.is_empty(), "{name}: qpos0 {q0} inside {r:?}: {mine:#?}");
            continue;
        }
        expected += 1;
        assert_eq!(mine.len(), 1, "{name}: {info:#?}");
        let msg = message(mine[0]);
        assert!((measured(mine[0]) - p).abs() < 1e-9, "{name}: {p} vs {msg}");
        match keys.iter().find(|(_, q)| !past(*r, q[i]).1) {
            Some((k, _)) => {
                named_key = true;
                assert!(msg.contains(&format!("keyframe `{k}` places it inside")), "{msg}");
            }
            None => {
                named_none = true;
                assert!(msg.contains("no keyframe places it inside either"), "{msg}");
            }
        }
    }
    assert_eq!(info.len(), expected, "{info:#?}");
    assert!(expected >= 3 && named_key && named_none, "the fixture must vary the cases");
}

/// Both qpos0 (through a joint's `ref`) and the keyframe inside the ranges: nothing. Without a
/// keyframe a default pose past a stop stays a warning (the only start the model offers).
#[test]
fn default_pose_inside_or_without_keyframe_keeps_its_verdict() {
    let file = format!("{KS}valid_default_pose_and_keyframe_inside.xml");
    let text = std::fs::read_to_string(&file).unwrap();
    let joints = scalar_joints(&text);
    assert!(joints.iter().any(|(_, r, q0)| r.is_some_and(|r| past(r, 0.0).1 && !past(r, *q0).1)));
    assert!(joints.iter().all(|(_, r, q0)| r.is_none_or(|r| !past(r, *q0).1)));
    let all = findings(&file);
    assert!(of(&all, "keyframe-state").is_empty(), "{all:#?}");

    let file = format!("{KS}invalid_default_pose_outside_range.xml");
    assert!(tags(&std::fs::read_to_string(&file).unwrap(), "key").is_empty());
    let all = findings(&file);
    let f = of(&all, "keyframe-state");
    assert_eq!(f.len(), 1, "{f:#?}");
    assert_eq!(f[0]["severity"], "warning");
}

/// The gripper under the arm's class: the passive joints (no actuator names them) that inherit
/// the class frictionloss are named with their largest own load, worked out here from the
/// written mass, centre of mass (a box at `pos` 0 0 r above the axis, the worst over the range
/// 0..hi: m·g·r·sin hi; a slide along gravity: m·g) and spring (stiffness × springref's distance
/// from the range's nearer end 0).
#[test]
fn passive_joints_held_by_the_arm_friction_are_named_with_their_loads() {
    let file = format!("{PF}invalid_gripper_inherits_arm_friction.xml");
    let text = std::fs::read_to_string(&file).unwrap();
    let driven: Vec<&str> =
        tags(&text, "position").into_iter().filter_map(|a| attr(a, "joint")).collect();
    let all = findings(&file);
    let f = of(&all, "passive-joint-friction");
    assert_eq!(f.len(), 2, "{f:#?}");
    let msgs: Vec<&str> = f.iter().map(|x| message(x)).collect();
    for d in &driven {
        assert!(msgs.iter().all(|m| !m.contains(&format!("{d} ("))), "{d} is driven: {msgs:#?}");
    }
    // Each body of the fixture holds one geom; the passive joints end their chains.
    let g = 9.81;
    let body_geom = |body: &str| {
        let i = text.find(&format!("<body name=\"{body}\"")).unwrap();
        tags(&text[i..], "geom")[0]
    };
    let load = |body: &str, hi: f64, k: f64, springref: f64| {
        let geom = body_geom(body);
        let m: f64 = attr(geom, "mass").unwrap().parse().unwrap();
        let gravity = match attr(geom, "pos") {
            Some(p) => m * g * nums(p)[2] * hi.sin(),
            None => m * g,
        };
        (gravity, k * springref)
    };
    let cases = [
        ("follower_joint", "follower_link", 0.85, 0.0, 0.0, "N·m"),
        ("knuckle_joint", "knuckle_link", 0.85, 0.05, 2.62, "N·m"),
        ("finger_slide", "slide_finger", 0.0, 0.0, 0.0, "N"),
    ];
    for (joint, body, hi, k, sr, unit) in cases {
        let (gr, sp) = load(body, hi, k, sr);
        let msg = msgs.iter().find(|m| m.contains(&format!("{joint} ("))).unwrap();
        let i = msg.find(&format!("{joint} (gravity ")).unwrap() + joint.len() + 10;
        let shown: f64 = msg[i..].split([',', ' ']).next().unwrap().parse().unwrap();
        assert!((shown - gr).abs() <= 0.005 * gr, "{joint}: gravity {gr} vs {msg}");
        if sp > 0.0 {
            let j = msg[i..].find("spring ").unwrap() + i + 7;
            let s: f64 = msg[j..].split(' ').next().unwrap().parse().unwrap();
            assert!((s - sp).abs() <= 0.005 * sp, "{joint}: spring {sp} vs {msg}");
        }
        let fl = if unit == "N" { "frictionloss 2 N " } else { "frictionloss 1 N·m " };
        assert!(msg.starts_with(fl), "{msg}");
        assert!(gr + sp < if unit == "N" { 2.0 } else { 1.0 });
    }
}

/// Friction of the gripper's own (on the joint, or a class no actuated joint uses), passive
/// joints whose gravity or spring exceed the class friction, a roller the ground turns, the
/// driven joints, and the real robots: nothing.
#[test]
fn own_friction_overcome_friction_and_real_robots_are_not_reported() {
    let mut files: Vec<String> =
        ["valid_friction_of_its_own.xml", "valid_loads_overcome_friction.xml"]
            .iter()
            .map(|f| format!("{PF}{f}"))
            .collect();
    files.extend(real_robot_files());
    for file in files {
        let all = findings(&file);
        let f = of(&all, "passive-joint-friction");
        assert!(f.is_empty(), "{file}: {f:#?}");
    }
}
