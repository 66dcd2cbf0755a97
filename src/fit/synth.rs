//! Synthetic "real" data: excitation commands (chirps, steps, smooth random) and recordings
//! generated from a model with hidden effects, with sensor noise, quantisation, irregular
//! sampling with jitter and dropped samples. Used by `modellint synth`, the tests and the
//! benchmark; `modellint fit` never reads the truth.

use std::path::PathBuf;

use crate::fit::effects::{Applied, simulate};
use crate::model::{JointType, Robot};
use crate::sim2real::recording::{BaseTrace, JointTrace, Recording};
use crate::sim2real::replay::{ReplayError, ReplayOptions};

/// Deterministic splitmix64 RNG.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x2545_F491_4F6C_DD1D)
    }
    pub fn u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

#[derive(Debug, Clone)]
pub struct SynthOptions {
    pub duration_s: f64,
    /// Mean sampling rate [Hz] (jittered).
    pub sample_hz: f64,
    /// Relative jitter of the sampling interval (0.2 = ±20 %).
    pub jitter: f64,
    pub control_hz: f64,
    /// Command amplitude about the keyframe [rad].
    pub amplitude: f64,
    /// Position noise σ [rad].
    pub noise: f64,
    /// Encoder quantum [rad] (0: none).
    pub quantum: f64,
    /// Fraction of samples dropped.
    pub drop: f64,
    /// Floating-base robots: the base is held this far above its keyframe pose [m] (a robot
    /// hung on a test stand, feet clear of the ground), written as `base.*` columns. 0: the
    /// keyframe pose (standing, feet on the floor).
    pub suspend_m: f64,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            duration_s: 5.0,
            sample_hz: 200.0,
            jitter: 0.2,
            control_hz: 100.0,
            amplitude: 0.5,
            noise: 1e-4,
            quantum: 0.0,
            drop: 0.0,
            suspend_m: 0.0,
        }
    }
}

/// Command of kind `kind % 3` (chirp, steps, smooth random) at time `t`.
fn command(
    kind: usize,
    t: f64,
    dur: f64,
    amp: f64,
    phase: f64,
    steps: &[f64],
    knots: &[f64],
) -> f64 {
    let ramp = (t / 0.3).min(1.0);
    match kind % 3 {
        0 => {
            // Linear chirp 0.3 → 3 Hz.
            let (f0, f1) = (0.3, 3.0);
            let ph = 2.0 * std::f64::consts::PI * (f0 * t + 0.5 * (f1 - f0) / dur * t * t) + phase;
            ramp * amp * ph.sin()
        }
        1 => {
            let k = ((t / dur) * steps.len() as f64) as usize;
            ramp * amp * steps[k.min(steps.len() - 1)]
        }
        _ => {
            // Cubic-smoothed random knots every 0.4 s.
            let x = t / 0.4;
            let i = (x as usize).min(knots.len() - 2);
            let a = (x - i as f64).clamp(0.0, 1.0);
            let s = a * a * (3.0 - 2.0 * a);
            ramp * amp * (knots[i] + s * (knots[i + 1] - knots[i]))
        }
    }
}

/// An excitation recording (commands only; `q` = command) for `joints` around `key_q`.
pub fn excitation(joints: &[(String, f64)], o: &SynthOptions, seed: u64) -> Recording {
    let mut rng = Rng::new(seed);
    let mut t = Vec::new();
    let dt = 1.0 / o.sample_hz;
    let mut x = 0.0;
    while x <= o.duration_s {
        t.push(x);
        x += dt * (1.0 + o.jitter * (2.0 * rng.uniform() - 1.0));
    }
    let n = t.len();
    let traces = joints
        .iter()
        .enumerate()
        .map(|(k, (name, q0))| {
            let kind = (seed as usize + k) % 3;
            let steps: Vec<f64> = (0..8).map(|_| 2.0 * rng.uniform() - 1.0).collect();
            let knots: Vec<f64> = (0..((o.duration_s / 0.4) as usize + 3))
                .map(|_| 2.0 * rng.uniform() - 1.0)
                .collect();
            let phase = rng.uniform() * std::f64::consts::TAU;
            let c: Vec<f64> = t
                .iter()
                .map(|&ti| q0 + command(kind, ti, o.duration_s, o.amplitude, phase, &steps, &knots))
                .collect();
            let mut j = JointTrace::new(name.clone(), c.clone());
            j.q_cmd = Some(c);
            j.qd = Some(vec![0.0; n]);
            j
        })
        .collect();
    Recording {
        source: PathBuf::from(format!("synth_{seed:03}.csv")),
        meta: Default::default(),
        control_rate_hz: Some(o.control_hz),
        control_t0_s: None,
        t,
        joints: traces,
        base: None,
    }
}

/// "Real" recordings: `n` excitations of `joints` replayed on `robot` with the hidden `truth`
/// effects, then noise, quantisation and dropped samples applied to the positions.
pub fn generate(
    robot: &Robot,
    joints: &[String],
    truth: &[Applied],
    n: usize,
    o: &SynthOptions,
    seed: u64,
) -> Result<Vec<Recording>, ReplayError> {
    let jq: Vec<(String, f64)> = joints
        .iter()
        .map(|j| {
            (
                j.clone(),
                robot
                    .joint(j)
                    .map_or(0.0, |jj| robot.key.qpos.get(jj.qposadr).copied().unwrap_or(0.0)),
            )
        })
        .collect();
    let free = robot.joints.iter().find(|j| j.jtype == JointType::Free).map(|j| j.qposadr);
    let base = |len: usize| -> Option<BaseTrace> {
        let qa = free.filter(|_| o.suspend_m > 0.0)?;
        let k = robot.key.qpos.get(qa..qa + 7)?;
        Some(BaseTrace {
            pos: vec![[k[0], k[1], k[2] + o.suspend_m]; len],
            quat: vec![[k[3], k[4], k[5], k[6]]; len],
        })
    };
    let cmds: Vec<Recording> = (0..n)
        .map(|i| {
            let mut r = excitation(&jq, o, seed.wrapping_mul(1000).wrapping_add(i as u64));
            r.base = base(r.t.len());
            r
        })
        .collect();
    let eps = simulate(robot, &cmds, truth, &ReplayOptions::default());
    let mut out = Vec::new();
    let mut rng = Rng::new(seed ^ 0xABCD);
    for (mut rec, ep) in cmds.into_iter().zip(eps) {
        let ep = ep?;
        for (k, j) in rec.joints.iter_mut().enumerate() {
            j.q = ep.q_sim[k]
                .iter()
                .map(|&q| {
                    let v = q + o.noise * rng.normal();
                    if o.quantum > 0.0 { (v / o.quantum).round() * o.quantum } else { v }
                })
                .collect();
            j.qd = Some(ep.qd_sim[k].iter().map(|&v| v + 10.0 * o.noise * rng.normal()).collect());
        }
        if o.drop > 0.0 {
            let keep: Vec<bool> =
                (0..rec.t.len()).map(|i| i < 2 || rng.uniform() >= o.drop).collect();
            let f = |v: &Vec<f64>| kept_rows(v, &keep);
            rec.t = f(&rec.t);
            if let Some(b) = rec.base.as_mut() {
                b.pos = kept_rows(&b.pos, &keep);
                b.quat = kept_rows(&b.quat, &keep);
            }
            for j in rec.joints.iter_mut() {
                j.q = f(&j.q);
                j.qd = j.qd.as_ref().map(f);
                j.q_cmd = j.q_cmd.as_ref().map(f);
            }
        }
        out.push(rec);
    }
    Ok(out)
}

/// The rows of `v` whose `keep` flag is set.
fn kept_rows<T: Copy>(v: &[T], keep: &[bool]) -> Vec<T> {
    v.iter().zip(keep).filter(|(_, k)| **k).map(|(x, _)| *x).collect()
}

/// Parses an effect spec `effect[@joint_glob]=v1,v2;…` (parameters in the effect's order, the
/// rest at their defaults; no glob = every joint in `joints`) into applied effects.
pub fn parse_spec(spec: &str, joints: &[String]) -> Result<Vec<Applied>, String> {
    let mut out = Vec::new();
    for item in spec.split(';').map(str::trim).filter(|s| !s.is_empty()) {
        let (lhs, rhs) = item
            .split_once('=')
            .ok_or_else(|| format!("`{item}`: expected effect[@joints]=values"))?;
        let (id, glob) = match lhs.split_once('@') {
            Some((a, b)) => (a.trim(), Some(b.trim())),
            None => (lhs.trim(), None),
        };
        let e = crate::fit::effects::by_id(id).ok_or_else(|| format!("unknown effect `{id}`"))?;
        let mut params: Vec<f64> = e.params().iter().map(|p| p.default).collect();
        for (k, v) in rhs.split(',').enumerate() {
            if k >= params.len() {
                return Err(format!("`{item}`: {id} has {} parameters", params.len()));
            }
            params[k] = v.trim().parse().map_err(|_| format!("`{item}`: bad number `{v}`"))?;
        }
        let sel: Vec<String> = match glob {
            Some(g) => {
                let m = globset::Glob::new(g).map_err(|x| x.to_string())?.compile_matcher();
                joints.iter().filter(|j| m.is_match(j.as_str())).cloned().collect()
            }
            None => joints.to_vec(),
        };
        if sel.is_empty() {
            return Err(format!("`{item}`: no joint matches"));
        }
        // One applied entry per joint (independent truth per joint).
        for j in sel {
            out.push(Applied { effect: e, joints: vec![j], params: params.clone() });
        }
    }
    Ok(out)
}

/// The truth file: every hidden effect with its parameters.
pub fn truth_toml(truth: &[Applied], o: &SynthOptions, seed: u64) -> String {
    let mut s = format!(
        "# Hidden effects of this synthetic dataset (modellint synth). `modellint fit` never reads this file.\nseed = {seed}\nnoise_rad = {}\nquantum_rad = {}\nsample_hz = {}\njitter = {}\ndrop = {}\nsuspend_m = {}\n\n",
        o.noise, o.quantum, o.sample_hz, o.jitter, o.drop, o.suspend_m
    );
    for a in truth {
        s.push_str(&format!(
            "[[effect]]\nid = \"{}\"\njoints = [{}]\n[effect.params]\n",
            a.effect.id(),
            a.joints.iter().map(|j| format!("\"{j}\"")).collect::<Vec<_>>().join(", ")
        ));
        for (d, v) in a.effect.params().iter().zip(&a.params) {
            s.push_str(&format!("{} = {v}\n", d.name));
        }
        s.push('\n');
    }
    s
}
