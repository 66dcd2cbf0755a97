//! The synth's own writer: `OUT/episodes/ep_NN.csv` (the recording format of
//! docs/recording-format.md), `OUT/truth_commands/ep_NN.csv` (the exact command of every
//! control tick) and `OUT/truth.json` (the answer key). Deterministic: the same dataset gives the
//! same bytes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use super::{Dataset, Episode, Floor};

/// Digits of the position/command columns (quantised values stay exact multiples of the quantum
/// to ~1e-10 rad).
const QD: usize = 10;

/// File stem of episode `i` (`ep_00`; wider when there are more than 100 episodes).
pub fn stem(i: usize, n: usize) -> String {
    let w = (n.saturating_sub(1)).to_string().len().max(2);
    format!("ep_{i:0w$}")
}

/// `v` with `digits` decimals; a negative value that rounds to zero is written without sign.
fn num(v: f64, digits: usize) -> String {
    let s = format!("{v:.digits$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => s,
    }
}

fn secs(us: i64) -> String {
    let sign = if us < 0 { "-" } else { "" };
    let a = us.unsigned_abs();
    format!("{sign}{}.{:06}", a / 1_000_000, a % 1_000_000)
}

/// One episode as CSV text.
pub fn episode_csv(ds: &Dataset, ep: &Episode) -> String {
    let s = &ds.settings;
    let mut o = String::new();
    o.push_str("# format: modellint-recording 1\n");
    let _ = writeln!(o, "# robot: {}", ds.robot);
    let _ = writeln!(o, "# episode: {}", ep.index);
    let _ = writeln!(o, "# split: {}", if ep.heldout { "heldout" } else { "train" });
    let _ = writeln!(o, "# control_rate_hz: {}", s.control_hz);
    let _ = writeln!(o, "# control_t0_s: {}", ds.control_t0_s);
    let _ = writeln!(
        o,
        "# base: {}",
        if ds.base.is_some() { "recorded (test stand)" } else { "fixed" }
    );
    o.push_str("# units: rad, rad/s\n");
    o.push_str(
        "# generator: modellint synth (simulated logging setup; answers in ../truth.json)\n",
    );
    o.push('t');
    for j in &ds.joints {
        let _ = write!(o, ",{j}.q,{j}.qd,{j}.q_cmd");
    }
    if ds.base.is_some() {
        o.push_str(",base.x,base.y,base.z,base.qw,base.qx,base.qy,base.qz");
    }
    o.push('\n');
    let base: Option<String> =
        ds.base.map(|b| b.iter().map(|v| format!(",{}", num(*v, 9))).collect());
    for (i, &t) in ep.t_us.iter().enumerate() {
        o.push_str(&secs(t));
        for j in 0..ds.joints.len() {
            let _ = write!(
                o,
                ",{},{},{}",
                num(ep.q[j][i], QD),
                num(ep.qd[j][i], 6),
                num(ep.q_cmd[j][i], QD)
            );
        }
        if let Some(b) = &base {
            o.push_str(b);
        }
        o.push('\n');
    }
    o
}

/// The exact command of every control tick of one episode.
pub fn commands_csv(ds: &Dataset, ep: &Episode) -> String {
    let c = &ep.commands;
    let mut o = String::from(
        "# the exact command of each control tick k, in force over [t_k, t_k+1) (t_k = control_t0_s + k / control_rate_hz, rounded to 1 µs)\n",
    );
    o.push_str("tick,t");
    for j in &ds.joints {
        let _ = write!(o, ",{j}.q_cmd");
    }
    o.push('\n');
    for (i, row) in c.cmd.iter().enumerate() {
        let k = c.first + i as i64;
        let _ = write!(o, "{k},{}", secs(c.clock.tick_us(k)));
        for v in row {
            let _ = write!(o, ",{}", num(*v, QD));
        }
        o.push('\n');
    }
    o
}

fn floor_json(joints: &[String], f: &[Floor]) -> Value {
    let mut m = serde_json::Map::new();
    for (j, x) in joints.iter().zip(f) {
        m.insert(j.clone(), json!({"mae_rad": x.mae, "rmse_rad": x.rmse, "rows": x.n}));
    }
    Value::Object(m)
}

/// The answer key.
pub fn truth_json(ds: &Dataset) -> String {
    let s = &ds.settings;
    let n = ds.episodes.len();
    let effects: Vec<Value> = ds
        .hidden
        .iter()
        .map(|h| {
            let mut p = serde_json::Map::new();
            for (name, v) in super::truth::param_names(h.effect).iter().zip(&h.params) {
                p.insert(name.to_string(), json!(v));
            }
            json!({"effect": h.effect, "joint": h.joint, "params": Value::Object(p)})
        })
        .collect();
    let file = |dir: &str, e: &Episode| format!("{dir}/{}.csv", stem(e.index, n));
    let episodes: Vec<Value> = ds
        .episodes
        .iter()
        .map(|e| {
            json!({
                "file": file("episodes", e),
                "commands": file("truth_commands", e),
                "split": if e.heldout { "heldout" } else { "train" },
                "seconds": s.duration_s,
                "samples": e.samples,
                "rows": e.t_us.len(),
                "dropped": e.dropped,
                "segments": e.segments.iter().map(|g| json!({"kind": g.kind.label(), "t0": g.t0, "t1": g.t1})).collect::<Vec<_>>(),
                "floor": floor_json(&ds.joints, &e.floor),
            })
        })
        .collect();
    let v = json!({
        "schema": "modellint-synth-truth/1",
        "generator": "modellint synth: its own MuJoCo loop, controller and recorder clocks; shares no replay code with gap/fit",
        "model": ds.model_path.display().to_string(),
        "recorded_joints": ds.joints,
        "effects": effects,
        "effect_notes": {
            "position_offset": "sensor offset: recorded q = true q + offset; the servo acts on the true angle",
            "armature, viscous_damping, coulomb_friction, joint_stiffness": "absolute values written to the model copy (dof_armature, dof_damping, dof_frictionloss, jnt_stiffness with the spring reference at the keyframe)",
            "action_delay": "the servo sees the zero-order-hold command delayed by delay_s (sub-step exact)",
        },
        "timing": {
            "control_rate_hz": s.control_hz,
            "control_t0_s": ds.control_t0_s,
            "sample_hz": s.sample_hz,
            "jitter": s.jitter,
            "log_at_ticks": s.log_at_ticks,
            "settle_s": s.settle_s,
            "jitter_note": "sample period = (1/sample_hz)·(1 + U(−jitter, jitter)), first row at t = 0 (end of the settle); times on a 1 µs clock",
            "q_cmd_note": "each row logs the command in force at its time: tick floor((t − control_t0_s)·control_rate_hz); a row exactly at a tick carries that tick",
            "state_note": "q, qd at a row: linear interpolation between the two bracketing physics steps",
        },
        "noise": {
            "q_noise_rad": s.noise,
            "quant_bits": s.quant_bits,
            "q_quantum_rad": s.quantum(),
            "qd_noise_rad_s": s.qd_noise,
            "drop_prob": s.drop,
            "q_note": "q = round((q_true + offset + noise) / quantum) · quantum",
        },
        "floor": floor_json(&ds.joints, &ds.floor),
        "floor_note": "MAE and RMSE of recorded q − (true q + offset) over the kept rows: what a perfect model can reach",
        "excitation": {
            "kind": s.excitation.label(),
            "amplitude_rad": s.amplitude,
            "hold_s": super::excitation::HOLD_S,
            "step_rise_s": super::excitation::RISE_S,
            "chirp_hz": [super::excitation::CHIRP_HZ.0, super::excitation::CHIRP_HZ.1],
            "chirp_corner_hz": super::excitation::CHIRP_CORNER_HZ,
        },
        "suspend_m": s.suspend_m,
        "base_pose": ds.base,
        "seed": s.seed,
        "episodes": episodes,
        "split": {
            "train": ds.episodes.iter().filter(|e| !e.heldout).map(|e| file("episodes", e)).collect::<Vec<_>>(),
            "heldout": ds.episodes.iter().filter(|e| e.heldout).map(|e| file("episodes", e)).collect::<Vec<_>>(),
        },
    });
    let mut t = serde_json::to_string_pretty(&v).unwrap_or_default();
    t.push('\n');
    t
}

/// Writes the dataset under `out`; returns the episode files.
pub fn write(ds: &Dataset, out: &Path) -> Result<Vec<PathBuf>, String> {
    let n = ds.episodes.len();
    let mk = |p: &Path| {
        std::fs::create_dir_all(p).map_err(|e| format!("cannot create {}: {e}", p.display()))
    };
    let put = |p: &Path, text: &str| {
        std::fs::write(p, text).map_err(|e| format!("cannot write {}: {e}", p.display()))
    };
    let (eps, cmds) = (out.join("episodes"), out.join("truth_commands"));
    mk(&eps)?;
    mk(&cmds)?;
    let mut files = Vec::new();
    for e in &ds.episodes {
        let name = format!("{}.csv", stem(e.index, n));
        let p = eps.join(&name);
        put(&p, &episode_csv(ds, e))?;
        put(&cmds.join(&name), &commands_csv(ds, e))?;
        files.push(p);
    }
    put(&out.join("truth.json"), &truth_json(ds))?;
    Ok(files)
}

#[cfg(test)]
mod tests {
    #[test]
    fn time_formatting_is_exact() {
        assert_eq!(super::secs(0), "0.000000");
        assert_eq!(super::secs(10_903), "0.010903");
        assert_eq!(super::secs(9_991_817), "9.991817");
        assert_eq!(super::secs(-6_000), "-0.006000");
        assert_eq!(super::stem(3, 4), "ep_03");
        assert_eq!(super::num(-1e-13, 10), "0.0000000000");
        assert_eq!(super::num(-0.0, 6), "0.000000");
        assert_eq!(super::num(-0.25, 3), "-0.250");
        assert_eq!(super::stem(3, 1000), "ep_003");
    }
}
