//! Probe simulations measured against closed-form values on single-joint fixtures.

use std::path::Path;

use modellint::finding::ProbeStatus;
use modellint::lint::{LintInput, Loaded, load, run_rules};
use modellint::probe::{direction, impulse, settle};

fn loaded(path: &str) -> Loaded {
    let input = LintInput {
        model: Path::new(path).to_path_buf(),
        spec: None,
        config: None,
        select: vec![],
        ignore: vec![],
    };
    load(&input).unwrap_or_else(|e| panic!("{e}"))
}

fn analytic_zeta(l: &Loaded, joint: &str) -> f64 {
    let j = l.robot.joint(joint).unwrap();
    let (_, kp, kd, _) = impulse::gains(&l.robot, j.id, None).unwrap();
    kd / (2.0 * (kp * l.robot.key.m_diag[j.dofadr]).sqrt())
}

#[test]
fn impulse_response_measures_zeta_within_15_percent_of_analytic() {
    let l = loaded("fixtures/probes/servo_underdamped.xml");
    let j = l.robot.joint("hinge").unwrap().id;
    let r = impulse::step_response(&l.robot, j, None).unwrap();
    let analytic = analytic_zeta(&l, "hinge");
    assert!((analytic - 0.223).abs() < 0.01, "fixture's analytic ζ drifted: {analytic}");
    let z = r.zeta.expect("an underdamped servo overshoots");
    assert!(((z - analytic) / analytic).abs() < 0.15, "measured ζ {z} vs analytic {analytic}");
    let wn = (r.kp / l.robot.key.m_diag[l.robot.joints[j].dofadr]).sqrt();
    assert!(((r.omega_n.unwrap() - wn) / wn).abs() < 0.15, "ω_n {:?} vs {wn}", r.omega_n);
    assert!(r.overshoot > 0.4, "ζ≈0.22 overshoots ~49 %: {}", r.overshoot);
}

#[test]
fn well_damped_servo_does_not_ring() {
    let l = loaded("fixtures/probes/servo_damped.xml");
    let j = l.robot.joint("hinge").unwrap().id;
    let r = impulse::step_response(&l.robot, j, None).unwrap();
    assert!(analytic_zeta(&l, "hinge") > 1.0);
    assert!(r.zeta.is_none() || r.zeta.unwrap() > 0.9, "{:?}", r.zeta);
    assert!(r.overshoot < 0.01, "overshoot {}", r.overshoot);
}

#[test]
fn direction_probe_sees_the_flipped_gear() {
    let l = loaded("fixtures/probes/flipped_gear.xml");
    let d = direction::run(&l.robot, 0).unwrap();
    let (j, dq) = d.moved.iter().copied().find(|(j, _)| *j == 0).expect("the joint moves");
    assert_eq!(j, 0);
    assert!(dq < -1e-3, "positive command on gear −1 must move the joint negative, moved {dq}");
}

#[test]
fn settle_probe_confirms_the_low_toe() {
    let l = loaded("fixtures/rules/toe-tilt/invalid.xml");
    let mut findings = run_rules(&l);
    findings.retain(|f| f.rule == "toe-tilt");
    assert!(!findings.is_empty());
    modellint::lint::confirm(&l, &mut findings);
    let p = findings.iter().find(|f| f.rule == "toe-tilt").and_then(|f| f.probe.clone()).unwrap();
    assert_eq!(p.status, ProbeStatus::Confirmed, "{}", p.note);
    // The raw measurement: some foot geom carries almost nothing after settling.
    let s = settle::run(&l.robot).unwrap();
    assert!(!s.stance.diverged);
    assert!(s.geom_load.values().any(|&f| f > 0.1));
}

#[test]
fn settle_probe_loads_every_geom_of_a_flat_foot() {
    let l = loaded("fixtures/rules/toe-tilt/valid.xml");
    let s = settle::run(&l.robot).unwrap();
    assert!(!s.stance.diverged);
    let feet: Vec<_> = l.robot.geoms.iter().filter(|g| g.collides() && g.body != 0).collect();
    let total: f64 = feet.iter().map(|g| s.geom_load.get(&g.id).copied().unwrap_or(0.0)).sum();
    assert!(total > 0.1, "the robot stands on its feet");
    for g in feet {
        let load = s.geom_load.get(&g.id).copied().unwrap_or(0.0);
        assert!(load > 0.02 * total / 2.0, "geom {} carries {load} N of {total} N", g.name);
    }
}

/// Lints one fixture with its probes (the spec beside it, if any) and returns the findings of
/// `rule`.
fn probed(path: &str, rule: &str) -> Vec<modellint::finding::Finding> {
    probed_with(path, rule, None)
}

/// `probed` with a modellint.toml (the user's stated intent for the rules' options).
fn probed_with(path: &str, rule: &str, config: Option<&str>) -> Vec<modellint::finding::Finding> {
    let toml = Path::new(path).with_extension("toml");
    let input = LintInput {
        model: Path::new(path).to_path_buf(),
        spec: toml.exists().then_some(toml),
        config: config.map(std::path::PathBuf::from),
        select: vec![],
        ignore: vec![],
    };
    let l = load(&input).unwrap_or_else(|e| panic!("{e}"));
    let mut fs = run_rules(&l);
    fs.retain(|f| f.rule == rule);
    assert!(!fs.is_empty(), "{path}: no {rule} finding");
    modellint::lint::confirm(&l, &mut fs);
    fs
}

fn outcome(f: &modellint::finding::Finding) -> modellint::finding::ProbeOutcome {
    f.probe.clone().unwrap_or_else(|| panic!("not probed: {}", f.message))
}

/// A free-floating robot file with no floor (its floor is in a scene) is measured on a copy
/// with a floor added; the fact keeps its level.
#[test]
fn stance_without_a_floor_stands_on_an_added_floor_and_the_fact_keeps_its_level() {
    let fs =
        probed("fixtures/rules/passive-joint-spring/invalid_no_floor.xml", "passive-joint-spring");
    for f in &fs {
        let p = outcome(f);
        assert!(f.fact, "{}", f.message);
        assert_eq!(p.status, ProbeStatus::Measured, "{}", p.note);
        let floor = p.preconditions.iter().find(|c| c.name == "floor").expect("recorded");
        assert!(floor.met && floor.detail.contains("the copy has a plane added"), "{floor:?}");
        assert_ne!(f.severity, modellint::finding::Severity::Info);
        assert!(!f.message.contains("refuted"));
    }
}

/// An MJCF robot file that floats (a free joint) and has no floor, its scene in another file:
/// the stance run stands it on a copy with only a floor added under its lowest point, and the
/// toe 3 mm below the sole is confirmed. The scene that includes the file stands it on the
/// scene's own floor: nothing added.
#[test]
fn a_robot_file_without_its_scene_stands_on_an_added_floor() {
    let fs = probed("fixtures/probes/stance_robot_file.xml", "toe-tilt");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Confirmed, "{}", p.note);
    assert!(p.preconditions.iter().all(|c| c.met), "{:?}", p.preconditions);
    // By hand from the file: the frame at 0.3 m, the toe capsule's axis 0.043 m below it,
    // radius 0.01 m.
    let z = p.measured["floor_added_z_m"];
    assert!((z - (0.3 - 0.043 - 0.01)).abs() < 1e-9, "floor at {z}");
    assert!(p.note.contains("probed on a copy with a floor added at z = 0.247 m"), "{}", p.note);
    assert!(!p.note.contains("free joint added"), "{}", p.note);
    let free = p.preconditions.iter().find(|c| c.name == "free_base").unwrap();
    assert_eq!(free.detail, "the base is free-floating");
    let fs = probed("fixtures/probes/stance_robot_file_scene.xml", "toe-tilt");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Confirmed, "{}", p.note);
    assert!(!p.measured.contains_key("floor_added_z_m"));
    assert!(!p.note.contains("floor added"), "{}", p.note);
}

#[test]
fn stance_under_upward_gravity_is_inconclusive_with_the_gravity_reason() {
    // A tilted box sole on its floor, but gravity 0 0 0.0001: the floor carries none of a
    // weight that is not there; the reason is gravity, not the foot.
    let fs = probed("fixtures/probes/stance_upward_gravity.xml", "toe-tilt");
    for f in &fs {
        let p = outcome(f);
        assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
        let reason = p.reason.as_deref().unwrap_or("");
        assert!(reason.contains("gravity is 0.0001 m/s² pointing away from the floor"), "{reason}");
        let names: Vec<_> = p.preconditions.iter().map(|c| (c.name, c.met)).collect();
        assert_eq!(&names[..2], [("floor", true), ("gravity", false)], "{names:?}");
        assert!(!f.message.contains("refuted"));
    }
}

#[test]
fn stance_from_a_keyframe_under_the_floor_is_inconclusive_with_that_reason() {
    // The keyframe starts the foot 0.3 m under the floor plane: the run says so, not only
    // that the floor carried no weight.
    let fs = probed("fixtures/probes/stance_buried_keyframe.xml", "toe-tilt");
    for f in &fs {
        let p = outcome(f);
        assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
        let reason = p.reason.as_deref().unwrap_or("");
        assert!(
            reason.contains("1 colliding geom of the robot entirely under the floor"),
            "{reason}"
        );
        let names: Vec<_> = p.preconditions.iter().map(|c| (c.name, c.met)).collect();
        assert_eq!(&names[..3], [("floor", true), ("gravity", true), ("above_floor", false)]);
    }
}

#[test]
fn stance_from_a_keyframe_past_a_joint_stop_is_inconclusive_with_that_reason() {
    // The keyframe turns the ankle 0.4 rad past its range: the joint limit throws the foot back
    // at the first step, so the run says the pose is illegal, not that the robot tilted.
    let fs = probed("fixtures/probes/stance_out_of_range_keyframe.xml", "toe-tilt");
    assert!(!fs.is_empty());
    for f in &fs {
        let p = outcome(f);
        assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
        let reason = p.reason.as_deref().unwrap_or("");
        assert!(
            reason.contains(
                "the keyframe places 1 joint outside its range (`right_ankle_yaw` at 0.6, 0.4 past [-0.2, 0.2]"
            ),
            "{reason}"
        );
        let names: Vec<_> = p.preconditions.iter().map(|c| (c.name, c.met)).collect();
        assert_eq!(
            &names[..4],
            [("floor", true), ("gravity", true), ("above_floor", true), ("in_range", false)]
        );
    }
}

/// The stance run of `passive-joint-spring` on `model` stood, loaded the foot and measured:
/// every precondition recorded, in order, and met.
fn assert_stance_measured(model: &str) {
    let fs = probed(model, "passive-joint-spring");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Measured, "{model}: {}", p.note);
    let names: Vec<_> = p.preconditions.iter().map(|c| (c.name, c.met)).collect();
    assert_eq!(
        names,
        [
            ("floor", true),
            ("gravity", true),
            ("above_floor", true),
            ("in_range", true),
            ("settled", true),
            ("free_base", true),
            ("feet_loaded", true),
            ("upright", true)
        ],
        "{model}"
    );
}

#[test]
fn stance_on_a_floor_records_every_precondition_met() {
    // The same passive toe on a floor: the stance run stands, loads the foot and measures.
    assert_stance_measured("fixtures/rules/passive-joint-spring/invalid.xml");
}

#[test]
fn stance_on_a_floor_body_welded_to_the_world_records_every_precondition_met() {
    // The floor is a plane on a jointless <body> (MuJoCo welds it to the world): the stance run
    // must stand on it as on a plane of the world body, load the foot and measure.
    assert_stance_measured("fixtures/probes/toe_static_floor_body.xml");
}

#[test]
fn an_undamped_spring_is_measured_by_a_ring_down_never_refuted() {
    let fs = probed(
        "fixtures/rules/passive-joint-spring/invalid_nospec_spring_ringing.xml",
        "passive-joint-spring",
    );
    let p = outcome(&fs[0]);
    assert_eq!(p.name, "ring-down");
    assert_eq!(p.status, ProbeStatus::Measured, "{}", p.note);
    // No damping: the amplitude after 20 periods is the release amplitude, within 2 %.
    let ratio = p.measured["amplitude_ratio"];
    assert!((ratio - 1.0).abs() < 0.02, "amplitude ratio {ratio}");
    assert!(!p.measured.contains_key("ring_time_s"), "an undamped spring never stops ringing");
    // The measured period is the analytic 2π√(I/k) (I = armature + link inertia at the keyframe).
    assert!(p.measured["period_s"] > 0.2 && p.measured["period_s"] < 0.3, "{:?}", p.measured);
}

#[test]
fn a_ring_down_of_a_spring_a_closed_loop_holds_is_inconclusive() {
    // On the stand every other joint is frozen, so the connect closing the four-bar holds the
    // spring joint: the constraint's softness, not the spring, would decide the "ring".
    let fs = probed(
        "fixtures/rules/passive-joint-spring/invalid_nospec_spring_loop.xml",
        "passive-joint-spring",
    );
    let p = outcome(&fs[0]);
    assert_eq!(p.name, "ring-down");
    assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
    let c = p.preconditions.iter().find(|c| c.name == "loop_free").unwrap();
    assert!(!c.met);
    assert!(c.detail.contains("connect `coupler`–`rocker`"), "{}", c.detail);
    assert!(fs[0].fact);
    assert_eq!(fs[0].severity, modellint::finding::Severity::Warning);
    // A spring outside any loop records the precondition met.
    let fs = probed(
        "fixtures/rules/passive-joint-spring/invalid_nospec_spring_ringing.xml",
        "passive-joint-spring",
    );
    let p = outcome(&fs[0]);
    assert!(p.preconditions.iter().any(|c| c.name == "loop_free" && c.met));
}

#[test]
fn a_ring_down_whose_joint_barely_leaves_the_release_is_inconclusive() {
    // Period ≈ 630 s: in the 10 s run the joint moves ~0.5 % of the release, so the run says
    // nothing of how long it rings (it used to read "still rings at 100 %").
    let fs = probed(
        "fixtures/rules/passive-joint-spring/invalid_nospec_spring_slow.xml",
        "passive-joint-spring",
    );
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
    let c = p.preconditions.iter().find(|c| c.name == "joint_moved").unwrap();
    assert!(!c.met, "{}", c.detail);
    assert_eq!(fs[0].severity, modellint::finding::Severity::Warning);
}

#[test]
fn a_ring_down_the_timestep_cannot_resolve_is_inconclusive() {
    let fs = probed(
        "fixtures/rules/passive-joint-spring/invalid_nospec_spring.xml",
        "passive-joint-spring",
    );
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
    let c = p.preconditions.iter().find(|c| c.name == "period_resolved").unwrap();
    assert!(!c.met);
    assert_eq!(fs[0].severity, modellint::finding::Severity::Warning);
}

#[test]
fn no_range_is_measured_not_refuted_by_the_limit_probe() {
    let fs = probed("fixtures/rules/soft-limits/invalid_no_range_nospec.xml", "soft-limits");
    let p = outcome(&fs[0]);
    assert!(fs[0].fact);
    assert_eq!(p.status, ProbeStatus::Measured, "{}", p.note);
    assert!(p.note.contains("no stop acts on it"), "{}", p.note);
    assert!(p.measured["q_max"] - p.measured["q_min"] > 1.0);
}

#[test]
fn ctrlrange_equal_to_range_is_never_refuted_with_or_without_a_spec() {
    // Without a spec, a servo strong enough to get there: measured, the stop engaged or not.
    let fs = probed("fixtures/rules/soft-limits/invalid.xml", "soft-limits");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Measured, "{}", p.note);
    assert_eq!(fs[0].severity, modellint::finding::Severity::Warning);
    // With soft_limit_factor = 0.9 and a servo too weak to reach the commanded end:
    // inconclusive with the reason, still a warning.
    let fs = probed("fixtures/rules/soft-limits/invalid_equal_spec.xml", "soft-limits");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
    let c = p.preconditions.iter().find(|c| c.name == "reached_commanded_extreme" && !c.met);
    assert!(c.is_some(), "{:?}", p.preconditions);
    assert_eq!(fs[0].severity, modellint::finding::Severity::Warning);
}

#[test]
fn a_toe_tilt_refutation_records_its_met_preconditions() {
    let fs = probed("fixtures/rules/toe-tilt/invalid_box.xml", "toe-tilt");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Refuted, "{}", p.note);
    assert!(p.preconditions.iter().all(|c| c.met));
    assert!(p.preconditions.iter().any(|c| c.name == "foot_loaded"));
}

/// The condim/friction findings of `foot-collision-geometry` whose probe is `foot-slide`.
fn slide_findings(path: &str) -> Vec<modellint::finding::Finding> {
    slide_findings_with(path, None)
}

fn slide_findings_with(path: &str, config: Option<&str>) -> Vec<modellint::finding::Finding> {
    let fs = probed_with(path, "foot-collision-geometry", config);
    let out: Vec<_> = fs
        .into_iter()
        .filter(|f| f.probe.as_ref().is_some_and(|p| p.name == "foot-slide"))
        .collect();
    assert!(!out.is_empty(), "{path}: no condim/friction finding measured by foot-slide");
    out
}

/// A robot file with no floor: the push runs on a copy with a floor added (condim 1, friction
/// 0: MuJoCo's maximum gives each contact the foot geom's own condim 1), so the frictionless feet
/// slide ½·(0.05 g)·t² ≈ 61 mm; the fact keeps its level.
#[test]
fn slide_without_a_floor_runs_on_an_added_floor() {
    for f in slide_findings("fixtures/rules/foot-collision-geometry/invalid_condim1_no_floor.xml") {
        let p = outcome(&f);
        assert!(f.fact);
        assert_eq!(p.status, ProbeStatus::Measured, "{}", p.note);
        assert!(p.preconditions.iter().all(|c| c.met), "{:?}", p.preconditions);
        assert!(p.measured.contains_key("floor_added_z_m"), "{:?}", p.measured);
        assert_eq!(p.measured["contact_dim"], 1.0);
        let free_slide = 0.5 * 0.05 * 9.81 * 0.5 * 0.5;
        let s = p.measured["slide_m"];
        assert!((s - free_slide).abs() < 0.1 * free_slide, "slid {s} m");
        assert_ne!(f.severity, modellint::finding::Severity::Info);
    }
}

#[test]
fn slide_reads_the_contact_mujoco_built_and_frictionless_feet_slide() {
    // Floor condim 1 with the higher priority: MuJoCo builds dim-1 contacts; a push of 5 % of
    // the weight for 0.5 s on frictionless contacts moves the foot ½·(0.05 g)·t² ≈ 61 mm.
    for f in
        slide_findings("fixtures/rules/foot-collision-geometry/invalid_priority_floor_condim1.xml")
    {
        let p = outcome(&f);
        assert_eq!(p.status, ProbeStatus::Measured, "{}", p.note);
        assert_eq!(p.measured["contact_dim"], 1.0);
        let free_slide = 0.5 * 0.05 * 9.81 * 0.5 * 0.5;
        let s = p.measured["slide_m"];
        assert!(
            (s - free_slide).abs() < 0.1 * free_slide,
            "slid {s} m, frictionless {free_slide} m"
        );
        assert!(p.preconditions.iter().all(|c| c.met), "{:?}", p.preconditions);
    }
    // condim 6, friction 1 on a condim-3 floor, condim 3 stated: dim-6 contacts at μ 1 hold the
    // push.
    let fs = slide_findings_with(
        "fixtures/rules/foot-collision-geometry/valid_default_friction.xml",
        Some("fixtures/config/foot_condim_stated.toml"),
    );
    assert_eq!(fs.len(), 2, "one condim finding per foot");
    for f in fs {
        let p = outcome(&f);
        assert_eq!(p.status, ProbeStatus::Measured, "{}", p.note);
        assert_eq!(p.measured["contact_dim"], 6.0);
        assert_eq!(p.measured["contact_friction"], 1.0);
        assert!(p.measured["slide_m"] < 0.002, "{}", p.note);
    }
}

/// The static rule leaves condim-1 feet on a condim-3 floor alone because MuJoCo combines them
/// to dim 3; the contacts MuJoCo really builds say the same.
#[test]
fn condim1_feet_on_a_condim3_floor_get_dim3_contacts_in_mujoco() {
    let l =
        loaded("fixtures/rules/foot-collision-geometry/valid_condim1_feet_on_condim3_floor.xml");
    let s = modellint::probe::slide::run(&l.robot).unwrap();
    let feet: Vec<usize> =
        l.robot.geoms.iter().filter(|g| g.body != 0 && g.condim == 1).map(|g| g.id).collect();
    assert!(!feet.is_empty());
    for g in feet {
        let b = s.built.get(&g).unwrap_or_else(|| panic!("geom {g} never touched the floor"));
        assert_eq!((b.dim, b.dim_min), (3, 3), "geom {g}");
        assert!((b.friction - 0.6).abs() < 1e-12);
    }
}

/// Feet that touch the floor only through explicit `<contact><pair>`s (their own masks are 0):
/// the stance runs see the floor and the loaded feet, and the slide reads the pair's condim 1
/// (the geoms say 3), so the foot slides as if frictionless.
#[test]
fn pair_only_feet_are_stood_on_and_measured_with_the_pairs_values() {
    for f in slide_findings("fixtures/rules/foot-collision-geometry/invalid_pair_only_condim1.xml")
    {
        let p = outcome(&f);
        assert_eq!(p.status, ProbeStatus::Measured, "{}", p.note);
        assert!(p.preconditions.iter().all(|c| c.met), "{:?}", p.preconditions);
        assert_eq!(p.measured["contact_dim"], 1.0);
        let free_slide = 0.5 * 0.05 * 9.81 * 0.5 * 0.5;
        let s = p.measured["slide_m"];
        assert!((s - free_slide).abs() < 0.1 * free_slide, "slid {s} m, free {free_slide} m");
    }
}

/// A pair that sets condim 3 on condim-1 feet over a condim-1 floor: the static rule leaves the
/// feet alone, and MuJoCo indeed builds dim-3 contacts at the pair's friction.
#[test]
fn a_pair_that_fixes_condim1_feet_gets_dim3_contacts_in_mujoco() {
    let l = loaded("fixtures/rules/foot-collision-geometry/valid_pair_fixes_condim1.xml");
    assert_eq!(l.robot.pairs.len(), 6);
    let s = modellint::probe::slide::run(&l.robot).unwrap();
    let feet: Vec<usize> =
        l.robot.geoms.iter().filter(|g| g.body != 0 && g.condim == 1).map(|g| g.id).collect();
    assert_eq!(feet.len(), 6);
    for g in feet {
        let b = s.built.get(&g).unwrap_or_else(|| panic!("geom {g} never touched the floor"));
        assert_eq!((b.dim, b.dim_min), (3, 3), "geom {g}");
        assert!((b.friction - 0.6).abs() < 1e-12);
    }
}

/// Both sides of a mirror-symmetric model get the mirror-image experiment, so the same
/// numbers and the same verdict (the right joint steps as the mirror of the left: opposite sign
/// for the roll axes, which a mirror reverses; the same sign for the pitch axes).
#[test]
fn mirror_pairs_get_the_same_step_response() {
    let l = loaded("fixtures/probes/mirror_humanoid.xml");
    for (a, b) in [("left_hip_roll", "right_hip_roll"), ("left_hip_pitch", "right_hip_pitch")] {
        let ra = impulse::step_response(&l.robot, l.robot.joint(a).unwrap().id, None).unwrap();
        let rb = impulse::step_response(&l.robot, l.robot.joint(b).unwrap().id, None).unwrap();
        let (za, zb) = (ra.zeta.expect("rings"), rb.zeta.expect("rings"));
        assert!((za - zb).abs() < 1e-6 * za, "{a} ζ {za} vs {b} ζ {zb}");
        assert!((ra.overshoot - rb.overshoot).abs() < 1e-6, "{} vs {}", ra.overshoot, rb.overshoot);
        let (wa, wb) = (ra.omega_n.unwrap(), rb.omega_n.unwrap());
        assert!((wa - wb).abs() < 1e-6 * wa, "{a} ω {wa} vs {b} ω {wb}");
    }
    let fs = probed("fixtures/probes/mirror_humanoid.xml", "underdamped-pd-gains");
    let verdict = |n: &str| {
        let f = fs.iter().find(|f| f.message.contains(&format!("`{n}`"))).unwrap();
        (f.severity, outcome(f).status)
    };
    assert_eq!(verdict("left_hip_roll"), verdict("right_hip_roll"));
    assert_eq!(verdict("left_hip_pitch"), verdict("right_hip_pitch"));
}

/// Dry friction that is a large share of the step's servo torque shapes the step response (here
/// it stops the ringing: measured ζ ≈ 0.9 against the viscous 0.22), so the run can neither
/// confirm nor refute a damping claim; without the friction the same servo confirms it.
#[test]
fn dry_friction_makes_the_step_response_inconclusive_not_a_refutation() {
    let fs = probed("fixtures/probes/servo_dry_friction.xml", "underdamped-pd-gains");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
    let why = p.reason.as_deref().unwrap_or("");
    assert!(why.contains("frictionloss 1 N·m"), "{why}");
    let fr = p.preconditions.iter().find(|c| c.name == "friction_small").expect("recorded");
    assert!(!fr.met);
    assert_eq!(fs[0].severity, modellint::finding::Severity::Error);
    assert!(!fs[0].message.contains("refuted"));

    let fs = probed("fixtures/probes/servo_underdamped.xml", "underdamped-pd-gains");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Confirmed, "{}", p.note);
    assert!(p.preconditions.iter().all(|c| c.met), "{:?}", p.preconditions);
    assert!(p.preconditions.iter().any(|c| c.name == "friction_small"));
}

/// One link of inertia `i` kg·m² on a vertical hinge (gravity exerts no torque), a position
/// servo of stiffness `kp` with kv chosen for damping ratio `zeta` from the closed form
/// kv = 2ζ√(kp·I): written here, not by the code under test, so ζ is known. `joint` and
/// `actuator` are extra attributes of the hinge and of the servo.
fn servo_file(
    name: &str,
    (kp, i, zeta): (f64, f64, f64),
    timestep: &str,
    joint: &str,
    actuator: &str,
) -> std::path::PathBuf {
    let kv = 2.0 * zeta * (kp * i).sqrt();
    let xml = format!(
        r#"<mujoco model="{name}">
  <option timestep="{timestep}" integrator="implicitfast"/>
  <worldbody>
    <body name="link">
      <joint name="hinge" axis="0 0 1"{joint}/>
      <inertial pos="0 0 0" mass="1" diaginertia="{i} {i} {i}"/>
    </body>
  </worldbody>
  <actuator><position name="hinge" joint="hinge" kp="{kp}" kv="{kv}"{actuator}/></actuator>
</mujoco>
"#
    );
    let dir = std::env::temp_dir().join(format!("modellint-probes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(&path, xml).unwrap();
    path
}

/// A servo of kp 100 on 0.1 kg·m² (ω_n 31.6 rad/s) at damping ratio `zeta`, with dry friction
/// `friction` N·m, at a 0.2 ms step ([`servo_file`]).
fn hand_built_servo(name: &str, zeta: f64, friction: f64) -> Loaded {
    let joint = format!(" frictionloss=\"{friction}\"");
    let path = servo_file(name, (100.0, 0.1, zeta), "0.0002", &joint, "");
    loaded(path.to_str().unwrap())
}

/// A slow, lightly damped servo (inertia 1 kg·m², kp 30: ω_n 5.48 rad/s) at damping ratio
/// `zeta`, range and ctrlrange ±1 ([`servo_file`]).
fn slow_servo(name: &str, zeta: f64) -> std::path::PathBuf {
    servo_file(name, (30.0, 1.0, zeta), "0.002", " range=\"-1 1\"", " ctrlrange=\"-1 1\"")
}

/// A joint that still rings when the 2 s run ends (envelope exp(−ζω_n t): ζ 0.05 keeps 58 % of
/// its first swing, ζ 0.09 37 %) is read at the centre of its swing, not at whatever point of
/// the swing the run's last tenth caught: it followed the step (within 1 % of it), and the
/// measured ζ confirms the claim. A well-damped joint of the same servo (ζ 0.5) has settled,
/// and its level is the last tenth's mean, as before.
#[test]
fn a_joint_still_ringing_at_the_end_of_the_run_is_read_at_its_centre() {
    for (k, &zeta) in [0.05, 0.09, 0.5].iter().enumerate() {
        let path = slow_servo(&format!("slow_ringing_{k}"), zeta);
        let l = loaded(path.to_str().unwrap());
        let j = l.robot.joint("hinge").unwrap().id;
        let r = impulse::step_response(&l.robot, j, None).unwrap();
        assert!((r.final_level - 1.0).abs() < 0.01, "ζ {zeta}: level {} ({r:?})", r.final_level);
        let z = r.zeta.expect("an underdamped servo overshoots");
        assert!((z - zeta).abs() < 0.02, "ζ {zeta}: measured {z}");
        if zeta < 0.1 {
            assert!(r.ringing, "ζ {zeta}: still ringing at the end: {r:?}");
            let fs = probed(path.to_str().unwrap(), "underdamped-pd-gains");
            let p = outcome(&fs[0]);
            assert_eq!(p.status, ProbeStatus::Confirmed, "ζ {zeta}: {} {:?}", p.note, p.reason);
            assert!(p.preconditions.iter().all(|c| c.met), "{:?}", p.preconditions);
        } else {
            assert!(!r.ringing, "ζ {zeta}: settled: {r:?}");
        }
    }
}

/// Step overshoot of a second-order loop, closed form.
fn closed_form_overshoot(z: f64) -> f64 {
    (-std::f64::consts::PI * z / (1.0 - z * z).sqrt()).exp()
}

/// The step response's ζ is the loop's: on a hand-built joint of known ζ it matches the closed
/// form, and so does the overshoot it is read from; with dry friction (6 % of the step's servo
/// torque, which stops the joint short of the target and takes a fixed amount off every swing)
/// the first swing still gives the viscous ζ within 0.01, where the overshoot of the settled
/// level (0.7 % at ζ 0.65: ζ ≈ 0.85) and the decrement (no second peak) do not.
#[test]
fn step_response_zeta_matches_a_hand_built_joint_of_known_zeta() {
    for (k, &zeta) in [0.3, 0.5, 0.6, 0.65].iter().enumerate() {
        for friction in [0.0, 0.3] {
            let l = hand_built_servo(&format!("known_zeta_{k}_{}", friction > 0.0), zeta, friction);
            let j = l.robot.joint("hinge").unwrap().id;
            let r = impulse::step_response(&l.robot, j, None).unwrap();
            let z = r
                .zeta
                .unwrap_or_else(|| panic!("ζ {zeta}, friction {friction}: no overshoot: {r:?}"));
            assert!(
                (z - zeta).abs() < 0.02,
                "ζ {zeta}, frictionloss {friction}: measured ζ {z} (decrement {:?}, overshoot {} of the settled level)",
                r.zeta_decrement,
                r.overshoot
            );
            let os = closed_form_overshoot(zeta);
            // MuJoCo's dry friction is a soft constraint: a little under frictionloss while the
            // joint moves, so the band is a little narrower than assumed.
            let tol = if friction > 0.0 { 0.15 } else { 0.05 };
            assert!(
                (r.loop_overshoot - os).abs() < tol * os,
                "ζ {zeta}, frictionloss {friction}: loop overshoot {} vs closed form {os}",
                r.loop_overshoot
            );
            if friction > 0.0 && zeta >= 0.5 {
                // The settled level's overshoot is far from the loop's: not a ζ measurement.
                assert!(r.overshoot < 0.6 * os, "settled-level overshoot {} vs {os}", r.overshoot);
            }
        }
    }
}

/// A confirmed step sets the level from the overshoot it measured: the upright link's computed
/// ζ 0.6 (9.5 % overshoot, past twice the 4.6 % ζ_min 0.7 accepts: error) measures under twice
/// (gravity takes m·g·l off the servo's stiffness): warning. An inconclusive run keeps the
/// computed level (the dry-friction test above).
#[test]
fn a_measured_step_sets_the_underdamped_level() {
    let path = "fixtures/rules/underdamped-pd-gains/invalid_measured_level.xml";
    let l = loaded(path);
    let static_level = run_rules(&l)
        .into_iter()
        .find(|f| f.rule == "underdamped-pd-gains")
        .map(|f| f.severity)
        .unwrap();
    assert_eq!(static_level, modellint::finding::Severity::Error);
    let fs = probed(path, "underdamped-pd-gains");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Confirmed, "{}", p.note);
    let os = p.measured["loop_overshoot"];
    let accepted = closed_form_overshoot(0.7);
    assert!(os > 1.25 * accepted && os <= 2.0 * accepted, "measured overshoot {os}");
    assert_eq!(fs[0].severity, modellint::finding::Severity::Warning, "{}", fs[0].message);
    assert!(fs[0].message.contains("measured step overshoot"), "{}", fs[0].message);
}

/// Runs the CLI on `model` (its spec beside it, if any) and returns its JSON output.
fn cli_json(model: &Path, extra: &[&str]) -> serde_json::Value {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg(model)
        .args(["--format", "json"])
        .args(extra)
        .env_remove("GITHUB_ACTIONS")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(&text).unwrap_or_else(|e| {
        panic!(
            "{}: not JSON ({e}): {text}\n{}",
            model.display(),
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

/// The probe outcomes of `rule`'s findings in a CLI JSON output.
fn cli_probes(v: &serde_json::Value, rule: &str) -> Vec<serde_json::Value> {
    let fs: Vec<_> = v["findings"]
        .as_array()
        .expect("findings")
        .iter()
        .filter(|f| f["rule"] == rule)
        .map(|f| {
            assert_ne!(f["severity"], "info", "{}", f["message"]);
            f["probe"].clone()
        })
        .collect();
    assert!(!fs.is_empty(), "no {rule} finding in {v}");
    fs
}

/// A copy of a fixture (and its spec) with `from` replaced by `to`, in a scratch directory.
fn edited_copy(path: &str, from: &str, to: &str, tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("modellint_probes_{tag}_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = Path::new(path);
    let text = std::fs::read_to_string(src).unwrap();
    assert!(text.contains(from), "{path} has no {from:?}");
    let dst = dir.join(src.file_name().unwrap());
    std::fs::write(&dst, text.replace(from, to)).unwrap();
    let toml = src.with_extension("toml");
    if toml.exists() {
        std::fs::copy(&toml, dst.with_extension("toml")).unwrap();
    }
    dst
}

/// A flipped gear on a joint an equality locks: the command cannot move the target, so the
/// direction probe cannot see the sign. Inconclusive with the reason, never confirmed (before
/// the fix it was confirmed as "a positive command moved no joint"); the same model unlocked is
/// confirmed.
#[test]
fn a_direction_probe_whose_target_cannot_move_is_inconclusive() {
    let path = "fixtures/probes/locked_flipped_gear.xml";
    let v = cli_json(Path::new(path), &[]);
    for p in cli_probes(&v, "actuator-mapping") {
        assert_eq!(p["name"], "actuator-direction", "{p}");
        assert_eq!(p["status"], "inconclusive", "{p}");
        let reason = p["reason"].as_str().unwrap_or("");
        assert!(reason.contains("did not move the targeted joint `hinge`"), "{reason}");
        assert!(reason.contains("held by equality `lock`"), "{reason}");
        let pre = p["preconditions"].as_array().unwrap();
        let moved = pre.iter().find(|c| c["name"] == "target_moved").expect("recorded");
        assert_eq!(moved["met"], false, "{p}");
    }
    let free = edited_copy(
        path,
        "<joint name=\"lock\"",
        "<joint name=\"lock\" active=\"false\"",
        "unlocked",
    );
    let v = cli_json(&free, &[]);
    for p in cli_probes(&v, "actuator-mapping") {
        assert_eq!(p["status"], "confirmed", "{p}");
        let pre = p["preconditions"].as_array().unwrap();
        assert!(pre.iter().any(|c| c["name"] == "target_moved" && c["met"] == true), "{p}");
    }
}

/// Coincident boxes: MuJoCo's contact list has them 100 mm deep (the rule fires), but
/// mj_geomDistance, which the probe tracks the pair's separation with, finds no overlap. The
/// probe's `overlap_at_keyframe` fails: inconclusive with the reason, naming both measures. The
/// same fingers moved 20 mm apart overlap in both: confirmed with the precondition met.
#[test]
fn a_penetration_probe_that_sees_no_overlap_is_inconclusive() {
    let path = "fixtures/probes/coincident_boxes.xml";
    let only = ["--select", "self-collision-at-keyframe"];
    let v = cli_json(Path::new(path), &only);
    for p in cli_probes(&v, "self-collision-at-keyframe") {
        assert_eq!(p["name"], "keyframe-penetration", "{p}");
        assert_eq!(p["status"], "inconclusive", "{p}");
        let reason = p["reason"].as_str().unwrap_or("");
        assert!(reason.contains("mj_geomDistance finds no overlap"), "{reason}");
        assert!(reason.contains("contact list has them 0.1 m deep"), "{reason}");
        let pre = p["preconditions"].as_array().unwrap();
        let overlap = pre.iter().find(|c| c["name"] == "overlap_at_keyframe").expect("recorded");
        assert_eq!(overlap["met"], false, "{p}");
    }
    let apart = edited_copy(
        path,
        "<body name=\"finger_b\" pos=\"0 0 -0.08\">",
        "<body name=\"finger_b\" pos=\"0.02 0 -0.08\">",
        "apart",
    );
    let v = cli_json(&apart, &only);
    for p in cli_probes(&v, "self-collision-at-keyframe") {
        assert_eq!(p["status"], "confirmed", "{p}");
        let pre = p["preconditions"].as_array().unwrap();
        assert!(pre.iter().any(|c| c["name"] == "overlap_at_keyframe" && c["met"] == true), "{p}");
    }
}

/// A probe result belongs only to the claim it measures (issue 45 item 2). The direction run
/// drives the actuator and sees which way its joint moves: that tests a sign against the spec,
/// not a ctrlrange that reaches outside the joint's range nor an actuator on a joint the spec
/// marks passive. Those findings carry no probe result (before the fix they were "inconclusive:
/// probe `actuator-direction` … moved: knee +0.0488"); the flipped gear is still driven.
#[test]
fn direction_probe_results_attach_only_to_the_sign_claim() {
    for path in [
        "fixtures/rules/actuator-mapping/invalid_ctrlrange.xml",
        "fixtures/rules/actuator-mapping/invalid_far_outside.xml",
        "fixtures/rules/actuator-mapping/invalid_passive.xml",
    ] {
        for f in probed(path, "actuator-mapping") {
            assert!(f.probe.is_none(), "{path}: {} carries {:?}", f.message, f.probe);
            assert!(f.claim.is_none(), "{path}: {} carries a claim", f.message);
        }
    }
    let fs = probed("fixtures/probes/locked_flipped_gear.xml", "actuator-mapping");
    assert!(fs.iter().all(|f| f.probe.as_ref().is_some_and(|p| p.name == "actuator-direction")));
}

/// The stance probes on a floated copy: a legged URDF (its root link welded to the world by
/// MuJoCo's importer) and a base of three slides and a ball stand on a copy with a free joint,
/// and the verdict says what the copy added.
#[test]
fn a_welded_urdf_biped_stands_on_a_floated_copy_and_its_tilted_toe_is_confirmed() {
    let fs = probed("fixtures/rules/toe-tilt/invalid_welded_urdf_biped.urdf", "toe-tilt");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Confirmed, "{}", p.note);
    assert!(p.preconditions.iter().all(|c| c.met), "{:?}", p.preconditions);
    // The lowest point, by hand from the file: hip -0.1, knee -0.3, ankle -0.3, toe joint
    // -0.04 below the foot; the toe box (0.05 × 0.02, pitched 0.03 rad) reaches
    // 0.025·sin 0.03 + 0.01·cos 0.03 below its centre.
    let low = -0.1 - 0.3 - 0.3 - 0.04 - (0.025 * 0.03f64.sin() + 0.01 * 0.03f64.cos());
    let z = p.measured["floor_added_z_m"];
    assert!((z - low).abs() < 1e-9, "floor at {z}, lowest point {low}");
    assert!(p.note.contains("probed on a floated copy: free joint added at `trunk`"), "{}", p.note);
    assert!(p.note.contains("floor added at z = -0.7507 m"), "{}", p.note);
    assert!(p.note.contains("its 8 joints held at qpos0"), "{}", p.note);
    // The copy carries the trunk too: the weight is the file's 8 + 2 × (3 + 2 + 0.8 + 0.1) kg.
    let w = p.measured["weight_n"];
    assert!((w - 19.8 * 9.81).abs() < 1e-6, "weight {w}");
}

#[test]
fn a_slide_ball_base_stands_on_a_floated_copy_and_its_low_toe_is_confirmed() {
    let fs = probed("fixtures/rules/toe-tilt/invalid_slide_ball_toe.xml", "toe-tilt");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Confirmed, "{}", p.note);
    assert!(p.note.contains("free joint added at `left_foot`"), "{}", p.note);
    // The model has its own floor: none added.
    assert!(!p.measured.contains_key("floor_added_z_m"));
    assert!(!p.note.contains("floor added"), "{}", p.note);
}

/// A level foot on the floated copy: every ground geom carries load (what refutes a toe claim).
fn assert_level_feet_loaded(path: &str) {
    use modellint::probe::float::{StanceModel, stance_model};
    let l = loaded(path);
    let StanceModel::Copy(c) = stance_model(&l) else { panic!("{path}: no floated copy") };
    let s = settle::run(&c.robot).unwrap();
    assert!(!s.stance.diverged, "{path}");
    assert!(s.stance.support_load > 0.9 * s.stance.weight, "{path}: {:?}", s.stance);
    assert!(s.stance.base_tilt_deg < 1.0 && s.stance.base_drop.abs() < 0.01, "{path}");
    // The lowest geoms of the copy (those within 1 mm of the floor at the start) all carry load.
    let floor = c.floor_z.unwrap_or(0.0);
    let low: Vec<usize> = c
        .robot
        .geoms
        .iter()
        .filter(|g| g.collides() && g.body != 0)
        .map(|g| g.id)
        .filter(|&g| {
            modellint::rules::geometry::shapes::Placed::of(&c.robot, g).lowest()[2] < floor + 1e-3
        })
        .collect();
    assert!(low.len() >= 2, "{path}: {low:?}");
    for g in low {
        let load = s.geom_load.get(&g).copied().unwrap_or(0.0);
        assert!(load > 0.02 * s.stance.weight / 2.0, "{path}: geom {g} carries {load} N");
    }
}

#[test]
fn level_feet_carry_load_on_the_floated_copies() {
    assert_level_feet_loaded("fixtures/rules/toe-tilt/valid_welded_urdf_biped.urdf");
    assert_level_feet_loaded("fixtures/rules/toe-tilt/valid_slide_ball_base.xml");
}

#[test]
fn an_arm_and_a_free_robot_are_not_floated() {
    use modellint::probe::float::needs_float;
    for path in [
        "fixtures/rules/toe-tilt/valid_urdf_table_arm.urdf",
        "fixtures/rules/welded-legged-base/valid_ceiling_arm.urdf",
        "fixtures/rules/welded-legged-base/valid_wheeled_base.urdf",
        "fixtures/rules/toe-tilt/invalid.xml",
        "fixtures/probes/stance_robot_file_scene.xml",
    ] {
        assert!(needs_float(&loaded(path).robot).is_none(), "{path}");
    }
}

#[test]
fn a_base_the_copy_cannot_float_is_inconclusive_with_the_reason() {
    let fs = probed("fixtures/rules/toe-tilt/invalid_slide_ball_unnamed_base.xml", "toe-tilt");
    let p = outcome(&fs[0]);
    assert_eq!(p.status, ProbeStatus::Inconclusive, "{}", p.note);
    let reason = p.reason.unwrap_or_default();
    assert!(reason.contains("no floated copy could be built"), "{reason}");
    assert!(reason.contains("has no name"), "{reason}");
    let free = p.preconditions.iter().find(|c| c.name == "free_base").unwrap();
    assert!(!free.met);
}
