use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::XNode;
use crate::model::{Format, JointType, Robot, Transmission};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds an MJCF file whose hinge ranges were written in radians while MuJoCo reads them in
    /// degrees: no `<compiler>` of the file states `angle` (so MJCF's default,
    /// `angle="degree"`, is in force), the file has at least `min_hinges` limited hinges, every
    /// one of them has both range ends within ±`max_range_end` as written (a full turn, 2π =
    /// 6.2832, with its rounding: the `6.28` of a continuous joint's ±2π), and at least one of
    /// them is driven by an actuator (a motor, a position servo, any actuator on the joint). Read
    /// as degrees, every joint of the robot then turns at most 12.6° — no actuated robot is
    /// built that way, and the numbers are what radian ranges look like (robosuite's Kinova
    /// Jaco `robot.xml`: ±6.28 on its continuous joints and 0.82–5.46 style ranges, with no
    /// `<compiler angle>` because robosuite compiles it inside an arena that states radians).
    /// Range ends equal to π/6, π/4, π/3, π/2, 2π/3, 3π/4, π, 3π/2 or 2π to the written precision
    /// (0.005: 3.14, 1.57, 0.785, 6.28) are named in the finding as further evidence. One finding per file, at the widest
    /// range. Not reported: a file that states `angle` (`"degree"` with real degree ranges, or
    /// `"radian"`), a file with any hinge range beyond ±`max_range_end` (±90, ±180: degrees),
    /// slide joints (metres, never converted), files with fewer than `min_hinges` limited hinges
    /// (a lone gripper hinge of a few degrees is plausible) or none actuated, URDFs (always
    /// radians).
    ///
    /// ## Why is this bad?
    /// Compiled on its own — in a test, a viewer, another training stack — the robot's joints
    /// get ranges 57.3× too narrow: a ±6.28 continuous joint becomes ±0.11 rad, a 0.82–5.46
    /// elbow 0.014–0.095 rad. qpos0 and keyframes land outside the ranges, the limit constraints
    /// push every joint back, and any controller or policy works inside a few degrees.
    ///
    /// ## How it is confirmed
    /// A fact of the file (the written ranges, the `<compiler>` attributes, the actuators'
    /// targets), never refuted by simulation.
    ///
    /// ## How to fix
    /// Add `<compiler angle="radian"/>` to the file, so it compiles the same on its own as inside
    /// a radian scene (other angles the file writes — `euler`, `axisangle`, `ref`, `springref` —
    /// are then radians too: check them).
    pub RangeInRadians {
        id: "range-in-radians",
        group: "limits",
        level: Severity::Error,
        probe: None,
        options: [
            opt("max_range_end", 6.3, "number as written", Domain::POSITIVE, "largest range end, as written, a hinge range in radians has: a full turn, 2π = 6.2832, with its rounding to 6.3; read as degrees, a range within it turns at most 12.6°"),
            opt("min_hinges", 2.0, "joints", Domain::AT_LEAST_ONE, "limited hinges the file must have, all within max_range_end: one small hinge (a gripper finger's few degrees) is plausible in degrees"),
        ],
    }
}

/// A written range end counts as a fraction of π when it lies within this of one: half the
/// last digit of a value written to two decimals (3.14, 1.57, 6.28), rad.
const PI_MULTIPLE_ROUNDING: f64 = 0.005;

/// Whether any `<compiler>` of the file states `angle`.
fn states_angle(robot: &Robot) -> bool {
    fn visit(n: &XNode) -> bool {
        (n.tag == "compiler" && n.get("angle").is_some()) || n.children.iter().any(visit)
    }
    robot.tree.children.iter().any(visit)
}

/// The fractions of π radian ranges are written with (π/6 to 2π), as (numerator, denominator).
const PI_FRACTIONS: [(i64, i64); 9] =
    [(1, 6), (1, 4), (1, 3), (1, 2), (2, 3), (3, 4), (1, 1), (3, 2), (2, 1)];

/// `|v|` as one of [`PI_FRACTIONS`] of π, "2π", "π/2", when it is one to the written precision.
fn pi_multiple(v: f64) -> Option<String> {
    let &(n, d) = PI_FRACTIONS.iter().find(|&&(n, d)| {
        (v.abs() - std::f64::consts::PI * n as f64 / d as f64).abs() <= PI_MULTIPLE_ROUNDING
    })?;
    let num = if n == 1 { "π".to_string() } else { format!("{n}π") };
    Some(if d == 1 { num } else { format!("{num}/{d}") })
}

impl Rule for RangeInRadians {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if robot.format != Format::Mjcf || states_angle(robot) {
            return;
        }
        let max_end = cx.opt("max_range_end");
        let hinges: Vec<_> =
            robot.joints.iter().filter(|j| j.jtype == JointType::Hinge && j.limited).collect();
        // The numbers as written: MuJoCo converted them from degrees.
        let written = |r: f64| r.to_degrees();
        if (hinges.len() as f64) < cx.opt("min_hinges")
            || !hinges.iter().all(|j| j.range.iter().all(|&r| written(r).abs() <= max_end))
        {
            return;
        }
        let actuated = |id: usize| {
            robot.actuators.iter().any(|a| {
                matches!(a.trn, Transmission::Joint | Transmission::JointInParent)
                    && usize::try_from(a.target).ok() == Some(id)
            })
        };
        let driven = hinges.iter().filter(|j| actuated(j.id)).count();
        if driven == 0 {
            return;
        }
        // The first of the widest ranges, in file order.
        let span = |j: &crate::model::Joint| j.range[1] - j.range[0];
        let Some(widest) =
            hinges.iter().copied().reduce(|a, b| if span(b) > span(a) { b } else { a })
        else {
            return;
        };
        let mut pis: Vec<String> = Vec::new();
        for j in &hinges {
            for r in j.range {
                let w = fmt_num(written(r).abs(), 4);
                if let Some(p) = pi_multiple(written(r))
                    && !pis.iter().any(|s| s.starts_with(&format!("{w} ")))
                {
                    pis.push(format!("{w} = {p}"));
                }
            }
        }
        let w = widest.range.map(written);
        let deg_span = w[1] - w[0];
        let evidence = if pis.is_empty() {
            String::new()
        } else {
            format!(
                ", and the range ends {} are radian values to the written precision",
                pis.join(", ")
            )
        };
        let msg = format!(
            "joint ranges read as degrees because the file states no <compiler angle> (MJCF's default is degree), but every one of its {} limited hinges ({} actuated) has its range within ±{}: as degrees the widest, `{}` [{}, {}], turns {}°{evidence}; radians were meant, add <compiler angle=\"radian\"/>",
            hinges.len(),
            driven,
            fmt_num(max_end, 3),
            widest.name,
            fmt_num(w[0], 4),
            fmt_num(w[1], 4),
            fmt_num(deg_span, 3),
        );
        let mut f = cx
            .at_attr(ElemKind::Joint, widest.id, &widest.name, "range", msg)
            .label(format!("[{}, {}] read as degrees", fmt_num(w[0], 4), fmt_num(w[1], 4)))
            .note(format!(
                "compiled on its own, `{}` gets [{}, {}] rad instead of [{}, {}] rad, and every other hinge is 57.3× narrower than written too: qpos0 and keyframes fall outside the ranges and a controller works inside a few degrees",
                widest.name,
                fmt_num(widest.range[0], 4),
                fmt_num(widest.range[1], 4),
                fmt_num(w[0], 4),
                fmt_num(w[1], 4)
            ))
            .help("add <compiler angle=\"radian\"/> to the file (then the file's other angles — euler, axisangle, ref, springref — are radians too)")
            .subject(Subject::Model)
            .measured(widest.range[1] - widest.range[0], "rad")
            .expected(deg_span, "rad");
        for j in hinges.iter().filter(|j| j.id != widest.id).take(2) {
            let (loc, _) = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "range");
            let r = j.range.map(written);
            f = f.secondary(
                loc,
                format!(
                    "`{}` [{}, {}] read as degrees",
                    j.name,
                    fmt_num(r[0], 4),
                    fmt_num(r[1], 4)
                ),
            );
        }
        out.push(f);
    }
}
