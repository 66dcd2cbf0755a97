//! `modellint gap` and `modellint convert`: reading the inputs ([`crate::sim2real::input`]),
//! replay of the dataset, output. Exit codes: 0 done, 1 done but some episode
//! diverged (excluded and listed), 2 could not do the job (nothing is printed as a result).

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::CmdError;

use crate::sim2real::gap::{self, GapOptions, GapReport};
use crate::sim2real::input::{expand_inputs, read_for_replay, read_recordings_with, scored_view};
use crate::sim2real::recording;
use crate::sim2real::replay::{self, ReplayOptions, Replayer};
use crate::sink::{Sink, Stderr};

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
    let report = match gap(&a, &Stderr::new(false)) {
        Ok(r) => r,
        Err(e) => return report_error(&e),
    };
    let out = if a.json {
        match gap_json(&report).and_then(|v| serde_json::to_string_pretty(&v)) {
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

/// Prints why a command could not run (the model's error with its snippet, else one line) and
/// returns exit code 2.
pub fn report_error(e: &CmdError) -> i32 {
    match e {
        CmdError::Load(e) => {
            eprint!("{}", crate::output::text::render_error(e, crate::output::color_on_stderr()))
        }
        CmdError::Message(m) => eprintln!("modellint: {m}"),
        CmdError::Said(_) => {}
    }
    2
}

/// The `gap --format json` document of `report`, stamped like every modellint JSON (the CLI's
/// and the Python API's).
pub fn gap_json(report: &GapReport) -> serde_json::Result<serde_json::Value> {
    let mut v = serde_json::to_value(report)?;
    crate::output::json::stamp(&mut v, "gap");
    Ok(v)
}

/// `modellint gap` without the printing: loads the model, reads and replays the recordings,
/// measures the gap (and writes the HTML report when asked). What `--format json` prints is
/// this report, serialised by [`gap_json`]; the Python API returns the same.
pub fn gap(a: &GapArgs, sink: &dyn Sink) -> Result<GapReport, CmdError> {
    let mut loaded = crate::lint::load_for_api(&a.model, a.spec.clone()).map_err(CmdError::Load)?;
    replay::hold_base(&mut loaded.robot, a.replay.base);
    if let Some(hz) = a.replay.control_hz
        && let Err(e) = crate::spec::control_hz_domain(hz)
    {
        return Err(format!("--control-hz {e}").into());
    }
    let files = expand_inputs(&a.recordings).map_err(|e| e.to_string())?;
    let robot = &loaded.robot;
    let mut inputs = read_for_replay(&files.files, robot, &a.replay, &a.parse)?;
    if let Some(n) = files.skipped_note() {
        inputs.notes.insert(0, n);
    }
    for w in &inputs.warnings {
        sink.warning(w);
    }
    for n in &inputs.notes {
        sink.note(n);
    }
    let (recs, notes, warnings, unscored) =
        (inputs.recs, inputs.notes, inputs.warnings, inputs.unscored);
    let mut opts = a.replay.clone();
    opts.pd_gains = replay::spec_pd_gains(loaded.spec.as_ref(), robot);
    let replayer = Replayer::new(robot);
    let total = recs.len();
    let progress = move |k: usize| sink.replayed(k, total);
    let results = replay::replay_all(&replayer, &recs, &opts, Some(&progress));
    sink.replays_done();
    let mut eps = Vec::with_capacity(results.len());
    for r in results {
        eps.push(r.map_err(|e| e.to_string())?);
    }
    // Joints left out with --no-command are replayed (the others move with them), not scored.
    let Some((srecs, seps)) = scored_view(&recs, &eps, &unscored) else {
        return Err(format!(
            "nothing left to score: every recorded joint is left out by --no-command ({})",
            unscored.join(", ")
        )
        .into());
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
        sink.note(&n);
        report.notes.push(n);
    }
    if let Some(dir) = &a.report {
        let slides: Vec<String> = robot
            .joints
            .iter()
            .filter(|j| j.jtype == crate::model::JointType::Slide)
            .map(|j| j.name.clone())
            .collect();
        match crate::sim2real::report::write(dir, &report, &srecs, &seps, &slides) {
            Ok(p) => sink.said(&format!("report written to {}", p.display())),
            Err(e) => {
                return Err(format!("cannot write report in {}: {e}", dir.display()).into());
            }
        }
    }
    Ok(report)
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
