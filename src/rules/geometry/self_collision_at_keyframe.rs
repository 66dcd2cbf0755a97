use std::collections::BTreeMap;

use mujoco_rs::prelude::*;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::model::{Format, GeomType, Robot, contact};
use crate::probe::penetration::{self, Penetration};
use crate::probe::{Claim, KeyframePenetration, Preconditions, Verdict};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Reports pairs of the robot's own collision geoms that penetrate each other at the standing
    /// keyframe (or `qpos0`) by at least `min_depth`. The pairs are MuJoCo's own contact list
    /// after `mj_forward` at the keyframe, so every filter MuJoCo applies is honoured: same body,
    /// parent/child bodies (unless `filterparent` is disabled), welded bodies,
    /// contype/conaffinity masks and `<exclude>` pairs. Contacts with the world body (the floor
    /// plane, terrain) and with planes and height fields are ignored: ground contact in stance
    /// is expected. In a URDF every geom is the robot's (the importer adds no floor; the root
    /// link, fixed to the world on import, compiles onto the world body), so the root link's
    /// geoms are judged against every link but those hung on the root by one joint, which a
    /// floating root would filter as parent and child. One case the contact
    /// list misses is added: two geoms MuJoCo tests that are the same shape (type, size, mesh)
    /// at exactly the same world pose. Two coincident convex meshes are a degenerate case of
    /// MuJoCo's convex collision (GJK/EPA) and get no contact at the keyframe, while coincident
    /// boxes do (box-box collision is analytic, 100 mm deep for 100 mm cubes); a millimetre of
    /// motion gives the meshes the same depth. Such a pair is reported with the shape's
    /// smallest extent as its depth.
    ///
    /// ## Why is this bad?
    /// Geoms that overlap in the initial pose produce large repulsive forces on the first step:
    /// the robot jumps or twitches at every reset, training episodes start from a state the
    /// hardware never sees, and the solver spends its iterations on an internal fight. Usually
    /// the cause is an oversized collision primitive, a wrong `pos`, or a missing `<exclude>`
    /// between adjacent links that cannot actually touch.
    ///
    /// ## How it is confirmed
    /// Static (MuJoCo collision at the keyframe); probe `keyframe-penetration` puts the robot on a
    /// stand at the keyframe, reads MuJoCo's contact force between the pair and steps 0.1 s to
    /// measure how fast the two geoms are pushed apart (confirmed from 1 cm/s).
    ///
    /// ## How to fix
    /// Shrink or move the overlapping collision geoms so they clear each other in the keyframe
    /// pose; if the two links can never touch on the hardware, add
    /// `<contact><exclude body1=".." body2=".."/></contact>` or set contype/conaffinity so the
    /// pair is filtered.
    pub SelfCollisionAtKeyframe {
        id: "self-collision-at-keyframe",
        group: "geometry",
        level: Severity::Warning,
        probe: KeyframePenetration,
        options: [opt("min_depth", 0.001, "m", Domain::NON_NEGATIVE, "smallest penetration depth reported")],
    }
}

/// How deep a pair of geoms overlaps at the keyframe, and whether it is a pair of identical
/// shapes at one pose that MuJoCo's contact list leaves out.
#[derive(Debug, Clone, Copy)]
pub struct Overlap {
    pub depth: f64,
    /// The same convex shape (type, size, mesh) at the same world pose: the convex collision of
    /// two coincident shapes is degenerate (the support points of the Minkowski difference are
    /// symmetric about the origin) and MuJoCo's convex-convex path (mesh geoms) returns no
    /// contact, while any motion of either geom puts them this deep.
    pub coincident: bool,
}

/// Deepest penetration per geom pair (geom ids ascending) at the keyframe, ground excluded
/// ([`ground_pair`], [`urdf_root_and_link`]).
pub fn keyframe_penetrations(robot: &Robot) -> BTreeMap<(usize, usize), Overlap> {
    let m = &robot.mj;
    let mut d = MjData::new(m);
    if let Some(k) = robot.key.key {
        let _ = d.reset_keyframe(k);
    }
    d.forward();
    let cons = d.contact();
    let mut out: BTreeMap<(usize, usize), Overlap> = BTreeMap::new();
    let ground = |a: &crate::model::Geom, b: &crate::model::Geom| {
        ground_pair(robot, a) || ground_pair(robot, b) || urdf_root_and_link(robot, a, b)
    };
    for c in cons {
        let (a, b) = (c.geom1, c.geom2);
        if a < 0 || b < 0 {
            continue;
        }
        let (a, b) = (a.min(b) as usize, a.max(b) as usize);
        let (ga, gb) = (&robot.geoms[a], &robot.geoms[b]);
        if ground(ga, gb) {
            continue;
        }
        let depth = -c.dist;
        let e =
            out.entry((a, b)).or_insert(Overlap { depth: f64::NEG_INFINITY, coincident: false });
        e.depth = e.depth.max(depth);
    }
    // Identical shapes at one pose that MuJoCo tests but lists no contact for.
    let (xpos, xmat, aabb) = (d.geom_xpos(), d.geom_xmat(), m.geom_aabb());
    let same = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| p == q);
    for (i, ga) in robot.geoms.iter().enumerate() {
        for gb in &robot.geoms[i + 1..] {
            let (a, b) = (ga.id, gb.id);
            if out.contains_key(&(a, b))
                || ground(ga, gb)
                || ga.gtype != gb.gtype
                || ga.size != gb.size
                || (ga.gtype == GeomType::Mesh && ga.mesh != gb.mesh)
                || (contact::filtered(robot, a, b).is_some()
                    && contact::pair_of(robot, a, b).is_none())
            {
                continue;
            }
            let (Some(pa), Some(pb), Some(ra), Some(rb), Some(bx)) =
                (xpos.get(a), xpos.get(b), xmat.get(a), xmat.get(b), aabb.get(a))
            else {
                continue;
            };
            if !same(pa, pb) || !same(ra, rb) {
                continue;
            }
            let depth = 2.0 * bx[3].min(bx[4]).min(bx[5]);
            if depth.is_finite() && depth > 0.0 {
                out.insert((a, b), Overlap { depth, coincident: true });
            }
        }
    }
    out
}

/// A geom whose contacts are the ground's: a plane or height field, or a geom of the world
/// body in an MJCF (the floor, terrain, scene props). In a URDF every geom is the robot's:
/// MuJoCo's importer adds no floor, and the root link, fixed to the world on import, compiles
/// onto the world body.
fn ground_pair(robot: &Robot, g: &crate::model::Geom) -> bool {
    matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
        || (g.body == 0 && robot.format != Format::Urdf)
}

/// In a URDF, a geom of the root link (welded to the world on import) and a geom of a link
/// hung on the root by one joint: a floating root would filter them as parent and child, so
/// the fixed import's contact between them is not the robot's self-collision.
fn urdf_root_and_link(robot: &Robot, a: &crate::model::Geom, b: &crate::model::Geom) -> bool {
    if robot.format != Format::Urdf {
        return false;
    }
    let weld = |g: &crate::model::Geom| robot.bodies.get(g.body).map_or(0, |x| x.weld);
    let on_root = |g: &crate::model::Geom| {
        let w = weld(g);
        w != 0
            && robot
                .bodies
                .get(w)
                .and_then(|x| robot.bodies.get(x.parent))
                .is_some_and(|p| p.weld == 0)
    };
    (weld(a) == 0 && on_root(b)) || (weld(b) == 0 && on_root(a))
}

fn gdesc(robot: &Robot, g: usize) -> String {
    let geom = &robot.geoms[g];
    if geom.name.is_empty() && geom.body == 0 && robot.format == Format::Urdf {
        // The importer compiles the root link (fixed to the world) onto the world body.
        let child = |l: &str| {
            robot
                .tree
                .children_tagged("joint")
                .any(|j| j.children_tagged("child").any(|c| c.get("link") == Some(l)))
        };
        let root =
            robot.tree.children_tagged("link").filter_map(|l| l.get("name")).find(|l| !child(l));
        if let Some(root) = root {
            return format!(
                "no. {} of the world body (root link `{root}` and the links fixed to it)",
                robot.geom_no(g)
            );
        }
    }
    if geom.name.is_empty() {
        return robot.unnamed_geom(g);
    }
    format!("`{}` (body {})", geom.name, robot.body_name(geom.body))
}

/// What the `keyframe-penetration` probe checks: MuJoCo pushes the overlapping pair apart at the
/// keyframe.
#[derive(Debug)]
pub struct PushedApart {
    pub geoms: (usize, usize),
}

impl Claim for PushedApart {
    type Probe = KeyframePenetration;
    fn key(&self, _: &Loaded) -> Result<(usize, usize), &'static str> {
        Ok(self.geoms)
    }
    fn judge(&self, _: &Loaded, p: &Penetration) -> Verdict {
        let mut m = BTreeMap::new();
        m.insert("depth_m".into(), -p.depth0);
        m.insert("contact_force_n".into(), p.contact_force);
        m.insert("separation_speed_m_s".into(), p.separation_speed);
        m.insert("distance_after_m".into(), p.dist_end);
        if let Some(t) = p.clear_time {
            m.insert("clear_time_s".into(), t);
        }
        let pushes = p.contact_force > 0.0; // NaN: no force
        if p.contact_depth.is_finite() {
            m.insert("contact_depth_m".into(), p.contact_depth);
        }
        let overlap = p.depth0 < 0.0;
        let detail = if overlap {
            format!(
                "mj_geomDistance finds the pair's compiled geometry overlapping by {} m at the keyframe",
                fmt_num(-p.depth0, 3)
            )
        } else {
            let dist = fmt_num(p.depth0.max(0.0), 3);
            if p.contact_depth.is_finite() {
                format!(
                    "mj_geomDistance finds no overlap of the pair at the keyframe (distance {dist} m) while MuJoCo's contact list has them {} m deep: the two disagree (coincident or degenerate convex shapes), so the probe cannot measure how the pair separates",
                    fmt_num(p.contact_depth, 3)
                )
            } else {
                format!(
                    "mj_geomDistance finds no overlap of the pair at the keyframe (distance {dist} m) and MuJoCo's contact list has no contact of the pair either (coincident convex shapes, a degenerate case of the convex collision), so the probe cannot measure how the pair separates"
                )
            }
        };
        let pre = Preconditions::new().check("overlap_at_keyframe", overlap, detail);
        if !pushes {
            return Verdict::refuted_or_inconclusive(
                &pre,
                m,
                "MuJoCo applies no force between the pair at the keyframe (the contact is inactive, e.g. its gap exceeds the overlap)",
            );
        }
        let clears = p
            .clear_time
            .map(|t| format!(", clear of each other after {} ms", fmt_num(t * 1000.0, 3)))
            .unwrap_or_default();
        let motion = if p.separation_speed >= penetration::JOLT_SPEED {
            format!("the pair jumps apart at up to {} m/s{clears}", fmt_num(p.separation_speed, 3))
        } else {
            format!(
                "the joints cannot separate them (at most {} m/s over {} s): the force and its friction act on every motion of the two links",
                fmt_num(p.separation_speed, 3),
                fmt_num(penetration::DURATION, 3)
            )
        };
        Verdict::confirmed(
            &pre,
            m,
            format!(
                "at the keyframe (base on a stand, commands held) MuJoCo pushes the pair apart with {} N; {motion}",
                fmt_num(p.contact_force, 4)
            ),
        )
    }
}

impl Rule for SelfCollisionAtKeyframe {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let min_depth = cx.opt("min_depth");
        let pose = match &robot.key.key_name {
            Some(k) if !k.is_empty() => format!("keyframe `{k}`"),
            Some(_) => "the keyframe".to_string(),
            None => "qpos0".to_string(),
        };
        for ((a, b), o) in keyframe_penetrations(robot) {
            // A URDF's root-link geom (on the world body) has no element of its own to point
            // at: the finding stands on the link's geom, and names the other in its message.
            let root_geom = |g: usize| robot.format == Format::Urdf && robot.geoms[g].body == 0;
            let (a, b) = if root_geom(a) { (b, a) } else { (a, b) };
            let depth = o.depth;
            if depth < min_depth {
                continue;
            }
            let gb = &robot.geoms[b];
            let msg = if o.coincident {
                format!(
                    "collision geoms {} and {} are the same shape at the same pose at {pose}: MuJoCo lists no contact between coincident convex shapes, but any motion of either puts them {} mm deep",
                    gdesc(robot, a),
                    gdesc(robot, b),
                    fmt_num(depth * 1000.0, 3)
                )
            } else {
                format!(
                    "collision geoms {} and {} penetrate by {} mm at {pose}",
                    gdesc(robot, a),
                    gdesc(robot, b),
                    fmt_num(depth * 1000.0, 3)
                )
            };
            let note = if o.coincident {
                "two identical convex shapes at one pose are a degenerate case of MuJoCo's convex collision (GJK/EPA on the Minkowski difference): at the keyframe it reports no contact, and the first millimetre of motion turns it into a contact as deep as the shape, which pushes the links apart with large forces"
            } else {
                "overlapping geoms in the initial pose push apart with large contact forces on the first step, so every episode starts with a jolt the hardware never experiences"
            };
            let mut f = cx.at_elem(ElemKind::Geom, a, &robot.geoms[a].name, msg).label(format!(
                "penetrates {} by {} mm",
                gdesc(robot, b),
                fmt_num(depth * 1000.0, 3)
            ));
            if !root_geom(b) {
                f = f.secondary(robot.elem_loc(ElemKind::Geom, b, &gb.name), "the other geom");
            }
            out.push(
                f.note(note)
                    .help("shrink or move the geoms so they clear each other in this pose, or filter the pair with <contact><exclude body1=.. body2=../></contact> or contype/conaffinity if the links cannot touch on the hardware")
                    .subject(Subject::Geom(a))
                    .claim(PushedApart { geoms: (a, b) })
                    .measured(depth, "m")
                    .expected(0.0, "m")
                    .with("depth_m", depth)
                    .with("geom2", b as f64),
            );
        }
    }
}
