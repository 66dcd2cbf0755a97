//! `modellint synth` command line: flags → [`Settings`], then generate and write.

use std::path::PathBuf;

use clap::Args;

use super::Settings;
use super::excitation::Excitation;

pub const LONG_ABOUT: &str = "\
Record a simulated \"real robot\" (the model plus hidden effects) through a simulated logging
setup, and write the recordings with their answer key. The synth runs its own MuJoCo loop and
shares no replay code with `gap`/`fit`, so it can check them.

The logging setup (defaults = the independent_arm2 development set):

  settle (2 s, unrecorded)   | recording time 0 ................................ duration
  controller ticks  --|-----|-----|-----|-----|-----|---   every 1/control-hz from control-phase,
                       u0    u1    u2    u3    u4           each command held until the next tick
  recorder rows     x      x    x       x    x      x      ~sample-hz ± jitter, asynchronous;
                                                            a row logs q, qd and the command in
                                                            force at its time (tick floor((t−t0)·rate))

  q = round((q_true + offset + N(0, noise)) / quantum) · quantum,  quantum = 2π / 2^quant-bits
  qd = qd_true + N(0, qd-noise);  rows dropped with probability --drop (never the first or last)
  --log-at-ticks: one row exactly at every tick instead (state read, then that tick's command).

Excitation per episode: 0.3 s hold, then ramped steps / exponential chirp 0.1→5 Hz / smoothed
random walk (--excitation mix shuffles all three) around the keyframe pose, inside joint ranges.

Hidden effects: --effects 'effect[@joint_glob]=v1,v2;…' with the parameters of `modellint fit`'s
effects in their order (missing ones at their defaults), e.g.
  --effects 'armature@*knee*=0.05;action_delay=0.012'     ('none' or '' = a clean control)

Output: OUT/episodes/ep_00.csv … (the last --heldout episodes carry `split: heldout`),
OUT/truth_commands/ep_00.csv (every tick's exact command), OUT/truth.json (effects, settings,
per-joint noise + quantisation floor, dropped rows). See `modellint docs synth`.";

#[derive(Args, Debug)]
pub struct SynthCmd {
    /// Model (MJCF or URDF).
    pub model: PathBuf,
    #[command(flatten)]
    pub packages: crate::cli_logs::PackageArgs,
    /// Output directory (episodes/, truth_commands/, truth.json).
    #[arg(long)]
    pub out: PathBuf,
    /// Effects to hide: `effect[@joint_glob]=v1,v2;…`; `none` for a clean control.
    #[arg(long, default_value = "none")]
    pub effects: String,
    /// Drive and record only the joints matching this glob (default: every joint with a
    /// position actuator).
    #[arg(long)]
    pub joints: Option<String>,
    #[arg(long, default_value_t = 4)]
    pub episodes: usize,
    /// Recorded seconds per episode.
    #[arg(long, default_value_t = 10.0)]
    pub duration: f64,
    /// Controller command rate [Hz].
    #[arg(long, default_value_t = 100.0)]
    pub control_hz: f64,
    /// Time of control tick 0 after the recording starts [s], less than one control period.
    #[arg(long, default_value_t = 0.0)]
    pub control_phase: f64,
    /// Mean recorder rate [Hz].
    #[arg(long, default_value_t = 88.0)]
    pub sample_hz: f64,
    /// Recorder period jitter, a fraction of the period (0.15 = ±15 %).
    #[arg(long, default_value_t = 0.15)]
    pub jitter: f64,
    /// Log exactly at the control ticks instead of the asynchronous recorder.
    #[arg(long)]
    pub log_at_ticks: bool,
    /// Unrecorded settle at the first command before recording starts [s].
    #[arg(long, default_value_t = 2.0)]
    pub settle: f64,
    /// Position noise σ [rad].
    #[arg(long, default_value_t = 5e-4)]
    pub noise: f64,
    /// Encoder resolution [bits]: quantum 2π/2^bits; 0 = no quantisation.
    #[arg(long, default_value_t = 12)]
    pub quant_bits: u32,
    /// Velocity noise σ [rad/s].
    #[arg(long, default_value_t = 0.01)]
    pub qd_noise: f64,
    /// Probability that a row is dropped (never the first or last).
    #[arg(long, default_value_t = 0.005)]
    pub drop: f64,
    /// Commands: mix (shuffled steps, chirp, random walk), chirp, steps or random.
    #[arg(long, default_value = "mix")]
    pub excitation: String,
    /// Command amplitude about the keyframe pose [rad] (shrunk to fit joint ranges).
    #[arg(long, default_value_t = 0.35)]
    pub amplitude: f64,
    /// The last N episodes are marked `split: heldout` (default 1; 0 with a single episode).
    #[arg(long)]
    pub heldout: Option<usize>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Floating-base robots: hold the base this many metres above its keyframe pose (a test
    /// stand; base.* columns written). 0: no stand.
    #[arg(long, default_value_t = 0.0)]
    pub suspend: f64,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

fn fail(msg: impl std::fmt::Display) -> i32 {
    eprintln!("modellint: synth: {msg}");
    2
}

impl SynthCmd {
    pub fn settings(&self) -> Result<Settings, String> {
        let excitation = Excitation::parse(&self.excitation).ok_or_else(|| {
            format!("--excitation must be mix, chirp, steps or random, got `{}`", self.excitation)
        })?;
        let s = Settings {
            episodes: self.episodes,
            duration_s: self.duration,
            control_hz: self.control_hz,
            control_phase_s: self.control_phase,
            sample_hz: self.sample_hz,
            jitter: self.jitter,
            log_at_ticks: self.log_at_ticks,
            settle_s: self.settle,
            noise: self.noise,
            quant_bits: self.quant_bits,
            qd_noise: self.qd_noise,
            drop: self.drop,
            excitation,
            amplitude: self.amplitude,
            heldout: self.heldout.unwrap_or(if self.episodes > 1 { 1 } else { 0 }),
            seed: self.seed,
            suspend_m: self.suspend,
        };
        s.validate()?;
        Ok(s)
    }
}

/// `modellint synth`.
pub fn run(a: SynthCmd) -> i32 {
    let s = match a.settings() {
        Ok(s) => s,
        Err(e) => return fail(e),
    };
    let loaded = match crate::lint::load_for_command(&a.model, None) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let robot = &loaded.robot;
    let joints = match super::driven_joints(robot, a.joints.as_deref()) {
        Ok(j) => j,
        Err(e) => return fail(e),
    };
    let hidden = match super::truth::parse(&a.effects, &joints) {
        Ok(h) => h,
        Err(e) => return fail(format!("--effects: {e}")),
    };
    if s.suspend_m > 0.0 && !robot.joints.iter().any(|j| j.jtype == crate::model::JointType::Free) {
        return fail("--suspend needs a floating-base model (a free joint)");
    }
    let quiet = a.quiet;
    let t0 = std::time::Instant::now();
    let progress = move |done: usize, total: usize| {
        if !quiet {
            let el = t0.elapsed().as_secs_f64();
            let eta = el / done as f64 * (total - done) as f64;
            eprintln!("synth: episode {done}/{total} simulated ({el:.1} s, ~{eta:.0} s left)");
        }
    };
    let ds = match super::generate(robot, &joints, &hidden, &s, &progress) {
        Ok(d) => d,
        Err(e) => return fail(e),
    };
    if let Err(e) = super::write::write(&ds, &a.out) {
        return fail(e);
    }
    if !quiet {
        let fl: Vec<String> = ds
            .joints
            .iter()
            .zip(&ds.floor)
            .map(|(j, f)| format!("{j} {:.3}/{:.3}", 1e3 * f.mae, 1e3 * f.rmse))
            .collect();
        eprintln!(
            "synth: {} episodes written to {} (answers in truth.json)",
            ds.episodes.len(),
            a.out.display()
        );
        eprintln!("synth: noise + quantisation floor MAE/RMSE [mrad]: {}", fl.join(", "));
    }
    0
}
