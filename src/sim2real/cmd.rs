//! `modellint gap` and `modellint convert`: reading the inputs ([`crate::sim2real::input`]),
//! replay of the dataset, output. Exit codes: 0 done, 1 done but some episode
//! diverged (excluded and listed), 2 could not do the job (nothing is printed as a result).

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use crate::sim2real::gap::{self, GapOptions, GapReport};
use crate::sim2real::input::{expand_inputs, read_for_replay, read_recordings_with, scored_view};
use crate::sim2real::recording;
use crate::sim2real::replay::{self, ReplayOptions, Replayer};

pub struct GapArgs {
    pub model: PathBuf,
    pub recordings: Vec<PathBuf>,
    pub spec: Option<PathBuf>,
    /// How the recordings are read (`--ignore-columns`).
    pub parse: recording::ParseOptions,
    /// How the recordings are replayed.
    pub replay: ReplayOptions,
    pub json: bool,
    pub report: Option<PathBuf>,
}

pub fn run_gap(a: GapArgs) -> i32 {
    let loaded = match crate::lint::load_for_command(&a.model, a.spec.clone()) {
        Ok(l) => l,
        Err(code) => return code,
    };
    if let Some(hz) = a.replay.control_hz
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
    let mut inputs = match read_for_replay(&files.files, robot, &a.replay, &a.parse) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("modellint: {e}");
            return 2;
        }
    };
    if let Some(n) = files.skipped_note() {
        inputs.notes.insert(0, n);
    }
    for w in &inputs.warnings {
        eprintln!("modellint: warning: {w}");
    }
    for n in &inputs.notes {
        eprintln!("modellint: note: {n}");
    }
    let (recs, notes, warnings, unscored) =
        (inputs.recs, inputs.notes, inputs.warnings, inputs.unscored);
    let opts = a.replay.clone();
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
    // Joints left out with --no-command are replayed (the others move with them), not scored.
    let (srecs, seps) = match scored_view(&recs, &eps, &unscored) {
        Some(v) => v,
        None => {
            eprintln!(
                "modellint: nothing left to score: every recorded joint is left out by \
                 --no-command ({})",
                unscored.join(", ")
            );
            return 2;
        }
    };
    let spec = loaded.spec.as_ref();
    let region = |name: &str| gap::joint_region(spec, name);
    let mut report = gap::compute(&srecs, &seps, &region, &GapOptions::default());
    report.notes = notes;
    report.warnings = warnings;
    // On the whole replay (the fine one must drive the same joints), reported on the scored.
    report.timestep = replay::timestep_check(robot, &recs, &opts, Some(&eps)).map(|mut c| {
        c.per_joint.retain(|j| !unscored.contains(&j.name));
        c
    });
    if let Some(n) = report.timestep.as_ref().and_then(replay::timestep_note) {
        eprintln!("modellint: note: {n}");
        report.notes.push(n);
    }
    if let Some(dir) = &a.report {
        match crate::sim2real::report::write(dir, &report, &srecs, &seps) {
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

/// `modellint convert IN OUT.csv`: a BAM log (→ CSV with the `servo.kp` column), a NumPy
/// `.npz`, LeRobot parquet or MCAP file → CSV. A file of several episodes writes
/// `OUT_ep<N>.csv` for each.
pub fn run_convert(input: &Path, output: &Path, map: &recording::LogMap) -> i32 {
    let opts = recording::ParseOptions { log_map: map.clone(), ..Default::default() };
    let recs = match read_recordings_with(input, &opts) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("modellint: {e}");
            return 2;
        }
    };
    let many = recs.len() > 1;
    for (i, rec) in recs.iter().enumerate() {
        let out = if many {
            let stem = output.file_stem().unwrap_or_default().to_string_lossy();
            let ep = rec.meta.get("episode_index").cloned().unwrap_or_else(|| i.to_string());
            output.with_file_name(format!("{stem}_ep{ep}.csv"))
        } else {
            output.to_path_buf()
        };
        if let Err(e) = std::fs::write(&out, recording::write_csv(rec)) {
            eprintln!("modellint: cannot write {}: {e}", out.display());
            return 2;
        }
        if many {
            eprintln!("modellint: wrote {}", out.display());
        }
    }
    0
}
