//! Checks of the recordings and options against the model that warn.
//!
//! Recorded positions outside the model's joint range: a wrong offset (an encoder zeroed
//! elsewhere than the model's zero), a wrong unit (degrees read as radians) or a model of
//! another robot. In the replay the model's limit acts against such a recording and
//! the fit would name the difference as physics; `gap` and `fit` warn, naming the joint, the
//! file, the time and the value against the range.

use std::f64::consts::PI;

use crate::model::{JointType, Robot};
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::BaseMode;

/// The warning for `--base free` / `--base recorded` on a model without a floating base (no
/// free joint: its root is fixed to the world), where the option changes nothing; `None` for
/// `--base fixed` (the default) or a floating-base model.
pub fn base_option_warning(robot: &Robot, base: BaseMode, recs: &[Recording]) -> Option<String> {
    let flag = match base {
        BaseMode::Fixed => return None,
        BaseMode::Free => "free",
        BaseMode::Recorded => "recorded",
    };
    if robot.joints.iter().any(|j| j.jtype == JointType::Free) {
        return None;
    }
    let with_base = recs.iter().filter(|r| r.base.is_some()).count();
    let cols = if with_base > 0 {
        format!(" (the base.* columns of {with_base} recording(s) are not used)")
    } else {
        String::new()
    };
    Some(format!(
        "--base {flag} changes nothing here: the model has no floating base (no <freejoint>; its \
         root body is fixed to the world){cols}. --base is for a robot whose root body moves: \
         `free` leaves the base to the physics after the first recorded pose, `recorded` drives \
         it from the base.x … base.qz columns, `fixed` (the default) pins it, as on a stand"
    ))
}

/// The note for recordings whose `base.*` columns the replay leaves (nearly) unused, once for
/// all of them: on a model without a floating base they are not read at all; on a floating base
/// held by `--base fixed` (the default) only their first row is, the pose the base is pinned at.
/// `None` without such columns, or when `--base free`/`recorded` reads them (or
/// [`base_option_warning`] already says the option changes nothing).
pub fn base_columns_note(robot: &Robot, base: BaseMode, recs: &[Recording]) -> Option<String> {
    let with_base = recs.iter().filter(|r| r.base.is_some()).count();
    if with_base == 0 || base != BaseMode::Fixed {
        return None;
    }
    let of = if with_base == recs.len() {
        "the recordings".to_string()
    } else {
        format!("{with_base} of {} recordings", recs.len())
    };
    if !robot.joints.iter().any(|j| j.jtype == JointType::Free) {
        return Some(format!(
            "the base.* columns of {of} were ignored: the model has no floating base (no \
             <freejoint>; its root body is fixed to the world), so there is no base to place"
        ));
    }
    Some(format!(
        "the base.* columns of {of} were ignored after their first row: the replay pins the \
         floating base at that pose (--base fixed, the default: a robot on a stand). --base \
         recorded drives the base through every recorded pose, --base free leaves it to the \
         physics after the first"
    ))
}

/// How far past its range, as a fraction of the range's span, a recorded position may go before
/// it is reported: MuJoCo's soft limit lets the model itself pass its range by a little under
/// load, and a hardware stop and encoder calibration sit within a few percent of the span
/// declared. A value beyond that is not noise.
pub const RANGE_SLACK: f64 = 0.05;

/// The most joints a warning lists one by one (the rest are counted).
const SHOWN: usize = 4;

/// One joint's worst excursion past its range over all recordings.
struct Excursion {
    joint: String,
    file: String,
    t: f64,
    value: f64,
    range: [f64; 2],
    slide: bool,
    /// A unit, not an offset: the recorded motion spans more than the whole range (no shift
    /// brings it in), and every recorded value lies within the range once scaled by π/180 — a
    /// recording in degrees, or an MJCF range written in radians under `<compiler
    /// angle="degree">` (MJCF's default), which are the same ratio.
    unit_fit: bool,
    /// Recorded motion: largest − smallest value over all recordings.
    span: f64,
}

/// The warning for recorded positions past the model's joint ranges (beyond [`RANGE_SLACK`]),
/// the worst sample of each joint; `None` when every recording stays within them.
pub fn out_of_range_warning(robot: &Robot, recs: &[Recording]) -> Option<String> {
    let mut found: Vec<Excursion> = Vec::new();
    for j in &robot.joints {
        if !j.limited || !matches!(j.jtype, JointType::Hinge | JointType::Slide) {
            continue;
        }
        let [lo, hi] = j.range;
        if !(lo.is_finite() && hi.is_finite() && hi > lo) {
            continue;
        }
        let slack = RANGE_SLACK * (hi - lo);
        let mut worst: Option<(f64, Excursion)> = None;
        let mut all_in_degrees = true;
        let (mut qmin, mut qmax) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut recorded = false;
        for r in recs {
            let Some(tr) = r.joints.iter().find(|t| t.name == j.name) else { continue };
            recorded = true;
            for (i, &q) in tr.q.iter().enumerate() {
                let d = q.to_radians();
                if d < lo - slack || d > hi + slack {
                    all_in_degrees = false;
                }
                qmin = qmin.min(q);
                qmax = qmax.max(q);
                let past = (lo - q).max(q - hi);
                if past > slack && worst.as_ref().is_none_or(|(w, _)| past > *w) {
                    let file = r.source.file_name().map_or_else(
                        || r.source.display().to_string(),
                        |n| n.to_string_lossy().into_owned(),
                    );
                    let t = r.t.get(i).copied().unwrap_or(f64::NAN);
                    worst = Some((
                        past,
                        Excursion {
                            joint: j.name.clone(),
                            file,
                            t,
                            value: q,
                            range: [lo, hi],
                            slide: j.jtype == JointType::Slide,
                            unit_fit: false,
                            span: 0.0,
                        },
                    ));
                }
            }
        }
        if let (true, Some((_, mut e))) = (recorded, worst) {
            e.span = qmax - qmin;
            e.unit_fit = all_in_degrees && !e.slide && qmax - qmin > hi - lo + slack;
            found.push(e);
        }
    }
    if found.is_empty() {
        return None;
    }
    let fmt = |v: f64| crate::util::fmt_num(v, 4);
    let items: Vec<String> = found
        .iter()
        .take(SHOWN)
        .map(|e| {
            let (unit, shown) = if e.slide {
                ("m", String::new())
            } else {
                ("rad", format!(" ({}°)", fmt(e.value * 180.0 / PI)))
            };
            let hint = if e.unit_fit {
                format!(
                    "; its recorded motion spans {} rad, more than the range's whole span (no \
                     offset brings it in), and scaled by π/180 every value lies within the \
                     range: a unit — positions in degrees (declare `# units: deg, deg/s`, or \
                     `--log-units deg`), or in an MJCF file a range written in radians under \
                     <compiler angle=\"degree\">, MJCF's default (add <compiler \
                     angle=\"radian\"/>)",
                    fmt(e.span)
                )
            } else {
                String::new()
            };
            format!(
                "{} in {} at t = {} s: {} {unit}{shown} against the range [{}, {}] {unit}{hint}",
                e.joint,
                e.file,
                fmt(e.t),
                fmt(e.value),
                fmt(e.range[0]),
                fmt(e.range[1])
            )
        })
        .collect();
    let more = if found.len() > SHOWN {
        format!("; and {} more joint(s)", found.len() - SHOWN)
    } else {
        String::new()
    };
    Some(format!(
        "recorded positions outside the model's joint range (by more than {}% of the range; the \
         worst sample of each joint): {}{more}. In the replay the model's limit acts against them \
         and the difference would come out as physics: a recording outside the range \
         means a wrong offset (the encoder's zero is not the model's), a wrong unit, or a model \
         of another robot",
        fmt(RANGE_SLACK * 100.0),
        items.join("; ")
    ))
}
