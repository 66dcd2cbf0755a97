use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::model::{GeomType, Robot};
use crate::probe::settle::{Settle, StanceClaim};
use crate::probe::{Preconditions, StanceSettle, Verdict};
use crate::rules::contact::feet::{Foot, FootKind, feet};
use crate::rules::geometry::shapes::{Placed, convex_hull, in_hull, tilt};
use crate::rules::{Context, Domain, Rule, RuleMeta, claim_each, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// At the standing keyframe (or `qpos0` when the model has none; when `qpos0` places limited
    /// joints past their stops, a pose the robot cannot take, both at `qpos0` and at `qpos0`
    /// with those joints moved to their nearest stop, reporting what holds at both, named "qpos0
    /// clamped into the joint ranges" — as every static foot rule: `foot-collision-geometry`,
    /// `links-without-collision`, `torsional-friction-length` too), checks that every foot's
    /// collision geoms form one flat sole: the lowest points of the foot and toe geoms that touch
    /// down (those within `contact_window` of the foot's lowest point) lie within
    /// `max_height_spread` of the sole height (the median of the foot body's own geoms), and every
    /// flat contact feature — a toe capsule's axis, a lateral (side-to-side) capsule or cylinder,
    /// a box's bottom face, a standing cylinder's cap — is parallel to the ground within
    /// `max_tilt`. Lowest points are computed analytically from the compiled pose and size
    /// (capsule, sphere, box, cylinder, ellipsoid) or from the compiled mesh vertices.
    ///
    /// A geom above the sole whose footprint (its lowest point, and a box's bottom face or a
    /// capsule's ends) lies inside the support polygon the level sole geoms already span adds
    /// no support in stance — a backup box a few millimetres above four point-contact corner
    /// spheres — and is not reported; above the sole and outside that polygon (a raised toe that
    /// shortens the foot in stance) it is.
    ///
    /// Heel-to-toe capsules on the foot body itself may be sloped on purpose (an arch, as in the
    /// Unitree H1's V-shaped sole capsules); only their lowest points are held to the band.
    ///
    /// Foot bodies come from the spec's `robot.foot_bodies` globs; without them, from body names
    /// containing `foot`, `ankle_roll`, `toe` or `sole`; failing that, the leaf bodies (no body
    /// below them collides) whose collision geoms reach within 3 cm of the robot's lowest
    /// point. Bodies below a foot body are its toes.
    ///
    /// Only flat feet are checked: a point foot (quadruped sphere) or a wheel has no sole to
    /// tilt (robot families: `rules::contact::feet`). The lower end of a shank box or capsule
    /// that lies inside the foot sphere (a URDF's fixed foot link fused into the shank) cannot
    /// touch the floor before the sphere does and does not make the foot a sole. A keyframe that holds a foot in the air
    /// — the model has a floor and the foot's lowest point is above it by more than the foot's
    /// own height (a lie-down pose dropped onto the belly) — is no stance: that foot is not
    /// judged there. A legged URDF, which MuJoCo's importer welds to the world, is judged as if
    /// its root link floated, at qpos0 (`welded-legged-base`); a fixed-base arm is not.
    ///
    /// ## Why is this bad?
    /// A toe capsule a few millimetres below the sole turns a flat foot into a rocker: the robot
    /// stands on the toe and the heel alternately, and the policy learns to balance on a contact
    /// pattern the real foot does not have. A tilted toe touches with one end only. A policy
    /// trained on a model whose toes were accidentally tilted stopped learning forward-balance
    /// recovery, although gains and rewards were fine.
    ///
    /// ## How it is confirmed
    /// Static geometry at the keyframe; probe `stance-settle` drops the robot onto the floor in
    /// the keyframe pose and records which geoms carry the load and how the foot rolls. A
    /// legged URDF and a base of three slides and a ball stand on a floated copy (a free joint
    /// on the base, a floor under the lowest foot when the model has none; `docs/probes.md`).
    ///
    /// ## How to fix
    /// Move the offending geom (its `pos`/`fromto`; in a URDF the `xyz` of the collision's
    /// `<origin>`) so its lowest point is level with the other sole geoms, and make toe capsule
    /// axes and box faces horizontal in the standing pose (its `quat`/`euler`; in a URDF the
    /// `rpy` of the `<origin>`), or fix the keyframe if the foot itself is not flat.
    pub ToeTilt {
        id: "toe-tilt",
        group: "contact",
        level: Severity::Warning,
        probe: StanceSettle,
        options: [
            opt("max_height_spread", 0.001, "m", Domain::NON_NEGATIVE, "largest height difference of a sole geom's lowest point from the sole height"),
            opt("max_tilt", 0.5, "deg", Domain::ANGLE_DEG, "largest angle between a flat contact feature and the ground"),
            opt("contact_window", 0.01, "m", Domain::POSITIVE, "geoms whose lowest point is within this of the foot's lowest point count as sole geoms"),
        ],
    }
}

fn kind_name(robot: &Robot, foot: &Foot, g: usize) -> String {
    let part = if foot.is_toe_geom(robot, g) { "toe" } else { "foot" };
    let shape = match robot.geoms[g].gtype {
        GeomType::Capsule => "capsule",
        GeomType::Sphere => "sphere",
        GeomType::Box => "box",
        GeomType::Cylinder => "cylinder",
        GeomType::Ellipsoid => "ellipsoid",
        GeomType::Mesh => "mesh",
        _ => "geom",
    };
    let name = &robot.geoms[g].name;
    if name.is_empty() {
        format!("{part} {shape} #{g}")
    } else {
        format!("{part} {shape} `{name}`")
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Whether a keyframe holds the foot in the air, so that it is no stance to judge a sole at:
/// the model has a floor (a horizontal plane of the world or a body welded to it that a foot
/// geom touches) and the foot's lowest point is above it by more than the foot's own height
/// (its collision geoms' vertical extent). A lie-down keyframe dropped from 0.36 m (Unitree
/// B2's `home`: calves folded level, a shin guard box as low as the foot sphere) is one; a
/// stance keyframe written a few millimetres above the floor, or `qpos0`, is judged.
fn in_the_air(robot: &Robot, foot: &Foot, zmin: f64) -> bool {
    if robot.key.key_name.is_none() {
        return false;
    }
    let floor = foot
        .geoms
        .iter()
        .flat_map(|&g| crate::model::contact::ground_partners(robot, g))
        .map(|(o, _)| Placed::of(robot, o))
        .filter(|p| p.gtype == GeomType::Plane && p.mat[8] > 1.0 - 1e-9)
        .map(|p| p.pos[2])
        .fold(f64::NEG_INFINITY, f64::max);
    if !floor.is_finite() {
        return false;
    }
    let top = foot
        .geoms
        .iter()
        .map(|&g| Placed::of(robot, g).support([0.0, 0.0, 1.0])[2])
        .fold(f64::NEG_INFINITY, f64::max);
    zmin - floor > top - zmin
}

/// What the `stance-settle` probe checks: after standing, a contact geom of the foot (the body,
/// its parent and children) carries (almost) no load.
#[derive(Debug)]
pub struct ContactGeomUnloaded {
    /// The body of the tilted geom.
    pub body: usize,
}

impl StanceClaim for ContactGeomUnloaded {
    fn judge_settled(&self, l: &Loaded, s: &Settle, pre: &Preconditions) -> Verdict {
        let foot = s.foot(&l.robot, self.body);
        let total = foot.load;
        let unloaded: Vec<String> = foot
            .geoms
            .iter()
            .filter(|g| s.load(**g) < 0.02 * total)
            .map(|&g| match l.robot.geoms[g].name.as_str() {
                "" => l.robot.unnamed_geom(g),
                n => n.to_string(),
            })
            .collect();
        let mut m = s.stance_measured();
        m.extend(foot.measured);
        let share = if s.stance.weight > 0.0 { total / s.stance.weight } else { 0.0 };
        let pre = pre.clone().check(
            "foot_loaded",
            share >= FOOT_MIN_SHARE,
            format!(
                "the foot carries {} % of the robot's weight (need ≥ {} %)",
                fmt_num(100.0 * share, 3),
                fmt_num(100.0 * FOOT_MIN_SHARE, 3)
            ),
        );
        if let Some(p) = pre.unmet() {
            let why = p.detail.clone();
            return Verdict::inconclusive(&pre, m, why);
        }
        if !unloaded.is_empty() {
            Verdict::confirmed(
                &pre,
                m,
                format!(
                    "after 1 s standing, {} carr{} < 2 % of the foot's {} N",
                    unloaded.join(", "),
                    if unloaded.len() == 1 { "ies" } else { "y" },
                    fmt_num(total, 3)
                ),
            )
        } else {
            Verdict::refuted_or_inconclusive(
                &pre,
                m,
                format!(
                    "every contact geom of the foot carries load ({} N in all)",
                    fmt_num(total, 3)
                ),
            )
        }
    }
}

/// How far outside the sole's support polygon a footprint point may lie and still count as
/// inside it: the rounding of compiled positions (m), not a tolerance of the design.
const ROUNDING_SLACK: f64 = 1e-9;

/// Smallest share of the robot's weight one foot must carry for its geoms' loads to count.
pub const FOOT_MIN_SHARE: f64 = 0.05;

impl Rule for ToeTilt {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let first = out.len();
        self.check_feet(cx, out);
        claim_each(&mut out[first..], |f| match f.subject {
            Subject::Geom(g) => {
                cx.robot.geoms.get(g).map(|geom| ContactGeomUnloaded { body: geom.body })
            }
            _ => None,
        });
    }
}

impl ToeTilt {
    fn check_feet(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let spread = cx.opt("max_height_spread");
        let max_tilt = cx.opt("max_tilt");
        let window = cx.opt("contact_window");
        let pose = super::pose::pose_word(robot);
        // A point foot or a wheel has no sole to tilt.
        for foot in feet(robot, cx.spec).into_iter().filter(|f| f.kind == FootKind::Flat) {
            let low: Vec<(usize, f64)> =
                foot.geoms.iter().map(|&g| (g, Placed::of(robot, g).lowest()[2])).collect();
            let zmin = low.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
            if in_the_air(robot, &foot, zmin) {
                continue;
            }
            let sole: Vec<(usize, f64)> =
                low.iter().copied().filter(|x| x.1 <= zmin + window).collect();
            let own: Vec<f64> =
                sole.iter().filter(|x| !foot.is_toe_geom(robot, x.0)).map(|x| x.1).collect();
            let zref = if own.is_empty() {
                median(sole.iter().map(|x| x.1).collect())
            } else {
                median(own)
            };
            let others = |g: usize| sole.iter().filter(|x| x.0 != g).count();
            // The support polygon of the geoms level with the sole, and whether a geom's
            // footprint lies inside it (then raising it changes nothing in stance).
            let footprint = |g: usize| -> Vec<[f64; 2]> {
                let p = Placed::of(robot, g);
                let mut pts = p.ground_points(spread);
                pts.push(p.lowest());
                pts.extend(p.sole_points(max_tilt.to_radians()));
                pts.iter().map(|q| [q[0], q[1]]).collect()
            };
            let support = convex_hull(
                &sole
                    .iter()
                    .filter(|x| (x.1 - zref).abs() <= spread)
                    .flat_map(|x| footprint(x.0))
                    .collect::<Vec<_>>(),
            );
            let covered =
                |g: usize| footprint(g).iter().all(|&q| in_hull(&support, q, ROUNDING_SLACK));
            for &(g, z) in &sole {
                let geom = &robot.geoms[g];
                let dz = z - zref;
                let what = kind_name(robot, &foot, g);
                if dz.abs() > spread && others(g) > 0 && !(dz > 0.0 && covered(g)) {
                    let (dir, effect) = if dz < 0.0 {
                        (
                            "below",
                            "makes a flat foot rock on it: the foot stands on this geom and pivots instead of resting on the whole sole",
                        )
                    } else {
                        (
                            "above",
                            "leaves it off the ground in stance: the foot rests on the other geoms and this one only touches once the foot rolls",
                        )
                    };
                    let msg = format!(
                        "{what} sits {} mm {dir} the sole of the {} at {pose}",
                        fmt_num(dz.abs() * 1000.0, 3),
                        foot.label(robot)
                    );
                    out.push(
                        cx.at_elem(ElemKind::Geom, g, &geom.name, msg)
                            .label(format!("lowest point {} mm {dir} the sole", fmt_num(dz.abs() * 1000.0, 3)))
                            .note(format!(
                                "a {what} {} mm {dir} the sole {effect}; the sole height is the median lowest point of the foot's own geoms (z = {:.1} mm), band ±{} mm",
                                fmt_num(dz.abs() * 1000.0, 3),
                                zref * 1000.0 + 0.0,
                                fmt_num(spread * 1000.0, 3)
                            ))
                            .help(if robot.format == crate::model::Format::Urdf {
                                "move the collision (the `xyz` of its `<origin>`) so its lowest point is level with the other sole geoms in the standing pose"
                            } else {
                                "move the geom (its `pos` or `fromto`) so its lowest point is level with the other sole geoms in the standing pose"
                            })
                            .subject(Subject::Geom(g))
                            .measured(dz * 1000.0, "mm")
                            .expected(0.0, "mm")
                            .with("height_offset_m", dz)
                            .with("tilt_deg", tilt(geom.gtype, &robot.key.geom_xmat[g]).map(f64::to_degrees).unwrap_or(0.0))
                            .with("foot_body", foot.root as f64),
                    );
                }
                // Tilt of flat features.
                let mat = &robot.key.geom_xmat[g];
                let Some(t) = tilt(geom.gtype, mat) else { continue };
                let axis = [mat[2], mat[5], mat[8]];
                let lying = matches!(geom.gtype, GeomType::Capsule | GeomType::Cylinder)
                    && axis[2].abs() < std::f64::consts::FRAC_1_SQRT_2;
                let longitudinal = lying && axis[0].abs() > axis[1].abs();
                if longitudinal && !foot.is_toe_geom(robot, g) {
                    continue;
                }
                let deg = t.to_degrees();
                if deg > max_tilt {
                    let feature = match geom.gtype {
                        GeomType::Box => "bottom face",
                        _ if lying => "axis",
                        _ => "cap face",
                    };
                    let msg = format!(
                        "{what} {feature} is tilted {}° from the ground at {pose}",
                        fmt_num(deg, 3)
                    );
                    out.push(
                        cx.at_elem(ElemKind::Geom, g, &geom.name, msg)
                            .label(format!("{feature} tilted {}°", fmt_num(deg, 3)))
                            .note(format!(
                                "a {what} whose {feature} is tilted {}° (limit {}°) touches the floor along one edge or at one end instead of lying flat, so the contact patch and the foot's rocking behaviour differ from the real foot",
                                fmt_num(deg, 3),
                                fmt_num(max_tilt, 3)
                            ))
                            .help(if robot.format == crate::model::Format::Urdf {
                                "rotate the collision (the `rpy` of its `<origin>`) so the feature is horizontal in the standing pose, or fix the joint origins if the whole foot is tilted"
                            } else {
                                "rotate the geom (its `quat`/`euler`/`fromto`) so the feature is horizontal in the standing pose, or fix the keyframe if the whole foot is tilted"
                            })
                            .subject(Subject::Geom(g))
                            .measured(deg, "°")
                            .expected(max_tilt, "°")
                            .with("height_offset_m", dz)
                            .with("tilt_deg", deg)
                            .with("foot_body", foot.root as f64),
                    );
                }
            }
        }
    }
}
