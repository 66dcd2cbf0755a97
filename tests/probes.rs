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
    assert!(!s.diverged);
    assert!(s.geom_load.values().any(|&f| f > 0.1));
}

#[test]
fn settle_probe_loads_every_geom_of_a_flat_foot() {
    let l = loaded("fixtures/rules/toe-tilt/valid.xml");
    let s = settle::run(&l.robot).unwrap();
    assert!(!s.diverged);
    let feet: Vec<_> = l.robot.geoms.iter().filter(|g| g.collides() && g.body != 0).collect();
    let total: f64 = feet.iter().map(|g| s.geom_load.get(&g.id).copied().unwrap_or(0.0)).sum();
    assert!(total > 0.1, "the robot stands on its feet");
    for g in feet {
        let load = s.geom_load.get(&g.id).copied().unwrap_or(0.0);
        assert!(load > 0.02 * total / 2.0, "geom {} carries {load} N of {total} N", g.name);
    }
}
