//! `soft-limits`' URDF case: a joint's `<safety_controller>` soft limits outside its hard
//! `<limit>` range. The URDF specification has the controller start limiting the joint at
//! `soft_lower_limit` and `soft_upper_limit`, which must lie inside `lower`..`upper`; a soft
//! limit beyond the hard one is never reached (the KUKA LWR's ±2.0595 rad around a ±1.5708 rad
//! range "reduced … to avoid contact with table").

use crate::finding::{Finding, Subject};
use crate::model::Format;
use crate::model::source::XNode;
use crate::rules::Context;
use crate::util::fmt_num;

fn num(n: &XNode, a: &str) -> Option<f64> {
    n.get(a).and_then(|v| v.trim().parse::<f64>().ok()).filter(|x| x.is_finite())
}

/// Revolute and prismatic URDF joints whose written `soft_lower_limit` lies below `lower` or
/// whose `soft_upper_limit` lies above `upper` by more than `tol` × the range. Only the soft
/// limits the file writes are judged (an omitted one defaults to 0 in the specification).
pub(super) fn urdf_soft_limits(cx: &Context, tol: f64, out: &mut Vec<Finding>) {
    let robot = cx.robot;
    if robot.format != Format::Urdf {
        return;
    }
    for j in robot.tree.children_tagged("joint") {
        let kind = j.get("type").map(str::trim).unwrap_or("");
        if kind != "revolute" && kind != "prismatic" {
            continue;
        }
        let (Some(limit), Some(safety)) =
            (j.children_tagged("limit").next(), j.children_tagged("safety_controller").next())
        else {
            continue;
        };
        let (lo, hi) = (num(limit, "lower").unwrap_or(0.0), num(limit, "upper").unwrap_or(0.0));
        let span = hi - lo;
        if !(span > 0.0) {
            continue;
        }
        let slack = tol * span;
        let below = num(safety, "soft_lower_limit").filter(|s| *s < lo - slack);
        let above = num(safety, "soft_upper_limit").filter(|s| *s > hi + slack);
        if below.is_none() && above.is_none() {
            continue;
        }
        let name = j.get("name").unwrap_or("");
        let unit = if kind == "prismatic" { "m" } else { "rad" };
        let mut ends = Vec::new();
        if let Some(s) = below {
            ends.push(format!("soft_lower_limit {} below lower {}", fmt_num(s, 5), fmt_num(lo, 5)));
        }
        if let Some(s) = above {
            ends.push(format!("soft_upper_limit {} above upper {}", fmt_num(s, 5), fmt_num(hi, 5)));
        }
        let msg = format!(
            "joint `{name}`'s <safety_controller> soft limits lie outside its hard <limit> ({} {unit}): the hard stop comes first, so the soft limit cannot act — one of the two ranges is not the joint's",
            ends.join(", ")
        );
        let attr = if below.is_some() { "soft_lower_limit" } else { "soft_upper_limit" };
        let at = safety.attr(attr).map_or(safety.loc, |a| a.loc);
        let mut f = cx
            .finding(msg, at)
            .element(format!("joint `{name}`"), j.loc)
            .label("outside the hard range")
            .secondary(limit.loc, format!("hard range [{}, {}] {unit}", fmt_num(lo, 5), fmt_num(hi, 5)))
            .note("the URDF specification's safety controller starts limiting the joint at its soft limits, which must lie inside the <limit> range (soft_lower_limit > lower, soft_upper_limit < upper); a soft limit beyond the hard one is never reached. MuJoCo's importer reads neither, but the hardware's controller does, and a hard range narrowed inside its own soft limits (a workspace cut written as the joint's) is not the joint's range")
            .help("state the joint's mechanical range in <limit> and put the soft limits inside it, or narrow the soft limits to the reduced range")
            .fact()
            .measured(below.or(above).unwrap_or(f64::NAN), unit)
            .expected(if below.is_some() { lo } else { hi }, unit);
        if let Some(jid) = robot.joints.iter().find(|x| x.name == name).map(|x| x.id) {
            f = f.subject(Subject::Joint(jid));
        }
        out.push(f);
    }
}
