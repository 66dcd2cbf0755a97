//! The classes the eighteenth audit round (issue 45) found missed, end to end from the CLI on
//! fixtures written from the class: which links a finding names and its heights are worked out
//! here from the fixtures' written text (geom classes and sizes, URDF joint origins and
//! shapes), not read from the tool.

mod common;

use common::lint::{findings, message, of, real_robot_files};
use common::xml_text::{attr, bodies_with_geoms, tags};

const LW: &str = "fixtures/rules/links-without-collision/";
const WL: &str = "fixtures/rules/welded-legged-base/";

fn nums(s: &str) -> Vec<f64> {
    s.split_whitespace().map(|x| x.parse().unwrap()).collect()
}

/// A geom's longest extent from its written size: a box's longest side, a capsule's length
/// with its caps, a cylinder's longer of diameter and length, a sphere's diameter.
fn extent(geom: &str) -> f64 {
    let size = nums(attr(geom, "size").unwrap());
    match attr(geom, "type").unwrap() {
        "box" => 2.0 * size.iter().copied().fold(0.0, f64::max),
        "capsule" => {
            let p = nums(attr(geom, "fromto").unwrap());
            let len =
                ((p[3] - p[0]).powi(2) + (p[4] - p[1]).powi(2) + (p[5] - p[2]).powi(2)).sqrt();
            len + 2.0 * size[0]
        }
        "cylinder" => (2.0 * size[0]).max(2.0 * size[1]),
        _ => 2.0 * size[0],
    }
}

/// A biped whose shanks end in colliding foot spheres and carry the drawn rods of an open knee
/// linkage (Leggy): the shanks are its feet though they are no leaves of the body tree, so the
/// long links drawn only (trunk, thighs) are named; the short drawn parts (hips, cranks, rods)
/// are not. With the trunk and thighs colliding, nothing is reported.
#[test]
fn shank_carrying_an_open_rod_is_a_foot() {
    let invalid = format!("{LW}invalid_shank_carries_open_rod.xml");
    let text = std::fs::read_to_string(&invalid).unwrap();
    let bodies = bodies_with_geoms(&text);
    // The feet, from the text: the bodies with a colliding geom; each carries a child body.
    let feet: Vec<&str> = bodies
        .iter()
        .filter(|(_, g)| g.iter().any(|g| attr(g, "class") == Some("col")))
        .map(|(n, _)| n.as_str())
        .collect();
    assert_eq!(feet, ["lshank", "rshank"]);
    for foot in &feet {
        let at = text.find(&format!("<body name=\"{foot}\"")).unwrap();
        let own_end = text[at..].find("</body>").unwrap();
        assert!(text[at + 1..at + own_end].contains("<body "), "{foot} carries no child");
    }
    // The drawn-only bodies, split by their longest geom: 0.2 m and more against 0.11 m and less.
    let drawn: Vec<(&str, f64)> = bodies
        .iter()
        .filter(|(_, g)| !g.is_empty() && g.iter().all(|g| attr(g, "class") == Some("vis")))
        .map(|(n, g)| (n.as_str(), g.iter().map(|g| extent(g)).fold(0.0, f64::max)))
        .collect();
    let long: Vec<&str> = drawn.iter().filter(|d| d.1 >= 0.2).map(|d| d.0).collect();
    let short: Vec<&str> = drawn.iter().filter(|d| d.1 <= 0.11).map(|d| d.0).collect();
    assert_eq!(long, ["body", "lthigh", "rthigh"]);
    assert_eq!(short.len() + long.len(), drawn.len(), "{drawn:?}");

    let all = findings(&invalid);
    let bare = of(&all, "links-without-collision");
    assert_eq!(bare.len(), 1, "{all:#?}");
    let msg = message(bare[0]);
    assert!(msg.contains(&format!("its {} feet collide", feet.len())), "{msg}");
    for name in &long {
        assert!(msg.contains(&format!("{name} (")), "{name}: {msg}");
    }
    for name in &short {
        assert!(!msg.contains(&format!("{name} (")), "{name}: {msg}");
    }

    let valid = format!("{LW}valid_shank_carries_open_rod.xml");
    let all = findings(&valid);
    assert!(of(&all, "links-without-collision").is_empty(), "{all:#?}");
}

/// A URDF biped whose root link is a frame at the ground (Darwin-OP's `base_link`, a fixed joint
/// 0.35 m below its trunk): its feet hang below the hips, not below the root frame, and are
/// legs; the height above the root frame is the fixed joint's, the hip's and the knee's offsets
/// and the foot sphere's, from the text. Two arms hanging from a pedestal that stands on the
/// ground (its box the lowest point) are no legs.
#[test]
fn root_frame_at_the_ground_under_the_trunk() {
    let invalid = format!("{WL}invalid_root_frame_at_ground.urdf");
    let text = std::fs::read_to_string(&invalid).unwrap();
    let origin_z = |joint: &str| {
        let at = text.find(&format!("<joint name=\"{joint}\"")).unwrap();
        let origin = tags(&text[at..], "origin")[0];
        nums(attr(origin, "xyz").unwrap())[2]
    };
    let shank = text.find("<link name=\"left_shank\">").unwrap();
    let shank_text = &text[shank..shank + text[shank..].find("</link>").unwrap()];
    let sphere_at = shank_text.find("<sphere ").unwrap();
    let foot_origin =
        tags(&shank_text[..sphere_at], "origin").last().map(|o| nums(attr(o, "xyz").unwrap())[2]);
    let radius: f64 = attr(&shank_text[sphere_at..], "radius").unwrap().parse().unwrap();
    let lowest = origin_z("base_link_to_trunk")
        + origin_z("left_hip")
        + origin_z("left_knee")
        + foot_origin.unwrap()
        - radius;
    assert!(lowest > 0.0, "the fixture's feet must lie above its root frame: {lowest}");

    let all = findings(&invalid);
    let welded = of(&all, "welded-legged-base");
    assert_eq!(welded.len(), 1, "{all:#?}");
    let msg = message(welded[0]);
    assert!(msg.contains("`base_link`"), "{msg}");
    assert!(msg.contains("`left_shank`, `right_shank`"), "{msg}");
    let why = welded[0]["note"].as_str().unwrap_or("");
    let shown = (lowest * 1000.0).round() / 1000.0;
    assert!(why.contains(&format!("{shown} m above the root link's frame")), "{lowest}: {why}");

    let valid = format!("{WL}valid_root_frame_at_ground_two_arms.urdf");
    let all = findings(&valid);
    for rule in ["welded-legged-base", "legged-urdf-armature"] {
        assert!(of(&all, rule).is_empty(), "{rule}: {all:#?}");
    }
}

/// The real robots (bipeds whose feet are leaves, or whose children collide: toes) keep two feet
/// each: a body that carries links colliding below it is still no foot, so a finding of
/// `links-without-collision`, where one is made (Asimov's bare legs), counts two.
#[test]
fn real_robots_keep_two_feet() {
    for file in real_robot_files() {
        let all = findings(&file);
        for f in of(&all, "links-without-collision") {
            assert!(message(f).contains("its 2 feet collide"), "{file}: {f:#?}");
        }
    }
}

/// A URDF whose `<dynamics damping>` × `<limit velocity>` exceeds `<limit effort>` on a joint
/// (the Unitree Qmini's hip yaw, knee and ankle): each such joint is named with the speed its
/// damping stops it at, effort / damping, all worked out from the text; joints whose damping
/// leaves the effort room, and a passive joint (effort 0, velocity 0), are not.
#[test]
fn urdf_damping_caps_the_stated_velocity() {
    const EL: &str = "fixtures/rules/effort-limit-mismatch/";
    let invalid = format!("{EL}invalid_urdf_damping_caps_velocity.urdf");
    let text = std::fs::read_to_string(&invalid).unwrap();
    let mut capped = Vec::new();
    let mut free = Vec::new();
    for (i, _) in text.match_indices("<joint name=\"") {
        let name = attr(&text[i..], "name").unwrap();
        let body = &text[i..i + text[i..].find("</joint>").unwrap()];
        let num = |tag: &str, a: &str| -> f64 {
            tags(body, tag).first().and_then(|t| attr(t, a)).map_or(0.0, |v| v.parse().unwrap())
        };
        let (d, e, v) =
            (num("dynamics", "damping"), num("limit", "effort"), num("limit", "velocity"));
        if d > 0.0 && e > 0.0 && v > 0.0 && d * v > e {
            capped.push((name, e / d, v));
        } else {
            free.push(name);
        }
    }
    assert_eq!(capped.iter().map(|c| c.0).collect::<Vec<_>>(), ["hip_yaw", "ankle"]);
    let all = findings(&invalid);
    let found = of(&all, "effort-limit-mismatch");
    assert_eq!(found.len(), capped.len(), "{all:#?}");
    for (name, terminal, v) in &capped {
        let f = found.iter().find(|f| message(f).starts_with(&format!("joint `{name}` "))).unwrap();
        assert!((f["measured"]["value"].as_f64().unwrap() - terminal).abs() < 1e-9, "{f:#?}");
        assert!(message(f).contains(&format!("velocity limit {v} rad/s")), "{f:#?}");
    }
    for name in &free {
        assert!(!found.iter().any(|f| message(f).contains(&format!("`{name}`"))), "{name}");
    }

    let valid = format!("{EL}valid_urdf_damping_below_velocity.urdf");
    let all = findings(&valid);
    assert!(of(&all, "effort-limit-mismatch").is_empty(), "{all:#?}");
}
