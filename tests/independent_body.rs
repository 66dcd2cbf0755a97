//! Body effects on recordings of the independent simulator (`bench/independent_py/realsim.py`,
//! committed in `fixtures/independent_py/`, see its README): a concealed payload on the shank of
//! a three-joint leg must come out as a `link_mass` on the knee's child body with the payload's
//! mass within 10 % and its place within 10 % of the link's length, written back into the
//! shank's `<inertial>`; the same leg with nothing concealed must give nothing, and so must a
//! battery moving the centre of mass of the trunk the leg hangs from on its test stand (welded
//! to the world, it loads no recorded joint). Every expected value is read from the simulator's
//! `truth.json`.

mod common;

use common::indep::{TruthBody, assert_nothing, assert_payload_found, fit, truth};

#[test]
fn a_payload_on_the_shank_is_found_and_written_into_its_inertial() {
    let truth = truth("R1_shank_payload");
    let shank = TruthBody::of(&truth, "shank");
    let (mass, _) = shank.payload();
    let pos = common::indep::v3(&shank.b["payload"]["pos"]);
    let com = shank.com;
    let out = std::env::temp_dir().join(format!("modellint-indep-body-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let written = out.join("fitted.xml");
    let v = fit("R1_shank_payload", &["--write-model", written.to_str().unwrap()]);
    assert_payload_found(&v, &shank, "knee");
    // With the payload fitted, nothing is left above the floors.
    assert_eq!(v["unexplained"].as_array().map(Vec::len), Some(0), "{}", v["unexplained"]);
    // The written model's shank is the nominal shank plus the fitted point: mass and centre of
    // mass as the truth's composite body within the same 10 %.
    let robot = common::load(&written);
    let b = robot.mj.body_mass();
    let ipos = robot.mj.body_ipos();
    let id = robot.joint("knee").unwrap().id;
    let body = robot.mj.jnt_bodyid()[id] as usize;
    let m0 = shank.b["nominal_mass"].as_f64().unwrap();
    assert!((b[body] - (m0 + mass)).abs() <= 0.1 * mass, "written mass {}", b[body]);
    let c_true: Vec<f64> = (0..3).map(|k| (m0 * com[k] + mass * pos[k]) / (m0 + mass)).collect();
    let dc: f64 = (0..3).map(|k| (ipos[body][k] - c_true[k]).powi(2)).sum::<f64>().sqrt();
    assert!(dc <= 0.1 * shank.len * mass / (m0 + mass), "written centre of mass off by {dc} m");
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn the_same_leg_without_a_payload_gives_nothing() {
    assert_nothing(&fit("R0_none", &[]));
}

/// A 1 kg battery on the test stand's trunk and its centre of mass moved 3 cm: the trunk is
/// welded to the world, so no recorded joint carries it and nothing can be said about it —
/// the fit must report nothing (not a body effect on the hip's thigh, not a joint effect).
#[test]
fn a_battery_on_the_trunk_of_a_leg_on_a_stand_is_not_reported() {
    let truth = truth("RS1_stand_trunk_battery");
    let stand = &truth["resolved"]["_bodies"]["stand"];
    assert!(stand["joint"].is_null(), "the stand must be welded: {stand}");
    assert!(stand["payload"]["mass"].as_f64().unwrap() > 0.0);
    assert_nothing(&fit("RS1_stand_trunk_battery", &[]));
}

/// Told to explain the payload with joint effects only, the fit keeps what helps and says
/// that the knee's residual is still far above its floor, where and how large.
#[test]
fn a_payload_the_effects_allowed_cannot_name_is_an_unexplained_residual() {
    let v = fit("R1_shank_payload", &["--effects", "armature,viscous_damping"]);
    let u = v["unexplained"].as_array().unwrap();
    let knee = u.iter().find(|x| x["joint"] == "knee").expect("the knee is unexplained");
    assert!(knee["residual_rms"].as_f64().unwrap() > 3.0 * knee["floor_rms"].as_f64().unwrap());
    let w = v["warnings"].to_string();
    assert!(w.contains("unexplained residual on knee"), "{w}");
}

/// The same, every episode held out in turn (`--holdout-by episode`, four folds): every fold
/// names the knee in its `unexplained` (JSON `folds[].unexplained`) far above its floor, and
/// in its warnings, as the single fit does — no fold presents the joint effects as the answer.
#[test]
fn every_fold_of_a_rotation_names_the_residual_its_effects_leave() {
    let v = fit(
        "R1_shank_payload",
        &["--effects", "armature,viscous_damping", "--holdout-by", "episode"],
    );
    let folds = v["folds"].as_array().expect("folds");
    assert_eq!(folds.len(), 4, "{v}");
    for f in folds {
        let u = f["unexplained"].as_array().expect("a fold's unexplained");
        let knee = u.iter().find(|x| x["joint"] == "knee");
        let knee = knee.unwrap_or_else(|| panic!("fold {}: knee not named: {u:?}", f["value"]));
        let (r, w) = (knee["residual_rms"].as_f64().unwrap(), knee["floor_rms"].as_f64().unwrap());
        assert!(r > 3.0 * w, "fold {}: knee {r} rad against its floor {w}", f["value"]);
        let warnings = f["warnings"].to_string();
        assert!(warnings.contains("unexplained residual on knee"), "{warnings}");
    }
}

/// `--holdout-by` rotates the held-out episodes; a told armature on the knee of the leg that
/// has none comes out at the model's own value within its uncertainty in every fold, and is
/// then a note, not a selected effect (as in a single fit).
#[test]
fn the_rotation_does_not_list_an_effect_at_the_models_own_value() {
    let v = fit("R0_none", &["--holdout-by", "episode", "--told", "armature@knee"]);
    let folds = v["folds"].as_array().unwrap();
    assert_eq!(folds.len(), 4, "{v}");
    for f in folds {
        assert_eq!(f["selected"].as_array().map(Vec::len), Some(0), "{}", f["selected"]);
        let notes = f["notes"].to_string();
        assert!(notes.contains("armature on knee") && notes.contains("within 2"), "{notes}");
    }
}

/// The same 0.25 kg sensor at the foot end of all four shanks of the quadruped on its stand:
/// one `link_mass` on the four knees' child bodies as one group (every leg), mass and place
/// within 10 %.
#[test]
fn the_same_payload_on_every_shank_is_one_group() {
    let truth = truth("QR6_shanks_payload");
    let v = fit("QR6_shanks_payload", &[]);
    let knees = r#"["FL_knee","FR_knee","RL_knee","RR_knee"]"#;
    let found = common::indep::found(&v);
    assert_eq!(found, [("link_mass".into(), knees.into())], "{found:?}");
    for leg in ["FL", "FR", "RL", "RR"] {
        let shank = TruthBody::of(&truth, &format!("{leg}_shank"));
        let (mass, along) = shank.payload();
        let p = &v["missing_physics"][0]["params"];
        let (dm, off) = (p["added_mass"].as_f64().unwrap(), p["offset"].as_f64().unwrap());
        assert!((dm - mass).abs() <= 0.1 * mass, "{leg}: added mass {dm} for {mass}");
        assert!((off - along).abs() <= 0.1 * shank.len, "{leg}: offset {off} for {along}");
    }
}

/// A robot file with a floating base (`quad12_float.xml`), recorded on a test stand (the
/// simulator welds the torso to the world): the replay must hold the base as the stand does,
/// with the legs loaded by gravity. Resetting the base's pose between physics steps alone let
/// the whole robot fall freely within each step — its legs weightless — and put the clean
/// recordings 2.8° MAE away (the fit then explains the missing gravity with effects).
#[test]
fn a_floating_base_robot_recorded_on_a_stand_replays_with_its_legs_loaded() {
    let v = fit("QR0f_stand_float_none", &[]);
    assert_nothing(&v);
    // The nominal model already replays the held-out episode at the recordings' noise
    // (0.5 mrad, a 12-bit encoder: RMSE ≈ 0.7 mrad; free within each step: 55 mrad).
    let rmse = v["before"]["position_rmse"].as_f64().unwrap();
    assert!(rmse < 2e-3, "held-out position RMSE {rmse} rad with nothing concealed");
}

/// The same robot on its stand with damping concealed on the four knees: found as one group,
/// the value within 10 % of the truth's.
#[test]
fn knee_damping_of_a_floating_base_robot_on_a_stand_is_found() {
    let truth = truth("QR7f_stand_float_knee_damping");
    let v = fit("QR7f_stand_float_knee_damping", &[]);
    let knees = r#"["FL_knee","FR_knee","RL_knee","RR_knee"]"#;
    let found = common::indep::found(&v);
    assert_eq!(found, [("viscous_damping".into(), knees.into())], "{found:?}");
    let want = truth["resolved"]["FL_knee"]["damping"][1].as_f64().unwrap();
    let got = v["missing_physics"][0]["params"]["damping"].as_f64().unwrap();
    assert!((got - want).abs() <= 0.1 * want, "knee damping {got} for {want}");
}

/// A humanoid's arm whose upper arm hangs along its shoulder yaw's axis (`models/arm4y.xml`, the
/// new-user tryout's kinematics), its centre of mass 4 cm forward — perpendicular to that axis,
/// where only the carrying shoulder pitch and roll see it through gravity. It must come out as a
/// `com_offset` on the yaw joint's child body: nothing along the link, 4 cm perpendicular to it
/// (within 10 %), and the written model's upper arm holds the truth's centre of mass within 10 %
/// of the shift. (With the directions picked as the link's axis and one perpendicular, the other
/// perpendicular was no parameter and the shift came out as a 0.007 rad offset on the pitch.)
#[test]
fn a_centre_of_mass_moved_off_a_yaw_axis_is_found_in_the_carrying_joints_plane() {
    let truth = truth("RY1_upper_arm_com_forward");
    let arm = TruthBody::of(&truth, "upper_arm");
    let shift = common::indep::v3(&arm.b["com_shift"]);
    let size = shift.iter().map(|x| x * x).sum::<f64>().sqrt();
    let out = std::env::temp_dir().join(format!("modellint-indep-yaw-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let written = out.join("fitted.xml");
    let v = fit("RY1_upper_arm_com_forward", &["--write-model", written.to_str().unwrap()]);
    let found = common::indep::found(&v);
    assert_eq!(found, [("com_offset".into(), r#"["shoulder_yaw"]"#.into())], "{found:?}");
    let p = &v["missing_physics"][0]["params"];
    let get = |k: &str| p[k].as_f64().unwrap_or_else(|| panic!("{k} in {p}"));
    let (along, across, normal) = (get("along"), get("across"), get("normal"));
    let (want_along, _) = arm.com_shift();
    assert!((along - want_along).abs() <= 0.1 * size, "along {along} for {want_along}");
    let perpendicular = (across * across + normal * normal).sqrt();
    assert!((perpendicular - size).abs() <= 0.1 * size, "({across}, {normal}) for {size} m");
    let robot = common::load(&written);
    let body = robot.mj.jnt_bodyid()[robot.joint("shoulder_yaw").unwrap().id] as usize;
    let (got, want) = (robot.mj.body_ipos()[body], common::indep::v3(&arm.b["real_body_com"]));
    let d = (0..3).map(|k| (got[k] - want[k]).powi(2)).sum::<f64>().sqrt();
    assert!(d <= 0.1 * size, "written centre of mass {got:?} for {want:?}");
    std::fs::remove_dir_all(&out).ok();
}

/// The same arm with nothing concealed: nothing (three directions of a body's place where the
/// carrying joints see three must not find one in the noise).
#[test]
fn the_yaw_arm_without_a_shift_gives_nothing() {
    assert_nothing(&fit("RY0_arm_none", &[]));
}
