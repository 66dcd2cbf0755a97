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
    /// its visual shape alone. When its colliding geoms all lie in the half of the leaf next to
    /// its joint (nearer the joint than half the visual's reach from it), they stand for
    /// nothing it touches with. When they lie at its far end, where a leaf touches, they are
    /// its contact unless, all together, they spread over less than `max_token_size` and
    /// `link_fraction` of the width of the visual (its second dimension): four corner spheres
    /// spread over a sole, a point foot's sphere across a shin's end and a fingertip pad across
    /// a finger are contacts; a single 1 mm speck at the toe of a 200 mm sole, 80 mm wide, is
    /// not. A leaf with no visual geometry (a sensor frame) is not judged.
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
    /// Whether the link carries no jointed link (judged against its visual shape only), and
    /// where its colliding geometry is.
    leaf: Leaf,
}

/// Where a token link's colliding geometry is, when the link is a leaf.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Leaf {
    /// The link carries jointed links (judged against their spacing and its visual extent).
    No,
    /// A leaf whose colliding geoms lie in the half next to its joint (judged against the
    /// visual's extent).
    AtJoint,
    /// A leaf whose colliding geoms lie at its far end, all within a speck (judged against the
    /// width of the visual there: its second dimension).
    AtEnd,
}

/// Second-largest full dimension of geom `g`'s bounding box in its own frame (m): the width
/// of a sole, of a shin's end, of a finger.
fn second_dimension(robot: &Robot, g: usize) -> f64 {
    robot.mj.geom_aabb().get(g).map_or(0.0, |bb| {
        let mut d = [bb[3], bb[4], bb[5]];
        d.sort_by(|x, y| y.partial_cmp(x).unwrap_or(std::cmp::Ordering::Equal));
        2.0 * d[1]
    })
}

/// How far the geoms `gs` spread together (m): the largest side of the world box around them,
/// each taken as a cube of its size across at its centre (one geom: its size across).
fn spread(robot: &Robot, gs: &[usize]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &g in gs {
        let Some(c) = robot.key.geom_xpos.get(g) else { continue };
        let h = across(robot, g) / 2.0;
        for k in 0..3 {
            lo[k] = lo[k].min(c[k] - h);
            hi[k] = hi[k].max(c[k] + h);
        }
    }
    (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max)
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
            // A leaf (a foot, a hand, a head): judged against its visual shape only: by size
            // when its colliding geoms all lie in the half of it next to its joint; at its far
            // end, where a leaf touches, by how far they spread across its width.
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
            if !(visual > 0.0 && a < max_size && a < fraction * visual) {
                continue;
            }
            if far < reach / 2.0 {
                out.push(Token {
                    body: b.id,
                    geom: largest,
                    across: a,
                    size: visual,
                    leaf: Leaf::AtJoint,
                });
                continue;
            }
            // At the far end: a contact there stands for the end it touches with only when it
            // covers a share of the end's width (a point foot's sphere across a shin's end,
            // pads spread over a sole's corners); a single speck at a sole's toe does not.
            let width = geoms
                .iter()
                .filter(|&&g| !colliding.contains(&g))
                .map(|&g| second_dimension(robot, g))
                .fold(0.0, f64::max);
            let spread = spread(robot, &colliding);
            if spread < max_size && spread < fraction * width {
                out.push(Token {
                    body: b.id,
                    geom: largest,
                    across: spread,
                    size: width,
                    leaf: Leaf::AtEnd,
                });
            }
            continue;
        }
        let spacing =
            own.iter().flat_map(|a| children.iter().map(move |c| dist(*a, *c))).fold(0.0, f64::max);
        let size = spacing.max(visual);
        if a < max_size && a < fraction * size {
            out.push(Token { body: b.id, geom: largest, across: a, size, leaf: Leaf::No });
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
                    match t.leaf {
                        Leaf::No => "link",
                        Leaf::AtJoint => "visual shape, at its joint",
                        Leaf::AtEnd => "wide visual end, at its tip",
                    }
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
