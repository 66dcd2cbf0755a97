//! `modellint synth`, the independent simulated logging setup. Expected answers are built
//! independently: the command of each row is recomputed from `truth_commands` with the
//! documented rule floor((t − t0)·rate); the physics is checked against closed-form second-order
//! responses of a hand-written one-hinge model; the logging statistics against the settings and
//! against `independent_arm2` (a separate Python simulator).

use std::path::{Path, PathBuf};
use std::process::Command;

use modellint::model::{Robot, source::SourceMap};
use modellint::synth::clock::{Commands, ControlClock};
use modellint::synth::{sim, truth};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d =
        std::env::temp_dir().join(format!("modellint_synth_test_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn synth(model: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg("synth")
        .arg(model)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap()
}

/// A CSV read by hand: `# key: value` metadata, header, rows as strings.
struct Csv {
    meta: Vec<(String, String)>,
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Csv {
    fn read(p: &Path) -> Csv {
        let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let mut meta = Vec::new();
        let mut header = Vec::new();
        let mut rows = Vec::new();
        for l in text.lines() {
            if let Some(m) = l.strip_prefix('#') {
                if let Some((k, v)) = m.split_once(':') {
                    meta.push((k.trim().to_string(), v.trim().to_string()));
                }
            } else if header.is_empty() {
                header = l.split(',').map(str::to_string).collect();
            } else {
                rows.push(l.split(',').map(str::to_string).collect());
            }
        }
        Csv { meta, header, rows }
    }
    fn meta(&self, k: &str) -> Option<&str> {
        self.meta.iter().find(|(a, _)| a == k).map(|(_, v)| v.as_str())
    }
    fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }
    fn f(&self, i: usize, c: usize) -> f64 {
        self.rows[i][c].parse().unwrap()
    }
    fn column(&self, name: &str) -> Vec<f64> {
        let c = self.col(name);
        (0..self.rows.len()).map(|i| self.f(i, c)).collect()
    }
}

const ARM3: &str = "fixtures/gap/arm3.xml";
const ARM3_JOINTS: [&str; 3] = ["shoulder_pitch", "elbow_pitch", "wrist_pitch"];

/// Checks every row's q_cmd against the truth commands: the row at t carries tick
/// floor((t − t0)·rate) (exact decimal strings).
fn check_commands(out: &Path, ep: &str) -> (usize, f64, f64) {
    let rec = Csv::read(&out.join("episodes").join(ep));
    let cmd = Csv::read(&out.join("truth_commands").join(ep));
    let rate: f64 = rec.meta("control_rate_hz").unwrap().parse().unwrap();
    let t0: f64 = rec.meta("control_t0_s").unwrap().parse().unwrap();
    let first: i64 = cmd.rows[0][0].parse().unwrap();
    let mut checked = 0;
    for (i, row) in rec.rows.iter().enumerate() {
        let t: f64 = row[0].parse().unwrap();
        let k = ((t - t0) * rate + 1e-9).floor() as i64;
        let crow = &cmd.rows[(k - first) as usize];
        assert_eq!(crow[0].parse::<i64>().unwrap(), k);
        for j in ARM3_JOINTS {
            assert_eq!(
                row[rec.col(&format!("{j}.q_cmd"))],
                crow[cmd.col(&format!("{j}.q_cmd"))],
                "{ep} row {i} t {t}: tick {k}"
            );
        }
        checked += 1;
    }
    (checked, rate, t0)
}

#[test]
fn every_row_logs_the_command_in_force() {
    let out = tmp("cmd");
    let o = synth(
        &root().join(ARM3),
        &out,
        &["--episodes", "2", "--duration", "3", "--control-phase", "0.0043"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let (n, rate, t0) = check_commands(&out, "ep_00.csv");
    assert!(n > 250, "{n} rows");
    assert_eq!((rate, t0), (100.0, 0.0043));
    // The tick −1 (before t0) exists and holds the settle command.
    let cmd = Csv::read(&out.join("truth_commands/ep_01.csv"));
    assert_eq!(cmd.rows[0][0], "-1");
    assert_eq!(cmd.rows[1][1], "0.004300");
    check_commands(&out, "ep_01.csv");
    // Commands change between ticks (the check above is not vacuous).
    let c = cmd.column("elbow_pitch.q_cmd");
    assert!(c.windows(2).filter(|w| w[0] != w[1]).count() > 50);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn log_at_ticks_rows_carry_their_tick() {
    let out = tmp("ticks");
    let o = synth(
        &root().join(ARM3),
        &out,
        &[
            "--episodes",
            "2",
            "--duration",
            "2",
            "--log-at-ticks",
            "--control-hz",
            "50",
            "--drop",
            "0",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let rec = Csv::read(&out.join("episodes/ep_00.csv"));
    let cmd = Csv::read(&out.join("truth_commands/ep_00.csv"));
    assert_eq!(rec.rows.len(), 100);
    for (k, row) in rec.rows.iter().enumerate() {
        assert_eq!(row[0], format!("{:.6}", k as f64 * 0.02));
        assert_eq!(
            row[rec.col("elbow_pitch.q_cmd")],
            cmd.rows[k][cmd.col("elbow_pitch.q_cmd")],
            "row {k}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn sampling_quantisation_and_drops_follow_the_settings() {
    let out = tmp("stats");
    let o = synth(
        &root().join(ARM3),
        &out,
        &[
            "--episodes",
            "3",
            "--duration",
            "20",
            "--sample-hz",
            "200",
            "--jitter",
            "0.3",
            "--drop",
            "0.1",
            "--quant-bits",
            "10",
            "--heldout",
            "2",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap()).unwrap();
    let quantum = std::f64::consts::TAU / 1024.0;
    let (mut rows, mut samples, mut dropped) = (0usize, 0usize, 0usize);
    let mut gaps = 0usize;
    for (e, split) in [(0, "train"), (1, "heldout"), (2, "heldout")] {
        let rec = Csv::read(&out.join(format!("episodes/ep_0{e}.csv")));
        assert_eq!(rec.meta("split"), Some(split));
        let t = rec.column("t");
        assert_eq!(t[0], 0.0);
        let period = 1.0 / 200.0;
        for w in t.windows(2) {
            let d = w[1] - w[0];
            // One period ±30 %, or m + 1 of them when m rows were dropped.
            let fits = |m: f64| d >= m * 0.7 * period - 2e-6 && d <= m * 1.3 * period + 2e-6;
            assert!((1..=6).any(|m| fits(m as f64)), "interval {d}");
            if d > 1.3 * period + 2e-6 {
                gaps += 1;
            }
        }
        for j in ARM3_JOINTS {
            for q in rec.column(&format!("{j}.q")) {
                let m = q / quantum;
                assert!((m - m.round()).abs() < 1e-6, "{q} is not a multiple of 2π/1024");
            }
        }
        let ep = &truth["episodes"][e];
        assert_eq!(ep["rows"].as_u64().unwrap() as usize, rec.rows.len());
        rows += rec.rows.len();
        samples += ep["samples"].as_u64().unwrap() as usize;
        dropped += ep["dropped"].as_u64().unwrap() as usize;
    }
    assert_eq!(samples, rows + dropped);
    // Mean rate 200 Hz: 3 × 20 s ≈ 12000 samples (±1 %).
    assert!((samples as f64 / 12000.0 - 1.0).abs() < 0.01, "{samples} samples");
    // Drops ~ Binomial(n, 0.1): within 4σ.
    let (n, p) = (samples as f64, 0.1);
    assert!(
        (dropped as f64 - n * p).abs() < 4.0 * (n * p * (1.0 - p)).sqrt(),
        "{dropped} of {samples} dropped"
    );
    assert!(gaps > dropped / 2, "{gaps} gaps for {dropped} drops");
    // Floor of a 10-bit encoder with 0.5 mrad noise: RMSE² ≈ σ² + Δ²/12 (exact for positions
    // spread evenly over the grid; holds and steps make it a few % lower).
    let expect = (0.0005f64.powi(2) + quantum * quantum / 12.0).sqrt();
    for j in ARM3_JOINTS {
        let r = truth["floor"][j]["rmse_rad"].as_f64().unwrap();
        assert!((r / expect - 1.0).abs() < 0.1, "{j}: floor RMSE {r} vs {expect}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn settle_starts_the_recording_at_rest_and_output_is_deterministic() {
    let out = tmp("settle");
    let args = [
        "--episodes",
        "1",
        "--duration",
        "1",
        "--noise",
        "0",
        "--qd-noise",
        "0",
        "--quant-bits",
        "0",
        "--drop",
        "0",
    ];
    let o = synth(&root().join(ARM3), &out, &args);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let rec = Csv::read(&out.join("episodes/ep_00.csv"));
    let t = rec.column("t");
    for j in ARM3_JOINTS {
        let (q, qd) = (rec.column(&format!("{j}.q")), rec.column(&format!("{j}.qd")));
        assert!(qd[0].abs() < 1e-4, "{j}: qd at start {}", qd[0]);
        // During the 0.3 s hold the joint stays at its settled position.
        for i in (0..t.len()).filter(|&i| t[i] < 0.29) {
            assert!((q[i] - q[0]).abs() < 1e-5, "{j} moved during the hold: {} → {}", q[0], q[i]);
        }
    }
    // The output directory is a dataset `gap` (and `fit`) read as it is: its episodes/, not
    // truth.json (which is no recording).
    let g = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg("gap")
        .arg(root().join(ARM3))
        .arg(&out)
        .args(["--format", "json"])
        .output()
        .unwrap();
    assert_eq!(g.status.code(), Some(0), "{}", String::from_utf8_lossy(&g.stderr));
    let gj: serde_json::Value = serde_json::from_slice(&g.stdout).unwrap();
    let text = gj.to_string();
    assert!(text.contains("ep_00.csv") && !text.contains("truth.json"), "{text}");
    let a = std::fs::read(out.join("episodes/ep_00.csv")).unwrap();
    let b = std::fs::read(out.join("truth.json")).unwrap();
    let out2 = tmp("settle2");
    assert_eq!(synth(&root().join(ARM3), &out2, &args).status.code(), Some(0));
    assert_eq!(a, std::fs::read(out2.join("episodes/ep_00.csv")).unwrap());
    assert_eq!(
        String::from_utf8_lossy(&b).replace(out.to_str().unwrap(), ""),
        String::from_utf8_lossy(&std::fs::read(out2.join("truth.json")).unwrap())
            .replace(out2.to_str().unwrap(), "")
    );
    for d in [out, out2] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn bad_values_exit_2_naming_the_flag() {
    let out = tmp("bad");
    for (args, flag) in [
        (vec!["--jitter", "1.5"], "--jitter"),
        (vec!["--control-hz", "0"], "--control-hz"),
        (vec!["--control-phase", "0.02"], "--control-phase"),
        (vec!["--sample-hz=-3"], "--sample-hz"),
        (vec!["--quant-bits", "40"], "--quant-bits"),
        (vec!["--drop", "0.9"], "--drop"),
        (vec!["--noise", "nan"], "--noise"),
        (vec!["--excitation", "sine"], "--excitation"),
        (vec!["--heldout", "4"], "--heldout"),
        (vec!["--duration", "0"], "--duration"),
        (vec!["--settle=-1"], "--settle"),
        (vec!["--effects", "bogus=1"], "--effects"),
        (vec!["--effects", "armature@nothing=0.1"], "--effects"),
        (vec!["--effects", "action_delay=-0.01"], "--effects"),
        (vec!["--joints", "nothing*"], "--joints"),
        (vec!["--suspend", "0.5"], "--suspend"),
    ] {
        let o = synth(&root().join(ARM3), &out, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?}: {err}");
    }
    assert!(!out.exists(), "nothing written on bad input");
    // A floating-base robot without a test stand would fall while the file says `base: fixed`
    // (the exact Asimov model 5° RMSE off its own clean recording): refused, with the fix.
    let o = synth(&root().join("models/asimov.xml"), &out, &["--episodes", "1"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("floating base") && err.contains("--suspend 0.5"), "{err}");
    assert!(!out.exists(), "nothing written for a floating base without --suspend");
    let h =
        Command::new(env!("CARGO_BIN_EXE_modellint")).args(["synth", "--help"]).output().unwrap();
    let h = String::from_utf8_lossy(&h.stdout);
    for k in ["--log-at-ticks", "--quant-bits", "command in", "truth.json", "effect[@joint_glob]"] {
        assert!(h.contains(k), "--help lacks {k}");
    }
}

// ---- closed-form physics of the synth's own loop ----

/// One hinge, no gravity: inertia I about the axis, a position servo kp/kv, optional armature.
fn hinge(name: &str, kp: f64, kv: f64, inertia: f64) -> Robot {
    let xml = format!(
        r#"<mujoco model="hinge">
  <compiler angle="radian"/>
  <option timestep="0.0001" gravity="0 0 0"/>
  <worldbody>
    <body name="link">
      <joint name="j" type="hinge" axis="0 1 0"/>
      <inertial pos="0 0 0" mass="1" diaginertia="{inertia} {inertia} {inertia}"/>
    </body>
  </worldbody>
  <actuator><position name="j" joint="j" kp="{kp}" kv="{kv}"/></actuator>
</mujoco>"#
    );
    let p = std::env::temp_dir().join(format!("modellint_synth_{}_{name}.xml", std::process::id()));
    std::fs::write(&p, xml).unwrap();
    let mut map = SourceMap::default();
    modellint::model::load(&mut map, &p, None).expect("hinge loads")
}

/// Step of `a` rad at t = 10 ms, sampled every 0.5 ms for 1.5 s; returns (t, q).
fn step_response(robot: &Robot, effects: &str, a: f64) -> (Vec<f64>, Vec<f64>) {
    let joints = vec!["j".to_string()];
    let hidden = truth::parse(effects, &joints).unwrap();
    let real = truth::real_robot(robot, &joints, &hidden).unwrap();
    let clock = ControlClock { rate_hz: 100.0, t0_us: 0 };
    let cmd: Vec<Vec<f64>> = (0..200).map(|k| vec![if k >= 1 { a } else { 0.0 }]).collect();
    let cmds = Commands { clock, first: 0, cmd };
    let samples: Vec<i64> = (0..3000).map(|i| i * 500).collect();
    let tr = sim::run(robot, &real, &cmds, &samples, 0.5, None).unwrap();
    (samples.iter().map(|&s| s as f64 * 1e-6).collect(), tr.q[0].clone())
}

/// Analytic underdamped step response of I·x'' + kv·x' + kp·x = kp·a (x(0) = x'(0) = 0).
fn analytic(t: f64, a: f64, kp: f64, kv: f64, inertia: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    let wn = (kp / inertia).sqrt();
    let z = kv / (2.0 * (kp * inertia).sqrt());
    let wd = wn * (1.0 - z * z).sqrt();
    a * (1.0 - (-z * wn * t).exp() * ((wd * t).cos() + z / (1.0 - z * z).sqrt() * (wd * t).sin()))
}

/// Times where x − a crosses zero upwards (linear interpolation).
fn up_crossings(t: &[f64], x: &[f64], a: f64) -> Vec<f64> {
    (1..t.len())
        .filter(|&i| x[i - 1] < a && x[i] >= a)
        .map(|i| t[i - 1] + (a - x[i - 1]) / (x[i] - x[i - 1]) * (t[i] - t[i - 1]))
        .collect()
}

#[test]
fn hinge_step_matches_the_second_order_response() {
    // I = 0.01, kp = 4, kv = 0.06: ωn = 20 rad/s, ζ = 0.15.
    let (kp, kv, i) = (4.0, 0.06, 0.01);
    let r = hinge("step", kp, kv, i);
    let (t, q) = step_response(&r, "none", 0.2);
    let mut worst: f64 = 0.0;
    for (tk, qk) in t.iter().zip(&q) {
        worst = worst.max((qk - analytic(tk - 0.01, 0.2, kp, kv, i)).abs());
    }
    assert!(worst < 0.002 * 0.2, "max deviation {worst} rad from the analytic response");
    // Overshoot exp(−ζπ/√(1−ζ²)) = 62.1 % for ζ = 0.15.
    let peak = q.iter().cloned().fold(f64::MIN, f64::max);
    assert!(((peak - 0.2) / 0.2 - 0.6209).abs() < 0.005, "overshoot {}", (peak - 0.2) / 0.2);
}

#[test]
fn action_delay_shifts_the_response_by_the_delay() {
    let (kp, kv, i) = (4.0, 0.06, 0.01);
    let r = hinge("delay", kp, kv, i);
    let d = 0.0137; // not a multiple of the 10 ms tick nor of the 0.1 ms step
    let (t, q) = step_response(&r, &format!("action_delay={d}"), 0.2);
    let mut worst: f64 = 0.0;
    for (tk, qk) in t.iter().zip(&q) {
        worst = worst.max((qk - analytic(tk - 0.01 - d, 0.2, kp, kv, i)).abs());
    }
    assert!(worst < 0.002 * 0.2, "delayed response off by {worst} rad");
    // And it is really shifted: the first up-crossing moves by d.
    let (t0, q0) = step_response(&r, "none", 0.2);
    let c0 = up_crossings(&t0, &q0, 0.2)[0];
    let c1 = up_crossings(&t, &q, 0.2)[0];
    assert!((c1 - c0 - d).abs() < 1e-4, "shift {} vs {d}", c1 - c0);
}

#[test]
fn armature_and_gain_error_change_the_natural_frequency() {
    // Undamped (kv 0): period 2π·√(I/kp); armature ΔI → ×√((I+ΔI)/I); kp × s → ×1/√s.
    let (kp, i) = (4.0, 0.01);
    let r = hinge("freq", kp, 0.0, i);
    let period = |eff: &str| {
        let (t, q) = step_response(&r, eff, 0.1);
        let c = up_crossings(&t, &q, 0.1);
        (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64
    };
    let p0 = period("none");
    let tp = std::f64::consts::TAU * (i / kp).sqrt();
    assert!((p0 / tp - 1.0).abs() < 0.002, "period {p0} vs {tp}");
    let pa = period("armature=0.0069");
    assert!((pa / p0 - ((i + 0.0069) / i).sqrt()).abs() < 0.003, "armature: ratio {}", pa / p0);
    let pg = period("gain_error=0.64,1");
    assert!((pg / p0 - 1.0 / 0.8).abs() < 0.003, "kp × 0.64: ratio {}", pg / p0);
}

#[test]
fn viscous_damping_gives_the_damping_ratio() {
    // kv 0, joint damping b = 0.04: ζ = b / (2√(kp·I)) = 0.1; log decrement of successive peaks
    // 2πζ/√(1−ζ²).
    let (kp, i) = (4.0, 0.01);
    let r = hinge("damp", kp, 0.0, i);
    let (t, q) = step_response(&r, "viscous_damping=0.04", 0.1);
    let peaks: Vec<f64> = (1..q.len() - 1)
        .filter(|&k| q[k] > q[k - 1] && q[k] >= q[k + 1] && t[k] > 0.01)
        .map(|k| q[k] - 0.1)
        .collect();
    let delta = (peaks[0] / peaks[1]).ln();
    let z = 0.1f64;
    let expect = std::f64::consts::TAU * z / (1.0 - z * z).sqrt();
    assert!((delta / expect - 1.0).abs() < 0.02, "log decrement {delta} vs {expect}");
}

#[test]
fn position_offset_is_a_sensor_bias() {
    // Noise-free, unquantised: every recorded q is the true q + offset; the truth file says so.
    let out = tmp("offset");
    let args = [
        "--episodes",
        "1",
        "--duration",
        "1",
        "--noise",
        "0",
        "--qd-noise",
        "0",
        "--quant-bits",
        "0",
        "--drop",
        "0",
    ];
    assert_eq!(synth(&root().join(ARM3), &out, &args).status.code(), Some(0));
    let out2 = tmp("offset2");
    assert_eq!(
        synth(
            &root().join(ARM3),
            &out2,
            &[&args[..], &["--effects", "position_offset@elbow*=0.05"]].concat()
        )
        .status
        .code(),
        Some(0)
    );
    let (a, b) =
        (Csv::read(&out.join("episodes/ep_00.csv")), Csv::read(&out2.join("episodes/ep_00.csv")));
    for (x, y) in a.column("elbow_pitch.q").iter().zip(b.column("elbow_pitch.q")) {
        assert!((y - x - 0.05).abs() < 1e-9);
    }
    assert_eq!(a.column("shoulder_pitch.q"), b.column("shoulder_pitch.q"));
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out2.join("truth.json")).unwrap()).unwrap();
    assert_eq!(truth["effects"][0]["effect"], "position_offset");
    assert_eq!(truth["effects"][0]["joint"], "elbow_pitch");
    assert_eq!(truth["effects"][0]["params"]["offset_rad"], 0.05);
    for d in [out, out2] {
        let _ = std::fs::remove_dir_all(d);
    }
}

// ---- cross-check against the independent simulator's arm2 data ----

fn arm2_dir() -> Option<PathBuf> {
    let d = root().join("../shared/data/recordings/independent_arm2");
    if d.join("arm2.none/episodes/ep_00.csv").exists() {
        Some(d)
    } else {
        eprintln!("skipping: {} is absent", d.display());
        None
    }
}

#[test]
fn arm2_settings_reproduce_the_independent_logging_statistics() {
    let Some(a) = arm2_dir() else { return };
    let out = tmp("arm2");
    let o = synth(&a.join("arm2.xml"), &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let stats = |dir: &Path| {
        let (mut rows, mut dts) = (0usize, Vec::new());
        let mut first = Vec::new();
        for e in 0..4 {
            let r = Csv::read(&dir.join(format!("episodes/ep_0{e}.csv")));
            let t = r.column("t");
            rows += t.len();
            dts.extend(t.windows(2).map(|w| w[1] - w[0]));
            first.push((r.f(0, r.col("shoulder.q")), r.f(0, r.col("elbow.q"))));
            assert_eq!(r.meta("split"), Some(if e == 3 { "heldout" } else { "train" }));
        }
        dts.sort_by(f64::total_cmp);
        (rows, dts[dts.len() / 2], dts[0], first)
    };
    let (n_ref, med_ref, min_ref, first_ref) = stats(&a.join("arm2.none"));
    let (n, med, min, first) = stats(&out);
    eprintln!(
        "arm2.none: {n_ref} rows, median interval {med_ref:.6} s, min {min_ref:.6}; synth: {n} rows, median {med:.6}, min {min:.6}"
    );
    assert!((n as f64 / n_ref as f64 - 1.0).abs() < 0.02, "rows {n} vs {n_ref}");
    assert!((med / med_ref - 1.0).abs() < 0.02, "median interval {med} vs {med_ref}");
    assert!((min / min_ref - 1.0).abs() < 0.02, "min interval {min} vs {min_ref}");
    // Both settle 2 s at the first command: the first recorded position (quantised) is the same
    // equilibrium under gravity, within one quantum + noise.
    for ((s, e), (sr, er)) in first.iter().zip(&first_ref) {
        assert!(
            (s - sr).abs() < 0.0035 && (e - er).abs() < 0.0035,
            "first row {s},{e} vs {sr},{er}"
        );
    }
    // Floor: 0.5 mrad noise + 12-bit quantisation ≈ 0.55 mrad MAE, 0.67 mrad RMSE (README).
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap()).unwrap();
    for j in ["shoulder", "elbow"] {
        let (mae, rmse) = (
            truth["floor"][j]["mae_rad"].as_f64().unwrap(),
            truth["floor"][j]["rmse_rad"].as_f64().unwrap(),
        );
        eprintln!("synth arm2 floor {j}: MAE {:.3} mrad, RMSE {:.3} mrad", 1e3 * mae, 1e3 * rmse);
        assert!(
            (mae / 0.00055 - 1.0).abs() < 0.06 && (rmse / 0.000669 - 1.0).abs() < 0.05,
            "{j}: {mae} / {rmse}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn arm2_commands_replayed_in_the_synth_loop_match_the_independent_recording() {
    // The independent simulator's exact per-tick commands, at its own sample times, through this
    // loop (settle, ZOH, interpolation): the difference from its recorded q must be at the
    // noise + quantisation floor (~0.55 mrad MAE) — the two simulators agree on the physics and
    // the timing convention.
    let Some(a) = arm2_dir() else { return };
    let mut map = SourceMap::default();
    let robot = modellint::model::load(&mut map, &a.join("arm2.xml"), None).unwrap();
    let joints = vec!["shoulder".to_string(), "elbow".to_string()];
    let real = truth::real_robot(&robot, &joints, &[]).unwrap();
    for ep in ["ep_00.csv", "ep_03.csv"] {
        let rec = Csv::read(&a.join("arm2.none/episodes").join(ep));
        let cmd = Csv::read(&a.join("arm2.none/truth_commands").join(ep));
        let cmds = Commands {
            clock: ControlClock { rate_hz: 100.0, t0_us: 0 },
            first: cmd.rows[0][0].parse().unwrap(),
            cmd: (0..cmd.rows.len())
                .map(|i| {
                    vec![cmd.f(i, cmd.col("shoulder.q_cmd")), cmd.f(i, cmd.col("elbow.q_cmd"))]
                })
                .collect(),
        };
        let t: Vec<i64> = rec.column("t").iter().map(|x| (x * 1e6).round() as i64).collect();
        let tr = sim::run(&robot, &real, &cmds, &t, 2.0, None).unwrap();
        for (k, j) in joints.iter().enumerate() {
            let q = rec.column(&format!("{j}.q"));
            let mae =
                q.iter().zip(&tr.q[k]).map(|(a, b)| (a - b).abs()).sum::<f64>() / q.len() as f64;
            eprintln!(
                "arm2.none {ep} {j}: synth loop vs independent recording MAE {:.3} mrad",
                1e3 * mae
            );
            assert!(mae < 0.00065, "{ep} {j}: MAE {mae}");
        }
    }
}

/// A one-hinge model with extra joint/actuator attributes written in the MJCF.
fn hinge_with(name: &str, joint_attrs: &str, act_attrs: &str) -> Robot {
    let xml = format!(
        r#"<mujoco model="hinge">
  <compiler angle="radian"/>
  <option timestep="0.001" gravity="0 0 0"/>
  <worldbody>
    <body name="link">
      <joint name="j" type="hinge" axis="0 1 0" {joint_attrs}/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
    </body>
  </worldbody>
  <actuator><position name="j" joint="j" {act_attrs}/></actuator>
</mujoco>"#
    );
    let p = std::env::temp_dir().join(format!("modellint_synth_{}_{name}.xml", std::process::id()));
    std::fs::write(&p, xml).unwrap();
    let mut map = SourceMap::default();
    modellint::model::load(&mut map, &p, None).expect("hinge loads")
}

#[test]
fn native_effects_equal_the_same_values_compiled_by_mujoco() {
    // Each MuJoCo-native hidden effect on the plain hinge must give the same trajectory as the
    // value written in the MJCF and compiled by MuJoCo (the independent reference), including
    // armature on a "simple" dof, where MuJoCo reads the compiled dof_M0.
    let s = modellint::synth::Settings {
        episodes: 1,
        duration_s: 3.0,
        noise: 0.0,
        qd_noise: 0.0,
        quant_bits: 0,
        drop: 0.0,
        heldout: 0,
        ..Default::default()
    };
    let joints = vec!["j".to_string()];
    let plain = hinge_with("plain", "", r#"kp="4" kv="0.06""#);
    let run = |r: &Robot, spec: &str| {
        let h = truth::parse(spec, &joints).unwrap();
        modellint::synth::generate(r, &joints, &h, &s, &|_, _| {}).unwrap().episodes[0].q_true[0]
            .clone()
    };
    let base = run(&plain, "none");
    for (spec, jattr, aattr) in [
        ("armature=0.0069", r#"armature="0.0069""#, r#"kp="4" kv="0.06""#),
        ("viscous_damping=0.05", r#"damping="0.05""#, r#"kp="4" kv="0.06""#),
        ("coulomb_friction=0.05", r#"frictionloss="0.05""#, r#"kp="4" kv="0.06""#),
        ("joint_stiffness=1.5", r#"stiffness="1.5""#, r#"kp="4" kv="0.06""#),
        ("gain_error=0.64,1.5", "", r#"kp="2.56" kv="0.09""#),
        ("torque_limit=0.3", "", r#"kp="4" kv="0.06" forcerange="-0.3 0.3""#),
    ] {
        let compiled = hinge_with("compiled", jattr, aattr);
        let want = run(&compiled, "none");
        let got = run(&plain, spec);
        let worst = want.iter().zip(&got).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let moved = want.iter().zip(&base).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-9, "{spec}: differs from the compiled model by {worst} rad");
        assert!(moved > 1e-3, "{spec}: the effect changes nothing ({moved} rad)");
    }
    // The per-step torque–speed clip (qfrc_applied) with a far velocity limit is MuJoCo's
    // forcerange up to the line's slope (|q̇|/1000 of the effort).
    let compiled = hinge_with("compiled", "", r#"kp="4" kv="0.06" forcerange="-0.3 0.3""#);
    let want = run(&compiled, "none");
    let got = run(&plain, "torque_limit=0.3,0.3,1000");
    let worst = want.iter().zip(&got).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let moved = want.iter().zip(&base).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(
        worst < 0.01 * moved,
        "per-step clip differs from forcerange by {worst} rad (effect size {moved})"
    );
}
