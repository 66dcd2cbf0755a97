//! Where `mirror-asymmetry` compares the places of a mirror pair's collision geoms, reflected
//! across the pair's mirror plane at the reference pose (the centres of mass: `mirror_com`).

use crate::finding::{Finding, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::Context;
use crate::util::fmt_num;

use super::mirror_asymmetry::{Pair, SIZE_NOISE, colliders};
use super::mirror_com::{Pose, mirror_plane, v_norm as norm, v_reflect, v_sub as sub, v_turn};

/// A mirror pair whose collision geoms match one to one in type and size but not in place: at
/// the reference pose, a right geom's offset from its body's origin, reflected across the
/// pair's mirror plane, lies farther than `place_tolerance` (or `geom_tolerance` of the geom's
/// bounding radius) from the offset of every left geom of its type and size — and the same
/// holds with the offset carried into the left body's frame unreflected (one part mounted
/// turned on both sides, or frames whose convention differs: a body frame turned 180° about
/// its axis with the geom placed accordingly, fits one of the two). Offsets from each body's
/// own origin, so a pair whose origins are themselves misplaced is judged on its geoms alone.
pub(super) fn geoms_misplaced(cx: &Context, p: &Pair, pose: &Option<Pose>) -> Option<Finding> {
    let robot = cx.robot;
    let pose = pose.as_ref()?;
    let (n, _) = mirror_plane(robot, pose, p)?;
    let gtol = cx.opt("geom_tolerance");
    let ptol = cx.opt("place_tolerance");
    let (l, r) = (p.left.0, p.right.0);
    let (ol, or) = (*pose.xpos.get(l)?, *pose.xpos.get(r)?);
    let (ml, mr) = (*pose.xmat.get(l)?, *pose.xmat.get(r)?);
    let (gl, gr) = (colliders(robot, l), colliders(robot, r));
    if gl.is_empty() {
        return None;
    }
    let offset = |g: usize, o: [f64; 3]| pose.geom_xpos.get(g).map(|x| sub(*x, o));
    let reflect = |v: [f64; 3]| v_reflect(v, n);
    // A right offset in the world → the left body's frame, the same local coordinates.
    let turn = |v: [f64; 3]| v_turn(v, &ml, &mr);
    let close = |x: f64, y: f64| (x - y).abs() <= SIZE_NOISE.max(gtol * x.abs().max(y.abs()));
    let partners = |g: usize| -> Vec<usize> {
        let a = &robot.geoms[g];
        gl.iter()
            .copied()
            .filter(|&h| {
                let b = &robot.geoms[h];
                b.gtype == a.gtype && (0..3).all(|k| close(a.size[k], b.size[k]))
            })
            .collect()
    };
    // For each right geom: its tolerance, and its distance to the nearest partner under `map`.
    let miss = |map: &dyn Fn([f64; 3]) -> [f64; 3], g: usize| -> Option<(f64, usize)> {
        let v = map(offset(g, or)?);
        partners(g)
            .into_iter()
            .filter_map(|h| Some((norm(sub(v, offset(h, ol)?)), h)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    };
    let allowed = |g: usize| ptol.max(gtol * robot.geoms[g].rbound.max(0.0));
    let fits = |map: &dyn Fn([f64; 3]) -> [f64; 3]| {
        gr.iter().all(|&g| miss(map, g).is_some_and(|(d, _)| d <= allowed(g)))
    };
    if fits(&reflect) || fits(&turn) {
        return None;
    }
    // The right geom farthest from its mirror place, and the partner nearest it.
    let (g, d, h) = gr
        .iter()
        .filter_map(|&g| miss(&reflect, g).map(|(d, h)| (g, d, h)))
        .filter(|&(g, d, _)| d > allowed(g))
        .max_by(|a, b| (a.1 - allowed(a.0)).total_cmp(&(b.1 - allowed(b.0))))?;
    let mm = |x: f64| fmt_num(1000.0 * x, 3);
    let gname = |id: usize| {
        let name = &robot.geoms[id].name;
        if name.is_empty() { format!("#{id}") } else { format!("`{name}`") }
    };
    let msg = format!(
        "body `{}`'s collision geom {} is not at the mirror image of `{}`'s {}: reflected across the mirror plane of its limb, it lies {} mm from it",
        p.right.1,
        gname(g),
        p.left.1,
        gname(h),
        mm(d)
    );
    let hloc = robot.elem_loc(ElemKind::Geom, h, &robot.geoms[h].name);
    Some(
        cx.at_elem(ElemKind::Geom, g, &robot.geoms[g].name, msg)
            .label(format!("{} mm off the mirror place", mm(d)))
            .secondary(hloc, format!("mirror `{}`'s geom", p.left.1))
            .note(format!(
                "the two bodies' collision geoms match in type and size, but at the reference pose (qpos0) this one's place relative to its body, mirrored, lies {} mm from its partner's, beyond {} mm (place_tolerance, or geom_tolerance of its size); as the same part turned into the other body's frame it does not fit either: one side's shape was moved or mistyped, so that foot or limb touches the ground or the body {} mm away from where the other side's does",
                mm(d),
                mm(allowed(g)),
                mm(d)
            ))
            .help("place the geom at the mirror image of its partner's place (in a URDF the `xyz` of its collision `<origin>`, in MJCF its `pos`), or where the body's visual is")
            .subject(Subject::Geom(g))
            .measured(d, "m")
            .expected(allowed(g), "m")
            .with("place_mismatch", d),
    )
}
