use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mirror::{Side, mirror_in};
use crate::model::mjcf::ElemKind;
use crate::model::source::Loc;
use crate::model::{ActuatorKind, Robot};
use crate::rules::inertia::isotropic_base_inertia::inertia_loc;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

use super::mirror_axes::{axis_angle, axis_cos, axis_finding};
use super::mirror_com::{com_differs, reference_pose};
use super::mirror_filter::filtering_differs;
use super::mirror_hub::hub_com_off;
use super::mirror_limits::limits_differ;
use super::mirror_places::geoms_misplaced;
use super::mirror_sites::sites_differ;
use super::mirror_tensor::tensor_differs;

/// Size difference tolerated between mirrored collision geoms whatever their size, m: the
/// 0.1–0.2 mm export noise of mesh-derived sizes, with a margin.
pub(super) const SIZE_NOISE: f64 = 0.0005;

declare_rule! {
    /// ## What it does
    /// Pairs left and right joints, actuators and bodies by swapping the side markers in their
    /// names (the spec's `robot.left`/`robot.right` first, then `left_`/`right_`, `Left_`/`Right_`,
    /// `l_`/`r_` prefixes and `_l`/`_r` suffixes, and `Left`/`Right` anywhere; a side letter
    /// alone between underscores, `J_hip_l_roll` ↔ `J_hip_r_roll`, or beside a part number, `5R_Link` ↔
    /// `5L_Link` (a letter inside a word, `3BRU_Link`'s, is no side), when the partner exists; bodies whose
    /// names carry no side marker pair through the mirror-paired joints that move them:
    /// `dof_left_elbow` moves `KC_C_401A`, `dof_right_elbow` moves `KC_C_402A`) and reports
    /// differences: joint armature, damping, stiffness and frictionloss, the joints' force
    /// limits (an MJCF joint's `actuatorfrcrange`; a URDF `<limit>`'s `effort`, and its
    /// `velocity`, which MuJoCo ignores and training frameworks read: Alex's right arm at 1000
    /// N·m and 100 rad/s against the left's 80–150 N·m and 9–11.5 rad/s), reported together,
    /// one finding per quantity, joint range (accepted
    /// when equal or mirrored, `[a, b]` ↔ `[−b, −a]`, as for roll and yaw joints; when the two
    /// axes are mirror lines within `axis_tolerance`, their sense decides which of the two: a
    /// right hinge axis that is the left one's mirror image turns a mirrored motion the
    /// opposite way and needs the mirrored range, its opposite needs the equal one — a hip roll
    /// range `[−0.17, 0.44]` copied onto both sides about the same `+x` axis is reported; a
    /// reflection keeps a translation's sign, so for slides the other way round), actuator
    /// kp/kv and gear, actuator force and control ranges (equal or mirrored), centres of mass
    /// that the file states (at the reference pose qpos0 the right one, reflected across the
    /// plane halfway between the pair's limb roots — walking up both bodies' parents while they
    /// differ, the last two distinct ancestors, so a pair whose own origins are not mirror
    /// images, a bracket mounted turned 180°, is judged against the plane of the hips or
    /// shoulders it hangs from; a gripper's fingers, on one body, against their own —, lies
    /// farther than `com_tolerance` and
    /// `com_fraction` of their offsets from the origins from the left one; not reported when it
    /// fits one part turned into the other's frame — a gripper mounted turned 180° — unless the
    /// geoms say the part is mirrored: one side's mesh scaled negatively, or the geoms at
    /// mirrored places and not at turned ones; a pair on hinges whose anchors are mirror images,
    /// whose centre of mass and carried bodies' origins — at least two such points — each lie at
    /// the same distance from its own hinge axis and place along it as their mirrors' and are all
    /// turned about it by one angle (within `pose_tolerance`) beyond `pose_tolerance`, is the
    /// same part on joints whose zeros differ: reported as that turn — "turned 159° about joint
    /// `right_knee_pitch`" — not as a centre of mass, and the bodies below it, which only follow
    /// the turn, are not reported), the centre of mass of a body on the mirror plane (a body
    /// with no side marker, in no pair, that carries mirror pairs — both limb roots of each
    /// hang from it: a trunk, a pelvis — must lie on the plane they mirror across, the widest
    /// pair's, within `com_tolerance` or `plane_com_fraction` of the half spacing of that pair's
    /// roots; every pair it carries must mirror across that plane, normals within 5° and
    /// midpoints within `com_tolerance`, else it is not judged; the centre of mass its own
    /// `<inertial>` states, so a URDF payload written as its own fixed link, which MuJoCo fuses
    /// into it, is not counted; a trunk whose centre of mass sits forward or low lies on the plane
    /// and passes: Darwin-OP's trunk 38.7 mm right of the centre line is reported), body masses, body
    /// principal moments of inertia (sorted, so independent of the frames the two sides'
    /// inertials are written in; compared with `inertia_tolerance`, for bodies whose masses
    /// agree and whose `<inertial>` the file states — moments MuJoCo computes from the geoms
    /// follow the collision geometry, compared on its own; when the masses differ too, the
    /// moments are in the mass finding's note, so every differing quantity of a pair is
    /// reported whatever the tolerances), the stated inertia tensors when masses, moments and
    /// centres of mass agree (sorted moments cannot see two principal axes swapped on one side,
    /// DEEP Robotics Lite3's `FR_HIP` diagonal written `Izz Iyy Ixx` against its mirror's
    /// `Ixx Iyy Izz`: at the reference pose, in the world frame, the right tensor with the left's
    /// moments on its own axes, reflected through the pair's mirror plane, M·I·M, must lie within
    /// `tensor_tolerance` of the left's, relative Frobenius difference — products of inertia
    /// copied without negating the lateral ones are reported too; one part mounted turned on
    /// both sides, the same tensor and centre of mass in each body's own frame, passes), and
    /// the types, sizes and places of
    /// each body pair's collision geoms (which covers the feet): when they match in type and
    /// size, each right geom's place on its body (its centre's offset from the body's origin at
    /// qpos0), reflected across the pair's mirror plane, must lie within `place_tolerance` (or
    /// `geom_tolerance` of the geom's bounding radius) of a partner's — or, for one part
    /// mounted turned on both sides, within it with the same local coordinates in the other
    /// body's frame. Body frames whose convention differs between the sides (a foot frame turned
    /// 180° about its axis, the geom placed accordingly) are mirror images in the world and
    /// pass; a sole box moved 13 mm on one side is reported. The sites a sensor reads (its
    /// object or its reference frame: a force-torque, touch or IMU site) pair by their names'
    /// side markers (or, unmarked, as the one sensed site on each body of a pair) and are
    /// judged the same way: one type and size, the place on the body within `place_tolerance`
    /// (or `geom_tolerance` of its bounding radius) and the axes its shape shows (a capsule's or
    /// cylinder's long axis, a box's or ellipsoid's axes of distinct half-sizes) within
    /// `axis_tolerance`, as mirror images or as one part turned into the other body's frame — a
    /// knee force-torque site 20 mm higher on one side, a touch capsule across the forearm
    /// against its mirror's along it. Sites no sensor reads (markers, drawn frames) measure
    /// nothing and are not compared, nor two sites on one body (no limb roots to mirror across).
    /// The collision filtering too: what each body of a pair can touch as MuJoCo filters contacts
    /// (`contype`/`conaffinity` masks, `<exclude>`, explicit `<contact><pair>`s, welded and parent
    /// bodies), the other bodies taken through their mirrors (a body on no side — the torso, the
    /// world, scenery — through itself; a side's part the names do not pair is left out, and so
    /// is a body pair the tree's structure keeps apart, one weld body or a parent's, since two
    /// sides' trees may differ by a bracket), must
    /// be what its mirror can touch: the first pair that differs is reported, naming both bodies,
    /// what only one of them touches and their masks, with how many other pairs differ (a right
    /// leg at `conaffinity` 3 touches the hip and its own parts, the left at 4 only the floor).
    /// Quadruped legs pair by their `FL_`/`FR_`, `RL_`/`RR_`, `HL_`/`HR_` (Spot-style hind
    /// legs) or `BL_`/`BR_` (back legs; and ANYmal-style `LF_`/`RF_`, `LH_`/`RH_`) prefixes, in
    /// either case; a biped's
    /// `LL_`/`LR_` (leg left, leg right) prefixes pair when the partner name exists (the same
    /// letters name a quadruped's left-rear leg, which has no `LL_` partner). Two actuators that
    /// both take their ctrlrange from mirror-paired joints through the same `inheritrange` are
    /// not compared on ctrlrange: a difference there is the joints' range difference, reported
    /// once on the joints. Scalars are compared with relative `tolerance`, ranges with
    /// absolute `range_tolerance`. Collision geoms are matched one to one by type, and sizes
    /// agree within `geom_tolerance` (relative) or 0.5 mm: enough for the 0.1–0.2 mm export noise
    /// of mesh-derived sizes (meshes are compared by their own compiled size), while a box 28 %
    /// larger or an extra duplicated cylinder on one side is reported. Joint armature and
    /// damping are the effective values (joint + actuator·gear² + tendon). A pair of hinges (or
    /// slides) on two bodies compares axes too: at qpos0 the right joint's world axis, reflected
    /// across the pair's mirror plane (halfway between the bodies' limb roots; the coordinate
    /// plane of the body both limbs hang from when the line between the roots lies within 5° of
    /// that body's axis: a root placed a few millimetres off must not tilt every axis; roots
    /// farther off define no plane, and the axes are not compared), must lie within
    /// `axis_tolerance` of the left one's line (an axis and its opposite are one line) — a
    /// hip axis written (0.9992, −0.0388, 0), 2.2° off its mirror's (1, 0, 0), is reported.
    ///
    /// ## Why is this bad?
    /// Real humanoids are built mirror-symmetric; an asymmetry in the model is almost always a
    /// typo or a half-applied edit. The policy learns to exploit it — a stiffer, lighter or
    /// stronger leg — and the learned gait limps or drifts on the symmetric hardware.
    ///
    /// ## How it is confirmed
    /// Static comparison of the compiled values.
    ///
    /// ## How to fix
    /// Copy the correct value to the other side (prefer a shared `<default class>` for both
    /// sides so they cannot drift apart), or mirror the range if it was copied unmirrored.
    pub MirrorAsymmetry {
        id: "mirror-asymmetry",
        group: "geometry",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("tolerance", 0.01, "ratio", Domain::NON_NEGATIVE, "relative difference tolerated between mirrored scalars"),
            opt("range_tolerance", 0.005, "rad or m", Domain::NON_NEGATIVE, "absolute difference tolerated between mirrored range ends (0.005 rad ≈ 0.3°: calibrated hardware limits differ by a few mrad)"),
            opt("geom_tolerance", 0.02, "ratio", Domain::NON_NEGATIVE, "relative size difference tolerated between mirrored collision geoms (or 0.5 mm)"),
            opt("place_tolerance", 0.005, "m", Domain::NON_NEGATIVE, "distance tolerated between a collision geom's place on its body and its mirror partner's, mirrored (or geom_tolerance of the geom's bounding radius, if larger): CAD exports of the two halves of a mirrored part place their shapes within a millimetre or two, a shape moved or mistyped by a digit lies centimetres off"),
            opt("com_tolerance", 0.01, "m", Domain::NON_NEGATIVE, "distance tolerated between a body's centre of mass and its mirror's reflected across the pair's mirror plane (halfway between its limb roots) at the reference pose (CAD exports of the two halves of a mirrored part and asymmetric wiring place them within millimetres)"),
            opt("plane_com_fraction", 0.2, "fraction", Domain::NON_NEGATIVE, "distance tolerated between the centre of mass of a body on the mirror plane (one with no side that carries mirror pairs: a trunk, a pelvis) and that plane, as a share of the half spacing of the widest pair's limb roots (or com_tolerance, if larger): a body's weight that far to one side rests 60/40 on the two sides' limbs"),
            opt("com_fraction", 0.25, "fraction", Domain::NON_NEGATIVE, "the same distance as a share of the centres of mass' offsets from their body origins: a centre of mass 0.1 m off its joint is also tolerated 25 mm"),
            opt("pose_tolerance", 5.0, "deg", Domain::NON_NEGATIVE, "angle within which a mirror pair's centre of mass and carried bodies must share one turn about the pair's hinge, and beyond which that turn counts as a differing joint zero (CAD exports place mirrored parts a fraction of a degree apart)"),
            opt("axis_tolerance", 1.0, "deg", Domain::NON_NEGATIVE, "angle tolerated between a joint's axis and its mirror's reflected across the pair's mirror plane: CAD exports of mirrored halves place axes within hundredths of a degree, a hand-edited or rounded axis or frame lies degrees off"),
            opt("tensor_tolerance", 0.07, "ratio", Domain::NON_NEGATIVE, "relative Frobenius difference tolerated between a mirror pair's inertia tensors in the world frame at the reference pose, the right one reflected through the mirror plane and given the left's principal moments (‖I_left − M·I_right·M‖ / ‖I‖; it bounds the moment error about any axis): the CAD halves of a mirrored part turn their axes a few degrees where two moments lie close (4.5 % measured on a public humanoid's forearm), while a swap of two principal axes whose moments differ by 8.6 % or more of the largest always exceeds it (√2·Δ ≥ 0.07·√3·I_max)"),
            opt("inertia_tolerance", 0.05, "ratio", Domain::NON_NEGATIVE, "relative difference tolerated between mirrored bodies' principal moments of inertia (CAD exports of the two halves of a mirrored part differ by 1–2 %)"),
        ],
    }
}

fn differs(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() > tol * a.abs().max(b.abs()) && (a - b).abs() > 1e-12
}

fn range_matches(a: [f64; 2], b: [f64; 2], tol: f64) -> bool {
    let same = (a[0] - b[0]).abs() <= tol && (a[1] - b[1]).abs() <= tol;
    let mirrored = (a[0] + b[1]).abs() <= tol && (a[1] + b[0]).abs() <= tol;
    same || mirrored
}

/// A mirror pair's range written the wrong one of the two forms [`range_matches`] accepts:
/// equal to its mirror's while the axes say the mirrored motion has the opposite sign
/// (`opposite`: a mirrored motion is the opposite coordinate on the right joint, so the
/// range must be `[−b, −a]`), or mirrored while the axes say the same sign. A range symmetric about 0 is
/// both and passes.
fn unmirrored_range(
    cx: &Context,
    p: &Pair,
    [a, b]: [[f64; 2]; 2],
    opposite: bool,
    slide: bool,
    tol: f64,
) -> Option<Finding> {
    let same = (a[0] - b[0]).abs() <= tol && (a[1] - b[1]).abs() <= tol;
    let mirrored = (a[0] + b[1]).abs() <= tol && (a[1] + b[0]).abs() <= tol;
    let want = if opposite { [-a[1], -a[0]] } else { a };
    if (opposite && mirrored) || (!opposite && same) {
        return None;
    }
    let unit = if slide { "m" } else { "rad" };
    let form = if opposite { "equals" } else { "is the mirror image of" };
    let sense = if opposite {
        "the two axes make the mirror image of a motion of the left joint the opposite coordinate of this one"
    } else {
        "the two axes make the mirror image of a motion of the left joint the same coordinate of this one"
    };
    let (lo, hi) = (a[0].abs().min(a[1].abs()), a[0].abs().max(a[1].abs()));
    let mut f = p.finding(cx, "range", "range", r(a), r(b), &format!(" {unit}"));
    f.message = format!(
        "joint `{}` range {} {unit} {form} its mirror `{}`'s, but the axes make the mirrored range {} {unit}",
        p.right.1,
        r(b),
        p.left.1,
        r(want)
    );
    Some(
        f.note(format!(
            "the range {form} `{}`'s, but {sense}: the mirrored range is {}; as written, the limb can move {} {unit} to the side where its mirror stops at {} {unit}, and the other way round",
            p.left.1,
            r(want),
            fmt_num(hi, 4),
            fmt_num(lo, 4)
        ))
        .help("write the mirrored range [−b, −a] for a hinge whose axis is the mirror image of its partner's (roll, yaw with the same axis), the equal range for one whose axis is the opposite (pitch written with the same axis); for slides the other way round")
        .measured(b[0], unit)
        .expected(want[0], unit),
    )
}

fn r(v: [f64; 2]) -> String {
    format!("[{}, {}]", fmt_num(v[0], 4), fmt_num(v[1], 4))
}

pub(super) struct Pair<'a> {
    pub(super) kind: ElemKind,
    pub(super) left: (usize, &'a str),
    pub(super) right: (usize, &'a str),
}

impl Pair<'_> {
    pub(super) fn finding(
        &self,
        cx: &Context,
        attr: &str,
        what: &str,
        lv: String,
        rv: String,
        unit: &str,
    ) -> Finding {
        let kw = crate::rules::kind_word(self.kind);
        let msg = format!(
            "{kw} `{}` {what} {rv}{unit} differs from its mirror `{}` ({lv}{unit})",
            self.right.1, self.left.1
        );
        let lloc = cx.robot.elem_loc(self.kind, self.left.0, self.left.1);
        let (lattr, _) = cx.robot.attr_loc(self.kind, self.left.0, self.left.1, attr);
        let subject = match self.kind {
            ElemKind::Joint => Subject::Joint(self.right.0),
            ElemKind::Actuator => Subject::Actuator(self.right.0),
            ElemKind::Body => Subject::Body(self.right.0),
            _ => Subject::Model,
        };
        let (rattr, rclass) = cx.robot.attr_loc(self.kind, self.right.0, self.right.1, attr);
        let lclass = cx.robot.attr_loc(self.kind, self.left.0, self.left.1, attr).1;
        // The `class=` written on an element: where it picks the default that gives the value.
        let own_class = |(id, name): (usize, &str)| {
            let e = cx.robot.elem(self.kind, id, name)?;
            e.attrs.get("class").filter(|o| o.class.is_none()).map(|o| o.loc)
        };
        let f = match (rclass, lclass, own_class(self.right)) {
            // The sides take the value from different default classes, picked by the elements'
            // `class=` (a class swapped between two actuators): the choice is the finding, the
            // shared default's line only where the value is written.
            (Some(rc), Some(lc), Some(rcloc)) if rc != lc => {
                let eloc = cx.robot.elem_loc(self.kind, self.right.0, self.right.1);
                let mut f = cx
                    .finding(msg, rcloc)
                    .element(
                        format!("{kw} {}", crate::rules::display_name(self.right.1, self.right.0)),
                        eloc,
                    )
                    .label(format!("class=\"{rc}\" gives {what} {rv}{unit}"))
                    .secondary(rattr, format!("{what} {rv}{unit} in <default class=\"{rc}\">"));
                if let Some(lcloc) = own_class(self.left) {
                    f = f
                        .secondary(lcloc, format!("mirror `{}` takes class=\"{lc}\"", self.left.1));
                }
                f.secondary(
                    lattr,
                    format!(
                        "mirror `{}` has {lv}{unit} from <default class=\"{lc}\">",
                        self.left.1
                    ),
                )
            }
            _ => cx
                .at_attr(self.kind, self.right.0, self.right.1, attr, msg)
                .label(format!("{what} {rv}{unit}"))
                .secondary(
                    if lattr == cx.robot.root_loc() { lloc } else { lattr },
                    format!("mirror `{}` has {lv}{unit}", self.left.1),
                ),
        };
        f
            .note("mirror-symmetric hardware should have a mirror-symmetric model; a policy exploits the stronger, stiffer or lighter side and limps on the real robot")
            .help("use the same value on both sides, ideally from one shared <default class>")
            .subject(subject)
    }
}

/// The mirrored bodies' principal moments (sorted, left then right), the index of the most
/// different one and the two `<inertial>` locations (right, left), when one of them differs by
/// more than `tol` relative.
type Moments = ([f64; 3], [f64; 3], usize, Loc, Loc);

fn moments_differ(cx: &Context, p: &Pair, tol: f64) -> Option<Moments> {
    let inertia = cx.robot.mj.body_inertia();
    let sorted = |b: usize| {
        let mut v = *inertia.get(b)?;
        v.sort_by(f64::total_cmp);
        Some(v)
    };
    let robot = cx.robot;
    // Only inertials the file states: moments MuJoCo computes from the geoms follow from the
    // collision geometry, compared (and reported) on its own.
    let loc = inertia_loc(robot, p.right.1)?;
    let lsrc = inertia_loc(robot, p.left.1)?;
    let (a, b) = (sorted(p.left.0)?, sorted(p.right.0)?);
    let worst = (0..3).filter(|&k| differs(a[k], b[k], tol)).max_by(|&x, &y| {
        let r = |k: usize| (a[k] - b[k]).abs() / a[k].abs().max(b[k].abs());
        r(x).total_cmp(&r(y))
    })?;
    Some((a, b, worst, loc, lsrc))
}

fn fmt_moments(v: [f64; 3]) -> String {
    format!("{} {} {}", fmt_num(v[0], 4), fmt_num(v[1], 4), fmt_num(v[2], 4))
}

/// A finding at the right body's inertial for moments that differ ([`moments_differ`]).
fn inertia_differs(cx: &Context, p: &Pair, tol: f64) -> Option<Finding> {
    let robot = cx.robot;
    let (a, b, worst, loc, lsrc) = moments_differ(cx, p, tol)?;
    let m = fmt_moments;
    let msg = format!(
        "body `{}` principal moments of inertia [{}] kg·m² differ from its mirror `{}`'s ([{}] kg·m²)",
        p.right.1,
        m(b),
        p.left.1,
        m(a)
    );
    let rloc = robot.elem_loc(ElemKind::Body, p.right.0, p.right.1);
    Some(
        cx.finding(msg, loc)
            .element(format!("body {}", p.right.1), rloc)
            .label(format!("moments [{}] kg·m²", m(b)))
            .secondary(lsrc, format!("mirror `{}` has [{}] kg·m²", p.left.1, m(a)))
            .note("the principal moments of a part and its mirror image are equal whatever frame each inertial is written in; a difference beyond CAD export noise is a different or wrongly copied part, and the policy learns a heavier-swinging side")
            .help("use the mirror part's inertial (principal moments equal, centre of mass mirrored) on both sides")
            .subject(Subject::Body(p.right.0))
            .measured(b[worst], "kg·m²")
            .expected(a[worst], "kg·m²"),
    )
}

/// Both actuators take their ctrlrange from their joints' ranges (`inheritrange`, the same
/// factor, no `ctrlrange`) and the joints are a mirror pair: a ctrlrange difference is then the
/// joints' range difference, reported on the joints.
fn inherited_from_mirror_joints(cx: &Context, a: usize, b: usize) -> bool {
    let robot = cx.robot;
    let inherit = |i: usize| {
        let act = &robot.actuators[i];
        let e = robot.elem(ElemKind::Actuator, i, &act.name)?;
        if e.attrs.contains_key("ctrlrange") {
            return None;
        }
        let factor = e.attrs.get("inheritrange")?.value.trim().parse::<f64>().ok()?;
        let j = robot.joints.get(usize::try_from(act.target).ok()?)?;
        Some((factor, j.name.as_str()))
    };
    let (Some((fa, ja)), Some((fb, jb))) = (inherit(a), inherit(b)) else { return false };
    fa == fb && mirror_in(ja, cx.spec, |n| robot.joint(n).is_some()).is_some_and(|(_, m)| m == jb)
}

/// (left id, right id) pairs among `names`.
pub(super) fn pairs(names: &[String], cx: &Context) -> Vec<(usize, usize)> {
    let mut v = Vec::new();
    for (i, n) in names.iter().enumerate() {
        if n.is_empty() {
            continue;
        }
        if let Some((Side::Left, m)) = mirror_in(n, cx.spec, |x| names.iter().any(|y| y == x))
            && let Some(j) = names.iter().position(|x| *x == m)
            && j != i
        {
            v.push((i, j));
        }
    }
    v
}

/// Body pairs that the names of the bodies do not give (part numbers, `KC_C_202R` and
/// `KC_C_202L`) but the joints that move them do: the bodies of a mirror-paired joint pair,
/// when neither body's own name carries a side marker and neither is already paired.
fn pairs_by_joints(cx: &Context, jn: &[String], named: &[(usize, usize)]) -> Vec<(usize, usize)> {
    let robot = cx.robot;
    let paired = |b: usize, v: &[(usize, usize)]| v.iter().any(|&(l, r)| l == b || r == b);
    let unmarked = |b: usize| {
        let n = &robot.bodies[b].name;
        !n.is_empty()
            && mirror_in(n, cx.spec, |x| robot.bodies.iter().any(|o| o.name == x)).is_none()
    };
    let mut v: Vec<(usize, usize)> = Vec::new();
    for (l, r) in pairs(jn, cx) {
        let (bl, br) = (robot.joints[l].body, robot.joints[r].body);
        if bl == br || bl == 0 || br == 0 || !unmarked(bl) || !unmarked(br) {
            continue;
        }
        if paired(bl, named) || paired(br, named) || paired(bl, &v) || paired(br, &v) {
            continue;
        }
        v.push((bl, br));
    }
    v
}

fn geom_signature(robot: &Robot, body: usize) -> Vec<(u8, [i64; 3])> {
    let mut v: Vec<(u8, [i64; 3])> = robot
        .geoms
        .iter()
        .filter(|g| g.body == body && g.collides())
        .map(|g| (g.gtype as u8, g.size.map(|s| (s * 1e4).round() as i64)))
        .collect();
    v.sort();
    v
}

/// Whether two sets of geoms are the same up to order: each geom of `a` has its own partner in
/// `b` of the same type with every size within `rel` (relative) or `abs` (metres).
pub fn same_geoms(robot: &Robot, a: &[usize], b: &[usize], rel: f64, abs: f64) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let close = |x: f64, y: f64| (x - y).abs() <= abs.max(rel * x.abs().max(y.abs()));
    let mut used = vec![false; b.len()];
    // Largest first, so a small geom cannot take a big one's partner.
    let mut order: Vec<usize> = a.to_vec();
    order.sort_by(|&x, &y| robot.geoms[y].rbound.total_cmp(&robot.geoms[x].rbound));
    for ga in order {
        let g = &robot.geoms[ga];
        let best = b
            .iter()
            .enumerate()
            .filter(|(i, _)| !used[*i])
            .filter(|(_, gb)| {
                let h = &robot.geoms[**gb];
                h.gtype == g.gtype && (0..3).all(|k| close(g.size[k], h.size[k]))
            })
            .min_by(|(_, x), (_, y)| {
                let d = |o: usize| {
                    (0..3).map(|k| (robot.geoms[o].size[k] - g.size[k]).abs()).sum::<f64>()
                };
                d(**x).total_cmp(&d(**y))
            });
        match best {
            Some((i, _)) => used[i] = true,
            None => return false,
        }
    }
    true
}

pub(super) fn colliders(robot: &Robot, body: usize) -> Vec<usize> {
    robot.geoms.iter().filter(|g| g.body == body && g.collides()).map(|g| g.id).collect()
}

/// "2 × capsule 12/30 mm, box 100/50/15 mm".
fn sig_str(sig: &[(u8, [i64; 3])]) -> String {
    const NAMES: [&str; 9] =
        ["plane", "hfield", "sphere", "capsule", "ellipsoid", "cylinder", "box", "mesh", "sdf"];
    let mut parts: Vec<(usize, String)> = Vec::new();
    for (t, s) in sig {
        let sizes: Vec<String> =
            s.iter().filter(|&&x| x != 0).map(|&x| fmt_num(x as f64 / 10.0, 4)).collect();
        let d = format!("{} {} mm", NAMES.get(*t as usize).unwrap_or(&"geom"), sizes.join("/"));
        match parts.last_mut() {
            Some((n, last)) if *last == d => *n += 1,
            _ => parts.push((1, d)),
        }
    }
    if parts.is_empty() {
        return "none".into();
    }
    let v: Vec<String> =
        parts.into_iter().map(|(n, d)| if n > 1 { format!("{n} × {d}") } else { d }).collect();
    format!("[{}]", v.join(", "))
}

impl Rule for MirrorAsymmetry {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let tol = cx.opt("tolerance");
        let rtol = cx.opt("range_tolerance");
        let gtol = cx.opt("geom_tolerance");
        let n4 = |x: f64| fmt_num(x, 4);
        // Joints.
        let jn: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
        let joint_pairs = pairs(&jn, cx);
        let bn: Vec<String> = robot.bodies.iter().map(|b| b.name.clone()).collect();
        let mut body_pairs = pairs(&bn, cx);
        body_pairs.extend(pairs_by_joints(cx, &jn, &body_pairs));
        let any = !body_pairs.is_empty() || !joint_pairs.is_empty();
        let pose = if any { Some(reference_pose(robot)) } else { None };
        let atol = cx.opt("axis_tolerance");
        out.extend(limits_differ(cx, &joint_pairs, tol));
        for (l, rr) in joint_pairs {
            let (a, b) = (&robot.joints[l], &robot.joints[rr]);
            let p = Pair { kind: ElemKind::Joint, left: (l, &a.name), right: (rr, &b.name) };
            for (attr, what, x, y, unit) in [
                ("armature", "armature", a.armature, b.armature, " kg·m²"),
                ("damping", "damping", a.damping, b.damping, " N·m·s/rad"),
                ("stiffness", "stiffness", a.stiffness, b.stiffness, " N·m/rad"),
                ("frictionloss", "frictionloss", a.frictionloss, b.frictionloss, " N·m"),
            ] {
                if differs(x, y, tol) {
                    out.push(
                        p.finding(cx, attr, what, n4(x), n4(y), unit)
                            .measured(y, unit.trim())
                            .expected(x, unit.trim()),
                    );
                }
            }
            // With the axes mirror lines of each other, their sense decides which of the two
            // a mirrored range is: for hinges equal when the right axis is the opposite of the
            // left's mirror image, mirrored when it is that image; a reflection keeps a
            // translation's sign (R·(d·a) = d·(R·a)), so for slides the other way round.
            let slide = a.jtype == crate::model::JointType::Slide;
            let sense = pose
                .as_ref()
                .and_then(|pose| axis_cos(cx, pose, l, rr))
                .filter(|c| c.abs() >= atol.to_radians().cos());
            if (a.limited || b.limited) && !range_matches(a.range, b.range, rtol) {
                out.push(
                    p.finding(cx, "range", "range", r(a.range), r(b.range), " rad")
                        .note("ranges of mirrored joints must be equal (pitch) or mirrored, [a, b] ↔ [−b, −a] (roll, yaw); this one is neither, so one leg can move further than the other"),
                );
            } else if (a.limited || b.limited)
                && let Some(c) = sense
                && let Some(f) =
                    unmirrored_range(cx, &p, [a.range, b.range], (c > 0.0) != slide, slide, rtol)
            {
                out.push(f);
            }
            if let Some(pose) = &pose
                && let Some(deg) = axis_angle(cx, pose, l, rr).filter(|d| *d > atol)
            {
                out.push(axis_finding(cx, &p, pose, deg, atol));
            }
        }
        // Actuators.
        let an: Vec<String> = robot.actuators.iter().map(|a| a.name.clone()).collect();
        for (l, rr) in pairs(&an, cx) {
            let (a, b) = (&robot.actuators[l], &robot.actuators[rr]);
            let p = Pair { kind: ElemKind::Actuator, left: (l, &a.name), right: (rr, &b.name) };
            if let (
                ActuatorKind::Position { kp: kpa, kv: kva },
                ActuatorKind::Position { kp: kpb, kv: kvb },
            ) = (a.kind, b.kind)
            {
                if differs(kpa, kpb, tol) {
                    out.push(
                        p.finding(cx, "kp", "kp", n4(kpa), n4(kpb), " N·m/rad")
                            .measured(kpb, "N·m/rad")
                            .expected(kpa, "N·m/rad"),
                    );
                }
                if differs(kva, kvb, tol) {
                    out.push(
                        p.finding(cx, "kv", "kv", n4(kva), n4(kvb), " N·m·s/rad")
                            .measured(kvb, "N·m·s/rad")
                            .expected(kva, "N·m·s/rad"),
                    );
                }
            } else if a.gainprm[0] != 0.0 && differs(a.gainprm[0], b.gainprm[0], tol) {
                out.push(p.finding(cx, "gainprm", "gain", n4(a.gainprm[0]), n4(b.gainprm[0]), ""));
            }
            if differs(a.gear.abs(), b.gear.abs(), tol) {
                out.push(p.finding(cx, "gear", "gear", n4(a.gear), n4(b.gear), ""));
            }
            if (a.forcelimited || b.forcelimited)
                && !range_matches(
                    a.forcerange,
                    b.forcerange,
                    tol * a.forcerange[1].abs().max(a.forcerange[0].abs()).max(1e-9),
                )
            {
                out.push(p.finding(
                    cx,
                    "forcerange",
                    "forcerange",
                    r(a.forcerange),
                    r(b.forcerange),
                    " N·m",
                ));
            }
            if (a.ctrllimited || b.ctrllimited)
                && !inherited_from_mirror_joints(cx, a.id, b.id)
                && !range_matches(
                    a.ctrlrange,
                    b.ctrlrange,
                    rtol.max(tol * a.ctrlrange[1].abs().max(a.ctrlrange[0].abs())),
                )
            {
                out.push(p.finding(
                    cx,
                    "ctrlrange",
                    "ctrlrange",
                    r(a.ctrlrange),
                    r(b.ctrlrange),
                    "",
                ));
            }
        }
        // Bodies: mass and collision geometry.
        out.extend(filtering_differs(cx, &body_pairs));
        out.extend(hub_com_off(cx, &body_pairs, &pose));
        out.extend(sites_differ(cx, &body_pairs, &pose));
        for (l, rr) in body_pairs {
            let (a, b) = (&robot.bodies[l], &robot.bodies[rr]);
            let p = Pair { kind: ElemKind::Body, left: (l, &a.name), right: (rr, &b.name) };
            // Moments follow the mass: a body reported for its mass has differing moments in the
            // same finding, as a note (a tolerance raised past the mass difference must not be
            // what reveals them).
            let itol = cx.opt("inertia_tolerance");
            if differs(a.mass, b.mass, tol) {
                let mut f = p
                    .finding(cx, "mass", "mass", n4(a.mass), n4(b.mass), " kg")
                    .measured(b.mass, "kg")
                    .expected(a.mass, "kg")
                    .with("mass_ratio", b.mass / a.mass.max(1e-12));
                if let Some((ma, mb, k, iloc, _)) = moments_differ(cx, &p, itol) {
                    let rel = (ma[k] - mb[k]).abs() / ma[k].abs().max(mb[k].abs());
                    let why = f.note.take().unwrap_or_default();
                    f = f
                        .secondary(iloc, format!("moments [{}] kg·m²", fmt_moments(mb)))
                        .note(format!(
                            "{why}; the principal moments of inertia differ too: [{}] kg·m² against the mirror's [{}] kg·m² ({} % apart, beyond inertia_tolerance {} %)",
                            fmt_moments(mb),
                            fmt_moments(ma),
                            fmt_num(rel * 100.0, 2),
                            fmt_num(itol * 100.0, 3)
                        ))
                        .with("inertia_ratio", mb[k] / ma[k].max(1e-12));
                }
                out.push(f);
            } else if let Some(f) = inertia_differs(cx, &p, itol) {
                out.push(f);
            } else if let Some(f) = com_differs(cx, &p, &pose) {
                out.push(f);
            } else if let Some(f) = tensor_differs(cx, &p, &pose) {
                // Masses, moments and centres of mass agree: the axes alone can differ.
                out.push(f);
            }
            if differs(a.mass, b.mass, tol) || moments_differ(cx, &p, itol).is_some() {
                out.extend(com_differs(cx, &p, &pose));
            }
            let (sa, sb) = (geom_signature(robot, l), geom_signature(robot, rr));
            if !same_geoms(robot, &colliders(robot, l), &colliders(robot, rr), gtol, SIZE_NOISE) {
                out.push(
                    p.finding(cx, "name", "collision geoms", sig_str(&sa), sig_str(&sb), "")
                        .label("collision geometry differs from the mirror body")
                        .note("the mirrored bodies' collision geoms differ in number, type or size by more than mesh export noise (matched one to one, sizes within 2 % or 0.5 mm); one side then collides, or touches the ground, differently from the other"),
                );
            } else if let Some(f) = geoms_misplaced(cx, &p, &pose) {
                out.push(f);
            }
        }
    }
}
