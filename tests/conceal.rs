//! Concealed-effect benchmark, reduced (the full matrix: `bench/conceal.sh`, results in
//! docs/conceal-benchmark.md). The cases on the 12-joint Asimov legs (minutes each on two cores)
//! three of the four Stribeck cases on arm3 (over a minute each; the pendulum's, Stribeck
//! against Coulomb on a light servo, stays) and the arm3 backlash + position offset pair (two
//! other arm3 pairs stay) are `#[ignore]`d here so that `.ci/run` stays well
//! under its limit: `bench/conceal_long.sh` (this file) and `bench/long_tests.sh` (every long
//! test) run them. Hidden effects → synthetic recordings at 88 Hz with jitter,
//! noise, 12-bit quantisation and drops → blind `fit` → scored against the truth, with the
//! held-out MAE measured on fresh episodes the fit never saw.

#[path = "../bench/conceal_core.rs"]
mod conceal_core;

use conceal_core::*;

fn report(s: &Score) {
    eprint!("{}{}", table_header(), table_row(s));
}

/// Single effect: found (recall 1, nothing invented), parameters within 10 % (delay: 1 physics
/// step), held-out MAE reduced by at least 80 % (of the part above the noise floor when the
/// floor makes 80 % of the recorded MAE unreachable: `Score::mae_ok`).
fn single(c: Case) {
    let s = run(&c);
    report(&s);
    assert_eq!(s.recall(), Some(1.0), "{}: not found; detected {:?}", c.name, s.detected);
    assert_eq!(s.fp, 0, "{}: invented effects; detected {:?}", c.name, s.detected);
    assert!(
        s.params_ok(),
        "{}: parameter error {:?} / delay {:?} steps; detected {:?}",
        c.name,
        s.param_rel,
        s.delay_steps,
        s.detected
    );
    assert!(
        s.mae_ok(),
        "{}: held-out MAE {} → {} (floor {}): {:.0} %",
        c.name,
        s.mae_before,
        s.mae_after,
        s.mae_floor,
        100.0 * s.reduction()
    );
}

#[test]
fn conceal_arm3_action_delay() {
    single(arm3_case(
        "arm3 action_delay",
        Kind::Single,
        vec![("action_delay", vec![0.025])],
        Noise::Real,
        7,
    ));
}

#[test]
fn conceal_arm3_armature() {
    single(arm3_case(
        "arm3 armature",
        Kind::Single,
        vec![("armature", vec![0.04])],
        Noise::Real,
        7,
    ));
}

#[test]
fn conceal_arm3_position_offset() {
    single(arm3_case(
        "arm3 position_offset",
        Kind::Single,
        vec![("position_offset", vec![0.05])],
        Noise::Real,
        7,
    ));
}

/// A humanoid-sized knee (kp 250 N·m/rad, 150 N·m): damping, dry friction and an effort
/// limit beyond the fixed bounds sized for small servos (5 N·m·s/rad, 5 N·m, 50 N·m). Before
/// the bounds grew with the drive, damping 9 came out as a servo gain error (kd × 2.4),
/// Coulomb 8 as 5.0 (on its bound) plus an invented backlash, and the limit was not found.
#[test]
fn conceal_heavy_knee_viscous_damping() {
    single(heavy_knee_case(
        "knee viscous_damping",
        Kind::Single,
        vec![("viscous_damping", vec![9.0])],
        Noise::Real,
        7,
    ));
}

#[test]
fn conceal_heavy_knee_coulomb_friction() {
    single(heavy_knee_case(
        "knee coulomb_friction",
        Kind::Single,
        vec![("coulomb_friction", vec![8.0])],
        Noise::Real,
        7,
    ));
}

#[test]
fn conceal_heavy_knee_torque_limit() {
    single(heavy_knee_case(
        "knee torque_limit",
        Kind::Single,
        vec![("torque_limit", vec![60.0])],
        Noise::Real,
        7,
    ));
}

#[test]
fn conceal_heavy_knee_control_selects_nothing() {
    let s = run(&heavy_knee_case("knee control", Kind::Control, vec![], Noise::Real, 11));
    report(&s);
    assert!(s.detected.is_empty(), "invented effects: {:?}", s.detected);
}

#[test]
fn conceal_rig_coulomb_friction() {
    single(rig_case(
        "rig coulomb_friction",
        Kind::Single,
        vec![("coulomb_friction", vec![0.03])],
        Noise::Real,
        5,
    ));
}

#[test]
fn conceal_rig_armature() {
    // Doubles the pendulum's inertia: far from linear, ranked 7th by the linearised diagnosis
    // (found through the every-effect candidates).
    single(rig_case("rig armature", Kind::Single, vec![("armature", vec![0.005])], Noise::Real, 5));
}

#[test]
fn conceal_arm3_torque_limit() {
    // Saturation confined to a few held-out windows (accepted by the decisive-improvement path).
    // Peak torque 1 N·m; the DC-motor line parameters (no-load speed, slope) left unlimited.
    single(arm3_case(
        "arm3 torque_limit",
        Kind::Single,
        vec![("torque_limit", vec![1.0, 1e4, 1e4])],
        Noise::Real,
        7,
    ));
}

#[test]
fn conceal_pendulum_stribeck_friction() {
    // Three parameters on the lightly damped servo (ζ ≈ 0.15), no quantisation: the simplex
    // needs its larger budget here — with 2× (as for 1–2 parameters) it stopped in the valley
    // at v_s 0.129 for 0.2, held-out MAE 1.01 mrad against a 0.41 mrad floor.
    single(
        pendulum_case(
            "pendulum stribeck_friction",
            Kind::Single,
            vec![("stribeck_friction", vec![0.06, 0.03, 0.2])],
            Noise::Real,
            5,
        )
        .unquantised(),
    );
}

/// Stribeck friction an order of magnitude above the other cases' (static 2 N·m on a kp-50
/// elbow: it holds the joint within ±0.04 rad of its command). From its fixed start
/// (0.1, 0.05, 0.1) the simplex ended at (0, 1.08, 0.055), training RMSE 2.5 mrad against 0.79
/// at the truth; the fit now also starts from the Coulomb fit on the same joint (Fs = Fd = c),
/// whichever start is better (`Effect::nests`).
#[test]
#[ignore = "long (over a minute on two cores): bench/long_tests.sh runs it"]
fn conceal_arm3_stribeck_friction_large_static() {
    single(arm3_case(
        "arm3 stribeck_friction large",
        Kind::Single,
        vec![("stribeck_friction", vec![2.0, 1.0, 0.2])],
        Noise::Real,
        7,
    ));
}

/// A slow servo: kp × 0.4, kd × 2 on arm3's elbow. Fitted from (1, 1) the gain error stepped
/// to the corner (3, 5) and ran out of iterations in the valley at (0.451, 2.263), 13 % off
/// (on other recordings it ended on kd's bound, and a gain error + damping pair was kept). A
/// multi-parameter fit that ends on a bound or before converging is started again from a
/// grid's best point: (0.401, 2.003).
/// A sharp breakaway (static 0.8 N·m, sliding 0.2, v_s 0.05 rad/s on arm3's elbow, 12-bit):
/// from the Coulomb fit's start (c, c, 0.1) the simplex ended at (0.357, 0.198, 0.150), a
/// wider, lower bump across a ridge (training RMSE 0.80 mrad against 0.67 at the truth). The
/// Stribeck fit also runs from the best of three sharper starts when one scores better.
#[test]
#[ignore = "long (over a minute on two cores): bench/long_tests.sh runs it"]
fn conceal_arm3_stribeck_friction_sharp_breakaway() {
    single(arm3_case(
        "arm3 stribeck_friction sharp",
        Kind::Single,
        vec![("stribeck_friction", vec![0.8, 0.2, 0.05])],
        Noise::Real,
        7,
    ));
}

#[test]
fn conceal_arm3_gain_error_slow_servo() {
    single(arm3_case(
        "arm3 gain_error slow",
        Kind::Single,
        vec![("gain_error", vec![0.4, 2.0])],
        Noise::Real,
        7,
    ));
}

/// Pair: both found, parameters within target, nothing invented.
#[test]
fn conceal_arm3_load_dependent_friction() {
    // 1 % dropped rows: two training episodes lose a row at a step command; without the gap mask
    // their transients dominate the objective and k comes out 15 % high.
    single(arm3_case(
        "arm3 load_dependent_friction",
        Kind::Single,
        vec![("load_dependent_friction", vec![0.05, 0.1])],
        Noise::Real,
        7,
    ));
}

#[test]
#[ignore = "long (over a minute on two cores): bench/long_tests.sh runs it"]
fn conceal_arm3_stribeck_friction_high_noise() {
    // σ 1 mrad, 3 % dropped rows: the held-out test alone cannot tell Stribeck from a 1-parameter
    // backlash; the training BIC in the Occam choice can. Found, nothing invented, the error at
    // the floor, all three parameters within 10 %. The velocity scale v_s was 16 % off (0.232
    // for 0.2) until the kept friction was re-fitted on short windows (the reshoot, gated on a
    // held-out improvement beyond noise: 0.2090); ungated, the re-fit followed the held-out
    // noise to v_s 0.285.
    let c = arm3_case(
        "arm3 stribeck_friction",
        Kind::Single,
        vec![("stribeck_friction", vec![0.3, 0.1, 0.2])],
        Noise::High,
        7,
    );
    let s = run(&c);
    report(&s);
    assert_eq!(s.recall(), Some(1.0), "{}: not found; detected {:?}", c.name, s.detected);
    assert_eq!(s.fp, 0, "{}: invented effects; detected {:?}", c.name, s.detected);
    let (_, _, p) = &s.detected[0];
    for (got, want) in [(p[0], 0.3), (p[1], 0.1), (p[2], 0.2)] {
        let tol = 0.10;
        assert!(
            (got - want).abs() <= tol * want,
            "{}: {got} vs {want} (±{tol}); detected {:?}",
            c.name,
            s.detected
        );
    }
    assert!(
        s.mae_ok(),
        "{}: held-out MAE {} → {} (floor {})",
        c.name,
        s.mae_before,
        s.mae_after,
        s.mae_floor
    );
}

#[test]
#[ignore = "12-joint legs, minutes each: bench/conceal_long.sh runs them"]
fn conceal_asimov_one_knee_is_not_smeared_over_both() {
    // Leg joints on a test stand; damping on the left knee only. The mirror completion tries
    // both knees as a group; held-out must keep the one-joint fit: nothing on the right knee.
    // Until the rollout difference step was widened (docs/fitting.md, step 5, "Finite differences") the damping
    // fit stopped at 2.48 on the error's small-scale ripple and a servo gain error (kp × 0.95,
    // kd × 1.49) won instead; now: viscous damping on the left knee within 10 %.
    single(asimov_case(
        "asimov left knee viscous_damping",
        Kind::Single,
        vec![("viscous_damping", vec!["left_knee".to_string()], vec![3.0])],
        Noise::Real,
        7,
    ));
}

/// Stribeck friction on one Asimov knee (12-bit encoders). The single Stribeck fit stops at the
/// Stribeck velocity's lower bound, where Coulomb friction 1.51 won (held-out −74 %). The
/// Stribeck + backlash look-ahead pair reaches (1.949, 0.970, 0.203) with a backlash that is
/// not needed; that Stribeck fit is a restart of the single one and now wins (held-out
/// −86 %, MAE 13.9 → 0.66 mrad against a 0.54 floor). Fails if the pair restart goes.
#[test]
#[ignore = "12-joint legs, minutes each: bench/conceal_long.sh runs them"]
fn conceal_asimov_knee_stribeck_12bit() {
    single(asimov_case(
        "asimov stribeck_friction@left_knee",
        Kind::Single,
        vec![("stribeck_friction", vec!["left_knee".to_string()], vec![2.0, 1.0, 0.2])],
        Noise::Real,
        7,
    ));
}

/// A 15 ms action delay on one Asimov knee, unquantised encoders. Both knees ranked for the
/// delay, and the candidate list replaced the one knee by the pair: fitted on both knees the
/// delay was 6.4 ms and lost to damping + armature on the left knee (0.86, 0.109), an invented
/// pair. The joint and its mirror pair now compete; fitted on the one knee it is 15.0 ms
/// (held-out −66 %, at the noise floor). Fails if the one-joint candidate goes again.
#[test]
#[ignore = "12-joint legs, minutes each: bench/conceal_long.sh runs them"]
fn conceal_asimov_knee_delay_one_side_unquantised() {
    single(
        asimov_case(
            "asimov action_delay@left_knee",
            Kind::Single,
            vec![("action_delay", vec!["left_knee".to_string()], vec![0.015])],
            Noise::Real,
            7,
        )
        .unquantised(),
    );
}

/// Load-dependent friction (0.5, 0.1) on one Asimov knee, 12-bit encoders. A sticking joint
/// keeps the start error of its quantised first reading, and the single-shooting fit bent the
/// load coefficient to it: (0.488, 0.088), 12 % low. The kept friction is now re-fitted on 1 s
/// windows (multiple shooting; `reshoot`): (0.490, 0.099). Fails if that re-fit goes.
#[test]
#[ignore = "12-joint legs, minutes each: bench/conceal_long.sh runs them"]
fn conceal_asimov_knee_load_dependent_friction_12bit() {
    single(asimov_case(
        "asimov load_dependent_friction@left_knee",
        Kind::Single,
        vec![("load_dependent_friction", vec!["left_knee".to_string()], vec![0.5, 0.1])],
        Noise::Real,
        7,
    ));
}

/// A 2 N·m torque limit on one Asimov knee, unquantised encoders. Clamped in the hook, the
/// servo's kv stayed in `implicitfast`'s velocity derivative while saturated and the limit came
/// out 2.025 with the held-out error short of the target; as MuJoCo's own `forcerange` the fit
/// needs a log-scale search (a uniform grid over 0.05–50 N·m misses the narrow optimum, and
/// nothing was found): 1.996, at the noise floor. Fails if either goes.
#[test]
#[ignore = "12-joint legs, minutes each: bench/conceal_long.sh runs them"]
fn conceal_asimov_knee_torque_limit_unquantised() {
    single(
        asimov_case(
            "asimov torque_limit@left_knee",
            Kind::Single,
            vec![("torque_limit", vec!["left_knee".to_string()], vec![2.0, 1e4, 1e4])],
            Noise::Real,
            7,
        )
        .unquantised(),
    );
}

fn pair(c: Case) {
    let s = run(&c);
    report(&s);
    assert_eq!(s.recall(), Some(1.0), "{}: detected {:?}", c.name, s.detected);
    assert_eq!(s.fp, 0, "{}: invented effects; detected {:?}", c.name, s.detected);
    assert!(
        s.params_ok(),
        "{}: parameter error {:?} / delay {:?} steps; detected {:?}",
        c.name,
        s.param_rel,
        s.delay_steps,
        s.detected
    );
}

/// Long (the longest case left in this file): the pair class stays in `make test` with the two
/// arm3 pairs below, and backlash found blind with tests/fit.rs's `backlash_recovered` and
/// tests/independent_chain.rs's knee and all-joints gear plays.
#[test]
#[ignore = "long (two minutes on two cores): bench/long_tests.sh runs it"]
fn conceal_arm3_pair_backlash_position_offset() {
    pair(arm3_case(
        "arm3 backlash+position_offset",
        Kind::Pair,
        vec![("backlash", vec![0.04]), ("position_offset", vec![0.05])],
        Noise::Real,
        13,
    ));
}

#[test]
fn conceal_arm3_pair_armature_viscous_damping() {
    // Each alone is mimicked by a delay or a gain error on its bound: needs the pair look-ahead.
    pair(arm3_case(
        "arm3 armature+viscous_damping",
        Kind::Pair,
        vec![("armature", vec![0.04]), ("viscous_damping", vec![0.4])],
        Noise::Real,
        13,
    ));
}

#[test]
fn conceal_arm3_pair_coulomb_armature_unquantised() {
    // Armature passes alone and is taken with a servo gain error before the friction is found;
    // the gain error then absorbs part of the friction and stays needed while the others keep
    // their values. Only the drop with a re-fit of the rest removes it (the blind fit found
    // armature 0.029 + gain error 0.735/0.726 + load-dependent friction before it).
    pair(
        arm3_case(
            "arm3 coulomb_friction+armature",
            Kind::Pair,
            vec![("coulomb_friction", vec![0.15]), ("armature", vec![0.04])],
            Noise::Real,
            7,
        )
        .unquantised(),
    );
}

#[test]
fn conceal_arm3_group_with_an_exception() {
    // Damping on every joint, three times as much on the elbow: one value for the group and the
    // elbow's own (the pair look-ahead's "group with an exception"). A gain error on the elbow
    // (or on all joints) mimics the extra damping and was kept instead before.
    let mut c =
        arm3_case("arm3 viscous_damping group + elbow", Kind::Group, vec![], Noise::Real, 7);
    c.truth = vec![
        ("viscous_damping", vec!["shoulder_pitch".into(), "wrist_pitch".into()], vec![0.3]),
        ("viscous_damping", vec!["elbow_pitch".into()], vec![0.9]),
    ];
    pair(c);
}

#[test]
fn conceal_control_selects_nothing() {
    let s = run(&arm3_case("arm3 control", Kind::Control, vec![], Noise::Real, 11));
    report(&s);
    assert!(s.detected.is_empty(), "invented effects: {:?}", s.detected);
}

#[test]
fn conceal_rig_control_selects_nothing() {
    let s = run(&rig_case("rig control", Kind::Control, vec![], Noise::Real, 11));
    report(&s);
    assert!(s.detected.is_empty(), "invented effects: {:?}", s.detected);
}

/// The Asimov leg servos carry MuJoCo's own 20 ms actuator delay; a servo gain error and a
/// further 15 ms of transport delay on the left knee, from the CLI as a user runs it (the two
/// candidates and the knee only, to keep `make test` short; the blind fit is in the benchmark).
/// Both are kept, as a pair, within target. Until a hook's servo torque read the delayed
/// command, the truth could not even be represented: gain error alone (0.645, 1.232) won.
#[test]
#[ignore = "12-joint legs, minutes each: bench/conceal_long.sh runs them"]
fn conceal_asimov_knee_gain_error_and_delay_from_the_cli() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_modellint");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::temp_dir().join(format!("modellint-asimov-pair-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let model = root.join("models/asimov.xml");
    let s = Command::new(bin)
        .arg("synth")
        .arg(&model)
        .args(["--effects", "gain_error@left_knee=0.7,1.3;action_delay@left_knee=0.015"])
        .args(["--episodes", "8", "--duration", "4", "--amplitude", "0.15", "--seed", "7"])
        .args(["--suspend", "0.5", "--heldout", "1", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let f = Command::new(bin)
        .arg("fit")
        .arg(&model)
        .arg(out.join("episodes"))
        .args(["--effects", "gain_error,action_delay", "--joints", "left_knee"])
        .args(["--format", "json", "--quiet"])
        .output()
        .unwrap();
    assert!(f.status.code().is_some_and(|c| c <= 1), "{}", String::from_utf8_lossy(&f.stderr));
    let v: serde_json::Value = serde_json::from_slice(&f.stdout).unwrap();
    let found = v["missing_physics"].as_array().unwrap();
    let param = |effect: &str, name: &str| {
        found
            .iter()
            .find(|m| m["effect"] == effect && m["joints"] == serde_json::json!(["left_knee"]))
            .and_then(|m| m["params"][name].as_f64())
            .unwrap_or_else(|| panic!("{effect} not kept on left_knee: {found:?}"))
    };
    assert_eq!(found.len(), 2, "{found:?}");
    for (effect, name, truth) in [("gain_error", "kp_scale", 0.7), ("gain_error", "kd_scale", 1.3)]
    {
        let got = param(effect, name);
        assert!((got / truth - 1.0).abs() < 0.1, "{effect} {name} {got} for {truth}");
    }
    let delay = param("action_delay", "delay_s");
    assert!((delay - 0.015).abs() < 1.5e-3, "delay {delay} s for 0.015");
    std::fs::remove_dir_all(&out).ok();
}

/// Viscous damping and armature on the left knee, blind (all effects, all 12 leg joints,
/// unquantised): a servo gain error (kd × 1.30 is the damping, kp × 0.80 stands in for the
/// inertia) passed alone, beat damping alone and won (held-out MAE 2.11 mrad against a 0.40
/// floor); armature alone is not kept (it needs the damping), so the look-ahead never paired
/// the two. It now also fits the known mimicking pairs on a two-parameter winner's joints from
/// fresh single fits. (Coulomb friction + armature, where load-dependent friction stood in, is
/// the benchmark's.)
#[test]
#[ignore = "12-joint legs, minutes each: bench/conceal_long.sh runs them"]
fn conceal_asimov_knee_damping_armature_beats_gain_error() {
    pair(
        asimov_case(
            "asimov viscous_damping+armature@left_knee",
            Kind::Pair,
            vec![
                ("viscous_damping", vec!["left_knee".to_string()], vec![3.0]),
                ("armature", vec!["left_knee".to_string()], vec![0.15]),
            ],
            Noise::Real,
            7,
        )
        .unquantised(),
    );
}
