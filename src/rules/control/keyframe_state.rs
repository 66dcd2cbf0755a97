use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{JointType, Robot};
use crate::rules::control::keyframe_floor;
use crate::rules::control::keyframe_scan::keyframes;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds initial states that MuJoCo does not start from as written. In every keyframe — or,
    /// when the model has none, in the default pose `qpos0` that `mj_resetData` starts from:
    /// - a free or ball joint whose quaternion is not of unit length (its length off 1 by more
    ///   than `quat_tolerance`, e.g. `0 0 0 0`);
    /// - a limited hinge or slide placed outside its range by more than `tolerance` × the
    ///   range;
    /// - an active joint equality (`<equality><joint>`, joint1 − qpos0 = polycoef(joint2 −
    ///   qpos0)) that the positions miss by more than `tolerance` × joint1's range (× 1 in joint
    ///   units when joint1 has no range);
    /// - a colliding geom of a body that is not fixed to the world lying entirely under a
    ///   floor plane it can touch (its bounding sphere, `geom_rbound`, below the plane's
    ///   surface: the base placed at the floor's height, legs and feet in the ground);
    /// - the floating-base robot (of the free bodies whose subtrees hold two or more hinges or
    ///   slides, the one with the most actuated joints: not a chair or cabinet of the scene)
    ///   whose lowest colliding geom lies more than `sink_depth` into the floor plane it
    ///   touches (a geom's exact lowest point along the plane's normal), or — when no
    ///   keyframe (or, without one, `qpos0`) brings it within `drop_height` of that plane —
    ///   more than `drop_height` above it: every reset drops the robot, landing at √(2·g·h).
    ///   Not judged: a model without a floor plane the robot touches, without gravity, with a
    ///   body held to the world by a connect or weld equality (a gantry), or with a colliding
    ///   world geom other than a plane reaching more than `drop_height` above the floor (a
    ///   platform or stairs it may stand on). A model with no floor at all — no plane or height
    ///   field anywhere: a legged robot's file, to which a training scene adds the ground at
    ///   z = 0 by convention — under gravity along −z (within 1°) is judged against z = 0 for
    ///   sinking alone: its lowest colliding geom more than `sink_depth` below z = 0 is
    ///   reported (a base written at the origin with the legs below it); a robot the file
    ///   places above z = 0 is not (the training code sets the start height). A robot fixed to
    ///   the world (an arm on its pedestal) has no free joint and is not judged.
    ///
    /// In a model with keyframes, the default pose `qpos0` is judged too, at level info: each
    /// limited hinge or slide that `qpos0` places outside its range by more than `tolerance` ×
    /// the range is reported, naming the first keyframe that places it inside (or that none
    /// does). A user who resets to that keyframe (`mj_resetDataKeyframe`) never meets it; one
    /// who resets by `mj_resetData` — as Gymnasium's MuJoCo environments do, their `init_qpos`
    /// being `qpos0` — starts every episode with the joint past its stop. Menagerie's Unitree
    /// Go2 is such a model (knees −2.7227..−0.83776 rad, qpos0 0, keyframe `home` inside):
    /// told at level info, not warned.
    ///
    /// A settled pose rests a little inside a soft limit or equality: within `tolerance` it is
    /// not reported.
    ///
    /// ## Why is this bad?
    /// MuJoCo normalises a quaternion before using it, silently: a zero quaternion becomes the
    /// identity, so the base starts in an orientation the file does not state. A joint past its
    /// stop, or off the joint it is coupled to, is kicked back by the limit or equality
    /// constraint at the first step: the robot starts with a jolt the real one never sees, and
    /// every episode reset to that state begins with it. Measured with MuJoCo's default
    /// joint-limit `solref`/`solimp` from `qpos0`, on two quadrupeds whose knees start past
    /// their stops (armature 0.01, timestep 0.002 s, no control):
    ///
    /// | knee past its stop | limit torque, step 1 | peak knee speed | back in range |
    /// |---|---|---|---|
    /// | 0.349 rad (DEEP Robotics X30) | 25.2 N·m | 6.4 rad/s | at 0.070 s, at 4.7 rad/s |
    /// | 0.92 rad (a cat-like quadruped) | 24.4 N·m | 17.1 rad/s | at 0.070 s, at 10.0 rad/s |
    ///
    /// A robot started in the air falls at
    /// every reset, and one started into the floor is thrown out of it: episodes begin with a
    /// fall or a kick the real robot never sees. MuJoCo XML reference,
    /// `keyframe/key/qpos` and `equality/joint`.
    ///
    /// ## How it is confirmed
    /// Static: reads the compiled `key_qpos` (or `qpos0`), the joint ranges and the equality's
    /// `eq_data`. A fact of the file, not a prediction a simulation could refute.
    ///
    /// ## How to fix
    /// Write a unit quaternion (`1 0 0 0` for no rotation), positions inside the joint ranges,
    /// and coupled joints that satisfy their equality, with the robot above the floor; without
    /// a keyframe, give the model one whose pose is legal (or joint ranges that contain 0). For
    /// a default pose past a stop in a model with a legal keyframe, reset to the keyframe
    /// (`mj_resetDataKeyframe`), or write the bodies in a pose inside the ranges.
    pub KeyframeState {
        id: "keyframe-state",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("tolerance", 0.02, "fraction of joint range", Domain::FRACTION_BELOW_ONE, "how far past its range, or off its joint equality, a position must be to count"),
            opt("quat_tolerance", 0.01, "", Domain::NON_NEGATIVE, "how far a free or ball joint's quaternion length may be from 1"),
            opt("drop_height", 0.25, "m", Domain::POSITIVE, "how far above its floor plane a floating-base robot's lowest geom may start: a drop of 0.25 m lands at 2.2 m/s under Earth gravity, a fall rather than a settle"),
            opt("sink_depth", 0.02, "m", Domain::POSITIVE, "how deep into its floor plane a floating-base robot's lowest geom may start: with MuJoCo's default solref (0.02 s, critically damped) and solimp (0.95) a contact's reference acceleration out of the floor is about 2770 s⁻² × the depth: 5.6 g at 0.02 m, against the millimetres a robot at rest sinks"),
        ],
    }
}

/// One state the rule reads: a keyframe, or the default pose.
struct State<'a> {
    /// Keyframe index, `None` for `qpos0`.
    key: Option<usize>,
    /// Keyframe name (empty when unnamed or `qpos0`).
    name: String,
    label: String,
    qpos: &'a [f64],
    /// The keyframe's `qpos` as the file writes it: MuJoCo's compiler normalises the
    /// quaternions of `key_qpos`, so a zero quaternion is only visible in the text.
    written: Option<Vec<f64>>,
}

/// The numbers of keyframe `k`'s `qpos` attribute as written, when they all parse.
fn written_qpos(robot: &Robot, k: usize, name: &str) -> Option<Vec<f64>> {
    let text = &robot.elem(ElemKind::Key, k, name)?.attrs.get("qpos")?.value;
    text.split_whitespace().map(|x| x.parse::<f64>().ok()).collect()
}

impl Rule for KeyframeState {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let (tol, qtol) = (cx.opt("tolerance"), cx.opt("quat_tolerance"));
        let qpos0 = robot.mj.qpos0();
        let mut states: Vec<State> = keyframes(robot)
            .into_iter()
            .map(|k| State {
                key: Some(k.index),
                label: k.label(),
                written: written_qpos(robot, k.index, &k.name),
                name: k.name,
                qpos: k.qpos,
            })
            .collect();
        if !states.is_empty() {
            default_pose_past_stops(cx, &states, tol, out);
        } else {
            states.push(State {
                key: None,
                name: String::new(),
                label: "the default pose qpos0 (no keyframe)".into(),
                qpos: qpos0,
                written: None,
            });
        }
        let mut buried = Vec::new();
        for s in &states {
            let at = |j: usize, msg: String| match s.key {
                Some(k) => cx.at_attr(ElemKind::Key, k, &s.name, "qpos", msg),
                None => cx.at_elem(ElemKind::Joint, j, &robot.joints[j].name, msg),
            };
            for j in &robot.joints {
                let a = j.qposadr;
                match j.jtype {
                    JointType::Free | JointType::Ball => {
                        let o = if j.jtype == JointType::Free { a + 3 } else { a };
                        let q = s.written.as_deref().and_then(|w| w.get(o..o + 4));
                        let Some(q) = q.or_else(|| s.qpos.get(o..o + 4)) else { continue };
                        let len = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                        if (len - 1.0).abs() <= qtol {
                            continue;
                        }
                        let msg = format!(
                            "{} gives {} joint `{}` the quaternion ({}) of length {}: MuJoCo normalises it{}",
                            s.label,
                            if j.jtype == JointType::Free { "free" } else { "ball" },
                            j.name,
                            q.iter().map(|x| fmt_num(*x, 4)).collect::<Vec<_>>().join(", "),
                            fmt_num(len, 3),
                            if len < 1e-12 {
                                " to the identity, an orientation the file does not state"
                            } else {
                                " to another orientation than the one written"
                            }
                        );
                        out.push(
                            at(j.id, msg)
                                .label("not a unit quaternion")
                                .note("a quaternion is normalised before use: the orientation that runs is not the one written, and a zero quaternion becomes the identity")
                                .help("write a unit quaternion (w x y z; `1 0 0 0` for no rotation)")
                                .subject(Subject::Joint(j.id))
                                .measured(len, ""),
                        );
                    }
                    JointType::Hinge | JointType::Slide if j.limited => {
                        let Some(&x) = s.qpos.get(a) else { continue };
                        let span = (j.range[1] - j.range[0]).abs();
                        let past = (j.range[0] - x).max(x - j.range[1]);
                        if past <= tol * span {
                            continue;
                        }
                        let u = if j.jtype == JointType::Slide { "m" } else { "rad" };
                        let msg = format!(
                            "{} places joint `{}` at {} {u}, {} {u} outside its range [{}, {}] {u}",
                            s.label,
                            j.name,
                            fmt_num(x, 4),
                            fmt_num(past, 3),
                            fmt_num(j.range[0], 4),
                            fmt_num(j.range[1], 4)
                        );
                        out.push(
                            at(j.id, msg)
                                .label("outside the joint range")
                                .note("the joint-limit constraint throws the joint back into its range at the first step: every reset to this state starts with a jolt")
                                .help("place the joint inside its range (or, without a keyframe, add one whose pose is legal)")
                                .subject(Subject::Joint(j.id))
                                .measured(past, u),
                        );
                    }
                    _ => {}
                }
            }
            let b = buried_geoms(cx, s);
            buried.push(b.is_some());
            out.extend(b);
            for (j1, j2, miss, scale) in equality_misses(robot, s.qpos, qpos0) {
                if miss.abs() <= tol * scale {
                    continue;
                }
                let (n1, u) = (&robot.joints[j1].name, unit(robot, j1));
                let other = j2.map_or("its constant".to_string(), |j| {
                    format!(
                        "joint `{}` ({} {})",
                        robot.joints[j].name,
                        fmt_num(s.qpos[robot.joints[j].qposadr], 4),
                        unit(robot, j)
                    )
                });
                let msg = format!(
                    "{} misses the joint equality coupling joint `{n1}` ({} {u}) to {other} by {} {u}",
                    s.label,
                    fmt_num(s.qpos[robot.joints[j1].qposadr], 4),
                    fmt_num(miss.abs(), 3)
                );
                out.push(
                    at(j1, msg)
                        .label("off its joint equality")
                        .note("the equality constraint snaps the coupled joints together at the first step: every reset to this state starts with a jolt")
                        .help("give the coupled joints positions that satisfy the equality (joint1 − qpos0 = polycoef(joint2 − qpos0))")
                        .subject(Subject::Joint(j1))
                        .measured(miss.abs(), u),
                );
            }
        }
        let starts: Vec<keyframe_floor::Start> = states
            .into_iter()
            .map(|s| keyframe_floor::Start { key: s.key, name: s.name, label: s.label })
            .collect();
        keyframe_floor::check(
            cx,
            &starts,
            &buried,
            cx.opt("drop_height"),
            cx.opt("sink_depth"),
            out,
        );
    }
}

/// In a model with keyframes: each limited hinge or slide that the default pose `qpos0` (what
/// `mj_resetData` starts from) places more than `tol` × its range outside that range, at level
/// info — a user who resets to a keyframe never sees it, one who resets by `mj_resetData` starts
/// every episode with the joint thrown back by its limit.
fn default_pose_past_stops(cx: &Context, keys: &[State], tol: f64, out: &mut Vec<Finding>) {
    let robot = cx.robot;
    let qpos0 = robot.mj.qpos0();
    for j in &robot.joints {
        if !(j.limited && matches!(j.jtype, JointType::Hinge | JointType::Slide)) {
            continue;
        }
        let a = j.qposadr;
        let span = (j.range[1] - j.range[0]).abs();
        let past = |x: f64| (j.range[0] - x).max(x - j.range[1]);
        let Some(&x) = qpos0.get(a) else { continue };
        if past(x) <= tol * span {
            continue;
        }
        let inside: Vec<&str> = keys
            .iter()
            .filter(|k| k.qpos.get(a).is_some_and(|&y| past(y) <= tol * span))
            .map(|k| k.label.as_str())
            .collect();
        let keyed = match inside.first() {
            Some(l) => format!(
                "; keyframe {l} places it inside, a reset by `mj_resetDataKeyframe` to it does not start past the stop"
            ),
            None => "; no keyframe places it inside either".to_string(),
        };
        let u = if j.jtype == JointType::Slide { "m" } else { "rad" };
        let msg = format!(
            "the default pose qpos0, which `mj_resetData` starts from, places joint `{}` at {} {u}, {} {u} outside its range [{}, {}] {u}{keyed}",
            j.name,
            fmt_num(x, 4),
            fmt_num(past(x), 3),
            fmt_num(j.range[0], 4),
            fmt_num(j.range[1], 4)
        );
        let mut f = cx
            .at_elem(ElemKind::Joint, j.id, &j.name, msg)
            .label("default pose outside the joint range")
            .note("qpos0 is the pose the bodies are written in (each joint at its `ref`): every reset by `mj_resetData` starts with the joint past its stop, and the joint-limit constraint throws it back over the first steps")
            .help("reset to a keyframe whose pose is legal (`mj_resetDataKeyframe`), or write the bodies in a pose inside the joint's range")
            .subject(Subject::Joint(j.id))
            .measured(past(x), u);
        f.severity = Severity::Info;
        out.push(f);
    }
}

/// The colliding geoms of bodies not fixed to the world that state `s` places entirely under a
/// floor plane they can touch (their bounding sphere below the plane's surface), reported
/// once with the deepest: MuJoCo's plane is a half-space, so each is in contact, buried.
fn buried_geoms(cx: &Context, s: &State) -> Option<Finding> {
    let robot = cx.robot;
    let m = &robot.mj;
    let mut d = mujoco_rs::prelude::MjData::new(m);
    if let Some(k) = s.key {
        let _ = d.reset_keyframe(k);
    }
    d.forward();
    let mut buried =
        crate::model::contact::buried_under_planes(robot, d.geom_xpos(), d.geom_xmat());
    if buried.is_empty() {
        return None;
    }
    buried.sort_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)));
    let (g0, pl, depth) = buried[0];
    let gname = |g: usize| {
        let n = &robot.geoms[g].name;
        if n.is_empty() { format!("geom {}", robot.unnamed_geom(g)) } else { format!("geom `{n}`") }
    };
    let plane = &robot.geoms[pl].name;
    let plane = if plane.is_empty() {
        "a floor plane".to_string()
    } else {
        format!("the floor plane `{plane}`")
    };
    let msg = format!(
        "{} places {} colliding {} of the robot entirely under {plane}: the deepest, {}, lies {} m below its surface (its whole bounding sphere)",
        s.label,
        buried.len(),
        if buried.len() == 1 { "geom" } else { "geoms" },
        gname(g0),
        fmt_num(depth, 3)
    );
    let f = match s.key {
        Some(k) => cx.at_attr(ElemKind::Key, k, &s.name, "qpos", msg),
        None => {
            let g = &robot.geoms[g0];
            cx.at_elem(ElemKind::Geom, g0, &g.name, msg)
        }
    };
    Some(
        f.label("under the floor")
            .note("a plane is a half-space to MuJoCo's collision: a geom below it is in contact, and the first step pushes the robot up through the floor with the contact force of that depth")
            .help("place the base high enough that the feet rest on the floor (its height above the feet's lowest point), or lower the floor")
            .subject(Subject::Model)
            .measured(depth, "m")
            .with("geoms", buried.len() as f64),
    )
}

fn unit(robot: &Robot, j: usize) -> &'static str {
    if robot.joints[j].jtype == JointType::Slide { "m" } else { "rad" }
}

/// For every active joint equality between scalar joints: (joint1, joint2, how far `qpos`
/// misses it in joint1's units, joint1's range span — or joint2's, or 1 when neither has a
/// range). MuJoCo's constraint: q1 − q1₀ − (c₀ + c₁·d + c₂·d² + c₃·d³ + c₄·d⁴) = 0,
/// d = q2 − q2₀ (d = 0 without joint2).
fn equality_misses(
    robot: &Robot,
    qpos: &[f64],
    qpos0: &[f64],
) -> Vec<(usize, Option<usize>, f64, f64)> {
    let m = &robot.mj;
    let (active, data) = (m.eq_active0(), m.eq_data());
    let scalar = |id: i32| {
        usize::try_from(id)
            .ok()
            .and_then(|j| robot.joints.get(j))
            .filter(|j| j.is_scalar())
            .map(|j| j.id)
    };
    let span = |j: usize| {
        let x = &robot.joints[j];
        x.limited.then(|| (x.range[1] - x.range[0]).abs()).filter(|s| *s > 0.0)
    };
    robot
        .equalities
        .iter()
        .filter(|e| e.etype == 2 && active.get(e.id).is_some_and(|&a| a))
        .filter_map(|e| {
            let j1 = scalar(e.obj1)?;
            let j2 = if e.obj2 < 0 { None } else { Some(scalar(e.obj2)?) };
            let c = data.get(e.id)?;
            let a1 = robot.joints[j1].qposadr;
            let d = match j2 {
                Some(j) => {
                    let a2 = robot.joints[j].qposadr;
                    qpos.get(a2)? - qpos0.get(a2)?
                }
                None => 0.0,
            };
            let poly = c[0] + d * (c[1] + d * (c[2] + d * (c[3] + d * c[4])));
            let miss = qpos.get(a1)? - qpos0.get(a1)? - poly;
            let scale = span(j1).or_else(|| j2.and_then(span)).unwrap_or(1.0);
            Some((j1, j2, miss, scale))
        })
        .collect()
}
