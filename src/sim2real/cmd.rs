//! `modellint gap` and `modellint convert`: input discovery, BAM import with the firmware-gain
//! conversion, replay of the dataset, output. Exit codes: 0 done, 1 done but some episode
//! diverged (excluded and listed), 2 could not do the job (nothing is printed as a result).

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use crate::sim2real::bam::{self, BAM_JOINT, BamLog};
use crate::sim2real::gap::{self, GapOptions, GapReport};
use crate::sim2real::recording::{self, Recording, RecordingError};
use crate::sim2real::replay::{self, BaseMode, ReplayOptions, Replayer};

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
/// [`xl330_kp_si`]) and meta `kp_si`. No control rate: the servo takes each goal as it arrives,
/// so the replay holds each goal from its own timestamp on.
pub fn bam_recording(log: BamLog) -> Recording {
    let mut rec = log.recording;
    let k = xl330_kp_si(log.kp, log.vin);
    let n = rec.t.len();
    if let Some(j) = rec.joints.iter_mut().find(|j| j.name == BAM_JOINT) {
        j.kp = Some(vec![k; n]);
    }
    rec.meta.insert("kp_si".into(), format!("{k}"));
    rec.control_rate_hz = None;
    rec
}

/// Reads one recording file: BAM JSON (sniffed) or CSV.
pub fn read_recording(path: &Path) -> Result<Recording, RecordingError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| RecordingError::new(path, None, None, format!("cannot read file: {e}")))?;
    if bam::is_bam_json(&text) {
        Ok(bam_recording(bam::parse_bam(path, &text)?))
    } else {
        recording::parse_csv(path, &text)
    }
}

/// Expands the command-line inputs: files as given, directories to their `*.csv` (and BAM
/// `*.json`) files in sorted order.
pub fn expand_inputs(inputs: &[PathBuf]) -> Result<Vec<PathBuf>, RecordingError> {
    let mut out = Vec::new();
    for p in inputs {
        if p.is_dir() {
            let rd = std::fs::read_dir(p).map_err(|e| {
                RecordingError::new(p, None, None, format!("cannot read directory: {e}"))
            })?;
            let mut files: Vec<PathBuf> = rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| {
                    f.is_file()
                        && f.extension().is_some_and(|x| {
                            x.eq_ignore_ascii_case("csv") || x.eq_ignore_ascii_case("json")
                        })
                })
                .collect();
            files.sort();
            if files.is_empty() {
                return Err(RecordingError::new(
                    p,
                    None,
                    None,
                    "directory holds no *.csv or *.json recordings",
                ));
            }
            out.extend(files);
        } else if p.is_file() {
            out.push(p.clone());
        } else {
            return Err(RecordingError::new(p, None, None, "no such file or directory"));
        }
    }
    Ok(out)
}

pub struct GapArgs {
    pub model: PathBuf,
    pub command_timing: Option<crate::sim2real::commands::CommandTiming>,
    pub recordings: Vec<PathBuf>,
    pub spec: Option<PathBuf>,
    pub control_hz: Option<f64>,
    pub base: BaseMode,
    pub json: bool,
    pub report: Option<PathBuf>,
}

pub fn run_gap(a: GapArgs) -> i32 {
    let loaded = match crate::lint::load_for_command(&a.model, a.spec.clone()) {
        Ok(l) => l,
        Err(code) => return code,
    };
    if let Some(hz) = a.control_hz
        && !(hz.is_finite() && hz > 0.0)
    {
        eprintln!("modellint: --control-hz must be positive, got {hz}");
        return 2;
    }
    let files = match expand_inputs(&a.recordings) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("modellint: {e}");
            return 2;
        }
    };
    let robot = &loaded.robot;
    let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let mut recs = Vec::with_capacity(files.len());
    for f in &files {
        let rec = match read_recording(f) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("modellint: {e}");
                return 2;
            }
        };
        if let Err(e) = rec.validate_joint_names(&names) {
            eprintln!("modellint: {e}");
            return 2;
        }
        recs.push(rec);
    }
    let opts = ReplayOptions {
        control_hz: a.control_hz,
        command_timing: a.command_timing,
        base: a.base,
        ..Default::default()
    };
    let replayer = Replayer::new(robot);
    let tty = std::io::stderr().is_terminal();
    let total = recs.len();
    let progress = move |k: usize| {
        if tty {
            eprint!("\rreplaying {k}/{total}");
        }
    };
    let results = replay::replay_all(&replayer, &recs, &opts, Some(&progress));
    if tty {
        eprintln!();
    }
    let mut eps = Vec::with_capacity(results.len());
    for r in results {
        match r {
            Ok(e) => eps.push(e),
            Err(e) => {
                eprintln!("modellint: {e}");
                return 2;
            }
        }
    }
    let spec = loaded.spec.as_ref();
    let region = |name: &str| {
        spec.and_then(|s| s.joint(name))
            .and_then(|f| f.region)
            .unwrap_or_else(|| gap::region_from_name(name))
    };
    let report = gap::compute(&recs, &eps, &region, &GapOptions::default());
    if let Some(dir) = &a.report {
        match crate::sim2real::report::write(dir, &report, &recs, &eps) {
            Ok(p) => eprintln!("modellint: report written to {}", p.display()),
            Err(e) => {
                eprintln!("modellint: cannot write report in {}: {e}", dir.display());
                return 2;
            }
        }
    }
    let out = if a.json {
        match serde_json::to_string_pretty(&report) {
            Ok(s) => s + "\n",
            Err(e) => {
                eprintln!("modellint: cannot serialise report: {e}");
                return 2;
            }
        }
    } else {
        report.to_text("gap")
    };
    if std::io::stdout().lock().write_all(out.as_bytes()).is_err() {
        return 2;
    }
    exit_code(&report)
}

fn exit_code(r: &GapReport) -> i32 {
    if r.diverged.is_empty() { 0 } else { 1 }
}

/// `modellint convert IN.json OUT.csv`: BAM log → CSV with the `servo.kp` column.
pub fn run_convert(input: &Path, output: &Path) -> i32 {
    let rec = match read_recording(input) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("modellint: {e}");
            return 2;
        }
    };
    if let Err(e) = std::fs::write(output, recording::write_csv(&rec)) {
        eprintln!("modellint: cannot write {}: {e}", output.display());
        return 2;
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn firmware_gain_matches_the_rig_actuator() {
        // fixtures/bam_xl330/rig.xml: gainprm = 0.8199237503 for kp 400, vin 7.4.
        assert!((xl330_kp_si(400.0, 7.4) - 0.8199237503).abs() < 1e-9);
        assert!((xl330_kp_si(800.0, 7.4) - 2.0 * 0.8199237503).abs() < 1e-9);
    }
}
