//! Concealed-effect benchmark core, shared by `examples/conceal_bench.rs` and `tests/conceal.rs`
//! (included with `#[path]`).
//!
//! One case = hidden truth (effects with parameters on joints) → recordings made by the
//! independent synth (`modellint::synth`: its own MuJoCo loop, 100 Hz controller, asynchronous
//! 88 Hz recorder logging the command in force, settle, noise, optional 12-bit quantisation,
//! drops), written to CSV and read back with the recording reader `fit` uses → `select::fit` on
//! the model that lacks the effects (the fit never sees the truth) → score against the truth:
//! precision/recall by (effect, joint), parameter error (relative; action_delay absolute in
//! physics steps), and position MAE on FRESH held-out episodes (never given to the fit) before
//! and after adding the fitted effects. The floor is the synth's own noise-free true reading
//! against the recording (noise + quantisation).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::time::Instant;

use modellint::fit::effects::{self, Applied, simulate};
use modellint::fit::select::{FitOptions, fit};
use modellint::model::{Robot, source::SourceMap};
use modellint::sim2real::recording::{Recording, read_csv};
use modellint::sim2real::replay::ReplayOptions;
use modellint::synth::{self, Settings, truth::Hidden};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// One effect on one joint.
    Single,
    /// Effect(s) on a joint group (left/right pair).
    Group,
    /// Two effects on one joint.
    Pair,
    /// Nothing missing: recordings from the model itself.
    Control,
}

impl Kind {
    pub fn label(self) -> &'static str {
        match self {
            Kind::Single => "single",
            Kind::Group => "group",
            Kind::Pair => "pair",
            Kind::Control => "control",
        }
    }
}

/// Sensor/sampling realism level (the encoder resolution is [`Case::quant_bits`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Noise {
    /// The arm2 logging setup (`modellint synth` defaults): 88 Hz ±15 % recorder, σ 0.5 mrad,
    /// 0.01 rad/s velocity noise, 0.5 % drops.
    Real,
    /// σ 1 mrad, 88 Hz ±30 %, 0.02 rad/s, 3 % drops.
    High,
}

impl Noise {
    pub fn label(self) -> &'static str {
        match self {
            Noise::Real => "real",
            Noise::High => "high",
        }
    }
}

#[derive(Debug, Clone)]
pub struct Case {
    pub name: String,
    pub kind: Kind,
    /// Model path relative to the crate root (or absolute).
    pub model: PathBuf,
    /// Recorded (and fitted) joints.
    pub joints: Vec<String>,
    /// Hidden truth: (effect id, joint group, parameters). Each group shares the parameters.
    pub truth: Vec<(&'static str, Vec<String>, Vec<f64>)>,
    pub noise: Noise,
    pub episodes: usize,
    pub duration_s: f64,
    pub amplitude: f64,
    pub seed: u64,
    /// Floating base held this far above the keyframe pose [m] (`Settings::suspend_m`).
    pub suspend_m: f64,
    /// Encoder resolution (0: no quantisation).
    pub quant_bits: u32,
}

impl Case {
    /// The synth settings of the fitted dataset (the held-out one uses another seed).
    pub fn synth(&self) -> Settings {
        let (noise, qd_noise, jitter, drop) = match self.noise {
            Noise::Real => (5e-4, 0.01, 0.15, 0.005),
            Noise::High => (1e-3, 0.02, 0.3, 0.03),
        };
        Settings {
            episodes: self.episodes,
            duration_s: self.duration_s,
            noise,
            qd_noise,
            jitter,
            drop,
            quant_bits: self.quant_bits,
            amplitude: self.amplitude,
            seed: self.seed,
            suspend_m: self.suspend_m,
            heldout: 1,
            ..Settings::default()
        }
    }
    /// The same case without encoder quantisation.
    pub fn unquantised(mut self) -> Case {
        self.quant_bits = 0;
        self
    }
    /// Noise label with the encoder: `real 12b`, `high none`.
    pub fn noise_label(&self) -> String {
        format!(
            "{} {}",
            self.noise.label(),
            if self.quant_bits == 0 { "none".to_string() } else { format!("{}b", self.quant_bits) }
        )
    }
    /// The hidden effects as the synth takes them (one per joint, full parameter vectors).
    pub fn hidden(&self) -> Vec<Hidden> {
        self.truth
            .iter()
            .flat_map(|(e, js, p)| {
                let defs = effects::by_id(e).unwrap_or_else(|| panic!("effect {e}")).params();
                let full: Vec<f64> =
                    (0..defs.len()).map(|i| p.get(i).copied().unwrap_or(defs[i].default)).collect();
                let id = effects::by_id(e).map(|x| x.id()).unwrap_or("");
                js.iter().map(move |j| Hidden {
                    effect: id,
                    joint: j.clone(),
                    params: full.clone(),
                })
            })
            .collect()
    }
    pub fn truth_label(&self) -> String {
        if self.truth.is_empty() {
            return "(none)".into();
        }
        self.truth
            .iter()
            .map(|(e, j, p)| {
                let k = effects::by_id(e).map_or(p.len(), |x| x.fitted());
                format!(
                    "{e}@{}={}",
                    j.join("+"),
                    p[..k].iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(",")
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    }
}

#[derive(Debug, Clone)]
pub struct Score {
    pub case: Case,
    /// Detected (effect, joint) pairs, with the fitted values.
    pub detected: Vec<(String, String, Vec<f64>)>,
    pub tp: usize,
    /// Invented: detected (effect, joint) pairs not in the truth.
    pub fp: usize,
    /// Missed truth (effect, joint) pairs.
    pub fneg: usize,
    /// Largest relative parameter error over matched non-delay effects.
    pub param_rel: Option<f64>,
    /// Largest action_delay error [physics steps] over matched delay effects.
    pub delay_steps: Option<f64>,
    /// Held-out MAE against the recordings [rad] (on the truth ∪ detected joints, or all joints
    /// when both are empty).
    pub mae_before: f64,
    pub mae_after: f64,
    /// Held-out MAE of the model against the noise-free truth simulation [rad].
    pub model_before: f64,
    pub model_after: f64,
    /// Noise-only floor of the recorded MAE (noise-free truth vs the recording).
    pub mae_floor: f64,
    pub secs: f64,
    /// |fitted − true| / reported standard error, per fitted parameter of every matched effect.
    pub z_err: Vec<f64>,
    pub warnings: Vec<String>,
    /// The fit's log of tried candidates (round, effect, joints, params, held-out improvement,
    /// significant, BIC decreased, kept), for explaining misses.
    pub tried: Vec<String>,
    /// Top of the first-round diagnosis (effect@joint: explained RMS).
    pub diagnosis: Vec<String>,
}

impl Score {
    pub fn precision(&self) -> Option<f64> {
        let d = self.tp + self.fp;
        (d > 0).then(|| self.tp as f64 / d as f64)
    }
    pub fn recall(&self) -> Option<f64> {
        let t = self.tp + self.fneg;
        (t > 0).then(|| self.tp as f64 / t as f64)
    }
    /// Relative reduction of the recorded held-out MAE.
    pub fn reduction(&self) -> f64 {
        1.0 - self.mae_after / self.mae_before.max(1e-300)
    }
    /// Share of the *reducible* recorded MAE removed: (before − after) / (before − floor). The
    /// floor is the true model's own MAE against the recording (noise + quantisation): no model
    /// can go below it, so for an effect that moves the joint by only a few times the noise a
    /// recorded reduction of 80 % is out of reach even for the exact truth.
    pub fn reducible_reduction(&self) -> Option<f64> {
        let room = self.mae_before - self.mae_floor;
        (room > 0.0).then(|| (self.mae_before - self.mae_after) / room)
    }
    /// Held-out MAE target: recorded MAE reduced ≥ 80 %, or — when the noise floor makes that
    /// impossible — ≥ 80 % of the reducible part removed.
    pub fn mae_ok(&self) -> bool {
        self.reduction() >= 0.80 || self.reducible_reduction().is_some_and(|r| r >= 0.80)
    }
    /// Relative reduction of the model error against the noise-free truth.
    pub fn model_reduction(&self) -> Option<f64> {
        (self.model_before > 0.0).then(|| 1.0 - self.model_after / self.model_before)
    }
    /// Parameters within target: ≤ 10 % relative, delay ≤ 1 physics step.
    pub fn params_ok(&self) -> bool {
        self.param_rel.is_none_or(|e| e <= 0.10) && self.delay_steps.is_none_or(|e| e <= 1.0)
    }
    /// Per-case pass: singles/groups: all found, params within target, [`Score::mae_ok`]; pairs: all found with params; controls: nothing found. No invented effects in any.
    pub fn pass(&self) -> bool {
        match self.case.kind {
            Kind::Control => self.fp == 0,
            Kind::Pair => self.fneg == 0 && self.fp == 0 && self.params_ok(),
            Kind::Single | Kind::Group => {
                self.fneg == 0 && self.fp == 0 && self.params_ok() && self.mae_ok()
            }
        }
    }
}

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn load(path: &Path) -> Robot {
    let mut map = SourceMap::default();
    modellint::model::load(&mut map, path, None)
        .unwrap_or_else(|e| panic!("{}: {e:?}", path.display()))
}

/// Actuated scalar joints of a robot (what `modellint synth` records).
pub fn actuated(robot: &Robot) -> Vec<String> {
    robot
        .joints
        .iter()
        .filter(|j| j.is_scalar() && !robot.actuators_on_joint(j.id).is_empty())
        .map(|j| j.name.clone())
        .collect()
}

fn mae(a: &[Vec<f64>], b: &[Vec<f64>], idx: &[usize]) -> (f64, usize) {
    let mut s = 0.0;
    let mut n = 0;
    for &k in idx {
        for (x, y) in a[k].iter().zip(&b[k]) {
            let e = x - y;
            if e.is_finite() {
                s += e.abs();
                n += 1;
            }
        }
    }
    (s, n)
}

/// Runs one case end to end.
/// Blind fit of `case` with `modellint fit`'s defaults (the tool as shipped), scored.
pub fn run(case: &Case) -> Score {
    let t0 = Instant::now();
    let path = if case.model.is_absolute() { case.model.clone() } else { root().join(&case.model) };
    // Model and hardware spec as `modellint fit` loads them (the spec's motor families are
    // fitted as groups too).
    let loaded = modellint::lint::load_for_command(&path, None)
        .unwrap_or_else(|_| panic!("{} does not load", path.display()));
    let robot = loaded.robot;
    let hidden = case.hidden();
    let o = case.synth();
    let (recs, _) = recorded(&robot, case, &hidden, &o, "fit");
    // The fit sees only the recordings and the model without the effects, with the CLI's
    // defaults.
    let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let opts = FitOptions {
        families: FitOptions::motor_families(loaded.spec.as_ref(), &names),
        ..FitOptions::default()
    };
    let out = fit(&robot, &recs, &opts);

    // Detection scoring by (effect, joint).
    let detected: Vec<(String, String, Vec<f64>)> = out
        .selected
        .iter()
        .flat_map(|s| s.joints.iter().map(move |j| (s.effect.clone(), j.clone(), s.values.clone())))
        .collect();
    let truth_pairs: Vec<(&str, &str, &Vec<f64>)> = case
        .truth
        .iter()
        .flat_map(|(e, js, p)| js.iter().map(move |j| (*e, j.as_str(), p)))
        .collect();
    let mut tp = 0;
    let mut param_rel: Option<f64> = None;
    let mut delay_steps: Option<f64> = None;
    for (e, j, p) in &truth_pairs {
        let Some(d) = detected.iter().find(|d| d.0 == *e && d.1 == *j) else { continue };
        tp += 1;
        let k = effects::by_id(e).map_or(p.len(), |x| x.fitted());
        for i in 0..k.min(p.len()).min(d.2.len()) {
            if *e == "action_delay" {
                let steps = (d.2[i] - p[i]).abs() / robot.opt.timestep;
                delay_steps = Some(delay_steps.map_or(steps, |x: f64| x.max(steps)));
            } else {
                let rel = (d.2[i] - p[i]).abs() / p[i].abs().max(1e-12);
                param_rel = Some(param_rel.map_or(rel, |x: f64| x.max(rel)));
            }
        }
    }
    // Calibration of the reported uncertainty: |fitted − true| / stderr.
    let mut z_err = Vec::new();
    for sel in &out.selected {
        let Some(e) = effects::by_id(&sel.effect) else { continue };
        let Some((_, _, p)) =
            truth_pairs.iter().find(|t| t.0 == sel.effect && sel.joints.iter().any(|j| j == t.1))
        else {
            continue;
        };
        for (i, d) in e.params().iter().take(e.fitted()).enumerate() {
            if let (Some(v), Some(se), Some(tv)) =
                (sel.params.get(d.name), sel.stderr.get(d.name), p.get(i))
                && se.is_finite()
                && *se > 0.0
            {
                z_err.push((v - tv).abs() / se);
            }
        }
    }
    let fp =
        detected.iter().filter(|d| !truth_pairs.iter().any(|t| t.0 == d.0 && t.1 == d.1)).count();
    let fneg = truth_pairs.len() - tp;

    // Fresh held-out episodes (other seed: other commands, timestamps, noise).
    let ho_o =
        Settings { episodes: 2, heldout: 1, seed: case.seed.wrapping_add(7777), ..o.clone() };
    let (ho, ho_ds) = recorded(&robot, case, &hidden, &ho_o, "heldout");
    let ropts = ReplayOptions::default();
    let sims = |a: &[Applied]| -> Vec<Vec<Vec<f64>>> {
        simulate(&robot, &ho, a, &ropts)
            .into_iter()
            .map(|e| e.map(|e| e.q_sim).expect("held-out replay"))
            .collect()
    };
    let (s_before, s_after) = (sims(&[]), sims(&out.applied));
    // The truth: the synth's noise-free reading (true position + sensor offset) at every row.
    let s_truth: Vec<Vec<Vec<f64>>> = ho_ds.episodes.iter().map(|e| e.q_true.clone()).collect();
    let mut focus: Vec<String> = truth_pairs
        .iter()
        .map(|t| t.1.to_string())
        .chain(detected.iter().map(|d| d.1.clone()))
        .collect();
    focus.sort();
    focus.dedup();
    let acc = |a: &[Vec<Vec<f64>>], b: Option<&[Vec<Vec<f64>>]>| {
        let (mut s, mut n) = (0.0, 0usize);
        for (r, rec) in ho.iter().enumerate() {
            let idx: Vec<usize> = rec
                .joints
                .iter()
                .enumerate()
                .filter(|(_, j)| focus.is_empty() || focus.contains(&j.name))
                .map(|(k, _)| k)
                .collect();
            let recq: Vec<Vec<f64>> = rec.joints.iter().map(|j| j.q.clone()).collect();
            let (ds, dn) = mae(&a[r], b.map_or(&recq, |b| &b[r]), &idx);
            s += ds;
            n += dn;
        }
        s / n.max(1) as f64
    };
    Score {
        case: case.clone(),
        detected,
        tp,
        fp,
        fneg,
        param_rel,
        delay_steps,
        mae_before: acc(&s_before, None),
        mae_after: acc(&s_after, None),
        model_before: acc(&s_before, Some(&s_truth)),
        model_after: acc(&s_after, Some(&s_truth)),
        mae_floor: acc(&s_truth, None),
        secs: t0.elapsed().as_secs_f64(),
        z_err,
        warnings: out.warnings,
        tried: out
            .tried
            .iter()
            .map(|t| {
                format!(
                    "r{} {} {}@{}={:?} heldout {:+.1} % sig {} bic↓ {} kept {}",
                    t.round,
                    t.phase,
                    t.effect,
                    t.joints.join("+"),
                    t.params.iter().map(|v| (v * 1e4).round() / 1e4).collect::<Vec<_>>(),
                    100.0 * t.heldout_improvement,
                    t.significant,
                    t.bic_decreased,
                    t.kept
                )
            })
            .collect(),
        diagnosis: out
            .diagnosis
            .iter()
            .take(6)
            .map(|c| format!("{}@{}: {:.2e}", c.effect, c.joint, c.explained_rms))
            .collect(),
    }
}

/// Generates `case`'s recordings with the independent synth, writes them as CSV and reads them
/// back with the recording reader `fit` uses (the same path a user's files take).
pub fn recorded(
    robot: &Robot,
    case: &Case,
    hidden: &[Hidden],
    o: &Settings,
    tag: &str,
) -> (Vec<Recording>, synth::Dataset) {
    let ds = synth::generate(robot, &case.joints, hidden, o, &|_, _| {})
        .unwrap_or_else(|e| panic!("{}: synth: {e}", case.name));
    let slug: String = format!("{} {} {tag}", case.name, case.noise_label())
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let dir = std::env::temp_dir().join(format!("modellint_conceal_{}_{slug}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let files = synth::write::write(&ds, &dir).unwrap_or_else(|e| panic!("{}: {e}", case.name));
    let recs = files
        .iter()
        .map(|f| read_csv(f).unwrap_or_else(|e| panic!("{}: {e}", f.display())))
        .collect();
    // MODELLINT_CONCEAL_KEEP=DIR keeps each case's recordings (to re-run `modellint fit` on them).
    match std::env::var_os("MODELLINT_CONCEAL_KEEP") {
        Some(keep) => {
            let to = PathBuf::from(keep).join(dir.file_name().unwrap_or_default());
            let _ = std::fs::remove_dir_all(&to);
            let _ = std::fs::create_dir_all(to.parent().unwrap_or(Path::new(".")));
            if std::fs::rename(&dir, &to).is_err() {
                let _ = std::fs::remove_dir_all(&dir);
            }
        }
        None => {
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
    (recs, ds)
}

fn pct(x: Option<f64>) -> String {
    x.map_or("–".into(), |v| format!("{:.0} %", 100.0 * v))
}

pub fn table_header() -> String {
    "| case | kind | noise | truth | detected | P | R | param err | held-out MAE before → after [mrad] (floor) | reduction | of reducible | model-error reduction | time [s] | pass |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n".into()
}

pub fn table_row(s: &Score) -> String {
    let det = if s.detected.is_empty() {
        "(none)".to_string()
    } else {
        s.detected
            .iter()
            .map(|(e, j, v)| {
                format!(
                    "{e}@{j}={}",
                    v.iter()
                        .take(effects::by_id(e).map_or(v.len(), |x| x.fitted()))
                        .map(|x| format!("{x:.4}"))
                        .collect::<Vec<_>>()
                        .join(",")
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let perr = match (s.param_rel, s.delay_steps) {
        (None, None) => "–".to_string(),
        (a, b) => [a.map(|v| format!("{:.1} %", 100.0 * v)), b.map(|v| format!("{v:.2} steps"))]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(", "),
    };
    format!(
        "| {} | {} | {} | {} | {} | {} | {} | {} | {:.2} → {:.2} ({:.2}) | {} | {} | {} | {:.0} | {} |\n",
        s.case.name,
        s.case.kind.label(),
        s.case.noise_label(),
        s.case.truth_label(),
        det,
        pct(s.precision()),
        pct(s.recall()),
        perr,
        1e3 * s.mae_before,
        1e3 * s.mae_after,
        1e3 * s.mae_floor,
        if s.case.kind == Kind::Control { "–".into() } else { pct(Some(s.reduction())) },
        if s.case.kind == Kind::Control { "–".into() } else { pct(s.reducible_reduction()) },
        pct(s.model_reduction()),
        s.secs,
        if s.pass() { "yes" } else { "**NO**" }
    )
}

/// Summary against the targets; returns (text, all met).
pub fn summary(scores: &[Score]) -> (String, bool) {
    let mut lines = Vec::new();
    let mut all = true;
    let singles: Vec<&Score> =
        scores.iter().filter(|s| matches!(s.case.kind, Kind::Single | Kind::Group)).collect();
    if !singles.is_empty() {
        let found = singles.iter().filter(|s| s.fneg == 0).count();
        let par = singles.iter().filter(|s| s.fneg == 0 && s.params_ok()).count();
        let raw = singles.iter().filter(|s| s.reduction() >= 0.80).count();
        let red = singles.iter().filter(|s| s.mae_ok()).count();
        let inv = singles.iter().filter(|s| s.fp > 0).count();
        let ok = found == singles.len() && par == singles.len();
        all &= ok && red == singles.len() && inv == 0;
        lines.push(format!(
            "singles/groups: found {found}/{n}, params within target (≤ 10 %, delay ≤ 1 step) {par}/{n} [{}]; held-out MAE reduced ≥ 80 % in {raw}/{n}, ≥ 80 % of the reducible error (above the noise floor) in {red}/{n} [{}]; cases with invented effects {inv}/{n} [{}]",
            if ok { "MET" } else { "MISSED" },
            if red == singles.len() { "MET" } else { "MISSED" },
            if inv == 0 { "MET" } else { "MISSED" },
            n = singles.len()
        ));
    }
    let pairs: Vec<&Score> = scores.iter().filter(|s| s.case.kind == Kind::Pair).collect();
    if !pairs.is_empty() {
        let (tp, tot): (usize, usize) =
            pairs.iter().fold((0, 0), |(a, b), s| (a + s.tp, b + s.tp + s.fneg));
        let rec = tp as f64 / tot.max(1) as f64;
        let inv_clean =
            pairs.iter().filter(|s| s.case.noise == Noise::Real).map(|s| s.fp).sum::<usize>();
        let ok = rec >= 0.9 && inv_clean == 0;
        all &= ok;
        lines.push(format!(
            "pairs: recall {tp}/{tot} = {:.0} % (target ≥ 90 %), invented effects on realistic-noise pairs {inv_clean} (target 0) [{}]",
            100.0 * rec,
            if ok { "MET" } else { "MISSED" }
        ));
    }
    let controls: Vec<&Score> = scores.iter().filter(|s| s.case.kind == Kind::Control).collect();
    if !controls.is_empty() {
        let clean = controls.iter().filter(|s| s.fp == 0).count();
        all &= clean == controls.len();
        lines.push(format!(
            "controls: nothing selected in {clean}/{} [{}]",
            controls.len(),
            if clean == controls.len() { "MET" } else { "MISSED" }
        ));
    }
    // Reported uncertainty (information, no target): how far the fitted values are from the
    // truth in units of their standard errors.
    let mut z: Vec<f64> = scores.iter().flat_map(|s| s.z_err.iter().copied()).collect();
    if !z.is_empty() {
        z.sort_by(f64::total_cmp);
        let within = |k: f64| z.iter().filter(|&&x| x <= k).count();
        lines.push(format!(
            "uncertainty: {} fitted parameters of found effects; |fitted − true| ≤ 1 stderr for {}, ≤ 2 for {}, ≤ 3 for {}; median {:.2}, max {:.1} stderr",
            z.len(),
            within(1.0),
            within(2.0),
            within(3.0),
            z[z.len() / 2],
            z[z.len() - 1]
        ));
    }
    let t: f64 = scores.iter().map(|s| s.secs).sum();
    let passed = scores.iter().filter(|s| s.pass()).count();
    // Overall agrees with the per-case verdicts (a case with an invented effect fails).
    all &= passed == scores.len();
    lines.push(format!(
        "cases passed {passed}/{}; total {t:.0} s; overall: {}",
        scores.len(),
        if all { "ALL TARGETS MET" } else { "TARGETS MISSED (see above)" }
    ));
    (lines.join("\n"), all)
}

// ---- case builders ----

pub const ARM3: &str = "fixtures/gap/arm3.xml";
pub const RIG: &str = "fixtures/bam_xl330/rig.xml";
pub const ASIMOV: &str = "models/asimov.xml";
/// Lightly damped pendulum servo (ζ ≈ 0.15).
pub const PENDULUM: &str = "fixtures/synth/pendulum_servo.xml";
/// A humanoid-sized knee on a stand (kp 250, 150 N·m): damping and friction beyond a small
/// servo's fixed fit box.
pub const HEAVY_KNEE: &str = "fixtures/synth/heavy_knee.xml";

pub fn arm3_joints() -> Vec<String> {
    ["shoulder_pitch", "elbow_pitch", "wrist_pitch"].iter().map(|s| s.to_string()).collect()
}

pub fn asimov_legs() -> Vec<String> {
    ["hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll"]
        .iter()
        .flat_map(|j| [format!("left_{j}"), format!("right_{j}")])
        .collect()
}

/// The 11 single effects on arm3's elbow with the parameters of tests/fit.rs.
pub fn arm3_single_truths() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("action_delay", vec![0.025]),
        ("coulomb_friction", vec![0.15]),
        ("viscous_damping", vec![0.4]),
        ("armature", vec![0.04]),
        ("position_offset", vec![0.05]),
        ("gain_error", vec![0.6, 1.0]),
        ("stribeck_friction", vec![0.3, 0.1, 0.2]),
        ("torque_limit", vec![1.0, 1e4, 1e4]),
        ("backlash", vec![0.04]),
        ("joint_stiffness", vec![2.0]),
        ("load_dependent_friction", vec![0.05, 0.1]),
    ]
}

pub fn arm3_case(
    name: &str,
    kind: Kind,
    truth: Vec<(&'static str, Vec<f64>)>,
    noise: Noise,
    seed: u64,
) -> Case {
    Case {
        name: name.into(),
        kind,
        model: ARM3.into(),
        joints: arm3_joints(),
        truth: truth.into_iter().map(|(e, p)| (e, vec!["elbow_pitch".to_string()], p)).collect(),
        noise,
        episodes: 8,
        duration_s: 4.0,
        amplitude: 0.5,
        seed,
        suspend_m: 0.0,
        quant_bits: 12,
    }
}

pub fn rig_case(
    name: &str,
    kind: Kind,
    truth: Vec<(&'static str, Vec<f64>)>,
    noise: Noise,
    seed: u64,
) -> Case {
    Case {
        name: name.into(),
        kind,
        model: RIG.into(),
        joints: vec!["servo".into()],
        truth: truth.into_iter().map(|(e, p)| (e, vec!["servo".to_string()], p)).collect(),
        noise,
        episodes: 8,
        duration_s: 4.0,
        amplitude: 0.8,
        seed,
        suspend_m: 0.0,
        quant_bits: 12,
    }
}

pub fn asimov_case(
    name: &str,
    kind: Kind,
    truth: Vec<(&'static str, Vec<String>, Vec<f64>)>,
    noise: Noise,
    seed: u64,
) -> Case {
    // On a test stand: base 0.5 m above the standing keyframe, feet in the air (with the base
    // pinned at the standing pose the feet drag on the floor and the replay is chaotic; see
    // docs/conceal-benchmark.md).
    Case {
        name: name.into(),
        kind,
        model: ASIMOV.into(),
        joints: asimov_legs(),
        truth,
        noise,
        episodes: 8,
        duration_s: 4.0,
        amplitude: 0.15,
        seed,
        suspend_m: 0.5,
        quant_bits: 12,
    }
}

pub fn heavy_knee_case(
    name: &str,
    kind: Kind,
    truth: Vec<(&'static str, Vec<f64>)>,
    noise: Noise,
    seed: u64,
) -> Case {
    Case {
        model: HEAVY_KNEE.into(),
        joints: vec!["knee".into()],
        truth: truth.into_iter().map(|(e, p)| (e, vec!["knee".to_string()], p)).collect(),
        episodes: 6,
        amplitude: 0.5,
        ..rig_case(name, kind, vec![], noise, seed)
    }
}

/// Effects on the humanoid-sized knee, each beyond the fixed bound a small servo's fit box
/// has (damping, friction 5; stiffness 20; effort limit 50).
pub fn heavy_knee_truths() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("viscous_damping", vec![9.0]),
        ("coulomb_friction", vec![8.0]),
        ("stribeck_friction", vec![10.0, 6.0, 0.2]),
        ("joint_stiffness", vec![40.0]),
        ("torque_limit", vec![60.0]),
    ]
}

pub fn pendulum_case(
    name: &str,
    kind: Kind,
    truth: Vec<(&'static str, Vec<f64>)>,
    noise: Noise,
    seed: u64,
) -> Case {
    Case {
        name: name.into(),
        kind,
        model: PENDULUM.into(),
        joints: vec!["servo".into()],
        truth: truth.into_iter().map(|(e, p)| (e, vec!["servo".to_string()], p)).collect(),
        noise,
        episodes: 4,
        duration_s: 10.0,
        amplitude: 0.35,
        seed,
        suspend_m: 0.0,
        quant_bits: 12,
    }
}

/// The 11 single effects on the pendulum servo (I = 0.005 kg·m², kp 2 N·m/rad).
pub fn pendulum_single_truths() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("action_delay", vec![0.015]),
        ("coulomb_friction", vec![0.03]),
        ("viscous_damping", vec![0.03]),
        ("armature", vec![0.003]),
        ("position_offset", vec![0.05]),
        ("gain_error", vec![0.7, 1.3]),
        ("stribeck_friction", vec![0.06, 0.03, 0.2]),
        ("torque_limit", vec![0.4, 1e4, 1e4]),
        ("backlash", vec![0.03]),
        ("joint_stiffness", vec![0.5]),
        ("load_dependent_friction", vec![0.01, 0.1]),
    ]
}

/// The 11 single effects for an asimov knee (kp 65, armature 0.034 kg·m²); first-guess sizes.
/// The knee's servo torque in the benchmark excitation (seed 7, amplitude 0.15) peaks at
/// 7.9 N·m and exceeds 2 N·m in 3.6 % of the samples: a 2 N·m limit binds at the steps (a
/// 10 N·m one never bound, so the case could not be found).
pub fn asimov_single_truths() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("action_delay", vec![0.015]),
        ("coulomb_friction", vec![1.0]),
        ("viscous_damping", vec![3.0]),
        ("armature", vec![0.15]),
        ("position_offset", vec![0.05]),
        ("gain_error", vec![0.7, 1.3]),
        ("stribeck_friction", vec![2.0, 1.0, 0.2]),
        ("torque_limit", vec![2.0, 1e4, 1e4]),
        ("backlash", vec![0.03]),
        ("joint_stiffness", vec![20.0]),
        ("load_dependent_friction", vec![0.5, 0.1]),
    ]
}

/// Pairs every robot gets (the ones issue 12 names: they may only help together).
pub fn pair_truths(singles: &[(&'static str, Vec<f64>)]) -> Vec<Vec<(&'static str, Vec<f64>)>> {
    let p = |e: &str| {
        singles
            .iter()
            .find(|(x, _)| *x == e)
            .map(|(x, v)| (*x, v.clone()))
            .unwrap_or_else(|| panic!("{e}"))
    };
    vec![
        vec![p("gain_error"), p("action_delay")],
        vec![p("coulomb_friction"), p("armature")],
        vec![p("backlash"), p("position_offset")],
        vec![p("viscous_damping"), p("armature")],
    ]
}
