//! Reading the CSV format (see the parent module's docs): metadata lines, the header row, the
//! data rows, then the recording-wide checks. Every error names the file and the 1-based line.

use std::collections::BTreeMap;
use std::path::Path;

use super::{
    BASE_SUFFIXES, BaseTrace, JOINT_SUFFIXES, JointTrace, KEY_CONTROL_RATE, KEY_CONTROL_T0,
    KEY_SPLIT, ParseOptions, RATE_NONE, Recording, RecordingError, Split,
};
use crate::sim2real::commands::{self, CommandTiming, KEY_COMMAND_TIMING};

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

/// Parses CSV text; see the module docs for the format.
pub fn parse_csv_with(
    path: &Path,
    text: &str,
    opts: &ParseOptions,
) -> Result<Recording, RecordingError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim().is_empty() {
        return Err(err(path, 1, None, "empty file".into()));
    }
    let lines: Vec<(usize, &str)> = text
        .split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
        .collect();
    // A CSV of other column names under a --log-map: read as its rewritten text.
    if !opts.log_map.is_empty() {
        let (_, idx) = parse_metadata(path, &lines)?;
        if idx < lines.len() {
            let map = opts.log_map.resolve()?;
            let mapped = super::csv_map::remap(path, &lines, idx, &map, &opts.ignore_columns)?;
            let mut opts = opts.clone();
            opts.log_map = Default::default();
            if mapped.skipped {
                opts.ignore_columns.push(format!("*.{}", super::csv_map::SKIPPED));
            }
            let lines: Vec<(usize, &str)> =
                mapped.lines.iter().map(|(n, l)| (*n, l.as_str())).collect();
            return parse_lines(path, &lines, &opts).map_err(|e| mapped.name_columns_as_written(e));
        }
    }
    parse_lines(path, &lines, opts)
}

/// [`parse_csv_with`] on the file's lines (1-based number, text without its line end).
fn parse_lines(
    path: &Path,
    lines: &[(usize, &str)],
    opts: &ParseOptions,
) -> Result<Recording, RecordingError> {
    let (meta, idx) = parse_metadata(path, lines)?;
    let Some(&(header_ln, header)) = lines.get(idx) else {
        let last = lines.iter().rev().find(|(_, l)| !l.trim().is_empty()).map_or(1, |(n, _)| *n);
        return Err(err(path, last, None, "no header row (only metadata/comment lines)".into()));
    };
    let mut ignore = globset::GlobSetBuilder::new();
    for g in &opts.ignore_columns {
        let glob = globset::Glob::new(g).map_err(|e| {
            RecordingError::new(path, None, None, format!("--ignore-columns {g}: {e}"))
        })?;
        ignore.add(glob);
    }
    let ignore = ignore
        .build()
        .map_err(|e| RecordingError::new(path, None, None, format!("--ignore-columns: {e}")))?;
    let header = parse_header(path, header_ln, header, &ignore)?;
    if let Some(model) = &opts.model_joints
        && let Some((col, msg)) =
            super::unknown_joints(header.joint_names.iter().map(String::as_str), model)
    {
        return Err(err(path, header_ln, Some(&col), msg));
    }
    // A driven joint without its command: at the header line too, before any value is read.
    let has_cmd = header.joint_cols.iter().map(|c| c[2].is_some());
    if let Err(msg) = super::uncommanded_joints(
        header.joint_names.iter().map(String::as_str).zip(has_cmd),
        opts,
        |j| format!("'{j}.q_cmd' column"),
    ) {
        return Err(err(path, header_ln, None, msg));
    }
    let Rows { cols, lines: row_lines, duplicates } = parse_rows(path, &header, &lines[idx + 1..])?;
    let rate_line = meta.rate_line;
    let units = meta.units_line;
    let names = header.names.clone();
    let mut rec = assemble(path, meta, header, cols);
    // Declared units: converted to SI before any check (degrees are then radians).
    if let Some(ln) = units
        && let Some(decl) = rec.meta.get(super::units::KEY_UNITS).cloned()
    {
        super::units::apply(&mut rec, &decl, &names).map_err(|m| err(path, ln, None, m))?;
    }
    if duplicates > 0 {
        rec.meta.insert(super::KEY_DUPLICATE_ROWS.to_string(), duplicates.to_string());
    }
    rec.check_inner(opts, Some(&row_lines))?;
    check_rate(path, &rec, rate_line)?;
    Ok(rec)
}

fn err(path: &Path, line: usize, col: Option<&str>, msg: String) -> RecordingError {
    RecordingError::new(path, Some(line), col, msg)
}

/// The leading `# key: value` lines.
struct Metadata {
    meta: BTreeMap<String, String>,
    control_rate_hz: Option<f64>,
    /// Line of the `control_rate_hz` key.
    rate_line: Option<usize>,
    /// Line of the `units` key.
    units_line: Option<usize>,
    control_t0_s: Option<f64>,
}

/// Metadata and comments up to the header; returns them and the index of the header line.
fn parse_metadata(
    path: &Path,
    lines: &[(usize, &str)],
) -> Result<(Metadata, usize), RecordingError> {
    let mut m = Metadata {
        meta: BTreeMap::new(),
        control_rate_hz: None,
        rate_line: None,
        units_line: None,
        control_t0_s: None,
    };
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
        let err = |msg: String| err(path, ln, None, msg);
        if m.meta.contains_key(k)
            || (k == KEY_CONTROL_RATE && m.control_rate_hz.is_some())
            || (k == KEY_CONTROL_T0 && m.control_t0_s.is_some())
        {
            return Err(err(format!("duplicate metadata key '{k}'")));
        }
        if k == KEY_CONTROL_RATE && v == RATE_NONE {
            // Declared: no control loop (each command acts from its own row's time).
            m.meta.insert(k.to_string(), v.to_string());
            continue;
        }
        if k == KEY_CONTROL_RATE || k == KEY_CONTROL_T0 {
            let x: f64 = v.parse().ok().filter(|x: &f64| x.is_finite()).ok_or_else(|| {
                err(format!("metadata '{k}': expected a finite number, found '{v}'"))
            })?;
            if k == KEY_CONTROL_RATE {
                if x <= 0.0 {
                    return Err(err(format!("metadata '{k}' must be positive, found {x}")));
                }
                m.control_rate_hz = Some(x);
                m.rate_line = Some(ln);
            } else {
                m.control_t0_s = Some(x);
            }
            continue;
        }
        if k == super::units::KEY_UNITS {
            m.units_line = Some(ln);
        } else if super::units::other_unit_key(k) {
            return Err(err(format!(
                "metadata '{k}': units are declared with one key, `# units: deg, deg/s` (a unit \
                 per kind of column) or `# units: knee.q=deg` (per column); see `modellint docs \
                 recording-format`"
            )));
        }
        if k == KEY_SPLIT && Split::parse(v).is_none() {
            return Err(err(format!("metadata '{k}' must be `train` or `heldout`, found '{v}'")));
        }
        if k == KEY_COMMAND_TIMING && CommandTiming::parse(v).is_none() {
            return Err(err(format!(
                "metadata '{k}' must be `in_force` or `sent_after`, found '{v}'"
            )));
        }
        m.meta.insert(k.to_string(), v.to_string());
    }
    Ok((m, idx))
}

#[derive(Clone, Copy, PartialEq)]
enum Field {
    Time,
    Joint(usize, usize), // joint index, suffix index in JOINT_SUFFIXES
    Base(usize),         // index in BASE_SUFFIXES
    Ignored,             // --ignore-columns
}

/// The header row: what each column holds.
struct Header<'a> {
    line: usize,
    names: Vec<&'a str>,
    fields: Vec<Field>,
    joint_names: Vec<String>,
    /// Column of each joint's suffixes (JOINT_SUFFIXES order).
    joint_cols: Vec<[Option<usize>; 7]>,
    /// Column of each base coordinate (BASE_SUFFIXES order).
    base_cols: [Option<usize>; 7],
    t_col: usize,
}

/// Header names (lower case) that are a time stamp under another name than `t`.
const TIME_NAMES: &[&str] =
    &["time", "timestamp", "time_s", "time_ms", "t_s", "t_ms", "stamp", "sec", "secs", "seconds"];

/// Joint column suffixes (lower case) that are a servo target under another name than `q_cmd`.
const COMMAND_NAMES: &[&str] =
    &["q_des", "q_target", "q_ref", "target", "cmd", "command", "q_d", "pos_des", "goal", "q_goal"];

fn parse_header<'a>(
    path: &Path,
    ln: usize,
    header: &'a str,
    ignore: &globset::GlobSet,
) -> Result<Header<'a>, RecordingError> {
    let err = |col: Option<&str>, msg: String| err(path, ln, col, msg);
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut h = Header {
        line: ln,
        fields: Vec::with_capacity(names.len()),
        joint_names: Vec::new(),
        joint_cols: Vec::new(),
        base_cols: [None; 7],
        t_col: 0,
        names: Vec::new(),
    };
    let mut t_col = None;
    for (ci, &name) in names.iter().enumerate() {
        if name.is_empty() {
            return Err(err(None, format!("header: column {} has an empty name", ci + 1)));
        }
        if names[..ci].contains(&name) {
            return Err(err(Some(name), format!("header: duplicate column '{name}'")));
        }
        let field = if name == "t" {
            t_col = Some(ci);
            Field::Time
        } else if ignore.is_match(name) {
            Field::Ignored
        } else {
            let Some((joint, suffix)) = name.rsplit_once('.') else {
                // A time stamp under another name is the likeliest: say to rename it.
                let lower = name.to_ascii_lowercase();
                let hint = if TIME_NAMES.contains(&lower.as_str()) {
                    format!(
                        "if it is the time stamp, name it 't' (seconds; other units declared with \
                         `# units: ms`); an extra signal is skipped with --ignore-columns '{name}'"
                    )
                } else {
                    format!(
                        "an extra signal? skip it with --ignore-columns '{name}'; a log with \
                         other column names is read with --log-map FILE.toml (`modellint docs \
                         recording-format`)"
                    )
                };
                return Err(err(
                    Some(name),
                    format!(
                        "header: column '{name}' is neither 't', 'base.<x|y|z|qw|qx|qy|qz>' nor '<joint>.<suffix>' \
                         ({hint})"
                    ),
                ));
            };
            if joint == "base"
                && let Some(b) = BASE_SUFFIXES.iter().position(|s| *s == suffix)
            {
                h.base_cols[b] = Some(ci);
                Field::Base(b)
            } else {
                let Some(si) = JOINT_SUFFIXES.iter().position(|s| *s == suffix) else {
                    // A servo target under another name: say to rename it to the command.
                    let lower = suffix.to_ascii_lowercase();
                    let hint = if COMMAND_NAMES.contains(&lower.as_str()) {
                        format!(
                            "if it is the servo's target, name it '{joint}.q_cmd'; an extra signal \
                             is skipped with --ignore-columns '*.{suffix}'"
                        )
                    } else {
                        format!("an extra signal? skip it with --ignore-columns '*.{suffix}'")
                    };
                    return Err(err(
                        Some(name),
                        format!(
                            "header: column '{name}' has unknown suffix '.{suffix}' (expected one of .{}; {hint})",
                            JOINT_SUFFIXES.join(", .")
                        ),
                    ));
                };
                if joint.is_empty() {
                    return Err(err(
                        Some(name),
                        format!("header: column '{name}' has an empty joint name"),
                    ));
                }
                let ji = match h.joint_names.iter().position(|j| j == joint) {
                    Some(ji) => ji,
                    None => {
                        h.joint_names.push(joint.to_string());
                        h.joint_cols.push([None; 7]);
                        h.joint_names.len() - 1
                    }
                };
                h.joint_cols[ji][si] = Some(ci);
                Field::Joint(ji, si)
            }
        };
        h.fields.push(field);
    }
    let Some(t_col) = t_col else {
        return Err(err(None, "header: no 't' column".into()));
    };
    h.t_col = t_col;
    h.names = names;
    check_header(path, &h)?;
    Ok(h)
}

/// At least one joint; every joint has its `.q`; the base has all seven columns or none.
fn check_header(path: &Path, h: &Header) -> Result<(), RecordingError> {
    if h.joint_names.is_empty() {
        return Err(err(
            path,
            h.line,
            None,
            "header: no joint column ('<joint>.q'): nothing to compare".into(),
        ));
    }
    for (ji, cols) in h.joint_cols.iter().enumerate() {
        if cols[0].is_none() {
            let present: Vec<String> = cols
                .iter()
                .enumerate()
                .filter(|(_, c)| c.is_some())
                .map(|(si, _)| format!("{}.{}", h.joint_names[ji], JOINT_SUFFIXES[si]))
                .collect();
            let col = format!("{}.q", h.joint_names[ji]);
            return Err(err(
                path,
                h.line,
                Some(&col),
                format!(
                    "header: joint '{}' has {} but no '{}' column",
                    h.joint_names[ji],
                    present.join(", "),
                    col
                ),
            ));
        }
    }
    let n_base = h.base_cols.iter().filter(|c| c.is_some()).count();
    if n_base != 0 && n_base != 7 {
        let missing: Vec<String> = BASE_SUFFIXES
            .iter()
            .zip(h.base_cols.iter())
            .filter(|(_, c)| c.is_none())
            .map(|(s, _)| format!("base.{s}"))
            .collect();
        return Err(err(
            path,
            h.line,
            None,
            format!(
                "header: base pose needs all seven columns (base.x base.y base.z base.qw base.qx base.qy base.qz); missing {}",
                missing.join(", ")
            ),
        ));
    }
    Ok(())
}

/// The data rows after the header.
struct Rows {
    /// Column-major values.
    cols: Vec<Vec<f64>>,
    /// The source line of each row.
    lines: Vec<usize>,
    /// Rows that repeated the row before them character for character (a logger that wrote a
    /// sample twice): left out. A repeated time with other values stays an error.
    duplicates: usize,
}

/// [`Rows`] of the lines after the header.
fn parse_rows(path: &Path, h: &Header, lines: &[(usize, &str)]) -> Result<Rows, RecordingError> {
    let names = &h.names;
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let mut row_lines: Vec<usize> = Vec::new();
    let mut blank_at: Option<usize> = None;
    let mut previous: Option<&str> = None;
    let mut duplicates = 0usize;
    for &(ln, raw) in lines {
        if raw.trim().is_empty() {
            blank_at.get_or_insert(ln);
            continue;
        }
        if let Some(b) = blank_at {
            return Err(err(path, b, None, "empty line inside the data rows".into()));
        }
        if previous == Some(raw.trim()) {
            duplicates += 1;
            continue;
        }
        previous = Some(raw.trim());
        let parts: Vec<&str> = raw.split(',').map(str::trim).collect();
        if parts.len() != names.len() {
            return Err(err(
                path,
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
            if h.fields[ci] == Field::Ignored {
                continue;
            }
            let v = parse_field(h.fields[ci], s).map_err(|m| {
                err(path, ln, Some(names[ci]), format!("column '{}': {m}", names[ci]))
            })?;
            cols[ci].push(v);
        }
        row_lines.push(ln);
    }
    if row_lines.len() < 2 {
        let ln = row_lines.last().copied().unwrap_or(h.line);
        return Err(err(
            path,
            ln,
            None,
            format!("need at least 2 data rows, found {}", row_lines.len()),
        ));
    }
    Ok(Rows { cols, lines: row_lines, duplicates })
}

/// One field: `.enabled` takes 0/1/false/true, every other column a finite number.
fn parse_field(field: Field, s: &str) -> Result<f64, String> {
    if let Field::Joint(_, 6) = field {
        return match s {
            "0" | "false" => Ok(0.0),
            "1" | "true" => Ok(1.0),
            _ => Err(format!("expected 0 or 1, found '{s}'")),
        };
    }
    if s.is_empty() {
        return Err("empty field".into());
    }
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) => Err(format!("non-finite value '{s}' ({x})")),
        Err(_) => Err(format!("cannot parse '{s}' as a number")),
    }
}

/// The recording from the parsed parts (columns moved, not copied).
fn assemble(path: &Path, m: Metadata, h: Header, mut cols: Vec<Vec<f64>>) -> Recording {
    let mut take = |c: Option<usize>| c.map(|c| std::mem::take(&mut cols[c]));
    let t = take(Some(h.t_col)).unwrap_or_default();
    let mut joints = Vec::with_capacity(h.joint_names.len());
    for (name, jc) in h.joint_names.into_iter().zip(h.joint_cols.iter()) {
        joints.push(JointTrace {
            name,
            q: take(jc[0]).unwrap_or_default(),
            qd: take(jc[1]),
            q_cmd: take(jc[2]),
            tau: take(jc[3]),
            kp: take(jc[4]),
            kd: take(jc[5]),
            enabled: take(jc[6]).map(|v| v.into_iter().map(|x| x != 0.0).collect()),
        });
    }
    let base = h.base_cols.iter().all(|c| c.is_some()).then(|| {
        let b: Vec<Vec<f64>> = h.base_cols.iter().map(|c| take(*c).unwrap_or_default()).collect();
        BaseTrace {
            pos: (0..t.len()).map(|i| [b[0][i], b[1][i], b[2][i]]).collect(),
            quat: (0..t.len()).map(|i| [b[3][i], b[4][i], b[5][i], b[6][i]]).collect(),
        }
    });
    Recording {
        source: path.to_path_buf(),
        meta: m.meta,
        control_rate_hz: m.control_rate_hz,
        control_t0_s: m.control_t0_s,
        t,
        joints,
        base,
    }
}

/// A declared control rate must not put the whole recording into one control tick, nor its
/// rows more than [`commands::MAX_TICKS_PER_ROW`] ticks apart at the median (timestamps in
/// milli- or nanoseconds).
fn check_rate(
    path: &Path,
    rec: &Recording,
    rate_line: Option<usize>,
) -> Result<(), RecordingError> {
    let (Some(rate), Some(ln)) = (rec.control_rate_hz, rate_line) else { return Ok(()) };
    let (Some(&first), Some(&last)) = (rec.t.first(), rec.t.last()) else { return Ok(()) };
    let timing = rec.command_timing().unwrap_or_default();
    let t0 = rec.control_t0_s.unwrap_or(first);
    let tick = |x: f64| commands::tick_of(x, t0, rate, timing);
    if let Err(e @ commands::ScheduleError::SparseRows { .. }) =
        commands::check_row_spacing(&rec.t, rate)
    {
        return Err(err(path, ln, None, format!("control_rate_hz {rate}: {e}")));
    }
    if tick(first) == tick(last) {
        return Err(err(
            path,
            ln,
            None,
            format!(
                "control_rate_hz {rate} puts all {} rows ({first} s … {last} s) into one control tick: the rate is too low \
                 for these timestamps (are the times in seconds?)",
                rec.t.len(),
            ),
        ));
    }
    Ok(())
}
