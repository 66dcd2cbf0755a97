use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::contact::{contact, ground_partners, pair_of};
use crate::model::mjcf::ElemKind;
use crate::model::{GeomType, Robot};
use crate::probe::settle::{Settle, StanceClaim};
use crate::probe::slide::{FootSlide, PUSH_S, PUSH_SHARE, Slide};
use crate::probe::{Measure, Measurement, Preconditions, StanceSettle, Verdict};
use crate::rules::contact::feet::{
    Foot, FootKind, MIN_SOLE_AREA, ankle_turning, corner_points, feet, is_humanoid,
};
use crate::rules::contact::foot_radius::radius_finding;
use crate::rules::geometry::shapes::{Placed, hull_area};
use crate::rules::{Context, Domain, Rule, RuleMeta, claim_each, opt, opt_one_of};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Checks the collision geometry of each foot (its foot and toe bodies): contact must use
    /// primitives, not meshes — capsules or spheres, and boxes unless `allow_boxes = 0`; capsule,
    /// sphere and cylinder radii of the geoms that touch the ground within [`min_radius`,
    /// `max_radius`] (0.5–50 mm by default: a sanity range against unit and scale errors, not
    /// one robot's design — the Asimov feet use about 12 mm, common reference feet 5 mm corner
    /// spheres, Menagerie's Unitree G1 1 mm corner points). Spheres below `min_radius` are a
    /// sole's corner points, not a slip, when three or more of them span a support polygon of
    /// at least 1 mm² (Atlas: eight 0.1 mm spheres over 26 × 13 cm): a sphere's radius only
    /// lifts its point contact, and a foot scaled down by a unit error spans no polygon; no
    /// frictionless (condim 1) ground contact, and the stated `condim`; sliding friction within
    /// `friction_tolerance` of the stated `friction`; at least three non-collinear
    /// ground contact points whose support polygon reaches both the heel and the toe third of the
    /// foot; and left and right feet with the same number and sizes of geoms (sizes within 2 % or
    /// 0.5 mm, so mesh export noise does not count). Problems are reported once per foot, listing
    /// the geoms, at the first offending geom's attribute. The support polygon counts a box's
    /// bottom face and a lying capsule's two ends whole when they are within 15° of the ground at
    /// the keyframe: the foot settles onto its sole, and the tilt is `toe-tilt`'s finding. With no
    /// keyframe (qpos0, no stance stated) a box lying on its largest face counts whole at any tilt.
    ///
    /// condim and friction are judged as MuJoCo combines them for each foot geom with the ground
    /// geoms it may touch (world-body geoms whose contype/conaffinity allow the pair): the larger
    /// condim and friction of the two, or the higher-`priority` geom's (`model::contact`). A
    /// condim-1 foot on a condim-3 floor has condim-3 contacts and is not reported. An explicit
    /// `<contact><pair>` of a foot geom and a ground geom sets the contact's condim and friction
    /// whatever the geoms' own values and masks (a foot that touches the floor only through pairs
    /// is judged by them, at the pair's attribute; a geom whose contact with the floor the masks
    /// or an `<exclude>` remove makes no ground contact and is not judged). With no
    /// ground geom in the file (a robot file without its scene), the geom's own values are
    /// judged and the message says so.
    ///
    /// Friction and condim are matters of intent: MuJoCo's default sliding friction 1 (its
    /// default condim is 3), and condim 6 (rolling friction, common on quadruped feet), are
    /// deliberate choices in many public models. Sliding friction is judged only against an
    /// intended value the user states — `friction` / `friction_tolerance` under
    /// `[rules.foot-collision-geometry]` in modellint.toml: one robot's identified friction (the
    /// Asimov 0.6) is no expectation for another robot's feet on another floor. Likewise condim:
    /// torsional and rolling friction (condim 4/6, a point-foot quadruped's usual choice) are
    /// judged only against a `condim` the user states; condim 1 (frictionless feet: the foot
    /// slides under any sideways force) is a warning whatever the intent.
    ///
    /// Foot bodies come from the spec's `robot.foot_bodies` globs; without them, from body names
    /// containing `foot`, `ankle_roll`, `toe` or `sole`; failing that, the leaf bodies (no body
    /// below them collides) whose collision geoms reach within 3 cm of the robot's lowest
    /// point; never a push rod (a body on ball joints only that a `connect` or `weld` equality
    /// ties to another body, such as Digit's toe rods, whatever its name). Only floating-base robots have feet (a fixed-base arm gets
    /// no foot rule unless the spec names feet). Families: a wheel (a sphere, cylinder or
    /// ellipsoid on an unlimited hinge) is not a foot; a point foot (spheres touching down
    /// within 2 cm of each other, as on quadrupeds) is judged by its ground geoms only — a shank
    /// geom above the foot sphere is not a foot — and gets no support-polygon finding, except on
    /// a humanoid with two feet (Gymnasium's Humanoid, a sphere per foot). A foot that touches down along a line or at one point is
    /// reported only when a joint at the foot could turn it about that contact (an ankle roll
    /// within 30° of the line, any tilting joint for a point, a ball joint; its axis at the
    /// keyframe passing within a third of the leg's length of the contact): then the foot is
    /// meant to stand on a sole that was modelled too thin. Without such a joint the line or
    /// point is the design — an underactuated biped's blade foot whose ankle only pitches and
    /// that the hip roll balances (Cassie), a stilt, a quadruped's foot bar — and is not
    /// reported, except on a humanoid (a left and a right foot and at least two limbs off the legs
    /// with two or more joints: arms; a jointed branch off one leg, such as Cassie's push rods,
    /// cranks and heel springs, is that leg's mechanism), which stands on soles: an ankle-pitch-only
    /// humanoid (H1 style) whose sole is a line is reported. On a flat foot, geom types and radii are judged on the ground
    /// geoms too (within 10 mm of the foot's lowest point at the keyframe: an ankle housing above
    /// the sole is not a foot contact); meshes on any of the foot's geoms.
    ///
    /// ## Why is this bad?
    /// Contact is system identification too. Mesh contact against the floor produces few,
    /// jumping contact points whose number changes with tiny pose changes, so the policy learns
    /// artifacts of the mesh; mesh-vs-mesh contact is worse. A foot with fewer than three
    /// non-collinear contact points, or none at heel or toe, has a degenerate support polygon.
    /// condim ≠ 3 changes the friction model (1: frictionless, 4/6: torsional and rolling
    /// friction), and friction other than the real feet's on the real floor changes slip.
    /// Mismatched left and right feet make the gait asymmetric.
    ///
    /// ## How it is confirmed
    /// Probe `stance-settle` (on a floor, feet loaded, robot upright: otherwise inconclusive)
    /// confirms mesh, non-primitive and support-polygon findings when the foot's contacts
    /// chatter (> 5 changes/s) or penetrate (> 5 mm). Radius, condim, friction and left/right
    /// mismatch are facts of the file: no stance run confirms or refutes them (a stance run
    /// does not measure friction). Probe `foot-slide` measures the condim and friction findings:
    /// the contact dimension and sliding friction MuJoCo built for the foot's ground contacts
    /// (`mjContact.dim`, `mjContact.friction`) and how far the foot slides under a sideways push
    /// of 5 % of the weight (inconclusive without a floor, a loaded upright stance, or a foot
    /// geom touching the ground).
    ///
    /// ## How to fix
    /// Replace mesh foot collision with several capsules (radius ≈12 mm) at heel, midfoot and
    /// toe, keep the mesh as a visual geom (`contype="0" conaffinity="0"`), set `condim="3"` and
    /// `friction="0.6"` on them — note MuJoCo uses the larger friction of the two geoms, so the
    /// floor must not be higher — and make the left and right feet mirror images.
    pub FootCollisionGeometry {
        id: "foot-collision-geometry",
        group: "contact",
        level: Severity::Warning,
        probe: StanceSettle,
        also: [FootSlide],
        options: [
            opt_one_of("allow_boxes", 1.0, "bool", "1: box feet are acceptable primitives; 0: only capsules and spheres", &[0.0, 1.0]),
            opt("min_radius", 0.0005, "m", Domain::NON_NEGATIVE, "smallest capsule/sphere radius"),
            opt("max_radius", 0.05, "m", Domain::POSITIVE, "largest capsule/sphere radius"),
            opt("unit_max_leg_fraction", 0.5, "", Domain::POSITIVE, "a contact radius above this fraction of its leg's length (a sphere as wide as the leg is long) is worded as a unit or scale error"),
            opt("unit_min_leg_fraction", 0.0001, "", Domain::POSITIVE, "a contact radius below this fraction of its leg's length (0.1 mm per metre of leg) is worded as a unit or scale error"),
            opt("friction", 0.6, "", Domain::NON_NEGATIVE, "intended sliding friction of foot geoms; judged only when this or `friction_tolerance` is set"),
            opt("friction_tolerance", 0.2, "", Domain::NON_NEGATIVE, "allowed deviation from `friction`"),
            opt_one_of("condim", 3.0, "", "intended contact dimension of the feet's ground contacts; other than 1 (frictionless, always reported) judged only when set", &[1.0, 3.0, 4.0, 6.0]),
            opt("contact_window", 0.005, "m", Domain::POSITIVE, "geom points within this of the foot's lowest point count as ground contacts"),
        ],
    }
}

fn gname(robot: &Robot, g: usize) -> String {
    let n = &robot.geoms[g].name;
    // Unnamed: its number in its body, which a scene file around the robot does not change.
    if n.is_empty() { format!("geom {}", robot.unnamed_geom(g)) } else { format!("`{n}`") }
}

fn list(robot: &Robot, gs: &[usize]) -> String {
    let mut v: Vec<String> = gs.iter().take(6).map(|&g| gname(robot, g)).collect();
    if gs.len() > 6 {
        v.push(format!("and {} more", gs.len() - 6));
    }
    v.join(", ")
}

fn type_word(t: GeomType) -> &'static str {
    match t {
        GeomType::Capsule => "capsule",
        GeomType::Sphere => "sphere",
        GeomType::Box => "box",
        GeomType::Cylinder => "cylinder",
        GeomType::Ellipsoid => "ellipsoid",
        GeomType::Mesh => "mesh",
        _ => "geom",
    }
}

/// The contact of foot geom `g` with ground geom `o` is an explicit pair's.
fn pair_at(robot: &Robot, g: usize, o: Option<usize>) -> bool {
    o.is_some_and(|o| pair_of(robot, g, o).is_some())
}

/// A condim or friction finding at the attribute that sets the value: the explicit pair's, or
/// the foot geom's own.
fn at_value(cx: &Context, g: usize, o: Option<usize>, attr: &str, msg: String) -> Finding {
    let robot = cx.robot;
    match o.and_then(|o| pair_of(robot, g, o)) {
        Some(p) => cx.at_attr(ElemKind::Pair, p.id, &p.name, attr, msg),
        None => cx.at_attr(ElemKind::Geom, g, &robot.geoms[g].name, attr, msg),
    }
}

/// Labels the other side of a condim or friction finding: the foot geom whose own value the
/// explicit pair overrides, or the ground geom the value is combined with.
fn ground_label(robot: &Robot, f: Finding, g: usize, o: Option<usize>, attr: &str) -> Finding {
    let Some(o) = o else { return f };
    let val = |x: &crate::model::Geom| {
        if attr == "condim" { x.condim.to_string() } else { fmt_num(x.friction[0], 3) }
    };
    if pair_of(robot, g, o).is_some() {
        let gloc = robot.elem_loc(ElemKind::Geom, g, &robot.geoms[g].name);
        return f.secondary(
            gloc,
            format!("foot geom, own {attr} {} (overridden by the pair)", val(&robot.geoms[g])),
        );
    }
    let oloc = robot.elem_loc(ElemKind::Geom, o, &robot.geoms[o].name);
    f.secondary(oloc, format!("ground geom, {attr} {}", val(&robot.geoms[o])))
}

/// Largest tilt of a box face or lying capsule at the keyframe that still counts as a sole
/// the foot settles onto (rad): 15°, well past a modelling slip, well short of a foot on its toe.
const SOLE_TILT: f64 = 15.0 * std::f64::consts::PI / 180.0;

/// Left/right feet match when every geom has a partner of the same type whose sizes agree within
/// 2 % or 0.5 mm: mesh-derived sizes differ by export noise (0.1–0.2 mm), a real edit by more.
const MIRROR_REL: f64 = 0.02;
const MIRROR_ABS: f64 = 0.0005;

/// What the `stance-settle` probe checks: the foot's contacts chatter (more than 5 changes/s) or
/// penetrate the floor by more than 5 mm while standing.
#[derive(Debug)]
pub struct FootContactUnsteady {
    /// The foot's body.
    pub body: usize,
}

impl StanceClaim for FootContactUnsteady {
    fn judge_settled(&self, l: &Loaded, s: &Settle, pre: &Preconditions) -> Verdict {
        let foot = s.foot(&l.robot, self.body);
        let touching =
            foot.geoms.iter().filter(|g| s.load(**g) > 0.02 * foot.load.max(1e-9)).count();
        let note = format!(
            "{} contact changes/s, {} mm deepest penetration, {} loaded contact geom(s)",
            fmt_num(foot.chatter_per_s, 3),
            fmt_num(foot.penetration * 1000.0, 3),
            touching
        );
        if foot.chatter_per_s > 5.0 || foot.penetration > 0.005 {
            Verdict::confirmed(pre, foot.measured, note)
        } else {
            // Steady contact in one 1 s stance does not show the geometry is sound (it shows
            // nothing about slip, rolling or other poses): no verdict.
            Verdict::inconclusive(pre, foot.measured, format!("steady stance contact ({note})"))
        }
    }
}

impl Rule for FootCollisionGeometry {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let first = out.len();
        self.check_feet(cx, out);
        claim_each(&mut out[first..], |f| match f.subject {
            Subject::Foot(body) => Some(FootContactUnsteady { body }),
            _ => None,
        });
    }
}

impl FootCollisionGeometry {
    fn check_feet(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let allow_boxes = cx.opt("allow_boxes") != 0.0;
        let (rmin, rmax) = (cx.opt("min_radius"), cx.opt("max_radius"));
        let (mu, mu_tol) = (cx.opt("friction"), cx.opt("friction_tolerance"));
        let window = cx.opt("contact_window");
        // Intended friction/condim stated by the user (config), not just this rule's default.
        let stated =
            cx.options.contains_key("friction") || cx.options.contains_key("friction_tolerance");
        // Intended contact dimension: without a stated one only frictionless contact (condim 1)
        // is a defect; torsional/rolling friction (4/6) is a design choice, not an error.
        let condim_stated = cx.options.contains_key("condim");
        let want_c = cx.opt("condim").round() as i32;
        // A wheel is not a foot; a point foot is judged by the geoms that touch the ground only
        // (a shank cylinder above the foot sphere is not a foot).
        let all_feet: Vec<Foot> = feet(robot, cx.spec)
            .into_iter()
            .filter(|f| f.kind != FootKind::Wheel)
            .map(|mut f| {
                if f.kind == FootKind::Point {
                    f.geoms = f.ground.clone();
                }
                f
            })
            .collect();
        let has_floor = (0..robot.geoms.len()).any(|g| crate::probe::stance::is_ground(robot, g));
        let humanoid = is_humanoid(robot, &all_feet);
        // No keyframe: qpos0, no stance stated (Digit v3's soles 23.5° off the ground there).
        let any_tilt = robot.keys.is_empty();
        for foot in &all_feet {
            let label = foot.label(robot);
            let subj = Subject::Foot(foot.root);
            // Meshes.
            let meshes: Vec<usize> = foot
                .geoms
                .iter()
                .copied()
                .filter(|&g| robot.geoms[g].gtype == GeomType::Mesh)
                .collect();
            if let Some(&g0) = meshes.first() {
                let partners: Vec<usize> = robot
                    .geoms
                    .iter()
                    .filter(|o| {
                        o.gtype == GeomType::Mesh
                            && !foot.geoms.contains(&o.id)
                            && meshes.iter().any(|&m| contact(robot, m, o.id).is_some())
                    })
                    .map(|o| o.id)
                    .collect();
                let mut f = cx
                    .at_attr(ElemKind::Geom, g0, &robot.geoms[g0].name, "type", format!("{label} collides through mesh geoms: {}", list(robot, &meshes)))
                    .label("mesh foot collision")
                    .note("mesh-floor contact yields few, jumping contact points that change with tiny pose changes; policies learn artifacts of the mesh instead of the foot")
                    .help("collide with several capsules (radius ≈12 mm) at heel, midfoot and toe; keep the mesh as a visual geom with contype=\"0\" conaffinity=\"0\"")
                    .subject(subj)
                    .with("mesh_geoms", meshes.len() as f64);
                if cx.level >= Severity::Warning {
                    f.severity = Severity::Error;
                }
                if !partners.is_empty() {
                    f.message.push_str(&format!(
                        "; it can also touch other meshes mesh-to-mesh ({})",
                        list(robot, &partners)
                    ));
                }
                out.push(f);
            }
            // Non-preferred primitives and radii: judged on the geoms that touch the ground
            // (within GROUND_WINDOW of the foot's lowest point at the keyframe); an ankle
            // housing above the sole is not a foot contact.
            let odd: Vec<usize> = foot
                .ground
                .iter()
                .copied()
                .filter(|&g| match robot.geoms[g].gtype {
                    GeomType::Capsule | GeomType::Sphere | GeomType::Mesh => false,
                    GeomType::Box => !allow_boxes,
                    _ => true,
                })
                .collect();
            if let Some(&g0) = odd.first() {
                out.push(
                    cx.at_attr(ElemKind::Geom, g0, &robot.geoms[g0].name, "type", format!("{label} collides through {} geoms: {}", type_word(robot.geoms[g0].gtype), list(robot, &odd)))
                        .label("not a capsule or sphere")
                        .note("box and cylinder contacts with the floor switch between corner, edge and face contact as the foot rolls, which makes contact forces less repeatable than capsule contact")
                        .help("use capsules (radius ≈12 mm) at heel, midfoot and toe, or set `allow_boxes = 1` for this rule if box feet are intended")
                        .subject(subj),
                );
            }
            // Radius. Spheres below `min_radius` that together span a support polygon are the
            // foot's corner points (a sphere's radius only lifts a point contact; a foot scaled
            // down by a unit error spans no polygon either).
            let corners = corner_points(robot, foot, rmin);
            let bad_r: Vec<usize> = foot
                .ground
                .iter()
                .copied()
                .filter(|&g| {
                    matches!(
                        robot.geoms[g].gtype,
                        GeomType::Capsule | GeomType::Sphere | GeomType::Cylinder
                    )
                })
                .filter(|&g| {
                    let r = robot.geoms[g].size[0];
                    (r < rmin && !corners.contains(&g)) || r > rmax
                })
                .collect();
            if !bad_r.is_empty() {
                out.push(radius_finding(cx, foot, &bad_r, &label, &list(robot, &bad_r)));
            }
            // condim and friction as MuJoCo builds them against the ground the foot touches
            // (model::contact): an explicit <pair>'s own values, else the combination — a
            // condim-1 foot on a condim-3 floor has condim-3 contacts.
            let eff = |g: usize| -> Vec<(Option<usize>, i32, f64)> {
                let ground = ground_partners(robot, g);
                let own = &robot.geoms[g];
                if ground.is_empty() {
                    // A geom that never touches the model's floor (masks, <exclude>) makes no
                    // ground contact to judge; without a floor, its own values are judged.
                    return if has_floor {
                        vec![]
                    } else {
                        vec![(None, own.condim, own.friction[0])]
                    };
                }
                ground.iter().map(|(o, c)| (Some(*o), c.condim, c.friction[0])).collect()
            };
            let with = |g: usize, o: Option<usize>, what: &str| {
                if let Some(o) = o
                    && let Some(p) = pair_of(robot, g, o)
                {
                    return format!(
                        "an explicit <contact><pair> with ground geom {} sets it, the geoms' own values do not count: {what} {}",
                        gname(robot, o),
                        if what == "condim" {
                            p.condim.to_string()
                        } else {
                            fmt_num(p.friction[0], 3)
                        }
                    );
                }
                match o {
                    Some(o) => {
                        let (mine, theirs) = (&robot.geoms[g], &robot.geoms[o]);
                        let val = |x: &crate::model::Geom| {
                            if what == "condim" {
                                x.condim.to_string()
                            } else {
                                fmt_num(x.friction[0], 3)
                            }
                        };
                        let rule = match crate::model::contact::combine(mine, theirs).by_priority {
                            Some(w) if w == o => "the higher-priority ground geom's",
                            Some(_) => "the higher-priority foot geom's",
                            None => "the larger of the two",
                        };
                        format!(
                            "{rule}: {what} {} on the foot, {} on ground geom {}",
                            val(mine),
                            val(theirs),
                            gname(robot, o)
                        )
                    }
                    None => format!(
                        "the geom's own {what}: no ground geom in this file, MuJoCo combines it with the floor's by maximum or priority",
                    ),
                }
            };
            let bad_c: Vec<(usize, Option<usize>, i32)> = foot
                .geoms
                .iter()
                .filter_map(|&g| {
                    eff(g)
                        .into_iter()
                        .find(|e| e.1 != want_c && (e.1 == 1 || condim_stated))
                        .map(|(o, c, _)| (g, o, c))
                })
                .collect();
            if let Some(&(g0, o0, c)) = bad_c.first() {
                let why = match c {
                    1 => "condim 1 is frictionless contact: the foot slides freely".to_string(),
                    _ if c > want_c => format!(
                        "condim {c} adds torsional/rolling friction that the stated contact model (condim {want_c}) does not have"
                    ),
                    _ => format!(
                        "condim {c} lacks the torsional/rolling friction of the stated contact model (condim {want_c})"
                    ),
                };
                let geoms: Vec<usize> = bad_c.iter().map(|b| b.0).collect();
                let mut f = at_value(
                    cx,
                    g0,
                    o0,
                    "condim",
                    format!(
                        "{label} contacts use condim {c} (expected {want_c}; {}): {}",
                        with(g0, o0, "condim"),
                        list(robot, &geoms)
                    ),
                );
                f = ground_label(robot, f, g0, o0, "condim");
                out.push(
                    f.label(format!("condim {}", if pair_at(robot, g0, o0) { c } else { robot.geoms[g0].condim }))
                        .note(format!(
                            "{why}; MuJoCo uses the larger condim of the two contacting geoms, or the higher-priority geom's, and an explicit <pair>'s own condim instead of either"
                        ))
                        .help(if pair_at(robot, g0, o0) {
                            format!("set condim=\"{want_c}\" on the <pair> elements of the foot geoms: a pair's values replace the geoms'")
                        } else {
                            format!("set condim=\"{want_c}\" on foot and toe geoms (and not higher on the floor)")
                        })
                        .subject(subj)
                        .measure(ContactAsBuilt { geoms: geoms.clone(), body: foot.root })
                        .measured(c as f64, "")
                        .expected(want_c as f64, ""),
                );
            }
            // Friction, against the value the user states: without one there is no expectation
            // (one robot's identified friction says nothing of another's feet and floor).
            let bad_f: Vec<(usize, Option<usize>, f64)> = foot
                .geoms
                .iter()
                .filter(|_| stated)
                .filter_map(|&g| {
                    eff(g)
                        .into_iter()
                        .find(|e| (e.2 - mu).abs() > mu_tol)
                        .map(|(o, _, v)| (g, o, v))
                })
                .collect();
            if let Some(&(g0, o0, v)) = bad_f.first() {
                let geoms: Vec<usize> = bad_f.iter().map(|b| b.0).collect();
                let mut f = at_value(
                    cx,
                    g0,
                    o0,
                    "friction",
                    format!(
                        "{label} contacts have sliding friction {} (stated {} ± {}; {}): {}",
                        fmt_num(v, 3),
                        fmt_num(mu, 3),
                        fmt_num(mu_tol, 3),
                        with(g0, o0, "friction"),
                        list(robot, &geoms)
                    ),
                );
                f = ground_label(robot, f, g0, o0, "friction");
                out.push(
                    f
                        .label(format!("friction {}", fmt_num(if pair_at(robot, g0, o0) { v } else { robot.geoms[g0].friction[0] }, 3)))
                        .note("foot friction decides when the foot slips; a policy trained on grippier feet than the hardware's learns pushes that slip on the real floor")
                        .help(format!("set friction=\"{} …\" on the foot and toe geoms; MuJoCo combines friction by the maximum of the two geoms (or takes the higher-priority geom's), so the floor's friction must not exceed it", fmt_num(mu, 3)))
                        .subject(subj)
                        .measure(ContactAsBuilt { geoms: geoms.clone(), body: foot.root })
                        .measured(v, "")
                        .expected(mu, ""),
                );
            }
            // Support polygon (a point foot touches down at one spot by design; not a biped's).
            if foot.kind == FootKind::Point && !(humanoid && all_feet.len() == 2) {
                continue;
            }
            let placed: Vec<(usize, Placed)> =
                foot.geoms.iter().map(|&g| (g, Placed::of(robot, g))).collect();
            let zmin = placed.iter().map(|(_, p)| p.lowest()[2]).fold(f64::INFINITY, f64::min);
            let mut pts: Vec<[f64; 3]> = Vec::new();
            for (_, p) in &placed {
                if p.lowest()[2] <= zmin + window {
                    pts.extend(p.ground_points(zmin + window - p.lowest()[2]));
                    pts.push(p.lowest());
                    // A box sole or lying capsule a few degrees off the ground at the keyframe
                    // settles onto its whole flat feature (the tilt is toe-tilt's finding).
                    let plate = any_tilt && p.plate_face_down();
                    pts.extend(p.sole_points(if plate { f64::INFINITY } else { SOLE_TILT }));
                }
            }
            let xs: Vec<f64> = placed
                .iter()
                .flat_map(|(_, p)| [p.support([1.0, 0.0, 0.0])[0], p.support([-1.0, 0.0, 0.0])[0]])
                .collect();
            let (x0, x1) = (
                xs.iter().copied().fold(f64::INFINITY, f64::min),
                xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            );
            let third = (x1 - x0) / 3.0;
            let heel = pts.iter().any(|p| p[0] <= x0 + third);
            let toe = pts.iter().any(|p| p[0] >= x1 - third);
            let area = hull_area(&pts.iter().map(|p| [p[0], p[1]]).collect::<Vec<_>>());
            let degenerate = area < MIN_SOLE_AREA;
            // A line or point contact that no ankle joint can turn is the design (a blade foot
            // balanced by the hip, a stilt) — except on a humanoid, which stands on soles.
            let ankle = if degenerate { ankle_turning(robot, foot.root, &pts) } else { None };
            if degenerate && ankle.is_none() && !humanoid {
                continue;
            }
            if degenerate || !heel || !toe {
                let g0 = placed
                    .iter()
                    .find(|(_, p)| p.lowest()[2] <= zmin + window)
                    .map(|x| x.0)
                    .unwrap_or(foot.geoms[0]);
                let what = if degenerate && ankle.is_none() {
                    format!(
                        "{label} touches the ground along a line or at a point (support polygon {} cm²): a humanoid (two feet, arms) stands on soles, and with no joint at the foot to turn it about that contact the model can only balance on the line",
                        fmt_num(area * 1e4, 3)
                    )
                } else if degenerate {
                    format!(
                        "{label} touches the ground along a line or at a point (support polygon {} cm²) although joint `{}` at the foot can turn it about that contact",
                        fmt_num(area * 1e4, 3),
                        ankle.map_or("", |j| robot.joints[j].name.as_str())
                    )
                } else {
                    format!(
                        "{label} has no ground contact at the {}",
                        if !heel { "heel" } else { "toe" }
                    )
                };
                out.push(
                    cx.at_elem(ElemKind::Geom, g0, &robot.geoms[g0].name, what)
                        .label("lowest foot geom")
                        .note("a foot needs at least three non-collinear contact points spread from heel to toe for a stable support polygon; otherwise it tips about the contact line and the policy learns to balance on it")
                        .help("add capsules so heel, midfoot and toe all touch the ground in the standing pose")
                        .subject(subj)
                        .measured(area, "m²")
                        .with("ground_points", pts.len() as f64),
                );
            }
        }
        // Left/right match.
        let left: Vec<&Foot> = all_feet
            .iter()
            .filter(|f| f.side == Some(crate::rules::contact::feet::Side::Left))
            .collect();
        let right: Vec<&Foot> = all_feet
            .iter()
            .filter(|f| f.side == Some(crate::rules::contact::feet::Side::Right))
            .collect();
        if let (Some(l), Some(r)) = (left.first(), right.first())
            && !crate::rules::geometry::mirror_asymmetry::same_geoms(
                robot, &l.geoms, &r.geoms, MIRROR_REL, MIRROR_ABS,
            )
        {
            let g0 = r.geoms[0];
            let msg = if l.geoms.len() != r.geoms.len() {
                format!(
                    "left and right feet differ: {} has {} collision geoms, {} has {}",
                    robot.body_name(l.root),
                    l.geoms.len(),
                    robot.body_name(r.root),
                    r.geoms.len()
                )
            } else {
                format!(
                    "left and right feet differ in collision geom types or sizes ({} vs {})",
                    robot.body_name(l.root),
                    robot.body_name(r.root)
                )
            };
            let lloc = robot.elem_loc(ElemKind::Body, l.root, robot.body_name(l.root));
            out.push(
                    cx.at_elem(ElemKind::Geom, g0, &robot.geoms[g0].name, msg)
                        .label("right foot geometry")
                        .secondary(lloc, "left foot")
                        .note("asymmetric foot contact makes the two legs behave differently, and the policy learns a limp the hardware does not need")
                        .help("make the right foot's collision geoms the mirror image of the left's")
                        .subject(Subject::Foot(r.root))
                        .fact(),
                );
        }
    }
}

/// What the `foot-slide` probe measures about a condim or friction finding (a fact of the file):
/// the contacts MuJoCo built for the foot's geoms against the ground, and the foot's slide under
/// a small sideways push. Never a verdict.
#[derive(Debug)]
pub struct ContactAsBuilt {
    /// The geoms the finding lists.
    pub geoms: Vec<usize>,
    /// The foot body whose slide is reported.
    pub body: usize,
}

impl Measure for ContactAsBuilt {
    type Probe = FootSlide;
    fn key(&self, _: &Loaded) -> Result<(), &'static str> {
        Ok(())
    }
    fn measure(&self, l: &Loaded, s: &Slide) -> Measurement {
        let robot = &l.robot;
        let built: Vec<(usize, crate::probe::slide::Built)> =
            self.geoms.iter().filter_map(|g| Some((*g, *s.built.get(g)?))).collect();
        let pre = s.preconditions().check(
            "touches_ground",
            !built.is_empty(),
            if built.is_empty() {
                format!(
                    "no listed geom of the foot ({}) touched the ground during the push",
                    list(robot, &self.geoms)
                )
            } else {
                format!(
                    "{} of the {} listed geoms touched the ground",
                    built.len(),
                    self.geoms.len()
                )
            },
        );
        let travel = s.travel.get(&self.body).copied().unwrap_or(0.0);
        let mut m = std::collections::BTreeMap::from([
            ("push_share".to_string(), PUSH_SHARE),
            ("slide_m".to_string(), travel),
            ("support_load_n".to_string(), s.stance.support_load),
            ("weight_n".to_string(), s.stance.weight),
        ]);
        if let Some(z) = crate::probe::stance::floor_added(&s.stance) {
            m.insert("floor_added_z_m".to_string(), z);
        }
        let Some(&(g0, b0)) = built.first() else {
            return Measurement::new(&pre, m, "no ground contact to measure".to_string());
        };
        let dim = built.iter().map(|b| b.1.dim).max().unwrap_or(b0.dim);
        let dim_min = built.iter().map(|b| b.1.dim_min).min().unwrap_or(b0.dim_min);
        m.insert("contact_dim".into(), dim as f64);
        m.insert("contact_dim_min".into(), dim_min as f64);
        m.insert("contact_friction".into(), b0.friction);
        let dims =
            if dim == dim_min { format!("dim-{dim}") } else { format!("dim-{dim_min}…{dim}") };
        let note = format!(
            "MuJoCo built {dims} ground contacts{} for {}; pushed sideways with {} % of its weight for {} s, the foot slid {} mm",
            if dim >= 3 {
                format!(" with sliding friction {}", fmt_num(b0.friction, 3))
            } else {
                " (no friction)".to_string()
            },
            if built.len() == 1 {
                gname(robot, g0)
            } else {
                list(robot, &built.iter().map(|b| b.0).collect::<Vec<_>>())
            },
            fmt_num(100.0 * PUSH_SHARE, 3),
            fmt_num(PUSH_S, 3),
            fmt_num(1000.0 * travel, 3)
        );
        let note = match crate::probe::stance::copy_note(&s.stance) {
            Some(c) => format!("{note} ({c})"),
            None => note,
        };
        Measurement::new(&pre, m, note)
    }
}
