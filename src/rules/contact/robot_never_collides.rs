use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::contact::{Filter, contact, contacts_disabled, filtered, takes_part};
use crate::model::mjcf::ElemKind;
use crate::model::{Format, GeomType, Robot};
use crate::rules::{Context, Rule, RuleMeta};

declare_rule! {
    /// ## What it does
    /// Reads the robot's contact filter as MuJoCo applies it (contype/conaffinity bit pairs:
    /// two geoms touch when one's contype shares a bit with the other's conaffinity; an
    /// explicit `<contact><pair>` touches whatever the bits) and reports two cases:
    /// - **falls through the floor**: the model has a floor (a plane or height field of the
    ///   world, or of a body welded to it) and no geom of the robot (the bodies that move) can
    ///   touch any floor — every robot geom's bits miss every floor's and no `<pair>` joins them;
    /// - **never touches itself**: the robot's geoms on bodies that MuJoCo would let touch (not
    ///   welded together, not a body and its parent, no `<exclude>` between them) are all kept
    ///   apart by their bits — AgiBot X1's collision class writes contype 1 and inherits
    ///   conaffinity 0, so no robot geom accepts another's. A model that declares any
    ///   `<contact><pair>` lists the contacts it wants and is not judged for this case.
    ///
    /// Not judged: a model with `<flag contact="disable"/>` (no contact by choice), a robot
    /// whose geoms never collide at all (`links-without-collision` and the foot rules say
    /// what is missing), a robot with one rigid part, and URDF files (MuJoCo's importer gives
    /// every geom contype 1, conaffinity 1).
    ///
    /// ## Why is this bad?
    /// A robot none of whose geoms can touch the floor falls through it at the first step: the
    /// feet's bits do not meet the floor's. A robot whose limbs cannot touch each other lets a
    /// leg swing through the other and an arm through the torso; a policy trained on it learns
    /// gaits and reaches the hardware cannot make (crossing the legs costs nothing). A model may
    /// leave self-contact out on purpose for speed; then the training must keep the limbs apart
    /// some other way. MuJoCo documentation, Computation › Collision detection (contype and
    /// conaffinity) and XML reference `contact/pair`.
    ///
    /// ## How it is confirmed
    /// Static: the compiled geoms' contype and conaffinity, the compiled `<pair>`s and
    /// `<exclude>`s and the bodies' weld structure, filtered as `mj_collision` filters them.
    /// A fact of the file.
    ///
    /// ## How to fix
    /// Give the robot's collision geoms a conaffinity that shares a bit with their contype (the
    /// default 1/1), or the floor a conaffinity that meets the robot's contype; to keep some
    /// pairs apart use `<exclude>` or separate bits for the sides (contype 2 / conaffinity 4 on
    /// the left, 4 / 2 on the right), or list the contacts that matter with `<contact><pair>`.
    pub RobotNeverCollides {
        id: "robot-never-collides",
        group: "contact",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

/// Floors: the planes and height fields of the world or of bodies welded to it.
fn floors(robot: &Robot) -> Vec<usize> {
    robot
        .geoms
        .iter()
        .filter(|g| matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
        .filter(|g| robot.bodies.get(g.body).is_some_and(|b| b.weld == 0))
        .map(|g| g.id)
        .collect()
}

/// "contype 1 / conaffinity 0" for each distinct pair of bits among `geoms`, most used first.
fn masks(robot: &Robot, geoms: &[usize]) -> String {
    let mut seen: Vec<((i32, i32), usize)> = Vec::new();
    for &g in geoms {
        let m = (robot.geoms[g].contype, robot.geoms[g].conaffinity);
        match seen.iter_mut().find(|s| s.0 == m) {
            Some(s) => s.1 += 1,
            None => seen.push((m, 1)),
        }
    }
    seen.sort_by_key(|s| std::cmp::Reverse(s.1));
    let v: Vec<String> = seen
        .iter()
        .take(4)
        .map(|((c, a), n)| format!("contype {c} / conaffinity {a} ({n})"))
        .collect();
    v.join(", ")
}

impl Rule for RobotNeverCollides {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if robot.format != Format::Mjcf || contacts_disabled(robot) {
            return;
        }
        let moving = |b: usize| robot.bodies.get(b).is_some_and(|x| x.weld != 0);
        let parts: Vec<usize> = robot
            .geoms
            .iter()
            .filter(|g| moving(g.body) && takes_part(robot, g.id))
            .map(|g| g.id)
            .collect();
        if parts.is_empty() {
            return;
        }
        let floors = floors(robot);
        let touches_floor =
            parts.iter().any(|&g| floors.iter().any(|&f| contact(robot, g, f).is_some()));
        if !floors.is_empty() && !touches_floor {
            out.push(falls_through(cx, &parts, floors[0]));
        }
        // Pairs of robot geoms MuJoCo would test but for the bits; a model that lists its
        // contacts in <pair>s chose them itself.
        if !robot.pairs.is_empty() {
            return;
        }
        let mut candidates = 0usize;
        let mut touching = false;
        for (i, &a) in parts.iter().enumerate() {
            for &b in &parts[i + 1..] {
                if contact(robot, a, b).is_some() {
                    touching = true;
                    break;
                }
                if filtered(robot, a, b) == Some(Filter::Masks) {
                    candidates += 1;
                }
            }
            if touching {
                break;
            }
        }
        if !touching && candidates > 0 {
            out.push(never_touches_itself(cx, &parts, candidates));
        }
    }
}

fn falls_through(cx: &Context, parts: &[usize], floor: usize) -> Finding {
    let robot = cx.robot;
    let f = &robot.geoms[floor];
    let name = if f.name.is_empty() { format!("no. {floor}") } else { format!("`{}`", f.name) };
    let msg = format!(
        "no geom of the robot can touch the floor {name} (contype {} / conaffinity {}): the robot's {} colliding geom{} ({}) share no bit with it either way and no <pair> joins them, so the robot falls through the floor",
        f.contype,
        f.conaffinity,
        parts.len(),
        if parts.len() == 1 { "" } else { "s" },
        masks(robot, parts)
    );
    let g0 = &robot.geoms[parts[0]];
    cx.at_attr(ElemKind::Geom, floor, &f.name, "conaffinity", msg)
        .label("the floor's bits")
        .secondary(robot.elem_loc(ElemKind::Geom, g0.id, &g0.name), "a robot geom that misses it")
        .note("MuJoCo tests two geoms only when one's contype shares a bit with the other's conaffinity (or a <contact><pair> names them); the robot's geoms and the floor's meet neither way")
        .help("give the robot's collision geoms a contype that shares a bit with the floor's conaffinity (or the floor a conaffinity that meets theirs), or pair the feet with the floor in <contact>")
        .subject(Subject::Model)
        .with("robot_geoms", parts.len() as f64)
}

fn never_touches_itself(cx: &Context, parts: &[usize], candidates: usize) -> Finding {
    let robot = cx.robot;
    let msg = format!(
        "no two geoms of the robot can touch each other: all {candidates} pairs of its colliding geoms that MuJoCo would test (on bodies not welded together, not parent and child, not excluded) are kept apart by their contype/conaffinity bits ({}) and no <pair> joins any: the limbs pass through each other and the body",
        masks(robot, parts)
    );
    let g0 = &robot.geoms[parts[0]];
    cx.at_attr(ElemKind::Geom, g0.id, &g0.name, "conaffinity", msg)
        .label("no robot geom accepts another's contype")
        .note("two geoms touch when one's contype shares a bit with the other's conaffinity; a robot whose geoms all accept no robot contype (conaffinity 0, or bits that miss) never meets itself, so a policy may cross its legs or swing an arm through the torso at no cost. If self-contact is left out on purpose (speed), the training must keep the limbs apart")
        .help("give the collision class a conaffinity sharing a bit with its contype (contype 1 conaffinity 1), keeping chosen pairs apart with <exclude> or side bits (left contype 2 / conaffinity 4, right 4 / 2)")
        .subject(Subject::Model)
        .measured(0.0, "pairs")
        .with("candidate_pairs", candidates as f64)
}
