use std::path::PathBuf;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{ActuatorKind, Robot};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::spec::Spec;
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// When the spec names a `robot.companion_urdf` (a path relative to the spec file), loads it
    /// and compares it with the MJCF joint by joint name: joint ranges (within
    /// `range_tolerance`; mirrored when the axis is flipped), effort limits against the
    /// actuators' `forcerange` (or the joint's `actuatorfrcrange`, or `gear × ctrlrange` of a
    /// torque motor), velocity limits against the spec's motor `velocity_limit`, joint axes
    /// (normalised; a flipped axis is reported as a sign-convention difference), and the masses
    /// of links and bodies with the same name (relative `tolerance`), and a URDF `<mimic>`'s
    /// multiplier (relative `tolerance`) and offset (`range_tolerance`) against the MJCF joint
    /// equality between the same joints. A companion URDF that is
    /// missing or cannot be parsed is itself a finding at the spec line.
    ///
    /// ## Why is this bad?
    /// The URDF usually feeds the deployment stack (kinematics, state estimation, limits in the
    /// motor driver) while the MJCF feeds training. When they drift apart the policy is trained
    /// on one robot and run on another: a range that is wider in simulation drives into a hard
    /// stop, a flipped axis inverts a joint's actions, a lighter link changes the dynamics.
    ///
    /// ## How it is confirmed
    /// Static comparison of the two files.
    ///
    /// ## How to fix
    /// Regenerate one file from the other, or correct the drifted values so both describe the
    /// same hardware; for a deliberately flipped axis, make sure the joint mapping negates
    /// commands and readings.
    pub UrdfMjcfDrift {
        id: "urdf-mjcf-drift",
        group: "mapping",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("range_tolerance", 0.001, "rad or m", Domain::NON_NEGATIVE, "largest difference of a range end"),
            opt("tolerance", 0.01, "ratio", Domain::NON_NEGATIVE, "relative difference tolerated for effort, velocity and mass"),
            opt("axis_tolerance", 0.01, "", Domain::NON_NEGATIVE, "largest difference between normalised axis vectors"),
        ],
    }
}

fn companion(spec: &Spec, cx: &Context) -> Option<(PathBuf, crate::model::source::Loc)> {
    let c = spec.robot.companion_urdf.as_ref()?;
    let base =
        cx.sources.file(spec.file).path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
    Some((base.join(c.get_ref()), spec.loc(c.span())))
}

/// Largest torque the model lets the joint's actuators apply, if bounded.
fn model_effort(robot: &Robot, j: usize) -> Option<f64> {
    let acts = robot.actuators_on_joint(j);
    let lim: Vec<f64> = acts
        .iter()
        .filter(|a| a.forcelimited)
        .map(|a| a.forcerange[0].abs().max(a.forcerange[1].abs()))
        .collect();
    if !lim.is_empty() {
        return lim.into_iter().reduce(f64::max);
    }
    if robot.mj.jnt_actfrclimited().get(j).copied().unwrap_or(false) {
        let fr = robot.mj.jnt_actfrcrange().as_flattened();
        return Some(fr[2 * j].abs().max(fr[2 * j + 1].abs()));
    }
    let m: Vec<f64> = acts
        .iter()
        .filter(|a| a.kind == ActuatorKind::Motor && a.ctrllimited)
        .map(|a| a.gear.abs() * a.ctrlrange[0].abs().max(a.ctrlrange[1].abs()))
        .collect();
    m.into_iter().reduce(f64::max)
}

/// MuJoCo's `mjEQ_JOINT`.
const EQ_JOINT: i32 = 2;

fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if n < 1e-12 { v } else { [v[0] / n, v[1] / n, v[2] / n] }
}

fn rel_differs(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() > tol * a.abs().max(b.abs()) && (a - b).abs() > 1e-9
}

impl Rule for UrdfMjcfDrift {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let Some(spec) = cx.spec else { return };
        let Some((path, spec_loc)) = companion(spec, cx) else { return };
        let robot = cx.robot;
        let urdf = match urdf_rs::read_file(&path) {
            Ok(u) => u,
            Err(e) => {
                let why = if path.is_file() {
                    format!("cannot be parsed: {e}")
                } else {
                    "does not exist".to_string()
                };
                out.push(
                    cx.finding(format!("companion URDF {} {why}", path.display()), spec_loc)
                        .label("companion_urdf")
                        .note("the spec names a URDF describing the same robot, so the two could be compared; without it drift between them goes unnoticed")
                        .help("fix the path (it is relative to the spec file) or remove `companion_urdf` from the spec"),
                );
                return;
            }
        };
        let rtol = cx.opt("range_tolerance");
        let tol = cx.opt("tolerance");
        let atol = cx.opt("axis_tolerance");
        let fname = path.file_name().map(|f| f.to_string_lossy().to_string()).unwrap_or_default();
        for uj in &urdf.joints {
            use urdf_rs::JointType as T;
            if !matches!(uj.joint_type, T::Revolute | T::Continuous | T::Prismatic) {
                continue;
            }
            let Some(j) = robot.joint(&uj.name) else { continue };
            let unit_r = if uj.joint_type == T::Prismatic { "m" } else { "rad" };
            let tag = |f: Finding| {
                f.secondary(spec_loc, format!("compared with {fname}"))
                    .subject(Subject::Joint(j.id))
            };
            // Axis.
            let (ua, ma) = (unit(uj.axis.xyz.0), unit(j.axis));
            let d_same = (0..3).map(|k| (ua[k] - ma[k]).abs()).fold(0.0, f64::max);
            let d_flip = (0..3).map(|k| (ua[k] + ma[k]).abs()).fold(0.0, f64::max);
            let flipped = d_flip <= atol && d_same > atol;
            let axis_s = |a: [f64; 3]| {
                format!("({}, {}, {})", fmt_num(a[0], 3), fmt_num(a[1], 3), fmt_num(a[2], 3))
            };
            if d_same > atol {
                let msg = if flipped {
                    format!(
                        "joint `{}` axis {} is the URDF's axis {} reversed",
                        j.name,
                        axis_s(ma),
                        axis_s(ua)
                    )
                } else {
                    format!(
                        "joint `{}` axis {} differs from the URDF's {}",
                        j.name,
                        axis_s(ma),
                        axis_s(ua)
                    )
                };
                out.push(tag(cx
                    .at_attr(ElemKind::Joint, j.id, &j.name, "axis", msg)
                    .label("axis")
                    .note(if flipped {
                        "a reversed axis inverts the joint's sign convention: positive commands and readings mean opposite motions in the two files unless the joint mapping negates them (MJCF body frames may also be rotated relative to URDF links; check both)"
                    } else {
                        "the axes are compared in each file's joint frame; a different axis means a different motion (or a rotated body frame, which should then be checked)"
                    })
                    .help("use the same axis in both files, or record the sign flip in the joint mapping")));
            }
            // Range.
            let limited = uj.joint_type != T::Continuous
                && uj.limit.lower.is_finite()
                && uj.limit.upper.is_finite();
            if limited && j.limited {
                let ur = if flipped {
                    [-uj.limit.upper, -uj.limit.lower]
                } else {
                    [uj.limit.lower, uj.limit.upper]
                };
                let dr = (j.range[0] - ur[0]).abs().max((j.range[1] - ur[1]).abs());
                if dr > rtol {
                    out.push(tag(cx
                        .at_attr(ElemKind::Joint, j.id, &j.name, "range", format!(
                            "joint `{}` range [{}, {}] {unit_r} differs from the URDF's [{}, {}] {unit_r}{}",
                            j.name, fmt_num(j.range[0], 4), fmt_num(j.range[1], 4), fmt_num(ur[0], 4), fmt_num(ur[1], 4),
                            if flipped { " (mirrored for the reversed axis)" } else { "" }))
                        .label(format!("differs by up to {} {unit_r}", fmt_num(dr, 3)))
                        .note("training and deployment disagree about where the joint stops: a wider simulated range lets the policy drive into the real hard stop")
                        .help("use the hardware range in both files")
                        .measured(dr, unit_r)
                        .expected(0.0, unit_r)));
                }
            } else if limited != j.limited && uj.joint_type != T::Continuous {
                out.push(tag(cx
                    .at_elem(
                        ElemKind::Joint,
                        j.id,
                        &j.name,
                        format!(
                            "joint `{}` is {} in the MJCF but {} in the URDF",
                            j.name,
                            if j.limited { "limited" } else { "unlimited" },
                            if limited { "limited" } else { "unlimited" }
                        ),
                    )
                    .note("one file lets the joint turn freely where the other stops it")
                    .help("limit the joint in both files")));
            }
            // Effort.
            if uj.limit.effort > 0.0
                && uj.limit.effort.is_finite()
                && let Some(me) = model_effort(robot, j.id)
                && rel_differs(me, uj.limit.effort, tol)
            {
                let acts = robot.actuators_on_joint(j.id);
                let f = match acts.first() {
                    Some(a) if a.forcelimited => {
                        cx.at_attr(ElemKind::Actuator, a.id, &a.name, "forcerange", "")
                    }
                    Some(a) if a.kind == ActuatorKind::Motor && a.ctrllimited => {
                        cx.at_attr(ElemKind::Actuator, a.id, &a.name, "ctrlrange", "")
                    }
                    _ => cx.at_attr(ElemKind::Joint, j.id, &j.name, "actuatorfrcrange", ""),
                };
                let mut f = tag(f
                            .label(format!("effort {}", fmt_num(me, 4)))
                            .note("the simulated actuator can push harder (or weaker) than the URDF's effort limit, which the motor driver enforces on hardware")
                            .help("use the hardware torque limit in both files")
                            .measured(me, "N·m")
                            .expected(uj.limit.effort, "N·m"));
                f.message = format!(
                    "joint `{}` effort limit {} N·m in the MJCF differs from the URDF's {} N·m",
                    j.name,
                    fmt_num(me, 4),
                    fmt_num(uj.limit.effort, 4)
                );
                out.push(f);
            }
            // Velocity vs spec.
            if uj.limit.velocity > 0.0 && uj.limit.velocity.is_finite() {
                let sv = cx.facts(&j.name).and_then(|f| {
                    let fam = f.motor?;
                    let m = spec.motor(&fam)?;
                    m.velocity_limit.as_ref().map(|v| (*v.get_ref(), spec.loc(v.span())))
                });
                if let Some((sv, sloc)) = sv
                    && rel_differs(sv, uj.limit.velocity, tol)
                {
                    out.push(tag(cx
                            .at_elem(ElemKind::Joint, j.id, &j.name, format!(
                                "joint `{}` velocity limit {} rad/s in the URDF differs from the spec's motor velocity_limit {} rad/s",
                                j.name, fmt_num(uj.limit.velocity, 4), fmt_num(sv, 4)))
                            .secondary(sloc, "spec velocity_limit")
                            .note("the deployment stack clamps or faults on the URDF's velocity limit; training assumes the spec's")
                            .help("make the URDF and the spec agree on the motor's velocity limit")
                            .measured(uj.limit.velocity, "rad/s")
                            .expected(sv, "rad/s")));
                }
            }
        }
        // Mimic joints: URDF `q = multiplier · q_leader + offset` against the MJCF joint
        // equality's `polycoef` (`q1 = c0 + c1 · q2 + …`).
        for uj in &urdf.joints {
            let Some(m) = &uj.mimic else { continue };
            let (Some(j), Some(lead)) = (robot.joint(&uj.name), robot.joint(&m.joint)) else {
                continue;
            };
            let (mul, off) = (m.multiplier.unwrap_or(1.0), m.offset.unwrap_or(0.0));
            let data = robot.mj.eq_data();
            let eq = robot
                .equalities
                .iter()
                .find(|e| e.etype == EQ_JOINT && e.obj1 == j.id as i32 && e.obj2 == lead.id as i32);
            let Some((eq, c)) = eq.and_then(|e| data.get(e.id).map(|d| (e, d))) else { continue };
            if rel_differs(c[1], mul, tol) || (c[0] - off).abs() > rtol {
                out.push(
                    cx.at_attr(ElemKind::Equality, eq.id, &eq.name, "polycoef", format!(
                        "joint `{}` follows `{}` as {} + {}·q in the MJCF but as {} + {}·q in the URDF's mimic",
                        j.name, lead.name, fmt_num(c[0], 4), fmt_num(c[1], 4), fmt_num(off, 4), fmt_num(mul, 4)))
                        .label("polycoef")
                        .secondary(spec_loc, format!("compared with {fname}"))
                        .note("the coupled joint moves by a different ratio in training and on the hardware (a linkage or belt the URDF's mimic describes): every pose and the load on the leader differ")
                        .help("use the linkage's measured ratio in both files (MJCF polycoef=\"offset multiplier 0 0 0\")")
                        .subject(Subject::Joint(j.id))
                        .measured(c[1], "")
                        .expected(mul, ""),
                );
            }
        }
        // Link masses.
        for link in &urdf.links {
            let Some(b) = robot.bodies.iter().find(|b| b.name == link.name && b.id != 0) else {
                continue;
            };
            let um = link.inertial.mass.value;
            if um > 0.0 && rel_differs(b.mass, um, tol) {
                out.push(
                    cx.at_elem(ElemKind::Body, b.id, &b.name, format!(
                        "body `{}` mass {} kg differs from the URDF link's {} kg ({}%)",
                        b.name, fmt_num(b.mass, 4), fmt_num(um, 4), fmt_num((b.mass - um) / um * 100.0, 3)))
                        .label("mass")
                        .secondary(spec_loc, format!("compared with {fname}"))
                        .note("a link mass that differs between training and deployment models changes the dynamics the policy was trained on and the model-based parts of the stack (gravity compensation, state estimation)")
                        .help("use the measured mass in both files")
                        .subject(Subject::Body(b.id))
                        .measured(b.mass, "kg")
                        .expected(um, "kg"),
                );
            }
        }
    }
}
