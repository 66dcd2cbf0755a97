use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::GeomType;
use crate::model::mjcf::ElemKind;
use crate::rules::inertia::isotropic_base_inertia::inertia_loc;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a moving body whose largest principal moment of inertia is more than its mass
    /// could give it inside its own geometry: no rigid body of mass m whose mass lies within R
    /// of its centre of mass has a moment above m·R² about any axis through that centre (the
    /// bound is reached only with all the mass on a ring of radius R). R is the farthest reach
    /// of the body's geoms from its compiled centre of mass — each geom's bounding sphere
    /// (`geom_rbound`, drawn and colliding geoms alike, meshes included), so R is never
    /// smaller than the part. Bodies without geoms (other than planes), bodies fixed to the
    /// world, and bodies welded to another body with geoms (whose geoms might carry the mass)
    /// are not judged. The root link of a legged URDF that MuJoCo's importer welds to the
    /// world (`welded-legged-base`) is judged although the importer fuses it into the world
    /// body: the robot floats on it for the foot rules and the stance probes, so it is judged
    /// as the stance probes' floated copy compiles it (a free joint on the root link, which
    /// MuJoCo then compiles with the links fixed to it into one moving body) — PhantomX's
    /// `MP_BODY`, 6.4 kg·m² on 0.98 kg.
    ///
    /// A URDF link fixed to another (MuJoCo's importer fuses them into one body, so the bound
    /// above judges only the fused body) is judged against its partner: the lighter of the two
    /// whose radius of gyration √(I_max/m) exceeds the heavier one's while its smallest
    /// principal moment is at least `min_share` of the heavier one's smallest (what it adds,
    /// about any axis, to the fused body) carries a placeholder inertia — a 1 g board with
    /// 1e-5 kg·m² on every axis (0.1 m) fused into a 0.108 kg frame of 0.046 m. The lighter
    /// links fixed to one link are reported together.
    ///
    /// A link (URDF, fused or moving) or a body (MJCF, not fixed to the world) whose stated mass
    /// is less than its own shapes could weigh in any material carries a placeholder mass
    /// (Xiaomi CyberDog2's `head`: 1 g behind a box of 76 × 60 × 40 mm). Each shape's floor is
    /// the lighter of a solid of `min_density` (the lightest foam) and a closed shell of
    /// `min_areal_density` (the thinnest cover) of its volume and surface area (primitives from
    /// their sizes, meshes from their compiled faces); the link's floor is its largest shape's,
    /// over the colliding shapes and over the drawn ones, whichever set gives the lower floor.
    /// An honest hollow cover (a 0.12 kg box of 0.22 m²) or a foam bumper passes; links
    /// without shapes (fused frames, an IMU) and massless links are not judged, nor shapes
    /// larger than the robot's joint span (a length in millimetres, `mesh-scale`'s and
    /// `oversized-collision-primitive`'s) or models with fewer than two joints.
    ///
    /// An MJCF body that states no mass (no `<inertial>`, or `inertiafromgeom="true"`; no geom
    /// of it writes `mass`) weighs what MuJoCo makes of its geoms' `density`: its compiled mass
    /// is judged against the same floor, its largest mass-carrying shape's (geoms of density 0
    /// or outside `inertiagrouprange` carry none; `shellinertia` geoms, whose density is per
    /// area, are not judged). The bodies whose geoms take one `density` value are reported
    /// together, with their effective density (compiled mass over summed geom volume): the gym
    /// Ant's `density="5"` on a Trossen hexapod, 7.5 g for a 1.5 l torso, a 0.21 kg robot.
    ///
    /// ## Why is this bad?
    /// A moment larger than the part's geometry allows is a placeholder or a unit slip (a
    /// `diaginertia="0.001 0.001 0.001"` on a 26 g finger is a 190 mm radius of gyration on a
    /// part a few centimetres long). The joints that move the part then accelerate far slower
    /// in simulation than on the hardware — a finger or wrist that feels many times heavier
    /// — so gains, gripper timing and contact forces learned on it do not transfer. A mass
    /// lighter than the part's shape is the reverse slip: the part swings, and loads the joints
    /// carrying it, as if it were not there. MuJoCo XML reference, `body/inertial`.
    ///
    /// ## How it is confirmed
    /// Static: compiled `body_mass`, `body_inertia`, `body_ipos` and the body's geoms'
    /// positions and bounding radii; for the light case, the stated `<inertial>` mass and the
    /// shapes' volumes and areas. The bound is geometry, not a prediction a simulation could
    /// refute.
    ///
    /// ## How to fix
    /// Use the part's inertia from CAD or the manufacturer's URDF, or remove `<inertial>` so
    /// MuJoCo computes mass and inertia from the body's geoms.
    pub InertiaExceedsGeometry {
        id: "inertia-exceeds-geometry",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("max_mass_share", 0.1, "fraction", Domain::NON_NEGATIVE, "largest mass of a link fixed to another, as a share of the other's, judged as a part mounted on it (a sensor, a board, a camera) for the fused case"),
            opt("min_density", 15.0, "kg/m³", Domain::POSITIVE, "the lightest solid a robot part is made of (expanded polystyrene foam, 15–30 kg/m³): a link lighter than its largest shape filled with it, and than that shape's shell, carries a placeholder mass"),
            opt("min_areal_density", 0.3, "kg/m²", Domain::POSITIVE, "the lightest closed shell a robot part is made of (0.3 mm of plastic at 1000 kg/m³; printed and moulded covers are 1–3 mm): a hollow part weighs at least its shape's surface area times this"),
            opt("min_share", 0.05, "fraction", Domain::NON_NEGATIVE, "least share of a link's smallest principal moment that a lighter, more spread-out link fixed to it must add to be reported as a fused placeholder"),
        ],
    }
}

impl Rule for InertiaExceedsGeometry {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let m = &robot.mj;
        let (inertia, ipos, gpos) = (m.body_inertia(), m.body_ipos(), m.geom_pos());
        out.extend(super::fused_placeholder::fused_placeholders(
            cx,
            cx.opt("min_share"),
            cx.opt("max_mass_share"),
        ));
        out.extend(super::light_placeholder::light_placeholders(
            cx,
            cx.opt("min_density"),
            cx.opt("min_areal_density"),
        ));
        out.extend(super::light_density::light_from_density(
            cx,
            cx.opt("min_density"),
            cx.opt("min_areal_density"),
        ));
        out.extend(super::floated_root_inertia::floated_root(cx));
        for b in robot.bodies.iter().filter(|b| b.id != 0 && b.weld != 0 && b.mass > 0.0) {
            if b.weld != b.id {
                continue; // welded to its parent: the parent's geoms may carry its mass
            }
            // A body welded to this one that has geoms may carry this body's mass (frames
            // without geoms, such as a camera's or a tool site's, carry none).
            let welded_shape = robot.bodies.iter().any(|o| {
                o.id != b.id && o.weld == b.id && robot.geoms.iter().any(|g| g.body == o.id)
            });
            if welded_shape {
                continue;
            }
            let (Some(i), Some(c)) = (inertia.get(b.id), ipos.get(b.id)) else { continue };
            let reach = robot
                .geoms
                .iter()
                .filter(|g| {
                    g.body == b.id && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
                })
                .filter_map(|g| {
                    let p = gpos.get(g.id)?;
                    let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2))
                        .sqrt();
                    (g.rbound > 0.0).then_some(d + g.rbound)
                })
                .fold(None, |acc: Option<f64>, r| Some(acc.map_or(r, |a| a.max(r))));
            let Some(r) = reach else { continue };
            let top = i[0].max(i[1]).max(i[2]);
            let bound = b.mass * r * r;
            if !(top > bound) || !bound.is_finite() {
                continue;
            }
            let name = robot.body_name(b.id);
            let msg = format!(
                "body `{name}` has a principal moment of inertia {} kg·m², but its mass {} kg within {} m of its centre of mass (its geoms' reach) allows at most {} kg·m² (m·R²): {}× too large",
                fmt_num(top, 4),
                fmt_num(b.mass, 4),
                fmt_num(r, 3),
                fmt_num(bound, 3),
                fmt_num(top / bound, 3)
            );
            let eloc = robot.elem_loc(ElemKind::Body, b.id, name);
            let loc = inertia_loc(robot, name).unwrap_or(eloc);
            let f = cx
                .finding(msg, loc)
                .element(format!("body {name}"), eloc)
                .label("more than the part's geometry allows")
                .note(format!(
                    "radius of gyration √(I/m) = {} m on a part that reaches {} m from its centre of mass: a placeholder or a unit slip",
                    fmt_num((top / b.mass).sqrt(), 3),
                    fmt_num(r, 3)
                ))
                .help("use the part's inertia from CAD or the manufacturer's URDF, or drop <inertial> so MuJoCo computes it from the body's geoms")
                .subject(Subject::Body(b.id))
                .measured(top, "kg·m²")
                .expected(bound, "kg·m²");
            out.push(f);
        }
    }
}
