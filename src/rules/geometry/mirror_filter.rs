//! Where `mirror-asymmetry` compares a mirror pair's collision filtering: what each body of a
//! pair can touch, as MuJoCo filters contacts (`contype`/`conaffinity` masks, `<exclude>`,
//! explicit `<contact><pair>`s, welded and parent bodies: `model::contact::contact`), against
//! what its mirror can touch, the other bodies taken through their own mirrors.

use crate::finding::{Finding, Subject};
use crate::model::Robot;
use crate::model::contact::contact;
use crate::model::mirror;
use crate::model::mjcf::ElemKind;
use crate::rules::Context;
use crate::spec::Spec;

/// The body each body's contacts are compared through: its mirror for a paired body, itself for
/// a body on no side (no ancestor of it is paired, its name has no side marker: the torso, the
/// world, scenery), `None` for an unpaired body below a paired one or named for a side (a side's
/// part whose mirror the names do not give).
fn mirror_map(robot: &Robot, spec: Option<&Spec>, pairs: &[(usize, usize)]) -> Vec<Option<usize>> {
    let n = robot.bodies.len();
    let mut partner: Vec<Option<usize>> = vec![None; n];
    for &(l, r) in pairs {
        partner[l] = Some(r);
        partner[r] = Some(l);
    }
    (0..n)
        .map(|b| {
            if partner[b].is_some() {
                return partner[b];
            }
            // A body whose name gives a side but no partner exists: its mirror is unknown.
            if mirror::side_of(&robot.bodies[b].name, spec).is_some() {
                return None;
            }
            let mut a = b;
            while a != 0 {
                a = robot.bodies[a].parent;
                if partner[a].is_some() {
                    return None;
                }
            }
            Some(b)
        })
        .collect()
}

/// `touch[a][b]`: some geom of body `a` and some geom of body `b` make contacts in MuJoCo.
fn touch_matrix(robot: &Robot) -> Vec<Vec<bool>> {
    let n = robot.bodies.len();
    let mut t = vec![vec![false; n]; n];
    for (i, a) in robot.geoms.iter().enumerate() {
        for b in &robot.geoms[i + 1..] {
            if a.body != b.body && !t[a.body][b.body] && contact(robot, a.id, b.id).is_some() {
                t[a.body][b.body] = true;
                t[b.body][a.body] = true;
            }
        }
    }
    t
}

/// Bodies `a` and `b` never collide by the tree's structure, whatever the file's filtering: one
/// weld body, or one's weld body the other's parent's (`filterparent`). Two sides whose trees
/// differ (a limb mounted through an extra bracket) differ here; that is no filtering the file
/// writes, and such a pair is not compared.
fn structural(robot: &Robot, a: usize, b: usize) -> bool {
    let weld = |x: usize| robot.bodies.get(x).map_or(x, |y| y.weld);
    let (w1, w2) = (weld(a), weld(b));
    let parent = |w: usize| weld(robot.bodies.get(w).map_or(0, |y| y.parent));
    w1 == w2 || (w1 != 0 && w2 != 0 && (w1 == parent(w2) || w2 == parent(w1)))
}

/// "contype 1, conaffinity 3": the distinct masks of a body's geoms.
fn masks(robot: &Robot, body: usize) -> String {
    let mut v: Vec<(i32, i32)> =
        robot.geoms.iter().filter(|g| g.body == body).map(|g| (g.contype, g.conaffinity)).collect();
    v.sort();
    v.dedup();
    let s: Vec<String> = v.iter().map(|(t, a)| format!("contype {t}, conaffinity {a}")).collect();
    s.join("; ")
}

fn names(robot: &Robot, v: &[usize]) -> String {
    const SHOWN: usize = 4;
    let mut s: Vec<String> = v
        .iter()
        .take(SHOWN)
        .map(|&b| match robot.bodies[b].name.as_str() {
            "" if b == 0 => "the world".to_string(),
            "" => format!("body #{b}"),
            n => format!("`{n}`"),
        })
        .collect();
    if v.len() > SHOWN {
        s.push(format!("{} more", v.len() - SHOWN));
    }
    s.join(", ")
}

/// The first mirror pair (in `pairs`' order) whose bodies can touch different things: a body
/// `x` the left one touches while the right one does not touch `x`'s mirror, or the other way
/// round. Bodies whose mirror is unknown are not compared; nor is a pair of which only one side
/// has geoms (the collision-geoms finding). The finding names both bodies, what only each
/// touches and their masks, with how many other pairs differ.
pub(super) fn filtering_differs(cx: &Context, pairs: &[(usize, usize)]) -> Option<Finding> {
    let robot = cx.robot;
    if pairs.is_empty() || robot.geoms.is_empty() {
        return None;
    }
    let map = mirror_map(robot, cx.spec, pairs);
    let touch = touch_matrix(robot);
    let has_geoms = |b: usize| robot.geoms.iter().any(|g| g.body == b);
    // (left, right, what only the left touches with its mirror, the same for the right), each
    // as (the body on the left's side, the body on the right's side).
    type Only = Vec<(usize, usize)>;
    let mut differing: Vec<(usize, usize, Only, Only)> = Vec::new();
    for &(l, r) in pairs {
        if !has_geoms(l) || !has_geoms(r) {
            continue;
        }
        let (mut only_l, mut only_r) = (Vec::new(), Vec::new());
        for (x, m) in map.iter().enumerate() {
            let Some(xm) = *m else { continue };
            if structural(robot, l, x) || structural(robot, r, xm) {
                continue;
            }
            // `x` on the left's side of the comparison, `xm` on the right's.
            match (touch[l][x], touch[r][xm]) {
                (true, false) => only_l.push((x, xm)),
                (false, true) => only_r.push((x, xm)),
                _ => {}
            }
        }
        if !only_l.is_empty() || !only_r.is_empty() {
            differing.push((l, r, only_l, only_r));
        }
    }
    let (l, r, only_l, only_r) = differing.first()?.clone();
    let (ln, rn) = (&robot.bodies[l].name, &robot.bodies[r].name);
    let left_of = |v: &Only| v.iter().map(|p| p.0).collect::<Vec<_>>();
    let right_of = |v: &Only| v.iter().map(|p| p.1).collect::<Vec<_>>();
    let mut parts = Vec::new();
    if !only_r.is_empty() {
        parts.push(format!(
            "touches {} where `{ln}` does not touch {}",
            names(robot, &right_of(&only_r)),
            names(robot, &left_of(&only_r))
        ));
    }
    if !only_l.is_empty() {
        parts.push(format!(
            "does not touch {} where `{ln}` touches {}",
            names(robot, &right_of(&only_l)),
            names(robot, &left_of(&only_l))
        ));
    }
    let (mr, ml) = (masks(robot, r), masks(robot, l));
    let how = if mr == ml {
        format!("both with {mr}: an <exclude> or <contact><pair> makes the difference")
    } else {
        format!("{mr} against {ml}")
    };
    let msg = format!(
        "body `{rn}` collides differently from its mirror `{ln}`: it {} ({how})",
        parts.join(", and ")
    );
    let first_geom = |b: usize| robot.geoms.iter().find(|g| g.body == b);
    let g = first_geom(r)?;
    let lg = first_geom(l)?;
    let (lloc, _) = robot.attr_loc(ElemKind::Geom, lg.id, &lg.name, "conaffinity");
    let more = differing.len() - 1;
    let others =
        if more > 0 { format!("; {more} other mirror pair(s) differ too") } else { String::new() };
    Some(
        cx.at_attr(ElemKind::Geom, g.id, &g.name, "conaffinity", msg)
            .label(format!("{mr} on `{rn}`"))
            .secondary(lloc, format!("mirror `{ln}`: {ml}"))
            .note(format!(
                "MuJoCo makes a contact between two geoms only when one's contype shares a bit with the other's conaffinity (and no <exclude>, welded or parent body filters it; an explicit <contact><pair> always collides): the two sides of a mirror-symmetric robot then collide with different parts, so one leg can pass through what stops the other, and a policy learns the difference{others}"
            ))
            .help("give both sides the same contype/conaffinity (one <default class> for both legs, or bits assigned by part rather than by side), and mirror any <exclude> or <pair>")
            .subject(Subject::Body(r))
            .with("differing_pairs", differing.len() as f64),
    )
}
