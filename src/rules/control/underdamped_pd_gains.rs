use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::model::{ActuatorKind, Robot, Transmission};
use crate::probe::impulse::{DIVERGED, StepResponse, measured_map};
use crate::probe::{Claim, ImpulseResponse, Preconditions, Verdict};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::spec::v;
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every joint under PD control (a `<position>` actuator, or a `<motor>` actuator whose
    /// motor family in the spec gives `kp`/`kd`), computes the closed-loop damping ratio
    /// ζ = kd / (2·√(kp·I)) and natural frequency ω_n = √(kp/I), where kd = actuator kv + the
    /// joint's effective damping (its own `damping`, plus actuator `damping`·gear² and tendon
    /// damping, MuJoCo ≥ 3.17; a voltage-driven `<dcmotor>`'s back-EMF adds K²/R × gear², as in
    /// MuJoCo's DC motor model note) and I is the joint's diagonal entry of the mass matrix at the
    /// standing keyframe (MuJoCo includes every armature in it: joint, actuator·gear², tendon). Reports joints with ζ below `min_damping_ratio`. The
    /// armature-only bound kd / (2·√(kp·armature)) is reported alongside. A joint with several
    /// actuators (the position, velocity and torque modes of one motor) is judged when exactly
    /// one of them is a servo and the others are `<velocity>` actuators or `<motor>`s: at ctrl 0
    /// a velocity actuator is a damper −kv·q̇ that acts while the servo holds the joint, so its
    /// kv·gear² is part of kd, and a motor adds nothing.
    ///
    /// The threshold's meaning is the step overshoot it accepts: a second-order loop overshoots
    /// a step by exp(−πζ/√(1−ζ²)), 4.6 % at ζ 0.7 (the usual "well-damped" servo). The level
    /// follows how much more a joint overshoots than the threshold accepts: at most 1.25 times
    /// (ζ 0.67–0.7 against 0.7: an overshoot no engineer or policy tells apart from the
    /// threshold's) is info, at the threshold; up to twice (ζ down to about 0.6) a warning; more
    /// the rule's level (error). When the probe measured the step (its preconditions met, the
    /// finding confirmed), the level comes from the overshoot it measured against the one the
    /// threshold accepts, in the same bands; when the run is inconclusive, from the computed ζ.
    /// A level set in the config applies to every finding.
    ///
    /// ## Why is this bad?
    /// A policy trained on an underdamped simulated joint learns to behave like an underdamped
    /// controller: its corrections overshoot, and on hardware each overshoot triggers a larger
    /// correction on the next cycle, exciting sustained oscillation (Asimov system identification §3). The real motor
    /// controllers were fine; the simulated data domain was wrong.
    ///
    /// ## How it is confirmed
    /// Probe `impulse-response`: the joint's target is stepped at the keyframe with the base
    /// fixed; the measured ζ is that of the second-order loop with the step's overshoot (what
    /// the threshold is about), compared with the threshold, and the measured overshoot sets the
    /// level.
    ///
    /// ## How to fix
    /// Raise kd (actuator `kv` or joint `damping`) to at least 2·ζ_min·√(kp·I), or lower kp.
    /// When the firmware caps kd (`kd_max` in the spec), lower kp to (kd_max / (2·ζ_min))² / I.
    pub UnderdampedPdGains {
        id: "underdamped-pd-gains",
        group: "control",
        level: Severity::Error,
        probe: ImpulseResponse,
        options: [opt("min_damping_ratio", 0.7, "", Domain::POSITIVE, "smallest acceptable closed-loop damping ratio ζ")],
    }
}

/// Largest ratio of a joint's step overshoot to the threshold's that is still "at the
/// threshold" (info).
const AT_THRESHOLD: f64 = 1.25;

/// Step overshoot of a second-order loop with damping ratio `z`, as a fraction (0 when ζ ≥ 1).
pub fn overshoot(z: f64) -> f64 {
    if !(z < 1.0) {
        return 0.0;
    }
    let z = z.max(0.0);
    (-std::f64::consts::PI * z / (1.0 - z * z).sqrt()).exp()
}

/// What the `impulse-response` probe checks: a step of the joint's target rings with a measured
/// ζ below the threshold (or diverges).
#[derive(Debug)]
pub struct Underdamped {
    pub joint: usize,
    /// The analytic ζ of the finding.
    pub predicted: f64,
    pub threshold: f64,
    /// The finding's message without its level's reason, when the rule grades the level (the
    /// config sets none): a measured step then sets the level from its own overshoot.
    pub graded: Option<String>,
}

/// The level of a finding whose step overshoots `ratio` times what the threshold accepts, and
/// the reason appended to its message (for a computed ζ past the threshold, none).
fn graded_level(ratio: f64, os: f64, os_min: f64, measured: bool) -> (Severity, String) {
    let what = if measured { "measured step overshoot" } else { "step overshoot" };
    let (o, m) = (fmt_num(100.0 * os, 2), fmt_num(100.0 * os_min, 2));
    if ratio <= AT_THRESHOLD {
        (Severity::Info, format!(" (at the threshold: {what} {o} % against the {m} % it accepts)"))
    } else {
        let sev = if ratio <= 2.0 { Severity::Warning } else { Severity::Error };
        // A computed level past the threshold needs no reason beyond the ζ in the message.
        let why = if measured {
            format!(" ({what} {o} % against the {m} % the threshold accepts)")
        } else {
            String::new()
        };
        (sev, why)
    }
}

impl Claim for Underdamped {
    type Probe = ImpulseResponse;
    fn key(&self, _: &Loaded) -> Result<usize, &'static str> {
        Ok(self.joint)
    }
    fn judge(&self, l: &Loaded, r: &StepResponse) -> Verdict {
        let slide = l
            .robot
            .joints
            .get(self.joint)
            .is_some_and(|j| j.jtype == crate::model::JointType::Slide);
        let unit = if slide { "m" } else { "rad" };
        let m = measured_map(r);
        let pre = r.preconditions();
        if r.diverged {
            return Verdict::confirmed(&Preconditions::new(), m, DIVERGED);
        }
        let zs = r.zeta_text();
        let pred = format!(" (predicted {})", fmt_num(self.predicted, 3));
        match r.zeta {
            Some(z) if z < self.threshold => {
                let v = Verdict::confirmed(
                    &pre,
                    m,
                    format!(
                        "measured ζ = {zs}{pred}{} on a {} {unit} step{}",
                        if r.past_undamped() {
                            String::new()
                        } else {
                            format!(", overshoot {:.1} %", 100.0 * r.loop_overshoot)
                        },
                        fmt_num(r.step, 3),
                        if r.frictionloss > 0.0 && r.past_undamped() {
                            format!(
                                " (the swing measured from the equilibrium dry friction shifts it to; {:.1} % past where it stopped)",
                                100.0 * r.overshoot
                            )
                        } else if r.frictionloss > 0.0 {
                            format!(
                                " (of the equilibrium dry friction shifts it to; {:.1} % past where it stopped)",
                                100.0 * r.overshoot
                            )
                        } else {
                            String::new()
                        }
                    ),
                );
                match &self.graded {
                    // The level from the overshoot the step showed, against the threshold's.
                    Some(base) => {
                        let os_min = overshoot(self.threshold);
                        let ratio = r.loop_overshoot / os_min.max(1e-12);
                        let (sev, why) = graded_level(ratio, r.loop_overshoot, os_min, true);
                        v.with_level(sev, format!("{base}{why}"))
                    }
                    None => v,
                }
            }
            _ => Verdict::refuted_or_inconclusive(
                &pre,
                m,
                format!("measured ζ = {zs}{pred} is not below {}", self.threshold),
            ),
        }
    }
}

/// Where a joint's PD gains come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GainSource {
    /// A position actuator (index).
    Actuator(usize),
    /// A motor actuator (index) with kp/kd from the spec's motor family.
    SpecMotor(usize),
}

/// One PD-controlled scalar joint, with gains referred to the joint.
#[derive(Debug, Clone)]
pub struct PdJoint {
    pub joint: usize,
    pub source: GainSource,
    pub kp: f64,
    /// Velocity gain of the controller (actuator kv·gear², or spec kd).
    pub kd_ctrl: f64,
    /// Total damping: kd_ctrl + joint damping.
    pub kd: f64,
    /// M[i,i] at the keyframe (armature included).
    pub inertia: f64,
    pub armature: f64,
    pub family: Option<String>,
    /// Velocity actuators on the same joint (id, kv at the joint): with ctrl 0 each is a
    /// damper −kv·q̇ that acts while the servo holds the joint; part of `kd_ctrl`.
    pub velocity: Vec<(usize, f64)>,
}

impl PdJoint {
    pub fn zeta(&self) -> f64 {
        damping_ratio(self.kp, self.kd, self.inertia)
    }
    pub fn omega_n(&self) -> f64 {
        (self.kp / self.inertia).sqrt()
    }
}

/// The attribute of actuator `aid`'s element that sets its `biasprm[index]` (1: stiffness,
/// 2: damping): `kp`/`kv` on a `<position>`, `biasprm` on a `<general>` (a `<position>`
/// default's `kp`/`kv` does not act on a `<general>` that writes its own `biasprm`).
pub fn servo_attr(robot: &Robot, aid: usize, index: usize) -> &'static str {
    let a = &robot.actuators[aid];
    match robot.elem(ElemKind::Actuator, aid, &a.name).map(|e| e.tag.as_str()) {
        Some("position") | None => {
            if index == 2 {
                "kv"
            } else {
                "kp"
            }
        }
        _ => "biasprm",
    }
}

pub fn damping_ratio(kp: f64, kd: f64, inertia: f64) -> f64 {
    kd / (2.0 * (kp * inertia).sqrt())
}

/// Every scalar joint driven by exactly one PD controller (position actuator on a joint
/// transmission, or motor actuator with spec kp/kd).
pub fn pd_joints(robot: &Robot, spec: Option<&crate::spec::Spec>) -> Vec<PdJoint> {
    let mut out = Vec::new();
    for j in &robot.joints {
        if !j.is_scalar() {
            continue;
        }
        let acts: Vec<_> = robot
            .actuators_on_joint(j.id)
            .into_iter()
            .filter(|a| matches!(a.trn, Transmission::Joint | Transmission::JointInParent))
            .collect();
        // One servo (or motor with spec gains) and, beside it, velocity actuators (dampers at
        // ctrl 0) and motors (no force at ctrl 0): the servo's loop sees their damping.
        let velocity: Vec<(usize, f64)> = acts
            .iter()
            .filter_map(|a| match a.kind {
                ActuatorKind::Velocity { kv } if a.servo.is_none() => {
                    Some((a.id, kv * a.gear * a.gear))
                }
                _ => None,
            })
            .collect();
        let mains: Vec<_> = if acts.len() == 1 {
            acts.clone()
        } else {
            acts.iter().copied().filter(|a| a.servo.is_some()).collect()
        };
        let others_known = acts.iter().all(|a| {
            a.servo.is_some()
                || matches!(a.kind, ActuatorKind::Velocity { .. } | ActuatorKind::Motor)
        });
        if mains.len() != 1 || !others_known {
            continue;
        }
        let a = mains[0];
        let inertia = robot.key.m_diag.get(j.dofadr).copied().unwrap_or(f64::NAN);
        if !(inertia > 0.0) {
            continue;
        }
        let facts = spec.and_then(|s| s.joint(&j.name));
        let family = facts.as_ref().and_then(|f| f.motor.clone());
        let g2 = a.gear * a.gear;
        // A servo's stiffness and damping are −biasprm[1], −biasprm[2] whatever its gain
        // scale: the gain only maps ctrl to the setpoint.
        let (source, kp, kd_ctrl) = match (a.servo, a.kind) {
            (Some(s), _) => (GainSource::Actuator(a.id), s.kp * g2, s.kv * g2),
            (None, ActuatorKind::Motor) => {
                let m = family.as_deref().and_then(|f| spec?.motor(f));
                match m.and_then(|m| Some((v(&m.kp)?, v(&m.kd).unwrap_or(0.0)))) {
                    Some((kp, kd)) => (GainSource::SpecMotor(a.id), kp, kd),
                    None => continue,
                }
            }
            _ => continue,
        };
        if !(kp > 0.0) {
            continue;
        }
        let kd_ctrl = kd_ctrl + velocity.iter().map(|v| v.1).sum::<f64>();
        out.push(PdJoint {
            joint: j.id,
            source,
            kp,
            kd_ctrl,
            kd: kd_ctrl + j.damping,
            inertia,
            armature: j.armature,
            family,
            velocity,
        });
    }
    out
}

impl Rule for UnderdampedPdGains {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let zmin = cx.opt("min_damping_ratio");
        for p in pd_joints(cx.robot, cx.spec) {
            let z = p.zeta();
            if !(z < zmin) {
                continue;
            }
            let j = &cx.robot.joints[p.joint];
            let w = p.omega_n();
            let z_arm =
                if p.armature > 0.0 { Some(damping_ratio(p.kp, p.kd, p.armature)) } else { None };
            let kd_max =
                p.family.as_deref().and_then(|f| cx.spec?.motor(f)).and_then(|m| v(&m.kd_max));
            let kd_need = 2.0 * zmin * (p.kp * p.inertia).sqrt();
            // A slide's gains and inertia are linear: N/m, N·s/m, kg.
            let (uk, ud, ui) = if j.jtype == crate::model::JointType::Slide {
                ("N/m", "N·s/m", "kg")
            } else {
                ("N·m/rad", "N·m·s/rad", "kg·m²")
            };
            let msg = format!(
                "joint `{}` is underdamped under PD control: ζ = {} (kp {} {uk}, kd {} {ud}, I {} {ui}, ω_n {} rad/s), below {}",
                j.name,
                fmt_num(z, 3),
                fmt_num(p.kp, 4),
                fmt_num(p.kd, 4),
                fmt_num(p.inertia, 4),
                fmt_num(w, 4),
                fmt_num(zmin, 3)
            );
            let ratio = overshoot(z) / overshoot(zmin).max(1e-12);
            let mut f = match p.source {
                GainSource::Actuator(aid) => {
                    let a = &cx.robot.actuators[aid];
                    let attr = servo_attr(cx.robot, aid, if a.biasprm[2] != 0.0 { 2 } else { 1 });
                    cx.at_attr(ElemKind::Actuator, aid, &a.name, attr, msg)
                }
                GainSource::SpecMotor(_) => cx.at_elem(ElemKind::Joint, j.id, &j.name, msg),
            };
            if let (GainSource::SpecMotor(_), Some(loc)) =
                (p.source, cx.facts(&j.name).and_then(|x| x.motor_loc))
            {
                f = f.secondary(loc, "kp/kd come from this motor family in the spec");
            }
            let arm_note = match z_arm {
                Some(za) => format!(
                    " With the armature alone ({} {ui}) ζ would be {}; the link inertia makes it worse.",
                    fmt_num(p.armature, 4),
                    fmt_num(za, 3)
                ),
                None => {
                    " The joint has no armature, so nothing but the link inertia sets I.".into()
                }
            };
            let parts_note = if j.armature_elsewhere()
                || j.damping_parts.iter().any(|p| p.source != crate::model::PartSource::Joint)
            {
                format!(
                    " Effective armature {} = {}; passive damping {} = {} (MuJoCo ≥ 3.17 applies actuator and tendon armature and damping at the joint).",
                    fmt_num(j.armature, 4),
                    crate::model::describe_parts(cx.robot, &j.armature_parts, "armature"),
                    fmt_num(j.damping, 4),
                    crate::model::describe_parts(cx.robot, &j.damping_parts, "damping")
                )
            } else {
                String::new()
            };
            let velocity_note = if p.velocity.is_empty() {
                String::new()
            } else {
                let v: Vec<String> = p
                    .velocity
                    .iter()
                    .map(|(a, kv)| {
                        format!("{} (kv {} {ud})", cx.actuator_label(*a), fmt_num(*kv, 4))
                    })
                    .collect();
                format!(
                    " kd includes the velocity actuators on the same joint, dampers −kv·q̇ while their ctrl is 0: {}.",
                    v.join(", ")
                )
            };
            f = f.note(format!(
                "An underdamped simulated joint teaches the policy to behave like an underdamped controller; on hardware its corrections overshoot and it oscillates (Asimov system identification §3).{arm_note}{parts_note}{velocity_note}"
            ));
            let help = match kd_max {
                // The cap limits the controller's kd; joint damping adds to it.
                Some(cap) if kd_need - j.damping > cap => format!(
                    "reaching ζ = {} needs a controller kd ≥ {} {ud}, above the firmware cap kd_max = {} {ud}, so it is impossible at this kp; lower kp to {} {uk} (with kd = kd_max + joint damping)",
                    fmt_num(zmin, 3),
                    fmt_num(kd_need - j.damping, 4),
                    fmt_num(cap, 4),
                    fmt_num(((cap + j.damping) / (2.0 * zmin)).powi(2) / p.inertia, 4)
                ),
                _ => format!(
                    "raise kd to ≥ {} {ud} (actuator kv + joint damping), or lower kp to ≤ {} {uk} at the current kd",
                    fmt_num(kd_need, 4),
                    fmt_num((p.kd / (2.0 * zmin)).powi(2) / p.inertia, 4)
                ),
            };
            let graded = (cx.level == cx.meta.default_level).then(|| f.message.clone());
            f = f
                .help(help)
                .label(format!("ζ = {}", fmt_num(z, 3)))
                .subject(Subject::Joint(j.id))
                .claim(Underdamped { joint: j.id, predicted: z, threshold: zmin, graded })
                .measured(z, "")
                .expected(zmin, "")
                .with("zeta", z)
                .with("omega_n", w)
                .with("kp", p.kp)
                .with("kd", p.kd)
                .with("inertia", p.inertia);
            if let Some(za) = z_arm {
                f = f.with("zeta_armature_only", za);
            }
            f = f.with("overshoot_ratio", ratio);
            if cx.level == cx.meta.default_level {
                let (sev, why) = graded_level(ratio, overshoot(z), overshoot(zmin), false);
                f.severity = sev;
                f.message.push_str(&why);
            }
            out.push(f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn overshoot_of_a_second_order_loop() {
        // Textbook values: ζ 0.7 → 4.6 %, ζ 0.5 → 16.3 %, ζ 0 → 100 %, ζ ≥ 1 → none.
        assert!((overshoot(0.7) - 0.0460).abs() < 1e-4);
        assert!((overshoot(0.5) - 0.1630).abs() < 1e-4);
        assert_eq!(overshoot(0.0), 1.0);
        assert_eq!(overshoot(1.2), 0.0);
        // The level bands against ζ_min 0.7: 0.695 at the threshold, 0.65 past it, 0.5 far past.
        let r = |z: f64| overshoot(z) / overshoot(0.7);
        assert!(r(0.695) <= AT_THRESHOLD && r(0.65) > AT_THRESHOLD && r(0.65) <= 2.0);
        assert!(r(0.5) > 2.0);
    }

    #[test]
    fn damping_ratio_known_values() {
        // Seed 001: kp 65, kd 5 on the hip armature 0.095625 alone.
        let z = damping_ratio(65.0, 5.0, 0.095625);
        assert!((z - 5.0 / (2.0 * (65.0f64 * 0.095625).sqrt())).abs() < 1e-12);
        assert!((z - 1.0025).abs() < 1e-3, "{z}");
        // Critically damped: kd = 2√(kp I).
        assert!((damping_ratio(100.0, 2.0 * (100.0f64 * 0.25).sqrt(), 0.25) - 1.0).abs() < 1e-12);
        // kp that reaches ζ_min with kd = kd_max: (kd_max/(2ζ))²/I.
        let (kd_max, zmin, i): (f64, f64, f64) = (3.0, 0.7, 0.5);
        let kp = (kd_max / (2.0 * zmin)).powi(2) / i;
        assert!((damping_ratio(kp, kd_max, i) - zmin).abs() < 1e-12);
    }
}
