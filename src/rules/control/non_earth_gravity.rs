use crate::declare_rule;
use crate::finding::{Finding, Severity};
use crate::model::source::{Loc, XNode};
use crate::model::{GeomType, JointType, Robot};
use crate::rules::{Context, Rule, RuleMeta, in_subtree};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a scene whose gravity cannot hold a floating robot on its floor: the effective
    /// `<option gravity>` (zero when `<flag gravity="disable"/>`) is weaker or stronger than
    /// Earth's anywhere a robot is tested ([`EARTH_G_MIN`]–[`EARTH_G_MAX`] m/s²: 9.780 at the
    /// equator to 9.832 at the poles, less about 0.03 on the highest mountains), or it does not
    /// pull towards the floor (its component along the floor's normal is not downward). Judged
    /// on models with a floor (a colliding plane or height field on a static body, or a box on
    /// the world body) and a robot on a floating base (a free joint, or three slides and a
    /// ball) that carries hinge or slide joints. A tilted gravity of Earth's strength (a slope
    /// simulated by tilting gravity) is not reported; neither is a fixed-base arm (gravity
    /// switched off to stand in for gravity compensation is out of this rule's scope).
    ///
    /// ## Why is this bad?
    /// Standing, walking and falling are loads of gravity: with it near zero or pointing
    /// away from the floor, the robot floats above its feet, its actuators hold no weight and
    /// its feet carry no load, so a policy trained or a controller tuned on the scene meets a
    /// different robot on the hardware. A magnitude in other units (981 for cm/s²) or a sign
    /// slip (`0 0 9.81`) is as wrong. MuJoCo applies `<option gravity>` to every body as
    /// written (XML reference, option/gravity).
    ///
    /// ## How it is confirmed
    /// Static: the compiled `opt.gravity`, `disableflags` and the floor geom's orientation. The
    /// stance probes of the contact rules record the same fact as a precondition ("gravity")
    /// and are inconclusive with this reason.
    ///
    /// ## How to fix
    /// Remove the `gravity` attribute (MuJoCo's default is `0 0 -9.81`) or write Earth's
    /// gravity towards the floor; remove `<flag gravity="disable"/>`. A scene of another
    /// world (the Moon's 1.62 m/s²) says so with a suppression comment and the reason.
    pub NonEarthGravity {
        id: "non-earth-gravity",
        group: "control",
        level: Severity::Error,
        probe: None,
        options: [],
    }
}

/// Lowest surface gravity on Earth where a robot is tested, m/s²: 9.780 at the equator, less
/// about 0.03 at 9 km altitude.
pub const EARTH_G_MIN: f64 = 9.75;
/// Highest surface gravity on Earth, m/s²: 9.832 at the poles, with the rounding of 9.83.
pub const EARTH_G_MAX: f64 = 9.84;
/// `mjDSBL_GRAVITY`: `<flag gravity="disable"/>`.
const DSBL_GRAVITY: i32 = 1 << 7;

/// The gravity MuJoCo applies (zero when disabled), m/s².
pub fn effective_gravity(robot: &Robot) -> [f64; 3] {
    if robot.opt.disableflags & DSBL_GRAVITY != 0 { [0.0; 3] } else { robot.opt.gravity }
}

/// The first geom a robot can stand on and its outward normal in the world frame (a plane's
/// z axis; +z for a height field or box), `None` without a floor.
pub fn floor(robot: &Robot) -> Option<(usize, [f64; 3])> {
    let g = (0..robot.geoms.len()).find(|&g| crate::probe::stance::is_ground(robot, g))?;
    let n = match (robot.geoms[g].gtype, robot.key.geom_xmat.get(g)) {
        (GeomType::Plane, Some(m)) => [m[2], m[5], m[8]],
        _ => [0.0, 0.0, 1.0],
    };
    Some((g, n))
}

/// How gravity `g` fails to hold a robot on a floor of normal `n`: `None` when it is Earth's
/// (magnitude within [`EARTH_G_MIN`, `EARTH_G_MAX`]) and pulls towards the floor, else the
/// sentence saying what it is.
pub fn off_earth(g: [f64; 3], n: [f64; 3]) -> Option<String> {
    let mag = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let nn = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-12);
    let down = -(g[0] * n[0] + g[1] * n[1] + g[2] * n[2]) / nn;
    let earth = (EARTH_G_MIN..=EARTH_G_MAX).contains(&mag);
    if earth && down > 0.0 {
        return None;
    }
    let dir = if mag == 0.0 {
        String::new()
    } else if down > 0.0 {
        " towards the floor".to_string()
    } else if down < 0.0 {
        " pointing away from the floor".to_string()
    } else {
        " along the floor".to_string()
    };
    Some(format!("gravity is {} m/s²{dir}", fmt_num(mag, 4)))
}

/// The `<option gravity>` attribute, else the `<flag gravity>` one, else the first `<option>`.
fn gravity_loc(robot: &Robot) -> Loc {
    let (mut attr, mut flag, mut elem) = (None, None, None);
    robot.tree.walk(&mut |n: &XNode| match n.tag.as_str() {
        "option" => {
            elem = elem.or(Some(n.loc));
            attr = attr.or(n.attr("gravity").map(|a| a.loc));
        }
        "flag" => flag = flag.or(n.attr("gravity").map(|a| a.loc)),
        _ => {}
    });
    attr.or(flag).or(elem).unwrap_or_else(|| robot.root_loc())
}

impl Rule for NonEarthGravity {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let Some((floor_geom, n)) = floor(robot) else { return };
        // A floating base carrying hinge or slide joints: a robot, not a crate.
        let base = robot.floating_bodies().into_iter().find(|&b| {
            robot.joints.iter().any(|j| {
                matches!(j.jtype, JointType::Hinge | JointType::Slide)
                    && j.body != b
                    && in_subtree(robot, b, j.body)
            })
        });
        let Some(base) = base else { return };
        let g = effective_gravity(robot);
        let Some(what) = off_earth(g, n) else { return };
        let disabled = robot.opt.disableflags & DSBL_GRAVITY != 0;
        let mag = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let floor_name = match robot.geoms[floor_geom].name.as_str() {
            "" => "the floor".to_string(),
            s => format!("the floor `{s}`"),
        };
        let why = if disabled { " (<flag gravity=\"disable\"/>)" } else { "" };
        let n_len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-12);
        let down = -(g[0] * n[0] + g[1] * n[1] + g[2] * n[2]) / n_len;
        let effect = if down > EARTH_G_MAX {
            format!("weighs {}× what it weighs on Earth", fmt_num(down / 9.80665, 3))
        } else {
            "is not held on its feet".to_string()
        };
        let msg = format!(
            "{what}{why}, not Earth's ({}–{} m/s² towards {floor_name}): the robot on the floating base `{}` {effect}",
            fmt_num(EARTH_G_MIN, 3),
            fmt_num(EARTH_G_MAX, 3),
            robot.body_name(base)
        );
        out.push(
            cx.finding(msg, gravity_loc(robot))
                .element("option gravity", gravity_loc(robot))
                .label(if disabled { "gravity disabled" } else { "not Earth's gravity" })
                .note("standing, walking and falling are loads of gravity: under another gravity the robot's weight, its actuators' loads and its feet's contact forces are not the hardware's (near zero or pointing away from the floor, the robot floats above its feet)")
                .help("remove the gravity attribute (MuJoCo's default is 0 0 -9.81) or write Earth's gravity towards the floor; a scene of another world says so with a suppression comment")
                .measured(mag, "m/s²")
                .expected(9.80665, "m/s²")
                .with("gravity_x", g[0])
                .with("gravity_y", g[1])
                .with("gravity_z", g[2]),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const UP: [f64; 3] = [0.0, 0.0, 1.0];

    #[test]
    fn earth_gravity_towards_the_floor_passes_and_tilted_too() {
        assert_eq!(off_earth([0.0, 0.0, -9.81], UP), None);
        // A 15° slope simulated by tilting gravity: Earth's magnitude, still towards the floor.
        let (s, c) = 15f64.to_radians().sin_cos();
        assert_eq!(off_earth([9.81 * s, 0.0, -9.81 * c], UP), None);
    }

    #[test]
    fn weak_strong_or_upward_gravity_is_reported() {
        assert!(off_earth([0.0, 0.0, 1e-4], UP).unwrap().contains("away from the floor"));
        assert!(off_earth([0.0, 0.0, 0.0], UP).unwrap().starts_with("gravity is 0 m/s²"));
        assert!(off_earth([0.0, 0.0, -981.0], UP).unwrap().contains("981"));
        assert!(off_earth([0.0, 0.0, 9.81], UP).unwrap().contains("away from the floor"));
        assert!(off_earth([0.0, 0.0, -1.62], UP).unwrap().contains("towards the floor"));
        // Earth's magnitude along the floor holds nothing on it.
        assert!(off_earth([9.81, 0.0, 0.0], UP).unwrap().contains("along the floor"));
    }
}
