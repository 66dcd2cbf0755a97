use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::model::{JointType, Transmission};
use crate::probe::limit::LimitHit;
use crate::probe::{LimitApproach, Measure, Measurement, Preconditions};
use crate::rules::{Context, Domain, Rule, RuleMeta, display_name, measure_each, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Checks the training range of every position actuator on a hinge or slide joint: its
    /// `ctrlrange` should be the spec's `robot.soft_limit_factor` (default 0.9) × the joint's
    /// hardware `range`, centred on it. Without a spec it still reports a ctrlrange that covers
    /// the whole joint range — its ends beyond the range's, or within `tolerance` of them (a
    /// margin of a rounding error is no soft limit) — or is unlimited, which lets the policy
    /// command the hard stops. It
    /// also reports an actuated hinge/slide joint with no range at all — unless the joint turns
    /// without end by design: a wheel (an unlimited hinge turning a round geom about its own
    /// axle), a mobile base's coordinates over the floor (a body fixed to the world but for two
    /// or more joints of its own, at least one a slide: x, y and yaw written in place of a free
    /// joint), or on a fixed-base robot a joint whose position actuators have no `ctrlrange`
    /// either while the model gives its other actuated joints ranges (an arm's continuous
    /// axes). It also reports a hinge whose range reaches more than a full turn (2π) beyond its
    /// position actuator's ctrlrange at both ends: stops no command comes near bound nothing
    /// (±31.415 written for ±3.1415). Actuators that share the problem through one `<default
    /// class>` are reported once.
    ///
    /// In a URDF, a revolute or prismatic joint's `<safety_controller>` whose written
    /// `soft_lower_limit` lies below its `<limit lower>`, or `soft_upper_limit` above its
    /// `upper`, by more than `tolerance` of the range: the specification has the safety
    /// controller start limiting the joint at its soft limits, inside the hard range, so a soft
    /// limit beyond the hard one never acts and one of the two ranges is not the joint's (the
    /// KUKA LWR's `kuka_arm_1_joint`: ±1.5708 rad "reduced … to avoid contact with table"
    /// inside soft limits of ±2.0595 rad). A fact of the file; no probe runs on it.
    ///
    /// ## Why is this bad?
    /// Training is meant to use soft limits, typically 0.9 of the hardware range (Asimov system identification §8):
    /// commanding the hard stops produces hard-stop impacts, exploitation of boundary states and
    /// shock loads near the limits on the real robot.
    ///
    /// ## How it is confirmed
    /// These findings are facts of the file (the numbers of `ctrlrange` and `range`); no
    /// simulation refutes them. Probe `limit-approach` measures the consequence: the actuator is
    /// commanded to each end of its ctrlrange and the probe records where the joint goes and
    /// whether the hard stop engages (impact speed, limit force). When the servo cannot drive
    /// the joint to within 5 % of its range of a commanded end, the measurement is
    /// inconclusive and says so. For a joint with no range it measures how far the joint swings.
    ///
    /// ## How to fix
    /// Set `ctrlrange` to the centred soft range given in the help (or
    /// `inheritrange="<factor>"` on the position actuator), and give every actuated joint its
    /// hardware `range`.
    pub SoftLimits {
        id: "soft-limits",
        group: "limits",
        level: Severity::Warning,
        probe: LimitApproach,
        options: [opt("tolerance", 0.02, "fraction of joint range", Domain::FRACTION_BELOW_ONE, "allowed deviation of each ctrlrange end from the soft range; ctrlrange ends this close to the hard ends cover the whole range")],
    }
}

/// One turn of a hinge (rad). A revolute joint's hardware stops lie within a turn of where it
/// works (a multi-turn axis such as a UR arm's ±2π still has its ctrlrange reach the stops): a
/// position servo whose ctrlrange stays more than this inside both stops never comes near them.
const FULL_TURN: f64 = std::f64::consts::TAU;

fn unit(t: JointType) -> &'static str {
    if t == JointType::Slide { "m" } else { "rad" }
}

fn rng(r: [f64; 2], u: &str) -> String {
    format!("[{}, {}] {u}", fmt_num(r[0], 4), fmt_num(r[1], 4))
}

/// What the `limit-approach` probe measures about a soft-limit finding — a fact of the file
/// (the numbers of `ctrlrange` and `range`), so never refuted: commanding each end of the
/// ctrlrange, where the joint goes and whether its hard stop engages (at what speed, with what
/// force). Preconditions: the joint has a stop, and the servo drove the joint to within 5 % of
/// its range of each commanded end (else: inconclusive, the run says nothing about the stop).
#[derive(Debug)]
pub struct HardStopExposure {
    pub actuator: usize,
}

/// A joint with no range: commanding the ctrlrange ends, how far the joint swings.
#[derive(Debug)]
pub struct SwingWithoutStop {
    pub actuator: usize,
}

fn limit_map(h: &LimitHit) -> BTreeMap<String, f64> {
    let mut m = BTreeMap::from([
        ("hit".to_string(), if h.hit { 1.0 } else { 0.0 }),
        ("impact_velocity".to_string(), h.impact_velocity),
        ("max_limit_force".to_string(), h.max_limit_force),
        ("q_min".to_string(), h.q_min),
        ("q_max".to_string(), h.q_max),
    ]);
    for (k, e) in ["lo", "hi"].iter().zip(&h.ends) {
        if e.target.is_finite() {
            m.insert(format!("target_{k}"), e.target);
        }
        m.insert(format!("reached_{k}"), e.reached);
    }
    m
}

/// Fraction of the joint range within which the servo counts as having reached its target.
pub const REACH_TOLERANCE: f64 = 0.05;

impl Measure for HardStopExposure {
    type Probe = LimitApproach;
    fn key(&self, _: &Loaded) -> Result<usize, &'static str> {
        Ok(self.actuator)
    }
    fn measure(&self, l: &Loaded, h: &LimitHit) -> Measurement {
        let span = (h.range[1] - h.range[0]).abs().max(1e-9);
        let short = h.shortfall();
        // Without a ctrlrange the run commands the joint's own range ends, where a servo settles
        // onto its stop whatever the training range: it measures nothing about one.
        let ctrlrange = l.robot.actuators.get(self.actuator).is_some_and(|a| a.ctrllimited);
        let mut pre = Preconditions::new()
            .check(
                "stop_exists",
                h.stop_exists,
                if h.stop_exists {
                    "the joint has a hard range"
                } else {
                    "the joint has no hard range"
                },
            )
            .check(
                "ctrlrange_exists",
                ctrlrange,
                if ctrlrange {
                    "the actuator has a ctrlrange to command"
                } else {
                    "the actuator has no ctrlrange: the run could only command the joint's own range ends, which says nothing of a training range"
                },
            );
        for (k, e) in ["lower", "upper"].iter().zip(&h.ends) {
            if !e.target.is_finite() {
                continue;
            }
            let i = usize::from(*k == "upper");
            let ok = short[i] <= REACH_TOLERANCE * span;
            pre = pre.check(
                "reached_commanded_extreme",
                ok,
                format!(
                    "commanded to the {k} ctrlrange end ({} rad), the joint came within {} rad of it or of the stop before it (tolerance {} rad)",
                    fmt_num(e.target, 4),
                    fmt_num(short[i], 3),
                    fmt_num(REACH_TOLERANCE * span, 3)
                ),
            );
        }
        let note = if !ctrlrange {
            format!(
                "no ctrlrange: commanding the joint's range ends {} moved it over [{}, {}] rad",
                rng(h.range, "rad"),
                fmt_num(h.q_min, 4),
                fmt_num(h.q_max, 4)
            )
        } else if h.hit {
            format!(
                "commanding the ctrlrange ends drove the joint into its hard stop at {} rad/s (limit force up to {} N·m)",
                fmt_num(h.impact_velocity, 3),
                fmt_num(h.max_limit_force, 3)
            )
        } else {
            format!(
                "commanding the ctrlrange ends moved the joint over [{}, {}] rad without engaging its hard stop {}",
                fmt_num(h.q_min, 4),
                fmt_num(h.q_max, 4),
                rng(h.range, "rad")
            )
        };
        Measurement::new(&pre, limit_map(h), note)
    }
}

impl Measure for SwingWithoutStop {
    type Probe = LimitApproach;
    fn key(&self, l: &Loaded) -> Result<usize, &'static str> {
        match l.robot.actuators.get(self.actuator) {
            Some(a) if a.ctrllimited => Ok(self.actuator),
            _ => Err("neither the joint nor its actuator has a range to command"),
        }
    }
    fn measure(&self, _: &Loaded, h: &LimitHit) -> Measurement {
        let note = format!(
            "commanded to its ctrlrange ends, the joint swung over [{}, {}] rad; no stop acts on it",
            fmt_num(h.q_min, 4),
            fmt_num(h.q_max, 4)
        );
        Measurement::new(&Preconditions::new(), limit_map(h), note)
    }
}

/// Attaches the limit-approach measurement to the findings about one actuator (all facts).
pub fn measure_hard_stops(cx: &Context, findings: &mut [Finding]) {
    let robot = cx.robot;
    measure_each(findings, |f| match f.subject {
        Subject::Actuator(actuator) => {
            let limited = robot
                .actuators
                .get(actuator)
                .and_then(|a| (a.target >= 0).then(|| robot.joints.get(a.target as usize)))
                .flatten()
                .is_some_and(|j| j.limited);
            Some(if limited {
                Stop::Exposure(HardStopExposure { actuator })
            } else {
                Stop::Swing(SwingWithoutStop { actuator })
            })
        }
        _ => None,
    });
}

/// One of the two measurements, by whether the joint has a range.
#[derive(Debug)]
pub enum Stop {
    Exposure(HardStopExposure),
    Swing(SwingWithoutStop),
}

impl Measure for Stop {
    type Probe = LimitApproach;
    fn key(&self, l: &Loaded) -> Result<usize, &'static str> {
        match self {
            Stop::Exposure(m) => m.key(l),
            Stop::Swing(m) => m.key(l),
        }
    }
    fn measure(&self, l: &Loaded, h: &LimitHit) -> Measurement {
        match self {
            Stop::Exposure(m) => m.measure(l, h),
            Stop::Swing(m) => m.measure(l, h),
        }
    }
}

/// A joint with no range that turns without end by design: a wheel ([`Robot::is_wheel`]), or,
/// on a fixed-base robot, a joint whose position actuators leave their targets unbounded too
/// (no `ctrlrange`) in a model that gives other actuated joints their ranges — the continuous
/// axes of an arm such as the Kinova Gen3's joints 1, 3, 5 and 7. Nothing in the file bounds
/// the joint, on purpose. On a floating-base (legged) robot the same omission is reported.
/// A mobile base's coordinates over the floor ([`Robot::is_base_coordinate`]) have no stops
/// either.
fn continuous(robot: &crate::model::Robot, joint: usize, acts: &[&crate::model::Actuator]) -> bool {
    if robot.is_wheel(joint) || robot.is_base_coordinate(joint) {
        return true;
    }
    let unbounded_servos = acts.iter().all(|a| a.servo.is_some() && !a.ctrllimited);
    let others_ranged = robot
        .joints
        .iter()
        .any(|o| o.id != joint && o.limited && !robot.actuators_on_joint(o.id).is_empty());
    let fixed_base = !robot.joints.iter().any(|j| j.jtype == JointType::Free);
    fixed_base && unbounded_servos && others_ranged
}

impl Rule for SoftLimits {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let first = out.len();
        self.check_ranges(cx, out);
        measure_hard_stops(cx, &mut out[first..]);
        super::urdf_soft_limits::urdf_soft_limits(cx, cx.opt("tolerance"), out);
    }
}

impl SoftLimits {
    fn check_ranges(&self, cx: &Context, out: &mut Vec<Finding>) {
        let tol = cx.opt("tolerance");
        let factor = cx.spec.map(|s| s.soft_limit_factor());
        let factor_loc =
            cx.spec.and_then(|s| s.robot.soft_limit_factor.as_ref().map(|f| s.loc(f.span())));
        // Findings that come from one default-class attribute are merged: key = span of the value.
        let mut groups: BTreeMap<(usize, usize, usize, u8), Vec<Finding>> = BTreeMap::new();
        for j in cx.robot.joints.iter().filter(|j| j.is_scalar()) {
            let acts = cx.robot.actuators_on_joint(j.id);
            if acts.is_empty() {
                continue;
            }
            let u = unit(j.jtype);
            if !j.limited && continuous(cx.robot, j.id, &acts) {
                continue;
            }
            if !j.limited {
                let a = acts[0];
                let f = cx
                    .at_elem(ElemKind::Joint, j.id, &j.name, format!("actuated joint `{}` has no range (limited=\"false\")", j.name))
                    .label("no range")
                    .note("without a hardware range the simulated joint can turn past the real robot's hard stops, and no soft training range can be derived")
                    .help("give the joint its hardware range=\"lo hi\" (and limited=\"true\" if autolimits is off)")
                    .subject(Subject::Actuator(a.id));
                out.push(f);
                continue;
            }
            for a in acts {
                let Some(servo) = a.servo else { continue };
                if !matches!(a.trn, Transmission::Joint | Transmission::JointInParent) {
                    continue;
                }
                // A ctrlrange written in degrees is its own finding (ctrlrange-in-degrees).
                if super::ctrlrange_in_degrees::looks_like_degrees(cx.robot, a, 0.05) {
                    continue;
                }
                // A servo's setpoint is in actuator length = gear·q; refer it to the joint.
                let c = a.setpoint_range().unwrap_or([f64::NEG_INFINITY, f64::INFINITY]);
                // A scaled servo's ctrlrange is in its own units: name both.
                let crng = |c: [f64; 2]| {
                    if servo.is_unit() {
                        rng(c, u)
                    } else {
                        format!(
                            "[{}, {}] (setpoint {}: gain/kp {})",
                            fmt_num(a.ctrlrange[0], 4),
                            fmt_num(a.ctrlrange[1], 4),
                            rng(c, u),
                            fmt_num(servo.scale, 4)
                        )
                    }
                };
                let r = j.range;
                let span = r[1] - r[0];
                let eps = 1e-9 * span.max(1.0);
                let mid = 0.5 * (r[0] + r[1]);
                // Ends within `tolerance` of the hard ends are the hard ends: a margin of a
                // rounding error (±6.2831 of ±6.28319) is no soft limit.
                let near = tol * span;
                let covers = c[0] <= r[0] + near && c[1] >= r[1] - near;
                let exp = factor.map(|fct| [mid - 0.5 * fct * span, mid + 0.5 * fct * span]);
                let dev = exp.map(|e| ((c[0] - e[0]).abs()).max((c[1] - e[1]).abs()) / span);
                let within_spec = dev.is_some_and(|d| d <= tol);
                let (kind, msg) = if !a.ctrllimited {
                    (
                        0u8,
                        format!(
                            "position actuator `{}` has no ctrlrange: the policy can command any target on joint `{}` (range {})",
                            display_name(&a.name, a.id),
                            j.name,
                            rng(r, u)
                        ),
                    )
                } else if covers && !within_spec {
                    // Past the range: by how much, so that a rounding (-0.22689280275926285
                    // written for -0.226893) does not read "[-0.2269, 0.733] is wider than
                    // [-0.2269, 0.733]".
                    let over = (r[0] - c[0]).max(c[1] - r[1]);
                    let margin = (c[0] - r[0]).max(r[1] - c[1]);
                    let how = if over > eps {
                        format!("reaches {} {u} past", fmt_num(over, 3))
                    } else if margin <= eps {
                        "equals".to_string()
                    } else {
                        format!(
                            "stops within {} {u} ({} % of the range, tolerance {} %) of",
                            fmt_num(margin, 3),
                            fmt_num(100.0 * margin / span, 2),
                            fmt_num(100.0 * tol, 3)
                        )
                    };
                    (
                        1,
                        format!(
                            "position actuator `{}` ctrlrange {} {how} joint `{}`'s hardware range {}",
                            display_name(&a.name, a.id),
                            crng(c),
                            j.name,
                            rng(r, u)
                        ),
                    )
                } else if let (Some(e), Some(d)) = (exp, dev) {
                    if d <= tol {
                        continue;
                    }
                    (
                        2,
                        format!(
                            "position actuator `{}` ctrlrange {} is not the soft range {} ({} × joint `{}` range {}, centred)",
                            display_name(&a.name, a.id),
                            crng(c),
                            rng(e, u),
                            fmt_num(factor.unwrap_or(0.9), 3),
                            j.name,
                            rng(r, u)
                        ),
                    )
                } else if j.jtype == JointType::Hinge
                    && a.ctrllimited
                    && c[0] - r[0] > FULL_TURN
                    && r[1] - c[1] > FULL_TURN
                {
                    (
                        3,
                        format!(
                            "joint `{}` range {} spans {} turns, and position actuator `{}` ctrlrange {} stays more than a full turn inside both of its stops",
                            j.name,
                            rng(r, u),
                            fmt_num(span / FULL_TURN, 3),
                            display_name(&a.name, a.id),
                            crng(c)
                        ),
                    )
                } else {
                    continue;
                };
                let attr = if cx.robot.elem(ElemKind::Actuator, a.id, &a.name).is_some_and(|e| {
                    !e.attrs.contains_key("ctrlrange") && e.attrs.contains_key("inheritrange")
                }) {
                    "inheritrange"
                } else {
                    "ctrlrange"
                };
                // Every hinge range in the file within ±π under MJCF's default degrees: the
                // tiny range is a unit slip, not a hardware range to train inside.
                let radian_slip = j.jtype == JointType::Hinge
                    && super::ctrlrange_in_degrees::ranges_look_like_radians(cx.robot);
                let msg = if radian_slip {
                    format!(
                        "{msg}; the file's range numbers [{}, {}] are read as degrees (MJCF's default <compiler angle=\"degree\">), and every hinge range in the file is within ±π: radians were likely meant",
                        fmt_num(r[0].to_degrees(), 4),
                        fmt_num(r[1].to_degrees(), 4)
                    )
                } else {
                    msg
                };
                let fct = factor.unwrap_or(0.9);
                let soft = exp.unwrap_or([mid - 0.5 * fct * span, mid + 0.5 * fct * span]);
                let mut f = cx
                    .at_attr(ElemKind::Actuator, a.id, &a.name, attr, msg)
                    .note("training should use soft limits inside the hardware range (typically 0.9 of it, Asimov system identification §8); commanding the hard stops trains hard-stop impacts and boundary exploitation that shock-load the real joints")
                    .help(format!(
                        "set ctrlrange=\"{} {}\" ({} × range, centred){}",
                        fmt_num(a.ctrl_for_joint(soft[0]).min(a.ctrl_for_joint(soft[1])), 4),
                        fmt_num(a.ctrl_for_joint(soft[0]).max(a.ctrl_for_joint(soft[1])), 4),
                        fmt_num(fct, 3),
                        // inheritrange maps the joint range onto ctrl one to one: a
                        // `<position>`'s, not a scaled servo's.
                        if servo.is_unit() {
                            format!(", or inheritrange=\"{}\"", fmt_num(fct, 3))
                        } else {
                            String::new()
                        }
                    ))
                    .label(if a.ctrllimited { format!("ctrlrange {}", crng(c)) } else { "unlimited".into() })
                    .subject(Subject::Actuator(a.id))
                    .with("ctrl_lo", c[0])
                    .with("ctrl_hi", c[1])
                    .with("range_lo", r[0])
                    .with("range_hi", r[1])
                    .with("soft_lo", soft[0])
                    .with("soft_hi", soft[1]);
                if radian_slip {
                    let (rloc, _) = cx.robot.attr_loc(ElemKind::Joint, j.id, &j.name, "range");
                    f = f.secondary(rloc, "read as degrees").help(
                        "if the ranges are radians, add <compiler angle=\"radian\"/> (MJCF reads angles in degrees by default); then set the ctrlrange inside the range",
                    );
                }
                if kind == 3 {
                    let (rloc, _) = cx.robot.attr_loc(ElemKind::Joint, j.id, &j.name, "range");
                    f = f
                        .secondary(rloc, format!("range {}", rng(r, u)))
                        .note("a revolute joint's hardware stops lie within a turn of where it works; stops no command comes within a turn of bound nothing, so the simulated joint has in effect no range (a slipped decimal point, e.g. 31.415 for 3.1415, or a placeholder)")
                        .help("give the joint its hardware range=\"lo hi\", then a ctrlrange inside it (e.g. inheritrange=\"0.9\")");
                }
                if let (2, Some(loc)) = (kind, factor_loc) {
                    f = f.secondary(loc, format!("spec soft_limit_factor = {}", fmt_num(fct, 3)));
                }
                let (loc, class) = cx.robot.attr_loc(ElemKind::Actuator, a.id, &a.name, attr);
                let key = if class.is_some() {
                    (loc.file, loc.start, loc.end, kind)
                } else {
                    (usize::MAX, a.id, 0, kind)
                };
                groups.entry(key).or_default().push(f);
            }
        }
        for (_, mut fs) in groups {
            if fs.len() == 1 {
                out.extend(fs);
                continue;
            }
            let n = fs.len();
            let names: Vec<String> =
                fs.iter().map(|f| f.element.trim_start_matches("actuator ").to_string()).collect();
            let mut f = fs.remove(0);
            let stops_out_of_reach = f.message.contains("more than a full turn inside");
            let what = match f.message.contains("no ctrlrange") {
                true => "have no ctrlrange".to_string(),
                false if f.message.contains("is not the soft range") => {
                    "are not at the spec's soft range".to_string()
                }
                false if stops_out_of_reach => {
                    "stay more than a full turn inside both stops of their joints' ranges"
                        .to_string()
                }
                false => "cover their joints' whole hardware range".to_string(),
            };
            if !stops_out_of_reach {
                f.help = Some(format!(
                    "set each actuator's ctrlrange to the centred soft range, e.g. inheritrange=\"{}\" in the default class",
                    fmt_num(factor.unwrap_or(0.9), 3)
                ));
            }
            f.message = format!(
                "{n} position actuators {what} through one default class: {} (first: {})",
                names.join(", "),
                f.message
            );
            out.push(f);
        }
    }
}
