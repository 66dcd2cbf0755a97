//! The classes of issue 45 the sixteenth round left open, end to end from the CLI on fixtures
//! written from the class: which bodies, links and joints a finding names, and its numbers, are
//! worked out here from the fixtures' written text (ball joints and `connect` equalities, URDF
//! shapes and fixed joints, `<limit>` attributes), not read from the tool.

mod common;

use common::lint::{findings, measured, message, of, real_robot_files};
use common::xml_text::{attr, tags};

const FC: &str = "fixtures/rules/foot-collision-geometry/";
const DD: &str = "fixtures/rules/default-density-mass/";
const PL: &str = "fixtures/rules/placeholder-joint-limits/";

/// The names of the bodies a fixture puts on ball joints and ties by a `connect` equality (its
/// push rods), read from the text: a `<body name=…>` whose next start tag is a ball joint.
fn push_rods(text: &str) -> Vec<String> {
    let connected: Vec<&str> = tags(text, "connect")
        .into_iter()
        .flat_map(|t| [attr(t, "body1"), attr(t, "body2")])
        .flatten()
        .collect();
    let mut rods = Vec::new();
    for (i, _) in text.match_indices("<body name=\"") {
        let name = attr(&text[i..], "name").unwrap();
        let rest = &text[i + 1..];
        let next = &rest[rest.find('<').unwrap()..];
        let ball = next.starts_with("<joint") && attr(next, "type") == Some("ball");
        if ball && connected.contains(&name) {
            rods.push(name.to_string());
        }
    }
    rods
}

/// A humanoid whose feet are driven through push rods named "toe" (Digit's `*-toe-A-rod`): the
/// rods (ball joints closed by `connect` equalities) are not part of the foot, so the flat box
/// sole from heel to toe is judged alone and passes; with a line sole the finding names the
/// body that holds the sole, never a rod or the crank matched first by its name.
#[test]
fn push_rods_named_toes_are_no_part_of_the_foot() {
    let valid = format!("{FC}valid_push_rods_named_toes.xml");
    let text = std::fs::read_to_string(&valid).unwrap();
    let rods = push_rods(&text);
    assert_eq!(rods.len(), 4, "{rods:?}");
    assert!(rods.iter().all(|r| r.contains("toe")), "{rods:?}");
    let all = findings(&valid);
    assert!(of(&all, "foot-collision-geometry").is_empty(), "{all:#?}");

    let invalid = format!("{FC}invalid_push_rods_line_sole.xml");
    let text = std::fs::read_to_string(&invalid).unwrap();
    assert_eq!(push_rods(&text), rods);
    let all = findings(&invalid);
    let feet = of(&all, "foot-collision-geometry");
    assert_eq!(feet.len(), 2, "{feet:#?}");
    for side in ["left", "right"] {
        // The body whose geom is the side's sole, from the text: the last body opened before it.
        let at = text.find(&format!("name=\"{side}-sole\"")).unwrap();
        let holder = attr(&text[text[..at].rfind("<body ").unwrap()..], "name").unwrap();
        let f = feet.iter().find(|f| message(f).starts_with(&format!("{side} foot"))).unwrap();
        let msg = message(f);
        assert!(msg.starts_with(&format!("{side} foot ({holder})")), "{msg}");
        assert!(msg.contains("along a line"), "{msg}");
        // The toe roll link can turn the foot about its line: named as the joint at the foot.
        assert!(msg.contains(&format!("joint `{holder}`")), "{msg}");
    }
    for f in &feet {
        assert!(!rods.iter().any(|r| message(f).contains(r.as_str())), "{f:#?}");
    }
}

/// The real robots' feet (toes on hinges with their own sole geoms) are judged as before: no
/// foot of theirs is found on a push rod.
#[test]
fn real_robots_feet_are_not_push_rods() {
    for file in real_robot_files() {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        let rods = push_rods(&text);
        for f in of(&findings(&file), "foot-collision-geometry") {
            assert!(!rods.iter().any(|r| message(f).contains(r.as_str())), "{file}: {f:#?}");
        }
    }
}

/// The volume of a URDF `<geometry>` child written as text (box, cylinder, sphere), m³.
fn volume(collision: &str) -> f64 {
    let nums = |s: &str| -> Vec<f64> { s.split_whitespace().map(|x| x.parse().unwrap()).collect() };
    if let Some(b) = tags(collision, "box").first() {
        return nums(attr(b, "size").unwrap()).iter().product();
    }
    if let Some(c) = tags(collision, "cylinder").first() {
        let r: f64 = attr(c, "radius").unwrap().parse().unwrap();
        let l: f64 = attr(c, "length").unwrap().parse().unwrap();
        return std::f64::consts::PI * r * r * l;
    }
    let s = tags(collision, "sphere")[0];
    let r: f64 = attr(s, "radius").unwrap().parse().unwrap();
    4.0 / 3.0 * std::f64::consts::PI * r.powi(3)
}

/// Each `<link>` element's text, by name.
fn links(text: &str) -> Vec<(String, String)> {
    text.match_indices("<link name=\"")
        .map(|(i, _)| {
            let name = attr(&text[i..], "name").unwrap().to_string();
            let head = &text[i..i + text[i..].find('>').unwrap()];
            let body = if head.ends_with('/') {
                String::new()
            } else {
                text[i..i + text[i..].find("</link>").unwrap()].to_string()
            };
            (name, body)
        })
        .collect()
}

/// (type, parent, child) of every URDF joint, from the text.
fn joints(text: &str) -> Vec<(String, String, String)> {
    text.match_indices("<joint name=\"")
        .map(|(i, _)| {
            let j = &text[i..i + text[i..].find("</joint>").unwrap()];
            let link_of = |t: &str| attr(tags(j, t)[0], "link").unwrap().to_string();
            (attr(j, "type").unwrap().to_string(), link_of("parent"), link_of("child"))
        })
        .collect()
}

/// A URDF arm whose links state no `<inertial>`: one finding naming each moving link (the child
/// of a revolute joint) with the links a fixed joint fuses into it, and in all the mass of water
/// that fills their collision shapes (1000 kg/m³), computed here from the shapes' written sizes;
/// the base, fixed to the world, and its visual geoms do not count. The same arm with its
/// inertials stated gets none.
#[test]
fn urdf_links_without_inertial_are_weighed_as_water() {
    let file = format!("{DD}invalid_urdf_links_without_inertial.urdf");
    let text = std::fs::read_to_string(&file).unwrap();
    let links = links(&text);
    let joints = joints(&text);
    let water = |name: &str| -> f64 {
        let body = &links.iter().find(|l| l.0 == name).unwrap().1;
        assert!(!body.contains("<inertial"), "{name}");
        body.split("<collision>").skip(1).map(|c| 1000.0 * volume(c)).sum()
    };
    let mut expected = 0.0;
    let mut moving = Vec::new();
    for (_, _, child) in joints.iter().filter(|j| j.0 == "revolute") {
        let fused: Vec<&String> =
            joints.iter().filter(|j| j.0 == "fixed" && &j.1 == child).map(|j| &j.2).collect();
        expected += water(child) + fused.iter().map(|f| water(f)).sum::<f64>();
        moving.push((child.clone(), fused));
    }
    assert_eq!(moving.len(), 3);
    let all = findings(&file);
    let mine = of(&all, "default-density-mass");
    assert_eq!(mine.len(), 1, "{all:#?}");
    let f = mine[0];
    let msg = message(f);
    assert!((measured(f) - expected).abs() < 1e-6 * expected, "{expected} kg vs {msg}");
    assert_eq!(f["data"]["links"].as_f64(), Some(3.0), "{f:#?}");
    assert!(msg.contains("all the mass of its moving links"), "{msg}");
    for (link, fused) in &moving {
        assert!(msg.contains(&format!("`{link}`")), "{link}: {msg}");
        for x in fused {
            assert!(msg.contains(&format!("`{link}` (with {x})")), "{x}: {msg}");
        }
    }
    assert!(!msg.contains("`base`"), "{msg}");

    let valid = format!("{DD}valid_urdf_inertials_stated.urdf");
    assert!(of(&findings(&valid), "default-density-mass").is_empty());
}

/// `velocity="0"` with a positive `effort` on a joint no `<transmission>` drives: one finding
/// naming exactly those joints (from the fixture's `<limit>`s); a passive joint's `effort="0"
/// velocity="0"` and a joint with a speed are not named.
#[test]
fn velocity_zero_with_an_effort_is_a_motor_that_cannot_move() {
    let file = format!("{PL}invalid_urdf_velocity_zero_with_effort.urdf");
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(!text.contains("<transmission name"));
    let mut stalled = Vec::new();
    let mut other = Vec::new();
    for (i, _) in text.match_indices("<joint name=\"") {
        let j = &text[i..i + text[i..].find("</joint>").unwrap()];
        let name = attr(j, "name").unwrap().to_string();
        let limit = tags(j, "limit")[0];
        let v: f64 = attr(limit, "velocity").unwrap().parse().unwrap();
        let e: f64 = attr(limit, "effort").unwrap().parse().unwrap();
        if v == 0.0 && e > 0.0 { stalled.push(name) } else { other.push(name) }
    }
    assert_eq!((stalled.len(), other.len()), (3, 2));
    let all = findings(&file);
    let zero: Vec<_> = of(&all, "placeholder-joint-limits")
        .into_iter()
        .filter(|f| message(f).contains("speed limit of 0"))
        .collect();
    assert_eq!(zero.len(), 1, "{all:#?}");
    let msg = message(zero[0]);
    assert_eq!(zero[0]["data"]["joints"].as_f64(), Some(stalled.len() as f64), "{msg}");
    for j in &stalled {
        assert!(msg.contains(&format!("`{j}` effort ")), "{j}: {msg}");
    }
    for j in &other {
        assert!(!msg.contains(&format!("`{j}`")), "{j}: {msg}");
    }
}
