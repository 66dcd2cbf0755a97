use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, ProbeOutcome, ProbeStatus, Severity};
use crate::lint::Loaded;
use crate::probe::WholeModelSanity;
use crate::probe::sanity::Sanity;

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
    pub UnstableSimulation { id: "unstable-simulation", group: "control", level: Severity::Error, probe: WholeModelSanity, options: [] }
}

/// The finding for a run of the probe that misbehaved (None when the run was clean).
pub fn finding(l: &Loaded, level: Severity, run: &Sanity) -> Option<Finding> {
    use crate::probe::Probe;
    let msg = run.problem.clone()?;
    let robot = &l.robot;
    let mut f = Finding::new(
        UnstableSimulation::META.id,
        level,
        format!("simulation is unstable under small commands: {msg}"),
        robot.root_loc(),
    )
    .note("a policy explores far more aggressively than ±5 % commands; training would reset or learn from corrupted states")
    .help("reduce the timestep, check tiny masses / huge armature ratios, and interpenetrating geoms at the keyframe");
    f.element = format!("model {}", robot.path.display());
    f.probe = Some(ProbeOutcome {
        name: WholeModelSanity::NAME.into(),
        status: ProbeStatus::Confirmed,
        reason: None,
        preconditions: Vec::new(),
        measured: BTreeMap::from([("max_speed".to_string(), run.max_speed)]),
        steps: run.steps,
        note: msg,
        level: None,
    });
    Some(f)
}
