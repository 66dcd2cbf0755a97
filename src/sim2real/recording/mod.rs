//! The CSV recording format for real (or simulated) joint trajectories.
//!
//! ```text
//! # control_rate_hz: 100
//! # robot: booster_t1
//! t,knee.q,knee.qd,knee.q_cmd,base.x,base.y,base.z,base.qw,base.qx,base.qy,base.qz
//! 0.000,0.10,0.0,0.11,0,0,0.7,1,0,0,0
//! 0.011,0.11,0.9,0.12,0,0,0.7,1,0,0,0
//! ```
//!
//! * Leading `# key: value` lines are metadata. `control_rate_hz` and `control_t0_s` are parsed
//!   into their own fields; every other key is kept verbatim in [`Recording::meta`]. A `#` line
//!   without a colon is a plain comment and is ignored. Blank lines may appear among them.
//! * The header row names the columns: `t` (seconds, strictly increasing, irregular spacing
//!   allowed), per joint `<joint>.q` (required), `<joint>.qd`, `<joint>.q_cmd`, `<joint>.tau`,
//!   `<joint>.kp`, `<joint>.kd`, `<joint>.enabled` (0/1) — all optional — and optionally the
//!   floating base `base.x base.y base.z base.qw base.qx base.qy base.qz` (all seven or none,
//!   quaternion in w-x-y-z order). Columns may come in any order; joints keep the order of their
//!   first column.
//! * Fields are comma separated; spaces around fields, CRLF line ends and trailing empty lines
//!   are accepted. Every error carries the file and the 1-based line number; parsing never
//!   panics.

mod check;
mod csv;
mod csv_map;
mod lerobot;
pub mod logs;
pub mod mapping;
pub mod npy;
mod pickle;
mod rosbag;
#[cfg(test)]
mod tests;
mod torch_pt;
mod units;
mod write;

use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

pub use csv::{parse_csv, parse_csv_with, read_csv};
pub use logs::{Kind, not_bam_json, read_log, sniff};
pub use mapping::LogMap;
pub use write::write_csv;

/// Metadata key of the whole seconds taken off a recording's times (`gap`/`fit` shift
/// Unix-epoch stamps; the MCAP reader does it in integer nanoseconds).
pub const KEY_TIME_OFFSET: &str = "time_offset_s";

/// Metadata key parsed into [`Recording::control_rate_hz`].
pub const KEY_CONTROL_RATE: &str = "control_rate_hz";
/// `control_rate_hz: none`: the log declares that no control loop paces its commands (each
/// acts from its own row's time, as a servo takes goals as they arrive); kept in the metadata.
pub const RATE_NONE: &str = "none";
/// Metadata key parsed into [`Recording::control_t0_s`].
pub const KEY_CONTROL_T0: &str = "control_t0_s";

/// Metadata key naming the episode's role in a fit: `train` or `heldout`.
pub const KEY_SPLIT: &str = "split";

/// A recording's declared role (metadata `split`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Split {
    Train,
    Heldout,
}

impl Split {
    pub fn parse(s: &str) -> Option<Split> {
        match s.trim() {
            "train" => Some(Split::Train),
            "heldout" => Some(Split::Heldout),
            _ => None,
        }
    }
}

/// The most median row intervals a recording may span (or 40 per row, if more): a time far
/// from the others is an error at its line ([`Recording::check`]). 10⁵: a 1000 s pause in a
/// 100 Hz log.
pub const MAX_SPAN_INTERVALS: f64 = 1e5;

/// Metadata key set by the CSV reader: how many rows repeated the row before them exactly and
/// were left out.
pub const KEY_DUPLICATE_ROWS: &str = "duplicate_rows_dropped";

const JOINT_SUFFIXES: [&str; 7] = ["q", "qd", "q_cmd", "tau", "kp", "kd", "enabled"];
const BASE_SUFFIXES: [&str; 7] = ["x", "y", "z", "qw", "qx", "qy", "qz"];

/// One recorded episode: a shared time axis plus per-joint and optional base traces.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Recording {
    pub source: PathBuf,
    pub meta: BTreeMap<String, String>,
    pub control_rate_hz: Option<f64>,
    pub control_t0_s: Option<f64>,
    pub t: Vec<f64>,
    pub joints: Vec<JointTrace>,
    pub base: Option<BaseTrace>,
}

/// All traces of one joint; every present vector has the length of [`Recording::t`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointTrace {
    pub name: String,
    pub q: Vec<f64>,
    pub qd: Option<Vec<f64>>,
    pub q_cmd: Option<Vec<f64>>,
    pub tau: Option<Vec<f64>>,
    pub kp: Option<Vec<f64>>,
    pub kd: Option<Vec<f64>>,
    pub enabled: Option<Vec<bool>>,
}

impl JointTrace {
    /// A joint with positions only.
    pub fn new(name: impl Into<String>, q: Vec<f64>) -> Self {
        JointTrace {
            name: name.into(),
            q,
            qd: None,
            q_cmd: None,
            tau: None,
            kp: None,
            kd: None,
            enabled: None,
        }
    }
}

/// Floating-base pose; quaternions are w, x, y, z.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BaseTrace {
    pub pos: Vec<[f64; 3]>,
    pub quat: Vec<[f64; 4]>,
}

/// An error reading a recording: where (file, 1-based line, column) and what.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordingError {
    pub file: PathBuf,
    pub line: Option<usize>,
    pub column: Option<String>,
    pub message: String,
}

impl RecordingError {
    pub fn new(
        file: &Path,
        line: Option<usize>,
        column: Option<&str>,
        message: impl Into<String>,
    ) -> Self {
        RecordingError {
            file: file.to_path_buf(),
            line,
            column: column.map(str::to_string),
            message: message.into(),
        }
    }
}

impl fmt::Display for RecordingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{}: {}", self.file.display(), l, self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

impl std::error::Error for RecordingError {}

/// Options for [`parse_csv_with`].
#[derive(Debug, Clone, Serialize)]
pub struct ParseOptions {
    /// Any joint position (`.q` or `.q_cmd`) with |value| above this is rejected as "looks like
    /// degrees". Default 10.0 rad: above 1.5 turns (3π ≈ 9.42), which no revolute joint of a
    /// legged robot reaches, while 10° already exceeds it. The CSV format does not say which
    /// joints are continuous (wheels, turntables accumulate angle): for such recordings raise
    /// this, e.g. to `f64::INFINITY`.
    pub max_abs_rad: f64,
    /// Columns to skip (glob patterns on the header name, e.g. `imu.*`, `*.temperature`): a
    /// log's extra signals. Any other column that is not `t`, `base.*` or `<joint>.<suffix>`
    /// is an error (a misspelt `q_cmd` must not be dropped silently).
    pub ignore_columns: Vec<String>,
    /// The model's joints, when known: a header naming any other joint is an error at the
    /// header line, before any value is read (a misspelt joint is the first thing to fix).
    pub model_joints: Option<Vec<String>>,
    /// The model's joints that an actuator drives, when known: a recorded one without its
    /// `<joint>.q_cmd` column is an error at the header line (the replay would have no command
    /// for its servo), unless [`ParseOptions::no_command`] names it. A joint no actuator
    /// drives (a passive joint) may be recorded as positions only.
    pub actuated_joints: Option<Vec<String>>,
    /// The model's hinge joints with no range and no position servo, when known (wheels,
    /// turntables): their angle accumulates, and [`ParseOptions::max_abs_rad`] does not apply.
    pub unlimited_joints: Option<Vec<String>>,
    /// Glob patterns on joint names (`--no-command`): driven joints recorded without a command
    /// that are accepted; `gap` and `fit` leave them out of their scores and of the fit
    /// ([`uncommanded_joints`]).
    pub no_command: Vec<String>,
    /// How a log of another format (.npz, parquet, MCAP) maps onto joints (`--log-map` and
    /// the `--log-*` flags).
    pub log_map: LogMap,
}

impl Default for ParseOptions {
    fn default() -> Self {
        ParseOptions {
            max_abs_rad: 10.0,
            ignore_columns: Vec::new(),
            model_joints: None,
            actuated_joints: None,
            unlimited_joints: None,
            no_command: Vec::new(),
            log_map: LogMap::default(),
        }
    }
}

/// The `--no-command` patterns as one matcher; the error names the bad pattern.
pub fn no_command_matcher(patterns: &[String]) -> Result<globset::GlobSet, String> {
    let mut b = globset::GlobSetBuilder::new();
    for g in patterns {
        b.add(globset::Glob::new(g).map_err(|e| format!("--no-command {g}: {e}"))?);
    }
    b.build().map_err(|e| format!("--no-command: {e}"))
}

/// Of the recorded joints `(name, has a command)`, those an actuator drives
/// (`opts.actuated_joints`) that have no command: `Ok` with the ones `opts.no_command` accepts,
/// else `Err` with a message naming every joint that is not accepted. `missing(joint)` says
/// what is missing where (`'elbow.q_cmd' column`, `'goal_position' key`).
pub fn uncommanded_joints<'a>(
    joints: impl IntoIterator<Item = (&'a str, bool)>,
    opts: &ParseOptions,
    missing: impl Fn(&str) -> String,
) -> Result<Vec<String>, String> {
    let Some(actuated) = &opts.actuated_joints else { return Ok(Vec::new()) };
    let accept = no_command_matcher(&opts.no_command)?;
    let (mut accepted, mut refused) = (Vec::new(), Vec::new());
    for (name, has_cmd) in joints {
        if has_cmd || !actuated.iter().any(|a| a == name) {
            continue;
        }
        if accept.is_match(name) {
            accepted.push(name.to_string());
        } else {
            refused.push(name.to_string());
        }
    }
    if refused.is_empty() {
        return Ok(accepted);
    }
    let what: Vec<String> = refused
        .iter()
        .map(|j| format!("joint '{j}' has positions but no {}", missing(j)))
        .collect();
    let one = if refused.len() == 1 { "it" } else { "them" };
    Err(format!(
        "{}, and the model drives {one} with an actuator: without the command the replay cannot \
         know what the servo was tracking (replaying it to its own positions would explain the \
         missing command as physics). Record the command, or leave {one} out of the scores and \
         the fit with --no-command {}",
        what.join("; "),
        refused.join(",")
    ))
}

/// For joints `names` not in `model_joints`: the first one's `.q` column and a message listing
/// each with the closest model joint names (case-insensitive edit distance).
pub(crate) fn unknown_joints<'a>(
    names: impl IntoIterator<Item = &'a str>,
    model_joints: &[String],
) -> Option<(String, String)> {
    let mut problems = Vec::new();
    let mut first_col = None;
    for name in names {
        if model_joints.iter().any(|m| m == name) {
            continue;
        }
        first_col.get_or_insert_with(|| format!("{name}.q"));
        let near = near_matches(name, model_joints, 3);
        if near.is_empty() {
            problems.push(format!("unknown joint '{name}'"));
        } else {
            problems.push(format!(
                "unknown joint '{name}' (did you mean {}?)",
                near.iter().map(|s| format!("'{s}'")).collect::<Vec<_>>().join(", ")
            ));
        }
    }
    let col = first_col?;
    let n = problems.len();
    let head = if n == 1 {
        "a joint not in the model".to_string()
    } else {
        format!("{n} joints not in the model")
    };
    Some((col, format!("{head}: {}", problems.join("; "))))
}

impl Recording {
    /// A test episode ("r.csv", no metadata, no base): `joints` on the time axis `t`, controlled
    /// at 100 Hz with ticks from the first sample.
    #[cfg(test)]
    pub(crate) fn at_100hz(t: Vec<f64>, joints: Vec<JointTrace>) -> Recording {
        Recording {
            source: "r.csv".into(),
            meta: Default::default(),
            control_rate_hz: Some(100.0),
            control_t0_s: None,
            t,
            joints,
            base: None,
        }
    }

    /// Errors unless every recorded joint is one of `model_joints`; the message lists, for each
    /// unknown joint, the closest model joint names (case-insensitive edit distance).
    pub fn validate_joint_names(&self, model_joints: &[String]) -> Result<(), RecordingError> {
        match unknown_joints(self.joints.iter().map(|j| j.name.as_str()), model_joints) {
            None => Ok(()),
            Some((col, msg)) => Err(RecordingError::new(&self.source, None, Some(&col), msg)),
        }
    }

    /// Fills `qd` where absent with the derivative of `q`: the three-point central difference
    /// for irregular spacing (exact for quadratics) inside, one-sided differences at both ends.
    pub fn derive_velocities(&mut self) {
        let t = &self.t;
        for j in &mut self.joints {
            if j.qd.is_none() && j.q.len() == t.len() {
                j.qd = Some(derivative(t, &j.q));
            }
        }
    }

    /// The declared `split` (metadata), if any.
    pub fn split(&self) -> Option<Split> {
        self.meta.get(KEY_SPLIT).and_then(|v| Split::parse(v))
    }

    /// The declared `command_timing` (metadata), if any.
    pub fn command_timing(&self) -> Option<crate::sim2real::commands::CommandTiming> {
        self.meta
            .get(crate::sim2real::commands::KEY_COMMAND_TIMING)
            .and_then(|v| crate::sim2real::commands::CommandTiming::parse(v))
    }

    /// Last time minus first time, 0 when there are fewer than two samples.
    pub fn duration(&self) -> f64 {
        match (self.t.first(), self.t.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }

    pub fn joint(&self, name: &str) -> Option<&JointTrace> {
        self.joints.iter().find(|j| j.name == name)
    }
}

/// First derivative of `x(t)` on an irregular grid (see [`Recording::derive_velocities`]).
pub fn derivative(t: &[f64], x: &[f64]) -> Vec<f64> {
    let n = t.len().min(x.len());
    if n < 2 {
        return vec![0.0; n];
    }
    let mut d = vec![0.0; n];
    d[0] = (x[1] - x[0]) / (t[1] - t[0]);
    d[n - 1] = (x[n - 1] - x[n - 2]) / (t[n - 1] - t[n - 2]);
    for i in 1..n - 1 {
        let h0 = t[i] - t[i - 1];
        let h1 = t[i + 1] - t[i];
        d[i] = (h0 * h0 * x[i + 1] - h1 * h1 * x[i - 1] + (h1 * h1 - h0 * h0) * x[i])
            / (h0 * h1 * (h0 + h1));
    }
    d
}

/// The shortest name (in bytes, of its comparable form) looked for inside another: `kne` is part
/// of a knee's name, `el` of too many.
const MIN_INSIDE: usize = 3;

/// Up to `max` model joint names that `name` (a log's joint) likely means, closest first:
/// the same name once case, separators and the words "joint"/"jnt" are set aside and a lone
/// `l`/`r` is read as left/right (`Elbow_Pitch_joint`, `l_knee`); then one name inside the
/// other (`elbow` for `elbow_pitch`: every such joint; [`MIN_INSIDE`]); then an edit distance of at most
/// max(2, len/3) between those forms (`shouldr`).
fn near_matches(name: &str, candidates: &[String], max: usize) -> Vec<String> {
    let want = joint_key(name);
    let limit = (want.chars().count() / 3).max(2);
    let mut scored: Vec<(usize, usize, &String)> = candidates
        .iter()
        .filter_map(|c| {
            let key = joint_key(c);
            let d = strsim::levenshtein(&want, &key);
            let tier = if key == want {
                0
            } else if want.len().min(key.len()) >= MIN_INSIDE
                && (key.contains(&want) || want.contains(&key))
            {
                1
            } else if d <= limit {
                2
            } else {
                return None;
            };
            Some((tier, d, c))
        })
        .collect();
    scored.sort();
    scored.into_iter().take(max).map(|(.., c)| c.clone()).collect()
}

/// A joint name's comparable form: lower case, words split at separators and case changes,
/// "joint"/"jnt" dropped, a lone `l`/`r` read as left/right, joined without separators.
fn joint_key(name: &str) -> String {
    let mut words: Vec<String> = Vec::new();
    let mut cur = String::new();
    let mut prev_lower = false;
    for ch in name.chars() {
        if !ch.is_alphanumeric() {
            words.push(std::mem::take(&mut cur));
            prev_lower = false;
            continue;
        }
        if ch.is_uppercase() && prev_lower {
            words.push(std::mem::take(&mut cur));
        }
        prev_lower = ch.is_lowercase() || ch.is_ascii_digit();
        cur.extend(ch.to_lowercase());
    }
    words.push(cur);
    words
        .into_iter()
        .filter(|w| !w.is_empty() && w != "joint" && w != "jnt")
        .map(|w| match w.as_str() {
            "l" => "left".to_string(),
            "r" => "right".to_string(),
            _ => w,
        })
        .collect()
}
