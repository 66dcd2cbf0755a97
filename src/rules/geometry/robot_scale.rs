use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{GeomType, Robot};
use crate::rules::control::keyframe_floor::MIN_ROBOT_JOINTS;
use crate::rules::geometry::oversized_collision::primitive_volume;
use crate::rules::{Context, Domain, Rule, RuleMeta, in_subtree, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a robot far lighter than the space it takes up: its mass over the volume of its
    /// bounding box below `min_bulk_density`. The robot is each kinematic tree on the world
    /// body that holds at least two hinges or slides (a scene's loose boxes and doors are not
    /// judged); its mass is the compiled mass of the tree's bodies, its bounding box the
    /// world-aligned box around every geom of the tree (planes and height fields left out;
    /// primitives and meshes by their compiled bounding boxes, drawn and colliding alike) and
    /// the tree's body origins, at the keyframe (without one, at qpos0). A robot's parts fill
    /// a share of that box, the rest is air: a rigid robot weighs more than the 1.2 kg/m³ of
    /// the air its box encloses. Measured on the 569 robot trees of this repository's fixtures,
    /// examples and shared models, the lightest for its box is 28.5 kg/m³ (a fixture's 0.78 kg
    /// hand whose collision mesh sits 1.57 m to its side; the shared Unitree H1 94.5) but for
    /// the models written in the wrong unit. A model whose lengths are ten times too large (decimetres
    /// read as metres: a 0.3 m robot modelled 3 m tall, its masses the real ones) is 1000 times
    /// lighter per volume than the robot (the Kayra lower body's copy: 0.59 kg/m³). Not
    /// judged: trees without geoms or of zero volume (a planar chain), massless trees.
    ///
    /// When at least half of the robot's mass is weighed by MuJoCo from the `density` its geoms
    /// write or inherit (bodies with no `<inertial>` whose compiled mass is their primitive
    /// geoms' volumes × their densities within 2 %, no geom stating a `mass`), and that mass over
    /// those geoms' volume is below `min_material_density` (15 kg/m³, the lightest expanded
    /// polystyrene), the finding names the density (gym's Ant: `density="5"` on every geom) as
    /// the evidence instead of the lengths' unit: the lengths and the density are then the
    /// file's two numbers, and only the density is below any solid's.
    ///
    /// ## Why is this bad?
    /// A model built at ten times its size with the real masses falls, swings and tips on
    /// time scales √10 ≈ 3.2 times slower than the robot, its inertias are a hundred times the
    /// real ones for the same mass, and its contacts, reach and step lengths are ten times too
    /// long: a policy trained on it learns a different machine. Nothing else in the file looks
    /// wrong, since every length, mesh scale and position agree with each other. MuJoCo reads
    /// lengths in metres (XML reference, `body/pos`, `asset/mesh` `scale`).
    ///
    /// ## How it is confirmed
    /// Static: compiled body masses and geom bounding boxes (`geom_aabb`) placed by MuJoCo's
    /// forward kinematics at the keyframe; the comparison is of the file's own numbers, not a
    /// prediction a simulation could refute.
    ///
    /// ## How to fix
    /// Write lengths in metres: divide every `pos`, size and `fromto` by the factor the robot
    /// is too large (and a mesh `scale` with them), or check the masses' unit (grams written as
    /// kilograms make a robot a thousand times too light).
    pub RobotScale {
        id: "robot-scale",
        group: "geometry",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("min_bulk_density", 2.0, "kg/m³", Domain::POSITIVE, "a robot's mass over the volume of its bounding box below this is no rigid robot: the air the box encloses weighs 1.2 kg/m³, the repository's robots 28.5 or more"),
            opt("min_material_density", 15.0, "kg/m³", Domain::POSITIVE, "a `density` MuJoCo weighs the robot's geoms at below this (the lightest expanded polystyrene) is named as the cause when those geoms carry at least half the robot's mass"),
        ],
    }
}

/// One robot: its top body, mass (kg), bounding-box extents (m) at the keyframe, bodies.
struct Tree {
    top: usize,
    mass: f64,
    extents: [f64; 3],
    bodies: Vec<usize>,
}

/// Agreement of a body's compiled mass with its geoms' volume × density for the mass to count
/// as weighed from the density (relative).
const DENSITY_AGREEMENT: f64 = 0.02;

/// MuJoCo's default geom density (kg/m³): water.
const DEFAULT_DENSITY: f64 = 1000.0;

/// The part of a tree's mass MuJoCo weighed from its geoms' densities: (that mass in kg, those
/// geoms' summed volume in m³, the distinct densities written, in order of first appearance).
/// A body counts when every mass-carrying geom is a primitive stating no `mass` and the body's
/// compiled mass is their volumes × densities within [`DENSITY_AGREEMENT`].
fn density_weighed(robot: &Robot, bodies: &[usize]) -> (f64, f64, Vec<f64>) {
    let (mut mass, mut volume, mut seen) = (0.0, 0.0, Vec::new());
    'body: for &b in bodies {
        let body_mass = robot.bodies[b].mass;
        if !(body_mass > 0.0) {
            continue;
        }
        let (mut m, mut v, mut rhos) = (0.0, 0.0, Vec::new());
        for g in robot.geoms.iter().filter(|g| g.body == b) {
            if matches!(g.gtype, GeomType::Plane | GeomType::Hfield) {
                continue;
            }
            let Some(e) = robot.elem(ElemKind::Geom, g.id, &g.name) else { continue 'body };
            let attr = |a: &str| e.attrs.get(a).map(|o| o.value.trim());
            if attr("mass").is_some() || attr("shellinertia") == Some("true") {
                continue 'body;
            }
            let rho = match attr("density").map(str::parse::<f64>) {
                Some(Ok(x)) => x,
                Some(Err(_)) => continue 'body,
                None => DEFAULT_DENSITY,
            };
            let Some(gv) = primitive_volume(g.gtype, g.size) else { continue 'body };
            if rho > 0.0 {
                m += rho * gv;
                v += gv;
                rhos.push(rho);
            }
        }
        if v > 0.0 && (m - body_mass).abs() <= DENSITY_AGREEMENT * body_mass {
            mass += body_mass;
            volume += v;
            for r in rhos {
                if !seen.contains(&r) {
                    seen.push(r);
                }
            }
        }
    }
    (mass, volume, seen)
}

/// The kinematic trees on the world body holding at least [`MIN_ROBOT_JOINTS`] hinges or
/// slides, with their mass and world-aligned bounding box at the keyframe (geoms' compiled
/// bounding boxes and the bodies' origins); trees without a geom are left out.
fn trees(robot: &Robot) -> Vec<Tree> {
    let key = &robot.key;
    let aabb = robot.mj.geom_aabb();
    let mut out = Vec::new();
    for top in robot.bodies.iter().filter(|b| b.id != 0 && b.parent == 0).map(|b| b.id) {
        let bodies: Vec<usize> =
            robot.bodies.iter().map(|b| b.id).filter(|&b| in_subtree(robot, top, b)).collect();
        let scalar = robot.joints.iter().filter(|j| j.is_scalar() && bodies.contains(&j.body));
        if scalar.count() < MIN_ROBOT_JOINTS {
            continue;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut add = |p: [f64; 3]| {
            for ((l, h), x) in lo.iter_mut().zip(hi.iter_mut()).zip(p) {
                *l = l.min(x);
                *h = h.max(x);
            }
        };
        let mut geoms = 0;
        for g in robot.geoms.iter().filter(|g| bodies.contains(&g.body)) {
            if matches!(g.gtype, GeomType::Plane | GeomType::Hfield) {
                continue;
            }
            let (Some(bb), Some(p), Some(r)) =
                (aabb.get(g.id), key.geom_xpos.get(g.id), key.geom_xmat.get(g.id))
            else {
                continue;
            };
            geoms += 1;
            for corner in 0..8 {
                let s = |i: usize| if corner >> i & 1 == 1 { 1.0 } else { -1.0 };
                let l = [bb[0] + s(0) * bb[3], bb[1] + s(1) * bb[4], bb[2] + s(2) * bb[5]];
                let w = |k: usize| r[3 * k] * l[0] + r[3 * k + 1] * l[1] + r[3 * k + 2] * l[2];
                add([p[0] + w(0), p[1] + w(1), p[2] + w(2)]);
            }
        }
        if geoms == 0 {
            continue;
        }
        for &b in &bodies {
            if let Some(p) = key.body_xpos.get(b) {
                add(*p);
            }
        }
        let extents = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        let mass = bodies.iter().map(|&b| robot.bodies[b].mass).sum();
        if extents.iter().all(|e| e.is_finite()) {
            out.push(Tree { top, mass, extents, bodies });
        }
    }
    out
}

impl Rule for RobotScale {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let min = cx.opt("min_bulk_density");
        let pose = match &robot.key.key_name {
            Some(k) => format!("at keyframe `{k}`"),
            None if robot.key.key.is_some() => "at the keyframe".to_string(),
            None => "at qpos0".to_string(),
        };
        for t in trees(robot) {
            let volume = t.extents[0] * t.extents[1] * t.extents[2];
            if !(volume > 0.0 && t.mass > 0.0) {
                continue;
            }
            let density = t.mass / volume;
            if density >= min {
                continue;
            }
            let name = robot.body_name(t.top);
            let who = if name.is_empty() {
                "the robot (its top body unnamed)".to_string()
            } else {
                format!("the robot under body `{name}`")
            };
            let e = t.extents.map(|x| fmt_num(x, 3));
            let (dm, dv, rhos) = density_weighed(robot, &t.bodies);
            let material = cx.opt("min_material_density");
            let by_density = dm >= 0.5 * t.mass && dv > 0.0 && dm / dv < material;
            let cause = if by_density {
                let listed: Vec<String> = rhos.iter().take(3).map(|r| fmt_num(*r, 4)).collect();
                format!(
                    "{} kg of it ({} %) is weighed by MuJoCo from its geoms at density {} kg/m³, {} kg/m³ over their own volume, below any solid's {} kg/m³: the density is the evidence, not the lengths",
                    fmt_num(dm, 3),
                    fmt_num(100.0 * dm / t.mass, 3),
                    listed.join(", "),
                    fmt_num(dm / dv, 3),
                    fmt_num(material, 3)
                )
            } else {
                "its lengths are likely written in a unit too small".to_string()
            };
            let msg = format!(
                "{who} weighs {} kg but spans {} × {} × {} m {pose}: {} kg/m³ over its bounding box, below {} kg/m³ (the air in that box weighs {} kg): {cause}",
                fmt_num(t.mass, 3),
                e[0],
                e[1],
                e[2],
                fmt_num(density, 3),
                fmt_num(min, 3),
                fmt_num(AIR_DENSITY * volume, 3),
            );
            let help = if by_density {
                "write the geoms' `density` of the parts' material (kg/m³: about 1000–2700 for plastics and aluminium, lower for hollow parts), or state each body's mass in an `<inertial>`"
            } else {
                "write lengths in metres (divide positions, sizes and mesh scale by the factor the model is too large), or check the unit of the masses"
            };
            let loc = robot.elem_loc(ElemKind::Body, t.top, name);
            out.push(
                cx.finding(msg, loc)
                    .element(format!("body {name}"), loc)
                    .label("a robot lighter than the space it spans")
                    .note("mass: the compiled mass of the tree's bodies; box: world-aligned, around every geom's compiled bounding box (drawn and colliding) and every body origin of the tree at the pose named")
                    .help(help)
                    .subject(Subject::Body(t.top))
                    .measured(density, "kg/m³")
                    .expected(min, "kg/m³"),
            );
        }
    }
}

/// Density of air at sea level and 20 °C (kg/m³): the lightest filling a robot's bounding
/// box could have, quoted in the message.
const AIR_DENSITY: f64 = 1.2;
