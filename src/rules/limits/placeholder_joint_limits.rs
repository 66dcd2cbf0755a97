use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::{Loc, XNode};
use crate::model::urdf_transmissions::{drives, transmissions};
use crate::model::{Format, JointType, Robot};
use crate::rules::{Context, Domain, Rule, RuleMeta, in_subtree, opt};

use super::actuator_effort::actuator_efforts;
use super::legs::{flange_roll, knee_and_below, leg_hinges};
use super::stated_limits::{Stated, one_value, overpowered, unpowered};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// In a URDF, finds `<limit>`s that cannot be the hardware's, judged from the robot's own
    /// physics, not from a list of round numbers:
    /// - **effort**: a joint's `effort` above `weight_multiple` × the torque of the whole
    ///   robot's weight at the joint's reach (the URDF's link masses summed, root link included,
    ///   × g × the farthest point of what the joint carries from its anchor, at qpos0; a force
    ///   of the robot's weight for a prismatic joint). That torque bounds every static load the joint can meet (a leg
    ///   joint holding the robot on its foot, an arm joint its links), so a motor many times
    ///   stronger is no motor of this robot (Bolt's `effort="1000"` N·m on a 1.3 kg robot);
    /// - **velocity**: a joint's `velocity` that would move the farthest point it carries
    ///   faster than `max_tip_speed` (velocity × reach, or the velocity itself for a prismatic
    ///   joint);
    /// - **zero**: `effort="0"` or `velocity="0"` on a joint a `<transmission>` drives (a motor
    ///   that gives no torque or cannot turn), and `velocity="0"` with a positive `effort` on
    ///   any moving joint (a motor's torque with no speed: myCobot 280's six joints); a passive
    ///   joint's `effort="0" velocity="0"` (no motor) is not judged;
    /// - **beyond a turn**: a revolute joint with a stop more than a full turn (2π, plus the
    ///   rounding of a value written to two decimals) from its zero: cable-wound multi-turn
    ///   axes such as a UR arm's are ±2π. The one wider real stop is a fixed-base arm's flange
    ///   roll, the last moving joint of its chain (nothing below it turns, so no link swings
    ///   through another): industrial wrists turn their last axis up to ±455° (ABB IRB 2400
    ///   ±400°); it is judged against `flange_max_turns` (1.3 turns) instead;
    /// - **effort 0 everywhere**: every moving joint states `effort="0"` while stating a speed
    ///   (`velocity` > 0) on one or more, with no `<transmission>`: motors with speeds and no
    ///   torque (a ROS-Industrial arm's `effort="0"` on all six axes); a passive joint among
    ///   motors (the others state torque) is not judged;
    /// - **a leg joint turning a full turn**: a hinge of a leg (the joints between a foot, or
    ///   a URDF leg's lowest link, and the body the legs leave) whose range spans a full turn
    ///   or more (2π, less the rounding of a value written to two decimals: Mini Cheetah's
    ///   ±6.28 rad): a hip or knee cannot turn a full turn, its leg would pass through the body
    ///   or its own thigh, so the range is a placeholder. A wheel at a leg's end (a round geom
    ///   centred on the hinge, ending the chain) turns about itself and is not judged, nor is
    ///   an arm's multi-turn axis (a UR arm's ±2π is the hardware's);
    /// - **a knee or ankle turning half a turn**: a leg's knee (the hinge between the two
    ///   longest links of its chain, thigh and shank) or a hinge below it (the ankle) whose
    ///   range is symmetric about its zero (`[−a, a]`, within the rounding of two decimals) and
    ///   spans half a turn (π, less that rounding) or more but less than a full turn: a knee
    ///   bends one way from straight, and a shank or foot swung a quarter turn or more each way
    ///   folds onto the link above it on one side (Stompy Micro's ±π/2 knees), so the range is
    ///   a placeholder. Hips and arms are not judged (Go2's thigh joint, beside the body,
    ///   swings 290°), nor a knee whose range is one-sided;
    /// - **one value on every joint**: every moving joint (revolute, continuous, prismatic;
    ///   at least `copied_min_joints` of them) states the same `velocity` while their `effort`s
    ///   span a factor of `motor_spread` or more (or the same `effort` while their
    ///   `velocity`s do): joints that differ that much in torque have different motors or
    ///   reductions, and a reduction that multiplies the torque divides the speed, so one
    ///   speed written on all of them is a value copied across the file, not the motors'
    ///   (iCub's `velocity="100"` on every joint, efforts 0.45–84 N·m). A robot whose joints
    ///   all state one effort and one velocity (one servo everywhere) is not judged;
    /// - **more power than the robot's mass holds**: the moving joints' stated limits claim a
    ///   peak power, Σ `effort` × `velocity` / 4 (a DC motor's peak mechanical power is a
    ///   quarter of its stall torque × its no-load speed), above `max_specific_power` W per kg
    ///   of the robot's stated mass (the URDF's link masses; not judged when none is written).
    ///   The motors weigh less than the robot that carries them, and a legged robot's actuator
    ///   gives about 350 W per kg of its own mass by this measure (MIT Mini Cheetah's: 17 N·m
    ///   peak, 40 rad/s, 0.48 kg; Katz et al., ICRA 2019), so a file claiming more per kg of
    ///   the whole robot than that states no motors of it (the Ghost Vision 60's and Stoch 3's
    ///   100 N·m at 100 rad/s on every joint: 5,450 and 1,200 W/kg). URDFs with their
    ///   motors' values state 10–360 W/kg (measured: Mini Pupper 9.5, Darwin-OP 25, PhantomX
    ///   46, KUKA LWR 75, Qmini 135, CyberDog 2 142, the MIT humanoid 355);
    /// - **no range**: a revolute or prismatic joint with no `<limit>`, or `lower` = `upper` =
    ///   0 (both absent or written as 0), which MuJoCo compiles as an unlimited joint.
    ///
    /// In an MJCF file the beyond-a-turn and leg cases are judged on the compiled `range` of
    /// every limited hinge (ANYmal C's `range="-9.42478 9.42478"`, 1.5 turns), and the effort
    /// case on the force bound of the actuators that drive each hinge or slide, as compiled:
    /// each actuator's `forcerange` (its larger end in magnitude, so a bound in either
    /// direction is judged), or a `<motor>`'s `ctrlrange` × gain, × its gear, summed over the
    /// joint's actuators and no more than the joint's `actuatorfrcrange`, against the torque of
    /// the weight of the joint's kinematic tree (the bodies below the one hanging from the
    /// world: scenery and other robots in the scene are not the robot) on Earth (9.81 m/s²,
    /// whatever gravity the file simulates: the motors are the hardware's) at the joint's reach —
    /// the Koch v1.0 arm's `forcerange="-87 87"` on a 0.24 kg arm; joints with no bound are not
    /// judged. The other cases are URDF `<limit>` attributes.
    ///
    /// Joints sharing one case are reported together; joints whose subtree has no extent
    /// beyond the axis are not judged for effort and velocity.
    ///
    /// ## Why is this bad?
    /// MuJoCo's URDF importer makes a positive `effort` the joint's `actuatorfrcrange`, and
    /// training frameworks read `effort` and `velocity` as the joint's torque and speed limits
    /// (Isaac Gym's DoF properties; legged_gym clips its torques at the effort): a placeholder
    /// bounds nothing, and a policy trained against it learns motions that need torque or
    /// speed the motors do not have. MuJoCo ignores `velocity`. A stop beyond a full turn never
    /// engages (±10 rad lets a leg swing through itself), and frameworks that scale actions or
    /// observations by the range spread them over it. A revolute joint whose `lower` and
    /// `upper` are both 0 is locked at 0 for ROS tools and free without end in MuJoCo (its
    /// range 0 0 means no limit).
    ///
    /// ## How it is confirmed
    /// Static: the `<limit>` attributes as written, the compiled model's masses, geometry,
    /// joint ranges and actuator force bounds at the keyframe. A fact of the file.
    ///
    /// ## How to fix
    /// Write the motor's peak torque at the joint (peak × reduction) as `effort`, its no-load
    /// speed at the joint (motor speed / reduction) as `velocity`, and the hardware's stops as
    /// `lower`/`upper`; a joint that turns without end is `type="continuous"`, one that does not
    /// move is `type="fixed"`.
    pub PlaceholderJointLimits {
        id: "placeholder-joint-limits",
        group: "limits",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("weight_multiple", 50.0, "× the robot's weight at the joint's reach", Domain::AT_LEAST_ONE, "an effort above this many times the torque of the whole robot's weight at the joint's reach is no motor of the robot"),
            opt("max_tip_speed", 100.0, "m/s", Domain::POSITIVE, "a velocity moving the farthest point the joint carries faster than this is no motor's"),
            opt("motor_spread", 3.0, "ratio", Domain::AT_LEAST_ONE, "largest / smallest effort (or velocity) of the moving joints from which they cannot share one motor and reduction, so one velocity (or effort) written on all of them is copied"),
            opt("copied_min_joints", 6.0, "joints", Domain::AT_LEAST_ONE, "fewest moving joints stating one value for the one-value case to judge them"),
            opt("max_specific_power", 1000.0, "W/kg", Domain::POSITIVE, "peak power the joints' limits may claim (Σ effort × velocity / 4) per kg of the robot's stated mass: about 3× a legged robot's actuator's own 350 W/kg (MIT Mini Cheetah), which the whole robot, heavier than its motors, cannot exceed"),
            opt("flange_max_turns", 1.3, "turns", Domain::AT_LEAST_ONE, "widest stop, in turns from the joint's zero, of a fixed-base arm's flange roll (the last moving joint of its chain): industrial wrists' data sheets give the last axis up to ±455° (ABB IRB 2400 ±400°, FANUC LR Mate 200iD ±450°, Yaskawa GP7 ±455°)"),
        ],
    }
}

/// One full turn of a revolute joint (rad): its stops lie within a turn of its zero.
const FULL_TURN: f64 = std::f64::consts::TAU;
/// How far a value of 2π written to two decimals (6.28, 6.29) can lie from it (rad): the
/// rounding of the last digit written, with a margin for the next one.
const WRITTEN_ROUNDING: f64 = 0.01;

/// Whether a stop `far` rad from the zero of hinge `j` is beyond what the joint can have: a
/// full turn (and the rounding of 2π written to two decimals), or a flange roll's
/// `flange_max_turns`.
fn beyond_stops(robot: &Robot, legs: &[usize], j: usize, far: f64, flange_turns: f64) -> bool {
    far > FULL_TURN + WRITTEN_ROUNDING
        && !(flange_roll(robot, legs, j) && far <= flange_turns * FULL_TURN + WRITTEN_ROUNDING)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Case {
    Effort,
    Velocity,
    Zero,
    Stalled,
    Unpowered,
    BeyondTurn,
    LegTurn,
    LegFold,
    OneValue,
    Power,
    NoRange,
}

/// One joint with a placeholder: where, what the measured quantity is, and the text for it.
pub(super) struct Hit {
    pub(super) case: Case,
    pub(super) joint: usize,
    pub(super) at: Loc,
    /// Effort: effort / weight torque; velocity: tip speed (m/s); beyond a turn: the farthest
    /// stop (rad); zero / no range: 0.
    pub(super) value: f64,
    pub(super) detail: String,
}

/// The farthest point of what joint `j` carries from its anchor at the keyframe (m): the
/// subtree's body origins and geoms (centre + bounding radius).
pub fn subtree_reach(robot: &Robot, j: usize) -> f64 {
    let (Some(joint), Some(anchor)) = (robot.joints.get(j), robot.key.joint_xanchor.get(j)) else {
        return 0.0;
    };
    let d = |p: &[f64; 3]| {
        ((p[0] - anchor[0]).powi(2) + (p[1] - anchor[1]).powi(2) + (p[2] - anchor[2]).powi(2))
            .sqrt()
    };
    let mut reach: f64 = 0.0;
    for b in robot.bodies.iter().filter(|b| in_subtree(robot, joint.body, b.id)) {
        if let Some(p) = robot.key.body_xpos.get(b.id) {
            reach = reach.max(d(p));
        }
    }
    for g in robot.geoms.iter().filter(|g| g.body != 0 && in_subtree(robot, joint.body, g.body)) {
        if let Some(p) = robot.key.geom_xpos.get(g.id) {
            reach = reach.max(d(p) + g.rbound.max(0.0));
        }
    }
    if reach.is_finite() { reach } else { 0.0 }
}

/// The robot's mass as the URDF states it: the sum of its links' `<inertial><mass>` (kg). The
/// compiled model loses the root link's (MuJoCo's importer fixes the root to the world and
/// fuses it, with the links fixed to it, into the world body). `None` when no mass is written.
fn urdf_mass(root: &XNode) -> Option<f64> {
    let m: f64 = root
        .children_tagged("link")
        .flat_map(|l| l.children_tagged("inertial"))
        .flat_map(|i| i.children_tagged("mass"))
        .filter_map(|m| m.get("value")?.trim().parse::<f64>().ok())
        .filter(|m| m.is_finite() && *m > 0.0)
        .sum();
    (m > 0.0).then_some(m)
}

/// A leg hinge limited to `[l, h]` whose range spans a full turn or more (and no stop lies
/// beyond a turn: that case is reported as such).
fn leg_turn(robot: &Robot, legs: &[usize], j: usize, l: f64, h: f64, at: Loc) -> Option<Hit> {
    let far = l.abs().max(h.abs());
    if !legs.contains(&j) || far > FULL_TURN + WRITTEN_ROUNDING {
        return None;
    }
    let span = h - l;
    let turns = fmt_num(span / FULL_TURN, 3);
    (span >= FULL_TURN - WRITTEN_ROUNDING).then(|| Hit {
        case: Case::LegTurn,
        joint: j,
        at,
        value: span,
        detail: format!(
            "`{}` [{}, {}] rad ({turns} turn{})",
            robot.joints[j].name,
            fmt_num(l, 4),
            fmt_num(h, 4),
            if turns == "1" { "" } else { "s" }
        ),
    })
}

/// A knee or a hinge below it limited to a symmetric `[−a, a]` that spans half a turn or more,
/// and less than a full turn (that is [`leg_turn`]'s).
fn leg_fold(robot: &Robot, below: &[usize], j: usize, l: f64, h: f64, at: Loc) -> Option<Hit> {
    let span = h - l;
    let half = FULL_TURN / 2.0;
    let in_leg = below.contains(&j) && (l + h).abs() <= WRITTEN_ROUNDING;
    (in_leg && span >= half - WRITTEN_ROUNDING && span < FULL_TURN - WRITTEN_ROUNDING).then(|| {
        Hit {
            case: Case::LegFold,
            joint: j,
            at,
            value: span,
            detail: format!(
                "`{}` [{}, {}] rad ({}°)",
                robot.joints[j].name,
                fmt_num(l, 4),
                fmt_num(h, 4),
                fmt_num(span.to_degrees(), 3)
            ),
        }
    })
}

/// The limited hinges of an MJCF model whose compiled range places a stop more than a full
/// turn from the joint's zero, or spans a full turn on a leg.
fn mjcf_beyond_turn(cx: &Context) -> Vec<Hit> {
    let robot = cx.robot;
    let legs = leg_hinges(cx);
    let below = knee_and_below(cx);
    let mut hits = Vec::new();
    for j in robot.joints.iter().filter(|j| j.jtype == JointType::Hinge && j.limited) {
        let [l, h] = j.range;
        let far = l.abs().max(h.abs());
        let (at, _) = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "range");
        if let Some(hit) = leg_turn(robot, &legs, j.id, l, h, at) {
            hits.push(hit);
        }
        hits.extend(leg_fold(robot, &below, j.id, l, h, at));
        if beyond_stops(robot, &legs, j.id, far, cx.opt("flange_max_turns")) {
            hits.push(Hit {
                case: Case::BeyondTurn,
                joint: j.id,
                at,
                value: far,
                detail: format!(
                    "`{}` [{}, {}] rad ({} turns)",
                    j.name,
                    fmt_num(l, 4),
                    fmt_num(h, 4),
                    fmt_num(far / FULL_TURN, 3)
                ),
            });
        }
    }
    hits
}

fn num(limit: Option<&XNode>, attr: &str) -> Option<(f64, Loc)> {
    let a = limit?.attr(attr)?;
    crate::model::c_number(a.value.trim()).filter(|v| v.is_finite()).map(|v| (v, a.loc))
}

impl Rule for PlaceholderJointLimits {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let multiple = cx.opt("weight_multiple");
        let max_speed = cx.opt("max_tip_speed");
        if robot.format != Format::Urdf {
            let mut hits = mjcf_beyond_turn(cx);
            let efforts = actuator_efforts(cx, multiple);
            let mass = efforts.first().map_or(0.0, |e| e.mass);
            hits.extend(efforts.into_iter().map(|e| Hit {
                case: Case::Effort,
                joint: e.joint,
                at: e.at,
                value: e.ratio,
                detail: e.detail,
            }));
            for case in [Case::Effort, Case::BeyondTurn, Case::LegTurn, Case::LegFold] {
                let group: Vec<&Hit> = hits.iter().filter(|h| h.case == case).collect();
                if let Some(f) = finding(cx, case, &group, multiple, max_speed, mass) {
                    out.push(f);
                }
            }
            return;
        }
        let legs = leg_hinges(cx);
        let below = knee_and_below(cx);
        let g = robot.opt.gravity;
        let g = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let mass = urdf_mass(&robot.tree).unwrap_or_else(|| robot.mass_split().0);
        let driven = transmissions(cx.sources, &robot.tree);
        let mut hits: Vec<Hit> = Vec::new();
        let mut stated: Vec<Stated> = Vec::new();
        for x in robot.tree.children_tagged("joint") {
            let Some(name) = x.get("name") else { continue };
            let jtype = x.get("type").unwrap_or("");
            let Some(j) = robot.joint(name).filter(|j| j.is_scalar()) else { continue };
            let limit = x.children_tagged("limit").next();
            let name_at = x.attr("name").map_or(x.loc, |a| a.loc);
            let slide = j.jtype == JointType::Slide;
            // Range: a revolute/prismatic joint states its stops.
            if matches!(jtype, "revolute" | "prismatic") {
                let lo = num(limit, "lower");
                let hi = num(limit, "upper");
                let (l, h) = (lo.map_or(0.0, |v| v.0), hi.map_or(0.0, |v| v.0));
                if l == 0.0 && h == 0.0 && !j.limited {
                    let detail = match limit {
                        None => format!("`{name}` ({jtype}, no <limit>)"),
                        Some(_) => format!("`{name}` ({jtype}, lower = upper = 0)"),
                    };
                    let at = hi.or(lo).map_or(limit.map_or(name_at, |l| l.loc), |v| v.1);
                    hits.push(Hit { case: Case::NoRange, joint: j.id, at, value: 0.0, detail });
                } else if jtype == "revolute" && j.limited {
                    let far = l.abs().max(h.abs());
                    let at = if l.abs() >= h.abs() { lo } else { hi };
                    if let Some(hit) =
                        leg_turn(robot, &legs, j.id, l, h, at.map_or(name_at, |v| v.1))
                    {
                        hits.push(hit);
                    }
                    let at_far = at.map_or(name_at, |v| v.1);
                    hits.extend(leg_fold(robot, &below, j.id, l, h, at_far));
                    if beyond_stops(robot, &legs, j.id, far, cx.opt("flange_max_turns")) {
                        let at = if l.abs() >= h.abs() { lo } else { hi };
                        hits.push(Hit {
                            case: Case::BeyondTurn,
                            joint: j.id,
                            at: at.map_or(name_at, |v| v.1),
                            value: far,
                            detail: format!(
                                "`{name}` [{}, {}] rad ({} turns)",
                                fmt_num(l, 4),
                                fmt_num(h, 4),
                                fmt_num(far / FULL_TURN, 3)
                            ),
                        });
                    }
                }
            }
            let effort = num(limit, "effort");
            let velocity = num(limit, "velocity");
            if matches!(jtype, "revolute" | "continuous" | "prismatic") {
                stated.push(Stated { joint: j.id, effort, velocity });
            }
            // A joint a transmission drives with a zero limit: a motor with no torque or speed.
            if drives(&driven, name) {
                for (what, v) in [("effort", effort), ("velocity", velocity)] {
                    if let Some((x, at)) = v
                        && x == 0.0
                    {
                        hits.push(Hit {
                            case: Case::Zero,
                            joint: j.id,
                            at,
                            value: 0.0,
                            detail: format!("`{name}` {what} 0"),
                        });
                    }
                }
            } else if matches!(jtype, "revolute" | "continuous" | "prismatic")
                && let (Some((v, at)), Some((e, _))) = (velocity, effort)
                && v == 0.0
                && e > 0.0
            {
                // No transmission, but a motor's torque and a speed of 0: a joint that cannot
                // move. A passive joint's effort 0 and velocity 0 (no motor) is not judged.
                let unit = if slide { "N" } else { "N·m" };
                hits.push(Hit {
                    case: Case::Stalled,
                    joint: j.id,
                    at,
                    value: 0.0,
                    detail: format!("`{name}` effort {} {unit}, velocity 0", fmt_num(e, 4)),
                });
            }
            // A prismatic joint's load is a force: its "reach" is a unit lever (the weight in N,
            // the velocity in m/s as it stands).
            let reach = if slide { 1.0 } else { subtree_reach(robot, j.id) };
            if !(reach > 0.0) {
                continue;
            }
            let (tu, vu) = if slide { ("N", "m/s") } else { ("N·m", "rad/s") };
            if let Some((e, at)) = effort.filter(|e| e.0 > 0.0)
                && mass > 0.0
                && g > 0.0
            {
                let weight = mass * g * reach;
                let ratio = e.abs() / weight;
                if ratio > multiple {
                    let lever =
                        if slide { String::new() } else { format!(" at {} m", fmt_num(reach, 3)) };
                    hits.push(Hit {
                        case: Case::Effort,
                        joint: j.id,
                        at,
                        value: ratio,
                        detail: format!(
                            "`{name}` {} {tu} = {}× the robot's weight{lever} ({} {tu})",
                            fmt_num(e, 4),
                            fmt_num(ratio, 3),
                            fmt_num(weight, 3)
                        ),
                    });
                }
            }
            if let Some((v, at)) = velocity.filter(|v| v.0 > 0.0) {
                let tip = v.abs() * reach;
                if tip > max_speed {
                    let detail = if slide {
                        format!("`{name}` {} {vu}", fmt_num(v, 4))
                    } else {
                        format!(
                            "`{name}` {} {vu} × {} m = {} m/s",
                            fmt_num(v, 4),
                            fmt_num(reach, 3),
                            fmt_num(tip, 3)
                        )
                    };
                    hits.push(Hit { case: Case::Velocity, joint: j.id, at, value: tip, detail });
                }
            }
        }
        hits.extend(one_value(&stated, cx.opt("motor_spread"), cx.opt("copied_min_joints")));
        hits.extend(unpowered(robot, &stated, &driven));
        if let Some(stated_mass) = urdf_mass(&robot.tree) {
            hits.extend(overpowered(robot, &stated, stated_mass, cx.opt("max_specific_power")));
        }
        for case in [
            Case::Effort,
            Case::Velocity,
            Case::Zero,
            Case::Stalled,
            Case::Unpowered,
            Case::BeyondTurn,
            Case::LegTurn,
            Case::LegFold,
            Case::OneValue,
            Case::Power,
            Case::NoRange,
        ] {
            let group: Vec<&Hit> = hits.iter().filter(|h| h.case == case).collect();
            if let Some(f) = finding(cx, case, &group, multiple, max_speed, mass) {
                out.push(f);
            }
        }
    }
}

fn finding(
    cx: &Context,
    case: Case,
    hits: &[&Hit],
    multiple: f64,
    max_speed: f64,
    mass: f64,
) -> Option<Finding> {
    // The primary joint: the largest value (the first in the file on a tie).
    let top = hits.iter().copied().reduce(|a, b| if b.value > a.value { b } else { a })?;
    let n = hits.len();
    let s = if n == 1 { "" } else { "s" };
    let states = if n == 1 { "states" } else { "state" };
    let list: Vec<&str> = hits.iter().map(|h| h.detail.as_str()).collect();
    let shown = if n > 6 {
        format!("{}; and {} more", list[..6].join("; "), n - 6)
    } else {
        list.join("; ")
    };
    let robot = cx.robot;
    let j = &robot.joints[top.joint];
    let (has, places) = if n == 1 { ("has", "places") } else { ("have", "place") };
    let write_stops = if robot.format == Format::Urdf {
        "write the hardware's stops (datasheet or CAD) as lower and upper"
    } else {
        "write the hardware's stops (datasheet or CAD) as range=\"lo hi\""
    };
    let (msg, label, note, help) = match case {
        Case::Effort if robot.format != Format::Urdf => (
            format!(
                "{n} joint{s} {has} actuators that can apply over {} times the torque of the whole robot's weight ({} kg) at the joint's reach, no motor of this robot: {shown}",
                fmt_num(multiple, 3),
                fmt_num(mass, 3)
            ),
            "placeholder force bound".to_string(),
            "the actuators' force bound (forcerange, or a motor's ctrlrange × gear) is the torque MuJoCo lets them apply: a bound this far above any load the robot can put on the joint bounds nothing, so a policy trained with it learns motions that need torque the motor does not have",
            "write the motor's peak torque at the joint (the motor's peak × the reduction, from the datasheet) as the actuator's forcerange (÷ gear), or as the joint's actuatorfrcrange",
        ),
        Case::Effort => (
            format!(
                "{n} joint{s} {states} an effort limit over {} times the torque of the whole robot's weight ({} kg) at the joint's reach, no motor of this robot: {shown}",
                fmt_num(multiple, 3),
                fmt_num(mass, 3)
            ),
            "placeholder effort".to_string(),
            "MuJoCo's importer makes the effort the joint's actuatorfrcrange, and training frameworks read it as the torque limit (legged_gym clips its torques at it): a bound this far above any load the robot can put on the joint bounds nothing, and a policy trained with it learns motions that need torque the motor does not have",
            "write the motor's peak torque at the joint (the motor's peak × the reduction, from the datasheet) as effort",
        ),
        Case::Velocity => (
            format!(
                "{n} joint{s} {states} a velocity limit that would move the farthest point the joint carries faster than {} m/s, no motor's: {shown}",
                fmt_num(max_speed, 3)
            ),
            "placeholder velocity".to_string(),
            "MuJoCo ignores a URDF's velocity (it has no joint speed limit); training frameworks read it as the joint's speed limit (Isaac Gym's DoF properties) and in observation and reward scales: a placeholder leaves the motor's real speed limit unmodelled",
            "write the motor's no-load speed at the joint (motor speed / reduction, from the datasheet) as velocity, and apply it in the training environment",
        ),
        Case::Zero => (
            format!(
                "{n} limit{s} of joints a <transmission> drives {} zero, a motor with no torque or no speed: {shown}",
                if n == 1 { "is" } else { "are" }
            ),
            "zero limit on a driven joint".to_string(),
            "ROS and training frameworks read effort 0 as a joint that gives no torque and velocity 0 as one that cannot move; MuJoCo's importer treats effort 0 as no force limit at all",
            "write the motor's peak torque at the joint as effort and its speed at the joint as velocity",
        ),
        Case::Stalled => (
            format!(
                "{n} joint{s} {states} a motor's torque (effort > 0) and a speed limit of 0 (velocity=\"0\"): the file claims {} that cannot move: {shown}",
                if n == 1 { "a motor" } else { "motors" }
            ),
            "velocity 0 with an effort".to_string(),
            "a URDF's velocity is the joint's speed limit (rad/s; m/s for a prismatic joint), so 0 claims the joint cannot move while its effort claims a motor: the file states no speed for it. MuJoCo's importer ignores velocity (its model moves at any speed); a tool that reads the URDF's limits (a ROS joint-limits interface, a training framework's DoF velocity limit) holds the joint still or, reading 0 as unset, limits nothing, by the tool. A passive joint (effort 0) is not judged",
            "write the motor's no-load speed at the joint (motor speed / reduction, from the datasheet) as velocity",
        ),
        Case::Unpowered => (
            format!(
                "every moving joint states effort=\"0\" while {n} state{} a speed (velocity > 0): the file claims {} with no torque: {shown}",
                if n == 1 { "s" } else { "" },
                if n == 1 { "a motor" } else { "motors" }
            ),
            "effort 0 on every joint".to_string(),
            "a URDF's effort is the joint's torque limit (N·m; N for a prismatic joint): 0 on every joint while the velocities state motors' speeds is a value never filled in. MuJoCo's importer reads effort 0 as no force limit at all; a tool that reads the URDF's limits (a ROS joint-limits interface, a training framework's torque limit) gets motors that give no torque or, reading 0 as unset, limits nothing, by the tool. A passive joint among motors (the others state torque) is not judged",
            "write the motor's peak torque at each joint (the motor's peak × the reduction, from the datasheet) as effort",
        ),
        Case::BeyondTurn if robot.format != Format::Urdf => (
            format!(
                "{n} hinge joint{s} {places} a stop more than a full turn (2π) from the joint's zero, no hardware stop: {shown}"
            ),
            "beyond a full turn".to_string(),
            "a revolute joint's stops lie within a turn of its zero (the widest real ones, cable-wound multi-turn axes such as a UR arm's, are ±2π); a range beyond a turn is a limit that never engages (the links swing through each other), and frameworks that scale actions or observations by the range spread them over it",
            "write the hardware's stops (datasheet or CAD) as range=\"lo hi\"; a joint that turns without end has no range (limited=\"false\")",
        ),
        Case::BeyondTurn => (
            format!(
                "{n} revolute joint{s} {places} a stop more than a full turn (2π) from the joint's zero, no hardware stop: {shown}"
            ),
            "beyond a full turn".to_string(),
            "a revolute joint's stops lie within a turn of its zero (the widest real ones, cable-wound multi-turn axes such as a UR arm's, are ±2π); MuJoCo makes these the joint's range, a limit that never engages (the links swing through each other), and frameworks that scale actions or observations by the range spread them over it",
            "write the hardware's stops (datasheet or CAD) as lower and upper; a joint that turns without end is type=\"continuous\"",
        ),
        Case::LegTurn => (
            format!(
                "{n} leg joint{s} {has} a range of a full turn (2π) or more, which no hip or knee can turn: {shown}"
            ),
            "a leg joint turning a full turn".to_string(),
            "a leg's hinges (hip, knee, ankle) swing links that hit the body or the next link long before a full turn: a range of a turn or more (±6.28 rad is a full turn each way) is a placeholder, a limit that never engages, so the simulated leg swings through the body, and frameworks that scale actions or observations by the range spread them over it. A wheel at a leg's end turns about itself and is not judged, nor an arm's multi-turn axis",
            write_stops,
        ),
        Case::LegFold => (
            format!(
                "{n} knee or ankle joint{s} {has} a range symmetric about the zero that spans half a turn (π) or more, which folds the link below onto the one above: {shown}"
            ),
            "a knee or ankle turning half a turn".to_string(),
            "a knee or an ankle swings a shank or a foot that meets the thigh or the shin before half a turn, whichever way it turns (a knee bends from straight to folded, about 150°, one way only): a range of ±π/2 or more (a quarter turn each way) is a placeholder, a limit that never engages on one side, and frameworks that scale actions or observations by the range spread them over it. Hips, arms and one-sided ranges are not judged",
            write_stops,
        ),
        Case::OneValue => (
            format!(
                "one limit copied onto every joint: {shown}; joints this different in torque (or speed) have different motors or reductions, so the value is not the motors'",
            ),
            "one value on every joint".to_string(),
            "a reduction that multiplies a motor's torque divides its speed: joints whose efforts differ several-fold cannot all have one speed limit (nor joints whose speeds differ, one torque). Training frameworks read the URDF's velocity and effort as the joints' limits (Isaac Gym's DoF properties) and in observation and reward scales; a value copied onto joints with different motors is the limit of one of them at most",
            "write each joint's motor speed at the joint (motor speed / reduction) as velocity and its peak torque at the joint as effort, from the datasheets",
        ),
        Case::Power => {
            let total: f64 = hits.iter().map(|h| h.value).sum();
            (
                format!(
                    "the moving joints' effort and velocity limits claim {} W of peak motor power (Σ effort × velocity / 4), {} W per kg of the robot's {} kg, over {} W/kg: more than motors as heavy as the whole robot give: {shown}",
                    fmt_num(total, 4),
                    fmt_num(total / mass, 4),
                    fmt_num(mass, 4),
                    fmt_num(cx.opt("max_specific_power"), 4)
                ),
                "more power than the robot's mass holds".to_string(),
                "a DC motor's peak mechanical power is a quarter of its stall torque × its no-load speed, and the best legged-robot actuators give about 350 W per kg of their own mass by that measure (MIT Mini Cheetah's 17 N·m, 40 rad/s, 0.48 kg): limits claiming more per kg of the whole robot, motors included, than a few times that are placeholders, and a policy trained against them learns torques at speeds no motor of the robot reaches together",
                "write each joint's peak torque (motor peak × reduction) as effort and no-load speed (motor speed / reduction) as velocity, from the motors' datasheets",
            )
        }
        Case::NoRange => (
            format!(
                "{n} joint{s} declared revolute or prismatic {states} no range: MuJoCo compiles {} unlimited, ROS tools read {} locked at 0: {shown}",
                if n == 1 { "it" } else { "them" },
                if n == 1 { "it" } else { "them" }
            ),
            "no range".to_string(),
            "URDF takes a missing lower or upper as 0; a range of 0 0 means no limit to MuJoCo, so the joint turns without end in simulation while ROS tools hold it at 0",
            "write the hardware's stops as lower and upper; a joint that turns without end is type=\"continuous\", one that does not move type=\"fixed\"",
        ),
    };
    let mut f = cx.finding(msg, top.at).element(format!("joint `{}`", j.name), top.at).label(label);
    for h in hits.iter().filter(|h| h.joint != top.joint).take(3) {
        f = f.secondary(h.at, format!("also `{}`", robot.joints[h.joint].name));
    }
    let mut f = f.note(note).help(help).subject(Subject::Joint(j.id)).with("joints", n as f64);
    f = match case {
        Case::Effort => f.measured(top.value, "×").expected(multiple, "×"),
        Case::Velocity => f.measured(top.value, "m/s").expected(max_speed, "m/s"),
        Case::BeyondTurn => f.measured(top.value, "rad").expected(FULL_TURN, "rad"),
        Case::LegTurn => f.measured(top.value, "rad").expected(FULL_TURN, "rad"),
        Case::LegFold => f.measured(top.value, "rad").expected(FULL_TURN / 2.0, "rad"),
        Case::OneValue => f.measured(top.value, "×").expected(cx.opt("motor_spread"), "×"),
        Case::Power => f
            .measured(hits.iter().map(|h| h.value).sum::<f64>() / mass, "W/kg")
            .expected(cx.opt("max_specific_power"), "W/kg"),
        Case::Zero | Case::Stalled | Case::Unpowered | Case::NoRange => f.measured(0.0, ""),
    };
    Some(f)
}
