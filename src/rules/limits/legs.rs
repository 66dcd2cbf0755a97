//! The legs of a robot as `placeholder-joint-limits` judges them: each foot's chain of hinges
//! up to the body the legs leave (wheels left out), and which of them sit below the hip.

use crate::model::{Format, JointType, Robot};
use crate::rules::{Context, in_subtree};

/// The hinges of the robot's legs: the joints on the chain from each foot (a URDF leg's lowest
/// link, `welded_legged_base::urdf_legs`; in an MJCF with a floating base, the foot rules'
/// feet) up to, not including, the first body that carries another foot too (the trunk, or a
/// waist's pelvis), and that do not turn a wheel.
pub(super) fn leg_hinges(cx: &Context) -> Vec<usize> {
    let mut v: Vec<usize> = leg_chains(cx).into_iter().flat_map(|c| c.1).collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// Each leg as (its foot or lowest link, its hinges from the body down: the joints of
/// [`leg_hinges`] on that foot's chain, in body order).
pub(crate) fn leg_chains(cx: &Context) -> Vec<(usize, Vec<usize>)> {
    let robot = cx.robot;
    let leaves: Vec<usize> = if robot.format == Format::Urdf {
        crate::rules::contact::welded_legged_base::urdf_legs(robot).unwrap_or_default()
    } else if crate::rules::contact::feet::floating_bases(robot).is_empty() {
        Vec::new()
    } else {
        crate::rules::contact::feet::feet(robot, cx.spec).iter().map(|f| f.root).collect()
    };
    if leaves.len() < 2 {
        return Vec::new();
    }
    let mut legs = Vec::new();
    for &leaf in &leaves {
        let mut chain: Vec<usize> = Vec::new();
        let mut b = leaf;
        for _ in 0..robot.bodies.len() {
            let carries_other = leaves.iter().any(|&o| o != leaf && in_subtree(robot, b, o));
            if b == 0 || carries_other {
                break;
            }
            chain.push(b);
            b = robot.bodies[b].parent;
        }
        let hinges: Vec<usize> = robot
            .joints
            .iter()
            .filter(|j| j.jtype == JointType::Hinge && chain.contains(&j.body))
            .filter(|j| !wheel(robot, j.id))
            .map(|j| j.id)
            .collect();
        legs.push((leaf, hinges));
    }
    legs
}

/// Whether hinge `j` turns a wheel, limited or not: shaped as one ([`Robot::turns_a_wheel`])
/// and every colliding geom of its body centred on the axis (within 10 % of the geom's
/// bounding radius, the wheel test's tolerance), so the body turns about itself. A shank with
/// a round knee housing concentric with the knee and a foot at its end swings the foot out on
/// a lever: a leg joint.
fn wheel(robot: &Robot, j: usize) -> bool {
    let (Some(joint), Some(a), Some(u)) =
        (robot.joints.get(j), robot.key.joint_xanchor.get(j), robot.key.joint_xaxis.get(j))
    else {
        return false;
    };
    robot.turns_a_wheel(j)
        && robot
            .geoms
            .iter()
            .filter(|g| g.body == joint.body && crate::model::contact::takes_part(robot, g.id))
            .all(|g| {
                let Some(p) = robot.key.geom_xpos.get(g.id) else { return false };
                let d = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
                let along = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
                let off = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - along * along).max(0.0).sqrt();
                off <= 0.1 * g.rbound.max(0.0)
            })
}

/// The leg hinges at and below the knee: on each leg's chain of hinges (top to bottom), the
/// segments between consecutive anchors (at the keyframe; rigid links, so any pose gives the
/// same lengths) and from the last anchor to the farthest of the foot's origin and geom
/// centres; the two longest are the thigh and the shank, and the hinge that ends the upper of
/// them is the knee. The hip's hinges, above the thigh, are not returned (Go2's thigh joint
/// sits a 96 mm hip offset below its abduction joint, above a 213 mm thigh).
pub(super) fn knee_and_below(cx: &Context) -> Vec<usize> {
    let robot = cx.robot;
    let (anchor, bpos, gpos) =
        (&robot.key.joint_xanchor, &robot.key.body_xpos, &robot.key.geom_xpos);
    let dist = |a: &[f64; 3], b: &[f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let mut out = Vec::new();
    for (leaf, mut hinges) in leg_chains(cx) {
        hinges.sort_by_key(|&j| (robot.joints[j].body, j));
        let pts: Vec<[f64; 3]> = hinges.iter().filter_map(|&j| anchor.get(j).copied()).collect();
        let (Some(last), true) = (pts.last(), pts.len() == hinges.len() && hinges.len() >= 2)
        else {
            continue;
        };
        let mut foot = bpos.get(leaf).map_or(0.0, |p| dist(last, p));
        for g in robot.geoms.iter().filter(|g| g.body == leaf) {
            if let Some(p) = gpos.get(g.id) {
                foot = foot.max(dist(last, p));
            }
        }
        let mut segs: Vec<(usize, f64)> =
            pts.windows(2).enumerate().map(|(i, w)| (i, dist(&w[0], &w[1]))).collect();
        segs.push((pts.len() - 1, foot));
        segs.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let upper = segs[0].0.min(segs[1].0);
        out.extend(hinges.iter().skip(upper + 1).copied());
    }
    out
}

/// Whether hinge `j` is a fixed-base arm's flange roll: the robot has no floating base and no
/// hinge or slide turns below it (it ends its chain: nothing it carries can swing through
/// another link), and it is no leg's joint.
pub(super) fn flange_roll(robot: &Robot, legs: &[usize], j: usize) -> bool {
    let Some(joint) = robot.joints.get(j) else { return false };
    if legs.contains(&j) || !robot.floating_bodies().is_empty() {
        return false;
    }
    let below = |mut b: usize| loop {
        if b == joint.body {
            return true;
        }
        if b == 0 {
            return false;
        }
        b = robot.bodies[b].parent;
    };
    !robot.joints.iter().any(|k| {
        k.id != j
            && matches!(k.jtype, JointType::Hinge | JointType::Slide)
            && (below(k.body) && (k.body != joint.body || k.id > j))
    })
}
