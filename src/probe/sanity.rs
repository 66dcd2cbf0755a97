//! Probe `whole-model-sanity`: 1 s from the keyframe with small random commands (seeded), as
//! MuJoCo Menagerie tests every model. Any MuJoCo warning, NaN, or energy blow-up is a finding
//! of the rule `unstable-simulation`.

use super::bench::{self, Bench, Setup};
use crate::lint::Loaded;
use crate::model::Robot;

/// The probe: the whole model under small random commands (one run per model).
pub struct WholeModelSanity;

impl super::Probe for WholeModelSanity {
    const NAME: &'static str = "whole-model-sanity";
    const WHOLE_MODEL: bool = true;
    const UNAVAILABLE: &'static str = "could not set up the bench";
    type Key = ();
    fn steps(out: &Sanity) -> usize {
        out.steps
    }
    type Output = Sanity;
    fn run(l: &Loaded, (): ()) -> Option<Sanity> {
        run(&l.robot)
    }
}

/// What the run saw.
#[derive(Debug, Clone)]
pub struct Sanity {
    pub steps: usize,
    /// Largest |q̇| before the run stopped.
    pub max_speed: f64,
    /// The first problem (a MuJoCo warning, NaN, a blow-up), if any.
    pub problem: Option<String>,
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

pub fn run(robot: &Robot) -> Option<Sanity> {
    let b = Bench::new(robot, Setup::default())?;
    let mut d = b.data(robot);
    let dt = b.dt();
    let n = (1.0 / dt).ceil() as usize;
    let hold = ((0.02 / dt).round() as usize).max(1);
    let nu = robot.actuators.len();
    let base: Vec<f64> = (0..nu).map(|a| bench::ctrl(&d, a)).collect();
    let mut rng = crate::util::Rng::from_state(0x5EED);
    let mut problem = None;
    let mut max_speed: f64 = 0.0;
    let mut steps = 0;
    for k in 0..n {
        if k % hold == 0 {
            for (a, act) in robot.actuators.iter().enumerate() {
                let width = if act.ctrllimited { act.ctrlrange[1] - act.ctrlrange[0] } else { 0.2 };
                let v = base[a] + 0.05 * width * (2.0 * rng.uniform() - 1.0);
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
    Some(Sanity { steps, max_speed, problem })
}
