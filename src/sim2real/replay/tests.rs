use super::run::{base_pose, quat_ang_vel};
use super::*;

#[test]
fn angular_velocity_of_a_yaw_rotation() {
    let a: f64 = 0.01; // rad turned about z in dt
    let q0 = [1.0, 0.0, 0.0, 0.0];
    let q1 = [(a / 2.0).cos(), 0.0, 0.0, (a / 2.0).sin()];
    let w = quat_ang_vel(&q0, &q1, 0.002);
    assert!((w[2] - 5.0).abs() < 1e-9 && w[0].abs() < 1e-12 && w[1].abs() < 1e-12, "{w:?}");
}

#[test]
fn base_pose_interpolates_and_normalises() {
    let b = crate::sim2real::recording::BaseTrace {
        pos: vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]],
        quat: vec![[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
    };
    let p = base_pose(&[0.0, 1.0], &b, 0.5);
    assert!((p[0] - 0.5).abs() < 1e-12);
    let n: f64 = p[3..].iter().map(|x| x * x).sum();
    assert!((n - 1.0).abs() < 1e-12);
}

#[test]
fn replay_samples_first_state_exactly_and_holds_commands() {
    let mut map = crate::model::source::SourceMap::default();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bam_xl330/rig.xml");
    let robot = crate::model::load(&mut map, &path, None).unwrap();
    let rec = held_recording("servo", 200, 0.005, 0.3, None);
    let ep = replay(&robot, &rec, &ReplayOptions::default(), None).unwrap();
    assert_eq!(ep.q_sim[0][0], 0.3);
    assert!(ep.diverged.is_none());
    // Gravity pulls the arm below the held target: K (0.3 − q) = m g l sin q.
    let q = *ep.q_sim[0].last().unwrap();
    assert!(q < 0.3 && q > -0.5, "{q}");
    assert!(ep.q_sim[0].iter().all(|x| x.is_finite()));
}

#[test]
fn dropped_command_rows_are_filled_before_the_hold() {
    let mut map = crate::model::source::SourceMap::default();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bam_xl330/rig.xml");
    let robot = crate::model::load(&mut map, &path, None).unwrap();
    // A 2 rad/s ramp logged at the 100 Hz control rate; then the same log with rows 50–52 lost.
    let n = 120;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let c: Vec<f64> = t.iter().map(|&x| 2.0 * x).collect();
    let rec_of = |keep: &dyn Fn(usize) -> bool| {
        let idx: Vec<usize> = (0..n).filter(|&i| keep(i)).collect();
        let mut j = crate::sim2real::recording::JointTrace::new(
            "servo",
            idx.iter().map(|&i| c[i]).collect(),
        );
        j.q_cmd = Some(idx.iter().map(|&i| c[i]).collect());
        let t = idx.iter().map(|&i| t[i]).collect();
        Recording::at_100hz(t, vec![j])
    };
    let full = replay(&robot, &rec_of(&|_| true), &ReplayOptions::default(), None).unwrap();
    let lossy = rec_of(&|i| !(50..53).contains(&i));
    let err = |fill: bool| {
        let o = ReplayOptions {
            command_fill: if fill { Fill::Ramps } else { Fill::Hold },
            ..Default::default()
        };
        let ep = replay(&robot, &lossy, &o, None).unwrap();
        // Same timestamps after the gap: compare there.
        (0..lossy.t.len())
            .filter(|&k| lossy.t[k] > 0.5)
            .map(|k| (ep.q_sim[0][k] - full.q_sim[0][k + 3]).abs())
            .fold(0.0, f64::max)
    };
    let (held, filled) = (err(false), err(true));
    assert!(held > 1e-3, "holding the row before the gap should lag the ramp: {held}");
    assert!(filled < 0.2 * held, "filled {filled} vs held {held}");
}

#[test]
fn blow_up_is_reported_not_panicked() {
    let mut map = crate::model::source::SourceMap::default();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bam_xl330/rig.xml");
    let robot = crate::model::load(&mut map, &path, None).unwrap();
    let n = 100;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let mut j = crate::sim2real::recording::JointTrace::new("servo", vec![0.0; n]);
    // An absurd gain makes explicit Euler unstable.
    j.kp = Some(vec![1e9; n]);
    j.q_cmd = Some(vec![1.0; n]);
    let rec = Recording {
        source: "r.csv".into(),
        meta: Default::default(),
        control_rate_hz: None,
        control_t0_s: None,
        t,
        joints: vec![j],
        base: None,
    };
    let ep = replay(&robot, &rec, &ReplayOptions::default(), None).unwrap();
    assert!(ep.diverged.is_some());
    assert!(ep.q_sim[0].last().unwrap().is_nan());
}

#[test]
fn delayed_actuator_starts_from_the_first_command_not_zero() {
    // No gravity, no friction: a joint held at its command is at equilibrium, so the
    // replay of a recording that holds q = q_cmd = 0.5 must stay at 0.5 exactly. A delay
    // history left at zero would drive the servo towards 0 for the first 20 ms
    // (kp 50 × 0.5 rad = 25 N·m on 0.01 kg·m²).
    let xml = r#"<mujoco><option gravity="0 0 0" timestep="0.002"/>
  <worldbody><body><joint name="j" type="hinge" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/></body></worldbody>
  <actuator><position joint="j" kp="50" kv="2" delay="0.02" nsample="10"/></actuator>
</mujoco>"#;
    let (robot, dir) = robot_from_xml("delay", xml);
    let rec = held_recording("j", 100, 0.005, 0.5, Some(100.0));
    let ep = replay(&robot, &rec, &ReplayOptions::default(), None).unwrap();
    let worst = ep.q_sim[0].iter().map(|q| (q - 0.5).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-9, "the held joint moved by {worst} rad");
    std::fs::remove_dir_all(&dir).ok();
}

/// The robot of MJCF text `xml`, loaded from a file in a fresh temporary directory (returned,
/// for the caller to remove).
pub(crate) fn robot_from_xml(tag: &str, xml: &str) -> (Robot, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!("modellint-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("model.xml");
    std::fs::write(&path, xml).unwrap();
    let mut map = crate::model::source::SourceMap::default();
    (crate::model::load(&mut map, &path, None).unwrap(), dir)
}

/// One joint at rest at `q`, commanded to `q`: `n` rows every `dt` seconds.
fn held_recording(joint: &str, n: usize, dt: f64, q: f64, rate: Option<f64>) -> Recording {
    let mut j = crate::sim2real::recording::JointTrace::new(joint, vec![q; n]);
    j.q_cmd = Some(vec![q; n]);
    j.qd = Some(vec![0.0; n]);
    Recording {
        source: "r.csv".into(),
        meta: Default::default(),
        control_rate_hz: rate,
        control_t0_s: None,
        t: (0..n).map(|i| i as f64 * dt).collect(),
        joints: vec![j],
        base: None,
    }
}

/// A position servo on a light link, 2 ms steps, no gravity: the two tick-timing tests.
const SERVO_2MS: &str = r#"<mujoco><option gravity="0 0 0" timestep="0.002"/>
  <worldbody><body><joint name="j" type="hinge" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/></body></worldbody>
  <actuator><position joint="j" kp="50" kv="2"/></actuator>
</mujoco>"#;

/// A command switches at its control tick, wherever the first row falls. The expected
/// trajectory is MuJoCo stepped directly on the tick grid (100 Hz ticks at t = 0, 2 ms steps,
/// so every tick is a step boundary), the command changed exactly at each tick; the recording
/// is that trajectory sampled 1.3 ms into every tick (first row off the step grid, at rest,
/// before the first non-zero command). The replay must reproduce it at every row: before the
/// fix its steps sat at 1.3 ms + k × 2 ms, every command switched 0.7 ms late, and the joint
/// ran up to 9.6 mrad behind.
#[test]
fn commands_switch_at_their_ticks_when_the_first_row_is_off_the_step_grid() {
    let (robot, dir) = robot_from_xml("ticks", SERVO_2MS);
    // Ticks 0–2 hold 0 (the joint rests at its command), then a new command every tick.
    let ticks = 60usize;
    let cmd: Vec<f64> =
        (0..ticks).map(|k| if k < 3 { 0.0 } else { 0.3 * ((k as f64) * 0.7).sin() }).collect();
    // Reference: 5 steps of 2 ms per tick, ctrl set at the tick.
    let mut d = MjData::new(&robot.mj);
    let (mut ts, mut qs, mut vs) = (vec![0.0], vec![0.0], vec![0.0]);
    for &c in cmd.iter().take(ticks - 1) {
        d.ctrl_mut()[0] = c;
        for _ in 0..5 {
            d.step();
            ts.push(d.time());
            qs.push(d.qpos()[0]);
            vs.push(d.qvel()[0]);
        }
    }
    // Rows 1.3 ms into each tick, linearly interpolated between steps (as the replay samples).
    let t: Vec<f64> = (0..ticks - 2).map(|k| k as f64 * 0.01 + 0.0013).collect();
    let worst = worst_against_reference(&robot, (&ts, &qs, &vs), &t, &cmd, 100.0);
    assert!(worst < 1e-9, "replay off the tick-grid reference by {worst} rad");
    std::fs::remove_dir_all(&dir).ok();
}

/// A tick period that is no multiple of the timestep (30 Hz ticks, 2 ms steps): a step takes
/// the command in force at its middle, so each command switches at the step edge nearest its
/// tick (at most 1 ms either way, none late on average). Before, each switched at the first
/// step edge at or after its tick: 0–2 ms late, 1 ms on average, and an independent simulator's
/// clean humanoid logs at 49.985 Hz replayed at 1.40 mrad MAE (1.10 after).
#[test]
fn ticks_between_step_edges_switch_at_the_nearest_edge() {
    let (robot, dir) = robot_from_xml("ticks30", SERVO_2MS);
    let rate = 30.0;
    let ticks = 40usize;
    let cmd: Vec<f64> =
        (0..ticks).map(|k| if k < 2 { 0.0 } else { 0.3 * ((k as f64) * 0.7).sin() }).collect();
    // Reference: step k (from 2k ms) runs the command of the tick in force at 2k + 1 ms.
    let mut d = MjData::new(&robot.mj);
    let (mut ts, mut qs, mut vs) = (vec![0.0], vec![0.0], vec![0.0]);
    let steps = ((ticks - 2) as f64 / rate / 0.002).round() as usize;
    for k in 0..steps {
        let tick = ((k as f64 * 0.002 + 0.001) * rate).floor() as usize;
        d.ctrl_mut()[0] = cmd[tick];
        d.step();
        ts.push(d.time());
        qs.push(d.qpos()[0]);
        vs.push(d.qvel()[0]);
    }
    // One row 5 ms into each tick, the first at t = 0 on a tick and a step edge.
    let t: Vec<f64> =
        (0..ticks - 3).map(|k| if k == 0 { 0.0 } else { k as f64 / rate + 0.005 }).collect();
    let worst = worst_against_reference(&robot, (&ts, &qs, &vs), &t, &cmd, rate);
    assert!(worst < 1e-9, "replay off the nearest-edge reference by {worst} rad");
    std::fs::remove_dir_all(&dir).ok();
}

/// The timestep check: a servo too stiff for a 5 ms step moves its own replay by far more than
/// at 0.1 ms, and the note names the joint; recordings made at the model's own steps sit on its
/// replay (gap 0), so the note's share rule fires only with a gap to compare.
#[test]
fn a_timestep_too_coarse_for_the_servo_is_measured() {
    let model = |dt: &str| {
        format!(
            r#"<mujoco><option gravity="0 0 0" timestep="{dt}" integrator="implicitfast"/>
  <worldbody><body><joint name="j" type="hinge" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/></body></worldbody>
  <actuator><position joint="j" kp="20" kv="0.3"/></actuator>
</mujoco>"#
        )
    };
    let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.01).collect();
    let cmd: Vec<f64> =
        t.iter().map(|&x| if (x * 2.0).fract() < 0.5 { 0.3 } else { -0.3 }).collect();
    let mut j = crate::sim2real::recording::JointTrace::new("j", vec![0.0; t.len()]);
    j.q_cmd = Some(cmd);
    j.qd = Some(vec![0.0; t.len()]);
    let mut rec = Recording {
        source: "r.csv".into(),
        meta: Default::default(),
        control_rate_hz: Some(100.0),
        control_t0_s: Some(0.0),
        t,
        joints: vec![j],
        base: None,
    };
    let mut disc = Vec::new();
    for dt in ["0.005", "0.0001"] {
        let (robot, dir) = robot_from_xml(&format!("dt{}", dt.len()), &model(dt));
        // The recording: the model's own replay at its own steps.
        let ep = replay(&robot, &rec, &ReplayOptions::default(), None).unwrap();
        rec.joints[0].q = ep.q_sim[0].clone();
        let c = super::timestep_check(
            &robot,
            std::slice::from_ref(&rec),
            &ReplayOptions::default(),
            None,
        )
        .unwrap();
        assert_eq!((c.per_joint.len(), c.fine_timestep), (1, c.timestep / 4.0));
        // `gap` hands in the replay it already made: the same answer.
        let given = super::timestep_check(
            &robot,
            std::slice::from_ref(&rec),
            &ReplayOptions::default(),
            Some(std::slice::from_ref(&ep)),
        );
        assert_eq!(given.as_ref(), Some(&c));
        assert!(c.per_joint[0].gap_mae < 1e-12, "{c:?}");
        disc.push(c.per_joint[0].discretisation_mae);
        std::fs::remove_dir_all(&dir).ok();
    }
    assert!(disc[0] > 1e-3 && disc[1] < 0.02 * disc[0], "{disc:?}");
    let c = super::TimestepCheck {
        timestep: 0.005,
        fine_timestep: 0.00125,
        per_joint: vec![super::JointTimestep {
            name: "j".into(),
            discretisation_mae: disc[0],
            gap_mae: 3.0 * disc[0],
        }],
    };
    let n = super::timestep_note(&c).unwrap();
    assert!(n.contains("timestep (5.000 ms)") && n.contains("j "), "{n}");
    let quiet = super::TimestepCheck {
        per_joint: vec![super::JointTimestep { gap_mae: 5.0 * disc[0], ..c.per_joint[0].clone() }],
        ..c
    };
    assert_eq!(super::timestep_note(&quiet), None);
}

/// A recording of the reference trajectory `(ts, qs, vs)` (MuJoCo stepped by hand) sampled at
/// `t` (linearly between steps, as the replay samples), logging tick k's command `cmd[k]` at
/// row k, ticks at `rate` from 0; replayed, its largest position error. Asserts the reference
/// moved.
fn worst_against_reference(
    robot: &Robot,
    (ts, qs, vs): (&[f64], &[f64], &[f64]),
    t: &[f64],
    cmd: &[f64],
    rate: f64,
) -> f64 {
    let at = |x: &[f64], t: f64| {
        let i = ts.partition_point(|&s| s <= t).clamp(1, ts.len() - 1);
        let a = (t - ts[i - 1]) / (ts[i] - ts[i - 1]);
        x[i - 1] + a * (x[i] - x[i - 1])
    };
    let mut j =
        crate::sim2real::recording::JointTrace::new("j", t.iter().map(|&x| at(qs, x)).collect());
    j.qd = Some(t.iter().map(|&x| at(vs, x)).collect());
    j.q_cmd = Some(cmd[..t.len()].to_vec());
    let rec = Recording {
        source: "r.csv".into(),
        meta: Default::default(),
        control_rate_hz: Some(rate),
        control_t0_s: Some(0.0),
        t: t.to_vec(),
        joints: vec![j],
        base: None,
    };
    let ep = replay(robot, &rec, &ReplayOptions::default(), None).unwrap();
    let moved = rec.joints[0].q.iter().map(|q| q.abs()).fold(0.0, f64::max);
    assert!(moved > 0.05, "the reference barely moved: {moved}");
    ep.q_sim[0].iter().zip(&rec.joints[0].q).map(|(s, r)| (s - r).abs()).fold(0.0, f64::max)
}
