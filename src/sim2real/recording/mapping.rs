//! How a log that is not modellint's CSV maps onto a [`Recording`]: which array, column or
//! topic holds the measured positions, the command, the velocities and the time; the joints'
//! names; their units. A small TOML file (`--log-map FILE`) and/or flags (`--log-command`, …;
//! a flag wins over the file). docs/recording-format.md, "Logs of other formats".

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{JointTrace, ParseOptions, Recording, RecordingError};

/// The mapping of a log's signals onto joints (every field optional: each format has defaults).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogMap {
    /// TOML file this mapping was read from (`--log-map`); the flags' fields override it.
    #[serde(skip)]
    pub file: Option<PathBuf>,
    /// Array / column / topic of the measured joint positions.
    pub measured: Option<String>,
    /// Array / column / topic of the position command.
    pub command: Option<String>,
    /// Array / column of the measured joint velocities (else derived from the positions).
    pub velocity: Option<String>,
    /// Array / column of the measured joint torques.
    pub effort: Option<String>,
    /// Array / column of the time stamps (in `time_unit`).
    pub time: Option<String>,
    /// Fixed sample interval [s] when the log has no time stamps.
    pub dt: Option<f64>,
    /// Unit of the time stamps: s (default), ms, us, ns.
    pub time_unit: Option<String>,
    /// The joints of the arrays' columns, in order (model joint names, or names `rename` maps).
    pub joints: Option<Vec<String>>,
    /// MCAP: the joints of a `Float64MultiArray` command's values, in order (default: the
    /// measured JointState's names).
    pub command_joints: Option<Vec<String>>,
    /// The log's joint name → the model's joint name.
    #[serde(default)]
    pub rename: BTreeMap<String, String>,
    /// Joints of the log to leave out (a gripper in percent, a wheel).
    #[serde(default)]
    pub skip: Vec<String>,
    /// Unit of positions and commands: rad (default) or deg (velocities then deg/s).
    pub units: Option<String>,
    /// The controller's rate [Hz] (CSV `control_rate_hz`).
    pub control_rate_hz: Option<f64>,
    /// `in_force` or `sent_after` (CSV `command_timing`).
    pub command_timing: Option<String>,
    /// Read only this episode (LeRobot `episode_index`).
    pub episode: Option<i64>,
}

impl LogMap {
    /// Nothing set (no file, no flag).
    pub fn is_empty(&self) -> bool {
        *self == LogMap::default()
    }

    /// The file's mapping (when `file` is set) with this one's fields over it.
    pub fn resolve(&self) -> Result<LogMap, RecordingError> {
        let Some(file) = &self.file else { return Ok(self.clone()) };
        let base = load(file)?;
        let pick = |a: &Option<String>, b: Option<String>| a.clone().or(b);
        let mut rename = base.rename;
        rename.extend(self.rename.clone());
        let mut skip = base.skip;
        skip.extend(self.skip.iter().cloned());
        Ok(LogMap {
            file: Some(file.clone()),
            measured: pick(&self.measured, base.measured),
            command: pick(&self.command, base.command),
            velocity: pick(&self.velocity, base.velocity),
            effort: pick(&self.effort, base.effort),
            time: pick(&self.time, base.time),
            dt: self.dt.or(base.dt),
            time_unit: pick(&self.time_unit, base.time_unit),
            joints: self.joints.clone().or(base.joints),
            command_joints: self.command_joints.clone().or(base.command_joints),
            rename,
            skip,
            units: pick(&self.units, base.units),
            control_rate_hz: self.control_rate_hz.or(base.control_rate_hz),
            command_timing: pick(&self.command_timing, base.command_timing),
            episode: self.episode.or(base.episode),
        })
    }
}

/// Reads a mapping TOML; errors at `file:line`.
pub fn load(path: &Path) -> Result<LogMap, RecordingError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        RecordingError::new(path, None, None, format!("cannot read the log mapping: {e}"))
    })?;
    let line_of = |off: usize| 1 + text[..off.min(text.len())].matches('\n').count();
    toml::from_str::<LogMap>(&text).map_err(|e| {
        let line = e.span().map(|s| line_of(s.start));
        RecordingError::new(path, line, None, format!("log mapping: {}", e.message()))
    })
}

/// A factor to SI from a position unit (`rad`, `deg`).
pub fn angle_factor(unit: &str) -> Option<f64> {
    match unit.trim() {
        "rad" | "radian" | "radians" => Some(1.0),
        "deg" | "degree" | "degrees" | "°" => Some(PI / 180.0),
        _ => None,
    }
}

/// A factor to seconds from a time unit.
pub fn time_factor(unit: &str) -> Option<f64> {
    match unit.trim() {
        "s" | "sec" | "seconds" => Some(1.0),
        "ms" => Some(1e-3),
        "us" | "µs" => Some(1e-6),
        "ns" => Some(1e-9),
        _ => None,
    }
}

/// The signals a reader found, per joint column, in the file's units, on one time axis.
#[derive(Debug, Default)]
pub(crate) struct Columns {
    /// "NumPy .npz", "LeRobot parquet", "MCAP": for messages and `source_format`.
    pub format: &'static str,
    /// Time stamps in the log's unit ([`LogMap::time_unit`]).
    pub t: Vec<f64>,
    /// The joints' names as the file gives them (JointState names, LeRobot `names`).
    pub names: Option<Vec<String>>,
    /// The key (array, column, topic) of each signal, for messages.
    pub measured_key: String,
    pub command_key: Option<String>,
    pub velocity_key: Option<String>,
    pub effort_key: Option<String>,
    pub time_key: Option<String>,
    /// What the file offers as a command, when no command was found (for the message).
    pub keys: Vec<String>,
    pub q: Vec<Vec<f64>>,
    pub q_cmd: Option<Vec<Vec<f64>>>,
    pub qd: Option<Vec<Vec<f64>>>,
    pub tau: Option<Vec<Vec<f64>>>,
    pub meta: BTreeMap<String, String>,
    pub control_rate_hz: Option<f64>,
    pub control_t0_s: Option<f64>,
    /// `command_timing` the format implies (LeRobot's `action` is sent after the observation).
    pub command_timing: Option<&'static str>,
}

/// The first of `defaults` among `keys` unless `given` names one; `given` not among `keys` is an
/// error listing them.
pub(crate) fn pick(
    given: Option<&str>,
    defaults: &[&str],
    keys: &[String],
    what: &str,
) -> Result<Option<String>, String> {
    if let Some(g) = given {
        if keys.iter().any(|k| k == g) {
            return Ok(Some(g.to_string()));
        }
        return Err(format!("no {what} '{g}' in the file (it has: {})", list(keys)));
    }
    Ok(defaults.iter().find(|d| keys.iter().any(|k| k == *d)).map(|d| d.to_string()))
}

pub(crate) fn list(keys: &[String]) -> String {
    if keys.is_empty() { "nothing".to_string() } else { keys.join(", ") }
}

/// The [`Recording`] of `cols` under `map`: names, renames, skips, units, then the CSV's checks
/// (the model's joints, a driven joint's command, time, degrees).
pub(crate) fn assemble(
    path: &Path,
    cols: Columns,
    map: &LogMap,
    opts: &ParseOptions,
) -> Result<Recording, RecordingError> {
    let err = |msg: String| RecordingError::new(path, None, None, msg);
    let k = cols.q.len();
    let names: Vec<String> = match (&map.joints, &cols.names) {
        (Some(j), _) if j.len() != k => {
            return Err(err(format!(
                "the mapping names {} joint(s), '{}' has {k} column(s)",
                j.len(),
                cols.measured_key
            )));
        }
        (Some(j), _) => j.clone(),
        (None, Some(n)) if n.len() == k => n.clone(),
        (None, Some(n)) => {
            return Err(err(format!(
                "the file names {} joint(s) for the {k} column(s) of '{}': name them with \
                 --log-joints",
                n.len(),
                cols.measured_key
            )));
        }
        (None, None) => {
            return Err(err(format!(
                "{} does not name the joints of '{}' ({k} column(s)): give the model's joint \
                 names in column order with --log-joints a,b,… or `joints = [...]` in a \
                 --log-map file",
                cols.format, cols.measured_key
            )));
        }
    };
    for from in map.rename.keys() {
        if !names.contains(from) {
            return Err(err(format!(
                "rename: no joint '{from}' in the log (its joints: {})",
                list(&names)
            )));
        }
    }
    for s in &map.skip {
        if !names.contains(s) {
            return Err(err(format!(
                "skip: no joint '{s}' in the log (its joints: {})",
                list(&names)
            )));
        }
    }
    non_finite(&cols, &names, map).map_err(err)?;
    let pos = match map.units.as_deref() {
        None => 1.0,
        Some(u) => angle_factor(u).ok_or_else(|| {
            err(format!("units '{u}': not a position unit (rad or deg; velocities follow as …/s)"))
        })?,
    };
    let tf = match map.time_unit.as_deref() {
        None => 1.0,
        Some(u) => time_factor(u)
            .ok_or_else(|| err(format!("time_unit '{u}': not a time unit (s, ms, us, ns)")))?,
    };
    let scale = |v: &[f64], f: f64| -> Vec<f64> { v.iter().map(|x| x * f).collect() };
    let col = |m: &Option<Vec<Vec<f64>>>, c: usize, f: f64| m.as_ref().map(|m| scale(&m[c], f));
    let mut joints = Vec::new();
    for (c, name) in names.iter().enumerate() {
        if map.skip.contains(name) {
            continue;
        }
        let model_name = map.rename.get(name).unwrap_or(name).clone();
        let mut j = JointTrace::new(model_name, scale(&cols.q[c], pos));
        // NaN: a command topic that does not name this joint (MCAP).
        j.q_cmd = col(&cols.q_cmd, c, pos).filter(|v| v.iter().all(|x| !x.is_nan()));
        j.qd = col(&cols.qd, c, pos);
        j.tau = col(&cols.tau, c, 1.0);
        joints.push(j);
    }
    if joints.is_empty() {
        return Err(err("every joint of the log is skipped: nothing to compare".into()));
    }
    let mut meta = cols.meta;
    meta.insert("source_format".into(), cols.format.to_string());
    meta.insert("measured".into(), cols.measured_key.clone());
    if let Some(c) = &cols.command_key {
        meta.insert("command".into(), c.clone());
    }
    if let Some(u) = &map.units {
        meta.insert(super::units::KEY_CONVERTED.into(), u.clone());
    }
    if let Some(ct) = map.command_timing.as_deref().or(cols.command_timing) {
        if crate::sim2real::commands::CommandTiming::parse(ct).is_none() {
            return Err(err(format!("command_timing '{ct}': must be `in_force` or `sent_after`")));
        }
        meta.insert(crate::sim2real::commands::KEY_COMMAND_TIMING.into(), ct.to_string());
    }
    if let Some(r) = map.control_rate_hz
        && !(r.is_finite() && r > 0.0)
    {
        return Err(err(format!("control_rate_hz must be positive, found {r}")));
    }
    let rec = Recording {
        source: path.to_path_buf(),
        meta,
        control_rate_hz: map.control_rate_hz.or(cols.control_rate_hz),
        control_t0_s: cols.control_t0_s.map(|t| t * tf),
        t: scale(&cols.t, tf),
        joints,
        base: None,
    };
    if let Some(model) = &opts.model_joints
        && let Some((_, msg)) =
            super::unknown_joints(rec.joints.iter().map(|j| j.name.as_str()), model)
    {
        return Err(err(format!(
            "{msg} (map the log's names with `[rename]` in a --log-map file, or give them with \
             --log-joints)"
        )));
    }
    let offer = list(&cols.keys);
    let measured = cols.measured_key.clone();
    super::uncommanded_joints(
        rec.joints.iter().map(|j| (j.name.as_str(), j.q_cmd.is_some())),
        opts,
        |_| format!("command in the log (its '{measured}' has no command beside it; name it with --log-command KEY, one of: {offer})"),
    )
    .map_err(err)?;
    rec.check(opts)?;
    Ok(rec)
}

/// The first value that is not a finite number in the signals of the joints the log keeps: the
/// array (column, topic) by its key, the 0-based row (the file's own index: a NumPy array's
/// first axis, a parquet frame, an MCAP message) with its time stamp, the column and its joint.
/// A command column that is NaN throughout is no command (an MCAP command topic that does not
/// name the joint): it is left to [`assemble`].
fn non_finite(cols: &Columns, names: &[String], map: &LogMap) -> Result<(), String> {
    let unit = map.time_unit.as_deref().unwrap_or("s");
    let stamp = |i: usize| match cols.t.get(i) {
        Some(&t) => format!(", time {} {unit}", super::check::seconds_text(t)),
        None => String::new(),
    };
    if let Some(i) = cols.t.iter().position(|x| !x.is_finite()) {
        let key = cols.time_key.as_deref().unwrap_or("time");
        return Err(format!("time '{key}' row {i} (0-based): non-finite value {}", cols.t[i]));
    }
    let signals = [
        (Some(&cols.q), Some(cols.measured_key.as_str()), "positions"),
        (cols.q_cmd.as_ref(), cols.command_key.as_deref(), "commands"),
        (cols.qd.as_ref(), cols.velocity_key.as_deref(), "velocities"),
        (cols.tau.as_ref(), cols.effort_key.as_deref(), "efforts"),
    ];
    for (m, key, what) in signals {
        let Some(m) = m else { continue };
        for (c, v) in m.iter().enumerate() {
            let name = names.get(c).map_or("", String::as_str);
            if map.skip.iter().any(|s| s == name) {
                continue;
            }
            if what == "commands" && v.iter().all(|x| x.is_nan()) {
                continue;
            }
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                let key = key.map_or(format!("the {what}"), |k| format!("'{k}'"));
                return Err(format!(
                    "{key} row {i} (0-based{}), column {c} (joint '{name}'): non-finite value {}",
                    stamp(i),
                    v[i]
                ));
            }
        }
    }
    Ok(())
}

/// Columns (one per joint) of a row-major `n × k` matrix.
pub(crate) fn columns_of(flat: &[f64], n: usize, k: usize) -> Vec<Vec<f64>> {
    (0..k).map(|c| (0..n).map(|i| flat[i * k + c]).collect()).collect()
}
