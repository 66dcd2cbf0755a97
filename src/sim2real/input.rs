//! Reading recordings from the command line's paths: files as given, directories expanded to
//! their recordings, each file read as BAM JSON (sniffed) or CSV.

use std::path::{Path, PathBuf};

use crate::model::{ActuatorKind, Robot};
use crate::sim2real::bam;
use crate::sim2real::input_rate::{
    no_rate_warning, off_grid_warning, overridden_rate_warning, undeclared_rate,
};
use crate::sim2real::recording::{self, ParseOptions, Recording, RecordingError};
use crate::sim2real::replay::{self, Episode, ReplayOptions};

/// Reads one recording file: BAM JSON (sniffed) or CSV.
pub fn read_recording(path: &Path) -> Result<Recording, RecordingError> {
    read_recording_with(path, &ParseOptions::default())
}

/// The recordings of one file, whatever its kind ([`recording::sniff`]): CSV, BAM JSON, NumPy
/// `.npz`, LeRobot parquet (one recording per episode), MCAP; any other kind is an error
/// naming it.
pub fn read_recordings_with(
    path: &Path,
    opts: &ParseOptions,
) -> Result<Vec<Recording>, RecordingError> {
    let bytes = std::fs::read(path)
        .map_err(|e| RecordingError::new(path, None, None, format!("cannot read file: {e}")))?;
    if let Some(r) = recording::read_log(path, &bytes, opts) {
        return r;
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        RecordingError::new(
            path,
            None,
            None,
            format!("not UTF-8 text (byte {}): not a CSV file", e.utf8_error().valid_up_to()),
        )
    })?;
    parse_text(path, &text, opts).map(|r| vec![r])
}

/// [`read_recording`] with parse options (`--ignore-columns` for CSV; for every format the
/// model's joints and which of them must have a command, [`ParseOptions::actuated_joints`]).
/// A file of several recordings (a LeRobot file of several episodes) is an error here.
pub fn read_recording_with(path: &Path, opts: &ParseOptions) -> Result<Recording, RecordingError> {
    let mut v = read_recordings_with(path, opts)?;
    if v.len() != 1 {
        return Err(RecordingError::new(
            path,
            None,
            None,
            format!("holds {} episodes: pick one with --log-episode N", v.len()),
        ));
    }
    Ok(v.remove(0))
}

/// CSV text or JSON (a BAM log; other JSON is an error saying what it is).
fn parse_text(path: &Path, text: &str, opts: &ParseOptions) -> Result<Recording, RecordingError> {
    let text = text.to_string();
    if bam::is_bam_json(&text) {
        let rec = bam::bam_recording(bam::parse_bam(path, &text)?);
        if let Some(model) = &opts.model_joints {
            rec.validate_joint_names(model)?;
        }
        // A log whose entries have no `goal_position`: at the first entry, naming the key.
        recording::uncommanded_joints(
            rec.joints.iter().map(|j| (j.name.as_str(), j.q_cmd.is_some())),
            opts,
            |_| "'goal_position' key in its entries (the servo's command)".to_string(),
        )
        .map_err(|m| RecordingError::new(path, bam::entry_line(&text, 0), None, m))?;
        Ok(rec)
    } else if recording::sniff(path, text.as_bytes()) == recording::Kind::Json {
        Err(recording::not_bam_json(path, &text))
    } else {
        recording::parse_csv_with(path, &text, opts)
    }
}

/// Recordings read for a replay, with what reading them found out about their control ticks.
pub struct ReplayInputs {
    pub recs: Vec<Recording>,
    /// [`replay::origin_messages`]: estimated tick origins (notes), contradicted ones and
    /// command columns that fit no tick grid (warnings).
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
    /// Driven joints recorded without a command in some file, accepted with `--no-command`:
    /// replayed following their recorded positions, left out of the scores and of the fit
    /// ([`scored_view`]); a note in `notes` says so.
    pub unscored: Vec<String>,
}

/// A recording with command columns for a model with no actuator at all (a bare URDF): the
/// replay would drop every command and let the joints fall, an error naming the columns.
fn no_actuator_for_commands(robot: &Robot, f: &Path, r: &Recording) -> Result<(), String> {
    if !robot.actuators.is_empty() {
        return Ok(());
    }
    let cols: Vec<String> = r
        .joints
        .iter()
        .filter(|j| j.q_cmd.is_some())
        .map(|j| format!("{}.q_cmd", j.name))
        .collect();
    if cols.is_empty() {
        return Ok(());
    }
    let more = if cols.len() > 4 { format!(" and {} more", cols.len() - 4) } else { String::new() };
    Err(format!(
        "{}: commands {}{more}, but {} has no actuator, so the replay would ignore every \
         command and let the joints fall (a URDF states no motors). Replay on a model with \
         actuators: an MJCF that includes the robot and adds one per commanded joint (e.g. \
         <actuator><position joint=\"{}\" kp=\"...\" kv=\"...\"/></actuator> with the servo's gains)",
        f.display(),
        cols.iter().take(4).cloned().collect::<Vec<_>>().join(", "),
        robot.path.display(),
        r.joints.iter().find(|j| j.q_cmd.is_some()).map(|j| j.name.as_str()).unwrap_or("")
    ))
}

/// Reads `files` for `gap` and `fit`: each recording's joints must be the model's, a joint an
/// actuator of the model drives must have its command (else an error at the header line, or
/// with `--no-command` it is left out of the scores: [`ReplayInputs::unscored`]), and its
/// timestamps must map onto its control ticks ([`replay::check_schedule`]); a missing
/// `control_t0_s` is estimated from the rows when the first row's time contradicts them
/// ([`replay::resolve_tick_origin`]). The first error ends it.
pub fn read_for_replay(
    files: &[PathBuf],
    robot: &Robot,
    opts: &ReplayOptions,
    parse: &ParseOptions,
) -> Result<ReplayInputs, String> {
    let model_joints: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let actuated: Vec<String> = robot
        .joints
        .iter()
        .filter(|j| !robot.actuators_on_joint(j.id).is_empty())
        .map(|j| j.name.clone())
        .collect();
    // A pattern that names no joint of the model is a typo, not a choice.
    let matcher = recording::no_command_matcher(&parse.no_command)?;
    for g in &parse.no_command {
        let one = recording::no_command_matcher(std::slice::from_ref(g))?;
        if !model_joints.iter().any(|j| one.is_match(j)) {
            return Err(format!(
                "--no-command {g}: matches no joint of the model ({} joints)",
                model_joints.len()
            ));
        }
    }
    let mut recs = Vec::with_capacity(files.len());
    let mut origins = Vec::with_capacity(files.len());
    let mut rates = Vec::new();
    let mut duplicates = Vec::new();
    // Files with a command but no control rate, declared or given: (name, median interval
    // between command changes).
    let mut no_rate: Vec<(String, Option<f64>)> = Vec::new();
    // Files whose declared rate --control-hz replaces, and whose command changes between ticks.
    let mut overridden: Vec<(String, f64)> = Vec::new();
    let mut off_grid: Vec<(String, replay::OffGrid)> = Vec::new();
    // joint → the files where it has no command (accepted by --no-command).
    let mut unscored: Vec<(String, Vec<String>)> = Vec::new();
    // Unknown joints and driven joints without a command are reported at the header line,
    // before any value is checked.
    let unlimited = robot
        .joints
        .iter()
        .filter(|j| j.jtype == crate::model::JointType::Hinge && !j.limited)
        .filter(|j| {
            // A position servo's joint does not turn on and on (its setpoint is an angle).
            !robot
                .actuators_on_joint(j.id)
                .iter()
                .any(|a| matches!(a.kind, ActuatorKind::Position { .. }))
        })
        .map(|j| j.name.clone())
        .collect();
    let parse = ParseOptions {
        model_joints: Some(model_joints.clone()),
        actuated_joints: Some(actuated.clone()),
        unlimited_joints: Some(unlimited),
        ..parse.clone()
    };
    let read: Vec<(PathBuf, Recording)> = {
        let mut v = Vec::with_capacity(files.len());
        for f in files {
            for r in read_recordings_with(f, &parse).map_err(|e| e.to_string())? {
                // A file of several episodes: each is named by its own source.
                v.push((if r.source == *f { f.clone() } else { r.source.clone() }, r));
            }
        }
        v
    };
    for (f, mut r) in read {
        no_actuator_for_commands(robot, &f, &r)?;
        for j in &r.joints {
            if j.q_cmd.is_none() && actuated.contains(&j.name) && matcher.is_match(&j.name) {
                let name = f.file_name().unwrap_or_default().to_string_lossy().into_owned();
                match unscored.iter_mut().find(|(n, _)| *n == j.name) {
                    Some((_, fs)) => fs.push(name),
                    None => unscored.push((j.name.clone(), vec![name])),
                }
            }
        }
        rebase_time(&mut r);
        if let Some(d) = r.meta.get(recording::KEY_DUPLICATE_ROWS) {
            duplicates
                .push(format!("{} ({d})", f.file_name().unwrap_or_default().to_string_lossy()));
        }
        r.validate_joint_names(&model_joints).map_err(|e| e.to_string())?;
        if let Some(gap) = undeclared_rate(&r, opts) {
            no_rate.push((f.file_name().unwrap_or_default().to_string_lossy().into_owned(), gap));
        }
        replay::check_schedule(&r, opts).map_err(|e| e.to_string())?;
        if let Some(fix) = replay::resolve_rate(&mut r, opts) {
            rates.push((f.clone(), fix));
        }
        let name = || f.file_name().unwrap_or_default().to_string_lossy().into_owned();
        if let (Some(given), Some(declared)) = (opts.control_hz, r.control_rate_hz)
            && (given - declared).abs() > 1e-9 * declared
        {
            overridden.push((name(), declared));
        }
        if let Some(o) = replay::off_grid(&r, opts) {
            off_grid.push((name(), o));
        }
        origins.push((f.clone(), replay::resolve_tick_origin(&mut r, opts)));
        recs.push(r);
    }
    let (mut notes, mut warnings) = replay::origin_messages(&origins);
    warnings.extend(replay::rate_messages(&rates));
    warnings.extend(no_rate_warning(&no_rate, recs.len()));
    warnings.extend(overridden_rate_warning(&overridden, opts.control_hz, recs.len()));
    warnings.extend(off_grid_warning(&off_grid, recs.len()));
    if !duplicates.is_empty() {
        notes.push(format!(
            "rows that repeat the row before them exactly were left out (a sample logged twice): {}",
            duplicates.join(", ")
        ));
    }
    if !unscored.is_empty()
        && recs.iter().all(|r| r.joints.iter().all(|j| unscored.iter().any(|(u, _)| *u == j.name)))
    {
        let names: Vec<&str> = unscored.iter().map(|(j, _)| j.as_str()).collect();
        return Err(format!(
            "nothing left to score: every recorded joint is left out by --no-command ({})",
            names.join(", ")
        ));
    }
    if !unscored.is_empty() {
        let list: Vec<String> = unscored
            .iter()
            .map(|(j, fs)| {
                let shown: Vec<&str> = fs.iter().take(3).map(String::as_str).collect();
                let more = if fs.len() > 3 { ", …" } else { "" };
                format!(
                    "{j} (no command in {} of {} file(s): {}{more})",
                    fs.len(),
                    files.len(),
                    shown.join(", ")
                )
            })
            .collect();
        notes.push(format!(
            "--no-command: left out of the scores and of the fit, replayed following their \
             recorded positions as their command: {}",
            list.join("; ")
        ));
    }
    let unscored: Vec<String> = unscored.into_iter().map(|(j, _)| j).collect();
    if let Some(w) = coupling_warning(robot, &recs, &unscored, opts) {
        warnings.push(w);
    }
    if let Some(w) = absent_joints_message(robot, &recs, &actuated, opts) {
        warnings.push(w);
    }
    warnings.extend(super::input_checks::base_option_warning(robot, opts.base, &recs));
    notes.extend(super::input_checks::base_columns_note(robot, opts.base, &recs));
    warnings.extend(super::input_checks::out_of_range_warning(robot, &recs));
    Ok(ReplayInputs { recs, notes, warnings, unscored })
}

/// Whether joints `a` and `b` of `robot` are in one kinematic chain (one's body is the other's,
/// or an ancestor of it): then each one's motion loads the other (inertia, gravity).
fn same_chain(robot: &Robot, a: &str, b: &str) -> bool {
    let body = |n: &str| robot.joint(n).map(|j| j.body);
    let (Some(ba), Some(bb)) = (body(a), body(b)) else { return false };
    let ancestor = |anc: usize, mut x: usize| {
        for _ in 0..robot.bodies.len() + 1 {
            if x == anc {
                return true;
            }
            match robot.bodies.get(x) {
                Some(b) if b.parent != x => x = b.parent,
                _ => return false,
            }
        }
        false
    };
    ancestor(ba, bb) || ancestor(bb, ba)
}

/// A warning naming the scored joints that move with a joint left out by `--no-command` (one
/// kinematic chain, or any joint on a free base): that joint is replayed to its own positions,
/// so its servo moves it behind its recorded motion, and their scores and fits carry that.
/// Driven joints of the model that no recording has a column for are held at the keyframe's
/// command in every replay, whatever they did on the robot: said when one shares a kinematic
/// chain with a recorded joint (every joint shares one when the base is free), whose replay
/// then carries what the absent joint's motion did to it.
fn absent_joints_message(
    robot: &Robot,
    recs: &[Recording],
    actuated: &[String],
    opts: &ReplayOptions,
) -> Option<String> {
    let recorded = |j: &str| recs.iter().any(|r| r.joints.iter().any(|x| x.name == j));
    let free = opts.base == replay::BaseMode::Free;
    let parts: Vec<String> = actuated
        .iter()
        .filter(|a| !recorded(a))
        .filter_map(|a| {
            let near: Vec<&str> = recs
                .iter()
                .flat_map(|r| r.joints.iter().map(|j| j.name.as_str()))
                .filter(|s| free || same_chain(robot, a, s))
                .fold(Vec::new(), |mut v, s| {
                    if !v.contains(&s) {
                        v.push(s);
                    }
                    v
                });
            (!near.is_empty()).then(|| format!("{a} → {}", near.join(", ")))
        })
        .collect();
    if parts.is_empty() {
        return None;
    }
    Some(format!(
        "driven joint(s) with no column in any recording are held at the keyframe's command \
         in every replay{}; the recorded joints in their kinematic chain feel whatever the \
         held joint did differently on the robot, and their scores and any fit carry it ({}): \
         record them (position and command; with positions alone, --no-command replays them \
         along their recorded positions)",
        if free { " (the base is free: every joint feels them)" } else { "" },
        parts.join("; ")
    ))
}

fn coupling_warning(
    robot: &Robot,
    recs: &[Recording],
    unscored: &[String],
    opts: &ReplayOptions,
) -> Option<String> {
    let mut scored: Vec<&str> = Vec::new();
    for r in recs {
        for j in &r.joints {
            if !unscored.contains(&j.name) && !scored.contains(&j.name.as_str()) {
                scored.push(&j.name);
            }
        }
    }
    let free = opts.base == replay::BaseMode::Free;
    let parts: Vec<String> = unscored
        .iter()
        .filter_map(|u| {
            let near: Vec<&str> =
                scored.iter().copied().filter(|s| free || same_chain(robot, u, s)).collect();
            (!near.is_empty()).then(|| format!("{u} → {}", near.join(", ")))
        })
        .collect();
    if parts.is_empty() {
        return None;
    }
    Some(format!(
        "--no-command: a joint left out is replayed to its own recorded positions, and its \
         servo moves it behind them (a servo lags its command); the scored joints in its \
         kinematic chain{} feel that lag in their inertia and gravity load, and their scores \
         and any fit on them carry it ({}). On independent_arm2's clean control, with the \
         elbow left out this way, the shoulder's position MAE is 1.08° against 0.03° with the \
         elbow's command: record the command, or leave out only joints that move apart from \
         the scored ones",
        if free { " (all of them: the base is free)" } else { "" },
        parts.join("; ")
    ))
}

/// `recs` and their replays `eps` without the joints `unscored` (same order otherwise; an
/// episode with no joint left is left out): what `gap` and `fit` score. `None` when no joint
/// is left in any recording.
pub fn scored_view(
    recs: &[Recording],
    eps: &[Episode],
    unscored: &[String],
) -> Option<(Vec<Recording>, Vec<Episode>)> {
    let mut rs = Vec::with_capacity(recs.len());
    let mut es = Vec::with_capacity(eps.len());
    for (r, e) in recs.iter().zip(eps) {
        let keep: Vec<bool> = r.joints.iter().map(|j| !unscored.contains(&j.name)).collect();
        let mut r = r.clone();
        let mut flags = keep.iter();
        r.joints.retain(|_| *flags.next().unwrap_or(&true));
        let mut e = e.clone();
        let pick = |v: &[Vec<f64>]| -> Vec<Vec<f64>> {
            v.iter().zip(&keep).filter(|(_, k)| **k).map(|(x, _)| x.clone()).collect()
        };
        e.q_sim = pick(&e.q_sim);
        e.qd_sim = pick(&e.qd_sim);
        e.joints =
            e.joints.iter().zip(&keep).filter(|(_, k)| **k).map(|(n, _)| n.clone()).collect();
        if !r.joints.is_empty() {
            rs.push(r);
            es.push(e);
        }
    }
    (!rs.is_empty()).then_some((rs, es))
}

/// Metadata key recording the whole seconds [`rebase_time`] took off a recording's times.
pub const KEY_TIME_OFFSET: &str = recording::KEY_TIME_OFFSET;

/// Times above this [s] are shifted to start near 0 before the replay.
const REBASE_ABOVE_S: f64 = 1e4;

/// Shifts a recording whose times are large (Unix-epoch stamps, ~1.7e9 s: a double resolves
/// only 0.24 µs there, and MuJoCo's clock, advanced step by step from it, drifts by a rounding
/// per step) by the whole seconds of its first time, `control_t0_s` with it (the ticks' phase
/// is unchanged); the offset is kept in the metadata (`time_offset_s`). On an independent
/// simulator's humanoid logs stamped from 1.7e9 s the replay's position error was 3.2× that of
/// the same logs from 1 s.
pub fn rebase_time(r: &mut Recording) {
    let Some(&first) = r.t.first() else { return };
    if !(first.abs() > REBASE_ABOVE_S) {
        return;
    }
    let off = first.floor();
    for x in &mut r.t {
        *x -= off;
    }
    if let Some(t0) = r.control_t0_s.as_mut() {
        *t0 -= off;
    }
    r.meta.insert(KEY_TIME_OFFSET.to_string(), format!("{off}"));
}

/// The recordings a command line names: [`expand_inputs`].
#[derive(Debug, Default, PartialEq)]
pub struct Inputs {
    /// Files to read, in order.
    pub files: Vec<PathBuf>,
    /// `*.json` files found in a directory that are not BAM logs (a `truth.json`, a report
    /// written there, an empty file a shell redirection has just created): not read.
    pub skipped: Vec<PathBuf>,
}

impl Inputs {
    /// One note naming the skipped files, if any.
    pub fn skipped_note(&self) -> Option<String> {
        if self.skipped.is_empty() {
            return None;
        }
        let names: Vec<String> = self.skipped.iter().map(|p| p.display().to_string()).collect();
        Some(format!(
            "not read, JSON files in a directory that are not BAM logs: {} (name a file on the \
             command line to read it whatever it holds)",
            names.join(", ")
        ))
    }
}

/// Expands the command-line inputs: files as given, directories to their `*.csv` files and
/// BAM `*.json` logs in sorted order (other JSON there is skipped and listed: a `truth.json`,
/// a report, `gap --format json > dir/gap.json`'s empty file). A dataset directory —
/// `episodes/` beside a `truth.json` and nothing else to read, as `modellint synth --out` and
/// the independent-simulator datasets lay it out — is read from its `episodes/`.
pub fn expand_inputs(inputs: &[PathBuf]) -> Result<Inputs, RecordingError> {
    let mut out = Inputs::default();
    for p in inputs {
        if p.is_dir() && p.join("meta/info.json").is_file() && p.join("data").is_dir() {
            // A LeRobot dataset: its data/chunk-*/ parquet files.
            let files = parquet_files(&p.join("data"))?;
            if files.is_empty() {
                return Err(RecordingError::new(
                    p,
                    None,
                    None,
                    "LeRobot dataset without parquet files under data/",
                ));
            }
            out.files.extend(files);
        } else if p.is_dir() {
            let (mut files, mut skipped) = recording_files(p)?;
            let episodes = p.join("episodes");
            if episodes.is_dir() && files.is_empty() {
                (files, skipped) = recording_files(&episodes)?;
            }
            if files.is_empty() {
                let why = if skipped.is_empty() {
                    "directory holds no recordings (*.csv, *.json, *.npz, *.pt, *.parquet, *.mcap)"
                        .to_string()
                } else {
                    format!(
                        "directory holds no recordings (*.csv, *.json, *.npz, *.pt, *.parquet, *.mcap; {} JSON file(s) there \
                         are not BAM logs)",
                        skipped.len()
                    )
                };
                return Err(RecordingError::new(p, None, None, why));
            }
            out.files.extend(files);
            out.skipped.extend(skipped);
        } else if p.is_file() {
            out.files.push(p.clone());
        } else {
            return Err(RecordingError::new(p, None, None, "no such file or directory"));
        }
    }
    Ok(out)
}

/// The recordings (`*.csv`, `*.npz`, `*.pt`, `*.parquet`, `*.mcap`, BAM `*.json`) directly in
/// `dir`, sorted, and the other `*.json` files there.
fn recording_files(dir: &Path) -> Result<(Vec<PathBuf>, Vec<PathBuf>), RecordingError> {
    let rd = std::fs::read_dir(dir)
        .map_err(|e| RecordingError::new(dir, None, None, format!("cannot read directory: {e}")))?;
    let mut files: Vec<PathBuf> = Vec::new();
    let mut skipped: Vec<PathBuf> = Vec::new();
    for f in rd.filter_map(|e| e.ok().map(|e| e.path())) {
        if !f.is_file() {
            continue;
        }
        let Some(ext) = f.extension() else { continue };
        if ["csv", "npz", "pt", "pth", "parquet", "mcap"]
            .iter()
            .any(|e| ext.eq_ignore_ascii_case(e))
        {
            files.push(f);
        } else if ext.eq_ignore_ascii_case("json") {
            // Unreadable files are kept: reading them reports the error at the file.
            match std::fs::read_to_string(&f) {
                Ok(text) if !bam::is_bam_json(&text) => skipped.push(f),
                _ => files.push(f),
            }
        }
    }
    files.sort();
    skipped.sort();
    Ok((files, skipped))
}

/// The `*.parquet` files under `dir` (one level of subdirectories: LeRobot's `chunk-000/`),
/// sorted.
fn parquet_files(dir: &Path) -> Result<Vec<PathBuf>, RecordingError> {
    let read = |d: &Path| {
        std::fs::read_dir(d)
            .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect::<Vec<_>>())
            .map_err(|e| RecordingError::new(d, None, None, format!("cannot read directory: {e}")))
    };
    let mut out = Vec::new();
    for e in read(dir)? {
        let entries = if e.is_dir() { read(&e)? } else { vec![e] };
        out.extend(entries.into_iter().filter(|f| {
            f.is_file() && f.extension().is_some_and(|x| x.eq_ignore_ascii_case("parquet"))
        }));
    }
    out.sort();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(p: &Path) {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, "x").unwrap();
    }

    const BAM: &str = r#"{"entries": [{"timestamp": 0, "goal_position": 0}]}"#;

    /// Unix-epoch stamps are shifted by whole seconds, the ticks' origin with them; small
    /// times are left alone.
    #[test]
    fn epoch_times_are_rebased_by_whole_seconds() {
        let t: Vec<f64> = (0..5).map(|i| 1.7e9 + 1.0015 + 0.005 * i as f64).collect();
        let mut r = Recording::at_100hz(t, vec![recording::JointTrace::new("j", vec![0.0; 5])]);
        r.control_t0_s = Some(1.7e9 + 0.0071);
        rebase_time(&mut r);
        assert!((r.t[0] - 0.0015).abs() < 1e-6 && (r.t[4] - 0.0215).abs() < 1e-6, "{:?}", r.t);
        assert!((r.control_t0_s.unwrap() - 0.0071 + 1.0).abs() < 1e-6, "{:?}", r.control_t0_s);
        assert_eq!(r.meta.get(KEY_TIME_OFFSET).map(String::as_str), Some("1700000001"));
        let mut small = Recording::at_100hz(vec![3.5, 3.6], vec![]);
        rebase_time(&mut small);
        assert_eq!((small.t[0], small.meta.len()), (3.5, 0));
    }

    /// A dataset directory (episodes/ beside truth.json) is read from its episodes; a directory
    /// with recordings of its own is read as it is, truth.json or not.
    #[test]
    fn a_dataset_directory_is_read_from_its_episodes() {
        let root = std::env::temp_dir().join(format!("modellint-inputs-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let ds = root.join("ds");
        touch(&ds.join("truth.json"));
        touch(&ds.join("episodes/ep_01.csv"));
        touch(&ds.join("episodes/ep_00.csv"));
        touch(&ds.join("truth_commands/ep_00.csv"));
        let got = expand_inputs(std::slice::from_ref(&ds)).unwrap();
        assert_eq!(got.files, vec![ds.join("episodes/ep_00.csv"), ds.join("episodes/ep_01.csv")]);
        assert!(got.skipped.is_empty());
        // Without truth.json too (an episodes/ directory and nothing else to read).
        std::fs::remove_file(ds.join("truth.json")).unwrap();
        assert_eq!(expand_inputs(std::slice::from_ref(&ds)).unwrap().files.len(), 2);

        // Recordings at the top level: read as given, the subdirectory is not searched.
        let flat = root.join("flat");
        touch(&flat.join("run.csv"));
        touch(&flat.join("truth.json"));
        touch(&flat.join("episodes/ep_00.csv"));
        let got = expand_inputs(std::slice::from_ref(&flat)).unwrap();
        assert_eq!(got.files, vec![flat.join("run.csv")]);
        assert_eq!(got.skipped, vec![flat.join("truth.json")]);
        assert!(got.skipped_note().unwrap().contains("truth.json"));

        // Nothing to read anywhere: the error names the directory.
        let empty = root.join("empty");
        std::fs::create_dir_all(empty.join("episodes")).unwrap();
        let e = expand_inputs(std::slice::from_ref(&empty)).unwrap_err();
        assert_eq!(e.file, empty);
        assert!(e.message.contains("directory holds no recordings"), "{}", e.message);
        let _ = std::fs::remove_dir_all(&root);
    }

    /// In a directory, JSON that is not a BAM log is skipped and listed (a report written
    /// there, the empty file `gap --format json > dir/gap.json` creates before modellint runs);
    /// BAM logs are read; a file named on the command line is read whatever it holds.
    #[test]
    fn json_in_a_directory_that_is_not_a_bam_log_is_skipped() {
        let root = std::env::temp_dir().join(format!("modellint-json-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        touch(&root.join("b.csv"));
        std::fs::write(root.join("gap.json"), "").unwrap();
        std::fs::write(root.join("report.json"), r#"{"joints": []}"#).unwrap();
        std::fs::write(root.join("a.json"), BAM).unwrap();
        let got = expand_inputs(std::slice::from_ref(&root)).unwrap();
        assert_eq!(got.files, vec![root.join("a.json"), root.join("b.csv")]);
        assert_eq!(got.skipped, vec![root.join("gap.json"), root.join("report.json")]);
        let named = expand_inputs(&[root.join("gap.json")]).unwrap();
        assert!(named.files == vec![root.join("gap.json")] && named.skipped.is_empty());
        // Only non-BAM JSON: an error that says so.
        for f in ["a.json", "b.csv"] {
            std::fs::remove_file(root.join(f)).unwrap();
        }
        let e = expand_inputs(std::slice::from_ref(&root)).unwrap_err();
        assert!(e.message.contains("2 JSON file(s) there are not BAM logs"), "{}", e.message);
        let _ = std::fs::remove_dir_all(&root);
    }
}
