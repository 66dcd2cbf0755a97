//! Importer for the servo logs of Rhoban's BAM project (JSON, one Dynamixel servo swinging a
//! pendulum): top-level `mass` [kg], `length` [m], `kp` (firmware units), `vin` [V], `motor`,
//! `trajectory`, and `entries`, each with `timestamp` [s], `position` [rad], `speed` [rad/s],
//! `goal_position` [rad], `torque_enable` (bool), `load` (raw register), `input_volts`, `temp`.
//!
//! The log becomes a [`Recording`] with one joint named [`BAM_JOINT`]: `position` → `q`,
//! `speed` → `qd`, `goal_position` → `q_cmd`, `torque_enable` → `enabled`. `load` is a raw
//! register of unspecified units and is not imported. Timestamps are kept as given and must be
//! strictly increasing; an entry that exactly repeats the previous one (every field equal) is
//! dropped and counted in meta `dropped_duplicates`; two entries with the same timestamp but
//! different data are an error naming the entry index.
//!
//! [`bam_recording`] makes a log replayable: the firmware P gain converted to N·m/rad with the
//! XL330 constants ([`xl330_kp_si`]) as a `servo.kp` column.

use super::recording::{JointTrace, ParseOptions, Recording, RecordingError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Name of the single joint of an imported BAM log.
pub const BAM_JOINT: &str = "servo";

/// A BAM log: the rig description and the recording.
#[derive(Debug, Clone, Serialize)]
pub struct BamLog {
    pub mass: f64,
    pub length: f64,
    pub kp: f64,
    pub vin: f64,
    pub motor: String,
    pub trajectory: String,
    pub recording: Recording,
}

#[derive(Deserialize)]
struct RawLog {
    mass: f64,
    length: f64,
    kp: f64,
    vin: f64,
    motor: String,
    trajectory: String,
    entries: Vec<RawEntry>,
}

#[derive(Deserialize, PartialEq)]
struct RawEntry {
    timestamp: f64,
    position: f64,
    speed: f64,
    /// The servo's command. Optional here so that a log without it is named as such (an
    /// error at the entry for `gap` / `fit` unless `--no-command`), not as "not a BAM log".
    #[serde(default)]
    goal_position: Option<f64>,
    torque_enable: BoolLike,
    // Not imported, only compared when looking for exact duplicates.
    #[serde(default)]
    load: Option<f64>,
    #[serde(default)]
    input_volts: Option<f64>,
    #[serde(default)]
    temp: Option<f64>,
}

#[derive(Deserialize, PartialEq, Clone, Copy)]
#[serde(untagged)]
enum BoolLike {
    Bool(bool),
    Num(f64),
}

impl BoolLike {
    fn get(self) -> bool {
        match self {
            BoolLike::Bool(b) => b,
            BoolLike::Num(x) => x != 0.0,
        }
    }
}

/// Cheap sniff: does this text look like a BAM log (a JSON object with `entries` holding
/// `timestamp` and `goal_position`, or `timestamp`, `position` and `torque_enable`: a log
/// whose command key is missing is still read as one, and said so)? Does not validate.
pub fn is_bam_json(text: &str) -> bool {
    let t = text.trim_start_matches('\u{feff}').trim_start();
    t.starts_with('{')
        && t.contains("\"entries\"")
        && t.contains("\"timestamp\"")
        && (t.contains("\"goal_position\"")
            || (t.contains("\"position\"") && t.contains("\"torque_enable\"")))
}

/// The 1-based line of entry `i` of a BAM log's `entries` (the line of its `timestamp` key),
/// for error messages; `None` when the text does not show it.
pub fn entry_line(text: &str, i: usize) -> Option<usize> {
    entry_lines(text).get(i).copied()
}

/// The 1-based line of every entry's `timestamp` key after `entries`, in one pass.
fn entry_lines(text: &str) -> Vec<usize> {
    let Some(start) = text.find("\"entries\"") else { return Vec::new() };
    let mut line = 1 + text[..start].matches('\n').count();
    let mut at = start;
    let mut out = Vec::new();
    for (k, _) in text[start..].match_indices("\"timestamp\"") {
        line += text[at..start + k].matches('\n').count();
        at = start + k;
        out.push(line);
    }
    out
}

pub fn read_bam(path: &Path) -> Result<BamLog, RecordingError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| RecordingError::new(path, None, None, format!("cannot read file: {e}")))?;
    parse_bam(path, &text)
}

pub fn parse_bam(path: &Path, text: &str) -> Result<BamLog, RecordingError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines = entry_lines(text);
    let at = |i: usize, msg: String| RecordingError::new(path, lines.get(i).copied(), None, msg);
    if text.trim().is_empty() {
        return Err(RecordingError::new(path, Some(1), None, "empty file"));
    }
    let raw: RawLog = serde_json::from_str(text).map_err(|e| {
        RecordingError::new(path, Some(e.line().max(1)), None, format!("not a BAM log: {e}"))
    })?;
    let mut t = Vec::with_capacity(raw.entries.len());
    let mut q = Vec::with_capacity(raw.entries.len());
    let mut qd = Vec::with_capacity(raw.entries.len());
    let mut q_cmd = Vec::with_capacity(raw.entries.len());
    let mut enabled = Vec::with_capacity(raw.entries.len());
    // The line of each entry kept (exact duplicates are dropped), for the recording's checks.
    let mut kept_lines = Vec::with_capacity(raw.entries.len());
    let mut dropped = 0usize;
    for (i, e) in raw.entries.iter().enumerate() {
        if i > 0 {
            let prev = &raw.entries[i - 1];
            if e == prev {
                dropped += 1;
                continue;
            }
            if e.timestamp == prev.timestamp {
                return Err(at(
                    i,
                    format!("entries {} and {i} share timestamp {} but differ", i - 1, e.timestamp),
                ));
            }
            if e.timestamp < prev.timestamp {
                return Err(at(
                    i,
                    format!(
                        "timestamp not increasing: entry {i} has {} after entry {} with {}",
                        e.timestamp,
                        i - 1,
                        prev.timestamp
                    ),
                ));
            }
        }
        kept_lines.push(lines.get(i).copied().unwrap_or(0));
        t.push(e.timestamp);
        q.push(e.position);
        qd.push(e.speed);
        if let Some(g) = e.goal_position {
            q_cmd.push(g);
        }
        enabled.push(e.torque_enable.get());
    }
    let mut meta = BTreeMap::new();
    meta.insert("source_format".to_string(), "bam".to_string());
    meta.insert("mass".to_string(), raw.mass.to_string());
    meta.insert("length".to_string(), raw.length.to_string());
    meta.insert("kp".to_string(), raw.kp.to_string());
    meta.insert("vin".to_string(), raw.vin.to_string());
    meta.insert("motor".to_string(), raw.motor.clone());
    meta.insert("trajectory".to_string(), raw.trajectory.clone());
    if dropped > 0 {
        meta.insert("dropped_duplicates".to_string(), dropped.to_string());
    }
    // Every entry has its command, or none has (then the joint has no command: `gap` / `fit`
    // decide, as for a CSV without `q_cmd`); some without it is an error at the first.
    let with_cmd = raw.entries.iter().filter(|e| e.goal_position.is_some()).count();
    if with_cmd != 0 && with_cmd != raw.entries.len() {
        let i = raw.entries.iter().position(|e| e.goal_position.is_none()).unwrap_or(0);
        return Err(at(
            i,
            format!(
                "entry {i} has no 'goal_position' (the servo's command), while {with_cmd} of the \
                 {} entries have one",
                raw.entries.len()
            ),
        ));
    }
    let mut joint = JointTrace::new(BAM_JOINT, q);
    joint.qd = Some(qd);
    joint.q_cmd = (with_cmd > 0).then_some(q_cmd);
    joint.enabled = Some(enabled);
    let recording = Recording {
        source: path.to_path_buf(),
        meta,
        control_rate_hz: None,
        control_t0_s: None,
        t,
        joints: vec![joint],
        base: None,
    };
    // Lines only when every kept entry's line is known (the text shows one `timestamp` key
    // per entry).
    let known = lines.len() == raw.entries.len();
    recording.check_at_lines(&ParseOptions::default(), known.then_some(&kept_lines[..]))?;
    Ok(BamLog {
        mass: raw.mass,
        length: raw.length,
        kp: raw.kp,
        vin: raw.vin,
        motor: raw.motor,
        trajectory: raw.trajectory,
        recording,
    })
}

/// XL330 constants (BAM project's first-order fit) for the firmware P-gain conversion.
pub const XL330_KT: f64 = 0.387;
pub const XL330_R: f64 = 4.02;
/// Dynamixel position-error gain: (4096 / 2π) / (256 · 885) duty per rad per firmware kp unit.
pub const XL330_ERROR_GAIN: f64 = (4096.0 / (2.0 * std::f64::consts::PI)) / (256.0 * 885.0);

/// Firmware P gain → N·m/rad: K = kp · error_gain · vin · kt / R.
pub fn xl330_kp_si(kp_firmware: f64, vin: f64) -> f64 {
    kp_firmware * XL330_ERROR_GAIN * vin * XL330_KT / XL330_R
}

/// A BAM log as a replayable recording: a constant `servo.kp` column in N·m/rad (see
/// [`xl330_kp_si`]), meta `kp_si` and the motor constants behind it (`motor_kt`, `motor_r`).
/// No control rate: the servo takes each goal as it arrives,
/// so the replay holds each goal from its own timestamp on.
pub fn bam_recording(log: BamLog) -> Recording {
    let mut rec = log.recording;
    let k = xl330_kp_si(log.kp, log.vin);
    let n = rec.t.len();
    if let Some(j) = rec.joints.iter_mut().find(|j| j.name == BAM_JOINT) {
        j.kp = Some(vec![k; n]);
    }
    rec.meta.insert("kp_si".into(), format!("{k}"));
    // The motor behind the linear law (the `motor_constants` effect's supply clip and refit).
    rec.meta.insert("motor_kt".into(), format!("{XL330_KT}"));
    rec.meta.insert("motor_r".into(), format!("{XL330_R}"));
    rec.control_rate_hz = None;
    rec
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// `$MODELLINT_SHARED_DATA`, else `<crate>/../shared/data`.
    fn shared_data() -> Option<PathBuf> {
        let dir = std::env::var_os("MODELLINT_SHARED_DATA")
            .map(PathBuf::from)
            .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
        dir.is_dir().then_some(dir)
    }

    fn entry(t: f64, q: f64) -> String {
        format!(
            r#"{{"position": {q}, "speed": 0.5, "load": 65530, "input_volts": 7.3, "temp": 28, "timestamp": {t}, "goal_position": 0.1, "torque_enable": true}}"#
        )
    }

    fn log(entries: &[String]) -> String {
        format!(
            r#"{{"mass": 0.49, "length": 0.1, "kp": 400, "vin": 7.4, "motor": "xl330", "trajectory": "sin_sin", "entries": [{}]}}"#,
            entries.join(", ")
        )
    }

    #[test]
    fn parses_synthetic_log() {
        let text = log(&[entry(0.0035, -0.003), entry(0.0087, -0.0015), entry(0.0139, 0.0)]);
        assert!(is_bam_json(&text));
        let b = parse_bam(Path::new("x.json"), &text).expect("parses");
        assert_eq!((b.mass, b.length, b.kp, b.vin), (0.49, 0.1, 400.0, 7.4));
        assert_eq!((b.motor.as_str(), b.trajectory.as_str()), ("xl330", "sin_sin"));
        let r = &b.recording;
        assert_eq!(r.t, vec![0.0035, 0.0087, 0.0139]);
        let j = r.joint(BAM_JOINT).expect("servo joint");
        assert_eq!(j.q, vec![-0.003, -0.0015, 0.0]);
        assert_eq!(j.qd, Some(vec![0.5; 3]));
        assert_eq!(j.q_cmd, Some(vec![0.1; 3]));
        assert_eq!(j.enabled, Some(vec![true; 3]));
        assert!(j.tau.is_none());
        assert_eq!(r.meta.get("kp").map(String::as_str), Some("400"));
        assert_eq!(r.meta.get("trajectory").map(String::as_str), Some("sin_sin"));
        assert!(!r.meta.contains_key("dropped_duplicates"));
    }

    #[test]
    fn duplicates_dropped_conflicts_and_disorder_rejected() {
        let p = Path::new("x.json");
        let text = log(&[entry(0.0, 0.0), entry(0.005, 0.1), entry(0.005, 0.1), entry(0.01, 0.2)]);
        let b = parse_bam(p, &text).expect("parses");
        assert_eq!(b.recording.t.len(), 3);
        assert_eq!(b.recording.meta.get("dropped_duplicates").map(String::as_str), Some("1"));
        let text = log(&[entry(0.0, 0.0), entry(0.005, 0.1), entry(0.005, 0.2)]);
        let e = parse_bam(p, &text).expect_err("conflict");
        assert!(e.message.contains("entries 1 and 2 share timestamp 0.005"), "{e}");
        let text = log(&[entry(0.0, 0.0), entry(0.005, 0.1), entry(0.004, 0.2)]);
        let e = parse_bam(p, &text).expect_err("disorder");
        assert!(e.message.contains("entry 2"), "{e}");
        let e = parse_bam(p, &log(&[entry(0.0, 0.0)])).expect_err("too short");
        assert!(e.message.contains("at least 2"), "{e}");
        let e = parse_bam(p, "{\"mass\": 1,\n \"entries\": []}").expect_err("missing fields");
        assert!(e.message.contains("missing field"), "{e}");
        assert!(parse_bam(p, "{\"mass\": ").is_err());
        assert!(!is_bam_json("t,a.q\n0,1\n"));
    }

    /// One entry per line: errors about an entry, and the recording's checks, name its line;
    /// entries without `goal_position` give a joint without a command, some without it an error.
    #[test]
    fn errors_name_the_entry_line() {
        let p = Path::new("x.json");
        let lines = |e: &[String]| {
            format!(
                "{{\"mass\": 0.49, \"length\": 0.1, \"kp\": 400, \"vin\": 7.4, \"motor\": \"xl330\", \"trajectory\": \"s\", \"entries\": [\n{}\n]}}",
                e.join(",\n")
            )
        };
        let e = parse_bam(p, &lines(&[entry(0.0, 0.0), entry(0.005, 0.1), entry(0.004, 0.2)]))
            .expect_err("disorder");
        assert_eq!(e.line, Some(4), "{e}");
        let mut far: Vec<String> = (0..20).map(|i| entry(0.005 * i as f64, 0.0)).collect();
        far.push(entry(1e12, 0.0));
        let e = parse_bam(p, &lines(&far)).expect_err("a time far from the others");
        assert_eq!(e.line, Some(22), "{e}");
        let no_goal: Vec<String> = (0..3)
            .map(|i| entry(0.005 * i as f64, 0.0).replace(", \"goal_position\": 0.1", ""))
            .collect();
        let text = lines(&no_goal);
        assert!(is_bam_json(&text));
        let b = parse_bam(p, &text).expect("parses");
        assert!(b.recording.joints[0].q_cmd.is_none());
        let mut some = no_goal.clone();
        some[0] = entry(0.0, 0.0);
        let e = parse_bam(p, &lines(&some)).expect_err("some without goal_position");
        assert_eq!(e.line, Some(3), "{e}");
        assert!(e.message.contains("entry 1 has no 'goal_position'"), "{e}");
    }

    #[test]
    fn all_real_logs_load() {
        let Some(data) = shared_data() else {
            eprintln!("skipping: ../shared absent (set MODELLINT_SHARED_DATA)");
            return;
        };
        let dir = data.join("recordings/bam_xl330");
        let mut files: Vec<PathBuf> = match std::fs::read_dir(&dir) {
            Ok(rd) => rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "json"))
                .collect(),
            Err(e) => panic!("{}: {e}", dir.display()),
        };
        files.sort();
        assert_eq!(files.len(), 16, "expected 16 BAM logs in {}", dir.display());
        let mut kps = std::collections::BTreeSet::new();
        for f in &files {
            let text = std::fs::read_to_string(f).expect("readable");
            assert!(is_bam_json(&text), "{}", f.display());
            let b = read_bam(f).unwrap_or_else(|e| panic!("{e}"));
            let r = &b.recording;
            assert!(r.t.len() > 1000, "{}: {} samples", f.display(), r.t.len());
            assert!((r.duration() - 6.0).abs() < 0.1, "{}: duration {}", f.display(), r.duration());
            assert_eq!((b.mass, b.length, b.vin, b.motor.as_str()), (0.49, 0.1, 7.4, "xl330"));
            kps.insert(b.kp as i64);
            let j = r.joint(BAM_JOINT).expect("servo");
            assert!(j.q.iter().all(|x| x.abs() < 4.0));
            if b.trajectory == "lift_and_drop" {
                assert!(
                    j.enabled.as_ref().is_some_and(|e| e.iter().any(|x| !x)),
                    "torque goes off"
                );
            }
        }
        assert_eq!(kps.into_iter().collect::<Vec<_>>(), vec![100, 200, 400, 800]);
    }

    #[test]
    fn firmware_gain_matches_the_rig_actuator() {
        // fixtures/bam_xl330/rig.xml: gainprm = 0.8199237503 for kp 400, vin 7.4.
        assert!((xl330_kp_si(400.0, 7.4) - 0.8199237503).abs() < 1e-9);
        assert!((xl330_kp_si(800.0, 7.4) - 2.0 * 0.8199237503).abs() < 1e-9);
    }
}
