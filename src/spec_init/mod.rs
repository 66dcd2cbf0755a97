//! `modellint init-spec MODEL`: a commented hardware-spec template derived from the compiled
//! model. What the model states (actuated and passive joints, left/right markers, feet, the
//! standing keyframe, effort limits) is written as values; what only the hardware can tell
//! (rotor inertia, gear ratio, control rate, action delay, soft-limit factor, …) is written as a
//! commented placeholder with its unit and, where the model holds a related number, that number.
//!
//! Motor families: the actuated joints grouped by (effort limit, effective armature) as MuJoCo
//! compiled them — one motor and gearbox gives one peak torque and one reflected inertia — named
//! after the actuators' shared `<default class>` or the joints' shared name part.

use std::fmt::Write as _;

use globset::Glob;

use crate::model::mirror;
use crate::model::mjcf::ElemKind;
use crate::model::{ActuatorKind, Robot};
use crate::rules::limits::effort_limit_mismatch::joint_torque_limit;
use crate::util::fmt_num;

mod count;
use count::{actuated, passive};
mod naming;

use naming::{GENERIC_WORDS, class_stem, region};

/// One motor family of the template.
#[derive(Debug, Clone)]
pub struct Family {
    pub name: String,
    /// Peak torque (N·m) or force (N) at the joint, from the model's limits; `None`: no limit.
    pub effort: Option<f64>,
    /// Effective armature at the joint (kg·m²).
    pub armature: f64,
    /// Actuated joints of the family, in model order.
    pub joints: Vec<usize>,
    /// `<default class>` names of the family's actuators, sorted, deduplicated.
    pub classes: Vec<String>,
    /// Position-servo gains (kp, kv) when every actuator of the family is a position servo
    /// with the same gains.
    pub servo: Option<(f64, f64)>,
    /// Whether any actuator of the family commands torque directly (`<motor>`).
    pub torque_driven: bool,
}

/// Relative tolerance under which two effort limits or armatures are one family's.
const SAME: f64 = 1e-6;

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= SAME * a.abs().max(b.abs()).max(1e-12)
}

/// The motor families of the model's actuated joints.
pub fn families(robot: &Robot) -> Vec<Family> {
    let mut fams: Vec<Family> = Vec::new();
    for j in actuated(robot) {
        let effort = joint_torque_limit(robot, j).map(|(x, _)| x);
        let armature = robot.joints[j].armature;
        let acts = robot.actuators_on_joint(j);
        let classes: Vec<String> = acts
            .iter()
            .filter_map(|a| robot.elem(ElemKind::Actuator, a.id, &a.name)?.class.clone())
            .collect();
        let servo = match acts.as_slice() {
            [a] => match a.kind {
                ActuatorKind::Position { kp, kv } => {
                    let g2 = a.gear * a.gear;
                    Some((kp * g2, kv * g2))
                }
                _ => None,
            },
            _ => None,
        };
        let torque = acts.iter().any(|a| a.kind == ActuatorKind::Motor);
        let found = fams.iter_mut().find(|f| {
            same(f.armature, armature)
                && match (f.effort, effort) {
                    (Some(a), Some(b)) => same(a, b),
                    (None, None) => true,
                    _ => false,
                }
        });
        match found {
            Some(f) => {
                f.joints.push(j);
                f.classes.extend(classes);
                if f.servo.is_some_and(|s| servo.is_none_or(|t| !same(s.0, t.0) || !same(s.1, t.1)))
                {
                    f.servo = None;
                }
                f.torque_driven |= torque;
            }
            None => fams.push(Family {
                name: String::new(),
                effort,
                armature,
                joints: vec![j],
                classes,
                servo,
                torque_driven: torque,
            }),
        }
    }
    for f in &mut fams {
        f.classes.sort();
        f.classes.dedup();
    }
    name_families(robot, &mut fams);
    fams
}

/// A TOML bare key from a name: letters, digits, `_` and `-`; lower case.
fn bare(s: &str) -> String {
    let k: String = s
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '-' { c.to_ascii_lowercase() } else { '_' })
        .collect();
    k.trim_matches('_').to_string()
}

/// A joint's side and its mirror partner's name, paired as lint pairs them
/// (`mirror::mirror_in`: `LL_`/`LR_` are a biped's legs only when the partner exists, not a
/// quadruped's left-rear leg).
fn mirror_of(robot: &Robot, name: &str) -> Option<(mirror::Side, String)> {
    mirror::mirror_in(name, None, |n| robot.joint(n).is_some())
}

/// A joint name without its side marker, split into lower-case words.
fn words(robot: &Robot, name: &str) -> Vec<String> {
    let stem = match mirror_of(robot, name) {
        Some((_, other)) => {
            let (p, s) = common_ends(name, &other);
            format!("{}{}", &name[..p], &name[name.len() - s..])
        }
        None => name.to_string(),
    };
    stem.split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(|w| w.to_ascii_lowercase())
        .collect()
}

/// Names each family: the `<default class>` its actuators share and no other family uses (or
/// the leading words of its classes, e.g. `size3` and `size3_limited`), else the first word its
/// joints' names share (side markers and generic words such as `joint` left out), else its
/// effort limit.
fn name_families(robot: &Robot, fams: &mut [Family]) {
    let class_use =
        |c: &str, fams: &[Family]| fams.iter().filter(|f| f.classes.iter().any(|x| x == c)).count();
    let mut names: Vec<String> = Vec::new();
    for i in 0..fams.len() {
        let f = &fams[i];
        let own = !f.classes.is_empty() && f.classes.iter().all(|c| class_use(c, fams) == 1);
        let by_class = Some(bare(&class_stem(&f.classes))).filter(|c| own && !c.is_empty());
        let by_words = {
            let lists: Vec<Vec<String>> =
                f.joints.iter().map(|&j| words(robot, &robot.joints[j].name)).collect();
            if lists.windows(2).all(|w| w[0] == w[1]) {
                // One joint kind (a left/right pair): its whole name.
                lists.first().map(|l| bare(&l.join("_")))
            } else {
                lists.first().and_then(|first| {
                    first
                        .iter()
                        .filter(|w| !GENERIC_WORDS.contains(&w.as_str()))
                        .find(|w| lists.iter().all(|l| l.contains(w)))
                        .map(|w| bare(w))
                })
            }
        };
        let by_effort = match f.effort {
            Some(e) => format!("effort_{}", fmt_num(e, 4).replace(['.', '-'], "_")),
            None => "unlimited".to_string(),
        };
        let mut name = by_class.or(by_words).filter(|n| !n.is_empty()).unwrap_or(by_effort);
        if names.contains(&name) {
            let mut k = 2;
            while names.contains(&format!("{name}_{k}")) {
                k += 1;
            }
            name = format!("{name}_{k}");
        }
        names.push(name);
    }
    for (f, n) in fams.iter_mut().zip(names) {
        f.name = n;
    }
}

/// Byte lengths of the common prefix and suffix of two names, each shrunk to a word boundary
/// (so `Hip_Right` / `Hip_Left` share `Hip_`, not the `t` of both sides).
fn common_ends(a: &str, b: &str) -> (usize, usize) {
    let (ab, bb) = (a.as_bytes(), b.as_bytes());
    let max = ab.len().min(bb.len());
    let mut p = ab.iter().zip(bb).take_while(|(x, y)| x == y).count();
    while p > 0
        && ab[p - 1].is_ascii_alphanumeric()
        && p < ab.len()
        && ab[p].is_ascii_alphanumeric()
    {
        p -= 1;
    }
    let mut s = ab.iter().rev().zip(bb.iter().rev()).take_while(|(x, y)| x == y).count();
    s = s.min(max - p);
    while s > 0 {
        let i = ab.len() - s;
        if i > 0 && ab[i].is_ascii_alphanumeric() && ab[i - 1].is_ascii_alphanumeric() {
            s -= 1;
        } else {
            break;
        }
    }
    while !a.is_char_boundary(p) || !a.is_char_boundary(a.len() - s) {
        p = p.saturating_sub(1);
        s = s.saturating_sub(1);
    }
    (p, s)
}

/// A glob that matches exactly `names` among `all`: a left/right pair as `{left,right}_knee`,
/// else each name escaped. One glob per returned entry.
fn globs(names: &[&str], all: &[String]) -> Vec<String> {
    let exact = |pat: &str, want: &[&str]| {
        Glob::new(pat).ok().is_some_and(|g| {
            let m = g.compile_matcher();
            all.iter().filter(|n| m.is_match(n.as_str())).count() == want.len()
                && want.iter().all(|n| m.is_match(n))
        })
    };
    if let [a, b] = names {
        let (p, s) = common_ends(a, b);
        let (ma, mb) = (&a[p..a.len() - s], &b[p..b.len() - s]);
        let pat = format!(
            "{}{{{},{}}}{}",
            globset::escape(&a[..p]),
            globset::escape(ma),
            globset::escape(mb),
            globset::escape(&a[a.len() - s..])
        );
        if !ma.is_empty() && !mb.is_empty() && exact(&pat, names) {
            return vec![pat];
        }
    }
    names.iter().map(|n| globset::escape(n)).collect()
}

/// A TOML string literal.
fn quote(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if c.is_control() => {
                let _ = write!(o, "\\u{:04X}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// A TOML float.
fn num(x: f64) -> String {
    let s = fmt_num(x, 6);
    if s.contains(['.', 'e', 'E']) { s } else { format!("{s}.0") }
}

/// Joints grouped into left/right pairs (left first) and singles, in model order of the first.
fn pair_up<'a>(robot: &'a Robot, joints: &[usize]) -> Vec<Vec<&'a str>> {
    let mut used = vec![false; joints.len()];
    let mut out = Vec::new();
    for i in 0..joints.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let name = robot.joints[joints[i]].name.as_str();
        let partner = mirror_of(robot, name).and_then(|(side, other)| {
            let k =
                (0..joints.len()).find(|&k| !used[k] && robot.joints[joints[k]].name == other)?;
            Some((side, k))
        });
        match partner {
            Some((side, k)) => {
                used[k] = true;
                let other = robot.joints[joints[k]].name.as_str();
                out.push(match side {
                    mirror::Side::Left => vec![name, other],
                    mirror::Side::Right => vec![other, name],
                });
            }
            None => out.push(vec![name]),
        }
    }
    out
}

/// The left/right markers the model's joint names use (the first built-in pair that mirrors a
/// joint onto another joint of the model).
fn side_markers(robot: &Robot) -> Option<(String, String)> {
    let names: Vec<&str> = robot.joints.iter().map(|j| j.name.as_str()).collect();
    for j in &robot.joints {
        if let Some((side, other)) = mirror_of(robot, &j.name)
            && names.contains(&other.as_str())
        {
            let (l, r) = match side {
                mirror::Side::Left => (j.name.as_str(), other.as_str()),
                mirror::Side::Right => (other.as_str(), j.name.as_str()),
            };
            let (p, s) = common_ends(l, r);
            let (ml, mr) = (&l[p..l.len() - s], &r[p..r.len() - s]);
            // Keep the separator next to the marker, as the spec's markers are matched.
            let (ml, mr) = if s > 0 && l[l.len() - s..].starts_with('_') {
                (format!("{ml}_"), format!("{mr}_"))
            } else if p > 0 && l[..p].ends_with('_') {
                (format!("_{ml}"), format!("_{mr}"))
            } else {
                (ml.to_string(), mr.to_string())
            };
            return Some((ml, mr));
        }
    }
    None
}

/// The commented spec template for `robot` (loaded from `model_display`).
pub fn template(robot: &Robot, model_display: &str) -> String {
    let mut o = String::new();
    let fams = families(robot);
    let act = actuated(robot);
    // A model with no actuator at all (a URDF; a file whose actuators the training framework
    // adds) says nothing of which joints a motor drives: none is written as passive.
    let no_actuators = robot.actuators.is_empty();
    let pas = if no_actuators { Vec::new() } else { passive(robot) };
    let all: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let w = &mut o;
    let _ = writeln!(
        w,
        "# Hardware spec for {model_display}, written by `modellint init-spec` from the compiled model."
    );
    let _ =
        writeln!(w, "# Values are what the model states now: check each against the real robot.");
    let _ = writeln!(
        w,
        "# Commented keys (`# key = ...`) are facts only the hardware can tell: fill them in and"
    );
    let _ = writeln!(
        w,
        "# uncomment them; `modellint {model_display} --spec <this file>` names the rules still waiting"
    );
    let _ = writeln!(w, "# for one. Every key: docs/spec.md.");
    let _ = writeln!(w);
    let _ = writeln!(w, "[robot]");
    // MJCF `<mujoco model=…>`, URDF `<robot name=…>`; else the file's name.
    let attr = if robot.format == crate::model::Format::Urdf { "name" } else { "model" };
    let name =
        robot.tree.get(attr).filter(|n| !n.is_empty()).map(str::to_string).unwrap_or_else(|| {
            robot.path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
        });
    let _ = writeln!(w, "name = {}", quote(&name));
    if no_actuators {
        let _ = writeln!(
            w,
            "# actuated = ...              # the model has no actuator: how many joints the hardware drives"
        );
        let _ = writeln!(
            w,
            "# passive = ...               # and how many no motor drives (then mark each in its [joints] table)"
        );
    } else {
        let _ = writeln!(
            w,
            "actuated = {}                 # joints an actuator drives in the model",
            act.len()
        );
        let _ = writeln!(
            w,
            "passive = {}                  # hinge/slide joints no actuator drives",
            pas.len()
        );
    }
    let _ = writeln!(
        w,
        "# soft_limit_factor = 0.9     # training ctrlrange = factor × hardware range, centred (0 < f ≤ 1); 0.9 when absent"
    );
    let delays: Vec<f64> = robot.actuators.iter().map(|a| a.delay).filter(|&d| d > 0.0).collect();
    let delay_note = match delays
        .iter()
        .cloned()
        .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.max(d))))
    {
        Some(d) => format!("the model delays its actuators by up to {} ms", fmt_num(d * 1e3, 4)),
        None => "the model has no actuator delay".to_string(),
    };
    let _ = writeln!(
        w,
        "# control_hz = ...             # Hz, the policy's command rate (needed by missing-action-delay)"
    );
    let _ = writeln!(
        w,
        "# action_delay_steps = [..., ...]  # [min, max] control steps of hardware command latency; {delay_note}"
    );
    let _ = writeln!(
        w,
        "# mass_kg = [..., ...]         # kg, the real robot's mass budget; the robot weighs {} kg{}",
        fmt_num(robot.mass_split().0, 4),
        match robot.mass_split().1 {
            s if s > 0.0 => format!(" (static scenery's {} kg not counted)", fmt_num(s, 4)),
            _ => String::new(),
        }
    );
    if let Some(k) = &robot.key.key_name {
        let _ = writeln!(w, "keyframe = {}              # the standing keyframe", quote(k));
    } else {
        let _ = writeln!(
            w,
            "# keyframe = \"stand\"         # the standing keyframe (the model has {} keyframe(s))",
            robot.keys.len()
        );
    }
    match side_markers(robot) {
        Some((l, r)) => {
            let _ = writeln!(
                w,
                "left = {}                 # name markers of left/right elements",
                quote(&l)
            );
            let _ = writeln!(w, "right = {}", quote(&r));
        }
        None => {
            let _ = writeln!(
                w,
                "# left = \"left_\"             # name markers of left/right elements (none found in the joint names)"
            );
            let _ = writeln!(w, "# right = \"right_\"");
        }
    }
    let feet = crate::rules::contact::feet::feet(robot, None);
    let mut foot_bodies: Vec<String> = Vec::new();
    for f in &feet {
        for b in std::iter::once(f.root).chain(f.toes.iter().copied()) {
            let n = robot.body_name(b).to_string();
            if !n.is_empty() && !foot_bodies.contains(&n) {
                foot_bodies.push(n);
            }
        }
    }
    if foot_bodies.is_empty() {
        let _ = writeln!(
            w,
            "foot_bodies = []              # no foot found (a fixed base or no foot contact): foot rules stay off"
        );
    } else {
        let list: Vec<String> = foot_bodies.iter().map(|b| quote(&globset::escape(b))).collect();
        let _ = writeln!(
            w,
            "foot_bodies = [{}]  # globs: bodies whose geoms are foot and toe contacts",
            list.join(", ")
        );
    }
    let urdf = robot.path.with_extension("urdf");
    match urdf.file_name().filter(|_| urdf.is_file() && robot.format == crate::model::Format::Mjcf)
    {
        Some(f) => {
            let _ = writeln!(
                w,
                "companion_urdf = {}  # compared by urdf-mjcf-drift",
                quote(&f.to_string_lossy())
            );
        }
        None => {
            let _ = writeln!(
                w,
                "# companion_urdf = \"robot.urdf\"  # a URDF of the same robot, relative to this file (needed by urdf-mjcf-drift)"
            );
        }
    }

    for f in &fams {
        let _ = writeln!(w);
        let names: Vec<&str> = f.joints.iter().map(|&j| robot.joints[j].name.as_str()).collect();
        let _ = writeln!(w, "# {} joint(s): {}", names.len(), names.join(", "));
        if !f.classes.is_empty() {
            let _ = writeln!(w, "# actuator class(es): {}", f.classes.join(", "));
        }
        let _ = writeln!(w, "[motors.{}]", f.name);
        let _ = writeln!(
            w,
            "# rotor_inertia = ...   # kg·m² at the motor shaft (datasheet); the model's armature {} = rotor_inertia × gear_ratio² × count",
            fmt_num(f.armature, 6)
        );
        let _ = writeln!(w, "# gear_ratio = ...      # reduction of the gearbox (> 0)");
        match f.effort {
            Some(e) => {
                let _ = writeln!(
                    w,
                    "peak_torque = {}     # N·m (N for a slide) at the joint: the model's effort limit",
                    num(e)
                );
            }
            None => {
                let _ = writeln!(
                    w,
                    "# peak_torque = ...     # N·m at the joint (the model sets no effort limit)"
                );
            }
        }
        let _ = writeln!(w, "# velocity_limit = ...  # rad/s at the joint");
        let _ = writeln!(w, "# saturation_torque = ...  # N·m, the speed–torque line's intercept");
        match (f.servo, f.torque_driven) {
            (Some((kp, kv)), _) => {
                let _ = writeln!(
                    w,
                    "# kp = ...              # hardware PD gains, N·m/rad; the model's position servo: kp {}",
                    fmt_num(kp, 4)
                );
                let _ = writeln!(
                    w,
                    "# kd = ...              # N·m·s/rad; the model's position servo: kv {}",
                    fmt_num(kv, 4)
                );
            }
            (None, true) => {
                let _ = writeln!(
                    w,
                    "# kp = ...              # hardware PD gains, N·m/rad and N·m·s/rad: the model drives these joints by torque,"
                );
                let _ = writeln!(w, "# kd = ...              # so underdamped-pd-gains needs them");
            }
            _ => {
                let _ = writeln!(
                    w,
                    "# kp = ...              # hardware PD gains, N·m/rad and N·m·s/rad"
                );
                let _ = writeln!(w, "# kd = ...");
            }
        }
        let _ =
            writeln!(w, "# kd_max = ...          # N·m·s/rad, the largest KD the firmware accepts");
        let _ = writeln!(w, "# friction_static = ...   # N·m");
        let _ = writeln!(w, "# friction_dynamic = ...  # N·m");
    }

    for f in &fams {
        for group in pair_up(robot, &f.joints) {
            for pat in globs(&group, &all) {
                let _ = writeln!(w);
                let _ = writeln!(w, "[joints.{}]", quote(&pat));
                let _ = writeln!(w, "motor = {}", quote(&f.name));
                let _ = writeln!(w, "{}", count::count_line(robot, &group));
                let _ = writeln!(
                    w,
                    "# direction = 1               # the hardware's gear sign, +1 or −1"
                );
                if let Some(r) = region(group[0]) {
                    let _ =
                        writeln!(w, "region = {}                # guessed from the name", quote(r));
                }
            }
        }
    }
    let pas_names: Vec<usize> = pas.clone();
    for group in pair_up(robot, &pas_names) {
        for pat in globs(&group, &all) {
            let _ = writeln!(w);
            let _ = writeln!(w, "# no actuator drives this joint in the model");
            let _ = writeln!(w, "[joints.{}]", quote(&pat));
            let _ = writeln!(w, "passive = true");
            if let Some(r) = region(group[0]) {
                let _ = writeln!(w, "region = {}                # guessed from the name", quote(r));
            }
        }
    }
    align_comments(&o)
}

/// Pads `code   # comment` lines so the comments start in one column.
fn align_comments(text: &str) -> String {
    const COL: usize = 32;
    let mut out = String::with_capacity(text.len() + 1024);
    for line in text.lines() {
        match line.find("  # ") {
            Some(i) if !line[..i].trim().is_empty() => {
                let code = line[..i].trim_end();
                let pad = COL.saturating_sub(code.chars().count()).max(2);
                let _ = writeln!(out, "{code}{}# {}", " ".repeat(pad), line[i + 4..].trim_start());
            }
            _ => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    out
}

/// `modellint init-spec --help`.
pub const LONG_ABOUT: &str = r#"Write a commented hardware-spec template derived from the model.

Some checks compare the model with facts about the real robot that no model file holds (motor
families, rotor inertia and gear ratio, control rate and action delay, which joints are passive).
`init-spec` writes those facts as a spec TOML (docs/spec.md), filled in where the compiled model
states them and left as commented placeholders, with their units, where only the hardware can
tell:
  - [robot]: the numbers of actuated and passive joints, the standing keyframe, the left/right
    name markers and the foot bodies, as the model has them;
  - [motors.<family>]: one family per (effort limit, armature) pair of the actuated joints, named
    after their shared actuator class or joint-name part, with the model's effort limit as
    peak_torque; rotor_inertia, gear_ratio, velocity_limit, kp/kd, friction are placeholders
    (the comment shows the model's armature and servo gains);
  - [joints."<glob>"]: each actuated joint (left/right pairs as `{left,right}_knee`) with its
    family, count (the number of tendon actuators when two or more drive it, a parallel linkage the
    model shows; else 1, with how to tell a two-motor ankle) and a region guessed from its name;
    joints no actuator drives as passive = true (not a joint an equality ties to a motor: a mimic).

The values are the model's own, so the spec agrees with the model as it is; check each against
the real robot, fill the placeholders in and uncomment them. A lint run with the spec names the
rules still waiting for a placeholder.

Examples:
  modellint init-spec robot.xml                  # writes robot.toml beside it (found by `modellint robot.xml`)
  modellint init-spec scene.xml -o robot.toml    # anywhere else: pass it with --spec
  modellint init-spec robot.xml -o -             # print it

Exit codes: 0 written; 2 the model does not load, or the file exists (--force replaces it)."#;

/// Writes the template for `model` to `output` (default `<model>.toml`, `-` = stdout); exit code.
pub fn run(model: &std::path::Path, output: Option<&std::path::Path>, force: bool) -> i32 {
    crate::model::mj::silence_warnings();
    let mut map = crate::model::source::SourceMap::default();
    let robot = match crate::model::load(&mut map, model, None) {
        Ok(r) => r,
        Err(e) => {
            eprint!("{}", crate::output::text::render_error(&e, crate::output::color_on_stderr()));
            return 2;
        }
    };
    let text = template(&robot, &model.display().to_string());
    let out =
        output.map(std::path::Path::to_path_buf).unwrap_or_else(|| model.with_extension("toml"));
    if out.as_os_str() == "-" {
        print!("{text}");
        return 0;
    }
    if out.exists() && !force {
        eprintln!(
            "modellint: {} exists; pass --force to replace it, or -o FILE to write elsewhere",
            out.display()
        );
        return 2;
    }
    if let Err(e) = std::fs::write(&out, text) {
        eprintln!("modellint: {}: cannot write the spec: {e}", out.display());
        return 2;
    }
    let found =
        output.is_none() || crate::spec_use::discover(model).path.as_deref() == Some(out.as_path());
    // A scene including the robot file: linting that file alone looks beside it, not here.
    let included = crate::spec_use::includes(model)
        .into_iter()
        .map(|f| f.with_extension("toml"))
        .find(|t| *t != out)
        .map(|t| {
            format!(
                ". Linting the included robot file alone reads {} instead (-o {} writes the spec \
                 there, where linting this scene finds it too)",
                t.display(),
                t.display()
            )
        })
        .unwrap_or_default();
    eprintln!(
        "modellint: wrote {} ({} motor families); check its values against the robot, fill in the commented placeholders{}{included}",
        out.display(),
        families(&robot).len(),
        if found {
            format!("; `modellint {}` uses it", model.display())
        } else {
            format!(", then `modellint {} --spec {}`", model.display(), out.display())
        }
    );
    0
}

#[cfg(test)]
mod tests;
