use mujoco_rs::prelude::MjData;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{JointType, Robot, Transmission};
use crate::rules::control::keyframe_scan::{key_actuators, keyframes};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds position servos that the static load on their joint holds far off their target at
    /// the model's keyframe (the one modellint lints at: `stand`, `home`, …, else the first;
    /// `qpos0` when there is none). MuJoCo evaluates, at the keyframe's pose with zero velocity,
    /// the load on each joint: gravity (−`qfrc_bias`), joint springs (`qfrc_spring`,
    /// stiffness × (springref − q)) and gravity compensation (`qfrc_gravcomp`, whether applied
    /// passively or through the actuators). The servos aim at the setpoints of the keyframe's
    /// `ctrl` when it gives them any non-zero target, else at the keyframe's pose. A servo of
    /// gain kp and gear g (stiffness kp·g², plus the joint's own spring stiffness) settles
    /// `sag` = load / stiffness away from its target (a first-order estimate: gravity's own
    /// change with the angle is not in the stiffness), cut at the joint's range. A sag larger
    /// than `max_sag_rad` (hinges), `max_sag_m` (slides) or `max_sag_fraction` of the joint's
    /// range is reported when the joint also settles that far from the keyframe's pose: a
    /// keyframe `ctrl` that offsets the target by the sag holds its pose and is not reported.
    /// Only hinge and slide joints driven by position servos alone (a `<position>`, or a
    /// `<general biastype="affine">` servo, through a joint transmission) are judged, and not
    /// those an equality constraint couples to another joint or body (the constraint shares the
    /// load). Torque-controlled joints are not judged; gravity compensation that carries the
    /// weight leaves no load and nothing to report.
    ///
    /// A joint spring also holds the servo off every target other than its `springref`: a
    /// servo of stiffness kp·g² commanded to θ settles at (kp·g²·θ + k·springref)/(kp·g² + k)
    /// against a spring of stiffness k. When the keyframe shows no sag, each end of the
    /// servo's ctrlrange (as joint positions, within the joint's range) is judged by the same
    /// thresholds with the spring alone (gravity is the keyframe's business): a joint
    /// `stiffness` copied from the servo's kp halves every command.
    ///
    /// ## Why is this bad?
    /// A servo too soft for the weight it carries (an arm's kp stated in the wrong units, a
    /// spring whose `springref` is not the servo's working pose) never reaches the pose a
    /// policy commands: at reset the joint drops by the sag, every target is missed by it, and
    /// a policy trained on the model learns to command offsets the real, stiffer actuator
    /// overshoots. MuJoCo XML reference, `actuator/position` (force = kp·(ctrl − gear·q) − kv·q̇),
    /// `joint/stiffness`, `joint/springref` and `body/gravcomp`.
    ///
    /// ## How it is confirmed
    /// Static: the forces are MuJoCo's own (`mj_forward` at the keyframe with zero velocity), the
    /// stiffness the compiled `actuator_gainprm`/`actuator_biasprm`, `actuator_gear` and
    /// `jnt_stiffness`. Contacts are not counted (the keyframe's legs are judged as if in the
    /// air: the sag a standing robot's legs show is larger).
    ///
    /// ## How to fix
    /// Raise `kp` to the real actuator's stiffness (the help gives the kp that keeps the sag within
    /// the threshold), set `springref` to the pose the servo works around, enable gravity
    /// compensation if the real controller has it, or give the keyframe the `ctrl` that holds its
    /// pose under the load.
    pub ServoSag {
        id: "servo-sag",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("max_sag_rad", 0.1, "rad", Domain::POSITIVE, "largest acceptable static offset of a hinge servo from the keyframe pose (0.1 rad ≈ 5.7°: 5 cm at the end of a 0.5 m link)"),
            opt("max_sag_m", 0.01, "m", Domain::POSITIVE, "largest acceptable static offset of a slide servo from the keyframe pose"),
            opt("max_sag_fraction", 0.1, "fraction", Domain::POSITIVE_FRACTION, "largest acceptable static offset as a fraction of the joint's range"),
        ],
    }
}

/// Generalized forces at one DoF at the keyframe pose (zero velocity), N·m or N.
#[derive(Debug, Clone, Copy, Default)]
pub struct DofLoad {
    /// −qfrc_bias: gravity (the velocity terms are zero).
    pub gravity: f64,
    /// qfrc_spring: the joint's spring.
    pub spring: f64,
    /// qfrc_gravcomp: gravity compensation, passive or through the actuators.
    pub gravcomp: f64,
    /// The load the servos hold: qfrc_passive − qfrc_bias and the gravity compensation
    /// applied through the actuators.
    pub net: f64,
    /// The position servos' own force at rest at the keyframe's pose (0 when they hold it).
    pub servo: f64,
}

/// The forces on every DoF at the robot's keyframe (or qpos0) with zero velocity: gravity,
/// springs and gravity compensation from MuJoCo, and the position servos' forces at rest
/// g·kp·(setpoint(ctrl) − g·q) for the keyframe's ctrl when it gives any servo a non-zero
/// target (else the servos hold the pose and push nothing). The servos' forces are computed
/// here, not read from `qfrc_actuator`: at a reset an actuator with a `delay` still outputs the
/// zero control of its empty history.
pub fn keyframe_loads(robot: &Robot) -> Vec<DofLoad> {
    let m = &robot.mj;
    let servos = key_actuators(robot, |a| a.servo.is_some());
    let mut d = MjData::new(m);
    let key = robot.key.key.and_then(|k| keyframes(robot).into_iter().find(|x| x.index == k));
    if let Some(k) = &key {
        let _ = d.reset_keyframe(k.index);
    }
    d.qvel_mut().iter_mut().for_each(|v| *v = 0.0);
    d.forward();
    let (bias, passive, spring, gc) =
        (d.qfrc_bias(), d.qfrc_passive(), d.qfrc_spring(), d.qfrc_gravcomp());
    let mut loads: Vec<DofLoad> = (0..bias.len())
        .map(|i| DofLoad {
            gravity: -bias[i],
            spring: spring.get(i).copied().unwrap_or(0.0),
            gravcomp: gc.get(i).copied().unwrap_or(0.0),
            net: passive.get(i).copied().unwrap_or(0.0) - bias[i],
            servo: 0.0,
        })
        .collect();
    // Gravity compensation through the actuators (`actuatorgravcomp`) is left out of
    // qfrc_passive and added to the actuator force.
    let actgc = m.jnt_actgravcomp();
    for j in &robot.joints {
        if actgc.get(j.id).is_some_and(|&x| x)
            && let Some(l) = loads.get_mut(j.dofadr)
        {
            l.net += l.gravcomp;
        }
    }
    let Some(k) = key.filter(|k| servos.iter().any(|s| k.ctrl[s.ctrl] != 0.0)) else {
        return loads;
    };
    for s in &servos {
        let (a, j) = (&robot.actuators[s.actuator], &robot.joints[s.joint]);
        let Some(sv) = a.servo else { continue };
        let g = if a.gear != 0.0 { a.gear } else { 1.0 };
        let q = k.joint_pos(robot, j.id);
        if let Some(l) = loads.get_mut(j.dofadr) {
            l.servo += g * sv.kp * (sv.setpoint(k.ctrl[s.ctrl]) - g * q);
        }
    }
    loads
}

impl Rule for ServoSag {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let servos = key_actuators(robot, |a| a.servo.is_some());
        if servos.is_empty() {
            return;
        }
        let loads = keyframe_loads(robot);
        let qpos = &robot.key.qpos;
        let coupled = |j: usize| {
            robot.equalities.iter().any(|e| {
                // joint (2) equalities name joints; connect/weld (0, 1) name bodies.
                match e.etype {
                    2 => e.obj1 == j as i32 || e.obj2 == j as i32,
                    0 | 1 => {
                        let b = robot.joints[j].body as i32;
                        e.obj1 == b || e.obj2 == b
                    }
                    _ => false,
                }
            })
        };
        let key_label = match (&robot.key.key_name, robot.key.key) {
            (Some(n), _) if !n.is_empty() => format!("keyframe `{n}`"),
            (_, Some(k)) => format!("keyframe #{k}"),
            _ => "qpos0 (the model has no keyframe)".into(),
        };
        let mut seen = Vec::new();
        for s in &servos {
            let j = &robot.joints[s.joint];
            if seen.contains(&j.id) || coupled(j.id) {
                continue;
            }
            seen.push(j.id);
            // Every actuator on the joint must be a servo through a joint transmission.
            let on = robot.actuators_on_joint(j.id);
            if on.iter().any(|a| {
                a.servo.is_none()
                    || !matches!(a.trn, Transmission::Joint | Transmission::JointInParent)
            }) {
                continue;
            }
            let servo_k: f64 = on
                .iter()
                .map(|a| {
                    let g = if a.gear != 0.0 { a.gear } else { 1.0 };
                    a.servo.map_or(0.0, |sv| sv.kp) * g * g
                })
                .sum();
            let stiffness = servo_k + j.stiffness.max(0.0);
            let Some(load) = loads.get(j.dofadr) else { continue };
            let Some(&q) = qpos.get(j.qposadr) else { continue };
            if !(servo_k > 0.0) || !load.net.is_finite() || !load.servo.is_finite() {
                continue;
            }
            // Where the servos aim (the pose itself when they hold it) and where the load
            // leaves the joint: the sag is measured from the target, and a keyframe whose
            // targets already offset it (the joint settles at the pose) is not reported.
            let target = q + load.servo / servo_k;
            let mut settled = target + load.net / stiffness;
            if j.limited {
                settled = settled.clamp(j.range[0].min(j.range[1]), j.range[0].max(j.range[1]));
            }
            let off_pose = settled - q;
            let sag = settled - target;
            let (unit, abs_max, force_unit) = match j.jtype {
                JointType::Slide => ("m", cx.opt("max_sag_m"), "N"),
                _ => ("rad", cx.opt("max_sag_rad"), "N·m"),
            };
            let span = if j.limited { (j.range[1] - j.range[0]).abs() } else { f64::INFINITY };
            let limit = abs_max.min(cx.opt("max_sag_fraction") * span);
            if !(sag.abs() > limit && off_pose.abs() > limit) {
                if let Some(f) =
                    spring_across_ctrlrange(cx, j, &on, servo_k, limit, unit, force_unit)
                {
                    out.push(f);
                }
                continue;
            }
            let a = on[0];
            let mut parts = Vec::new();
            for (name, v) in [
                ("gravity", load.gravity),
                ("spring", load.spring),
                ("gravity compensation", load.gravcomp),
            ] {
                if v.abs() > 1e-9 * (1.0 + load.net.abs()) {
                    parts.push(format!("{name} {}", fmt_num(v, 3)));
                }
            }
            let of_range = if span.is_finite() {
                format!(", {} % of its range", fmt_num(100.0 * sag.abs() / span, 2))
            } else {
                String::new()
            };
            let cut = if (target + load.net / stiffness - settled).abs() > 0.0 {
                " (stopped by the joint's range)"
            } else {
                ""
            };
            let msg = format!(
                "position servo {} (stiffness {} {force_unit}/{unit}) is held {} {unit} off its target on joint `{}` at {key_label} by a static load of {} {force_unit}{}{cut}{of_range}",
                cx.actuator_label(a.id),
                fmt_num(stiffness, 3),
                fmt_num(sag, 3),
                j.name,
                fmt_num(load.net, 3),
                if parts.is_empty() { String::new() } else { format!(" ({})", parts.join(", ")) },
            );
            let other_k = stiffness - servo_k;
            let kp_needed = (load.net.abs() / limit - other_k)
                / (servo_k / a.servo.map_or(1.0, |s| s.kp).max(f64::MIN_POSITIVE));
            let jloc = robot.elem_loc(ElemKind::Joint, j.id, &j.name);
            let mut f = cx
                .at_attr(ElemKind::Actuator, a.id, &a.name, "kp", msg)
                .label(format!("kp {}", fmt_num(a.servo.map_or(0.0, |s| s.kp), 3)))
                .secondary(jloc, format!("sags {} {unit} at {key_label}", fmt_num(sag, 3)));
            if load.spring.abs() > 1e-9 {
                let sloc = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "springref").0;
                f = f.secondary(
                    sloc,
                    format!("spring pulls towards springref {}", fmt_num(j.springref, 3)),
                );
            }
            let f = f
                .note("at rest a position servo settles where its force kp·g²·error balances the load on its joint (gravity, springs, less any gravity compensation); the error is the load over the stiffness")
                .help(format!(
                    "kp ≥ {} keeps the sag within {} {unit}; or set springref to the servo's working pose, enable gravity compensation if the real controller has it, or give the keyframe the ctrl that holds its pose",
                    fmt_num(kp_needed.max(0.0), 3),
                    fmt_num(limit, 3)
                ))
                .subject(Subject::Actuator(a.id))
                .measured(sag, unit)
                .expected(limit, unit)
                .with("load", load.net)
                .with("stiffness", stiffness);
            out.push(f);
        }
    }
}

/// Where the joint spring alone leaves a joint's servos at the end of their ctrlrange farthest
/// from the spring's rest position: a finding when that is more than `limit` short of the
/// commanded position (the servos' commands as joint positions, cut at the joint's range).
fn spring_across_ctrlrange(
    cx: &Context,
    j: &crate::model::Joint,
    on: &[&crate::model::Actuator],
    servo_k: f64,
    limit: f64,
    unit: &str,
    force_unit: &str,
) -> Option<Finding> {
    let k = j.stiffness;
    if !(k > 0.0) || on.len() != 1 {
        return None;
    }
    let a = on[0];
    let [lo, hi] = a.setpoint_range()?;
    let (rlo, rhi) = (j.range[0].min(j.range[1]), j.range[0].max(j.range[1]));
    let clamp = |x: f64| if j.limited { x.clamp(rlo, rhi) } else { x };
    let reach = |t: f64| {
        let t = clamp(t);
        (t, clamp((servo_k * t + k * j.springref) / (servo_k + k)))
    };
    let ((t, x), (t2, x2)) = (reach(lo), reach(hi));
    let (t, x) = if (x2 - t2).abs() > (x - t).abs() { (t2, x2) } else { (t, x) };
    let short = x - t;
    if !(short.abs() > limit) || !short.is_finite() {
        return None;
    }
    let msg = format!(
        "position servo {} (stiffness {} {force_unit}/{unit}) reaches {} {unit} when commanded to {} {unit}, the end of its ctrlrange: joint `{}`'s spring (stiffness {} {force_unit}/{unit} towards springref {}) holds it {} {unit} short ({} % of the way from springref)",
        cx.actuator_label(a.id),
        fmt_num(servo_k, 3),
        fmt_num(x, 3),
        fmt_num(t, 3),
        j.name,
        fmt_num(k, 3),
        fmt_num(j.springref, 3),
        fmt_num(short.abs(), 3),
        fmt_num(100.0 * k / (servo_k + k), 3),
    );
    let robot = cx.robot;
    let sloc = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "stiffness").0;
    Some(
        cx.at_attr(ElemKind::Actuator, a.id, &a.name, "kp", msg)
            .label(format!("kp {}", fmt_num(a.servo.map_or(0.0, |s| s.kp), 3)))
            .secondary(sloc, format!("spring stiffness {} towards springref {}", fmt_num(k, 3), fmt_num(j.springref, 3)))
            .note("a position servo against a joint spring settles where kp·g²·(target − q) balances k·(q − springref): every target but springref is missed by k/(kp·g² + k) of its distance from springref")
            .help(format!(
                "remove the joint's stiffness if the servo alone is the actuator (a stiffness equal to kp is the servo's gain written twice), or raise kp to at least {} so the spring costs at most {} {unit} of the ctrlrange",
                fmt_num((k * ((t - j.springref).abs() / limit - 1.0)).max(0.0) / (servo_k / a.servo.map_or(1.0, |s| s.kp).max(f64::MIN_POSITIVE)), 3),
                fmt_num(limit, 3)
            ))
            .subject(Subject::Actuator(a.id))
            .measured(short, unit)
            .expected(limit, unit)
            .with("spring_stiffness", k)
            .with("stiffness", servo_k),
    )
}
