//! Contact parameters as MuJoCo combines them for a pair of geoms (`mj_contactParam` in
//! MuJoCo's `engine_collision_driver.c`): when the two priorities differ, the higher-priority
//! geom's condim, friction, solref and solimp are used; with equal priority, condim and each
//! friction coefficient are the larger of the two, solimp (and a standard, positive solref) is
//! the `solmix`-weighted mean, and a direct (non-positive) solref the elementwise minimum.
//!
//! An explicit `<contact><pair>` (compiled `pair_*`) overrides all of this for its two geoms
//! (`mj_collision` in the same file): MuJoCo checks the pair whatever the geoms'
//! contype/conaffinity and any `<exclude>`, with the pair's own condim, friction, solref, solimp,
//! margin and gap, and drops the dynamic contact of the same two geoms. Dynamic contacts are
//! filtered as `mj_collision` filters them ([`filtered`]): never within one weld body (geoms of
//! one body, or of bodies welded together with no joint between them), never between a body's
//! weld body and its parent's unless `<flag filterparent="disable"/>` (neither side the
//! world's), never between the bodies of an `<exclude>`, and only when the contype/conaffinity
//! masks allow it. `<flag contact="disable"/>` or `<flag constraint="disable"/>` removes every
//! contact, explicit pairs included ([`contacts_disabled`]). (MuJoCo 2's `<option collision>`
//! no longer exists: MuJoCo 3 rejects the attribute when it compiles the model.)

use mujoco_rs::prelude::MjModel;

use super::{Geom, Robot};

/// An explicit `<contact><pair>` as compiled.
#[derive(Debug, Clone, PartialEq)]
pub struct Pair {
    pub id: usize,
    pub name: String,
    pub geom1: usize,
    pub geom2: usize,
    pub condim: i32,
    /// Tangential 1 and 2, torsional, rolling 1 and 2.
    pub friction: [f64; 5],
    pub solref: [f64; 2],
    pub solimp: [f64; 5],
    pub margin: f64,
    pub gap: f64,
}

/// The compiled pairs and the excluded body pairs (lower id first).
pub(super) fn read_pairs(m: &MjModel) -> (Vec<Pair>, Vec<(usize, usize)>) {
    let (g1, g2, dim) = (m.pair_geom1(), m.pair_geom2(), m.pair_dim());
    let (fr, sr, si) = (m.pair_friction(), m.pair_solref(), m.pair_solimp());
    let (mg, gp) = (m.pair_margin(), m.pair_gap());
    let pairs = (0..g1.len())
        .map(|i| Pair {
            id: i,
            name: super::mj::name_at(m, m.name_pairadr(), i),
            geom1: g1[i].max(0) as usize,
            geom2: g2[i].max(0) as usize,
            condim: dim[i],
            friction: fr[i],
            solref: sr[i],
            solimp: si[i],
            margin: mg[i],
            gap: gp[i],
        })
        .collect();
    let excludes = m
        .exclude_signature()
        .iter()
        .map(|&s| {
            let (a, b) = (((s >> 16) & 0xFFFF) as usize, (s & 0xFFFF) as usize);
            (a.min(b), a.max(b))
        })
        .collect();
    (pairs, excludes)
}

/// MuJoCo's `mjMINVAL`.
const MINVAL: f64 = 1e-15;

/// The parameters of a contact between two geoms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Combined {
    pub condim: i32,
    /// Sliding, torsional, rolling (MuJoCo duplicates sliding and rolling to five values).
    pub friction: [f64; 3],
    pub solref: [f64; 2],
    pub solimp: [f64; 5],
    /// The geom whose parameters won on priority, if the priorities differ.
    pub by_priority: Option<usize>,
    /// The explicit `<pair>` whose parameters MuJoCo uses instead of the geoms'.
    pub pair: Option<usize>,
}

/// The parameters MuJoCo uses for a contact between `a` and `b`.
pub fn combine(a: &Geom, b: &Geom) -> Combined {
    if a.priority != b.priority {
        let w = if a.priority > b.priority { a } else { b };
        return Combined {
            condim: w.condim,
            friction: w.friction,
            solref: w.solref,
            solimp: w.solimp,
            by_priority: Some(w.id),
            pair: None,
        };
    }
    let mix = match (a.solmix >= MINVAL, b.solmix >= MINVAL) {
        (true, true) => a.solmix / (a.solmix + b.solmix),
        (false, false) => 0.5,
        (false, true) => 0.0,
        (true, false) => 1.0,
    };
    let solref = if a.solref[0] > 0.0 && b.solref[0] > 0.0 {
        [0, 1].map(|i| mix * a.solref[i] + (1.0 - mix) * b.solref[i])
    } else {
        [0, 1].map(|i| a.solref[i].min(b.solref[i]))
    };
    Combined {
        condim: a.condim.max(b.condim),
        friction: [0, 1, 2].map(|i| a.friction[i].max(b.friction[i])),
        solref,
        solimp: [0, 1, 2, 3, 4].map(|i| mix * a.solimp[i] + (1.0 - mix) * b.solimp[i]),
        by_priority: None,
        pair: None,
    }
}

/// The explicit pair of geoms `a` and `b`, if the model declares one.
pub fn pair_of(robot: &Robot, a: usize, b: usize) -> Option<&Pair> {
    robot.pairs.iter().find(|p| (p.geom1, p.geom2) == (a, b) || (p.geom1, p.geom2) == (b, a))
}

/// An `<exclude>` removes the dynamic contacts between the two bodies.
pub fn excluded(robot: &Robot, a: usize, b: usize) -> bool {
    robot.excludes.contains(&(a.min(b), a.max(b)))
}

/// The parameters of the contacts MuJoCo makes between geoms `a` and `b`: an explicit pair's, or
/// the geoms' combined ([`combine`]) when no filter removes their dynamic contact ([`filtered`]);
/// `None` when the two never touch.
pub fn contact(robot: &Robot, a: usize, b: usize) -> Option<Combined> {
    if contacts_disabled(robot) {
        return None;
    }
    if let Some(p) = pair_of(robot, a, b) {
        return Some(Combined {
            condim: p.condim,
            friction: [p.friction[0], p.friction[2], p.friction[3]],
            solref: p.solref,
            solimp: p.solimp,
            by_priority: None,
            pair: Some(p.id),
        });
    }
    let (ga, gb) = (robot.geoms.get(a)?, robot.geoms.get(b)?);
    filtered(robot, a, b).is_none().then(|| combine(ga, gb))
}

/// `mjDSBL_CONSTRAINT` and `mjDSBL_CONTACT`: either makes `mj_collision` return at once.
const DSBL_CONSTRAINT: i32 = 1;
const DSBL_CONTACT: i32 = 1 << 4;
/// `mjDSBL_FILTERPARENT`.
const DSBL_FILTERPARENT: i32 = 1 << 10;

/// The model makes no contact at all: `<flag contact="disable"/>` or `constraint="disable"`.
pub fn contacts_disabled(robot: &Robot) -> bool {
    robot.opt.disableflags & (DSBL_CONTACT | DSBL_CONSTRAINT) != 0
}

/// Why MuJoCo never makes a dynamic (contype/conaffinity) contact between two geoms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    /// `<flag contact="disable"/>` or `constraint="disable"`.
    Disabled,
    /// Same weld body: one body, or bodies welded together (no joint between them).
    Welded,
    /// One weld body is the other's parent's weld body (`filterparent`, on by default).
    Parent,
    /// An `<exclude>` of the two bodies.
    Excluded,
    /// Neither contype matches the other's conaffinity.
    Masks,
}

/// The filter that removes the dynamic contact of geoms `a` and `b` (`mj_collision`'s order),
/// `None` when MuJoCo tests the pair. An unknown geom is `Masks`.
pub fn filtered(robot: &Robot, a: usize, b: usize) -> Option<Filter> {
    if contacts_disabled(robot) {
        return Some(Filter::Disabled);
    }
    let (Some(ga), Some(gb)) = (robot.geoms.get(a), robot.geoms.get(b)) else {
        return Some(Filter::Masks);
    };
    let weld = |body: usize| robot.bodies.get(body).map_or(body, |x| x.weld);
    let (w1, w2) = (weld(ga.body), weld(gb.body));
    if w1 == w2 {
        return Some(Filter::Welded);
    }
    let wparent = |w: usize| weld(robot.bodies.get(w).map_or(0, |x| x.parent));
    if robot.opt.disableflags & DSBL_FILTERPARENT == 0
        && w1 != 0
        && w2 != 0
        && (w1 == wparent(w2) || w2 == wparent(w1))
    {
        return Some(Filter::Parent);
    }
    if excluded(robot, ga.body, gb.body) {
        return Some(Filter::Excluded);
    }
    (!may_collide(ga, gb)).then_some(Filter::Masks)
}

/// The geom can touch anything: contacts are enabled and its masks allow contacts, or an
/// explicit pair names it.
pub fn takes_part(robot: &Robot, g: usize) -> bool {
    !contacts_disabled(robot)
        && (robot.geoms.get(g).is_some_and(|x| x.collides())
            || robot.pairs.iter().any(|p| p.geom1 == g || p.geom2 == g))
}

/// The colliding geoms of bodies not fixed to the world that the pose `(xpos, xmat)` (MuJoCo's
/// geom positions and row-major frames) places entirely under a floor plane they can touch:
/// their bounding sphere below the plane's surface. MuJoCo's plane is a half-space, so a robot
/// started inside it is pushed out or falls through. Each as (geom, plane, depth of the
/// sphere's top under the surface, m), the first such plane of each geom.
pub fn buried_under_planes(
    robot: &Robot,
    xpos: &[[f64; 3]],
    xmat: &[[f64; 9]],
) -> Vec<(usize, usize, f64)> {
    let rbound = robot.mj.geom_rbound();
    let mut out = Vec::new();
    for g in &robot.geoms {
        let moving = robot.bodies.get(g.body).is_some_and(|b| b.weld != 0);
        if !moving || g.gtype == super::GeomType::Plane || !takes_part(robot, g.id) {
            continue;
        }
        let (Some(p), Some(&r)) = (xpos.get(g.id), rbound.get(g.id)) else { continue };
        for (pl, _) in ground_partners(robot, g.id) {
            if robot.geoms[pl].gtype != super::GeomType::Plane {
                continue;
            }
            let (Some(o), Some(x)) = (xpos.get(pl), xmat.get(pl)) else { continue };
            // The plane's normal is its frame's z axis (the third column, row-major).
            let n = [x[2], x[5], x[8]];
            let top = (0..3).map(|i| (p[i] - o[i]) * n[i]).sum::<f64>() + r;
            if top < 0.0 {
                out.push((g.id, pl, -top));
                break;
            }
        }
    }
    out
}

/// Masks allow a contact between the two geoms.
pub fn may_collide(a: &Geom, b: &Geom) -> bool {
    (a.contype & b.conaffinity) != 0 || (b.contype & a.conaffinity) != 0
}

/// The planes and height fields of the world and of bodies welded to it, and the world body's
/// boxes, that `geom` touches (the floor, terrain:
/// what a foot actually stands on), each with the contact's parameters ([`contact`]: through an
/// explicit pair, or by the masks and combination).
pub fn ground_partners(robot: &Robot, geom: usize) -> Vec<(usize, Combined)> {
    use super::GeomType;
    robot
        .geoms
        .iter()
        .filter(|o| {
            // A plane or height field may sit on a body welded to the world (a static floor
            // body); a box is ground only on the world body itself.
            o.id != geom
                && match o.gtype {
                    GeomType::Plane | GeomType::Hfield => {
                        robot.bodies.get(o.body).is_some_and(|b| b.weld == 0)
                    }
                    GeomType::Box => o.body == 0,
                    _ => false,
                }
        })
        .filter_map(|o| Some((o.id, contact(robot, geom, o.id)?)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::GeomType;

    fn geom(id: usize, condim: i32, friction: f64, priority: i32, solmix: f64) -> Geom {
        Geom {
            id,
            name: String::new(),
            body: 0,
            gtype: GeomType::Sphere,
            size: [0.01, 0.0, 0.0],
            contype: 1,
            conaffinity: 1,
            condim,
            friction: [friction, 0.005, 0.0001],
            group: 0,
            mesh: -1,
            rbound: 0.01,
            priority,
            solmix,
            solref: [0.02, 1.0],
            solimp: [0.9, 0.95, 0.001, 0.5, 2.0],
        }
    }

    fn load_xml(tag: &str, xml: &str) -> crate::model::Robot {
        let dir = std::env::temp_dir().join(format!("modellint_contact_{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join(format!("{tag}.xml"));
        std::fs::write(&p, xml).expect("write");
        crate::model::load(&mut crate::model::source::SourceMap::default(), &p, None)
            .expect("loads")
    }

    /// A static base on the world, a hinged link `a` with a child `a_fixed` welded to it (no
    /// joint), then hinged `b` and `c`; `<exclude>` of `a` and `c`; a mask-less geom on `c`.
    fn chain(flags: &str) -> String {
        format!(
            r#"<mujoco><option>{flags}</option><worldbody>
            <geom name="floor" type="plane" size="1 1 .1"/>
            <body name="base"><geom name="base" size=".05"/>
              <body name="a" pos="0 0 .2"><joint axis="0 1 0"/><geom name="a" size=".05"/>
                <body name="a_fixed" pos=".1 0 0"><geom name="a_fixed" size=".05"/>
                  <body name="b" pos=".1 0 0"><joint axis="0 1 0"/><geom name="b" size=".05"/>
                    <body name="c" pos=".1 0 0"><joint axis="0 1 0"/><geom name="c" size=".05"/>
                      <geom name="ghost" size=".05" contype="0" conaffinity="0"/>
            </body></body></body></body></body></worldbody>
            <contact><exclude body1="a" body2="c"/></contact></mujoco>"#
        )
    }

    #[test]
    fn dynamic_contacts_are_filtered_as_mujoco_filters_them() {
        let r = load_xml("filters", &chain(""));
        let g = |n: &str| r.geoms.iter().find(|x| x.name == n).expect("geom").id;
        // The static base is welded to the world: it never touches the floor.
        assert_eq!(filtered(&r, g("base"), g("floor")), Some(Filter::Welded));
        // A body and the child welded to it are one rigid part.
        assert_eq!(filtered(&r, g("a"), g("a_fixed")), Some(Filter::Welded));
        // `b`'s parent is `a_fixed`, whose weld body is `a`: parent filtering.
        assert_eq!(filtered(&r, g("a_fixed"), g("b")), Some(Filter::Parent));
        assert_eq!(filtered(&r, g("a"), g("b")), Some(Filter::Parent));
        // The parent filter never applies to a world-welded parent: `a` touches the base.
        assert_eq!(filtered(&r, g("a"), g("base")), None);
        assert_eq!(filtered(&r, g("a"), g("c")), Some(Filter::Excluded));
        assert_eq!(filtered(&r, g("a_fixed"), g("c")), None);
        assert_eq!(filtered(&r, g("b"), g("ghost")), Some(Filter::Parent));
        assert_eq!(filtered(&r, g("a_fixed"), g("ghost")), Some(Filter::Masks));
        assert!(contact(&r, g("c"), g("floor")).is_some());
        assert!(takes_part(&r, g("c")));
    }

    #[test]
    fn filterparent_and_contact_flags_are_read() {
        let r = load_xml("noparent", &chain(r#"<flag filterparent="disable"/>"#));
        let g = |n: &str| r.geoms.iter().find(|x| x.name == n).expect("geom").id;
        assert_eq!(filtered(&r, g("a_fixed"), g("b")), None);
        // Welded bodies stay filtered whatever the flag.
        assert_eq!(filtered(&r, g("a"), g("a_fixed")), Some(Filter::Welded));
        let r = load_xml("nocontact", &chain(r#"<flag contact="disable"/>"#));
        let g = |n: &str| r.geoms.iter().find(|x| x.name == n).expect("geom").id;
        assert_eq!(filtered(&r, g("c"), g("floor")), Some(Filter::Disabled));
        assert!(contact(&r, g("c"), g("floor")).is_none());
        assert!(!takes_part(&r, g("c")));
    }

    /// MuJoCo itself decides: every geom overlaps every other at the origin, so the pairs
    /// `mj_collision` reports are exactly the ones its filters leave in.
    #[test]
    fn filters_agree_with_the_contacts_mujoco_makes() {
        for flags in ["", r#"<flag filterparent="disable"/>"#] {
            let xml = chain(flags).replace(r#"pos="0 0 .2""#, "").replace(r#"pos=".1 0 0""#, "");
            let r = load_xml(if flags.is_empty() { "overlap" } else { "overlap_np" }, &xml);
            let mut d = mujoco_rs::prelude::MjData::new(&r.mj);
            d.forward();
            let made: std::collections::BTreeSet<(usize, usize)> = d
                .contact()
                .iter()
                .map(|c| (c.geom1.min(c.geom2) as usize, c.geom1.max(c.geom2) as usize))
                .collect();
            let n = r.geoms.len();
            let ours: std::collections::BTreeSet<(usize, usize)> = (0..n)
                .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
                .filter(|&(a, b)| filtered(&r, a, b).is_none())
                .collect();
            assert!(!made.is_empty());
            assert_eq!(made, ours, "flags {flags:?}");
        }
    }

    #[test]
    fn equal_priority_takes_the_larger_condim_and_friction() {
        let foot = geom(1, 1, 0.6, 0, 1.0);
        let floor = geom(0, 3, 1.0, 0, 1.0);
        let c = combine(&foot, &floor);
        assert_eq!(c.condim, 3);
        assert_eq!(c.friction[0], 1.0);
        assert_eq!(c.by_priority, None);
        assert_eq!(combine(&floor, &foot), c);
    }

    #[test]
    fn higher_priority_wins_whole() {
        let foot = geom(1, 1, 0.6, 1, 1.0);
        let floor = geom(0, 3, 1.0, 0, 1.0);
        let c = combine(&foot, &floor);
        assert_eq!((c.condim, c.friction[0], c.by_priority), (1, 0.6, Some(1)));
    }

    #[test]
    fn solref_and_solimp_mix_by_solmix() {
        let mut a = geom(1, 3, 1.0, 0, 3.0);
        let mut b = geom(0, 3, 1.0, 0, 1.0);
        a.solref = [0.04, 1.0];
        b.solref = [0.02, 2.0];
        a.solimp[0] = 0.8;
        b.solimp[0] = 0.9;
        let c = combine(&a, &b);
        assert!((c.solref[0] - 0.035).abs() < 1e-12 && (c.solref[1] - 1.25).abs() < 1e-12);
        assert!((c.solimp[0] - 0.825).abs() < 1e-12);
        // Direct (negative) solref: elementwise minimum.
        a.solref = [-1000.0, -10.0];
        b.solref = [-500.0, -20.0];
        assert_eq!(combine(&a, &b).solref, [-1000.0, -20.0]);
        // Both solmix zero: half and half.
        a.solmix = 0.0;
        b.solmix = 0.0;
        a.solimp[0] = 0.8;
        assert!((combine(&a, &b).solimp[0] - 0.85).abs() < 1e-12);
    }
}
