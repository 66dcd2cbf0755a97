use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::Robot;
use crate::model::mirror::{Side, leg_joint, side_of};
use crate::model::mjcf::ElemKind;
use crate::rules::limits::legs::leg_chains;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a legged robot whose root frame is not REP-103's body frame (x forward, y left,
    /// z up), judged from the legs as the names place them. The legs are
    /// `placeholder-joint-limits`' (each foot's chain of hinges up to the body the legs leave:
    /// a URDF's root link, an MJCF's floating base). A leg's hip is the origin of the body its
    /// topmost hinge moves, its low point the origin of its lowest link (a foot, or the link a
    /// fixed foot is fused into), both in the root body's frame with every joint at zero
    /// (qpos0: the file's own pose, whatever a keyframe does with the legs or the base). A leg
    /// is left or right, and front or rear, by the names of its links and joints: the side
    /// markers `mirror-asymmetry` pairs by (`left`, `l_`, `_R`, …), `front`/`fore` and
    /// `rear`/`hind`/`back`, and the quadruped prefixes `FL_` `RR_` `HL_` `BL_`, `LF_` `RH_`;
    /// the side (and the end) most of the leg's names carry, a tie giving none (one link
    /// exported under the other side's name, as DDT Diablo's wheels, does not move the leg). Three
    /// directions are measured when the legs give them: forward (front hips less rear hips on
    /// the same side, averaged over the sides), left (left hips less right hips at the same
    /// end, averaged over the ends: a front-left and a rear-right leg alone give neither) and
    /// up (the hips' mean less the low points'). A direction farther than `max_angle` from its
    /// axis (+x, +y, +z) lies nearer another axis or the opposite one, and the frame is
    /// reported with the axis each such direction lies along. Legs without side or end names
    /// give no evidence; a robot with no named pair is not judged, and up alone is never
    /// judged (a robot with no named pair gives no frame to compare it in).
    ///
    /// ## Why is this bad?
    /// REP-103 (ROS, "Standard Units of Measure and Coordinate Conventions") fixes a body's
    /// frame as x forward, y left, z up, and the tools that read a robot file assume it: a
    /// velocity command `vx` drives along the root's x, an IMU's heading and the gravity
    /// vector are read in that frame, and MuJoCo's importer places a URDF's root as written,
    /// so a frame with y forward walks sideways under a forward command and one lying on its
    /// side starts lying down. The policy learns the file's convention, not the robot's.
    ///
    /// ## How it is confirmed
    /// Static: the compiled bodies' `pos` and `quat` composed from the root at qpos0, and the
    /// names.
    ///
    /// ## How to fix
    /// Turn the root link's frame to x forward, y left, z up: rotate the joints that leave it
    /// (their `<origin rpy>`, or the MJCF body's `quat`) and its inertial and geoms, or add a
    /// fixed parent link in REP-103's frame; or, if the convention is deliberate, rotate the
    /// commands and the IMU in the training environment and say so.
    pub RootFrameConvention {
        id: "root-frame-convention",
        group: "geometry",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("max_angle", 45.0, "deg", Domain::NON_NEGATIVE, "angle beyond which a direction the legs give (forward, left, up) lies off its REP-103 axis (+x, +y, +z): past 45° it lies nearer another axis or the opposite one"),
        ],
    }
}

/// Shortest difference of hip means that counts as a direction, m.
const MIN_SPREAD: f64 = 1e-3;

/// Whether a leg is at the front (`Some(true)`) or the rear, by a name on it.
fn end_of(name: &str) -> Option<bool> {
    let low = name.to_ascii_lowercase();
    if low.contains("front") || low.contains("fore") {
        return Some(true);
    }
    if low.contains("rear") || low.contains("hind") || low.contains("back") {
        return Some(false);
    }
    let (c, _) = leg_joint(name)?;
    // `FL_` `RL_` `HL_` `BL_` (conventions 0, 1): the end first; `LF_` `LH_` (2, 3): second.
    let letter = name.chars().nth(if c < 2 { 0 } else { 1 })?.to_ascii_lowercase();
    match letter {
        'f' => Some(true),
        'r' | 'h' | 'b' => Some(false),
        _ => None,
    }
}

/// The value most of a leg's names give (its side, its end); a tie gives none: one misnamed
/// link (a wheel exported under the other side's name) does not turn the leg over.
fn majority<T: PartialEq + Copy>(votes: impl Iterator<Item = T>) -> Option<T> {
    let mut tally: Vec<(T, usize)> = Vec::new();
    for v in votes {
        match tally.iter_mut().find(|(t, _)| *t == v) {
            Some((_, n)) => *n += 1,
            None => tally.push((v, 1)),
        }
    }
    let best = tally.iter().map(|&(_, n)| n).max()?;
    let mut top = tally.iter().filter(|&&(_, n)| n == best);
    match (top.next(), top.next()) {
        (Some(&(t, _)), None) => Some(t),
        _ => None,
    }
}

/// Rotation matrix (row-major) of a unit quaternion (w, x, y, z).
fn quat_mat(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = (q.iter().map(|x| x * x).sum::<f64>()).sqrt();
    let [w, x, y, z] = if n > 0.0 { q.map(|c| c / n) } else { [1.0, 0.0, 0.0, 0.0] };
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
        [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
        [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

fn mat_mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|r| [0, 1, 2].map(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

fn mat_vec(a: [[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    a.map(|r| r[0] * v[0] + r[1] * v[1] + r[2] * v[2])
}

/// Body `b`'s origin in the frame of `root` with every joint at its zero (qpos0: the file's
/// own pose, whatever a keyframe does): the bodies' `pos` and `quat` composed from `root`
/// down. `None` when `b` does not hang from `root`.
fn at_zero(robot: &Robot, root: usize, b: usize) -> Option<[f64; 3]> {
    let (pos, quat) = (robot.mj.body_pos(), robot.mj.body_quat());
    let mut chain = Vec::new();
    let mut c = b;
    while c != root {
        if c == 0 || chain.len() > robot.bodies.len() {
            return None;
        }
        chain.push(c);
        c = robot.bodies[c].parent;
    }
    let (mut p, mut r) = ([0.0; 3], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    for &c in chain.iter().rev() {
        let d = mat_vec(r, *pos.get(c)?);
        p = [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
        r = mat_mul(r, quat_mat(*quat.get(c)?));
    }
    Some(p)
}

/// The mean over groups of the difference between the `a` and `b` members of each group that
/// has both: legs compared with their partner at the same end (or on the same side), so a
/// front-left and a rear-right leg alone say nothing of either direction. (vector, pairs
/// compared as "a against b" counts).
fn paired(
    legs: &[Leg],
    a: fn(&Leg) -> bool,
    b: fn(&Leg) -> bool,
    key: fn(&Leg) -> u8,
) -> Option<([f64; 3], usize)> {
    let mut diffs = Vec::new();
    let mut n = 0;
    for k in [0u8, 1, 2] {
        let group: Vec<&Leg> = legs.iter().filter(|l| key(l) == k).collect();
        let pa: Vec<[f64; 3]> = group.iter().filter(|l| a(l)).map(|l| l.hip).collect();
        let pb: Vec<[f64; 3]> = group.iter().filter(|l| b(l)).map(|l| l.hip).collect();
        if let (Some(ma), Some(mb)) = (mean(&pa), mean(&pb)) {
            diffs.push(sub(ma, mb));
            n += pa.len() + pb.len();
        }
    }
    mean(&diffs).map(|v| (v, n))
}

/// A leg: its hip, its lowest link (both in the root frame at qpos0), its side and end.
struct Leg {
    hip: [f64; 3],
    low: [f64; 3],
    side: Option<Side>,
    front: Option<bool>,
}

fn mean(v: &[[f64; 3]]) -> Option<[f64; 3]> {
    (!v.is_empty()).then(|| {
        let n = v.len() as f64;
        [0, 1, 2].map(|k| v.iter().map(|p| p[k]).sum::<f64>() / n)
    })
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// "+y", "−x": the axis a direction lies nearest.
fn axis_word(v: [f64; 3]) -> String {
    let k = (0..3).max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs())).unwrap_or(0);
    format!("{}{}", if v[k] >= 0.0 { "+" } else { "−" }, ["x", "y", "z"][k])
}

/// A direction the legs give: (what, its vector in the root frame, the axis it should lie on,
/// the evidence in words).
type Direction = (&'static str, [f64; 3], usize, String);

impl Rule for RootFrameConvention {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let roots = crate::rules::contact::feet::floating_bases(robot);
        let [root] = roots[..] else { return };
        let mut legs: Vec<Leg> = Vec::new();
        for (leaf, hinges) in leg_chains(cx) {
            let Some(&top) = hinges.first() else { continue };
            let hip_body = robot.joints[top].body;
            let (Some(hip), Some(low)) =
                (at_zero(robot, root, hip_body), at_zero(robot, root, leaf))
            else {
                continue;
            };
            // The names on the leg: its links from the foot up, and its hinges.
            let mut names: Vec<&str> = Vec::new();
            let mut b = leaf;
            while b != 0 && b != root && names.len() <= robot.bodies.len() {
                names.push(robot.body_name(b));
                b = robot.bodies[b].parent;
            }
            names.extend(hinges.iter().map(|&j| robot.joints[j].name.as_str()));
            let side = majority(names.iter().filter_map(|n| side_of(n, cx.spec)));
            let front = majority(names.iter().filter_map(|n| end_of(n)));
            legs.push(Leg { hip, low, side, front });
        }
        let end_key = |l: &Leg| match l.front {
            Some(true) => 0,
            Some(false) => 1,
            None => 2,
        };
        let side_key = |l: &Leg| match l.side {
            Some(Side::Left) => 0,
            Some(Side::Right) => 1,
            None => 2,
        };
        let mut dirs: Vec<Direction> = Vec::new();
        if let Some((v, n)) =
            paired(&legs, |l| l.front == Some(true), |l| l.front == Some(false), side_key)
        {
            dirs.push(("forward", v, 0, format!("{n} front and rear hips on one side compared")));
        }
        if let Some((v, n)) =
            paired(&legs, |l| l.side == Some(Side::Left), |l| l.side == Some(Side::Right), end_key)
        {
            dirs.push(("left", v, 1, format!("{n} left and right hips at one end compared")));
        }
        if dirs.is_empty() {
            return; // no named pair: nothing says which way the robot faces
        }
        let hips: Vec<[f64; 3]> = legs.iter().map(|l| l.hip).collect();
        let lows: Vec<[f64; 3]> = legs.iter().map(|l| l.low).collect();
        if let (Some(h), Some(f)) = (mean(&hips), mean(&lows)) {
            dirs.push((
                "up",
                sub(h, f),
                2,
                format!("{} hips against their legs' lowest links", hips.len()),
            ));
        }
        let max = cx.opt("max_angle");
        let mut wrong = Vec::new();
        let mut worst: f64 = 0.0;
        for (what, v, axis, words) in &dirs {
            let n = norm(*v);
            if !(n > MIN_SPREAD) {
                continue;
            }
            let deg = (v[*axis] / n).clamp(-1.0, 1.0).acos().to_degrees();
            if deg > max {
                worst = worst.max(deg);
                wrong.push(format!(
                    "{what} is {} ({words}: {} m along {}; {}° from {})",
                    axis_word(*v),
                    fmt_num(n, 3),
                    axis_word(*v),
                    fmt_num(deg, 3),
                    ["+x", "+y", "+z"][*axis]
                ));
            }
        }
        if wrong.is_empty() {
            return;
        }
        let name = if root == 0 {
            crate::rules::contact::welded_legged_base::root_link(robot)
                .and_then(|l| l.get("name"))
                .unwrap_or("world")
                .to_string()
        } else {
            robot.body_name(root).to_string()
        };
        let loc = match (root, crate::rules::contact::welded_legged_base::root_link(robot)) {
            (0, Some(l)) => l.attr("name").map_or(l.loc, |a| a.loc),
            _ => robot.elem_loc(ElemKind::Body, root, &name),
        };
        let msg = format!(
            "root frame of `{name}` is not REP-103's (x forward, y left, z up): {}",
            wrong.join("; ")
        );
        let f = cx
            .finding(msg, loc)
            .element(format!("body `{name}`"), loc)
            .label("the root frame")
            .note("directions measured from the legs' hips (the body their topmost hinge moves) and lowest links (a foot, or the link a fixed foot is fused into), in the root body's frame with every joint at zero (qpos0), the legs' sides and ends read from their names")
            .help("turn the root frame to x forward, y left, z up (rotate the joints that leave it, its inertial and geoms, or add a fixed parent link in that frame), or rotate the commands and the IMU in the training environment")
            .subject(Subject::Body(root))
            .measured(worst, "°")
            .expected(max, "°")
            .with("directions_off", wrong.len() as f64);
        out.push(f);
    }
}
