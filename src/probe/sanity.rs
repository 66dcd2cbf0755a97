//! Probe `whole-model-sanity`: 1 s from the keyframe with small random commands (seeded), as
//! MuJoCo Menagerie tests every model. Any MuJoCo warning, NaN, or energy blow-up is a finding
//! of the rule `unstable-simulation`.

use super::bench::{self, Bench, Setup};
use crate::declare_rule;
use crate::finding::{Finding, ProbeOutcome, ProbeStatus, Severity};
use crate::model::Robot;
use crate::rules::RuleMeta;

declare_rule! {
    /// ## What it does
    /// Runs the model for 1 s from its standing keyframe with small random position/torque
    /// commands and reports MuJoCo warnings (bad qacc/qvel/qpos, full contact or constraint
    /// buffers), NaN states, or a velocity blow-up.
    ///
    /// ## Why is this bad?
    /// A model that blows up under small commands will blow up under a policy's exploration: the
    /// training run resets constantly, and the policy learns from corrupted transitions.
    ///
    /// ## How it is confirmed
    /// This finding *is* the probe `whole-model-sanity`: it exists only when the simulation
    /// misbehaved. It is skipped with `--no-probe`.
    ///
    /// ## How to fix
    /// Look at the first warning MuJoCo names: bad qacc usually means a near-singular inertia
    /// (tiny masses with large armature ratios), gains too stiff for the timestep, or
    /// interpenetrating geoms at the keyframe. Reduce the timestep or fix the offending element.
    pub UnstableSimulation { id: "unstable-simulation", group: "control", level: Severity::Error, probe: Some("whole-model-sanity"), options: [] }
}

pub fn meta() -> &'static RuleMeta {
    &UnstableSimulation::META
}

const WARNING_NAMES: [&str; 7] = [
    "near-singular inertia",
    "contact buffer full",
    "constraint buffer full",
    "bad qpos",
    "bad qvel",
    "bad qacc",
    "bad ctrl",
];

/// splitmix64, for a deterministic command sequence.
fn next(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E3779B97F4A7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

pub fn run(robot: &Robot, level: Severity) -> Option<Finding> {
    let b = Bench::new(robot, Setup::default())?;
    let mut d = b.data(robot);
    let dt = b.dt();
    let n = (1.0 / dt).ceil() as usize;
    let hold = ((0.02 / dt).round() as usize).max(1);
    let nu = robot.actuators.len();
    let base: Vec<f64> = (0..nu).map(|a| bench::ctrl(&d, a)).collect();
    let mut seed = 0x5EED_u64;
    let mut problem = None;
    let mut max_speed: f64 = 0.0;
    let mut steps = 0;
    for k in 0..n {
        if k % hold == 0 {
            for (a, act) in robot.actuators.iter().enumerate() {
                let width = if act.ctrllimited { act.ctrlrange[1] - act.ctrlrange[0] } else { 0.2 };
                let v = base[a] + 0.05 * width * next(&mut seed);
                let v =
                    if act.ctrllimited { v.clamp(act.ctrlrange[0], act.ctrlrange[1]) } else { v };
                bench::set_ctrl(&mut d, a, v);
            }
        }
        b.step(&mut d);
        steps += 1;
        let w = &d.ffi().warning;
        if let Some(i) = w.iter().position(|w| w.number > 0) {
            problem = Some(format!(
                "MuJoCo warning `{}` at t = {:.3} s",
                WARNING_NAMES.get(i).unwrap_or(&"unknown"),
                k as f64 * dt
            ));
            break;
        }
        let qv = d.qvel();
        let s = qv.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !s.is_finite() {
            problem = Some(format!("NaN velocity at t = {:.3} s", k as f64 * dt));
            break;
        }
        max_speed = max_speed.max(s);
        if s > 1e3 {
            problem = Some(format!("velocity blow-up: |q̇| = {s:.0} at t = {:.3} s", k as f64 * dt));
            break;
        }
    }
    let msg = problem?;
    let mut f = Finding::new(meta().id, level, format!("simulation is unstable under small commands: {msg}"), robot.root_loc())
        .note("a policy explores far more aggressively than ±5 % commands; training would reset or learn from corrupted states")
        .help("reduce the timestep, check tiny masses / huge armature ratios, and interpenetrating geoms at the keyframe");
    f.element = format!("model {}", robot.path.display());
    let mut measured = std::collections::BTreeMap::new();
    measured.insert("max_speed".into(), max_speed);
    f.probe = Some(ProbeOutcome {
        name: "whole-model-sanity".into(),
        status: ProbeStatus::Confirmed,
        measured,
        steps,
        note: msg,
    });
    Some(f)
}
