//! A CSV whose columns are named otherwise than modellint's (`t, q_shoulder, qd_shoulder,
//! u_shoulder`, or `timestamp_ns, pos_0, pos_1, target_0, target_1`) read through a
//! `--log-map` mapping: the header is rewritten to modellint's names (`t`, `<joint>.q`,
//! `<joint>.q_cmd`, …) and the mapping's units and rate become metadata lines, each kept on its
//! own line number, so that the CSV reader's checks and its `file:line` errors apply unchanged.
//! docs/recording-format.md, "Logs of other formats".

use std::collections::BTreeMap;
use std::path::Path;

use super::mapping::{LogMap, angle_factor, time_factor};
use super::{BASE_SUFFIXES, JOINT_SUFFIXES, KEY_CONTROL_RATE, RecordingError};
use crate::sim2real::commands::KEY_COMMAND_TIMING;

/// The column suffix each signal of the mapping becomes.
const SIGNALS: [(&str, &str); 4] =
    [("measured", "q"), ("command", "q_cmd"), ("velocity", "qd"), ("effort", "tau")];

/// Separators between a signal's key and the joint's name or index in a column name.
const SEPARATORS: [char; 5] = ['_', '.', '-', ':', '['];

/// The suffix a skipped joint's columns get (`3.skipped-by-log-map`), to be ignored.
pub(super) const SKIPPED: &str = "skipped-by-log-map";

/// Time columns taken when the mapping names none and the file has no `t`.
const TIME_DEFAULTS: [&str; 4] = ["t", "time", "timestamp", "stamp"];

/// A CSV rewritten by [`remap`].
pub(super) struct Remapped {
    /// The file's lines (1-based number, text), header and metadata rewritten.
    pub lines: Vec<(usize, String)>,
    /// Whether a joint's columns are skipped (renamed `<index>.`[`SKIPPED`]: the caller ignores
    /// them).
    pub skipped: bool,
    /// (modellint's name, the column as the file names it) of every renamed column: an error
    /// the reader raises on the rewritten text names the column as the user wrote it.
    pub renamed: Vec<(String, String)>,
}

impl Remapped {
    /// `e` with every quoted rewritten column name (`'elbow.q_cmd'`) replaced by the file's own
    /// (`'target_elbow'`), in the message and in the error's column.
    pub fn name_columns_as_written(&self, mut e: RecordingError) -> RecordingError {
        for (new, old) in &self.renamed {
            e.message = e.message.replace(&format!("'{new}'"), &format!("'{old}'"));
            if e.column.as_deref() == Some(new.as_str()) {
                e.column = Some(old.clone());
            }
        }
        e
    }
}

/// A CSV's lines with the header and metadata rewritten under `map` (`ignore`: the
/// `--ignore-columns` patterns, columns the mapping need not name). `header_idx` is the index
/// of the header line in `lines`.
pub(super) fn remap(
    path: &Path,
    lines: &[(usize, &str)],
    header_idx: usize,
    map: &LogMap,
    ignore: &[String],
) -> Result<Remapped, RecordingError> {
    let (header_ln, header) = lines[header_idx];
    let err = |ln: usize, msg: String| RecordingError::new(path, Some(ln), None, msg);
    let map_err = |msg: String| {
        let file = map.file.as_ref().map_or(String::new(), |f| format!(" ({})", f.display()));
        err(header_ln, format!("--log-map{file}: {msg}"))
    };
    if map.command_joints.is_some() || map.episode.is_some() {
        return Err(map_err(
            "`command_joints` (MCAP) and `episode` (LeRobot) do not apply to a CSV".into(),
        ));
    }
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let listed = || cols.join(", ");
    let mut out: Vec<String> = cols.iter().map(|c| c.to_string()).collect();
    let mut skipped = false;
    // The time column.
    let time =
        match &map.time {
            Some(k) => Some(find_exact(&cols, k).ok_or_else(|| {
                map_err(missing(&format!("time column '{k}'"), k, &cols, &listed()))
            })?),
            None => TIME_DEFAULTS.iter().find_map(|d| find_exact(&cols, d)),
        };
    match (time, map.dt) {
        (Some(_), Some(_)) => {
            return Err(map_err("give either a time column or `dt`, not both".into()));
        }
        (None, None) => {
            return Err(map_err(format!(
                "no time column: name it with `time = \"COLUMN\"` (or give `dt` for rows at a \
                 fixed interval); the file's columns: {}",
                listed()
            )));
        }
        (Some(i), None) => out[i] = "t".into(),
        (None, Some(dt)) if !(dt.is_finite() && dt > 0.0) => {
            return Err(map_err(format!("dt must be a positive number of seconds, found {dt}")));
        }
        (None, Some(_)) => {}
    }
    // The joints' signals: `KEY<sep>NAME` / `NAME<sep>KEY` (NAME a joint's name, or its index in
    // `joints`), or `KEY` alone for a single joint named by `joints`.
    let mut keyed: Vec<(&str, &str, &String)> = SIGNALS
        .iter()
        .zip([&map.measured, &map.command, &map.velocity, &map.effort])
        .filter_map(|((what, suffix), k)| k.as_ref().map(|k| (*what, *suffix, k)))
        .collect();
    if let Some((what, ..)) = keyed.iter().find(|(_, _, k)| k.trim().is_empty()) {
        return Err(map_err(format!("`{what}` is empty: name the signal's columns")));
    }
    // The longest key first: `pos_des_0` is the command `pos_des`'s, not `pos`'s joint `des_0`.
    keyed.sort_by_key(|(_, _, k)| std::cmp::Reverse(k.len()));
    let mut taken = vec![false; cols.len()];
    let joint_of = |name: &str| -> Result<Option<String>, RecordingError> {
        let log_name = match (name.parse::<usize>(), &map.joints) {
            (Ok(i), Some(j)) => j.get(i).cloned().ok_or_else(|| {
                map_err(format!(
                    "column index {i} but `joints` names {} joint(s) ({})",
                    j.len(),
                    j.join(", ")
                ))
            })?,
            (Ok(i), None) => {
                return Err(map_err(format!(
                    "columns numbered by joint ({i}): give the model's joint names in that order \
                     with `joints = [...]` (or --log-joints)"
                )));
            }
            (Err(_), _) => name.to_string(),
        };
        if map.skip.contains(&log_name) {
            return Ok(None);
        }
        Ok(Some(map.rename.get(&log_name).cloned().unwrap_or(log_name)))
    };
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for (what, suffix, key) in &keyed {
        let mut found = 0;
        for (ci, c) in cols.iter().enumerate() {
            if Some(ci) == time || taken[ci] {
                continue;
            }
            let name = if *c == key.as_str() {
                match map.joints.as_deref() {
                    Some([one]) => Some(one.clone()),
                    _ => None,
                }
            } else {
                split_key(c, key)
            };
            let Some(name) = name else { continue };
            found += 1;
            taken[ci] = true;
            match joint_of(&name)? {
                Some(j) => {
                    let new = format!("{j}.{suffix}");
                    if let Some(prev) = seen.insert(new.clone(), ci) {
                        return Err(map_err(format!(
                            "columns '{}' and '{c}' both map to '{new}'",
                            cols[prev]
                        )));
                    }
                    out[ci] = new;
                }
                None => {
                    out[ci] = format!("{ci}.{SKIPPED}");
                    skipped = true;
                }
            }
        }
        if found == 0 {
            let shapes = format!("'{key}', '{key}_<joint>', '<joint>_{key}'");
            return Err(map_err(missing(
                &format!("{what} column(s) {shapes}"),
                key,
                &cols,
                &listed(),
            )));
        }
    }
    // A standard `<joint>.<suffix>` column of a joint the mapping renames.
    for (ci, c) in cols.iter().enumerate() {
        if out[ci] != *c || Some(ci) == time {
            continue;
        }
        if let Some((j, s)) = c.rsplit_once('.') {
            if map.skip.iter().any(|x| x == j) {
                out[ci] = format!("{ci}.{SKIPPED}");
                skipped = true;
            } else if let Some(to) = map.rename.get(j) {
                out[ci] = format!("{to}.{s}");
            }
        }
    }
    // A column the mapping names nothing of, and that is not modellint's own: say what the
    // mapping reads, so that a velocity or torque column is added to it (or skipped).
    let ignored = |c: &str| {
        ignore.iter().any(|g| globset::Glob::new(g).is_ok_and(|g| g.compile_matcher().is_match(c)))
    };
    for (ci, c) in cols.iter().enumerate() {
        let own = c.rsplit_once('.').is_some_and(|(j, s)| {
            (j == "base" && BASE_SUFFIXES.contains(&s)) || JOINT_SUFFIXES.contains(&s)
        });
        if out[ci] == *c && Some(ci) != time && !own && !ignored(c) {
            let read: Vec<String> = keyed.iter().map(|(w, _, k)| format!("{w} '{k}'")).collect();
            return Err(map_err(format!(
                "column '{c}' is named by no key of the mapping (it reads {}): add its signal \
                 (`measured`, `command`, `velocity`, `effort` = its key), or skip it with \
                 --ignore-columns '{c}'",
                if read.is_empty() { "the time only".to_string() } else { read.join(", ") }
            )));
        }
    }
    for from in map.rename.keys().chain(&map.skip) {
        let named = |c: &&str| {
            c.rsplit_once('.').is_some_and(|(j, _)| j == from)
                || keyed.iter().any(|(_, _, k)| split_key(c, k).as_deref() == Some(from.as_str()))
        };
        let by_index = map.joints.as_ref().is_some_and(|j| j.contains(from));
        if !by_index && !cols.iter().any(named) {
            return Err(map_err(format!("no joint '{from}' in the file's columns ({})", listed())));
        }
    }
    // Metadata the mapping declares, on the header's line number (before it, as the reader
    // wants metadata).
    let meta_keys: Vec<&str> = lines[..header_idx]
        .iter()
        .filter_map(|(_, l)| l.trim().strip_prefix('#')?.split_once(':').map(|(k, _)| k.trim()))
        .collect();
    let mut meta: Vec<String> = Vec::new();
    let mut units = Vec::new();
    if let Some(u) = &map.units {
        let f = angle_factor(u)
            .ok_or_else(|| map_err(format!("units '{u}': not a position unit (rad or deg)")))?;
        if f != 1.0 {
            units.push("deg, deg/s".to_string());
        }
    }
    if let Some(u) = &map.time_unit {
        time_factor(u)
            .ok_or_else(|| map_err(format!("time_unit '{u}': not a time unit (s, ms, us, ns)")))?;
        if u.trim() != "s" {
            units.push(format!("t={}", u.trim()));
        }
    }
    let mut declare = |key: &str, value: String| {
        if meta_keys.contains(&key) {
            let example =
                if key == super::units::KEY_UNITS { " (`# units: deg, deg/s`)" } else { "" };
            return Err(map_err(format!(
                "the file declares `# {key}:` already{example}, and the mapping (or a --log-* \
                 flag) declares it again: give it in one place"
            )));
        }
        meta.push(format!("# {key}: {value}"));
        Ok(())
    };
    if !units.is_empty() {
        declare(super::units::KEY_UNITS, units.join(", "))?;
    }
    if let Some(r) = map.control_rate_hz {
        declare(KEY_CONTROL_RATE, r.to_string())?;
    }
    if let Some(ct) = &map.command_timing {
        declare(KEY_COMMAND_TIMING, ct.clone())?;
    }
    let mut text: Vec<(usize, String)> = lines[..header_idx]
        .iter()
        .map(|(n, l)| (*n, l.to_string()))
        .chain(meta.into_iter().map(|m| (header_ln, m)))
        .collect();
    let dt = if time.is_none() { map.dt } else { None };
    let mut head = out.join(",");
    if dt.is_some() {
        head = format!("t,{head}");
    }
    text.push((header_ln, head));
    let mut row = 0usize;
    for &(n, l) in &lines[header_idx + 1..] {
        match dt {
            Some(dt) if !l.trim().is_empty() && !l.trim_start().starts_with('#') => {
                text.push((n, format!("{},{l}", dt * row as f64)));
                row += 1;
            }
            _ => text.push((n, l.to_string())),
        }
    }
    let renamed = cols
        .iter()
        .zip(&out)
        .filter(|(c, o)| **c != o.as_str() && !o.ends_with(SKIPPED))
        .map(|(c, o)| (o.clone(), c.to_string()))
        .collect();
    Ok(Remapped { lines: text, skipped, renamed })
}

/// The column named `k` exactly.
fn find_exact(cols: &[&str], k: &str) -> Option<usize> {
    cols.iter().position(|c| *c == k)
}

/// The joint part of column `c` under signal key `k`: `k<sep>NAME` or `NAME<sep>k`.
fn split_key(c: &str, k: &str) -> Option<String> {
    let after = c.strip_prefix(k).and_then(|r| {
        let mut ch = r.chars();
        let sep = ch.next()?;
        SEPARATORS.contains(&sep).then(|| ch.as_str().trim_end_matches(']').to_string())
    });
    let before = c.strip_suffix(k).and_then(|r| {
        let sep = r.chars().last()?;
        SEPARATORS.contains(&sep).then(|| r[..r.len() - sep.len_utf8()].to_string())
    });
    after.or(before).filter(|n| !n.is_empty())
}

/// "no … in the file (its columns: …; did you mean …?)".
fn missing(what: &str, key: &str, cols: &[&str], listed: &str) -> String {
    let names: Vec<String> = cols.iter().map(|c| c.to_string()).collect();
    let near = crate::util::near_matches(key, &names);
    let hint = if near.is_empty() {
        String::new()
    } else {
        format!(
            "; did you mean {}?",
            near.iter().map(|n| format!("'{n}'")).collect::<Vec<_>>().join(" or ")
        )
    };
    format!("no {what} in the file (its columns: {listed}{hint})")
}
