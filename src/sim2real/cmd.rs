//! `modellint gap` and `modellint convert`: reading the inputs ([`crate::sim2real::input`]),
//! replay of the dataset, output. Exit codes: 0 done, 1 done but some episode
//! diverged (excluded and listed), 2 could not do the job (nothing is printed as a result).

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::CmdError;

use crate::sim2real::gap::{self, GapOptions, GapReport};
use crate::sim2real::input::{expand_inputs, read_for_replay, read_recording, scored_view};
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

/// `modellint gap` without the printing: loads the model, reads and replays the recordings,
/// measures the gap (and writes the HTML report when asked). What `--format json` prints is
/// this report, serialised; the Python API returns the same.
pub fn gap(a: &GapArgs, sink: &dyn Sink) -> Result<GapReport, CmdError> {
    let loaded = crate::lint::load_for_api(&a.model, a.spec.clone()).map_err(CmdError::Load)?;
    if let Some(hz) = a.replay.control_hz
        && !(hz.is_finite() && hz > 0.0)
    {
        return Err(format!("--control-hz must be positive, got {hz}").into());
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
    let opts = a.replay.clone();
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
        match crate::sim2real::report::write(dir, &report, &srecs, &seps) {
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
