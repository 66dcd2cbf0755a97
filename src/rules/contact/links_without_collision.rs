use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{Geom, GeomType, JointType, Robot};
use crate::rules::contact::feet::{FootKind, feet_over, floating_bases};
use crate::rules::geometry::shapes::{V3, add, col, norm, scale, sub, to_local_dir};
use crate::rules::{Context, Domain, Rule, RuleMeta, in_subtree, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a legged robot on a floating base whose feet collide while other links of real
    /// size do not: thighs, shanks, the torso, upper arms and forearms drawn by visual geoms
    /// only (`contype = conaffinity = 0`, named by no `<contact><pair>`), so a knee, a hip or
    /// the torso passes through the floor and the legs and arms pass through each other.
    ///
    /// The robot is the subtree of a body with a free joint (or a floating base written as
    /// three slides and a ball, as humanoid-gym's files do, or the whole of a legged URDF that
    /// MuJoCo's importer welded to the world, as if its root link floated: `welded-legged-base`)
    /// that carries hinge or slide joints
    /// and two or more feet; or of a body that moves in a vertical plane in place of floating
    /// (the planar locomotors of Gym, Brax and dm_control: its joints all base coordinates, one
    /// of them a slide with a vertical part, so it falls onto the floor), with one foot or more
    /// (a hopper stands on one). Feet are the foot bodies of the contact rules: by name, else the leaf
    /// bodies that touch down); a wheel counts as a foot when it ends a leg, a hinge or slide
    /// between it and the base besides its axle (a wheel-legged robot: DDT Diablo, the wheeled
    /// Pupper v3), not on a rover whose wheels turn on the base. A link is one of its bodies other than the feet
    /// and their toes (which collide through what touches down); it is **covered** when a geom
    /// of its rigid part (the body or a body welded to it, no joint between: MuJoCo's weld
    /// body) takes part in contacts. An uncovered link is reported when
    /// a stretch of its skeleton at least `min_link_share` of the robot's size long lies
    /// outside every collision geom of the robot: the skeleton is the segments from the body's
    /// origin to its child bodies' origins and to the ends of its geoms' long axes (a capsule's
    /// or cylinder's axis, a box's or ellipsoid's longest half-size, a sphere's or mesh's centre) at the
    /// keyframe, sampled every 2 mm; a point is inside a primitive by its shape, inside a mesh
    /// by its bounding sphere (which never leaves out a point of the mesh); the robot's size is
    /// the largest distance between two of its bodies' origins. A short link between two joints
    /// (a hip or shoulder housing) that its neighbours' collision geoms enclose is not
    /// reported.
    ///
    /// Not reported: a fixed-base robot (an arm on a table touches what its gripper touches);
    /// a model that lists its contacts by explicit `<contact><pair>`s (the author chose
    /// them); a robot none of whose geoms collides (`visual-mesh-collision` reports it); a
    /// model with `<flag contact="disable"/>`.
    ///
    /// Outside a floating robot (a fixed arm, a torso on a pedestal) one case is reported: a
    /// body whose collision geometry the file switched off — a geom that its own name or its
    /// mesh's name calls collision geometry (`collision` in it) compiles with `contype =
    /// conaffinity = 0` (a visual class's defaults: robosuite's Baxter torso, mesh
    /// `base_link_collision` in class `viz`), and no geom of the body (of its weld body, for a
    /// moving one) takes part in contacts, while geoms of jointed links do: those links pass
    /// through it.
    ///
    /// ## Why is this bad?
    /// Training puts a legged robot through falls, kneeling, crossed legs and arm swings. With
    /// only the feet colliding, a falling robot lands on its feet or sinks its knees and torso
    /// into the floor, a swing leg passes through the stance leg and an arm through the torso:
    /// the policy learns motions the hardware cannot make and recoveries from falls that never
    /// happen that way. MuJoCo documentation, Modeling › Collision detection
    /// (`contype`/`conaffinity`).
    ///
    /// ## How it is confirmed
    /// Static: compiled contact masks, explicit pairs, weld bodies and the keyframe positions.
    /// No simulation is needed to show that a geom with no contact masks collides with nothing.
    ///
    /// ## How to fix
    /// Give each listed link a collision primitive fitted to it (a capsule along a thigh or a
    /// forearm, a box on the torso) in the collision group (3). A speed-oriented variant that
    /// keeps only the foot contacts on purpose (an MJX training file) says so by listing its
    /// contacts with `<contact><pair>`, or with a suppression comment and the reason.
    pub LinksWithoutCollision {
        id: "links-without-collision",
        group: "contact",
        level: Severity::Warning,
        probe: None,
        options: [opt(
            "min_link_share",
            0.15,
            "",
            Domain::POSITIVE_FRACTION,
            "an uncovered link is reported when a stretch of its skeleton (origin to child bodies' origins and geoms' centres) this share of the robot's size (largest distance between two of its bodies' origins at the keyframe) long lies outside every collision geom"
        )],
    }
}

/// Whether wheel body `wheel` ends a leg: a hinge or slide on a body between it and `base`
/// besides its own axle (a wheel-legged robot: DDT Diablo, the wheeled Pupper v3, Unitree
/// Go2-W). A wheel on the base itself (a rover's) does not make the robot legged.
fn ends_a_leg(robot: &Robot, base: usize, wheel: usize) -> bool {
    let mut b = robot.bodies[wheel].parent;
    let mut steps = 0;
    while b != base && b != 0 && steps <= robot.bodies.len() {
        if robot
            .joints
            .iter()
            .any(|j| j.body == b && matches!(j.jtype, JointType::Hinge | JointType::Slide))
        {
            return true;
        }
        b = robot.bodies[b].parent;
        steps += 1;
    }
    false
}

/// Feet a robot on a floating base needs to count as legged here (one foot alone is a foot
/// dropped on a floor or a test rig, whose only body is that foot).
const MIN_FEET_FLOATING: usize = 2;
/// Feet a locomotor moving in a vertical plane needs: a one-legged hopper stands on one.
const MIN_FEET_VERTICAL_PLANE: usize = 1;

/// The bodies that move in a vertical plane over the floor in place of floating (the planar
/// locomotors of Gym, Brax and dm_control: a horizontal slide, a vertical slide and a pitch
/// hinge on a body under the world): a body under a world-fixed parent whose joints are all
/// base coordinates ([`Robot::is_base_coordinate`]), no ball among them, with a slide whose
/// axis has a vertical part — the body rises and falls onto the floor, so its links can strike
/// it. A planar base on the floor (slides along x and y, a yaw hinge) has no such slide.
fn vertical_plane_bases(robot: &Robot) -> Vec<usize> {
    (1..robot.bodies.len())
        .filter(|&b| {
            let on: Vec<_> = robot.joints.iter().filter(|j| j.body == b).collect();
            !on.is_empty()
                && on.iter().all(|j| j.is_scalar() && robot.is_base_coordinate(j.id))
                && on.iter().any(|j| {
                    j.jtype == JointType::Slide
                        && robot.key.joint_xaxis.get(j.id).is_some_and(|a| a[2] != 0.0)
                })
        })
        .collect()
}

fn dist(a: V3, b: V3) -> f64 {
    norm(sub(a, b))
}
/// Whether world point `p` lies inside geom `g` at the keyframe: primitives by their shape,
/// meshes (and anything else) by their bounding sphere, which never leaves out a point of the
/// mesh.
fn inside(robot: &Robot, g: &Geom, p: V3) -> bool {
    let (Some(&c), Some(m)) = (robot.key.geom_xpos.get(g.id), robot.key.geom_xmat.get(g.id)) else {
        return false;
    };
    let l = to_local_dir(m, sub(p, c));
    let s = g.size;
    match g.gtype {
        GeomType::Sphere => norm(l) <= s[0],
        GeomType::Capsule => l[0].hypot(l[1]).hypot((l[2].abs() - s[1]).max(0.0)) <= s[0],
        GeomType::Cylinder => l[0].hypot(l[1]) <= s[0] && l[2].abs() <= s[1],
        GeomType::Box => l.iter().zip(s).all(|(x, h)| x.abs() <= h),
        GeomType::Ellipsoid => {
            l.iter()
                .zip(s)
                .map(|(x, h)| if h > 0.0 { (x / h).powi(2) } else { f64::INFINITY })
                .sum::<f64>()
                <= 1.0
        }
        _ => norm(l) <= g.rbound,
    }
}

/// The ends of a geom's long axis at the keyframe (capsule and cylinder: their axis; box and
/// ellipsoid: their longest half-size), else its centre (a sphere, a mesh: no axis to follow).
fn geom_ends(robot: &Robot, g: &Geom) -> Vec<V3> {
    let (Some(&c), Some(m)) = (robot.key.geom_xpos.get(g.id), robot.key.geom_xmat.get(g.id)) else {
        return Vec::new();
    };
    let (k, h) = match g.gtype {
        GeomType::Capsule | GeomType::Cylinder => (2, g.size[1]),
        GeomType::Box | GeomType::Ellipsoid => {
            let k = (0..3).fold(0, |a, i| if g.size[i] > g.size[a] { i } else { a });
            (k, g.size[k])
        }
        _ => return vec![c],
    };
    let d = scale(col(m, k), h);
    vec![add(c, d), sub(c, d)]
}

/// Samples per metre of a link's skeleton.
const SAMPLES_PER_M: f64 = 500.0;

/// The longest stretch of body `b`'s skeleton — the segments from its origin to its child
/// bodies' origins and to its geoms' centres, at the keyframe — that lies outside every geom in
/// `colliders`, m.
pub fn bare_stretch(robot: &Robot, b: usize, colliders: &[&Geom]) -> f64 {
    let Some(&o) = robot.key.body_xpos.get(b) else { return 0.0 };
    let children = robot
        .bodies
        .iter()
        .filter(|c| c.id != 0 && c.id != b && c.parent == b)
        .filter_map(|c| robot.key.body_xpos.get(c.id).copied());
    let geoms = robot
        .geoms
        .iter()
        .filter(|g| g.body == b && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
        .flat_map(|g| geom_ends(robot, g));
    let ends: Vec<V3> = children.chain(geoms).collect();
    let mut longest = 0.0f64;
    for e in ends {
        let len = norm(sub(e, o));
        let n = ((len * SAMPLES_PER_M).ceil() as usize).clamp(1, 10_000);
        let step = len / n as f64;
        let mut run = 0.0f64;
        for i in 0..=n {
            let p = add(o, scale(sub(e, o), i as f64 / n as f64));
            if colliders.iter().any(|g| inside(robot, g, p)) {
                run = 0.0;
            } else {
                run += if i == 0 { 0.0 } else { step };
                longest = longest.max(run);
            }
        }
    }
    longest
}

impl Rule for LinksWithoutCollision {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if !robot.pairs.is_empty() || crate::model::contact::contacts_disabled(robot) {
            return;
        }
        let takes_part = |g: usize| crate::model::contact::takes_part(robot, g);
        let robot_collides = robot.geoms.iter().any(|g| {
            g.body != 0 && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield) && g.collides()
        });
        if !robot_collides {
            return; // no collision geometry at all: visual-mesh-collision
        }
        let weld = |b: usize| robot.bodies.get(b).map_or(b, |x| x.weld);
        let covered = |b: usize| {
            robot.geoms.iter().any(|g| {
                weld(g.body) == weld(b)
                    && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
                    && takes_part(g.id)
            })
        };
        let share = cx.opt("min_link_share");
        let planar = vertical_plane_bases(robot);
        let mut bases = floating_bases(robot);
        for &b in &planar {
            if !bases.contains(&b) {
                bases.push(b);
            }
        }
        let feet = feet_over(robot, cx.spec, &bases);
        for base in bases {
            let jointed = robot.joints.iter().any(|j| {
                j.body != base
                    && matches!(j.jtype, JointType::Hinge | JointType::Slide)
                    && in_subtree(robot, base, j.body)
            });
            let on_feet: Vec<usize> = feet
                .iter()
                .filter(|f| in_subtree(robot, base, f.root))
                .flat_map(|f| std::iter::once(f.root).chain(f.toes.iter().copied()))
                .collect();
            let n_feet = feet
                .iter()
                .filter(|f| {
                    in_subtree(robot, base, f.root)
                        && (f.kind != FootKind::Wheel || ends_a_leg(robot, base, f.root))
                })
                .count();
            let min_feet =
                if planar.contains(&base) { MIN_FEET_VERTICAL_PLANE } else { MIN_FEET_FLOATING };
            if !jointed || n_feet < min_feet {
                continue;
            }
            let bodies: Vec<usize> =
                (1..robot.bodies.len()).filter(|&b| in_subtree(robot, base, b)).collect();
            let pos = |b: usize| robot.key.body_xpos.get(b).copied().unwrap_or([0.0; 3]);
            let size = bodies
                .iter()
                .flat_map(|&a| bodies.iter().map(move |&b| (a, b)))
                .map(|(a, b)| dist(pos(a), pos(b)))
                .fold(0.0, f64::max);
            if size <= 0.0 {
                continue;
            }
            let colliders: Vec<&Geom> = robot
                .geoms
                .iter()
                .filter(|g| {
                    in_subtree(robot, base, g.body)
                        && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
                        && takes_part(g.id)
                })
                .collect();
            let bare: Vec<(usize, f64)> = bodies
                .iter()
                .filter(|&&b| !on_feet.contains(&b) && !covered(b))
                .map(|&b| (b, bare_stretch(robot, b, &colliders)))
                .filter(|&(_, r)| r >= share * size)
                .collect();
            if bare.is_empty() {
                continue;
            }
            out.push(report(cx, &bare, size, share, n_feet));
        }
        switched_off(cx, out);
    }
}

/// Whether the geom's name or its mesh's name calls it collision geometry.
fn named_collision(robot: &Robot, g: &Geom) -> bool {
    let mesh = usize::try_from(g.mesh).ok().and_then(|m| robot.meshes.get(m));
    [Some(&g.name), mesh].into_iter().flatten().any(|n| n.to_lowercase().contains("collision"))
}

/// Bodies outside every floating robot whose collision-named geometry compiles with no contact
/// bits while jointed links collide (the rule's docs).
fn switched_off(cx: &Context, out: &mut Vec<Finding>) {
    let robot = cx.robot;
    let takes_part = |g: usize| crate::model::contact::takes_part(robot, g);
    let solid = |g: &Geom| g.body != 0 && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield);
    // A static body (weld 0) is its own group; a moving one is its weld body.
    let group = |b: usize| match robot.bodies.get(b).map_or(0, |x| x.weld) {
        0 => b,
        w => w,
    };
    let jointed_collide =
        robot.geoms.iter().any(|g| solid(g) && robot.bodies[g.body].weld != 0 && takes_part(g.id));
    let floating = floating_bases(robot);
    if !jointed_collide || floating.contains(&0) {
        return;
    }
    let mut seen: Vec<usize> = Vec::new();
    for g in robot.geoms.iter().filter(|g| solid(g) && !takes_part(g.id)) {
        let key = group(g.body);
        if seen.contains(&key)
            || !named_collision(robot, g)
            || floating.iter().any(|&fb| in_subtree(robot, fb, g.body))
            || robot.geoms.iter().any(|h| solid(h) && group(h.body) == key && takes_part(h.id))
        {
            continue;
        }
        seen.push(key);
        let mesh = usize::try_from(g.mesh).ok().and_then(|m| robot.meshes.get(m));
        let what = match (g.name.is_empty(), mesh) {
            (false, _) => format!("geom `{}`", g.name),
            (true, Some(m)) => format!("geom no. {} (mesh `{m}`)", g.id),
            (true, None) => format!("geom no. {}", g.id),
        };
        let body = robot.body_name(g.body);
        out.push(
            cx.at_elem(
                ElemKind::Geom,
                g.id,
                &g.name,
                format!(
                    "body `{body}`'s collision geometry collides with nothing: {what}, named as collision geometry, compiles with contype = conaffinity = 0 and no geom of the body takes part in contacts, while the model's jointed links collide and pass through it"
                ),
            )
            .label("contype = conaffinity = 0")
            .note("a class meant for visual geoms (contype=\"0\" conaffinity=\"0\") given to the collision mesh switches it off: the arms sweep through the body in training, and reach poses the hardware's body blocks")
            .help("give the collision geom the contact bits of the model's other collision geoms (a collision class, or contype=\"1\" conaffinity=\"1\"), or exclude the pairs that must not touch with <contact><exclude>")
            .subject(Subject::Body(g.body))
            .measured(0.0, "contact bits")
            .expected(1.0, "contact bits"),
        );
    }
}

fn report(cx: &Context, bare: &[(usize, f64)], size: f64, share: f64, n_feet: usize) -> Finding {
    let robot = cx.robot;
    let list: Vec<String> = bare
        .iter()
        .map(|&(b, r)| format!("{} ({} m bare)", robot.body_name(b), fmt_num(r, 2)))
        .collect();
    let shown = if list.len() > 8 {
        format!("{}, … ({} links)", list[..8].join(", "), list.len())
    } else {
        list.join(", ")
    };
    let n = bare.len();
    let (b0, _) = bare[0];
    let name = robot.body_name(b0);
    let mut f = cx
        .at_elem(
            ElemKind::Body,
            b0,
            name,
            format!(
                "{n} link{} of the legged robot {} no collision geometry while its {}: {shown}",
                if n == 1 { "" } else { "s" },
                if n == 1 { "has" } else { "have" },
                if n_feet == 1 {
                    "foot collides".to_string()
                } else {
                    format!("{n_feet} feet collide")
                }
            ),
        )
        .label("no geom of this link takes part in contacts");
    for &(b, _) in bare.iter().skip(1).take(3) {
        f = f.secondary(
            robot.elem_loc(ElemKind::Body, b, robot.body_name(b)),
            "no collision geometry either",
        );
    }
    f.note(format!(
        "each listed link has a stretch of at least {} m ({} of the robot's size, {} m) outside every collision geom, and nothing of it can touch the floor or another link: a falling robot sinks its knees and torso into the ground, a swing leg passes through the stance leg, an arm through the torso — motions and recoveries the hardware cannot make",
        fmt_num(share * size, 2),
        fmt_num(share, 2),
        fmt_num(size, 2)
    ))
    .help("give each listed link a collision primitive fitted to it (a capsule along a thigh or forearm, a box on the torso) in the collision group (3); a variant that keeps only the foot contacts on purpose (an MJX training file) lists its contacts with <contact><pair> or says why in a suppression comment")
    .subject(Subject::Model)
    .measured(n as f64, "links")
    .expected(0.0, "links")
}
