//! URDF defect classes of issue 45 (audit round six's "Left:"): geared joints with no rotor
//! inertia (`transmission-without-armature`), placeholder `<limit>`s
//! (`placeholder-joint-limits`) and legged URDFs welded to the world (`welded-legged-base`; their feet judged as if the root floated). Each value is computed here by hand from the fixture's numbers.

use std::path::Path;

use modellint::finding::Finding;
use modellint::lint::{LintInput, load, run_rules};

fn of(id: &str, fixture: &str) -> Vec<Finding> {
    let path = Path::new("fixtures/rules").join(id).join(fixture);
    let input = LintInput {
        model: path.clone(),
        spec: None,
        config: None,
        select: vec![id.to_string()],
        ignore: vec![],
    };
    let loaded = load(&input).unwrap_or_else(|e| panic!("{} failed to load: {e}", path.display()));
    run_rules(&loaded).into_iter().filter(|f| f.rule == id).collect()
}

/// The finding whose measured quantity is in `unit` (each case of a rule measures its own).
fn in_unit<'a>(f: &'a [Finding], unit: &str) -> &'a Finding {
    let mut it = f.iter().filter(|f| f.measured.as_ref().is_some_and(|m| m.unit == unit));
    let one = it.next().unwrap_or_else(|| panic!("no finding in {unit}: {f:?}"));
    assert!(it.next().is_none(), "two findings in {unit}");
    one
}

fn data(f: &Finding, key: &str) -> f64 {
    *f.data.get(key).unwrap_or_else(|| panic!("no `{key}` in {f:?}"))
}

#[test]
fn transmission_reduction_squared_is_the_missing_factor() {
    const ID: &str = "transmission-without-armature";
    // Old syntax: hip and knee at 9:1, one finding for both, factor 9² = 81.
    let f = of(ID, "invalid.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!((data(&f[0], "reduction"), data(&f[0], "reflection_factor")), (9.0, 81.0));
    assert_eq!(data(&f[0], "joints"), 2.0);
    // ros_control: 50:1 and -100:1 (the sign is the direction) → 2,500 and 10,000.
    let f = of(ID, "invalid_ros_control.urdf");
    let got: Vec<(f64, f64)> =
        f.iter().map(|f| (data(f, "reduction"), data(f, "reflection_factor"))).collect();
    assert_eq!(got, vec![(50.0, 2500.0), (100.0, 10000.0)]);
    // ros2_control: only the knee's 6.33 is written.
    let f = of(ID, "invalid_ros2_control.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((data(&f[0], "reflection_factor") - 6.33 * 6.33).abs() < 1e-9);
    assert_eq!(data(&f[0], "joints"), 1.0);
    assert!(f[0].message.contains("`knee`") && !f[0].message.contains("`hip`"), "{}", f[0].message);
    for v in ["valid.urdf", "valid_unexpanded_xacro.urdf"] {
        assert!(of(ID, v).is_empty(), "{v}");
    }
}

#[test]
fn placeholder_limits_are_judged_from_weight_reach_and_a_turn() {
    const ID: &str = "placeholder-joint-limits";
    let f = of(ID, "invalid.urdf");
    assert_eq!(f.len(), 4, "{f:?}");
    // Effort: the robot weighs 1 + 0.5 + 0.5 kg; the knee carries the foot sphere 0.2 m below
    // it, radius 0.02 → reach 0.22 m; 1000 N·m over 2 · 9.81 · 0.22 N·m (the knee's ratio is
    // the larger of the two: the hip's reach is 0.42 m).
    let e = in_unit(&f, "×");
    let effort = e.measured.as_ref().unwrap().value;
    assert!((effort - 1000.0 / (2.0 * 9.81 * 0.22)).abs() < 1e-6, "{effort}");
    assert_eq!(data(e, "joints"), 2.0);
    // Velocity: the hip's 1000 rad/s × its 0.42 m reach.
    let tip = in_unit(&f, "m/s").measured.as_ref().unwrap().value;
    assert!((tip - 1000.0 * 0.42).abs() < 1e-6, "{tip}");
    // Power: 1000 N·m × 1000 rad/s / 4 on each of the two joints, over the URDF's stated 2 kg.
    let power = in_unit(&f, "W/kg").measured.as_ref().unwrap().value;
    assert!((power - 2.0 * 1000.0 * 1000.0 / 4.0 / 2.0).abs() < 1e-6, "{power}");
    // Stops at ±10 rad, more than a turn (2π) from zero.
    let turn = in_unit(&f, "rad");
    assert_eq!(turn.measured.as_ref().unwrap().value, 10.0);
    assert_eq!(data(turn, "joints"), 2.0);
    // No range: effort/velocity only, no <limit>, lower = upper = 0 on a slide.
    let f = of(ID, "invalid_no_range.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(data(&f[0], "joints"), 3.0);
    // A driven joint's effort 0 and velocity 0.
    let f = of(ID, "invalid_zero_driven.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(data(&f[0], "joints"), 2.0);
    for v in ["valid.urdf", "valid_light_servo_arm.urdf"] {
        assert!(of(ID, v).is_empty(), "{v}: {:?}", of(ID, v));
    }
}

#[test]
fn mujoco_makes_a_urdf_effort_the_joint_force_range_and_a_zero_range_unlimited() {
    // What the rule's documentation says of MuJoCo's importer, checked on the compiled model.
    let load_urdf = |f: &str| {
        let path = Path::new("fixtures/rules/placeholder-joint-limits").join(f);
        let input =
            LintInput { model: path, spec: None, config: None, select: vec![], ignore: vec![] };
        load(&input).unwrap().robot
    };
    let r = load_urdf("invalid.urdf");
    let hip = r.joint("hip").unwrap();
    assert!(hip.limited && hip.range == [-10.0, 10.0], "{hip:?}");
    assert!(r.mj.jnt_actfrclimited()[hip.id]);
    assert_eq!(r.mj.jnt_actfrcrange()[hip.id], [-1000.0, 1000.0]);
    // The root link (1 kg) is fused into the world body: the compiled robot weighs 1 kg, the
    // URDF 2 kg.
    assert!((r.mass_split().0 - 1.0).abs() < 1e-9, "{}", r.mass_split().0);
    let r = load_urdf("invalid_no_range.urdf");
    for j in ["shoulder", "elbow", "rail"] {
        assert!(!r.joint(j).unwrap().limited, "{j}");
    }
}

#[test]
fn a_legged_urdf_welded_to_the_world_is_named_and_arms_and_wheels_are_not() {
    const ID: &str = "welded-legged-base";
    // Two legs; each foot sphere (r 0.025) 0.05 + 0.2 + 0.2 m below the trunk's frame.
    let f = of(ID, "invalid.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].measured.as_ref().unwrap().value, 2.0);
    assert!((data(&f[0], "depth") - 0.475).abs() < 1e-9, "{}", data(&f[0], "depth"));
    for v in ["valid_ceiling_arm.urdf", "valid_wheeled_base.urdf"] {
        assert!(of(ID, v).is_empty(), "{v}");
    }
}

/// The foot families of `fixture` (under `fixtures/rules/<dir>`), as (foot body, kind).
fn feet_of(dir: &str, fixture: &str) -> Vec<(String, modellint::rules::contact::feet::FootKind)> {
    let path = Path::new("fixtures/rules").join(dir).join(fixture);
    let input =
        LintInput { model: path.clone(), spec: None, config: None, select: vec![], ignore: vec![] };
    let loaded = load(&input).unwrap_or_else(|e| panic!("{} failed to load: {e}", path.display()));
    let r = &loaded.robot;
    modellint::rules::contact::feet::feet(r, None)
        .into_iter()
        .map(|f| (r.body_name(f.root).to_string(), f.kind))
        .collect()
}

#[test]
fn a_welded_legged_urdf_has_its_feet_judged_as_if_it_floated() {
    use modellint::rules::contact::feet::FootKind::{Flat, Point};
    // The biped's feet (named `*_foot`, the toes below them), flat; the quadruped's calves
    // ending in 22 mm spheres, point feet; an arm and a wheeled base have none.
    let biped = feet_of("toe-tilt", "invalid_welded_urdf_biped.urdf");
    assert_eq!(biped, vec![("left_foot".into(), Flat), ("right_foot".into(), Flat)]);
    let quad = feet_of("toe-tilt", "valid_welded_urdf_quadruped.urdf");
    assert_eq!(quad.len(), 4, "{quad:?}");
    assert!(quad.iter().all(|(n, k)| n.ends_with("_calf") && *k == Point), "{quad:?}");
    assert!(feet_of("toe-tilt", "valid_urdf_table_arm.urdf").is_empty());
    assert!(feet_of("welded-legged-base", "valid_wheeled_base.urdf").is_empty());
    assert!(feet_of("welded-legged-base", "valid_ceiling_arm.urdf").is_empty());
    // The left toe box is pitched 0.03 rad in the file: its bottom face 0.03 rad = 1.7189°
    // from the ground at qpos0; the right toe and both soles are level.
    let f = of("toe-tilt", "invalid_welded_urdf_biped.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((data(&f[0], "tilt_deg") - 0.03f64.to_degrees()).abs() < 1e-6, "{f:?}");
    assert!(of("toe-tilt", "valid_welded_urdf_biped.urdf").is_empty());
    // The welded robot's legs have no collision geometry: the four 0.3 m thigh and shank
    // links are bare, the feet collide.
    let f = of("links-without-collision", "invalid_welded_urdf_biped.urdf");
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(f[0].message.starts_with("4 links"), "{}", f[0].message);
}
