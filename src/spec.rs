//! The hardware spec: facts about the real robot that a model file cannot hold (motor families,
//! gear ratios, rotor inertia, passive joints, delay, soft-limit factor). TOML, beside the model
//! (`models/asimov.toml` for `models/asimov.xml`) or given with `--spec`.

use std::collections::BTreeMap;
use std::path::Path;

use globset::{Glob, GlobMatcher};
use serde::Deserialize;
use toml::Spanned;

use crate::error::LoadError;
use crate::model::source::{Loc, SourceMap};

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    pub name: Option<String>,
    /// Expected number of actuated joints.
    pub actuated: Option<Spanned<usize>>,
    /// Expected number of passive joints.
    pub passive: Option<Spanned<usize>>,
    /// Training ctrlrange = factor × hardware range, centred.
    pub soft_limit_factor: Option<Spanned<f64>>,
    /// Policy / command rate, Hz.
    pub control_hz: Option<Spanned<f64>>,
    /// Hardware action delay range in control steps.
    pub action_delay_steps: Option<Spanned<[f64; 2]>>,
    /// Total mass budget, kg.
    pub mass_kg: Option<Spanned<[f64; 2]>>,
    /// Name of the standing keyframe.
    pub keyframe: Option<Spanned<String>>,
    /// Name markers of left/right elements.
    pub left: Option<String>,
    pub right: Option<String>,
    /// Bodies whose geoms are foot and toe contacts (globs).
    pub foot_bodies: Option<Spanned<Vec<String>>>,
    /// A URDF describing the same robot, compared by `urdf-mjcf-drift`.
    pub companion_urdf: Option<Spanned<String>>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Motor {
    /// Rotor inertia at the motor shaft, kg·m².
    pub rotor_inertia: Option<Spanned<f64>>,
    pub gear_ratio: Option<Spanned<f64>>,
    /// Peak torque at the joint, N·m.
    pub peak_torque: Option<Spanned<f64>>,
    /// Joint velocity limit, rad/s.
    pub velocity_limit: Option<Spanned<f64>>,
    /// Speed–torque line intercept, N·m.
    pub saturation_torque: Option<Spanned<f64>>,
    /// Largest KD the firmware accepts, N·m·s/rad.
    pub kd_max: Option<Spanned<f64>>,
    pub kp: Option<Spanned<f64>>,
    pub kd: Option<Spanned<f64>>,
    pub friction_static: Option<Spanned<f64>>,
    pub friction_dynamic: Option<Spanned<f64>>,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct JointEntry {
    pub motor: Option<Spanned<String>>,
    pub count: Option<Spanned<u32>>,
    pub direction: Option<Spanned<i32>>,
    pub passive: Option<Spanned<bool>>,
    pub region: Option<Spanned<String>>,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawSpec {
    #[serde(default)]
    robot: RobotSpec,
    #[serde(default)]
    motors: BTreeMap<String, Motor>,
    #[serde(default)]
    joints: BTreeMap<String, Spanned<JointEntry>>,
}

/// What the spec says about one model joint, after merging every matching `[joints."glob"]`.
#[derive(Debug, Clone, Default)]
pub struct JointFacts {
    pub motor: Option<String>,
    pub count: u32,
    pub direction: Option<i32>,
    pub passive: bool,
    pub region: Option<String>,
    /// The spec line(s) that matched this joint (for secondary labels).
    pub locs: Vec<Loc>,
    pub motor_loc: Option<Loc>,
}

#[derive(Debug, Clone)]
pub struct Spec {
    pub file: usize,
    pub robot: RobotSpec,
    pub motors: BTreeMap<String, Motor>,
    patterns: Vec<(String, GlobMatcher, JointEntry, Loc)>,
}

pub fn v(x: &Option<Spanned<f64>>) -> Option<f64> {
    x.as_ref().map(|s| *s.get_ref())
}

impl Spec {
    pub fn loc(&self, span: std::ops::Range<usize>) -> Loc {
        Loc { file: self.file, start: span.start, end: span.end }
    }

    pub fn soft_limit_factor(&self) -> f64 {
        self.robot.soft_limit_factor.as_ref().map(|s| *s.get_ref()).unwrap_or(0.9)
    }

    /// Facts for a joint name (None when no pattern matches it).
    pub fn joint(&self, name: &str) -> Option<JointFacts> {
        let mut out: Option<JointFacts> = None;
        for (_, m, e, loc) in &self.patterns {
            if !m.is_match(name) {
                continue;
            }
            let f = out.get_or_insert_with(|| JointFacts { count: 1, ..Default::default() });
            f.locs.push(*loc);
            if let Some(mo) = &e.motor {
                f.motor = Some(mo.get_ref().clone());
                f.motor_loc = Some(self.loc(mo.span()));
            }
            if let Some(c) = &e.count {
                f.count = *c.get_ref();
            }
            if let Some(d) = &e.direction {
                f.direction = Some(*d.get_ref());
            }
            if let Some(p) = &e.passive {
                f.passive = *p.get_ref();
            }
            if let Some(r) = &e.region {
                f.region = Some(r.get_ref().clone());
            }
        }
        out
    }

    pub fn motor(&self, family: &str) -> Option<&Motor> {
        self.motors.get(family)
    }

    /// Expected armature of a joint: rotor inertia × gear² × motor count.
    pub fn expected_armature(&self, facts: &JointFacts) -> Option<f64> {
        let m = self.motor(facts.motor.as_deref()?)?;
        let (ri, g) = (v(&m.rotor_inertia)?, v(&m.gear_ratio)?);
        Some(ri * g * g * facts.count as f64)
    }

    pub fn foot_matchers(&self) -> Vec<GlobMatcher> {
        self.robot
            .foot_bodies
            .as_ref()
            .map(|s| {
                s.get_ref()
                    .iter()
                    .filter_map(|p| Glob::new(p).ok().map(|g| g.compile_matcher()))
                    .collect()
            })
            .unwrap_or_default()
    }
}

fn err_at(map: &SourceMap, file: usize, span: std::ops::Range<usize>, msg: String) -> LoadError {
    LoadError::at(map, Loc { file, start: span.start, end: span.end }, msg)
}

/// Parses and validates a spec against the model's joint names.
pub fn load(map: &mut SourceMap, path: &Path, joint_names: &[String]) -> Result<Spec, LoadError> {
    let file = crate::model::source::read_source(map, path)?;
    let text = map.file(file).text.clone();
    let raw: RawSpec = toml::from_str(&text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        err_at(map, file, span, format!("invalid hardware spec: {}", e.message()))
    })?;
    let bad = |span: std::ops::Range<usize>, m: String| err_at(map, file, span, m);
    for (name, m) in &raw.motors {
        for (key, val) in [
            ("rotor_inertia", &m.rotor_inertia),
            ("gear_ratio", &m.gear_ratio),
            ("peak_torque", &m.peak_torque),
            ("velocity_limit", &m.velocity_limit),
            ("saturation_torque", &m.saturation_torque),
            ("kd_max", &m.kd_max),
            ("kp", &m.kp),
            ("kd", &m.kd),
            ("friction_static", &m.friction_static),
            ("friction_dynamic", &m.friction_dynamic),
        ] {
            if let Some(s) = val {
                let x = *s.get_ref();
                let strict = matches!(
                    key,
                    "gear_ratio"
                        | "peak_torque"
                        | "velocity_limit"
                        | "saturation_torque"
                        | "kd_max"
                );
                let ok = x.is_finite() && if strict { x > 0.0 } else { x >= 0.0 };
                if !ok {
                    return Err(bad(
                        s.span(),
                        format!(
                            "motors.{name}.{key} must be a finite {} number, got {x}",
                            if strict { "positive" } else { "non-negative" }
                        ),
                    ));
                }
            }
        }
    }
    let r = &raw.robot;
    if let Some(f) = &r.soft_limit_factor {
        let x = *f.get_ref();
        if !(x > 0.0 && x <= 1.0) {
            return Err(bad(
                f.span(),
                format!("robot.soft_limit_factor must be in (0, 1], got {x}"),
            ));
        }
    }
    if let Some(f) = &r.control_hz
        && let Err(e) = control_hz_domain(*f.get_ref())
    {
        return Err(bad(f.span(), format!("robot.control_hz {e}")));
    }
    for (key, val) in [("action_delay_steps", &r.action_delay_steps), ("mass_kg", &r.mass_kg)] {
        if let Some(s) = val {
            let [a, b] = *s.get_ref();
            if !(a.is_finite() && b.is_finite() && a >= 0.0 && a <= b) {
                return Err(bad(
                    s.span(),
                    format!("robot.{key} must be [min, max] with 0 ≤ min ≤ max, got [{a}, {b}]"),
                ));
            }
        }
    }
    // Joint patterns in file order (later tables override earlier ones).
    let mut entries: Vec<(String, Spanned<JointEntry>)> = raw.joints.into_iter().collect();
    entries.sort_by_key(|(_, e)| e.span().start);
    let mut patterns = Vec::new();
    for (pat, e) in entries {
        let span = e.span();
        let loc = Loc { file, start: span.start, end: span.end };
        let glob = Glob::new(&pat)
            .map_err(|er| bad(span.clone(), format!("joints.\"{pat}\": bad glob pattern: {er}")))?;
        let m = glob.compile_matcher();
        if !joint_names.iter().any(|n| m.is_match(n)) {
            let near = crate::util::near_matches(&pat, joint_names);
            return Err(bad(
                span,
                format!(
                    "joints.\"{pat}\" matches no joint of the model{}",
                    if near.is_empty() {
                        String::new()
                    } else {
                        format!(" (did you mean {}?)", near.join(", "))
                    }
                ),
            ));
        }
        let je = e.into_inner();
        if let Some(mo) = &je.motor
            && !raw.motors.contains_key(mo.get_ref())
        {
            return Err(bad(
                mo.span(),
                format!("motor family `{}` is not defined under [motors]", mo.get_ref()),
            ));
        }
        if let Some(c) = &je.count
            && *c.get_ref() == 0
        {
            return Err(bad(c.span(), "count must be at least 1".into()));
        }
        if let Some(d) = &je.direction
            && d.get_ref().abs() != 1
        {
            return Err(bad(d.span(), format!("direction must be 1 or -1, got {}", d.get_ref())));
        }
        if let Some(rg) = &je.region
            && !["legs", "arms", "torso", "head"].contains(&rg.get_ref().as_str())
        {
            return Err(bad(
                rg.span(),
                format!("region must be one of legs, arms, torso, head; got `{}`", rg.get_ref()),
            ));
        }
        patterns.push((pat, m, je, loc));
    }
    Ok(Spec { file, robot: raw.robot, motors: raw.motors, patterns })
}

/// `models/asimov.toml` for `models/asimov.xml`, when it exists.
pub fn beside(model: &Path) -> Option<std::path::PathBuf> {
    let p = model.with_extension("toml");
    p.is_file().then_some(p)
}

/// The slowest controller rate accepted [Hz]. A policy or servo loop of a legged robot or an
/// arm runs at tens to thousands of hertz; a value under one hertz is a period written where a
/// rate belongs (0.02 for a 50 Hz controller) and would make every command last longer than
/// most recordings.
pub const CONTROL_HZ_MIN: f64 = 1.0;

/// `Err(reason)` when `hz` is not a controller rate: not finite, not positive, or below
/// [`CONTROL_HZ_MIN`] (then the reason names the rate the value would be as a period).
pub fn control_hz_domain(hz: f64) -> Result<(), String> {
    if !(hz.is_finite() && hz > 0.0) {
        return Err(format!("must be a positive rate in Hz, got {hz}"));
    }
    if hz < CONTROL_HZ_MIN {
        return Err(format!(
            "is a rate in Hz, got {hz} (one command every {} s): if {hz} s is the control \
             period, the rate is {} Hz",
            (1e3 / hz).round() / 1e3,
            (1e3 / hz).round() / 1e3
        ));
    }
    Ok(())
}
