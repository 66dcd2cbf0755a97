//! `mirror-asymmetry`'s limits: the effort (force limit) and, in a URDF, the velocity of
//! mirror-paired joints. A URDF's `<limit effort velocity>` as written (MuJoCo makes a positive
//! effort the joint's `actuatorfrcrange` and ignores the velocity; training frameworks read
//! both); an MJCF joint's compiled `actuatorfrcrange`.

use crate::finding::{Finding, Subject};
use crate::model::Format;
use crate::model::mjcf::ElemKind;
use crate::model::source::Loc;
use crate::rules::Context;
use crate::util::fmt_num;

/// One side's limit: value and where it is written.
type Side = Option<(f64, Loc)>;

/// A joint's (effort, velocity) limits: a URDF's `<limit>` attributes; an MJCF joint's
/// `actuatorfrcrange` (its larger bound) and no velocity.
fn limits(cx: &Context, j: usize) -> (Side, Side) {
    let robot = cx.robot;
    let name = &robot.joints[j].name;
    if robot.format == Format::Urdf {
        let Some(x) = robot.tree.children_tagged("joint").find(|x| x.get("name") == Some(name))
        else {
            return (None, None);
        };
        let limit = x.children_tagged("limit").next();
        let get = |a: &str| {
            let at = limit?.attr(a)?;
            let v =
                crate::model::c_number(at.value.trim()).filter(|v| v.is_finite() && *v > 0.0)?;
            Some((v, at.loc))
        };
        return (get("effort"), get("velocity"));
    }
    let lim = robot.mj.jnt_actfrclimited();
    let rng = robot.mj.jnt_actfrcrange();
    let effort = (lim.get(j).copied().unwrap_or(false))
        .then(|| rng.get(j).map(|r| r[0].abs().max(r[1].abs())))
        .flatten()
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(|v| (v, robot.attr_loc(ElemKind::Joint, j, name, "actuatorfrcrange").0));
    (effort, None)
}

/// One finding per quantity (effort, velocity) for the mirror-paired joints `(left, right)`
/// whose limits differ by more than `tol` relative: the right joints' values against their
/// mirrors', at the first right joint's attribute.
pub(super) fn limits_differ(cx: &Context, pairs: &[(usize, usize)], tol: f64) -> Vec<Finding> {
    let robot = cx.robot;
    let mut out = Vec::new();
    let sides: Vec<((Side, Side), (Side, Side))> =
        pairs.iter().map(|&(l, r)| (limits(cx, l), limits(cx, r))).collect();
    for (k, what, unit) in [(0, "effort", "N·m"), (1, "velocity", "rad/s")] {
        let pick = |s: &(Side, Side)| if k == 0 { s.0 } else { s.1 };
        let mut hits: Vec<(usize, usize, f64, Loc, f64, Loc)> = Vec::new();
        for (&(l, r), (ls, rs)) in pairs.iter().zip(&sides) {
            let (Some((a, aloc)), Some((b, bloc))) = (pick(ls), pick(rs)) else { continue };
            if (a - b).abs() > tol * a.max(b) {
                hits.push((l, r, a, aloc, b, bloc));
            }
        }
        let Some(&(l0, r0, a0, aloc0, b0, bloc0)) = hits.first() else { continue };
        let n = hits.len();
        let list: Vec<String> = hits
            .iter()
            .map(|&(l, r, a, _, b, _)| {
                format!(
                    "`{}` {} against `{}` {}",
                    robot.joints[r].name,
                    fmt_num(b, 4),
                    robot.joints[l].name,
                    fmt_num(a, 4)
                )
            })
            .collect();
        let msg = format!(
            "{n} mirror joint pair{} state{} different {what} limits ({unit}): {}",
            if n == 1 { "" } else { "s" },
            if n == 1 { "s" } else { "" },
            list.join("; ")
        );
        let mut f = cx
            .finding(msg, bloc0)
            .element(format!("joint `{}`", robot.joints[r0].name), bloc0)
            .label(format!("{what} {} {unit}", fmt_num(b0, 4)))
            .secondary(
                aloc0,
                format!("mirror `{}` has {} {unit}", robot.joints[l0].name, fmt_num(a0, 4)),
            );
        for &(_, r, _, _, b, bloc) in hits.iter().skip(1).take(3) {
            f = f.secondary(
                bloc,
                format!("also `{}` {} {unit}", robot.joints[r].name, fmt_num(b, 4)),
            );
        }
        out.push(
            f.note(format!(
                "a joint and its mirror carry the same motor and reduction on mirror-symmetric hardware, so the same {what} limit; training frameworks read a URDF's effort and velocity as the joints' limits (MuJoCo makes the effort the joint's actuatorfrcrange), and a policy learns a stronger or faster side"
            ))
            .help(format!("write the motor's {what} at the joint on both sides (from the datasheet), or mirror the correct side's <limit>"))
            .subject(Subject::Joint(r0))
            .measured(b0, unit)
            .expected(a0, unit)
            .with("pairs", n as f64),
        );
    }
    out
}
