//! Probe `impulse-response`: a small step in one joint's position target on a fixed test stand.
//!
//! * Drives: the joint's own actuator (a position servo, or the spec's PD gains applied through
//!   a motor), target stepped by δ after a 1 s settle (a servo whose ctrl passes through a
//!   first-order filter, `dyntype` filter, has its activation stepped with it: the loop's
//!   step, not the filter's smoothed one); every other DoF frozen (the probed joint
//!   sees its own row of MuJoCo's mass matrix, armature included), contacts off, gravity on.
//! * Measures: overshoot; the first peak's overshoot of the loop's equilibrium (dry friction's
//!   band taken off) → damping ratio ζ; the logarithmic decrement between the first two peaks
//!   (recorded; it tells growing peaks),
//!   damped period → natural frequency ω_n, and the effective inertia kp/ω_n² it implies.
//! * Confirms: underdamped gains when measured ζ is below the threshold; an armature mismatch
//!   when the measured inertia differs from the hardware's by more than the tolerance;
//!   instability when the response diverges (NaN, MuJoCo warnings, growth).
//! * Budget: 1 s settle + 2 s response at the model's timestep.

use std::collections::BTreeMap;

use super::bench::{self, Bench, Setup};
use crate::lint::Loaded;
use crate::model::{ActuatorKind, Robot};

/// The probe: a step response of one joint (key: the joint's id).
pub struct ImpulseResponse;

impl super::Probe for ImpulseResponse {
    const NAME: &'static str = "impulse-response";
    const UNAVAILABLE: &'static str =
        "joint has no PD servo to step (no position actuator, no spec kp/kd)";
    type Key = usize;
    fn steps(out: &StepResponse) -> usize {
        out.steps
    }
    type Output = StepResponse;
    fn run(l: &Loaded, joint: usize) -> Option<StepResponse> {
        step_response(&l.robot, joint, spec_gains(l, joint))
    }
}

/// The spec's kp/kd of the joint's motor family, for a joint driven by a torque motor.
pub fn spec_gains(l: &Loaded, joint: usize) -> Option<(f64, f64)> {
    let spec = l.spec.as_ref()?;
    let facts = spec.joint(&l.robot.joints.get(joint)?.name)?;
    let m = spec.motor(facts.motor.as_deref()?)?;
    Some((crate::spec::v(&m.kp)?, crate::spec::v(&m.kd)?))
}

#[derive(Debug, Clone)]
pub struct StepResponse {
    pub steps: usize,
    pub diverged: bool,
    /// Largest swing past the settled level, as a fraction of it.
    pub overshoot: f64,
    /// The first swing's overshoot of the loop's own equilibrium (from the statics: kp over kp
    /// plus the load's stiffness, less the dry-friction band): the overshoot of the loop's
    /// viscous dynamics, which the threshold is about (see [`analyse`]).
    pub loop_overshoot: f64,
    /// Damping ratio of the second-order loop with that overshoot, OS = exp(−πζ/√(1−ζ²)); None
    /// when the response does not overshoot (ζ ≳ 1).
    pub zeta: Option<f64>,
    /// ζ from the logarithmic decrement between the first two overshoot peaks, when both stand
    /// above the noise floor. Equal to `zeta` on a linear second-order loop; dry friction takes a
    /// fixed amount off every swing, which the small second peak feels most, so it is recorded
    /// (and used to tell growing peaks) but not taken as the loop's ζ.
    pub zeta_decrement: Option<f64>,
    pub omega_n: Option<f64>,
    pub inertia: Option<f64>,
    pub kp: f64,
    pub kd: f64,
    /// Final level of the response as a fraction of the commanded step (1: it got there).
    pub final_level: f64,
    /// The joint still rang at the end of the run: `final_level` is the centre of its swing
    /// ([`settled_level`]), not the mean of the run's last tenth.
    pub ringing: bool,
    /// The response touched the joint's range limits (the stop, not the servo, shaped it).
    pub touched_limit: bool,
    /// Size of the step, rad (or m): 0.05, or 5 % of a smaller range.
    pub step: f64,
    /// The joint's dry friction (`frictionloss`), N·m (or N).
    pub frictionloss: f64,
}

/// Largest |final level − 1| of a step response that counts as having followed the step.
pub const STEP_TOLERANCE: f64 = 0.2;
/// Largest dry friction, as a share of the servo torque of the step (kp × step), under which
/// the step response measures the viscous damping ratio: above it Coulomb friction, not
/// damping, shapes the response (it stalls the joint short of the target or stops the ringing).
pub const FRICTION_SHARE: f64 = 0.2;

impl StepResponse {
    /// What a run needs before its ω_n or shape can say anything about the servo: dry friction
    /// small against the step's servo torque, and the response clear of the joint's stops.
    pub fn dynamics_preconditions(&self) -> super::Preconditions {
        let n = crate::util::fmt_num;
        let servo = self.kp * self.step;
        super::Preconditions::new()
            .check(
                "friction_small",
                self.frictionloss <= FRICTION_SHARE * servo,
                format!(
                    "the joint's frictionloss {} N·m is {} % of the servo torque of the step (kp × {} rad = {} N·m; need ≤ {} %): dry friction, not damping, shapes the response",
                    n(self.frictionloss, 3),
                    n(100.0 * self.frictionloss / servo.max(1e-12), 3),
                    n(self.step, 3),
                    n(servo, 3),
                    n(100.0 * FRICTION_SHARE, 3)
                ),
            )
            .check(
                "clear_of_limits",
                !self.touched_limit,
                if self.touched_limit {
                    "the step response touched the joint's range limit"
                } else {
                    "the step response stayed clear of the joint's range limits"
                },
            )
    }

    /// What the run had to reach before a measured ζ can confirm or refute a damping claim, or
    /// a clean response refute a distortion claim: the [`Self::dynamics_preconditions`], the
    /// joint settled at the step, and its oscillation (if any) decays.
    pub fn preconditions(&self) -> super::Preconditions {
        let n = crate::util::fmt_num;
        let mut pre = self.dynamics_preconditions();
        pre = pre
            .check(
                "step_followed",
                (self.final_level - 1.0).abs() <= STEP_TOLERANCE,
                if !self.ringing {
                    format!(
                        "the joint settled at {} % of the commanded step (need {}–{} %)",
                        n(100.0 * self.final_level, 3),
                        n(100.0 * (1.0 - STEP_TOLERANCE), 3),
                        n(100.0 * (1.0 + STEP_TOLERANCE), 3)
                    )
                } else {
                    format!(
                        "the joint still rings at the end of the run; its swing centres at {} % of the commanded step (need {}–{} %)",
                        n(100.0 * self.final_level, 3),
                        n(100.0 * (1.0 - STEP_TOLERANCE), 3),
                        n(100.0 * (1.0 + STEP_TOLERANCE), 3)
                    )
                },
            )
            .check(
                "decaying",
                self.zeta_decrement.is_none_or(|z| z >= 0.0),
                match self.zeta_decrement {
                    Some(z) if z < 0.0 => format!(
                        "the response's peaks grow (ζ from their decay {}): not a damped second-order response",
                        n(z, 3)
                    ),
                    _ => "the response's oscillation (if any) decays".to_string(),
                },
            );
        pre
    }
}

/// PD gains acting on a joint: from its position actuator, else from the spec (through a motor).
pub fn gains(
    robot: &Robot,
    joint: usize,
    spec_kp_kd: Option<(f64, f64)>,
) -> Option<(usize, f64, f64, bool)> {
    let j = &robot.joints[joint];
    for a in robot.actuators_on_joint(joint) {
        if let Some(s) = a.servo {
            let g2 = a.gear * a.gear;
            return Some((a.id, s.kp * g2, s.kv * g2 + j.damping, true));
        }
    }
    let (kp, kd) = spec_kp_kd?;
    let a = robot
        .actuators_on_joint(joint)
        .into_iter()
        .find(|a| matches!(a.kind, ActuatorKind::Motor))?;
    Some((a.id, kp, kd + j.damping, false))
}

pub fn step_response(
    robot: &Robot,
    joint: usize,
    spec_kp_kd: Option<(f64, f64)>,
) -> Option<StepResponse> {
    let j = robot.joints.get(joint)?;
    if !j.is_scalar() {
        return None;
    }
    let (act, kp, kd, is_position) = gains(robot, joint, spec_kp_kd)?;
    let gear = robot.actuators[act].gear;
    let b = Bench::new(
        robot,
        Setup { isolate_dof: Some(j.dofadr), no_contact: true, ..Default::default() },
    )?;
    let mut d = b.data(robot);
    let dt = b.dt();
    let q0 = bench::qpos(&d, j.qposadr);
    let mut target = if is_position { bench::ctrl(&d, act) } else { q0 };
    let settle = (1.0 / dt).ceil() as usize;
    let resp = (2.0 / dt).ceil() as usize;
    let mut steps = 0;
    let pd = |d: &mut mujoco_rs::prelude::MjData<&mujoco_rs::prelude::MjModel>, tgt: f64| {
        if !is_position {
            let q = bench::qpos(d, j.qposadr);
            let v = bench::qvel(d, j.dofadr);
            bench::set_ctrl(d, act, (kp * (tgt - q) - (kd - j.damping) * v) / gear);
        }
    };
    if !is_position {
        target = q0;
    }
    for _ in 0..settle {
        pd(&mut d, target);
        b.step(&mut d);
        steps += 1;
    }
    let q_eq = bench::qpos(&d, j.qposadr);
    // Step of 0.05 rad (or 5 % of the range) towards the side with more room; the right joint
    // of a left/right pair steps as the mirror image of its left partner (`mirror_sign`).
    let (lo, hi) = if j.limited { (j.range[0], j.range[1]) } else { (-1e9, 1e9) };
    let size = 0.05f64.min(0.05 * (hi - lo).abs().max(1e-3));
    let own = step_sign(q_eq, size, lo, hi);
    let sign = match mirror_sign(robot, &d, joint) {
        Some(s) if step_sign(q_eq, size, lo, hi) == s || room(q_eq, s * size, lo, hi) => s,
        _ => own,
    };
    let delta = sign * size;
    // A servo of gear g and setpoint scale s holds q = s·ctrl / g: a step of delta in q is
    // g·delta/s in ctrl.
    let scale = robot.actuators[act].servo.map_or(1.0, |s| s.scale);
    let new_target = if is_position { target + delta * gear / scale } else { target + delta };
    let mut y = Vec::with_capacity(resp);
    let warn0 = bench::warnings(&d);
    let mut diverged = false;
    for _ in 0..resp {
        if is_position {
            bench::set_ctrl(&mut d, act, new_target);
            // A filtered servo (dyntype filter) steps its activation too: the loop's step.
            bench::set_filtered_act(&mut d, act, new_target);
        } else {
            pd(&mut d, new_target);
        }
        b.step(&mut d);
        steps += 1;
        let q = bench::qpos(&d, j.qposadr);
        if !q.is_finite()
            || bench::warnings(&d) > warn0
            || (q - q_eq).abs() > 100.0 * delta.abs() + 10.0
        {
            diverged = true;
            break;
        }
        y.push((q - q_eq) / delta);
    }
    if diverged {
        return Some(StepResponse {
            steps,
            diverged,
            overshoot: f64::NAN,
            loop_overshoot: f64::NAN,
            zeta: None,
            zeta_decrement: None,
            omega_n: None,
            inertia: None,
            kp,
            kd,
            final_level: f64::NAN,
            ringing: false,
            touched_limit: false,
            step: size,
            frictionloss: j.frictionloss,
        });
    }
    // Dry friction's band, as a share of the step: while the joint moves one way, friction is a
    // constant torque that shifts the loop's equilibrium by frictionloss over the loop's static
    // stiffness, kp plus the load's (gravity, springs: −d(qfrc_passive − qfrc_bias)/dq by a
    // central difference at the settled pose). The frictionless equilibrium of the step is
    // kp / (kp + k_load) of it.
    let k_load = {
        let mut d2 = b.data(robot);
        let eps = 1e-4;
        let mut g = [0.0; 2];
        for (k, s) in [-1.0, 1.0].iter().enumerate() {
            d2.qpos_mut().copy_from_slice(d.qpos());
            d2.qvel_mut().iter_mut().for_each(|v| *v = 0.0);
            d2.qpos_mut()[j.qposadr] = q_eq + s * eps;
            d2.forward();
            g[k] = d2.qfrc_passive()[j.dofadr] - d2.qfrc_bias()[j.dofadr];
        }
        -(g[1] - g[0]) / (2.0 * eps)
    };
    let stiffness = kp + if k_load.is_finite() { k_load } else { 0.0 };
    let (level, band) = if stiffness > 0.0 {
        (kp / stiffness, j.frictionloss / (stiffness * size))
    } else {
        (1.0, 0.0)
    };
    let mut r = analyse(&y, dt, kp, kd, steps, band, level);
    r.step = size;
    r.frictionloss = j.frictionloss;
    r.touched_limit = j.limited
        && y.iter().any(|v| {
            let q = q_eq + v * delta;
            q <= j.range[0] + 1e-6 || q >= j.range[1] - 1e-6
        });
    Some(r)
}

/// Room for a step of `delta` from `q` inside [lo, hi] (with the step again as margin).
fn room(q: f64, delta: f64, lo: f64, hi: f64) -> bool {
    if delta > 0.0 { q + 2.0 * delta <= hi } else { q + 2.0 * delta >= lo }
}

/// +1, or −1 when a positive step would come within one step of the upper limit and a
/// negative one has room.
fn step_sign(q: f64, size: f64, lo: f64, hi: f64) -> f64 {
    if q + size > hi - size && q - size > lo { -1.0 } else { 1.0 }
}

/// For the right joint of a left/right pair: the step sign that mirrors its left partner's
/// step across the robot's sagittal plane, so both sides of a mirror-symmetric model get the
/// same experiment. The plane's normal is the line between the two joints' anchors; a hinge
/// axis is an axial vector, so its mirror image is `2(a·n)n − a`, and the right joint steps
/// with the left's sign when its own axis points along that image, against it otherwise.
/// `None` for a left or unpaired joint, or when the axes are not mirror images (±).
pub fn mirror_sign(
    robot: &Robot,
    d: &mujoco_rs::prelude::MjData<&mujoco_rs::prelude::MjModel>,
    joint: usize,
) -> Option<f64> {
    let j = robot.joints.get(joint)?;
    let (side, other) =
        crate::model::mirror::mirror_in(&j.name, None, |n| robot.joint(n).is_some())?;
    if side != crate::model::mirror::Side::Right {
        return None;
    }
    let p = robot.joint(&other).filter(|p| p.is_scalar() && p.jtype == j.jtype)?;
    let (xa, xn) = (d.xaxis(), d.xanchor());
    let (ar, al) = (*xa.get(j.id)?, *xa.get(p.id)?);
    let (pr, pl) = (*xn.get(j.id)?, *xn.get(p.id)?);
    let mut n = [pl[0] - pr[0], pl[1] - pr[1], pl[2] - pr[2]];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if !(len > 1e-9) {
        return None;
    }
    n.iter_mut().for_each(|x| *x /= len);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let an = dot(al, n);
    // A slide axis is a polar vector: its mirror image is a − 2(a·n)n.
    let image: [f64; 3] = if j.jtype == crate::model::JointType::Slide {
        [0, 1, 2].map(|i| al[i] - 2.0 * an * n[i])
    } else {
        [0, 1, 2].map(|i| 2.0 * an * n[i] - al[i])
    };
    let c = dot(ar, image);
    if c.abs() < 0.9 {
        return None;
    }
    // The left partner's own choice, from its keyframe position and range.
    let (lo, hi) = if p.limited { (p.range[0], p.range[1]) } else { (-1e9, 1e9) };
    let size = 0.05f64.min(0.05 * (hi - lo).abs().max(1e-3));
    let ql = robot.key.qpos.get(p.qposadr).copied().unwrap_or(0.0);
    Some(step_sign(ql, size, lo, hi) * c.signum())
}

/// Second-order identification from a normalised step response (1 = the commanded step).
/// `band` is the joint's dry friction as a share of the step (frictionloss over the loop's
/// static stiffness and the step), `level` the frictionless equilibrium as a share of the step.
///
/// ζ comes from the end of the first swing: until the joint first stops, it moves one way, so dry friction
/// is a constant torque and the motion is exactly a linear second-order step response towards
/// the equilibrium shifted by the band, `level` − `band`; where it stops overshoots that equilibrium by
/// exp(−πζ/√(1−ζ²)); the equilibrium comes from the statics, not from where the response ends (a
/// lightly damped joint still rings at the end of the run). (Measured against
/// the settled level, a joint that sticks anywhere within the band shows a smaller overshoot,
/// and the decrement between the first two peaks, which dry friction shrinks by a fixed amount
/// each swing, says a different ζ again.)
pub fn analyse(
    y: &[f64],
    dt: f64,
    kp: f64,
    kd: f64,
    steps: usize,
    band: f64,
    level: f64,
) -> StepResponse {
    let n = y.len();
    let (yf, ringing) = settled_level(y);
    let e: Vec<f64> = y.iter().map(|v| v / yf - 1.0).collect();
    let peak = e.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let overshoot = peak.max(0.0);
    // Local maxima of the error above a noise floor.
    let floor = 1e-4;
    let mut peaks = Vec::new();
    for i in 1..n.saturating_sub(1) {
        if e[i] > floor && e[i] >= e[i - 1] && e[i] > e[i + 1] {
            peaks.push((i, e[i]));
        }
    }
    let mut zeta = None;
    let mut zeta_decrement = None;
    let mut omega_n = None;
    // The end of the first swing: past half the step, the first sample where the joint has
    // (all but) stopped — its speed under 0.2 % of the swing's fastest. A swing that reverses
    // stops at its peak; one that dry friction halts short of the target stops there and then
    // only creeps (MuJoCo's friction is a soft constraint).
    let vmax = y.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    let first_peak = (0..n.saturating_sub(1))
        .find(|&i| y[i] > 0.5 && y[i + 1] - y[i] <= 0.002 * vmax)
        .map(|i| y[i]);
    let equilibrium = level - band;
    let loop_overshoot = match first_peak {
        Some(p) if equilibrium > 0.0 => (p / equilibrium - 1.0).max(0.0),
        _ => 0.0,
    };
    let zeta_of = |os: f64| {
        let l = os.ln();
        -l / (std::f64::consts::PI.powi(2) + l * l).sqrt()
    };
    if loop_overshoot > floor {
        // OS = exp(−πζ/√(1−ζ²)) reaches 100 % at ζ = 0: a first swing past that (dry friction
        // shifting the equilibrium it is measured from, or a loop that gains energy) has no
        // damping ratio ≥ 0, and 0 is the most it tells (`zeta_text` says which).
        zeta = Some(zeta_of(loop_overshoot).max(0.0));
    }
    // The ω_n estimate below keeps the formula's ζ (negative past 100 %), as it always has.
    let zeta_raw = (loop_overshoot > floor).then(|| zeta_of(loop_overshoot));
    if overshoot > floor {
        // ζ for the damped period: the loop's, else (a response too distorted for a first
        // swing) the settled level's overshoot.
        let z = zeta_raw.unwrap_or_else(|| zeta_of(overshoot));
        if peaks.len() >= 2 && peaks[1].1 > floor * 2.0 {
            let dl = (peaks[0].1 / peaks[1].1).ln();
            zeta_decrement = Some(dl / (4.0 * std::f64::consts::PI.powi(2) + dl * dl).sqrt());
            // The damped period between the two peaks.
            let td = (peaks[1].0 - peaks[0].0) as f64 * dt;
            let wd = 2.0 * std::f64::consts::PI / td;
            omega_n = Some(wd / (1.0 - z * z).max(1e-9).sqrt());
        } else if let Some(&(i, _)) = peaks.first() {
            // Only one peak: the first peak of a step response is at t = π/ω_d.
            let wd = std::f64::consts::PI / (i as f64 * dt);
            omega_n = Some(wd / (1.0 - z * z).max(1e-9).sqrt());
        }
    }
    let inertia = omega_n.map(|w| kp / (w * w));
    StepResponse {
        steps,
        diverged: false,
        overshoot,
        loop_overshoot,
        zeta,
        zeta_decrement,
        omega_n,
        inertia,
        kp,
        kd,
        final_level: yf,
        ringing,
        touched_limit: false,
        step: 0.05,
        frictionloss: 0.0,
    }
}

/// Largest peak-to-peak swing, as a share of the step, over the last tenth of a step response
/// under which the joint counts as settled there: a larger swing is a joint still ringing at
/// the end of the run (ζ 0.09 at ω_n 5.5 rad/s keeps ±28 % after 2 s), whose last tenth sits
/// anywhere on its swing, not at its level.
pub const SETTLED_SWING: f64 = 0.02;

/// The level a normalised step response settles at, and whether it was still ringing. A
/// response that swings by at most [`SETTLED_SWING`] over its last tenth is read as that
/// tenth's mean. One still swinging is read at the centre its oscillation decays towards:
/// Aitken's Δ² on its last three turning points a, b, c (maximum, minimum, maximum or the
/// reverse), (a·c − b²) / (a + c − 2b), exact for an exponentially decaying sinusoid about any
/// level — where the last tenth would be a point of the swing. With fewer than three turning
/// points the last tenth's mean is kept.
pub fn settled_level(y: &[f64]) -> (f64, bool) {
    let n = y.len();
    let tail = &y[n - n / 10..];
    let mean = tail.iter().sum::<f64>() / tail.len().max(1) as f64;
    let (lo, hi) =
        tail.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if !(hi - lo > SETTLED_SWING) {
        return (mean, false);
    }
    let turns: Vec<f64> = (1..n.saturating_sub(1))
        .filter(|&i| (y[i] >= y[i - 1] && y[i] > y[i + 1]) || (y[i] <= y[i - 1] && y[i] < y[i + 1]))
        .map(|i| y[i])
        .collect();
    let [.., a, b, c] = turns[..] else { return (mean, true) };
    let den = a + c - 2.0 * b;
    let centre = (a * c - b * b) / den;
    // Turning points that alternate about a level: b on the other side of both a and c.
    if (a - b) * (c - b) > 0.0 && centre.is_finite() { (centre, true) } else { (mean, true) }
}

/// The overshoot of an undamped second-order loop (ζ = 0), as a fraction of the step: 100 %.
/// A damped loop's first swing stays under it.
pub const UNDAMPED_OVERSHOOT: f64 = 1.0;

/// What a diverged step response says.
pub const DIVERGED: &str = "the step response diverged (NaN, MuJoCo warning or unbounded growth)";

impl StepResponse {
    /// The first swing overshoots the loop's equilibrium by [`UNDAMPED_OVERSHOOT`] or more: no
    /// damping ratio ≥ 0 gives that swing, and `zeta` is 0.
    pub fn past_undamped(&self) -> bool {
        self.zeta.is_some() && self.loop_overshoot >= UNDAMPED_OVERSHOOT
    }

    /// ζ as shown: the number, or "≥ 1 (no overshoot)"; past an undamped loop's overshoot, 0
    /// with what the peaks then did — decayed (the log decrement's ζ) or grew, or no second peak
    /// to tell (a growing oscillation: unstable).
    pub fn zeta_text(&self) -> String {
        let n = crate::util::fmt_num;
        if self.past_undamped() {
            let os = format!(
                "0: the first swing overshoots {:.1} %, past the {} % of an undamped loop",
                100.0 * self.loop_overshoot,
                n(100.0 * UNDAMPED_OVERSHOOT, 3)
            );
            return match self.zeta_decrement {
                Some(d) if d > 0.0 => {
                    format!(
                        "{os}, and the later peaks decay (ζ {} by their log decrement)",
                        n(d, 3)
                    )
                }
                _ => format!("{os} — a growing oscillation (unstable)"),
            };
        }
        self.zeta.map(|z| n(z, 3)).unwrap_or_else(|| "≥ 1 (no overshoot)".into())
    }
}

/// The measured values by name, for the JSON output.
pub fn measured_map(r: &StepResponse) -> BTreeMap<String, f64> {
    let mut m = BTreeMap::new();
    if r.diverged {
        m.insert("diverged".into(), 1.0);
    }
    m.insert("overshoot".into(), r.overshoot);
    if r.loop_overshoot.is_finite() {
        m.insert("loop_overshoot".into(), r.loop_overshoot);
    }
    if let Some(z) = r.zeta {
        m.insert("zeta".into(), z);
    }
    if let Some(z) = r.zeta_decrement {
        m.insert("zeta_decrement".into(), z);
    }
    if let Some(w) = r.omega_n {
        m.insert("omega_n".into(), w);
    }
    if let Some(i) = r.inertia {
        m.insert("inertia".into(), i);
    }
    m.insert("kp".into(), r.kp);
    m.insert("kd".into(), r.kd);
    if r.final_level.is_finite() {
        m.insert("final_level".into(), r.final_level);
    }
    if r.ringing {
        m.insert("ringing_at_end".into(), 1.0);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact second-order step response sampled at dt.
    fn second_order(zeta: f64, wn: f64, dt: f64, n: usize) -> Vec<f64> {
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        (1..=n)
            .map(|k| {
                let t = k as f64 * dt;
                1.0 - (-zeta * wn * t).exp()
                    * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin())
            })
            .collect()
    }

    #[test]
    fn identifies_zeta_and_omega_from_a_clean_response() {
        for &(z, w) in &[(0.1, 10.0), (0.3, 20.0), (0.6, 8.0)] {
            let y = second_order(z, w, 0.001, 4000);
            let r = analyse(&y, 0.001, 65.0, 1.0, 4000, 0.0, 1.0);
            assert!((r.zeta.unwrap() - z).abs() < 0.03 * z, "zeta {z}: {:?}", r.zeta);
            assert!((r.omega_n.unwrap() - w).abs() < 0.02 * w, "omega {w}: {:?}", r.omega_n);
        }
    }

    #[test]
    fn growing_peaks_are_not_a_damping_measurement() {
        // Peaks that grow (stick-slip, a contact pushing): the log decrement gives ζ < 0.
        let dt = 0.001;
        let y: Vec<f64> = (0..4000)
            .map(|i| {
                let t = i as f64 * dt;
                let a = if t < 3.0 { 0.02 * (1.0 + t) } else { 0.0 };
                1.0 + a * (20.0 * t).sin()
            })
            .collect();
        let r = analyse(&y, dt, 1.0, 0.1, 4000, 0.0, 1.0);
        assert!(r.zeta_decrement.is_some_and(|z| z < 0.0), "{:?}", r.zeta_decrement);
        let pre = r.preconditions();
        let p = pre.list().iter().find(|p| p.name == "decaying").unwrap();
        assert!(!p.met && p.detail.contains("peaks grow"), "{}", p.detail);
    }

    #[test]
    fn a_swing_past_the_undamped_overshoot_reports_no_negative_zeta() {
        // A loop with negative damping (ζ = −0.02): each swing grows, the first overshoots
        // past 100 %. The equilibrium is the settled level (no friction band).
        let dt = 0.001;
        let y = second_order(-0.02, 10.0, dt, 700);
        let r = analyse(&y, dt, 100.0, 1.0, 700, 0.0, 1.0);
        assert!(r.loop_overshoot >= UNDAMPED_OVERSHOOT, "{}", r.loop_overshoot);
        assert_eq!(r.zeta, Some(0.0));
        assert!(r.zeta_text().starts_with("0: the first swing overshoots"), "{}", r.zeta_text());
        // Built directly: a first swing of 101 % whose later peaks decay (dry friction shifted
        // the equilibrium the swing is measured from), and one with no second peak.
        let mut r = analyse(&second_order(0.1, 10.0, dt, 4000), dt, 100.0, 1.0, 4000, 0.0, 1.0);
        r.loop_overshoot = 1.01;
        r.zeta = Some(0.0);
        r.zeta_decrement = Some(0.084);
        let t = r.zeta_text();
        assert!(t.contains("101.0 %") && t.contains("decay (ζ 0.084") && !t.contains('-'), "{t}");
        r.zeta_decrement = None;
        assert!(r.zeta_text().ends_with("a growing oscillation (unstable)"), "{}", r.zeta_text());
        r.loop_overshoot = 0.5;
        r.zeta = Some(0.2157);
        assert_eq!(r.zeta_text(), "0.216");
    }

    #[test]
    fn overdamped_has_no_zeta() {
        let dt = 0.001;
        let y: Vec<f64> = (1..4000).map(|k| 1.0 - (-(k as f64) * dt * 5.0).exp()).collect();
        assert!(analyse(&y, dt, 1.0, 1.0, 4000, 0.0, 1.0).zeta.is_none());
    }
}
