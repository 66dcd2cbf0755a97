//! Effects: pieces of physics a model may be missing, each with named, bounded parameters and a
//! way into the simulation — an edit of the compiled model copy (MuJoCo-native), a per-physics-
//! step torque/command hook ([`ActuatorHook`]), or a measurement transform (sensor bias).
//!
//! One effect, one file: each `src/fit/effects/<id>.rs` declares its effect with
//! [`declare_effect!`](crate::declare_effect) — the doc comment is its documentation (the tables
//! of docs/fitting.md and `modellint fit --help` are generated from it, see [`docs`]) and the
//! parameters are its table — and implements [`Effect`]: how it enters the simulation, its
//! residual signature for the diagnosis, its write-back and its Isaac Lab / mjlab snippet.
//! Adding an effect is that file, one line in the `registry!` below and its tests.
//!
//! [`simulate`] replays recordings with any set of [`Applied`] effects; the fit engine
//! ([`crate::fit::select`]) and `modellint synth`-style data generation use the same machinery.

use std::collections::{BTreeMap, VecDeque};

use mujoco_rs::prelude::*;
use rayon::prelude::*;

use crate::fit::diagnose::{Samples, Signature};
use crate::model::{ActuatorKind, Robot, mj};
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::{
    ActuatorHook, Episode, ReplayError, ReplayOptions, Replayer, StepIo,
};

pub mod docs;
pub mod held;
pub mod inertial;
mod probe;
mod target;
pub mod unmoved;
pub use probe::{PROBE_STEP, probe_step};
pub use target::{JointTarget, bounds_for_drive};
pub use unmoved::{Seen, Unmoved};

/// The effect registry: one `module::Type` per effect, in the fit engine's preference order
/// (simpler first). Declares each module and [`all`].
macro_rules! registry {
    ($($module:ident::$effect:ident),* $(,)?) => {
        $(mod $module;)*
        $(pub use $module::$effect;)*

        /// Every effect, in the fit engine's preference order (simpler first).
        pub fn all() -> Vec<&'static dyn Effect> {
            vec![$(&$module::$effect),*]
        }
    };
}

// Registering an effect is one line here.
registry![
    action_delay::ActionDelay,
    coulomb_friction::CoulombFriction,
    viscous_damping::ViscousDamping,
    armature::Armature,
    position_offset::PositionOffset,
    gain_error::GainError,
    stribeck_friction::StribeckFriction,
    torque_limit::TorqueLimit,
    backlash::Backlash,
    joint_stiffness::JointStiffness,
    load_dependent_friction::LoadDependentFriction,
    external_load_friction::ExternalLoadFriction,
    torque_off_braking::TorqueOffBraking,
    motor_constants::MotorConstants,
    link_mass::LinkMass,
    com_offset::ComOffset,
    link_inertia::LinkInertia,
    ground_contact::GroundContact,
];

/// One fitted parameter: name, unit, bounds and default (the value meaning "effect absent"
/// where there is one).
#[derive(Debug, Clone, Copy)]
pub struct ParamDef {
    pub name: &'static str,
    pub unit: &'static str,
    pub lo: f64,
    pub hi: f64,
    pub default: f64,
}

/// Where a fitted value goes when written back.
#[derive(Debug, Clone, PartialEq)]
pub enum WriteBack {
    /// MJCF attributes on the `<joint>` element: (attribute, value).
    Joint(Vec<(&'static str, f64)>),
    /// MJCF attributes on the joint's `<actuator>` element(s): (attribute, value).
    Actuator(Vec<(&'static str, f64)>),
    /// MuJoCo cannot express it: written to the actuator TOML only.
    TomlOnly,
    /// The joint's child body's `<inertial>`, from the model copy with every kept effect.
    Inertial,
    /// The joint's child body's ground-touching `<geom>`s (`solref`, `priority`, `solimp`,
    /// `friction`, `condim`), from the model copy with every kept effect.
    Geoms,
}

/// Per-joint, per-episode state of a hook effect (reset at every episode start).
#[derive(Debug, Clone, Default)]
pub struct EffectState {
    pub fifo: VecDeque<f64>,
    pub s: [f64; 4],
    pub started: bool,
}

/// What a hook effect sees at one physics step of one joint ([`Effect::torque`]).
pub struct HookCtx<'a> {
    /// The effect's own state on this joint (delay line, values set by [`Effect::start`]).
    pub st: &'a mut EffectState,
    /// Joint position and velocity before the step.
    pub q: f64,
    pub qd: f64,
    /// The recorded command of this step (before any command effect).
    pub q_target: f64,
    /// The servo's inputs and what the effect may change (`ctrl`, `tau`).
    pub io: &'a mut StepIo,
    /// Physics time step [s].
    pub dt: f64,
    /// The effect's full parameter vector.
    pub p: &'a [f64],
}

/// How an effect enters the simulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Entry {
    /// Edits the compiled model copy.
    Model,
    /// Rewrites the command the servo sees (runs before torque hooks).
    Command,
    /// Adds joint torque every physics step.
    Torque,
    /// Transforms the simulated measurement (sensor effects).
    Measurement,
}

/// What [`declare_effect!`](crate::declare_effect) declares: the effect's id, how it enters the
/// simulation, its parameters and its documentation.
#[derive(Debug, Clone, Copy)]
pub struct EffectMeta {
    /// Stable snake_case id (`--effects`, JSON, TOML).
    pub id: &'static str,
    pub entry: Entry,
    pub params: &'static [ParamDef],
    /// Markdown from the effect's doc comment: a one-paragraph summary, a description, and the
    /// sections [`docs::SECTIONS`] names.
    pub docs: &'static str,
}

/// Implemented by [`declare_effect!`](crate::declare_effect): the declared metadata.
pub trait Declared {
    fn meta(&self) -> &'static EffectMeta;
}

/// Declares an effect type whose doc comment is its documentation (see [`docs::SECTIONS`]) and
/// whose parameters are listed here; the file then implements [`Effect`] for it.
#[macro_export]
macro_rules! declare_effect {
    (
        $(#[doc = $doc:expr])*
        pub $name:ident {
            id: $id:expr,
            entry: $entry:ident,
            params: [$($param:expr),* $(,)?] $(,)?
        }
    ) => {
        $(#[doc = $doc])*
        pub struct $name;
        impl $name {
            pub const META: $crate::fit::effects::EffectMeta = $crate::fit::effects::EffectMeta {
                id: $id,
                entry: $crate::fit::effects::Entry::$entry,
                params: &[$($param),*],
                docs: concat!($($doc, "\n"),*),
            };
        }
        impl $crate::fit::effects::Declared for $name {
            fn meta(&self) -> &'static $crate::fit::effects::EffectMeta {
                &Self::META
            }
        }
    };
}

/// Where a joint's actuator element is, for [`Effect::actuator_attr`].
#[derive(Debug, Clone, Copy)]
pub struct ActuatorSite<'a> {
    /// Tag of the MJCF element (`position`, `motor`, `general`, …).
    pub tag: &'a str,
    /// The compiled actuator (`None` when it is not in the model).
    pub kind: Option<ActuatorKind>,
    /// The model's physics time step [s].
    pub timestep: f64,
    /// The compiled actuator's gear (1 when it is not in the model) and its force range when
    /// it is force-limited.
    pub gear: f64,
    pub forcerange: Option<[f64; 2]>,
}

/// What an effect contributes to a joint's Isaac Lab / mjlab `ImplicitActuatorCfg`.
#[derive(Debug, Clone, PartialEq)]
pub enum IsaacLab {
    /// A field line (`armature=0.1,  # kg·m²`).
    Field(String),
    /// A comment line (`# …`): a value the configuration has no field for.
    Comment(String),
}

pub trait Effect: Declared + Sync {
    fn id(&self) -> &'static str {
        self.meta().id
    }
    fn params(&self) -> &'static [ParamDef] {
        self.meta().params
    }
    fn entry(&self) -> Entry {
        self.meta().entry
    }
    /// Start point of a fit: the model's current value for MuJoCo-native parameters, else the
    /// defaults.
    fn initial(&self, _m: &MjModel, _t: &JointTarget) -> Vec<f64> {
        self.params().iter().map(|p| p.default).collect()
    }
    /// Bounds of a fit (defaults from [`ParamDef`]; native parameters widen them around the
    /// model's value).
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        let _ = (m, t);
        (self.params().iter().map(|p| p.lo).collect(), self.params().iter().map(|p| p.hi).collect())
    }
    /// MuJoCo-native effects (and the native part of a hook effect): write `p` into the model
    /// copy.
    fn apply_model(&self, _m: &mut MjModel, _t: &JointTarget, _p: &[f64]) {}
    /// Hook effects: called every physics step before `mj_step`; may change `io.ctrl` (command
    /// effects) or add to `io.tau` (torque effects).
    fn torque(&self, _cx: HookCtx<'_>) {}
    /// Measurement effects: sensor reading minus true position.
    fn measurement_bias(&self, _p: &[f64]) -> f64 {
        0.0
    }
    /// Number of parameters that are actually fitted (the first `n`); the rest stay at default.
    fn fitted(&self) -> usize {
        self.params().len()
    }
    /// `true` when the simulated trajectory depends smoothly on the parameters, so that a
    /// Levenberg–Marquardt step on a finite-difference rollout Jacobian converges in a few
    /// iterations (how `mujoco.sysid` fits); `false` (the default) for kinks and dead zones
    /// (backlash, saturation, Stribeck's curve), fitted by derivative-free search.
    fn smooth(&self) -> bool {
        false
    }
    /// `true` when the one fitted parameter is searched on a log scale (the line search's
    /// grid and Brent steps on ln p): a scale spanning decades whose optimum is narrow, such as a torque
    /// limit. Only for one-parameter derivative-free fits, and only with a positive lower bound.
    fn log_search(&self) -> bool {
        false
    }
    /// `true` when the effect at its start ([`Effect::initial`]) changes nothing: the model
    /// with it replays exactly (bit for bit) as the model without it — a MuJoCo-native
    /// parameter written back at the model's own value, a zero delay, offset or added mass, a
    /// gain scale of one. A fit's first point is then the base model's replay, which the search
    /// holds already. `false` (the default) when the start acts (a play of zero width is still
    /// a motor behind a gear spring; friction variants start at a guess).
    fn neutral_start(&self) -> bool {
        false
    }
    /// [`Effect::neutral_start`] on the joint `t` of the model `m`: an effect whose start acts
    /// on some models only (a spring of zero stiffness pulls nowhere, wherever its reference
    /// is put) says so here.
    fn neutral_at(&self, _m: &MjModel, _t: &JointTarget) -> bool {
        self.neutral_start()
    }
    /// `true` for the friction models (Coulomb, Stribeck, load-dependent): alternative
    /// descriptions of one loss, never a pair that only makes sense together.
    fn friction(&self) -> bool {
        false
    }
    /// The plain model this one elaborates, when both describe the same loss (Coulomb
    /// friction for the load- or velocity-shaped friction models): beside it on the same
    /// joints the two split one loss in two, and the search prefers the plain one alone.
    /// `None` (the default): this effect is plain, or elaborates none.
    fn plain_variant(&self) -> Option<&'static dyn Effect> {
        None
    }
    /// `true` when a joint with this effect can stay where it starts for as long as it sticks
    /// (dry friction, a dead band): a start error does not die out as it does on the smooth
    /// model, so the start estimate leaves the joint alone (`fit --start-estimate`). Default:
    /// the friction models.
    fn holds_start(&self) -> bool {
        self.friction()
    }
    /// This effect's parameters when it also takes over what `other`, kept on the same joints,
    /// contributes: `mine` are this effect's parameters, `delta` the change `other`'s parameters
    /// make from their start values (for a MuJoCo-native parameter, the model's own value).
    /// `None` (the default): `other` is not a special case of this effect. Example: Coulomb
    /// friction c next to Stribeck friction (Fs, Fd, v_s) is Stribeck friction
    /// (Fs + c, Fd + c, v_s).
    fn absorb(&self, other: &dyn Effect, mine: &[f64], delta: &[f64]) -> Option<Vec<f64>> {
        let _ = (other, mine, delta);
        None
    }
    /// A simpler effect that is a special case of this one (through [`Effect::absorb`]): a fit
    /// of this effect also starts from that effect's fit on the same joints when that start is
    /// better than [`Effect::initial`]. Stribeck friction starts from a Coulomb fit: from its
    /// fixed defaults the simplex settled on a breakaway step just above the sign's smoothing
    /// velocity (v_s 0.010, static 3.6 N·m for 2.0 on a stiff knee servo, training RMSE 4.8×
    /// the truth's). `None` (the default): only `initial`.
    fn nests(&self) -> Option<&'static str> {
        None
    }
    /// Further starts derived from the [`Effect::nests`] start, for an effect whose error
    /// surface has more than one basin along a ridge the simplex does not cross. When one of
    /// them is better than the start, the fit also runs from the best of them and keeps the
    /// lower training error. Empty (the default): none.
    fn nested_alternatives(&self, _start: &[f64]) -> Vec<Vec<f64>> {
        vec![]
    }
    /// Whether the replay is bit for bit the same at any `p[i]`, the rest held. Default: no.
    fn idle(&self, _p: &[f64], _i: usize) -> bool {
        false
    }
    /// The diagnosis: this effect's signature feature, computed from one joint's samples (the
    /// residual is least-squares fitted on it, see [`crate::fit::diagnose`]).
    fn signature(&self, s: &Samples) -> Signature;
    /// Keys of the diagnosis evidence the text output of `modellint fit` shows for this effect
    /// (after `corr` and `explained_share`).
    fn shown_evidence(&self) -> &'static [&'static str] {
        &[]
    }
    /// The first parameter's values for the diagnosis's linearised re-ranking: one probe
    /// simulation at each value, from `start` within `[lo, hi]`; the one that explains the
    /// residual best ranks the candidate. Empty: no probe. Default: a step of 5 % of the range
    /// (down when up would leave the bounds).
    fn probes(&self, start: f64, lo: f64, hi: f64, evidence: &BTreeMap<String, f64>) -> Vec<f64> {
        let _ = evidence;
        vec![probe_step(start, lo, hi)]
    }
    /// How many of the fitted parameters (the first ones) the diagnosis's linearised re-ranking
    /// probes, each giving a sensitivity column of its own: the candidate is scored by the best
    /// linear combination of its columns ([`crate::fit::select`]'s screen), so an effect whose
    /// parameters are directions of equal standing (a centre of mass moved along or across a
    /// link) is not ranked by whichever direction happens to come first. The first parameter
    /// is probed at [`Effect::probes`], the others at [`probe_step`]. Default: 1.
    fn screened(&self) -> usize {
        1
    }
    /// How many of the fitted parameters (the first ones, at least [`Effect::screened`]) the
    /// screen probes for the linear step a coarse fit starts from; only the first
    /// [`Effect::screened`] columns rank the candidate and predict its gain. When every fitted
    /// parameter is probed, a smooth candidate's coarse fit is that step replayed once where it
    /// confirms its gain ([`crate::fit::select`]'s `coarse::confirmed_step`). Default:
    /// [`Effect::screened`].
    fn stepped(&self) -> usize {
        self.screened()
    }
    fn write_back(&self, p: &[f64]) -> WriteBack;
    /// One `(attribute, value)` of [`WriteBack::Actuator`] as MJCF attributes (name, text) on the
    /// actuator element `act`, or why it cannot be written there. Default: the attribute as is.
    fn actuator_attr(
        &self,
        attr: &'static str,
        v: f64,
        act: &ActuatorSite,
    ) -> Result<Vec<(&'static str, String)>, String> {
        let _ = act;
        Ok(vec![(attr, num(v))])
    }
    /// The line this effect adds to a joint's Isaac Lab / mjlab actuator configuration, from the
    /// fitted parameters by name. Default: a comment with the parameters.
    fn isaaclab(&self, params: &BTreeMap<String, f64>, timestep: f64) -> IsaacLab {
        let _ = timestep;
        IsaacLab::Comment(format!(
            "# {}: {}",
            self.id(),
            params.iter().map(|(k, v)| format!("{k} = {}", num(*v))).collect::<Vec<_>>().join(", ")
        ))
    }
    /// Whether the effect can act on these recordings at all (e.g. torque-off braking needs a
    /// torque-off interval, a supply clip needs the supply voltage); the fit leaves it out of
    /// the candidates otherwise.
    fn applies(&self, _recs: &[Recording]) -> bool {
        true
    }
    /// Hook effects: called once per episode and joint before the first step with the
    /// recording's metadata (e.g. a supply voltage the effect needs), to fill `st`.
    fn start(&self, _st: &mut EffectState, _meta: &BTreeMap<String, String>, _p: &[f64]) {}
    /// Order of the hook effects within a step: command effects (0) run first, then torque
    /// effects (1); an effect that needs every other torque of the step (implicit friction,
    /// stage 2) runs last.
    fn stage(&self) -> u8 {
        if self.entry() == Entry::Command { 0 } else { 1 }
    }
    /// `false` for an effect tried only when named (`--effects`, `--told`). Default: `true`.
    fn by_default(&self) -> bool {
        true
    }
    /// What each parameter is measured from, where its name and unit do not say it (a body
    /// effect's place: from the modelled centre of mass; its mass: added to the model's): (name,
    /// meaning), shown beside the values in the text and the JSON. Default: none.
    fn param_meaning(&self) -> &'static [(&'static str, &'static str)] {
        &[]
    }
    /// Whether this effect is a candidate on `t` at all: `false` where another candidate is the
    /// same change (a link only its own joint moves: its inertia is that joint's armature).
    fn acts_on(&self, _t: &JointTarget) -> bool {
        true
    }
    /// Whether the effect changes the motion first at the joints it is fitted on — a torque, a
    /// transmission, a command or a reading of those joints — so that where their residual is
    /// at its floor it has nothing of its own left to explain there (the search's joint floor,
    /// `fit::select::joint_floor`). Default `true`; `false` for the body effects, whose mass
    /// every joint between the body and the base carries (a trunk's mass above the hip's axis
    /// loads the knee and the ankle, not the hip), and for the ground contact.
    fn joint_local(&self) -> bool {
        true
    }
    /// Why moving parameter `j` from `start` to `v` on `t` leaves a replay of `m` as it was, to
    /// the last bit, given what the base replay reached on the joint (`seen`); `None` (the
    /// default) when it may change it. The screen does not replay such a probe ([`unmoved`]).
    fn unmoved(
        &self,
        m: &MjModel,
        t: &JointTarget,
        start: &[f64],
        jv: (usize, f64),
        seen: Seen,
    ) -> Option<Unmoved> {
        let _ = (m, t, start, jv, seen);
        None
    }
    /// Whether [`Effect::unmoved`] reads `seen` (the base replay's peaks, `select::at_base`).
    fn unmoved_reads_peaks(&self) -> bool {
        false
    }
    /// Whether one parameter vector means the same thing on targets `a` and `b`, so that the
    /// two may share it in a group (mirror links, every leg). Default: the effect acts on both
    /// ([`Effect::acts_on`]: a servo's gain error is not shared with the passive joint an
    /// equality couples to it); the body effects need alike bodies
    /// ([`inertial::BodyAxes::alike`]).
    fn alike(&self, a: &JointTarget, b: &JointTarget) -> bool {
        self.acts_on(a) && self.acts_on(b)
    }
    /// The components a change of the ground contact may stand in for, each as (its parameter's
    /// index, this effect with that parameter held at its nominal value: [`held::Held`]) — a
    /// body's place along and across its link moves gravity's moment, as a softer floor does
    /// under the feet. The floor's rival ([`crate::fit::floor_rival`]) fits each variant beside
    /// a ground contact to ask whether the component is identified apart from the floor.
    /// Default: none.
    fn held_components(&self) -> Vec<(usize, &'static dyn Effect)> {
        vec![]
    }
}

/// A value as MJCF / TOML / Python text: 6 decimals, trailing zeros trimmed, no `-0`.
pub fn num(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s.is_empty() || s == "-0" { "0".into() } else { s }
}

/// A fitted parameter by name (`NaN` when absent), for [`Effect::isaaclab`].
pub fn named(params: &BTreeMap<String, f64>, name: &str) -> f64 {
    params.get(name).copied().unwrap_or(f64::NAN)
}

/// The effect `id`: a registered one, or one's [`Effect::held_components`] variant
/// (`EFFECT~PARAMETER`).
pub fn by_id(id: &str) -> Option<&'static dyn Effect> {
    let all = all();
    if let Some(e) = all.iter().find(|e| e.id() == id) {
        return Some(*e);
    }
    let (base, _) = id.split_once('~')?;
    let e = all.into_iter().find(|e| e.id() == base)?;
    e.held_components().into_iter().map(|(_, h)| h).find(|h| h.id() == id)
}

/// Whether `effect` may share one parameter vector over the joints of `group` (a mirror pair,
/// every leg, a merge of two kept groups): each joint a target and [`Effect::alike`] for each
/// two of them — a body effect needs alike links, a joint effect groups any joints.
pub fn alike_over(robot: &Robot, effect: &dyn Effect, group: &[String]) -> bool {
    let t: Vec<JointTarget> = group.iter().filter_map(|j| JointTarget::of(robot, j)).collect();
    t.len() == group.len()
        && t.iter().enumerate().all(|(i, a)| t[i + 1..].iter().all(|b| effect.alike(a, b)))
}

/// Pairs of effects that mimic each other alone but not together: a servo gain error and a
/// delay both shift the phase; friction and inertia both slow the response; a dead band and an
/// offset both bias it; damping and inertia both change the decay. The fit tries them jointly
/// when no single effect passes ([`crate::fit::select`]), in this order (which decides ties and
/// the order of the `tried` log).
pub fn mimicking_pairs() -> Vec<(&'static dyn Effect, &'static dyn Effect)> {
    vec![
        (&gain_error::GainError, &action_delay::ActionDelay),
        (&coulomb_friction::CoulombFriction, &armature::Armature),
        (&stribeck_friction::StribeckFriction, &armature::Armature),
        (&backlash::Backlash, &position_offset::PositionOffset),
        (&viscous_damping::ViscousDamping, &armature::Armature),
        (&gain_error::GainError, &coulomb_friction::CoulombFriction),
    ]
}

/// An effect with parameters on a set of joints (a joint group shares one parameter vector).
#[derive(Clone)]
pub struct Applied {
    pub effect: &'static dyn Effect,
    pub joints: Vec<String>,
    pub params: Vec<f64>,
}

impl Applied {
    /// The parameter vector, padded with the effect's defaults when shorter than the effect's
    /// parameter list (a caller may give only the fitted ones), so that no effect indexes past it.
    pub fn full_params(&self) -> std::borrow::Cow<'_, [f64]> {
        let defs = self.effect.params();
        if self.params.len() >= defs.len() {
            std::borrow::Cow::Borrowed(&self.params)
        } else {
            let mut p = self.params.clone();
            p.extend(defs[self.params.len()..].iter().map(|d| d.default));
            std::borrow::Cow::Owned(p)
        }
    }
}

impl std::fmt::Debug for Applied {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}{:?}={:?}", self.effect.id(), self.joints, self.params)
    }
}

/// Smooth sign used by friction hooks (ε in rad/s).
pub fn smooth_sign(v: f64, eps: f64) -> f64 {
    (v / eps).tanh()
}

/// Servo torque the position actuator produces for this step's io, clamped to its force range
/// as MuJoCo clamps it (`StepIo::servo_range`).
pub fn servo_torque(q: f64, qd: f64, io: &StepIo) -> f64 {
    if !io.enabled {
        return 0.0;
    }
    let tau = io.kp * (io.acting_ctrl() - q) - io.kd * qd;
    match io.servo_range {
        Some((lo, hi)) if lo <= hi => tau.clamp(lo, hi),
        _ => tau,
    }
}

/// A copy of `robot.mj` with the MuJoCo-native effects of `applied` written in (and the
/// MuJoCo-native part of a hook effect, such as a torque limit's force clamp).
pub fn model_with(robot: &Robot, applied: &[Applied]) -> MjModel {
    let mut m = robot.mj.clone();
    for a in applied {
        for name in &a.joints {
            if let Some(t) = JointTarget::of(robot, name) {
                a.effect.apply_model(&mut m, &t, &a.full_params());
            }
        }
    }
    m
}

struct Hook<'a> {
    applied: &'a [Applied],
    /// The episode's recording metadata (for [`Effect::start`]).
    meta: &'a BTreeMap<String, String>,
    /// Per recorded joint: (index into `applied`, state), command effects first.
    lists: Vec<Vec<(usize, EffectState)>>,
    dt: f64,
}

impl ActuatorHook for Hook<'_> {
    fn reset(&mut self, joints: &[String], dt: f64) {
        self.dt = dt;
        self.lists = joints
            .iter()
            .map(|n| {
                let mut v: Vec<(usize, EffectState)> = self
                    .applied
                    .iter()
                    .enumerate()
                    .filter(|(_, a)| {
                        matches!(a.effect.entry(), Entry::Command | Entry::Torque)
                            && a.joints.iter().any(|j| j == n)
                    })
                    .map(|(i, a)| {
                        let mut st = EffectState::default();
                        a.effect.start(&mut st, self.meta, &a.full_params());
                        (i, st)
                    })
                    .collect();
                v.sort_by_key(|(i, _)| self.applied[*i].effect.stage());
                v
            })
            .collect();
    }
    fn before_step(
        &mut self,
        _t: f64,
        joint_idx: usize,
        q: f64,
        qd: f64,
        q_target: f64,
        out: &mut StepIo,
    ) {
        let Some(list) = self.lists.get_mut(joint_idx) else { return };
        for (i, st) in list.iter_mut() {
            let a = &self.applied[*i];
            let p = a.full_params();
            a.effect.torque(HookCtx { st, q, qd, q_target, io: out, dt: self.dt, p: &p });
        }
    }
}

/// Replays `rec` on `model` (a copy made by [`model_with`]) with the hook and measurement effects
/// of `applied`.
pub fn replay_with(
    robot: &Robot,
    model: &MjModel,
    rec: &Recording,
    applied: &[Applied],
    opts: &ReplayOptions,
) -> Result<Episode, ReplayError> {
    let replayer = Replayer::with_model(robot, model);
    let bias: Vec<f64> = rec
        .joints
        .iter()
        .map(|j| {
            applied
                .iter()
                .filter(|a| a.effect.entry() == Entry::Measurement && a.joints.contains(&j.name))
                .map(|a| a.effect.measurement_bias(&a.full_params()))
                .sum()
        })
        .collect();
    let has_bias = bias.iter().any(|&b| b != 0.0);
    let shifted;
    let rec_in = if has_bias {
        // The sensor reads true + bias: start the true joint at reading − bias.
        let mut r = rec.clone();
        for (j, b) in r.joints.iter_mut().zip(&bias) {
            if let Some(q0) = j.q.first_mut() {
                *q0 -= b;
            }
        }
        shifted = r;
        &shifted
    } else {
        rec
    };
    let hooked = applied.iter().any(|a| matches!(a.effect.entry(), Entry::Command | Entry::Torque));
    let mut ep = if hooked {
        let mut h = Hook { applied, meta: &rec.meta, lists: vec![], dt: 0.0 };
        replayer.replay(rec_in, opts, Some(&mut h))?
    } else {
        replayer.replay(rec_in, opts, None)?
    };
    if has_bias {
        for (q, b) in ep.q_sim.iter_mut().zip(&bias) {
            q.iter_mut().for_each(|x| *x += b);
        }
    }
    Ok(ep)
}

/// Replays every recording (in parallel) with `applied` effects.
pub fn simulate(
    robot: &Robot,
    recs: &[Recording],
    applied: &[Applied],
    opts: &ReplayOptions,
) -> Vec<Result<Episode, ReplayError>> {
    let m = model_with(robot, applied);
    recs.par_iter().map(|r| replay_with(robot, &m, r, applied, opts)).collect()
}

/// Writes `v` into entry `i` of a model array (nothing when out of range).
pub(crate) fn set(a: &mut [f64], i: usize, v: f64) {
    if let Some(x) = a.get_mut(i) {
        *x = v;
    }
}

/// Entry `i` of a model array (0 when out of range).
pub(crate) fn get(a: &[f64], i: usize) -> f64 {
    a.get(i).copied().unwrap_or(0.0)
}

#[cfg(test)]
mod testkit;
#[cfg(test)]
pub(crate) use testkit::{hinge_recording, hinge_robot};

#[cfg(test)]
mod tests;
