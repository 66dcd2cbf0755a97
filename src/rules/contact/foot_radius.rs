//! `foot-collision-geometry`'s contact-radius finding: a ground geom's radius outside
//! [`min_radius`, `max_radius`], worded by what the robot's own size says about it. A radius
//! out of proportion with the leg that carries it (a sphere whose diameter reaches the leg's
//! length, or one ten thousand times smaller than the leg) is a unit or scale slip; a radius
//! within proportion (Gymnasium Humanoid's 75 mm foot spheres on 0.6 m legs, dm_control's
//! quadruped's 80 mm toes) is the foot's design and is reported as one.
use crate::finding::{Finding, Subject};
use crate::model::Robot;
use crate::model::mjcf::ElemKind;
use crate::rules::Context;
use crate::rules::contact::feet::{Foot, leg_length};
use crate::util::fmt_num;

/// Tilt at which the rolling distance of a large contact sphere is stated (rad): 10°.
const ROLL_TILT: f64 = std::f64::consts::PI / 18.0;

/// The wording when no joint carries the foot (a loose body taken for a foot): nothing to
/// measure the radius against.
const NO_LEG: &str = "no leg carries this foot to measure the radius against, so nothing shows a unit slip: the size is read as the foot's design";

/// The finding for `bad` (the foot's ground geoms whose radius is outside the band; the first
/// one is the finding's place), worded as a unit or scale error only when the radius is out of
/// proportion with the leg (`unit_max_leg_fraction`, `unit_min_leg_fraction` of its length).
pub fn radius_finding(
    cx: &Context,
    foot: &Foot,
    bad: &[usize],
    label: &str,
    listed: &str,
) -> Finding {
    let robot: &Robot = cx.robot;
    let (rmin, rmax) = (cx.opt("min_radius"), cx.opt("max_radius"));
    let (hi, lo) = (cx.opt("unit_max_leg_fraction"), cx.opt("unit_min_leg_fraction"));
    let g0 = bad[0];
    let r = robot.geoms[g0].size[0];
    let leg = (robot.key.geom_xpos.get(g0).copied())
        .and_then(|c| leg_length(robot, foot.root, c))
        .filter(|&l| l > 0.0);
    let mm = |v: f64| fmt_num(v * 1000.0, 3);
    let base = format!(
        "{label} has contact radius {} mm outside {}–{} mm: {listed}",
        mm(r),
        mm(rmin),
        mm(rmax)
    );
    let unit = leg.is_some_and(|l| r > hi * l || r < lo * l);
    let share = leg.map(|l| {
        format!(
            "the radius is {} % of the {} m leg that carries it",
            fmt_num(100.0 * r / l, 3),
            fmt_num(l, 3)
        )
    });
    let (note, help) = if unit {
        (
            format!(
                "{}: a contact sphere as wide as the leg is long, or {} times smaller than it, is out of proportion with the robot — usually a unit or scale error",
                share.unwrap_or_default(),
                fmt_num(1.0 / lo, 3)
            ),
            "check the geom's size (MuJoCo sizes are in metres; a sphere's size is its radius)"
                .to_string(),
        )
    } else if r > rmax {
        (
            format!(
                "{}. A foot that touches down on a sphere of this radius rolls on it: its contact point travels {} mm along the floor for each 10° the foot tilts, and the foot stands on that one point",
                share.map_or(NO_LEG.to_string(), |s| format!("{s}, in proportion with the robot: the size is the foot's design, not a unit slip")),
                mm(r * ROLL_TILT)
            ),
            "model the contact the foot has: a sole of capsules or corner spheres of a few millimetres at heel and toe, or a radius matching the hardware's rubber tip".to_string(),
        )
    } else {
        (
            format!(
                "{}. A sphere this small that spans no support polygon with the foot's other contacts is a single point of contact, whose depth the solver resolves over a fraction of a millimetre",
                share.map_or(NO_LEG.to_string(), |s| format!("{s}, not below {} % of it: the robot's size gives no sign of a unit slip, the size is the foot's design", fmt_num(100.0 * lo, 3))),
            ),
            "give the foot its sole: three or more spheres spread over heel and toe (corner points), or capsules of a few millimetres".to_string(),
        )
    };
    cx.at_attr(ElemKind::Geom, g0, &robot.geoms[g0].name, "size", base)
        .label(format!("radius {} mm", mm(r)))
        .note(note)
        .help(help)
        .subject(Subject::Foot(foot.root))
        .fact()
        .measured(r, "m")
        .expected(0.5 * (rmin + rmax), "m")
}
