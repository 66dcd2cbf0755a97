//! LeRobot datasets (parquet): per frame `observation.state` and `action` (lists of floats, one
//! per joint), `timestamp` [s], `episode_index`, `frame_index`. The dataset's `meta/info.json`
//! (found up to three directories above the file) gives `fps` (the control rate) and each
//! feature's joint `names`. A file may hold several episodes (LeRobot v3): each is a recording.
//!
//! The `action` of a frame is what the policy or teleoperator sent *after* that frame's
//! observation, so the command timing is `sent_after` unless the mapping says otherwise.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::record::Field;

use super::mapping::{Columns, LogMap, pick};

const MEASURED: &[&str] = &["observation.state"];
const COMMAND: &[&str] = &["action"];
const VELOCITY: &[&str] = &["observation.velocity"];
const EFFORT: &[&str] = &["observation.effort"];
const TIME: &[&str] = &["timestamp"];

/// Whether `bytes` start like a parquet file.
pub fn is_parquet(bytes: &[u8]) -> bool {
    bytes.starts_with(b"PAR1")
}

/// The dataset's `meta/info.json` above `file`, if any.
fn info_json(file: &Path) -> Option<(PathBuf, serde_json::Value)> {
    let mut dir = file.parent();
    for _ in 0..4 {
        let d = dir?;
        let p = d.join("meta/info.json");
        if let Ok(text) = std::fs::read_to_string(&p) {
            return serde_json::from_str(&text).ok().map(|v| (p, v));
        }
        dir = d.parent();
    }
    None
}

/// A feature's joint names in info.json: a list, or an object holding one list
/// (`{"motors": [...]}`).
fn feature_names(info: &serde_json::Value, key: &str) -> Option<Vec<String>> {
    let names = info.get("features")?.get(key)?.get("names")?;
    let list = match names {
        serde_json::Value::Array(a) => a,
        serde_json::Value::Object(o) if o.len() == 1 => o.values().next()?.as_array()?,
        _ => return None,
    };
    list.iter().map(|v| v.as_str().map(str::to_string)).collect()
}

fn number(f: &Field) -> Option<f64> {
    Some(match *f {
        Field::Float(x) => x as f64,
        Field::Double(x) => x,
        Field::Float16(x) => x.to_f64(),
        Field::Byte(x) => x as f64,
        Field::Short(x) => x as f64,
        Field::Int(x) => x as f64,
        Field::Long(x) => x as f64,
        Field::UByte(x) => x as f64,
        Field::UShort(x) => x as f64,
        Field::UInt(x) => x as f64,
        Field::ULong(x) => x as f64,
        Field::Bool(b) => f64::from(u8::from(b)),
        _ => return None,
    })
}

fn vector(f: &Field) -> Option<Vec<f64>> {
    match f {
        Field::ListInternal(l) => l.elements().iter().map(number).collect(),
        other => number(other).map(|x| vec![x]),
    }
}

/// One episode's frames: the columns asked for, per frame.
#[derive(Default)]
struct Episode {
    t: Vec<f64>,
    /// Whether a time stamp was stored as a 32-bit float.
    t_f32: bool,
    q: Vec<Vec<f64>>,
    cmd: Vec<Vec<f64>>,
    qd: Vec<Vec<f64>>,
    tau: Vec<Vec<f64>>,
}

/// Per episode (its `episode_index`, or `None` without that column): its [`Columns`].
pub(crate) fn lerobot_columns(
    path: &Path,
    map: &LogMap,
) -> Result<Vec<(Option<i64>, Columns)>, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read file: {e}"))?;
    let reader =
        SerializedFileReader::new(file).map_err(|e| format!("not a readable parquet file: {e}"))?;
    let keys: Vec<String> = reader
        .metadata()
        .file_metadata()
        .schema_descr()
        .root_schema()
        .get_fields()
        .iter()
        .map(|f| f.name().to_string())
        .collect();
    let measured = pick(map.measured.as_deref(), MEASURED, &keys, "column")?.ok_or_else(|| {
        format!(
            "no column of measured joint positions ('observation.state'; it has: {}): name it \
             with --log-measured COLUMN",
            super::mapping::list(&keys)
        )
    })?;
    let command = pick(map.command.as_deref(), COMMAND, &keys, "column")?;
    let velocity = pick(map.velocity.as_deref(), VELOCITY, &keys, "column")?;
    let effort = pick(map.effort.as_deref(), EFFORT, &keys, "column")?;
    let time = pick(map.time.as_deref(), TIME, &keys, "column")?;
    let info = info_json(path);
    let fps = info.as_ref().and_then(|(_, v)| v.get("fps")?.as_f64()).filter(|f| *f > 0.0);
    if time.is_none() && map.dt.is_none() && fps.is_none() {
        return Err("no time: no 'timestamp' column, no fps in meta/info.json; give --log-time \
                    COLUMN or --log-dt SECONDS"
            .into());
    }
    let mut episodes: BTreeMap<Option<i64>, Episode> = BTreeMap::new();
    let rows = reader.get_row_iter(None).map_err(|e| format!("parquet: {e}"))?;
    for (i, row) in rows.enumerate() {
        let row = row.map_err(|e| format!("parquet row {i}: {e}"))?;
        let mut ep = None;
        let (mut t, mut t32) = (None, false);
        let mut frame = None;
        let (mut q, mut c, mut v, mut e) = (None, None, None, None);
        for (name, f) in row.get_column_iter() {
            let bad = |what: &str| format!("row {i}: column '{name}' is not {what}");
            let n = name.as_str();
            if n == "episode_index" {
                ep = Some(number(f).ok_or_else(|| bad("a number"))? as i64);
            }
            if n == "frame_index" {
                frame = number(f);
            }
            if Some(n) == time.as_deref() {
                t = Some(number(f).ok_or_else(|| bad("a number"))?);
                t32 = matches!(f, Field::Float(_));
            }
            let list = || vector(f).ok_or_else(|| bad("a list of numbers"));
            if n == measured {
                q = Some(list()?);
            }
            if Some(n) == command.as_deref() {
                c = Some(list()?);
            }
            if Some(n) == velocity.as_deref() {
                v = Some(list()?);
            }
            if Some(n) == effort.as_deref() {
                e = Some(list()?);
            }
        }
        if map.episode.is_some_and(|want| ep != Some(want)) {
            continue;
        }
        let e_ = episodes.entry(ep).or_default();
        let t = match (t, map.dt, fps) {
            (Some(t), _, _) => t,
            (None, Some(dt), _) => frame.unwrap_or(e_.t.len() as f64) * dt,
            (None, None, Some(fps)) => frame.unwrap_or(e_.t.len() as f64) / fps,
            (None, None, None) => unreachable!("checked above"),
        };
        e_.t.push(t);
        e_.t_f32 |= t32;
        e_.q.push(q.unwrap_or_default());
        if let Some(c) = c {
            e_.cmd.push(c);
        }
        if let Some(v) = v {
            e_.qd.push(v);
        }
        if let Some(e) = e {
            e_.tau.push(e);
        }
    }
    if episodes.is_empty() {
        return Err(match map.episode {
            Some(k) => format!("no frame of episode {k}"),
            None => "no frame".into(),
        });
    }
    let info_v = info.as_ref().map(|(_, v)| v);
    let names = info_v.and_then(|v| feature_names(v, &measured));
    let cmd_names = command.as_deref().and_then(|c| info_v.and_then(|v| feature_names(v, c)));
    let mut out = Vec::new();
    for (ep, mut e) in episodes {
        let k = e.q.first().map_or(0, Vec::len);
        let width = |rows: &[Vec<f64>], what: &str| -> Result<(), String> {
            match rows.iter().position(|r| r.len() != k) {
                Some(i) => Err(format!(
                    "frame {i}{}: '{what}' has {} values, '{measured}' {k}",
                    ep.map(|x| format!(" of episode {x}")).unwrap_or_default(),
                    rows[i].len()
                )),
                None => Ok(()),
            }
        };
        width(&e.q, &measured)?;
        // The command's columns in the measured joints' order, when info.json names both.
        if let (Some(n), Some(cn)) = (&names, &cmd_names)
            && n != cn
        {
            let at: Option<Vec<usize>> = n.iter().map(|j| cn.iter().position(|x| x == j)).collect();
            let Some(at) = at else {
                return Err(format!(
                    "meta/info.json names the joints of '{}' ({}) and of '{measured}' ({}) \
                     differently: map them with --log-map",
                    command.as_deref().unwrap_or(""),
                    cn.join(", "),
                    n.join(", ")
                ));
            };
            for r in &mut e.cmd {
                *r = at.iter().map(|&i| r.get(i).copied().unwrap_or(f64::NAN)).collect();
            }
        }
        for (rows, what) in [
            (&e.cmd, command.as_deref()),
            (&e.qd, velocity.as_deref()),
            (&e.tau, effort.as_deref()),
        ] {
            if let Some(w) = what {
                width(rows, w)?;
            }
        }
        let n = e.t.len();
        let cols = |rows: &[Vec<f64>]| -> Option<Vec<Vec<f64>>> {
            (rows.len() == n && n > 0)
                .then(|| (0..k).map(|j| rows.iter().map(|r| r[j]).collect()).collect())
        };
        // 32-bit stamps on the fps grid (frame_index / fps) are put back on it: a float32 holds
        // them to ~1 µs, and a row a rounding after a tick edge would take the next tick's
        // command.
        let mut meta = BTreeMap::new();
        if e.t_f32
            && let Some(fps) = fps
            && e.t.iter().all(|t| ((t * fps) - (t * fps).round()).abs() < 1e-3)
        {
            for t in &mut e.t {
                *t = (*t * fps).round() / fps;
            }
            meta.insert("timestamps_snapped_to_fps".into(), "true".into());
        }
        if let Some(ep) = ep {
            meta.insert("episode_index".into(), ep.to_string());
        }
        if let Some((p, _)) = &info {
            meta.insert("lerobot_info".into(), p.display().to_string());
        }
        out.push((
            ep,
            Columns {
                format: "LeRobot parquet",
                t: e.t.clone(),
                names: names.clone(),
                measured_key: measured.clone(),
                command_key: command.clone(),
                velocity_key: velocity.clone(),
                effort_key: effort.clone(),
                time_key: None,
                keys: keys.clone(),
                q: cols(&e.q).unwrap_or_default(),
                q_cmd: cols(&e.cmd),
                qd: cols(&e.qd),
                tau: cols(&e.tau),
                meta,
                control_rate_hz: fps,
                control_t0_s: None,
                command_timing: Some("sent_after"),
            },
        ));
    }
    Ok(out)
}
