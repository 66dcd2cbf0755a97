//! URDF and MJCF `<inertial>`s that MuJoCo's compiler rejects. MuJoCo stops at the first body it
//! cannot accept and names that one; an export that wrote placeholder or broken inertias usually
//! wrote several (a whole leg of zeros, every servo horn's tensor), so the load error lists all of
//! them with their lines, and one edit fixes the file.

use nalgebra::{Matrix3, SymmetricEigen};

use crate::model::source::{SourceMap, XNode};

/// MuJoCo's `mjMINVAL`: the smallest mass or moment of inertia a moving body may have.
const MJ_MINVAL: f64 = 1e-15;

/// Relative rounding of a principal-moment comparison: the digits a file writes, not a tolerance
/// of the design.
const ROUNDING: f64 = 1e-9;

struct Link<'a> {
    node: &'a XNode,
    mass: f64,
    /// Whether a product of inertia is written: MuJoCo then diagonalises the full tensor and
    /// needs every principal moment positive.
    full: bool,
    /// Principal moments, ascending.
    moments: [f64; 3],
}

fn num(n: &XNode, attr: &str) -> f64 {
    n.get(attr).and_then(|v| v.trim().parse::<f64>().ok()).unwrap_or(0.0)
}

fn link<'a>(node: &'a XNode) -> Option<Link<'a>> {
    let inertial = node.children_tagged("inertial").next()?;
    let mass = inertial.children_tagged("mass").next().map(|m| num(m, "value")).unwrap_or(0.0);
    let i = inertial.children_tagged("inertia").next()?;
    let (xx, xy, xz, yy, yz, zz) =
        (num(i, "ixx"), num(i, "ixy"), num(i, "ixz"), num(i, "iyy"), num(i, "iyz"), num(i, "izz"));
    let m = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
    let mut e: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
    e.sort_by(f64::total_cmp);
    let full = xy != 0.0 || xz != 0.0 || yz != 0.0;
    Some(Link { node, mass, full, moments: [e[0], e[1], e[2]] })
}

/// Each link of `tree` (a URDF `<robot>`) whose stated inertia MuJoCo rejects, as "link `name`
/// (line N): why": a principal moment that is negative (or not positive, when a product of
/// inertia is written: MuJoCo diagonalises that tensor), principal moments breaking A + B ≥ C (unless
/// `<compiler balanceinertia="true"/>` in the URDF's `<mujoco>` block), or a link that moves on a
/// joint with mass and no inertia, counting the links fixed to it that MuJoCo fuses into it.
pub fn rejected(map: &SourceMap, tree: &XNode) -> Vec<String> {
    let balance = tree
        .children_tagged("mujoco")
        .any(|m| m.children_tagged("compiler").any(|c| c.get("balanceinertia") == Some("true")));
    let joints: Vec<&XNode> = tree.children_tagged("joint").collect();
    let parent_joint = |name: &str| {
        joints
            .iter()
            .find(|j| j.children_tagged("child").next().and_then(|c| c.get("link")) == Some(name))
    };
    let fixed_children = |name: &str| -> Vec<&str> {
        joints
            .iter()
            .filter(|j| j.get("type") == Some("fixed"))
            .filter(|j| {
                j.children_tagged("parent").next().and_then(|p| p.get("link")) == Some(name)
            })
            .filter_map(|j| j.children_tagged("child").next().and_then(|c| c.get("link")))
            .collect()
    };
    let links: Vec<Link> = tree.children_tagged("link").filter_map(link).collect();
    let by_name = |name: &str| links.iter().find(|l| l.node.name() == Some(name));
    let mut out = Vec::new();
    for l in &links {
        let name = l.node.name().unwrap_or("");
        let line = map.file(l.node.loc.file).line_col(l.node.loc.start).0;
        let why = if let Some(why) = moments_rejected(l.moments, l.full, balance) {
            Some(why)
        } else {
            let moving =
                parent_joint(name).is_some_and(|j| !matches!(j.get("type"), Some("fixed") | None));
            // The links MuJoCo fuses into this one: fixed children, recursively.
            let mut group = vec![name];
            let mut k = 0;
            while k < group.len() {
                group.extend(fixed_children(group[k]));
                k += 1;
            }
            let fused_inertia = group
                .iter()
                .filter_map(|n| by_name(n))
                .any(|f| f.moments[2] > MJ_MINVAL || (f.node.name() != Some(name) && f.mass > 0.0));
            (moving && l.mass > 0.0 && !fused_inertia)
                .then(|| format!("moves on a joint with mass {} kg and no inertia", l.mass))
        };
        if let Some(why) = why {
            out.push(format!("link `{name}` (line {line}): {why}"));
        }
    }
    out
}

/// Why MuJoCo rejects principal moments `[a, b, c]` (ascending): one not positive when `full`
/// (a tensor MuJoCo diagonalises) or negative beyond rounding, or A + B < C unless `balance`.
fn moments_rejected([a, b, c]: [f64; 3], full: bool, balance: bool) -> Option<String> {
    if (full && a <= 0.0) || a < -MJ_MINVAL.max(ROUNDING * c.abs()) {
        Some(format!(
            "principal moments {:.3e}, {:.3e}, {:.3e} kg·m² (not all positive: not an inertia)",
            a, b, c
        ))
    } else if !balance && a + b < c * (1.0 - ROUNDING) - MJ_MINVAL {
        Some(format!(
            "principal moments {:.3e} + {:.3e} < {:.3e} kg·m² (A + B ≥ C fails: no rigid body has them)",
            a, b, c
        ))
    } else {
        None
    }
}

/// Each MJCF body of `tree` whose `<inertial>` MuJoCo rejects, as "body `name` (line N): why":
/// its `diaginertia` or `fullinertia` (principal moments: the written diagonal, or the full
/// tensor's eigenvalues) with a negative moment (not positive for `fullinertia`, which MuJoCo
/// diagonalises), or moments breaking A + B ≥ C unless `<compiler balanceinertia="true">`.
pub fn mjcf_rejected(map: &SourceMap, tree: &XNode) -> Vec<String> {
    let mut balance = false;
    tree.walk(&mut |n: &XNode| {
        if n.tag == "compiler" && n.get("balanceinertia") == Some("true") {
            balance = true;
        }
    });
    let nums = |v: &str| -> Vec<f64> {
        v.split_whitespace().filter_map(|x| x.parse::<f64>().ok()).collect()
    };
    let mut out = Vec::new();
    tree.walk(&mut |n: &XNode| {
        if n.tag != "body" {
            return;
        }
        let Some(i) = n.children_tagged("inertial").next() else { return };
        let (moments, full) = if let Some(d) = i.get("diaginertia").map(nums) {
            if d.len() < 3 {
                return;
            }
            let mut e = [d[0], d[1], d[2]];
            e.sort_by(f64::total_cmp);
            (e, false)
        } else if let Some(f) = i.get("fullinertia").map(nums) {
            if f.len() < 6 {
                return;
            }
            let m = Matrix3::new(f[0], f[3], f[4], f[3], f[1], f[5], f[4], f[5], f[2]);
            let mut e: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
            e.sort_by(f64::total_cmp);
            ([e[0], e[1], e[2]], true)
        } else {
            return;
        };
        if let Some(why) = moments_rejected(moments, full, balance) {
            let line = map.file(i.loc.file).line_col(i.loc.start).0;
            out.push(format!("body `{}` (line {line}): {why}", n.name().unwrap_or("")));
        }
    });
    out
}

/// `msg` with the list of rejected inertials appended, when MuJoCo's error is about an inertia
/// and the file states more than the one it names (`urdf`: a URDF `<robot>`, else an MJCF).
pub fn explain(map: &SourceMap, tree: &XNode, msg: String, urdf: bool) -> String {
    if !msg.contains("inertia") {
        return msg;
    }
    let all = if urdf { rejected(map, tree) } else { mjcf_rejected(map, tree) };
    if all.len() < 2 {
        return msg;
    }
    format!(
        "{msg} (MuJoCo names the first; the file states {} inertials it rejects: {})",
        all.len(),
        all.join("; ")
    )
}
