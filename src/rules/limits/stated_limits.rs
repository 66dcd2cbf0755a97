//! What a URDF's moving joints state in `<limit>` (effort, velocity) read together for
//! `placeholder-joint-limits`: a value copied onto joints of different motors, and motors with a
//! speed and no torque.
use crate::model::JointType;
use crate::model::Robot;
use crate::model::source::Loc;
use crate::model::urdf_transmissions::drives;
use crate::util::fmt_num;

use super::placeholder_joint_limits::{Case, Hit};

/// A moving URDF joint's written `effort` and `velocity` (value, where).
pub(super) struct Stated {
    pub(super) joint: usize,
    pub(super) effort: Option<(f64, Loc)>,
    pub(super) velocity: Option<(f64, Loc)>,
}

/// Every moving joint states `effort="0"` and one or more a speed (`velocity` > 0), none driven
/// by a `<transmission>` (those are [`Case::Zero`]'s): motors with speeds and no torque. One
/// hit per joint with a speed.
pub(super) fn unpowered(
    robot: &Robot,
    stated: &[Stated],
    driven: &[crate::model::urdf_transmissions::Drive],
) -> Vec<Hit> {
    let name = |s: &Stated| robot.joints.get(s.joint).map_or("", |j| j.name.as_str());
    let all_zero = !stated.is_empty()
        && stated.iter().all(|s| s.effort.is_some_and(|e| e.0 == 0.0) && !drives(driven, name(s)));
    if !all_zero {
        return Vec::new();
    }
    stated
        .iter()
        .filter_map(|s| {
            let (v, _) = s.velocity.filter(|v| v.0 > 0.0)?;
            let (_, at) = s.effort?;
            let slide = robot.joints.get(s.joint)?.jtype == JointType::Slide;
            Some(Hit {
                case: Case::Unpowered,
                joint: s.joint,
                at,
                value: 0.0,
                detail: format!(
                    "`{}` effort 0, velocity {} {}",
                    name(s),
                    fmt_num(v, 4),
                    if slide { "m/s" } else { "rad/s" }
                ),
            })
        })
        .collect()
}

/// The one-value case: every moving joint (at least `min_joints`) states one positive velocity
/// while their positive efforts span `spread` or more, or one effort while their velocities do.
/// One hit for the first joint, its detail naming the value, the other quantity's span and the
/// count; `value` is that span.
pub(super) fn one_value(stated: &[Stated], spread: f64, min_joints: f64) -> Option<Hit> {
    type Get = fn(&Stated) -> Option<(f64, Loc)>;
    let quantities: [(&str, &str, &str, &str, Get, Get); 2] = [
        ("velocity", "efforts", "rad/s", "N·m", |s| s.velocity, |s| s.effort),
        ("effort", "velocities", "N·m", "rad/s", |s| s.effort, |s| s.velocity),
    ];
    if (stated.len() as f64) < min_joints {
        return None;
    }
    for (what, others, unit, ounit, one, other) in quantities {
        let vals: Vec<(f64, Loc)> =
            stated.iter().filter_map(|s| one(s).filter(|v| v.0 > 0.0)).collect();
        if vals.len() != stated.len() || vals.iter().any(|v| v.0 != vals[0].0) {
            continue;
        }
        let spans: Vec<f64> =
            stated.iter().filter_map(|s| other(s).map(|v| v.0)).filter(|v| *v > 0.0).collect();
        let lo = spans.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = spans.iter().copied().fold(0.0, f64::max);
        if spans.len() < 2 || !(hi >= spread * lo) {
            continue;
        }
        return Some(Hit {
            case: Case::OneValue,
            joint: stated[0].joint,
            at: vals[0].1,
            value: hi / lo,
            detail: format!(
                "{what} {} {unit} on all {} moving joints, whose {others} range from {} to {} {ounit} ({}×)",
                fmt_num(vals[0].0, 4),
                stated.len(),
                fmt_num(lo, 4),
                fmt_num(hi, 4),
                fmt_num(hi / lo, 3)
            ),
        });
    }
    None
}

/// The power case: the peak power the moving joints' stated limits claim, Σ effort × velocity / 4
/// (a motor's peak mechanical power, at half its stall torque and half its no-load speed), above
/// `max_specific` W per kg of the robot's stated mass (`mass`, the URDF's link masses: no motors
/// weigh more than the robot that carries them). One hit per joint stating both, its `value`
/// that joint's power (W).
pub(super) fn overpowered(
    robot: &Robot,
    stated: &[Stated],
    mass: f64,
    max_specific: f64,
) -> Vec<Hit> {
    let hits: Vec<Hit> = stated
        .iter()
        .filter_map(|s| {
            let (e, at) = s.effort.filter(|e| e.0 > 0.0)?;
            let (v, _) = s.velocity.filter(|v| v.0 > 0.0)?;
            let j = robot.joints.get(s.joint)?;
            let (tu, vu) =
                if j.jtype == JointType::Slide { ("N", "m/s") } else { ("N·m", "rad/s") };
            let power = e * v / 4.0;
            Some(Hit {
                case: Case::Power,
                joint: s.joint,
                at,
                value: power,
                detail: format!(
                    "`{}` {} {tu} × {} {vu} / 4 = {} W",
                    j.name,
                    fmt_num(e, 4),
                    fmt_num(v, 4),
                    fmt_num(power, 4)
                ),
            })
        })
        .collect();
    let total: f64 = hits.iter().map(|h| h.value).sum();
    if mass > 0.0 && total > max_specific * mass { hits } else { Vec::new() }
}
