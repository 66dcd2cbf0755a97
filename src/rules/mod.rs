//! The rule engine. One rule per file under `src/rules/<group>/`; each is declared with
//! `declare_rule!`, whose doc comment *is* the rule's documentation (`modellint rule <id>`,
//! `docs/rules/<id>.md`), and registered with one line in `registry()`.

use std::collections::BTreeMap;

use crate::finding::{Finding, Severity};
use crate::model::Robot;
use crate::model::mjcf::ElemKind;
use crate::model::source::{Loc, SourceMap};
use crate::spec::Spec;

pub mod contact;
pub mod control;
pub mod geometry;
pub mod inertia;
pub mod limits;
pub mod mapping;

/// A configurable threshold of a rule: `[rules.<id>] <name> = <value>` in modellint.toml.
#[derive(Debug, Clone, Copy)]
pub struct RuleOption {
    pub name: &'static str,
    pub default: f64,
    pub unit: &'static str,
    pub help: &'static str,
    /// The only values the option takes when not empty (a contact dimension, a 0/1 switch);
    /// a config stating another is rejected at its line.
    pub allowed: &'static [f64],
    /// The values that mean something for the option (a length is not negative, a fraction
    /// lies in 0..1); a config stating a value outside it is rejected at its line.
    pub domain: Domain,
}

/// The interval a numeric rule option must lie in: `lo` to `hi`, each end included or not.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    pub lo: f64,
    pub lo_included: bool,
    pub hi: f64,
    pub hi_included: bool,
}

impl Domain {
    /// Any finite number.
    pub const ANY: Domain =
        Domain { lo: f64::NEG_INFINITY, lo_included: false, hi: f64::INFINITY, hi_included: false };
    /// x ≥ 0: a tolerance, a length or depth that may be zero.
    pub const NON_NEGATIVE: Domain =
        Domain { lo: 0.0, lo_included: true, hi: f64::INFINITY, hi_included: false };
    /// x > 0: a length, a window, a ratio threshold that zero would make meaningless.
    pub const POSITIVE: Domain =
        Domain { lo: 0.0, lo_included: false, hi: f64::INFINITY, hi_included: false };
    /// 0 ≤ x ≤ 1: a share of something.
    pub const FRACTION: Domain = Domain { lo: 0.0, lo_included: true, hi: 1.0, hi_included: true };
    /// 0 < x ≤ 1: a share that zero would make meaningless.
    pub const POSITIVE_FRACTION: Domain =
        Domain { lo: 0.0, lo_included: false, hi: 1.0, hi_included: true };
    /// 0 ≤ x < 1: a relative tolerance that must leave something of the whole.
    pub const FRACTION_BELOW_ONE: Domain =
        Domain { lo: 0.0, lo_included: true, hi: 1.0, hi_included: false };
    /// x ≥ 1: a ratio of the larger to the smaller of two values.
    pub const AT_LEAST_ONE: Domain =
        Domain { lo: 1.0, lo_included: true, hi: f64::INFINITY, hi_included: false };
    /// 0 ≤ x < 90: an angle from the horizontal or vertical, in degrees.
    pub const ANGLE_DEG: Domain =
        Domain { lo: 0.0, lo_included: true, hi: 90.0, hi_included: false };

    pub fn contains(&self, x: f64) -> bool {
        let above = if self.lo_included { x >= self.lo } else { x > self.lo };
        let below = if self.hi_included { x <= self.hi } else { x < self.hi };
        x.is_finite() && above && below
    }

    /// The interval as text, e.g. `≥ 0`, `> 0`, `0 … 1`, `≥ 0 and < 1`.
    pub fn describe(&self) -> String {
        let lo = |x: f64| if x == 0.0 { "0".to_string() } else { x.to_string() };
        let lower = (self.lo > f64::NEG_INFINITY)
            .then(|| format!("{} {}", if self.lo_included { "≥" } else { ">" }, lo(self.lo)));
        let upper = (self.hi < f64::INFINITY)
            .then(|| format!("{} {}", if self.hi_included { "≤" } else { "<" }, lo(self.hi)));
        match (lower, upper) {
            (Some(l), Some(u)) => format!("{l} and {u}"),
            (Some(l), None) => l,
            (None, Some(u)) => u,
            (None, None) => "any finite number".into(),
        }
    }
}

#[derive(Debug, Clone, Copy)]
pub struct RuleMeta {
    /// Stable kebab-case id naming the problem.
    pub id: &'static str,
    pub group: &'static str,
    pub default_level: Severity,
    /// Name of the probe simulation that can confirm the rule's findings, if any: the
    /// [`crate::probe::Probe::NAME`] of the type named in `declare_rule!`, whose claims the
    /// rule's findings carry.
    pub probe: Option<&'static str>,
    /// Further probes whose measurements some of the rule's findings carry.
    pub also_probes: &'static [&'static str],
    pub options: &'static [RuleOption],
    /// Markdown from the rule's doc comment.
    pub docs: &'static str,
}

/// Everything a rule may read. Rules are pure: same context, same findings.
pub struct Context<'a> {
    pub robot: &'a Robot,
    pub spec: Option<&'a Spec>,
    pub sources: &'a SourceMap,
    pub options: BTreeMap<String, f64>,
    pub meta: &'static RuleMeta,
    pub level: Severity,
}

impl Context<'_> {
    /// A threshold: from `[rules.<id>]` in the config, else the rule's default.
    pub fn opt(&self, name: &str) -> f64 {
        if let Some(v) = self.options.get(name) {
            return *v;
        }
        self.meta.options.iter().find(|o| o.name == name).map(|o| o.default).unwrap_or(f64::NAN)
    }
    /// Starts a finding of this rule at its configured level.
    pub fn finding(&self, message: impl Into<String>, primary: Loc) -> Finding {
        Finding::new(self.meta.id, self.level, message, primary)
    }
    /// Finding on an attribute of a compiled object, pointing at the value that set it and, when
    /// inherited, labelling the `<default class>` it came from.
    pub fn at_attr(
        &self,
        kind: ElemKind,
        id: usize,
        name: &str,
        attr: &str,
        message: impl Into<String>,
    ) -> Finding {
        let (loc, class) = self.robot.attr_loc(kind, id, name, attr);
        let eloc = self.robot.elem_loc(kind, id, name);
        let mut f = self.finding(message, loc).element(self.element_label(kind, id, name), eloc);
        if let Some(c) = class {
            f = f.secondary(
                eloc,
                format!("{} inherits `{attr}` from <default class=\"{c}\">", kind_word(kind)),
            );
        }
        f
    }
    /// "joint `knee`"-style label of a finding's element; an unnamed geom by its number in its
    /// body, not by its id (which the geoms a scene file adds shift).
    fn element_label(&self, kind: ElemKind, id: usize, name: &str) -> String {
        if kind == ElemKind::Geom && name.is_empty() {
            format!("geom {}", self.robot.unnamed_geom(id))
        } else {
            format!("{} {}", kind_word(kind), display_name(name, id))
        }
    }
    pub fn at_elem(
        &self,
        kind: ElemKind,
        id: usize,
        name: &str,
        message: impl Into<String>,
    ) -> Finding {
        let eloc = self.robot.elem_loc(kind, id, name);
        self.finding(message, eloc).element(self.element_label(kind, id, name), eloc)
    }
    /// How a message names actuator `id`: `` `name` ``, or for an unnamed one its index and
    /// where the file writes it (`#3 (robot.xml:42)`).
    pub fn actuator_label(&self, id: usize) -> String {
        let name = self.robot.actuators.get(id).map(|a| a.name.as_str()).unwrap_or("");
        if !name.is_empty() {
            return format!("`{name}`");
        }
        let loc = self.robot.elem_loc(ElemKind::Actuator, id, "");
        match self.sources.files.get(loc.file) {
            Some(f) => {
                let file = f.path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default();
                format!("#{id} ({file}:{})", f.line_col(loc.start).0)
            }
            None => format!("#{id}"),
        }
    }
    /// Spec facts for a joint, if a spec is present and mentions it.
    pub fn facts(&self, joint: &str) -> Option<crate::spec::JointFacts> {
        self.spec.and_then(|s| s.joint(joint))
    }
}

/// Gives each of `findings` the claim `claim` makes for it (a finding it returns `None` for
/// keeps its own): how a rule names what its probe should check.
pub fn claim_each<C: crate::probe::Claim>(
    findings: &mut [Finding],
    claim: impl Fn(&Finding) -> Option<C>,
) {
    for f in findings {
        if f.fact {
            continue; // a fact carries a measurement, never a claim that could refute it
        }
        if let Some(c) = claim(f) {
            f.claim = Some(std::sync::Arc::new(crate::probe::AsClaim(c)));
        }
    }
}

/// Gives each of `findings` the measurement `measure` makes for it and marks it a fact of the
/// file: its probe measures the consequence and cannot refute it.
pub fn measure_each<M: crate::probe::Measure>(
    findings: &mut [Finding],
    measure: impl Fn(&Finding) -> Option<M>,
) {
    for f in findings {
        if let Some(m) = measure(f) {
            f.fact = true;
            f.claim = Some(std::sync::Arc::new(crate::probe::AsMeasure(m)));
        }
    }
}

/// Whether body `b` is `top` or lies beyond it in the kinematic tree (`top` 0: every body).
pub fn in_subtree(robot: &Robot, top: usize, mut b: usize) -> bool {
    for _ in 0..=robot.bodies.len() {
        if b == top {
            return true;
        }
        match robot.bodies.get(b) {
            Some(x) if b != 0 => b = x.parent,
            _ => return false,
        }
    }
    false
}

pub fn kind_word(kind: ElemKind) -> &'static str {
    match kind {
        ElemKind::Body => "body",
        ElemKind::Joint => "joint",
        ElemKind::Geom => "geom",
        ElemKind::Site => "site",
        ElemKind::Actuator => "actuator",
        ElemKind::Tendon => "tendon",
        ElemKind::Equality => "equality",
        ElemKind::Key => "key",
        ElemKind::Mesh => "mesh",
        ElemKind::Pair => "contact pair",
        ElemKind::Sensor => "sensor",
        ElemKind::Default => "default",
    }
}

pub fn display_name(name: &str, id: usize) -> String {
    if name.is_empty() { format!("#{id}") } else { name.to_string() }
}

pub trait Rule: Sync {
    fn meta(&self) -> &'static RuleMeta;
    fn check(&self, cx: &Context, out: &mut Vec<Finding>);
}

/// Declares a rule type whose doc comment is its documentation. `probe:` is `None` or the type
/// of the probe (a [`crate::probe::Probe`]) whose claims the rule's findings carry.
#[macro_export]
macro_rules! declare_rule {
    (@probe None) => { None };
    (@probe $probe:ident) => { Some(<$probe as $crate::probe::Probe>::NAME) };
    (
        $(#[doc = $doc:expr])*
        pub $name:ident {
            id: $id:expr,
            group: $group:expr,
            level: $lvl:expr,
            probe: $probe:ident,
            $(also: [$($also:ident),* $(,)?],)?
            options: [$($opt:expr),* $(,)?] $(,)?
        }
    ) => {
        $(#[doc = $doc])*
        pub struct $name;
        impl $name {
            pub const META: $crate::rules::RuleMeta = $crate::rules::RuleMeta {
                id: $id,
                group: $group,
                default_level: $lvl,
                probe: $crate::declare_rule!(@probe $probe),
                also_probes: &[$($(<$also as $crate::probe::Probe>::NAME),*)?],
                options: &[$($opt),*],
                docs: concat!($($doc, "\n"),*),
            };
        }
    };
}

/// Shorthand for a rule option whose values lie in `domain`.
pub const fn opt(
    name: &'static str,
    default: f64,
    unit: &'static str,
    domain: Domain,
    help: &'static str,
) -> RuleOption {
    RuleOption { name, default, unit, help, allowed: &[], domain }
}

/// Shorthand for a rule option that takes one of a few values (`allowed`).
pub const fn opt_one_of(
    name: &'static str,
    default: f64,
    unit: &'static str,
    help: &'static str,
    allowed: &'static [f64],
) -> RuleOption {
    RuleOption { name, default, unit, help, allowed, domain: Domain::ANY }
}

/// Every rule, in documentation order. Registering a rule is one line here.
pub fn registry() -> Vec<&'static dyn Rule> {
    vec![
        &mapping::actuator_mapping::ActuatorMapping,
        &mapping::missing_actuators::MissingActuators,
        &inertia::armature_mismatch::ArmatureMismatch,
        &inertia::parallel_ankle_armature::ParallelAnkleArmature,
        &control::drive_friction_mismatch::DriveFrictionMismatch,
        &inertia::zero_armature::ZeroArmature,
        &inertia::transmission_armature::TransmissionWithoutArmature,
        &inertia::legged_urdf_armature::LeggedUrdfArmature,
        &inertia::passive_joint_armature::PassiveJointArmature,
        &control::passive_joint_friction::PassiveJointFriction,
        &inertia::isotropic_base_inertia::IsotropicBaseInertia,
        &inertia::isotropic_link_inertia::IsotropicLinkInertia,
        &inertia::mass_budget::MassBudget,
        &inertia::repeated_class_mass::RepeatedClassMass,
        &inertia::inertial_overridden::InertialOverridden,
        &inertia::default_density_mass::DefaultDensityMass,
        &inertia::visual_geom_mass::VisualGeomMass,
        &inertia::copied_inertial::CopiedInertial,
        &inertia::inertia_exceeds_geometry::InertiaExceedsGeometry,
        &contact::toe_tilt::ToeTilt,
        &contact::foot_collision_geometry::FootCollisionGeometry,
        &contact::links_without_collision::LinksWithoutCollision,
        &contact::token_collision::TokenCollisionGeometry,
        &contact::welded_legged_base::WeldedLeggedBase,
        &contact::torsional_friction::TorsionalFriction,
        &contact::robot_never_collides::RobotNeverCollides,
        &contact::contact_margin::ContactMargin,
        &limits::soft_limits::SoftLimits,
        &control::underdamped_pd_gains::UnderdampedPdGains,
        &control::servo_stall_band::ServoStallBand,
        &control::servo_sag::ServoSag,
        &control::spring_overpowers_actuator::SpringOverpowersActuator,
        &limits::effort_limit_mismatch::EffortLimitMismatch,
        &limits::placeholder_joint_limits::PlaceholderJointLimits,
        &limits::wheel_spring::WheelSpring,
        &mapping::passive_joint_spring::PassiveJointSpring,
        &mapping::free_passive_joint::FreePassiveJoint,
        &mapping::detached_limb::DetachedLimb,
        &control::gains_unstable_for_timestep::GainsUnstableForTimestep,
        &control::solref_below_timestep::SolrefBelowTimestep,
        &control::solimp_out_of_range::SolimpOutOfRange,
        &control::non_earth_gravity::NonEarthGravity,
        &geometry::mirror_asymmetry::MirrorAsymmetry,
        &geometry::root_frame::RootFrameConvention,
        &control::missing_action_delay::MissingActionDelay,
        &control::keyframe_motor_ctrl::KeyframeMotorCtrl,
        &control::keyframe_servo_ctrl::KeyframeServoCtrl,
        &control::keyframe_state::KeyframeState,
        &geometry::self_collision_at_keyframe::SelfCollisionAtKeyframe,
        &geometry::collision_visual_mismatch::CollisionVisualMismatch,
        &geometry::oversized_collision::OversizedCollisionPrimitive,
        &geometry::visual_mesh_collision::VisualMeshCollision,
        &geometry::mesh_scale::MeshScale,
        &geometry::robot_scale::RobotScale,
        &mapping::urdf_mjcf_drift::UrdfMjcfDrift,
        &limits::ctrlrange_in_degrees::CtrlrangeInDegrees,
        &limits::range_in_radians::RangeInRadians,
        &mapping::sensor_quantity::SensorQuantity,
        &mapping::touch_sensor_site::TouchSensorSite,
    ]
}

/// Engine-level diagnostics that are not model rules but still have ids and docs.
pub mod meta_rules {
    use super::*;
    declare_rule! {
        /// ## What it does
        /// Reports a `<!-- modellint: ignore[<id>] reason -->` comment that suppressed nothing.
        ///
        /// ## Why is this bad?
        /// A stale suppression hides the next real finding on that element and tells readers a
        /// problem exists where none does.
        ///
        /// ## How it is confirmed
        /// Static: the engine records which suppressions matched a finding in this run.
        ///
        /// ## How to fix
        /// Delete the comment, or correct the rule id it names.
        pub UnusedSuppression { id: "unused-suppression", group: "engine", level: Severity::Warning, probe: None, options: [] }
    }
    declare_rule! {
        /// ## What it does
        /// Reports a malformed `modellint:` comment: an unknown directive, a missing reason, or an
        /// unknown rule id.
        ///
        /// ## Why is this bad?
        /// A suppression must say why the finding does not apply; one without a reason cannot be
        /// reviewed, and one with a misspelled id silently suppresses nothing.
        ///
        /// ## How it is confirmed
        /// Static: parsed from the XML comments directly before each element.
        ///
        /// ## How to fix
        /// Write `<!-- modellint: ignore[<rule-id>] <why this is fine> -->` directly before the
        /// element.
        pub InvalidSuppression { id: "invalid-suppression", group: "engine", level: Severity::Error, probe: None, options: [] }
    }
    pub fn all() -> Vec<&'static RuleMeta> {
        vec![
            &UnusedSuppression::META,
            &InvalidSuppression::META,
            &control::unstable_simulation::UnstableSimulation::META,
            &crate::lint::TrailingXmlContent::META,
            &crate::lint::UndeclaredXmlPrefix::META,
        ]
    }
}

/// All rule metadata: model rules then engine rules.
pub fn all_meta() -> Vec<&'static RuleMeta> {
    let mut v: Vec<&'static RuleMeta> = registry().into_iter().map(|r| r.meta()).collect();
    v.extend(meta_rules::all());
    v
}

pub fn find_meta(id: &str) -> Option<&'static RuleMeta> {
    all_meta().into_iter().find(|m| m.id == id)
}

/// Render a rule's documentation page (the source of `docs/rules/<id>.md`).
pub fn doc_page(m: &RuleMeta) -> String {
    let mut s = format!("# `{}`\n\n", m.id);
    s.push_str(&format!(
        "Group: `{}` · default level: `{}` · probe: {}\n\n",
        m.group,
        m.default_level.as_str(),
        match m.probe {
            Some(p) => std::iter::once(p)
                .chain(m.also_probes.iter().copied())
                .map(|p| format!("`{p}`"))
                .collect::<Vec<_>>()
                .join(", "),
            None => "none (static only)".into(),
        }
    ));
    // Doc comments arrive with one leading space per line.
    for line in m.docs.lines() {
        s.push_str(line.strip_prefix(' ').unwrap_or(line));
        s.push('\n');
    }
    if !m.options.is_empty() {
        s.push_str("\n## Options\n\nSet in `modellint.toml` under `[rules.");
        s.push_str(m.id);
        s.push_str(
            "]`.\n\n| option | default | unit | values | meaning |\n|---|---|---|---|---|\n",
        );
        for o in m.options {
            let values = if o.allowed.is_empty() {
                o.domain.describe()
            } else {
                let v: Vec<String> = o.allowed.iter().map(|a| a.to_string()).collect();
                format!("one of {}", v.join(", "))
            };
            s.push_str(&format!(
                "| `{}` | {} | {} | {} | {} |\n",
                o.name, o.default, o.unit, values, o.help
            ));
        }
    }
    s
}

/// `modellint gen-docs`: write (or with `check`, compare) one page per rule under `out`.
pub fn gen_docs(out: &std::path::Path, check: bool) -> i32 {
    let mut stale = Vec::new();
    for m in all_meta() {
        let path = out.join(format!("{}.md", m.id));
        let body = format!(
            "<!-- generated by `modellint gen-docs` from src/rules; do not edit -->\n{}",
            doc_page(m)
        );
        if check {
            if std::fs::read_to_string(&path).ok().as_deref() != Some(body.as_str()) {
                stale.push(path.display().to_string());
            }
        } else if let Err(e) =
            std::fs::create_dir_all(out).and_then(|_| std::fs::write(&path, body))
        {
            eprintln!("modellint: cannot write {}: {e}", path.display());
            return 2;
        }
    }
    if !stale.is_empty() {
        eprintln!("modellint: stale rule docs (run `modellint gen-docs`): {}", stale.join(", "));
        return 1;
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every option's default lies in its domain (or its allowed values): a default the config
    /// check would reject would be a rule configured against its own meaning.
    #[test]
    fn option_defaults_lie_in_their_domains() {
        for m in all_meta() {
            for o in m.options {
                let ok = if o.allowed.is_empty() {
                    o.domain.contains(o.default)
                } else {
                    o.allowed.contains(&o.default)
                };
                assert!(
                    ok,
                    "rule {} option {} default {} outside {}",
                    m.id,
                    o.name,
                    o.default,
                    o.domain.describe()
                );
            }
        }
    }

    #[test]
    fn domains_include_and_exclude_their_ends() {
        assert!(Domain::NON_NEGATIVE.contains(0.0) && !Domain::NON_NEGATIVE.contains(-1e-9));
        assert!(!Domain::POSITIVE.contains(0.0) && Domain::POSITIVE.contains(1e-9));
        assert!(Domain::FRACTION.contains(1.0) && !Domain::FRACTION_BELOW_ONE.contains(1.0));
        assert!(!Domain::AT_LEAST_ONE.contains(0.99) && Domain::AT_LEAST_ONE.contains(1.0));
        assert!(!Domain::ANY.contains(f64::NAN) && !Domain::POSITIVE.contains(f64::INFINITY));
        assert_eq!(Domain::FRACTION_BELOW_ONE.describe(), "≥ 0 and < 1");
        assert_eq!(Domain::POSITIVE.describe(), "> 0");
    }
}
