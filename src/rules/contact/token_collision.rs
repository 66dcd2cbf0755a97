use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{GeomType, Robot};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds links of a robot whose only collision geometry is a token: every colliding geom
    /// of the link (the jointed body and the bodies welded to it) is smaller across than
    /// `max_token_size` (5 mm) and than `link_fraction` (1/20) of the link's own size, the
    /// larger of the distance from the link's joint to the joints of the links it carries and
    /// the extent of its visual (non-colliding) geometry. Such a link counts as colliding (so
    /// `links-without-collision` is silent) but nothing can touch it: an exporter's
    /// placeholder (1 mm boxes on hips, thighs and calves) in place of the link's shape. A
    /// leaf (a link that carries no jointed link: a foot, a hand, a head) is judged against
    /// its visual shape alone, and only when its colliding geoms all lie in the half of the
    /// leaf next to its joint (nearer the joint than half the visual's reach from it): a
    /// contact sphere at a point foot's or toe's tip and a fingertip pad are where the leaf
    /// touches, at its far end; a leaf with no visual geometry (a sensor frame) is not judged.
    /// One finding lists every such link.
    ///
    /// ## Why is this bad?
    /// The legs pass through each other, through obstacles and through the floor in a fall,
    /// and self-collision checks report nothing: a policy learns motions (crossed legs, knees
    /// through the ground) the real robot cannot make, and contact-rich tasks see a link as
    /// a point.
    ///
    /// ## How it is confirmed
    /// Static: the compiled geoms' bounding boxes, contact masks and the joint anchors at the
    /// keyframe (or qpos0).
    ///
    /// ## How to fix
    /// Give each link collision geometry that covers its visual shape (capsules or boxes along
    /// the link, or its convex mesh), and exclude the contacts between neighbours that must
    /// overlap with `<contact><exclude>`.
    pub TokenCollisionGeometry {
        id: "token-collision-geometry",
        group: "contact",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("max_token_size", 0.005, "m", Domain::POSITIVE, "a collision geom smaller than this across (a bolt head) covers no part of a link"),
            opt("link_fraction", 0.05, "of the link's size", Domain::POSITIVE_FRACTION, "a link's collision geometry smaller than this share of the link's size stands for none"),
        ],
    }
}

/// Largest full dimension of geom `g`'s bounding box in its own frame (m).
fn across(robot: &Robot, g: usize) -> f64 {
    robot.mj.geom_aabb().get(g).map_or(0.0, |bb| 2.0 * bb[3].max(bb[4]).max(bb[5]))
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// One token link: (jointed body, largest colliding geom, its size across, the link's size).
struct Token {
    body: usize,
    geom: usize,
    across: f64,
    size: f64,
    /// A link that carries no jointed link (judged against its visual shape only).
    leaf: bool,
}

fn token_links(robot: &Robot, max_size: f64, fraction: f64) -> Vec<Token> {
    let mut out = Vec::new();
    for b in robot.bodies.iter().filter(|b| b.id != 0 && b.weld == b.id) {
        if !robot.joints.iter().any(|j| j.body == b.id) {
            continue;
        }
        let group: Vec<usize> =
            robot.bodies.iter().filter(|x| x.weld == b.id).map(|x| x.id).collect();
        let geoms: Vec<usize> = robot
            .geoms
            .iter()
            .filter(|g| group.contains(&g.body))
            .filter(|g| !matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
            .map(|g| g.id)
            .collect();
        let colliding: Vec<usize> = geoms
            .iter()
            .copied()
            .filter(|&g| crate::model::contact::takes_part(robot, g))
            .collect();
        let Some(&largest) = colliding.iter().max_by(|&&x, &&y| {
            across(robot, x).partial_cmp(&across(robot, y)).unwrap_or(std::cmp::Ordering::Equal)
        }) else {
            continue;
        };
        // The link's joints and those of the links it carries.
        let own: Vec<[f64; 3]> = robot
            .joints
            .iter()
            .filter(|j| j.body == b.id)
            .filter_map(|j| robot.key.joint_xanchor.get(j.id).copied())
            .collect();
        let children: Vec<[f64; 3]> = robot
            .joints
            .iter()
            .filter(|j| {
                let jb = robot.bodies.get(j.body);
                jb.is_some_and(|x| x.weld == x.id && group.contains(&x.parent))
            })
            .filter_map(|j| robot.key.joint_xanchor.get(j.id).copied())
            .collect();
        let visual = geoms
            .iter()
            .filter(|&&g| !colliding.contains(&g))
            .map(|&g| across(robot, g))
            .fold(0.0, f64::max);
        let a = across(robot, largest);
        if children.is_empty() {
            // A leaf (a foot, a hand, a head): judged against its visual shape only, and only
            // when its colliding geoms all lie in the half of it next to its joint: a contact
            // sphere at a point foot's tip or a fingertip pad is where the leaf touches.
            let Some(&joint) = own.first() else { continue };
            let reach = geoms
                .iter()
                .filter(|&&g| !colliding.contains(&g))
                .filter_map(|&g| {
                    let c = robot.key.geom_xpos.get(g)?;
                    Some(dist(joint, *c) + across(robot, g) / 2.0)
                })
                .fold(0.0, f64::max);
            let far = colliding
                .iter()
                .filter_map(|&g| robot.key.geom_xpos.get(g).map(|c| dist(joint, *c)))
                .fold(0.0, f64::max);
            if visual > 0.0 && a < max_size && a < fraction * visual && far < reach / 2.0 {
                out.push(Token { body: b.id, geom: largest, across: a, size: visual, leaf: true });
            }
            continue;
        }
        let spacing =
            own.iter().flat_map(|a| children.iter().map(move |c| dist(*a, *c))).fold(0.0, f64::max);
        let size = spacing.max(visual);
        if a < max_size && a < fraction * size {
            out.push(Token { body: b.id, geom: largest, across: a, size, leaf: false });
        }
    }
    out
}

impl Rule for TokenCollisionGeometry {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let tokens = token_links(robot, cx.opt("max_token_size"), cx.opt("link_fraction"));
        let Some(first) = tokens.first() else { return };
        let mm = |x: f64| fmt_num(x * 1000.0, 3);
        let list: Vec<String> = tokens
            .iter()
            .map(|t| {
                format!(
                    "`{}` ({} mm on a {} mm {})",
                    robot.body_name(t.body),
                    mm(t.across),
                    mm(t.size),
                    if t.leaf { "visual shape, at its joint" } else { "link" }
                )
            })
            .collect();
        let ratio =
            tokens.iter().map(|t| t.size / t.across.max(1e-12)).fold(f64::INFINITY, f64::min);
        let g = &robot.geoms[first.geom];
        let msg = format!(
            "{} link{} collide only through geometry {}× or more smaller than the link: {}",
            tokens.len(),
            if tokens.len() == 1 { "" } else { "s" },
            fmt_num(ratio, 3),
            list.join(", ")
        );
        let f = cx
            .at_attr(ElemKind::Geom, g.id, &g.name, "size", msg)
            .label(format!("{} mm across: stands for the whole link", mm(first.across)))
            .note("the link counts as colliding, but nothing can touch it: limbs pass through each other and through obstacles")
            .help("give each link collision geometry that covers its visual shape (capsules or boxes along the link, or its convex mesh)")
            .subject(Subject::Body(first.body))
            .measured(tokens.len() as f64, "links")
            .with("smallest_ratio", ratio)
            .with("first_across", first.across)
            .with("first_size", first.size);
        out.push(f);
    }
}
