//! The classes of issue 45 the twelfth round left open, end to end from the CLI on fixtures
//! written from the class: the expected numbers are worked out here from the fixtures' written
//! values (hip offsets, limits, masses and moments), not read from the tool.

mod common;

use common::lint::{findings, measured, message, of, real_robot_files};

fn none_of(file: &str, rule: &str) {
    let all = findings(file);
    assert!(of(&all, rule).is_empty(), "{file}: {:#?}", of(&all, rule));
}

fn expected(f: &serde_json::Value) -> f64 {
    f["expected"]["value"].as_f64().unwrap_or(f64::NAN)
}

const RFC: &str = "fixtures/rules/root-frame-convention/";

/// Front hips at y +0.1 against rear hips at y −0.1 (forward along +y, 90° from +x); left hips
/// at x −0.05 against right hips at +0.05 (left along −x, 90° from +y). A biped whose left hip
/// sits at y −0.09, the right at +0.09: left along −y, 180° from +y. Legs spread along z and
/// hanging along −y: up along +y.
#[test]
fn a_root_frame_off_rep103_is_reported_with_its_axes() {
    let all = findings(&format!("{RFC}invalid_urdf_y_forward.urdf"));
    let m = of(&all, "root-frame-convention");
    assert_eq!(m.len(), 1, "{m:#?}");
    let msg = message(m[0]);
    assert!(
        msg.contains("forward is +y (4 front and rear hips on one side compared: 0.2 m"),
        "{msg}"
    );
    assert!(msg.contains("left is −x (4 left and right hips at one end compared: 0.1 m"), "{msg}");
    assert!(!msg.contains("up is"), "{msg}");
    assert!((measured(m[0]) - 90.0).abs() < 1e-6, "{}", measured(m[0]));
    let all = findings(&format!("{RFC}invalid_mjcf_biped_facing_back.xml"));
    let m = of(&all, "root-frame-convention");
    assert_eq!(m.len(), 1, "{m:#?}");
    assert!(message(m[0]).contains("left is −y"), "{}", message(m[0]));
    assert!((measured(m[0]) - 180.0).abs() < 1e-6, "{}", measured(m[0]));
    let all = findings(&format!("{RFC}invalid_urdf_on_its_side.urdf"));
    let m = of(&all, "root-frame-convention");
    assert_eq!(m.len(), 1, "{m:#?}");
    assert!(message(m[0]).contains("up is +y"), "{}", message(m[0]));
    for valid in [
        "valid_urdf_x_forward.urdf",
        "valid_urdf_unnamed_legs.urdf",
        "valid_mjcf_biped_x_forward.xml",
        "valid_mjcf_yawed_keyframe.xml",
    ] {
        none_of(&format!("{RFC}{valid}"), "root-frame-convention");
    }
}

/// The shared real models and the shipped model are x-forward, y-left, z-up.
#[test]
fn x_forward_robots_are_not_reported() {
    for f in real_robot_files() {
        none_of(&f, "root-frame-convention");
    }
}

const PJL: &str = "fixtures/rules/placeholder-joint-limits/";

/// Velocity 100 on all 14 joints whose efforts are 15..90 N·m: 90 / 15 = 6×. Effort 30 on all
/// 14 whose velocities are 8..24 rad/s: 3×.
#[test]
fn one_limit_copied_onto_every_joint_is_reported() {
    let all = findings(&format!("{PJL}invalid_urdf_one_velocity.urdf"));
    let m: Vec<_> = of(&all, "placeholder-joint-limits")
        .into_iter()
        .filter(|f| message(f).starts_with("one limit copied"))
        .collect();
    assert_eq!(m.len(), 1, "{m:#?}");
    assert!(message(m[0]).contains("velocity 100 rad/s on all 14 moving joints"));
    assert!((measured(m[0]) - 90.0 / 15.0).abs() < 1e-9, "{}", measured(m[0]));
    let all = findings(&format!("{PJL}invalid_urdf_one_effort.urdf"));
    let m: Vec<_> = of(&all, "placeholder-joint-limits")
        .into_iter()
        .filter(|f| message(f).starts_with("one limit copied"))
        .collect();
    assert_eq!(m.len(), 1, "{m:#?}");
    assert!(message(m[0]).contains("effort 30 N·m on all 14 moving joints"));
    assert!((measured(m[0]) - 24.0 / 8.0).abs() < 1e-9, "{}", measured(m[0]));
    for valid in [
        "valid_urdf_one_servo.urdf",
        "valid_urdf_one_velocity_close_efforts.urdf",
        "valid_urdf_hips_wide.urdf",
    ] {
        none_of(&format!("{PJL}{valid}"), "placeholder-joint-limits");
    }
}

const MA: &str = "fixtures/rules/mirror-asymmetry/";

/// The right shoulder and elbow at 1000 N·m and 100 rad/s against the left's 20 and 15 N·m,
/// 20 and 24 rad/s; an MJCF right knee's actuatorfrcrange ±60 against the left's ±90.
#[test]
fn mirror_joints_with_different_limits_are_reported() {
    let all = findings(&format!("{MA}invalid_urdf_arm_limits.urdf"));
    let m: Vec<_> = of(&all, "mirror-asymmetry")
        .into_iter()
        .filter(|f| message(f).contains("limits"))
        .collect();
    assert_eq!(m.len(), 2, "{m:#?}");
    assert!(message(m[0]).starts_with("2 mirror joint pairs state different effort limits"));
    assert_eq!((measured(m[0]), expected(m[0])), (1000.0, 20.0));
    assert!(message(m[1]).starts_with("2 mirror joint pairs state different velocity limits"));
    assert_eq!((measured(m[1]), expected(m[1])), (100.0, 20.0));
    let all = findings(&format!("{MA}invalid_mjcf_knee_force_limits.xml"));
    let m = of(&all, "mirror-asymmetry");
    assert_eq!(m.len(), 1, "{m:#?}");
    assert_eq!((measured(m[0]), expected(m[0])), (60.0, 90.0));
    none_of(&format!("{MA}valid_urdf_limits_mirrored.urdf"), "mirror-asymmetry");
}

const IEG: &str = "fixtures/rules/inertia-exceeds-geometry/";

/// Two 1 g links with 1e-5 kg·m² on every axis fixed to a frame whose smallest principal
/// moment is 6.13e-5 kg·m²: 2e-5 / 6.13e-5. A 10 g camera whose smallest moment is 2e-4 on a
/// head whose smallest is 1e-3: 0.2.
#[test]
fn placeholder_inertias_fused_into_a_link_are_reported() {
    let all = findings(&format!("{IEG}invalid_urdf_fused_boards.urdf"));
    let m = of(&all, "inertia-exceeds-geometry");
    assert_eq!(m.len(), 1, "{m:#?}");
    assert!(message(m[0]).starts_with("links fixed to link `base_link`"), "{}", message(m[0]));
    assert!((measured(m[0]) - 2e-5 / 6.13e-5).abs() < 1e-9, "{}", measured(m[0]));
    // Radii of gyration: √(1e-5 / 0.001) = 0.1 m against √(1.8e-4 / 0.108) = 0.0408 m.
    assert!(message(m[0]).contains("radius of gyration 0.0408 m"), "{}", message(m[0]));
    let all = findings(&format!("{IEG}invalid_urdf_fused_camera.urdf"));
    let m = of(&all, "inertia-exceeds-geometry");
    assert_eq!(m.len(), 1, "{m:#?}");
    assert!((measured(m[0]) - 0.2).abs() < 1e-9, "{}", measured(m[0]));
    none_of(&format!("{IEG}valid_urdf_fused_parts.urdf"), "inertia-exceeds-geometry");
}
