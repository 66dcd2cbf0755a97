//! `armature-mismatch`'s bound that needs no force limits and no spec: a joint's armature
//! against the inertia the joint moves. A drive's reflected inertia is gear² × its rotor's; the
//! largest share of a joint's inertia it reaches on a real robot is a high-ratio servo turning
//! the lightest part it can carry. Armature beyond `max_link_ratio` × the joint's own inertia
//! is no drive: a value kept from a template (the gym Ant's `armature="1"` on a hexapod whose
//! leg links weigh grams) that, not the robot, sets how every joint moves.

use std::collections::BTreeMap;

use crate::finding::{Finding, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::Context;
use crate::util::fmt_num;

/// (joint, armature, the inertia the joint moves without it)
type Judged = (usize, f64, f64);

/// Actuated hinges and slides whose compiled armature exceeds `max_ratio` × the inertia the
/// joint moves: the joint-space inertia's diagonal at the standing keyframe or qpos0 (MuJoCo's
/// composite inertia of the joint's subtree about its axis; its mass along a slide) less the
/// armature itself. Joints that share one armature attribute (a `<default class>`) are
/// reported together. Joints whose motor the spec names are `armature-mismatch`'s spec case.
pub(super) fn armature_over_link(cx: &Context, max_ratio: f64, out: &mut Vec<Finding>) {
    let robot = cx.robot;
    let mut groups: BTreeMap<(usize, usize, usize), Vec<Judged>> = BTreeMap::new();
    let mut judged = 0usize;
    for j in robot.joints.iter().filter(|j| j.is_scalar()) {
        if robot.actuators_on_joint(j.id).is_empty()
            || cx.facts(&j.name).is_some_and(|f| f.motor.is_some())
        {
            continue;
        }
        let a = j.armature;
        let Some(&diag) = robot.key.m_diag.get(j.dofadr) else { continue };
        let seen = diag - a;
        if !(a > 0.0) || !(seen > 0.0) {
            continue;
        }
        judged += 1;
        if a <= max_ratio * seen {
            continue;
        }
        let (loc, class) = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "armature");
        let key =
            if class.is_some() { (loc.file, loc.start, loc.end) } else { (usize::MAX, j.id, 0) };
        groups.entry(key).or_default().push((j.id, a, seen));
    }
    for (_, js) in groups {
        out.push(report(cx, &js, judged, max_ratio));
    }
}

fn report(cx: &Context, js: &[Judged], judged: usize, max_ratio: f64) -> Finding {
    let robot = cx.robot;
    let (j0, a0, _) = js[0];
    let first = &robot.joints[j0];
    let slide = first.jtype == crate::model::JointType::Slide;
    let unit = if slide { "kg" } else { "kg·m²" };
    let ratio = |x: &Judged| x.1 / x.2;
    let lo = js.iter().map(ratio).fold(f64::INFINITY, f64::min);
    let hi = js.iter().map(ratio).fold(0.0, f64::max);
    let sci = |x: f64| if (1e-3..1e4).contains(&x) { fmt_num(x, 3) } else { format!("{x:.2e}") };
    let n = js.len();
    let who = if n == 1 {
        format!("joint `{}`", first.name)
    } else {
        let names: Vec<&str> = js.iter().take(6).map(|x| robot.joints[x.0].name.as_str()).collect();
        let more = if n > 6 { format!(", … ({n} joints)") } else { String::new() };
        format!("{n} joints ({}{more})", names.join(", "))
    };
    let seen_lo = js.iter().map(|x| x.2).fold(f64::INFINITY, f64::min);
    let seen_hi = js.iter().map(|x| x.2).fold(0.0, f64::max);
    let range =
        if n == 1 { format!("{}×", sci(lo)) } else { format!("{}–{}×", sci(lo), sci(hi)) };
    let msg = format!(
        "armature {} {unit} on {who} is {range} the inertia {} moves ({}{} {unit}: the subtree about the axis, armature left out), beyond the {}× a real drive reaches: the armature, not the robot, sets how {} accelerate{}",
        fmt_num(a0, 4),
        if n == 1 { "the joint" } else { "each joint" },
        sci(seen_lo),
        if n == 1 { String::new() } else { format!("–{}", sci(seen_hi)) },
        sci(max_ratio),
        if n == 1 { "it" } else { "they" },
        if n == 1 { "s" } else { "" },
    );
    let mut f = crate::rules::inertia::at_armature(cx, first, msg)
        .label(format!("armature {} {unit}", fmt_num(a0, 4)));
    for x in js.iter().skip(1).take(3) {
        let j = &robot.joints[x.0];
        f = f.secondary(
            robot.elem_loc(ElemKind::Joint, j.id, &j.name),
            format!("{}× its {} {unit}", sci(ratio(x)), sci(x.2)),
        );
    }
    f.note(format!(
        "armature is the drive's rotor inertia reflected through its gear, gear² × rotor; a servo of gear 288 (Dynamixel XC/XL330-M288) reflects about 1.3e-3 kg·m², which on the lightest part such a servo turns (its horn and a bracket, ~3 g at 15 mm: 7e-7 kg·m²) is ~2e3× — max_link_ratio {}× is beyond any drive; {} of the model's {judged} actuated joints judged exceed it",
        sci(max_ratio),
        n
    ))
    .help("set the armature to the drive's reflected rotor inertia (rotor_inertia × gear²; a few 1e-3 kg·m² for a hobby servo, 0.01–0.1 kg·m² for a legged robot's geared motor), or 0 where nothing is known")
    .subject(Subject::Joint(first.id))
    .measured(a0, unit)
    .expected(max_ratio * js[0].2, unit)
    .with("joints", n as f64)
    .with("ratio_min", lo)
    .with("ratio_max", hi)
}
