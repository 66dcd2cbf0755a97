//! The joint-axis comparison of `mirror-asymmetry`: a mirror pair of hinge or slide joints
//! whose axes, at the reference pose, are not mirror images of each other.

use crate::finding::{Finding, Subject};
use crate::model::JointType;
use crate::model::mjcf::ElemKind;
use crate::rules::Context;
use crate::util::fmt_num;

use super::mirror_asymmetry::Pair;
use super::mirror_com::{Pose, limb_roots, mirror_plane, v_dot, v_norm};

/// The angle (degrees) within which the line between a pair's limb roots is taken for an axis
/// of the body both limbs hang from: CAD places the two roots mirror images in that body's
/// frame, a root a few millimetres off over the hips' width (Stompy Pro's 5 mm over 0.31 m)
/// tilts the line by a degree, which would tilt every reflected axis by twice that.
const FRAME_SNAP_DEG: f64 = 5.0;

/// The mirror plane's normal for axes: the axis of the common parent of the pair's limb roots
/// nearest the plane's normal `n`, when within [`FRAME_SNAP_DEG`]; `n` when the roots hang
/// from different bodies; `None` when the line between the roots lies farther than that from
/// every axis of their parent (the limbs are not placed as mirror images: a detached or
/// misplaced limb, which other rules judge).
fn snapped(cx: &Context, pose: &Pose, l: usize, r: usize, n: [f64; 3]) -> Option<[f64; 3]> {
    let robot = cx.robot;
    let (ra, rb) = limb_roots(robot, l, r);
    let parent = |b: usize| robot.bodies.get(b).map(|x| x.parent);
    let Some(common) = parent(ra).filter(|p| Some(*p) == parent(rb)) else { return Some(n) };
    let x = pose.xmat.get(common)?;
    let axes = [0, 1, 2].map(|k| [x[k], x[3 + k], x[6 + k]]);
    let best =
        axes.iter().copied().max_by(|a, b| v_dot(*a, n).abs().total_cmp(&v_dot(*b, n).abs()));
    best.filter(|a| v_dot(*a, n).abs() >= FRAME_SNAP_DEG.to_radians().cos())
}

/// The angle (degrees) between joint `l`'s axis and joint `r`'s reflected across the pair's
/// mirror plane (the plane of the joints' bodies, halfway between their limb roots, turned onto
/// the nearest coordinate plane of the body the limbs hang from when within
/// [`FRAME_SNAP_DEG`]), at the
/// reference pose; an axis and its opposite are the same line (the sign of an axis is a
/// convention: a mirrored hinge often turns the other way). `None` when the pair is not two
/// hinges or two slides on two bodies, or no plane or axis is defined.
pub(super) fn axis_angle(cx: &Context, pose: &Pose, l: usize, r: usize) -> Option<f64> {
    let deg = axis_cos(cx, pose, l, r)?.abs().min(1.0).acos().to_degrees();
    deg.is_finite().then_some(deg)
}

/// The cosine between joint `l`'s axis and joint `r`'s reflected across the pair's mirror
/// plane (as [`axis_angle`], with its sign): near 1 when the right axis is the mirror image of
/// the left one — then a mirrored motion turns the right joint by the opposite angle
/// (reflection R: R·Rot(a, θ)·R = Rot(R·a, −θ)), so its range must be the mirrored `[−b, −a]`
/// —, near −1 when it is the opposite of that image — the same angle, the same range.
pub(super) fn axis_cos(cx: &Context, pose: &Pose, l: usize, r: usize) -> Option<f64> {
    let robot = cx.robot;
    let (a, b) = (robot.joints.get(l)?, robot.joints.get(r)?);
    let scalar = |t: JointType| matches!(t, JointType::Hinge | JointType::Slide);
    if a.jtype != b.jtype || !scalar(a.jtype) || a.body == b.body {
        return None;
    }
    let bodies = Pair { kind: ElemKind::Body, left: (a.body, ""), right: (b.body, "") };
    let (n, _) = mirror_plane(robot, pose, &bodies)?;
    let n = snapped(cx, pose, a.body, b.body, n)?;
    let (ua, ub) = (*pose.xaxis.get(l)?, *pose.xaxis.get(r)?);
    let (na, nb) = (v_norm(ua), v_norm(ub));
    if !(na > 0.0 && nb > 0.0) {
        return None;
    }
    let h = v_dot(ub, n);
    let reflected = [0, 1, 2].map(|k| ub[k] - 2.0 * h * n[k]);
    let cos = v_dot(ua, reflected) / (na * nb);
    cos.is_finite().then_some(cos)
}

/// A finding on the right joint of pair `p` whose axis lies `deg` degrees off its mirror's
/// (beyond `tol_deg`).
pub(super) fn axis_finding(cx: &Context, p: &Pair, pose: &Pose, deg: f64, tol_deg: f64) -> Finding {
    let robot = cx.robot;
    let world = |j: usize| {
        pose.xaxis.get(j).map_or("?".to_string(), |u| {
            format!("({}, {}, {})", fmt_num(u[0], 4), fmt_num(u[1], 4), fmt_num(u[2], 4))
        })
    };
    let msg = format!(
        "joint `{}`'s axis {} (world, at qpos0) is {}° off the mirror image of `{}`'s {}",
        p.right.1,
        world(p.right.0),
        fmt_num(deg, 3),
        p.left.1,
        world(p.left.0)
    );
    let (lattr, _) = robot.attr_loc(ElemKind::Joint, p.left.0, p.left.1, "axis");
    cx.at_attr(ElemKind::Joint, p.right.0, p.right.1, "axis", msg)
        .label(format!("axis {}° off the mirror's", fmt_num(deg, 3)))
        .secondary(lattr, format!("mirror `{}`", p.left.1))
        .note(format!(
            "the axes of a mirrored pair of joints are mirror images across the plane halfway between the limbs' roots (an axis and its opposite are one line); this one is tilted beyond axis_tolerance {}°, the few-degree tilt of a hand-edited or rounded axis or of a frame written off by a few degrees: the joint swings its limb out of the plane its mirror swings in",
            fmt_num(tol_deg, 3)
        ))
        .help("write the mirror image of the other side's axis (and body frame), from the CAD")
        .subject(Subject::Joint(p.right.0))
        .measured(deg, "deg")
        .expected(0.0, "deg")
}
