//! The inertia-tensor comparison of `mirror-asymmetry` (split from the rule's file): a mirror
//! pair's stated inertia tensors, both in the world frame at the reference pose, the right one
//! reflected through the pair's mirror plane. Sorted principal moments (compared in the rule's
//! file) cannot see two principal axes swapped on one side; the tensors can.

use crate::finding::{Finding, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::Context;
use crate::rules::inertia::isotropic_base_inertia::inertia_loc;
use crate::util::fmt_num;

use super::mirror_asymmetry::Pair;
use super::mirror_com::{Pose, mirror_plane, posed_mirrored};

type M3 = [[f64; 3]; 3];

/// Row-major 3×3 from MuJoCo's flat `xmat`/`ximat`.
fn mat(m: [f64; 9]) -> M3 {
    [[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]]
}

fn mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn tr(a: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[j][i]))
}

/// ‖a − b‖ (Frobenius).
fn frob_diff(a: &M3, b: &M3) -> f64 {
    (0..9).map(|k| (a[k / 3][k % 3] - b[k / 3][k % 3]).powi(2)).sum::<f64>().sqrt()
}

fn frob(a: &M3) -> f64 {
    frob_diff(a, &[[0.0; 3]; 3])
}

/// The reflection through a plane of unit normal `n`: 1 − 2·n·nᵀ.
fn reflection(n: [f64; 3]) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| f64::from(u8::from(i == j)) - 2.0 * n[i] * n[j]))
}

/// Body `b`'s inertia tensor about its centre of mass in the world frame at the pose:
/// X·diag(I)·Xᵀ, X the principal axes (`ximat`'s columns). With `moments` (sorted ascending),
/// those moments on `b`'s axes in their order instead of its own: the tensor that differs from
/// another body's with those moments by the axes alone.
fn world_tensor(cx: &Context, pose: &Pose, b: usize, moments: Option<[f64; 3]>) -> Option<M3> {
    let mut d = *cx.robot.mj.body_inertia().get(b)?;
    if let Some(sorted) = moments {
        let mut order = [0, 1, 2];
        order.sort_by(|&i, &j| d[i].total_cmp(&d[j]));
        for (rank, &k) in order.iter().enumerate() {
            d[k] = sorted[rank];
        }
    }
    let x = mat(*pose.ximat.get(b)?);
    let diag = [[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]];
    Some(mul(&mul(&x, &diag), &tr(&x)))
}

/// The principal axis (world, unit) of body `b`'s largest moment, with that moment.
fn major_axis(cx: &Context, pose: &Pose, b: usize) -> Option<([f64; 3], f64)> {
    let d = *cx.robot.mj.body_inertia().get(b)?;
    let x = *pose.ximat.get(b)?;
    let k = (0..3).max_by(|&i, &j| d[i].total_cmp(&d[j]))?;
    Some(([x[k], x[3 + k], x[6 + k]], d[k]))
}

/// The world axis a unit direction lies closest to: "x", "−z", or the vector itself.
fn axis_word(v: [f64; 3]) -> String {
    let k = (0..3).max_by(|&i, &j| v[i].abs().total_cmp(&v[j].abs())).unwrap_or(0);
    if v[k].abs() >= 15f64.to_radians().cos() {
        ["x", "y", "z"][k].to_string()
    } else {
        format!("({}, {}, {})", fmt_num(v[0], 3), fmt_num(v[1], 3), fmt_num(v[2], 3))
    }
}

/// A mirror pair whose stated inertia tensors are not mirror images while their masses,
/// principal moments and centres of mass agree (each reported on its own otherwise): at the
/// reference pose, the right body's tensor about its centre of mass, in the world frame and
/// reflected through the pair's mirror plane (M·I·M, M = 1 − 2·n·nᵀ), differs from the left's
/// by more than `tensor_tolerance` of the larger tensor's norm (relative Frobenius difference).
/// The right body's own principal moments are replaced by the left's (sorted, matched in order)
/// first: moment noise is `inertia_tolerance`'s to judge, this comparison judges the axes. Not
/// judged: a pair not posed as mirror images there (one part on joints whose zeros differ,
/// reported as that turn), and one part mounted turned on both sides — the same tensor and the
/// same centre of mass (within `place_tolerance`) in each body's own frame.
pub(super) fn tensor_differs(cx: &Context, p: &Pair, pose: &Option<Pose>) -> Option<Finding> {
    let robot = cx.robot;
    let pose = pose.as_ref()?;
    // Stated inertials only: a tensor MuJoCo computes from the geoms follows the collision
    // geometry, compared on its own.
    let loc = inertia_loc(robot, p.right.1)?;
    let lsrc = inertia_loc(robot, p.left.1)?;
    if !posed_mirrored(cx, p, pose) {
        return None;
    }
    let (n, _) = mirror_plane(robot, pose, p)?;
    let m = reflection(n);
    let (tl, tr_) =
        (world_tensor(cx, pose, p.left.0, None)?, world_tensor(cx, pose, p.right.0, None)?);
    // The left's moments on the right's axes: moment noise is `inertia_tolerance`'s to judge,
    // the axes this comparison's.
    let mut lm = *robot.mj.body_inertia().get(p.left.0)?;
    lm.sort_by(f64::total_cmp);
    let on_right_axes = world_tensor(cx, pose, p.right.0, Some(lm))?;
    let mirrored = mul(&mul(&m, &on_right_axes), &m);
    let scale = frob(&tl).max(frob(&tr_));
    if !(scale > 0.0) {
        return None;
    }
    let rel = frob_diff(&tl, &mirrored) / scale;
    let tol = cx.opt("tensor_tolerance");
    if !(rel > tol) {
        return None;
    }
    // One part mounted turned on both sides (a gripper's fingers): the same tensor and the same
    // centre of mass in each body's own frame. A centre of mass written mirrored says the part is
    // mirrored, and its tensor must be too.
    let (rl, rr) = (mat(*pose.xmat.get(p.left.0)?), mat(*pose.xmat.get(p.right.0)?));
    let local = |r: &M3, t: &M3| mul(&mul(&tr(r), t), r);
    let ipos = robot.mj.body_ipos();
    let (cl, cr) = (*ipos.get(p.left.0)?, *ipos.get(p.right.0)?);
    let com_apart = (0..3).map(|k| (cl[k] - cr[k]).powi(2)).sum::<f64>().sqrt();
    if com_apart <= cx.opt("place_tolerance")
        && frob_diff(&local(&rl, &tl), &local(&rr, &tr_)) <= tol * scale
    {
        return None;
    }
    let ((al, il), (ar, _)) = (major_axis(cx, pose, p.left.0)?, major_axis(cx, pose, p.right.0)?);
    let ar = [0, 1, 2].map(|i| (0..3).map(|k| m[i][k] * ar[k]).sum::<f64>());
    let cos = (0..3).map(|k| al[k] * ar[k]).sum::<f64>().abs().min(1.0);
    let deg = cos.acos().to_degrees();
    let pct = fmt_num(rel * 100.0, 3);
    let msg = format!(
        "body `{}`'s inertia tensor is not the mirror image of `{}`'s: with equal principal moments, their axes differ — reflected through the mirror plane, the tensors differ by {pct} %",
        p.right.1, p.left.1
    );
    let rloc = robot.elem_loc(ElemKind::Body, p.right.0, p.right.1);
    Some(
        cx.finding(msg, loc)
            .element(format!("body {}", p.right.1), rloc)
            .label(format!("tensor {pct} % from the mirror image"))
            .secondary(lsrc, format!("mirror `{}`", p.left.1))
            .note(format!(
                "at the reference pose (qpos0), in the world frame, `{}`'s tensor reflected through the pair's mirror plane differs from `{}`'s by {pct} % of its norm (Frobenius), beyond tensor_tolerance {} %; the largest moment, {} kg·m², lies about {} on `{}` and about {} on `{}` mirrored ({}° apart): two principal axes are swapped or turned on one side — the sorted moments agree, so the moments comparison cannot see it — and one side swings about each axis with the other side's inertia",
                p.right.1,
                p.left.1,
                fmt_num(tol * 100.0, 3),
                fmt_num(il, 4),
                axis_word(al),
                p.left.1,
                axis_word(ar),
                p.right.1,
                fmt_num(deg, 3)
            ))
            .help("write the mirror image of the other side's inertial: the same diagonal in the same order for frames aligned alike (products of inertia with the lateral axis negated), or take both from the CAD of each part")
            .subject(Subject::Body(p.right.0))
            .measured(rel, "ratio")
            .expected(tol, "ratio")
            .with("tensor_mismatch", rel),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reflection_keeps_a_diagonal_and_negates_lateral_products() {
        let m = reflection([0.0, 1.0, 0.0]);
        let t = [[1.0, 0.2, 0.1], [0.2, 2.0, 0.3], [0.1, 0.3, 3.0]];
        let r = mul(&mul(&m, &t), &m);
        assert_eq!(r, [[1.0, -0.2, 0.1], [-0.2, 2.0, -0.3], [0.1, -0.3, 3.0]]);
        // Swapping two diagonal entries is no reflection of the tensor.
        let s = [[3.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]];
        let d = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]];
        let rel = frob_diff(&d, &mul(&mul(&m, &s), &m)) / frob(&d);
        assert!((rel - (8.0f64).sqrt() / (14.0f64).sqrt()).abs() < 1e-12);
    }
}
