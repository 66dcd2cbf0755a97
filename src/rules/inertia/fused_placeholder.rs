//! `inertia-exceeds-geometry`'s fused case: a URDF link fixed to another (MuJoCo's importer
//! fuses the two into one body) that is much lighter than its partner yet carries a radius of
//! gyration larger than the partner's own, and so adds a sizeable share to the fused body's
//! moments: a placeholder inertia (a 1 g board with 1e-5 kg·m², a radius of gyration of 0.1 m,
//! fused into a 0.108 kg frame of 0.046 m).

use nalgebra::{Matrix3, SymmetricEigen};

use crate::finding::{Finding, Subject};
use crate::model::Format;
use crate::model::source::{Loc, XNode};
use crate::rules::Context;
use crate::util::fmt_num;

/// A link's stated mass (kg), principal moments (kg·m², ascending) and where its `<inertia>`
/// is written.
struct Stated {
    mass: f64,
    moments: [f64; 3],
    at: Loc,
}

fn stated(link: &XNode) -> Option<Stated> {
    let inertial = link.children_tagged("inertial").next()?;
    let num = |n: &XNode, a: &str| n.get(a).and_then(|v| v.trim().parse::<f64>().ok());
    let mass = num(inertial.children_tagged("mass").next()?, "value")?;
    let i = inertial.children_tagged("inertia").next()?;
    let g = |a: &str| num(i, a).unwrap_or(0.0);
    let m = Matrix3::new(
        g("ixx"),
        g("ixy"),
        g("ixz"),
        g("ixy"),
        g("iyy"),
        g("iyz"),
        g("ixz"),
        g("iyz"),
        g("izz"),
    );
    let mut e: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
    e.sort_by(f64::total_cmp);
    let ok = mass.is_finite() && mass > 0.0 && e.iter().all(|x| x.is_finite() && *x > 0.0);
    ok.then_some(Stated { mass, moments: [e[0], e[1], e[2]], at: i.loc })
}

/// One finding per link that lighter links fixed to it distort (`min_share`: the least share
/// of its smallest principal moment they must add).
/// A heavy link, its stated inertia, and the light links fixed to it that carry placeholders.
type Group = (String, Stated, Vec<(String, Stated)>);

/// `max_mass`: the largest share of its partner's mass a light link may have (a part mounted on
/// it, not a limb segment of comparable weight).
pub(super) fn fused_placeholders(cx: &Context, min_share: f64, max_mass: f64) -> Vec<Finding> {
    let robot = cx.robot;
    if robot.format != Format::Urdf {
        return Vec::new();
    }
    let link = |name: &str| {
        robot.tree.children_tagged("link").find(|l| l.get("name") == Some(name)).and_then(stated)
    };
    // (heavy link, [(light link, its stated inertia)]), in file order.
    let mut groups: Vec<Group> = Vec::new();
    for j in robot.tree.children_tagged("joint").filter(|j| j.get("type") == Some("fixed")) {
        let p = j.children_tagged("parent").next().and_then(|c| c.get("link"));
        let c = j.children_tagged("child").next().and_then(|c| c.get("link"));
        let (Some(p), Some(c)) = (p, c) else { continue };
        let (Some(sp), Some(sc)) = (link(p), link(c)) else { continue };
        let ((hn, h), (ln, l)) =
            if sp.mass >= sc.mass { ((p, sp), (c, sc)) } else { ((c, sc), (p, sp)) };
        let gyr = |s: &Stated| (s.moments[2] / s.mass).sqrt();
        let light = l.mass <= max_mass * h.mass;
        if !light || !(gyr(&l) > gyr(&h)) || !(l.moments[0] >= min_share * h.moments[0]) {
            continue;
        }
        match groups.iter_mut().find(|g| g.0 == hn) {
            Some(g) => g.2.push((ln.to_string(), l)),
            None => groups.push((hn.to_string(), h, vec![(ln.to_string(), l)])),
        }
    }
    let mut out = Vec::new();
    for (hn, h, lights) in groups {
        let gyr = |s: &Stated| (s.moments[2] / s.mass).sqrt();
        let added: f64 = lights.iter().map(|l| l.1.moments[0]).sum();
        let share = added / h.moments[0];
        let list: Vec<String> = lights
            .iter()
            .map(|(n, s)| {
                format!(
                    "`{n}` ({} kg, {} kg·m², radius of gyration {} m)",
                    fmt_num(s.mass, 4),
                    fmt_num(s.moments[2], 3),
                    fmt_num(gyr(s), 3)
                )
            })
            .collect();
        let n = lights.len();
        let msg = format!(
            "{} fixed to link `{hn}` ({} kg, radius of gyration {} m) {} a placeholder inertia: {}; MuJoCo fuses {} into `{hn}`, adding at least {} % to its smallest principal moment {} kg·m²",
            if n == 1 { "a link" } else { "links" },
            fmt_num(h.mass, 4),
            fmt_num(gyr(&h), 3),
            if n == 1 { "carries" } else { "carry" },
            list.join(", "),
            if n == 1 { "it" } else { "them" },
            fmt_num(share * 100.0, 3),
            fmt_num(h.moments[0], 3)
        );
        let (l0, s0) = &lights[0];
        let mut f = cx
            .finding(msg, s0.at)
            .element(format!("link `{l0}`"), s0.at)
            .label(format!(
                "radius of gyration {} m on {} kg",
                fmt_num(gyr(s0), 3),
                fmt_num(s0.mass, 4)
            ))
            .secondary(h.at, format!("`{hn}`: radius of gyration {} m", fmt_num(gyr(&h), 3)));
        for (ln, s) in lights.iter().skip(1).take(3) {
            f = f.secondary(s.at, format!("also `{ln}`"));
        }
        let body = robot.bodies.iter().find(|b| b.name == hn).map_or(0, |b| b.id);
        out.push(
            f.note("a part fixed inside or onto another is no more spread out than the part it sits on unless it is long and thin and heavy enough to matter: a light link whose radius of gyration exceeds its partner's is a placeholder inertia (a CAD default or a value typed for the solver), and fused it changes how the whole body turns")
                .help("give the light link its own inertia (for a small part, about its mass × its size² / 10), or drop its <inertial> and let the fused body carry it")
                .subject(Subject::Body(body))
                .measured(share, "fraction")
                .expected(min_share, "fraction")
                .with("links", n as f64),
        );
    }
    out
}
