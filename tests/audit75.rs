//! The classes the sixteenth audit round fixed, end to end from the CLI on fixtures written from
//! the class. The expected sides, tilts and links are worked out here from the fixtures' written
//! values (hip offsets, Euler angles, collision masks), not read from the tool.

mod common;

use common::lint::{findings, measured, message, of};

fn none_of(file: &str, rule: &str) {
    let all = findings(file);
    assert!(of(&all, rule).is_empty(), "{file}: {:#?}", of(&all, rule));
}

const RFC: &str = "fixtures/rules/root-frame-convention/";

/// Each leg of the biped names its side on its hip, knee and ankle joints and its thigh and
/// shin links (five names), and the other side on its foot link (one). The legs whose five
/// names say left hang from y +0.12 in the valid file: no finding. In the invalid one they
/// hang from y −0.12: left lies along −y, 2 × 0.12 = 0.24 m from the right hips, 180° off +y.
#[test]
fn a_leg_is_on_the_side_most_of_its_names_give() {
    none_of(&format!("{RFC}valid_urdf_foot_named_other_side.urdf"), "root-frame-convention");
    let all = findings(&format!("{RFC}invalid_urdf_foot_named_other_side_facing_back.urdf"));
    let m = of(&all, "root-frame-convention");
    assert_eq!(m.len(), 1, "{all:#?}");
    let msg = message(m[0]);
    assert!(msg.contains("left is −y (2 left and right hips at one end compared: 0.24 m"), "{msg}");
    assert!((measured(m[0]) - 180.0).abs() < 1e-6, "{}", measured(m[0]));
}

const FCG: &str = "fixtures/rules/foot-collision-geometry/";

/// The box soles are turned by the ankle bodies' Euler angles: 0.45 rad (25.78°) in pitch on
/// the left, 0.35 rad (20.05°) in roll on the right. With no keyframe (qpos0) each sole is a
/// whole box face, and the tilt is still `toe-tilt`'s finding; the keyframe that holds the
/// same pose makes it the stance, and the left sole, past the 15° a foot settles through,
/// stands on its edge.
#[test]
fn a_box_sole_tilted_at_qpos0_is_a_sole_and_its_tilt_is_toe_tilts() {
    let valid = format!("{FCG}valid_box_soles_tilted_at_qpos0.xml");
    let all = findings(&valid);
    assert!(of(&all, "foot-collision-geometry").is_empty(), "{all:#?}");
    let tilt = of(&all, "toe-tilt");
    let left = tilt.iter().find(|f| message(f).contains("left_sole")).expect("left sole tilt");
    assert!((measured(left) - 0.45_f64.to_degrees()).abs() < 0.1, "{}", measured(left));
    assert!(message(left).contains("at qpos0"), "{}", message(left));
    let all = findings(&format!("{FCG}invalid_box_soles_tilted_in_keyframe.xml"));
    let m = of(&all, "foot-collision-geometry");
    assert!(
        m.iter().any(|f| message(f)
            .starts_with("left foot (left_ankle_link) touches the ground along a line")),
        "{m:#?}"
    );
    // The capsule line foot with no keyframe stays a line: a sole modelled too thin.
    let all = findings(&format!("{FCG}invalid_humanoid_line_foot.xml"));
    assert_eq!(of(&all, "foot-collision-geometry").len(), 2, "{all:#?}");
    // A plate turned 60° at qpos0 (the right knee's zero, 0.08 × 0.04 × 0.01 m half-sizes)
    // stands on its 0.04 × 0.01 end face, not its largest: still the line it touches along.
    let all = findings("fixtures/rules/mirror-asymmetry/invalid_joint_zero_turned.xml");
    let m = of(&all, "foot-collision-geometry");
    assert_eq!(m.len(), 1, "{m:#?}");
    assert!(message(m[0]).starts_with("right foot (right_foot) touches the ground along a line"));
    // Shank boxes (24 × 24 × 197 mm) that end past a quadruped's foot spheres stand on an end
    // face: no sole, no heel or toe to miss.
    let all = findings("fixtures/rules/toe-tilt/invalid_urdf_shank_box_past_foot_sphere.urdf");
    assert!(of(&all, "foot-collision-geometry").is_empty(), "{all:#?}");
}

const LWC: &str = "fixtures/rules/links-without-collision/";

/// Every leg carries a hip and a knee hinge above its wheel: the wheels end legs, and the base
/// box, drawn only (contype = conaffinity = 0), is the one bare link. Its skeleton runs from its
/// origin to the hips at (±0.1, ±0.07), 0.122 m, whose last 15 mm the thigh capsules cover, and
/// to the ends of the box's longest half-size, 0.14 m along x, which nothing covers: 0.14 m bare.
/// The rover's wheels turn on the base itself: not a legged robot, not judged.
#[test]
fn a_wheel_at_the_end_of_a_leg_is_a_foot() {
    let all = findings(&format!("{LWC}invalid_wheel_legged_bare_base.xml"));
    let m = of(&all, "links-without-collision");
    assert_eq!(m.len(), 1, "{all:#?}");
    let msg = message(m[0]);
    assert!(msg.starts_with("1 link of the legged robot has no collision geometry while its 4 feet collide: base_link"), "{msg}");
    let bare: f64 = msg
        .split("base_link (")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or(f64::NAN);
    assert!((bare - 0.14).abs() < 0.005, "{msg}");
    none_of(&format!("{LWC}valid_wheel_legged.xml"), "links-without-collision");
    none_of(&format!("{LWC}valid_rover_bare_body.xml"), "links-without-collision");
}
