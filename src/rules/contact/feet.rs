//! Which bodies are feet and which side they are on. Shared by the contact rules and
//! `collision-visual-mismatch`; left/right names mirror by [`crate::model::mirror`].
//!
//! Foot bodies come from the spec's `robot.foot_bodies` globs; without them, from body names
//! containing `foot`, `ankle_roll`, `toe` or `sole`; failing that, the leaf bodies whose
//! collision geoms reach within 3 cm of the robot's lowest collision point at the keyframe (a
//! leaf of the colliding tree: a body may carry links that collide nowhere, as a shank holds
//! the rod of an open knee linkage, [`collides_below`]).
//! A push rod of a closed-loop linkage ([`linkage_bodies`]: on ball joints only, tied by a
//! `connect` or `weld` equality) and what hangs below it is never matched, whatever its name.
//! Each matched body that has no matched ancestor is a foot root; its descendants (and any
//! other toe-named matched body on the same side and the same leg, e.g. a separately matched
//! toe; not one whose branch leaves the trunk apart, a quadruped's other leg) are its toe bodies. A
//! root with no contact geom of its own whose foot's contacts all hang below one descendant (an
//! ankle roll link above the pitch link that holds the sole), or below another matched body of
//! its side (a toe motor's crank matched before the toe links), hands the foot to that body.
//!
//! Only a floating-base robot has feet (unless the spec names them; a free joint, or three
//! slides and a ball: [`Robot::floating_bodies`]): a fixed-base arm or a test rig gets no
//! foot rules. A legged URDF, which MuJoCo's importer welds to the world, counts as floating
//! from its root link ([`floating_bases`]). Each foot is classified by its ground geoms (the collision
//! geoms whose lowest point at the keyframe is within [`GROUND_WINDOW`] of the foot's lowest):
//! a **point foot** touches down through spheres whose lowest points lie within
//! [`POINT_SPREAD`] of each other (the quadruped's foot sphere; flat-foot rules do not apply; a
//! geom whose ground points all lie inside a lower-reaching sphere of the foot — a shank box
//! ending inside the foot sphere a URDF's fixed foot link was fused onto — touches nothing
//! before that sphere and is no ground geom); a
//! **wheel** touches down through a geom of a body that an unlimited hinge turns about the
//! geom's own round axis ([`Robot::is_wheel`]: sphere, or cylinder, capsule or ellipsoid on its
//! axle; no foot rules apply); anything else is a **flat foot**. A body welded to the floating
//! base (no joint between them, e.g. a ROS `base_footprint`) is trunk, never a foot. A flat foot whose
//! ground contact is a line or a point is a design, not a thin sole, when no joint at the foot
//! can turn it about that contact ([`ankle_turning`], from the joints' world axes at the
//! keyframe) — unless the robot is a humanoid ([`is_humanoid`]: two feet and arms), which
//! stands on soles.

pub use crate::model::mirror::{Side, side_of};
use crate::model::{GeomType, Robot};
use crate::rules::geometry::shapes::Placed;
use crate::spec::Spec;

/// How far above the foot's lowest point a geom may reach and still touch the ground, m.
pub const GROUND_WINDOW: f64 = 0.01;
/// Largest horizontal spread of the contact points of a point foot, m.
pub const POINT_SPREAD: f64 = 0.02;

/// The robot family a foot belongs to, by how it touches the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FootKind {
    /// A sole or a set of contacts that spans a support polygon (humanoids).
    Flat,
    /// One small contact region through spheres (point-foot quadrupeds).
    Point,
    /// A rolling wheel.
    Wheel,
}

#[derive(Debug, Clone)]
pub struct Foot {
    pub kind: FootKind,
    /// The collision geoms that touch the ground (within [`GROUND_WINDOW`] of the lowest).
    pub ground: Vec<usize>,
    pub side: Option<Side>,
    /// The foot body (subject of findings).
    pub root: usize,
    /// Toe bodies: the root's descendants and other matched bodies on the same side and leg.
    pub toes: Vec<usize>,
    /// Collision geoms (non-plane) of the root and its toes.
    pub geoms: Vec<usize>,
}

impl Foot {
    pub fn is_toe_geom(&self, robot: &Robot, g: usize) -> bool {
        self.toes.contains(&robot.geoms[g].body)
    }
    pub fn label(&self, robot: &Robot) -> String {
        match self.side {
            Some(s) => format!("{} foot ({})", s.word(), robot.body_name(self.root)),
            None => format!("foot {}", robot.body_name(self.root)),
        }
    }
}

fn is_ancestor(robot: &Robot, anc: usize, mut b: usize) -> bool {
    while b != 0 {
        b = robot.bodies[b].parent;
        if b == anc {
            return true;
        }
    }
    false
}

/// The deepest body that is `bodies`' own or an ancestor of each of them (0: the world).
fn common_ancestor(robot: &Robot, bodies: &[usize]) -> usize {
    let mut c = bodies.first().copied().unwrap_or(0);
    while c != 0 && !bodies.iter().all(|&b| b == c || is_ancestor(robot, c, b)) {
        c = robot.bodies[c].parent;
    }
    c
}

/// Whether a body below `body` has a collision geom: `body` is then no end of a limb. A body
/// whose descendants collide nowhere ends its limb's contact even when it carries links (a
/// shank holding the open rod of a knee linkage, a sensor mount), so it is a leaf for the
/// feet found by geometry.
pub fn collides_below(robot: &Robot, body: usize) -> bool {
    robot.geoms.iter().any(|g| {
        g.body != body
            && is_ancestor(robot, body, g.body)
            && crate::model::contact::takes_part(robot, g.id)
            && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
    })
}

fn contact_geoms(robot: &Robot, body: usize) -> impl Iterator<Item = usize> + '_ {
    robot
        .geoms
        .iter()
        .filter(move |g| {
            g.body == body
                && crate::model::contact::takes_part(robot, g.id)
                && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
        })
        .map(|g| g.id)
}

/// The bodies the foot rules take for floating bases: each free joint's body and each body
/// floated by three slides and a ball ([`Robot::floating_bodies`]); with none, in a
/// legged URDF that MuJoCo's importer welded to the world
/// ([`crate::rules::contact::welded_legged_base::is_welded_legged`]), the world body the
/// importer fused the root link into (0): its feet are judged as if the root link floated at
/// its pose in the file (the static geometry at qpos0 is the same). Empty for a fixed-base
/// robot (an arm, a wheeled base welded by the importer, any MJCF without a free joint).
pub fn floating_bases(robot: &Robot) -> Vec<usize> {
    let free = robot.floating_bodies();
    if free.is_empty() && crate::rules::contact::welded_legged_base::is_welded_legged(robot) {
        return vec![0];
    }
    free
}

/// The feet of the model, left before right.
pub fn feet(robot: &Robot, spec: Option<&Spec>) -> Vec<Foot> {
    feet_over(robot, spec, &floating_bases(robot))
}

/// The feet of the model under the given bases (the floating bases, or with them the bodies a
/// rule also takes for a base, as `links-without-collision` does a planar locomotor's), left
/// before right.
pub fn feet_over(robot: &Robot, spec: Option<&Spec>, bases: &[usize]) -> Vec<Foot> {
    let n = robot.bodies.len();
    let globs = spec.map(|s| s.foot_matchers()).unwrap_or_default();
    // A spec that sets `foot_bodies` (even to []) is authoritative.
    let from_spec = spec.is_some_and(|s| s.robot.foot_bodies.is_some());
    let mut matched: Vec<usize> = if from_spec {
        (1..n).filter(|&b| globs.iter().any(|m| m.is_match(robot.body_name(b)))).collect()
    } else {
        (1..n)
            .filter(|&b| {
                let l = robot.body_name(b).to_lowercase();
                ["foot", "ankle_roll", "toe", "sole"].iter().any(|k| l.contains(k))
            })
            .collect()
    };
    // A body welded to the floating base (no joint between them: the trunk, a ROS
    // `base_footprint` frame) is part of the trunk, not a foot, unless the spec names it. The
    // floating body itself may be a foot (a foot dropped alone on a floor, a test rig).
    // A floating base written as slides and a ball floats as a free joint does.
    let weld = |b: usize| robot.bodies.get(b).map_or(b, |x| x.weld);
    let on_limb = |b: usize| {
        from_spec || (b != 0 && bases.contains(&b)) || !bases.iter().any(|&f| weld(f) == weld(b))
    };
    matched.retain(|&b| on_limb(b));
    // A push rod of a closed-loop linkage (and what hangs below it) is no foot and no toe,
    // whatever its name, unless the spec names it.
    let rods = linkage_bodies(robot);
    let in_rod = |b: usize| !from_spec && rods.iter().any(|&r| r == b || is_ancestor(robot, r, b));
    matched.retain(|&b| !in_rod(b));
    // Only a floating-base robot (a legged one) has feet to guess at: a fixed-base arm or a
    // test rig does not.
    let floating = !bases.is_empty();
    if !floating && !from_spec {
        return Vec::new();
    }
    if matched.is_empty() && !from_spec && floating {
        // Leaf bodies whose collision geoms touch down.
        let lowest = |b: usize| {
            contact_geoms(robot, b)
                .map(|g| Placed::of(robot, g).lowest()[2])
                .fold(f64::INFINITY, f64::min)
        };
        let zmin = (1..n).map(lowest).fold(f64::INFINITY, f64::min);
        matched = (1..n)
            .filter(|&b| {
                !collides_below(robot, b) && lowest(b) <= zmin + 0.03 && on_limb(b) && !in_rod(b)
            })
            .collect();
    }
    let roots: Vec<usize> = matched
        .iter()
        .copied()
        .filter(|&b| !matched.iter().any(|&a| a != b && is_ancestor(robot, a, b)))
        .collect();
    let mut out: Vec<Foot> = Vec::new();
    for &root in &roots {
        let side = crate::model::mirror::mirror_in(robot.body_name(root), spec, |n| {
            robot.bodies.iter().any(|b| b.name == n)
        })
        .map(|(s, _)| s);
        let toes: Vec<usize> =
            (1..n).filter(|&b| is_ancestor(robot, root, b) && !in_rod(b)).collect();
        // A second root on the same side (a separately matched toe) joins the first — on the
        // same leg: two roots whose common ancestor is the trunk (a floating base and what is
        // welded to it) or the world end two legs (a quadruped's `toe_front_left` and
        // `toe_back_left`), two feet.
        let same_leg = |a: usize| {
            let c = common_ancestor(robot, &[a, root]);
            c != 0 && !bases.iter().any(|&f| weld(f) == weld(c))
        };
        if let Some(f) =
            out.iter_mut().find(|f| side.is_some() && f.side == side && same_leg(f.root))
        {
            let toe_named = robot.body_name(root).to_lowercase().contains("toe");
            if toe_named {
                f.toes.push(root);
                f.toes.extend(toes);
                continue;
            }
        }
        out.push(Foot {
            kind: FootKind::Flat,
            ground: Vec::new(),
            side,
            root,
            toes,
            geoms: Vec::new(),
        });
    }
    for f in &mut out {
        let mut bodies = vec![f.root];
        bodies.extend(f.toes.iter().copied());
        f.geoms = bodies.iter().flat_map(|&b| contact_geoms(robot, b)).collect();
        f.geoms.sort();
        // The foot is the body that carries its contacts: a matched body with no contact geom
        // of its own whose contacts all hang below one descendant (an ankle roll link above the
        // pitch link that holds the sole) hands the foot to that descendant; one whose contacts
        // all hang below another matched body of its side (a motor crank matched first, beside
        // the toe pitch and roll links that hold the sole) hands it to that body, which keeps
        // its own descendants as toes.
        if !f.geoms.is_empty() && !f.geoms.iter().any(|&g| robot.geoms[g].body == f.root) {
            let carriers: Vec<usize> = f.geoms.iter().map(|&g| robot.geoms[g].body).collect();
            let c = common_ancestor(robot, &carriers);
            if c != f.root && is_ancestor(robot, f.root, c) {
                f.toes.retain(|&b| b != c && !is_ancestor(robot, b, c));
                f.root = c;
            } else if c != f.root && f.toes.contains(&c) {
                f.toes.retain(|&b| is_ancestor(robot, c, b));
                f.root = c;
            }
        }
        let low: Vec<(usize, [f64; 3])> =
            f.geoms.iter().map(|&g| (g, Placed::of(robot, g).lowest())).collect();
        let zmin = low.iter().map(|x| x.1[2]).fold(f64::INFINITY, f64::min);
        let mut ground: Vec<(usize, [f64; 3])> =
            low.into_iter().filter(|x| x.1[2] <= zmin + GROUND_WINDOW).collect();
        let spheres_down: Vec<(usize, [f64; 3])> = ground
            .iter()
            .copied()
            .filter(|&(g, _)| robot.geoms[g].gtype == GeomType::Sphere)
            .collect();
        ground.retain(|&(g, z)| !spheres_down.iter().any(|&(s, zs)| shadowed(robot, g, z, s, zs)));
        f.ground = ground.iter().map(|x| x.0).collect();
        let spread = ground
            .iter()
            .flat_map(|a| ground.iter().map(move |b| (a.1[0] - b.1[0]).hypot(a.1[1] - b.1[1])))
            .fold(0.0, f64::max);
        let wheel = ground.iter().any(|&(g, _)| {
            let geom = &robot.geoms[g];
            robot.joints.iter().any(|j| j.body == geom.body && robot.is_wheel(j.id))
        });
        let spheres = !ground.is_empty()
            && ground.iter().all(|&(g, _)| robot.geoms[g].gtype == GeomType::Sphere);
        f.kind = if wheel {
            FootKind::Wheel
        } else if spheres && spread <= POINT_SPREAD {
            FootKind::Point
        } else {
            FootKind::Flat
        };
    }
    out.retain(|f| !f.geoms.is_empty());
    out.sort_by_key(|f| (f.side.map(|s| s as u8).unwrap_or(2), f.root));
    out
}

/// The push rods of closed-loop linkages: bodies that a `connect` or `weld` equality ties to
/// another body (its body or site, MuJoCo >= 3.1) and whose own joints are all ball joints
/// (one or more) — a two-force member with a spherical end at each side, like Digit's toe rods
/// from the toe motors' cranks to the toe roll link or Cassie's plantar rod. Such a body
/// transmits a motor's force to the foot; it is never a foot or a toe, and its geoms (a capsule
/// along the rod, reaching up the shin) do not outline a sole.
pub fn linkage_bodies(robot: &Robot) -> Vec<usize> {
    use crate::model::JointType;
    let objtype = robot.mj.eq_objtype();
    let site_body = robot.mj.site_bodyid();
    let body_of = |e: &crate::model::Equality, o: i32| -> Option<usize> {
        if o < 0 {
            return None;
        }
        match objtype.get(e.id).map(|&t| t as i32) {
            Some(6) => site_body.get(o as usize).map(|&b| b.max(0) as usize),
            _ => Some(o as usize),
        }
    };
    let mut tied: Vec<usize> = robot
        .equalities
        .iter()
        .filter(|e| e.etype == 0 || e.etype == 1)
        .flat_map(|e| [body_of(e, e.obj1), body_of(e, e.obj2)])
        .flatten()
        .filter(|&b| b != 0 && b < robot.bodies.len())
        .collect();
    tied.sort();
    tied.dedup();
    tied.retain(|&b| {
        let mut js = robot.joints.iter().filter(|j| j.body == b).peekable();
        js.peek().is_some() && js.all(|j| j.jtype == JointType::Ball)
    });
    tied
}

/// Whether ground geom `g` (lowest point `low`) lies, where it reaches the ground, inside the
/// foot's sphere `s` (lowest point `s_low`): every point of `g` within [`GROUND_WINDOW`] of its
/// lowest ([`Placed::ground_points`]) is inside the sphere, and the sphere reaches lower. Such a
/// geom cannot touch a flat floor before the sphere does — the lower end of a shank box or
/// capsule that ends inside a point foot's sphere (a URDF's fixed foot link, which MuJoCo's
/// importer fuses into the shank) — so it is no ground contact of the foot.
fn shadowed(robot: &Robot, g: usize, low: [f64; 3], s: usize, s_low: [f64; 3]) -> bool {
    if g == s || s_low[2] >= low[2] {
        return false;
    }
    let ball = Placed::of(robot, s);
    let r = robot.geoms[s].size[0];
    let inside = |p: [f64; 3]| {
        let d = [p[0] - ball.pos[0], p[1] - ball.pos[1], p[2] - ball.pos[2]];
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= r
    };
    let pts = Placed::of(robot, g).ground_points(GROUND_WINDOW);
    !pts.is_empty() && pts.into_iter().all(inside)
}

/// Largest angle between a joint axis and a contact line for the joint to roll the foot about
/// the line (rad): 30°.
const ROLL_ALIGN: f64 = 30.0 * std::f64::consts::PI / 180.0;
/// A joint is at the foot (an ankle) when its axis passes closer to the contact than this share
/// of the distance from the contact to the leg's first joint: an ankle a few cm above the sole
/// is, a hip roll at the top of the leg (which balances a line foot by moving the whole leg) is
/// not.
const ANKLE_SHARE: f64 = 1.0 / 3.0;

/// The joint at the foot that can turn the foot about its degenerate contact — a line through
/// `pts` (ground contact points at the keyframe) or, when they lie within [`POINT_SPREAD`], a
/// point — or `None` when no joint can: then the line or point foot is the design (an
/// underactuated biped's blade foot whose ankle only pitches, like Cassie's; a stilt), not a
/// sole modelled too thin. A joint counts when it sits on the foot's body or an ancestor below
/// the floating base, its world axis at the keyframe is within 30° of the line (for a point:
/// more than 60° from vertical, any tilt) — a ball joint turns about every axis — and the axis
/// passes within a third of the leg's length of the contact.
pub fn ankle_turning(robot: &Robot, root: usize, pts: &[[f64; 3]]) -> Option<usize> {
    use crate::model::JointType;
    if pts.is_empty() {
        return None;
    }
    let k = pts.len() as f64;
    let c = [0, 1, 2].map(|i| pts.iter().map(|p| p[i]).sum::<f64>() / k);
    // The contact's direction: its two farthest points (horizontal); none for a point.
    let mut far = (0.0, [0.0; 3]);
    for a in pts {
        for b in pts {
            let d = [b[0] - a[0], b[1] - a[1], 0.0];
            let n = d[0].hypot(d[1]);
            if n > far.0 {
                far = (n, [d[0] / n, d[1] / n, 0.0]);
            }
        }
    }
    let line = (far.0 > POINT_SPREAD).then_some(far.1);
    // The leg's joints, foot first, up to the floating base.
    let mut chain: Vec<usize> = Vec::new();
    let mut b = root;
    let floating = robot.floating_bodies();
    while b != 0 {
        let js: Vec<&crate::model::Joint> = robot.joints.iter().filter(|j| j.body == b).collect();
        if floating.contains(&b) {
            break;
        }
        chain.extend(js.iter().map(|j| j.id));
        b = robot.bodies[b].parent;
    }
    let anchor = |j: usize| robot.key.joint_xanchor.get(j).copied().unwrap_or(c);
    let axis = |j: usize| robot.key.joint_xaxis.get(j).copied().unwrap_or([0.0, 0.0, 1.0]);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let norm = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let leg = chain.last().map_or(0.0, |&j| norm(sub(anchor(j), c)));
    chain.into_iter().find(|&j| {
        let jt = robot.joints[j].jtype;
        if !matches!(jt, JointType::Hinge | JointType::Ball) {
            return false;
        }
        let u = axis(j);
        let nu = norm(u).max(1e-12);
        let u = [u[0] / nu, u[1] / nu, u[2] / nu];
        let dist = if jt == JointType::Ball {
            norm(sub(anchor(j), c))
        } else {
            norm(cross(sub(c, anchor(j)), u))
        };
        let turns = jt == JointType::Ball
            || match line {
                Some(v) => dot(u, v).abs() >= ROLL_ALIGN.cos(),
                None => u[2].abs() <= (std::f64::consts::FRAC_PI_2 - ROLL_ALIGN).cos(),
            };
        turns && dist < ANKLE_SHARE * leg
    })
}

/// The length of the leg that carries foot body `root`, measured to `point` (world, keyframe):
/// the straight distance from the anchor of the leg's top joint — the last joint on the chain
/// from the foot up to the floating base (or the world) — to the point. `None` when no joint
/// lies on that chain (a foot welded to its base): no leg to measure.
pub fn leg_length(robot: &Robot, root: usize, point: [f64; 3]) -> Option<f64> {
    let floating = robot.floating_bodies();
    let mut top = None;
    let mut b = root;
    while b != 0 && !floating.contains(&b) {
        if let Some(j) = robot.joints.iter().rfind(|j| j.body == b) {
            top = Some(j.id);
        }
        b = robot.bodies[b].parent;
    }
    let a = robot.key.joint_xanchor.get(top?).copied()?;
    Some(((a[0] - point[0]).powi(2) + (a[1] - point[1]).powi(2) + (a[2] - point[2]).powi(2)).sqrt())
}

/// Fewest hinge or ball joints a limb off the legs needs to count as an arm (a shoulder and an
/// elbow; a head's pan and tilt count too, a single waist or tail joint does not).
pub const ARM_JOINTS: usize = 2;

/// Whether the robot is a humanoid: a left and a right foot, and at least two limbs off the
/// legs ([`Robot::limb_of`]) with [`ARM_JOINTS`] or more hinge or ball joints each — arms (and a
/// head). A limb that branches off one leg (below the bodies the feet share) belongs to that
/// leg's mechanism: Cassie's achilles rods, foot cranks and heel springs are no arms. A
/// humanoid stands on soles; an underactuated biped with no upper body (Cassie's blade feet) or
/// a quadruped is another family.
pub fn is_humanoid(robot: &Robot, feet: &[Foot]) -> bool {
    use crate::model::JointType;
    let sides = |s: Side| feet.iter().any(|f| f.side == Some(s));
    if !(sides(Side::Left) && sides(Side::Right)) {
        return false;
    }
    // The legs: every foot body and its ancestors, with how many feet each body carries.
    let mut leg = vec![0usize; robot.bodies.len()];
    for f in feet {
        for &t in &f.toes {
            leg[t] += 1;
        }
        let mut b = f.root;
        while b != 0 {
            leg[b] += 1;
            b = robot.bodies[b].parent;
        }
    }
    // A limb branching off a body that carries one foot only (a leg's push rod, crank or
    // spring of a closed-loop linkage) is part of that leg, not an arm.
    let off_one_leg = |mut b: usize| loop {
        if b == 0 {
            return false;
        }
        if leg[b] > 0 {
            return leg[b] == 1;
        }
        b = robot.bodies[b].parent;
    };
    let mut per_limb: std::collections::BTreeMap<usize, usize> = Default::default();
    for j in &robot.joints {
        if !matches!(j.jtype, JointType::Hinge | JointType::Ball)
            || j.name.is_empty()
            || leg[j.body] > 0
            || off_one_leg(j.body)
        {
            continue;
        }
        if let Some(limb) = robot.limb_of(&j.name) {
            *per_limb.entry(limb).or_default() += 1;
        }
    }
    per_limb.values().filter(|&&n| n >= ARM_JOINTS).count() >= 2
}

/// Smallest support polygon a flat foot's ground points must span, m² (1 mm²): below it the
/// contact is a line or a point.
pub const MIN_SOLE_AREA: f64 = 1e-6;

/// The foot's ground spheres below `rmin` when three or more of them span a support polygon of
/// at least [`MIN_SOLE_AREA`] at the keyframe: corner points of a sole, whose radius does not
/// matter; empty otherwise.
pub fn corner_points(robot: &Robot, foot: &Foot, rmin: f64) -> Vec<usize> {
    let small: Vec<usize> = foot
        .ground
        .iter()
        .copied()
        .filter(|&g| robot.geoms[g].gtype == GeomType::Sphere && robot.geoms[g].size[0] < rmin)
        .collect();
    let centres: Vec<[f64; 2]> = small
        .iter()
        .map(|&g| {
            let p = Placed::of(robot, g).pos;
            [p[0], p[1]]
        })
        .collect();
    if small.len() >= 3 && crate::rules::geometry::shapes::hull_area(&centres) >= MIN_SOLE_AREA {
        small
    } else {
        Vec::new()
    }
}
