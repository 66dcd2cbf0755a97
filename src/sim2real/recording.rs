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

use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// Metadata key parsed into [`Recording::control_rate_hz`].
pub const KEY_CONTROL_RATE: &str = "control_rate_hz";
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
}

impl Default for ParseOptions {
    fn default() -> Self {
        ParseOptions { max_abs_rad: 10.0 }
    }
}

/// Reads and parses a CSV recording with default [`ParseOptions`].
pub fn read_csv(path: &Path) -> Result<Recording, RecordingError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| RecordingError::new(path, None, None, format!("cannot read file: {e}")))?;
    parse_csv(path, &text)
}

/// Parses CSV text with default [`ParseOptions`]; `path` is only used for `source` and errors.
pub fn parse_csv(path: &Path, text: &str) -> Result<Recording, RecordingError> {
    parse_csv_with(path, text, &ParseOptions::default())
}

#[derive(Clone, Copy, PartialEq)]
enum Field {
    Time,
    Joint(usize, usize), // joint index, suffix index in JOINT_SUFFIXES
    Base(usize),         // index in BASE_SUFFIXES
}

/// Parses CSV text; see the module docs for the format.
pub fn parse_csv_with(
    path: &Path,
    text: &str,
    opts: &ParseOptions,
) -> Result<Recording, RecordingError> {
    let err = |line: usize, col: Option<&str>, msg: String| {
        RecordingError::new(path, Some(line), col, msg)
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim().is_empty() {
        return Err(err(1, None, "empty file".into()));
    }
    let lines: Vec<(usize, &str)> = text
        .split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
        .collect();

    // Metadata and comments, then the header.
    let mut meta = BTreeMap::new();
    let mut control_rate_hz = None;
    let mut rate_line = None;
    let mut control_t0_s = None;
    let mut idx = 0;
    while idx < lines.len() {
        let (ln, raw) = lines[idx];
        let line = raw.trim();
        if line.is_empty() {
            idx += 1;
            continue;
        }
        let Some(comment) = line.strip_prefix('#') else {
            break;
        };
        idx += 1;
        let Some((k, v)) = comment.split_once(':') else {
            continue;
        };
        let (k, v) = (k.trim(), v.trim());
        if k.is_empty() {
            continue;
        }
        let known = k == KEY_CONTROL_RATE || k == KEY_CONTROL_T0;
        if meta.contains_key(k)
            || (k == KEY_CONTROL_RATE && control_rate_hz.is_some())
            || (k == KEY_CONTROL_T0 && control_t0_s.is_some())
        {
            return Err(err(ln, None, format!("duplicate metadata key '{k}'")));
        }
        if known {
            let x: f64 = v.parse().ok().filter(|x: &f64| x.is_finite()).ok_or_else(|| {
                err(ln, None, format!("metadata '{k}': expected a finite number, found '{v}'"))
            })?;
            if k == KEY_CONTROL_RATE {
                if x <= 0.0 {
                    return Err(err(
                        ln,
                        None,
                        format!("metadata '{k}' must be positive, found {x}"),
                    ));
                }
                control_rate_hz = Some(x);
                rate_line = Some(ln);
            } else {
                control_t0_s = Some(x);
            }
        } else {
            if k == KEY_SPLIT && Split::parse(v).is_none() {
                return Err(err(
                    ln,
                    None,
                    format!("metadata '{k}' must be `train` or `heldout`, found '{v}'"),
                ));
            }
            if k == crate::sim2real::commands::KEY_COMMAND_TIMING
                && crate::sim2real::commands::CommandTiming::parse(v).is_none()
            {
                return Err(err(
                    ln,
                    None,
                    format!("metadata '{k}' must be `in_force` or `sent_after`, found '{v}'"),
                ));
            }
            meta.insert(k.to_string(), v.to_string());
        }
    }
    let Some(&(header_ln, header)) = lines.get(idx) else {
        let last = lines.iter().rev().find(|(_, l)| !l.trim().is_empty()).map_or(1, |(n, _)| *n);
        return Err(err(last, None, "no header row (only metadata/comment lines)".into()));
    };
    idx += 1;

    // Header.
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut fields = Vec::with_capacity(names.len());
    let mut joint_names: Vec<String> = Vec::new();
    let mut joint_cols: Vec<[Option<usize>; 7]> = Vec::new();
    let mut base_cols: [Option<usize>; 7] = [None; 7];
    let mut t_col = None;
    for (ci, &name) in names.iter().enumerate() {
        if name.is_empty() {
            return Err(err(
                header_ln,
                None,
                format!("header: column {} has an empty name", ci + 1),
            ));
        }
        if names[..ci].contains(&name) {
            return Err(err(header_ln, Some(name), format!("header: duplicate column '{name}'")));
        }
        let field = if name == "t" {
            t_col = Some(ci);
            Field::Time
        } else {
            let Some((joint, suffix)) = name.rsplit_once('.') else {
                return Err(err(
                    header_ln,
                    Some(name),
                    format!(
                        "header: column '{name}' is neither 't', 'base.<x|y|z|qw|qx|qy|qz>' nor '<joint>.<suffix>'"
                    ),
                ));
            };
            if joint == "base" && BASE_SUFFIXES.contains(&suffix) {
                let b = BASE_SUFFIXES.iter().position(|s| *s == suffix).unwrap_or(0);
                base_cols[b] = Some(ci);
                Field::Base(b)
            } else {
                let Some(si) = JOINT_SUFFIXES.iter().position(|s| *s == suffix) else {
                    return Err(err(
                        header_ln,
                        Some(name),
                        format!(
                            "header: column '{name}' has unknown suffix '.{suffix}' (expected one of .{})",
                            JOINT_SUFFIXES.join(", .")
                        ),
                    ));
                };
                if joint.is_empty() {
                    return Err(err(
                        header_ln,
                        Some(name),
                        format!("header: column '{name}' has an empty joint name"),
                    ));
                }
                let ji = match joint_names.iter().position(|j| j == joint) {
                    Some(ji) => ji,
                    None => {
                        joint_names.push(joint.to_string());
                        joint_cols.push([None; 7]);
                        joint_names.len() - 1
                    }
                };
                joint_cols[ji][si] = Some(ci);
                Field::Joint(ji, si)
            }
        };
        fields.push(field);
    }
    if t_col.is_none() {
        return Err(err(header_ln, None, "header: no 't' column".into()));
    }
    for (ji, cols) in joint_cols.iter().enumerate() {
        if cols[0].is_none() {
            let present: Vec<String> = cols
                .iter()
                .enumerate()
                .filter(|(_, c)| c.is_some())
                .map(|(si, _)| format!("{}.{}", joint_names[ji], JOINT_SUFFIXES[si]))
                .collect();
            let col = format!("{}.q", joint_names[ji]);
            return Err(err(
                header_ln,
                Some(&col),
                format!(
                    "header: joint '{}' has {} but no '{}' column",
                    joint_names[ji],
                    present.join(", "),
                    col
                ),
            ));
        }
    }
    let n_base = base_cols.iter().filter(|c| c.is_some()).count();
    if n_base != 0 && n_base != 7 {
        let missing: Vec<String> = BASE_SUFFIXES
            .iter()
            .zip(base_cols.iter())
            .filter(|(_, c)| c.is_none())
            .map(|(s, _)| format!("base.{s}"))
            .collect();
        return Err(err(
            header_ln,
            None,
            format!(
                "header: base pose needs all seven columns (base.x base.y base.z base.qw base.qx base.qy base.qz); missing {}",
                missing.join(", ")
            ),
        ));
    }

    // Rows, column-major.
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let mut row_lines: Vec<usize> = Vec::new();
    let mut blank_at: Option<usize> = None;
    for &(ln, raw) in &lines[idx..] {
        if raw.trim().is_empty() {
            blank_at.get_or_insert(ln);
            continue;
        }
        if let Some(b) = blank_at {
            return Err(err(b, None, "empty line inside the data rows".into()));
        }
        let parts: Vec<&str> = raw.split(',').map(str::trim).collect();
        if parts.len() != names.len() {
            return Err(err(
                ln,
                None,
                format!(
                    "expected {} fields, found {}{}",
                    names.len(),
                    parts.len(),
                    if parts.len() < names.len() { " (truncated line?)" } else { "" }
                ),
            ));
        }
        for (ci, s) in parts.iter().enumerate() {
            let v = if let Field::Joint(_, 6) = fields[ci] {
                match *s {
                    "0" | "false" => 0.0,
                    "1" | "true" => 1.0,
                    _ => {
                        return Err(err(
                            ln,
                            Some(names[ci]),
                            format!("column '{}': expected 0 or 1, found '{s}'", names[ci]),
                        ));
                    }
                }
            } else {
                parse_num(s)
                    .map_err(|m| err(ln, Some(names[ci]), format!("column '{}': {m}", names[ci])))?
            };
            cols[ci].push(v);
        }
        row_lines.push(ln);
    }
    if row_lines.len() < 2 {
        let ln = row_lines.last().copied().unwrap_or(header_ln);
        return Err(err(ln, None, format!("need at least 2 data rows, found {}", row_lines.len())));
    }

    let take = |c: Option<usize>, cols: &mut Vec<Vec<f64>>| c.map(|c| std::mem::take(&mut cols[c]));
    let t = take(t_col, &mut cols).unwrap_or_default();
    let mut joints = Vec::with_capacity(joint_names.len());
    for (name, jc) in joint_names.into_iter().zip(joint_cols.iter()) {
        joints.push(JointTrace {
            name,
            q: take(jc[0], &mut cols).unwrap_or_default(),
            qd: take(jc[1], &mut cols),
            q_cmd: take(jc[2], &mut cols),
            tau: take(jc[3], &mut cols),
            kp: take(jc[4], &mut cols),
            kd: take(jc[5], &mut cols),
            enabled: take(jc[6], &mut cols).map(|v| v.into_iter().map(|x| x != 0.0).collect()),
        });
    }
    let base = if n_base == 7 {
        let b: Vec<Vec<f64>> =
            base_cols.iter().map(|c| take(*c, &mut cols).unwrap_or_default()).collect();
        Some(BaseTrace {
            pos: (0..t.len()).map(|i| [b[0][i], b[1][i], b[2][i]]).collect(),
            quat: (0..t.len()).map(|i| [b[3][i], b[4][i], b[5][i], b[6][i]]).collect(),
        })
    } else {
        None
    };
    let rec = Recording {
        source: path.to_path_buf(),
        meta,
        control_rate_hz,
        control_t0_s,
        t,
        joints,
        base,
    };
    rec.check_inner(opts, Some(&row_lines))?;
    if let (Some(rate), Some(ln)) = (rec.control_rate_hz, rate_line) {
        let timing = rec.command_timing().unwrap_or_default();
        let t0 = rec.control_t0_s.unwrap_or(rec.t[0]);
        let tick = |x: f64| crate::sim2real::commands::tick_of(x, t0, rate, timing);
        if tick(rec.t[0]) == tick(rec.t[rec.t.len() - 1]) {
            return Err(err(
                ln,
                None,
                format!(
                    "control_rate_hz {rate} puts all {} rows ({} s … {} s) into one control tick: the rate is too low \
                     for these timestamps (are the times in seconds?)",
                    rec.t.len(),
                    rec.t[0],
                    rec.t[rec.t.len() - 1]
                ),
            ));
        }
    }
    Ok(rec)
}

fn parse_num(s: &str) -> Result<f64, String> {
    if s.is_empty() {
        return Err("empty field".into());
    }
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) => Err(format!("non-finite value '{s}' ({x})")),
        Err(_) => Err(format!("cannot parse '{s}' as a number")),
    }
}

/// Serialises a recording; `parse_csv(write_csv(r))` gives back `r` exactly (except `source`)
/// for any recording `parse_csv` would accept. Metadata keys must not contain ':' and neither
/// keys nor values may contain line breaks (they are replaced by spaces) or begin/end with spaces.
pub fn write_csv(rec: &Recording) -> String {
    use std::fmt::Write;
    let clean = |s: &str| s.replace(['\r', '\n'], " ");
    let mut out = String::new();
    if let Some(r) = rec.control_rate_hz {
        let _ = writeln!(out, "# {KEY_CONTROL_RATE}: {r}");
    }
    if let Some(t0) = rec.control_t0_s {
        let _ = writeln!(out, "# {KEY_CONTROL_T0}: {t0}");
    }
    for (k, v) in &rec.meta {
        if k == KEY_CONTROL_RATE || k == KEY_CONTROL_T0 {
            continue;
        }
        let _ = writeln!(out, "# {}: {}", clean(k), clean(v));
    }
    let mut header = vec!["t".to_string()];
    for j in &rec.joints {
        let present = [
            true,
            j.qd.is_some(),
            j.q_cmd.is_some(),
            j.tau.is_some(),
            j.kp.is_some(),
            j.kd.is_some(),
            j.enabled.is_some(),
        ];
        for (si, p) in present.iter().enumerate() {
            if *p {
                header.push(format!("{}.{}", j.name, JOINT_SUFFIXES[si]));
            }
        }
    }
    if rec.base.is_some() {
        header.extend(BASE_SUFFIXES.iter().map(|s| format!("base.{s}")));
    }
    out.push_str(&header.join(","));
    out.push('\n');
    let num =
        |v: Option<&Vec<f64>>, i: usize| v.and_then(|v| v.get(i)).copied().unwrap_or(f64::NAN);
    for i in 0..rec.t.len() {
        let _ = write!(out, "{}", rec.t[i]);
        for j in &rec.joints {
            let _ = write!(out, ",{}", num(Some(&j.q), i));
            for v in [&j.qd, &j.q_cmd, &j.tau, &j.kp, &j.kd].into_iter().flatten() {
                let _ = write!(out, ",{}", num(Some(v), i));
            }
            if let Some(e) = &j.enabled {
                out.push_str(if e.get(i).copied().unwrap_or(false) { ",1" } else { ",0" });
            }
        }
        if let Some(b) = &rec.base {
            let p = b.pos.get(i).copied().unwrap_or([f64::NAN; 3]);
            let q = b.quat.get(i).copied().unwrap_or([f64::NAN; 4]);
            for v in p.iter().chain(q.iter()) {
                let _ = write!(out, ",{v}");
            }
        }
        out.push('\n');
    }
    out
}

impl Recording {
    /// Checks consistency (lengths, finiteness, strictly increasing time, at least two samples,
    /// positions not in degrees). Errors name the sample index (no line numbers).
    pub fn check(&self, opts: &ParseOptions) -> Result<(), RecordingError> {
        self.check_inner(opts, None)
    }

    /// `row_lines[i]` is the 1-based source line of sample `i`, when known.
    fn check_inner(
        &self,
        opts: &ParseOptions,
        row_lines: Option<&[usize]>,
    ) -> Result<(), RecordingError> {
        let line = |i: usize| row_lines.and_then(|r| r.get(i).copied());
        let at = |i: usize| match line(i) {
            Some(l) => format!("line {l}"),
            None => format!("sample {i}"),
        };
        let err = |i: usize, col: Option<&str>, msg: String| {
            RecordingError::new(&self.source, line(i), col, msg)
        };
        let n = self.t.len();
        if n < 2 {
            return Err(err(0, None, format!("need at least 2 samples, found {n}")));
        }
        for (i, &x) in self.t.iter().enumerate() {
            if !x.is_finite() {
                return Err(err(i, Some("t"), format!("non-finite time {x}")));
            }
            if i > 0 && x <= self.t[i - 1] {
                return Err(err(
                    i,
                    Some("t"),
                    format!(
                        "time not strictly increasing: t = {x} at {} is not after t = {} at {}",
                        at(i),
                        self.t[i - 1],
                        at(i - 1)
                    ),
                ));
            }
        }
        let check_vec = |col: &str, v: &[f64]| -> Result<(), RecordingError> {
            if v.len() != n {
                return Err(err(
                    0,
                    Some(col),
                    format!("column '{col}' has {} samples, time has {n}", v.len()),
                ));
            }
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(err(
                    i,
                    Some(col),
                    format!("column '{col}': non-finite value {}", v[i]),
                ));
            }
            Ok(())
        };
        for j in &self.joints {
            let named = [
                ("q", Some(&j.q)),
                ("qd", j.qd.as_ref()),
                ("q_cmd", j.q_cmd.as_ref()),
                ("tau", j.tau.as_ref()),
                ("kp", j.kp.as_ref()),
                ("kd", j.kd.as_ref()),
            ];
            for (suffix, v) in named {
                if let Some(v) = v {
                    check_vec(&format!("{}.{suffix}", j.name), v)?;
                }
            }
            if let Some(e) = &j.enabled
                && e.len() != n
            {
                let col = format!("{}.enabled", j.name);
                return Err(err(
                    0,
                    Some(&col),
                    format!("column '{col}' has {} samples, time has {n}", e.len()),
                ));
            }
            for (suffix, v) in [("q", Some(&j.q)), ("q_cmd", j.q_cmd.as_ref())] {
                let Some(v) = v else { continue };
                if let Some(i) = v.iter().position(|x| x.abs() > opts.max_abs_rad) {
                    let col = format!("{}.{suffix}", j.name);
                    return Err(err(
                        i,
                        Some(&col),
                        format!(
                            "column '{col}': |{}| > {} rad at t = {}: looks like degrees (positions must be in radians; \
                         for continuous joints raise max_abs_rad)",
                            v[i], opts.max_abs_rad, self.t[i]
                        ),
                    ));
                }
            }
        }
        if let Some(b) = &self.base {
            if b.pos.len() != n || b.quat.len() != n {
                return Err(err(
                    0,
                    Some("base.x"),
                    format!("base pose has {}/{} samples, time has {n}", b.pos.len(), b.quat.len()),
                ));
            }
            let bad = b
                .pos
                .iter()
                .zip(b.quat.iter())
                .position(|(p, q)| p.iter().chain(q.iter()).any(|x| !x.is_finite()));
            if let Some(i) = bad {
                return Err(err(i, Some("base.x"), "base pose: non-finite value".into()));
            }
        }
        Ok(())
    }

    /// Errors unless every recorded joint is one of `model_joints`; the message lists, for each
    /// unknown joint, the closest model joint names (case-insensitive edit distance).
    pub fn validate_joint_names(&self, model_joints: &[String]) -> Result<(), RecordingError> {
        let mut problems = Vec::new();
        let mut first_col = None;
        for j in &self.joints {
            if model_joints.contains(&j.name) {
                continue;
            }
            first_col.get_or_insert_with(|| format!("{}.q", j.name));
            let near = near_matches(&j.name, model_joints, 3);
            if near.is_empty() {
                problems.push(format!("unknown joint '{}'", j.name));
            } else {
                problems.push(format!(
                    "unknown joint '{}' (did you mean {}?)",
                    j.name,
                    near.iter().map(|s| format!("'{s}'")).collect::<Vec<_>>().join(", ")
                ));
            }
        }
        if problems.is_empty() {
            return Ok(());
        }
        Err(RecordingError::new(
            &self.source,
            None,
            first_col.as_deref(),
            format!("{} not in the model: {}", problems.len(), problems.join("; ")),
        ))
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

    /// Last time minus first time, 0 when there are fewer than two samples.
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

fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.to_lowercase().chars().collect();
    let b: Vec<char> = b.to_lowercase().chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for i in 1..=a.len() {
        cur[0] = i;
        for k in 1..=b.len() {
            let sub = prev[k - 1] + usize::from(a[i - 1] != b[k - 1]);
            cur[k] = sub.min(prev[k] + 1).min(cur[k - 1] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// Up to `max` candidates within edit distance max(2, len/3) of `name`, closest first.
fn near_matches(name: &str, candidates: &[String], max: usize) -> Vec<String> {
    let limit = (name.chars().count() / 3).max(2);
    let mut scored: Vec<(usize, &String)> = candidates
        .iter()
        .map(|c| (edit_distance(name, c), c))
        .filter(|(d, _)| *d <= limit)
        .collect();
    scored.sort();
    scored.into_iter().take(max).map(|(_, c)| c.clone()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("rec.csv")
    }

    const GOOD: &str = "# control_rate_hz: 100\r\n# robot: t1\r\n# plain comment\r\n\
        t, knee.q ,knee.q_cmd,knee.enabled,hip.q,hip.qd\r\n\
        0.0, 0.1, 0.2, 1, -0.5, 0.25\r\n\
        0.013,0.11,0.21,0,-0.4,1e-3\r\n\
        0.02,0.12,0.22,1,-0.3,0\r\n\r\n";

    fn parse_err(text: &str) -> RecordingError {
        match parse_csv(p(), text) {
            Ok(r) => panic!("expected an error, parsed {r:?}"),
            Err(e) => e,
        }
    }

    #[test]
    fn parses_crlf_metadata_spaces_and_trailing_blank() {
        let r = parse_csv(p(), GOOD).expect("parses");
        assert_eq!(r.control_rate_hz, Some(100.0));
        assert_eq!(r.meta.get("robot").map(String::as_str), Some("t1"));
        assert_eq!(r.meta.len(), 1);
        assert_eq!(r.t, vec![0.0, 0.013, 0.02]);
        assert_eq!(r.joints.len(), 2);
        let knee = r.joint("knee").expect("knee");
        assert_eq!(knee.q, vec![0.1, 0.11, 0.12]);
        assert_eq!(knee.q_cmd.as_deref(), Some(&[0.2, 0.21, 0.22][..]));
        assert_eq!(knee.enabled.as_deref(), Some(&[true, false, true][..]));
        assert!(knee.qd.is_none());
        assert_eq!(r.joint("hip").and_then(|h| h.qd.clone()), Some(vec![0.25, 1e-3, 0.0]));
        assert!((r.duration() - 0.02).abs() < 1e-15);
        assert!(r.base.is_none());
    }

    #[test]
    fn round_trips_exactly() {
        let mut r = parse_csv(p(), GOOD).expect("parses");
        r.control_t0_s = Some(-0.0025);
        r.meta.insert("note".into(), "a: b, c".into());
        r.t = vec![0.0, 0.1 + 0.2, 1.0 / 3.0];
        r.joints[0].tau = Some(vec![1e-300, -2.5e-8, 123456.789]);
        r.joints[0].kp = Some(vec![75.0; 3]);
        r.joints[0].kd = Some(vec![5.0; 3]);
        r.base = Some(BaseTrace {
            pos: vec![[0.1, -0.2, 0.7]; 3],
            quat: vec![[1.0, 0.0, -0.0, std::f64::consts::FRAC_1_SQRT_2]; 3],
        });
        let text = write_csv(&r);
        let back = parse_csv(p(), &text).expect("re-parses");
        assert_eq!(back, r);
        assert_eq!(write_csv(&back), text);
    }

    #[test]
    fn structural_errors() {
        let e = parse_err("");
        assert_eq!((e.line, e.message.as_str()), (Some(1), "empty file"));
        let e = parse_err("# a: b\n# c: d\n");
        assert_eq!(e.line, Some(2));
        assert!(e.message.contains("no header"), "{e}");
        assert!(parse_err("x.q\n1\n2\n").message.contains("no 't' column"));
        let e = parse_err("t,a.q,a.q\n0,1,1\n1,1,1\n");
        assert!(e.message.contains("duplicate column 'a.q'") && e.line == Some(1), "{e}");
        let e = parse_err("t,a.q,a.vel\n0,1,1\n1,1,1\n");
        assert!(
            e.message.contains("unknown suffix '.vel'") && e.column.as_deref() == Some("a.vel"),
            "{e}"
        );
        let e = parse_err("t,a.qd\n0,1\n1,1\n");
        assert!(e.message.contains("no 'a.q' column"), "{e}");
        let e = parse_err("t,a.q,base.x,base.y,base.z\n0,0,0,0,0\n1,0,0,0,0\n");
        assert!(e.message.contains("missing base.qw"), "{e}");
        let e = parse_err("t,a.q\n0,1\n");
        assert!(e.message.contains("at least 2") && e.line == Some(2), "{e}");
        assert!(parse_err("t,a.q\n").message.contains("found 0"));
        let e = parse_err("t,a.q\n0,1\n\n1,2\n");
        assert_eq!(e.line, Some(3));
    }

    #[test]
    fn row_errors_name_the_line() {
        let e = parse_err("# k: v\nt,a.q,a.q_cmd\n0,1,1\n0.1,1\n");
        assert_eq!(e.line, Some(4));
        assert!(e.message.contains("truncated"), "{e}");
        assert_eq!(e.to_string(), "rec.csv:4: expected 3 fields, found 2 (truncated line?)");
        let e = parse_err("t,a.q\n0,1\n0.1,1.o\n");
        assert!(
            e.line == Some(3) && e.column.as_deref() == Some("a.q") && e.message.contains("'1.o'"),
            "{e}"
        );
        for bad in ["NaN", "inf", "-infinity"] {
            let e = parse_err(&format!("t,a.q\n0,1\n0.1,{bad}\n"));
            assert!(e.line == Some(3) && e.message.contains("non-finite"), "{e}");
        }
        let e = parse_err("t,a.q\n0,1\n0.2,1\n0.1,1\n");
        assert_eq!(e.line, Some(4));
        assert!(e.message.contains("t = 0.1 at line 4 is not after t = 0.2 at line 3"), "{e}");
        let e = parse_err("t,a.q\n0,1\n0,1\n");
        assert!(e.message.contains("not strictly increasing"), "{e}");
        let e = parse_err("t,a.q,a.enabled\n0,1,1\n0.1,1,2\n");
        assert!(e.message.contains("expected 0 or 1"), "{e}");
        let e = parse_err("t,a.q\n0,,\n");
        assert!(e.message.contains("expected 2 fields, found 3"), "{e}");
        let e = parse_err("t,a.q\n0,\n1,1\n");
        assert!(e.message.contains("empty field"), "{e}");
        let e = parse_err("# control_rate_hz: fast\nt,a.q\n0,1\n1,1\n");
        assert_eq!(e.line, Some(1));
    }

    #[test]
    fn split_timing_and_one_tick_errors_name_the_line() {
        let e = parse_err("# robot: a\n# split: test\nt,a.q\n0,1\n1,1\n");
        assert_eq!(e.line, Some(2));
        assert!(e.message.contains("train") && e.message.contains("heldout"), "{}", e.message);
        let e = parse_err("# command_timing: later\nt,a.q\n0,1\n1,1\n");
        assert_eq!(e.line, Some(1));
        let e = parse_err("# x: 1\n# control_rate_hz: 0.5\nt,a.q\n0,1\n0.5,1\n1.9,1\n");
        assert_eq!(e.line, Some(2));
        assert!(e.message.contains("one control tick"), "{}", e.message);
        let e = parse_err("# control_rate_hz: -3\nt,a.q\n0,1\n1,1\n");
        assert_eq!(e.line, Some(1));
        let ok = parse_csv(p(), "# split: heldout\n# command_timing: sent_after\n# control_rate_hz: 1\nt,a.q\n0,1\n1,1\n").unwrap();
        assert_eq!(ok.split(), Some(Split::Heldout));
        assert_eq!(ok.command_timing(), Some(crate::sim2real::commands::CommandTiming::SentAfter));
    }

    #[test]
    fn degrees_are_rejected_with_adjustable_threshold() {
        let text = "t,knee.q\n0,10\n0.01,45\n0.02,90\n";
        let e = parse_err(text);
        assert_eq!(e.line, Some(3));
        assert!(e.message.contains("looks like degrees"), "{e}");
        let ok = parse_csv_with(p(), text, &ParseOptions { max_abs_rad: f64::INFINITY });
        assert!(ok.is_ok());
        let e = parse_err("t,knee.q,knee.q_cmd\n0,0,0\n0.01,0,-30\n");
        assert_eq!(e.column.as_deref(), Some("knee.q_cmd"));
    }

    #[test]
    fn joint_name_validation_suggests_near_matches() {
        let r = parse_csv(p(), "t,Left_Knee_Pitc.q,Waist.q\n0,0,0\n1,0,0\n").expect("parses");
        let model: Vec<String> = ["Left_Knee_Pitch", "Right_Knee_Pitch", "Waist", "AAHead_yaw"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let e = r.validate_joint_names(&model).expect_err("unknown joint");
        assert!(
            e.message.contains("unknown joint 'Left_Knee_Pitc' (did you mean 'Left_Knee_Pitch'"),
            "{e}"
        );
        assert!(!e.message.contains("Waist"), "{e}");
        let r2 = parse_csv(p(), "t,waist.q,Zzz.q\n0,0,0\n1,0,0\n").expect("parses");
        let e = r2.validate_joint_names(&model).expect_err("unknown");
        assert!(e.message.contains("'waist' (did you mean 'Waist'?)"), "{e}");
        assert!(e.message.ends_with("unknown joint 'Zzz'"), "{e}");
        let r3 = parse_csv(p(), "t,Waist.q\n0,0\n1,0\n").expect("parses");
        assert!(r3.validate_joint_names(&model).is_ok());
    }

    #[test]
    fn derived_velocities_exact_for_quadratic_on_irregular_grid() {
        let t = vec![0.0, 0.004, 0.011, 0.015, 0.022, 0.03];
        let q: Vec<f64> = t.iter().map(|&x| 1.0 + 2.0 * x - 3.0 * x * x).collect();
        let mut r = Recording {
            source: p().into(),
            meta: BTreeMap::new(),
            control_rate_hz: None,
            control_t0_s: None,
            t: t.clone(),
            joints: vec![JointTrace::new("a", q)],
            base: None,
        };
        let mut keep = JointTrace::new("b", vec![0.0; 6]);
        keep.qd = Some(vec![7.0; 6]);
        r.joints.push(keep);
        r.derive_velocities();
        let qd = r.joints[0].qd.as_ref().expect("derived");
        for i in 1..t.len() - 1 {
            assert!(
                (qd[i] - (2.0 - 6.0 * t[i])).abs() < 1e-9,
                "i={i} {} vs {}",
                qd[i],
                2.0 - 6.0 * t[i]
            );
        }
        assert!((qd[0] - (2.0 - 3.0 * 0.004)).abs() < 1e-9);
        assert_eq!(r.joints[1].qd, Some(vec![7.0; 6]));
    }
}
