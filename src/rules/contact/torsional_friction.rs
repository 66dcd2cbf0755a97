use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::Geom;
use crate::model::contact::{Combined, combine, ground_partners, pair_of, takes_part};
use crate::model::mjcf::ElemKind;
use crate::rules::contact::feet::feet;
use crate::rules::geometry::shapes::Placed;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every foot collision geom (feet as `rules::contact::feet` finds them) whose contact
    /// with the ground has condim ≥ 4 — condim as MuJoCo combines it: an explicit `<pair>`'s, the
    /// higher-`priority` geom's, else the larger of the two — compares the contact's torsional
    /// friction coefficient μ_t with the most the foot can carry: MuJoCo's torsional
    /// coefficient is a length (torsional friction torque ≤ μ_t × normal force), and a contact
    /// patch of radius r with sliding friction μ_s resists twisting with at most μ_s × N × r
    /// (all the normal force at the patch's rim). The rule reports μ_t > μ_s × r, with r half the
    /// diagonal of the geom's bounding box in the ground plane at the keyframe (an upper bound on
    /// any patch the geom can make). The ground is the file's world planes, height fields and
    /// boxes; a file with none is combined with MuJoCo's default geom (condim 3, friction
    /// 1 0.005 0.0001), which a scene's floor usually keeps. No constant is involved.
    ///
    /// ## Why is this bad?
    /// A torsional coefficient longer than the foot makes the foot resist turning more than
    /// sliding friction at its very edge could: the feet cannot pivot, so turning in place and
    /// yaw recovery work in simulation by a torque no hardware foot produces. The usual cause is
    /// a copied `friction="0.5 0.5 0.5"`, reading all three numbers as coefficients of the same
    /// kind (MuJoCo's default torsional value is 0.005 m).
    ///
    /// ## How it is confirmed
    /// Static: the combined contact parameters and the geom's compiled size and pose.
    ///
    /// ## How to fix
    /// Set the torsional (second) friction value to a length below μ_s × the foot's contact
    /// radius (MuJoCo's default 0.005 m, or a few millimetres to a few centimetres for a sole),
    /// or use condim 3 if the identified contact model has no torsional friction.
    pub TorsionalFriction {
        id: "torsional-friction-length",
        group: "contact",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

/// MuJoCo's default geom contact parameters, standing in for a floor the file does not have.
fn default_ground(like: &Geom) -> Geom {
    Geom {
        id: usize::MAX,
        condim: 3,
        friction: [1.0, 0.005, 0.0001],
        priority: 0,
        solmix: 1.0,
        ..like.clone()
    }
}

/// Half the diagonal of geom `g`'s bounding box in the ground (x-y) plane at the keyframe, m.
pub fn ground_patch_radius(p: &Placed) -> f64 {
    let w = |d: [f64; 3]| {
        let (a, b) = (p.support(d), p.support([-d[0], -d[1], -d[2]]));
        (a[0] - b[0]) * d[0] + (a[1] - b[1]) * d[1]
    };
    0.5 * (w([1.0, 0.0, 0.0]).powi(2) + w([0.0, 1.0, 0.0]).powi(2)).sqrt()
}

impl Rule for TorsionalFriction {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let mut seen = std::collections::BTreeSet::new();
        for foot in feet(robot, cx.spec) {
            for &g in &foot.geoms {
                if !seen.insert(g) || !takes_part(robot, g) {
                    continue;
                }
                let mine = &robot.geoms[g];
                let mut ground: Vec<(Option<usize>, Combined)> =
                    ground_partners(robot, g).into_iter().map(|(o, c)| (Some(o), c)).collect();
                if ground.is_empty() {
                    ground.push((None, combine(mine, &default_ground(mine))));
                }
                // The contact with the largest torsional excess over what the patch carries.
                let r = ground_patch_radius(&Placed::of(robot, g));
                let worst = ground
                    .iter()
                    .filter(|(_, c)| c.condim >= 4)
                    .map(|(o, c)| (*o, *c, c.friction[1] - c.friction[0] * r))
                    .filter(|&(_, _, excess)| excess > 0.0)
                    .max_by(|a, b| a.2.total_cmp(&b.2));
                let Some((o, c, _)) = worst else { continue };
                let (mu_s, mu_t) = (c.friction[0], c.friction[1]);
                let msg = format!(
                    "foot geom {} has torsional friction {} m with condim {}: more than sliding friction {} × its contact radius {} mm = {} m can carry",
                    gname(robot, g),
                    fmt_num(mu_t, 3),
                    c.condim,
                    fmt_num(mu_s, 3),
                    fmt_num(1000.0 * r, 3),
                    fmt_num(mu_s * r, 3)
                );
                // At the attribute MuJoCo takes the torsional value from.
                let pair = o.and_then(|o| pair_of(robot, g, o));
                let owner = match (pair, c.by_priority) {
                    (Some(_), _) => None,
                    (None, Some(w)) => Some(w),
                    (None, None) => match o {
                        Some(o) if robot.geoms[o].friction[1] > mine.friction[1] => Some(o),
                        _ => Some(g),
                    },
                };
                let mut f = match (pair, owner) {
                    (Some(p), _) => cx.at_attr(ElemKind::Pair, p.id, &p.name, "friction", msg),
                    (None, Some(w)) if w != usize::MAX => {
                        cx.at_attr(ElemKind::Geom, w, &robot.geoms[w].name, "friction", msg)
                    }
                    _ => cx.at_attr(ElemKind::Geom, g, &mine.name, "friction", msg),
                };
                f = f
                    .note(format!(
                        "MuJoCo's torsional coefficient is a length: the contact resists twisting with up to μ_t × normal force. A patch of radius r with sliding friction μ_s resists with at most μ_s × N × r; {} m against {} m means the foot cannot pivot where the real one would.{}",
                        fmt_num(mu_t, 3),
                        fmt_num(mu_s * r, 3),
                        if o.is_none() {
                            " No ground geom in this file: combined with MuJoCo's default geom (condim 3, friction 1 0.005 0.0001)."
                        } else {
                            ""
                        }
                    ))
                    .help(format!(
                        "set the torsional (second) friction value to ≤ {} m (MuJoCo's default is 0.005), or condim=\"3\" if the contact model has no torsional friction",
                        fmt_num(mu_s * r, 3)
                    ))
                    .label(format!("torsional {} m", fmt_num(mu_t, 3)))
                    .subject(Subject::Geom(g))
                    .measured(mu_t, "m")
                    .expected(mu_s * r, "m")
                    .with("mu_sliding", mu_s)
                    .with("mu_torsional", mu_t)
                    .with("patch_radius_m", r)
                    .with("condim", c.condim as f64);
                out.push(f);
            }
        }
    }
}

fn gname(robot: &crate::model::Robot, g: usize) -> String {
    let n = &robot.geoms[g].name;
    if n.is_empty() { robot.unnamed_geom(g) } else { format!("`{n}`") }
}
