//! Which kind of file a recording is (by its first bytes, then its name), and the readers of
//! logs other than CSV and BAM JSON: NumPy `.npz`, PyTorch `.pt`, LeRobot parquet, MCAP. A file
//! of a kind that is not read (a ROS 1 bag, a single `.npy` array, a legacy-format `.pt`, JSON
//! that is not a BAM log) is named as what it is, with what to do.

use std::path::{Path, PathBuf};

use super::mapping::{Columns, assemble};
use super::{ParseOptions, Recording, RecordingError};

/// What a file holds, as far as its first bytes (and for a zip, its member names) tell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Text that is not JSON: read as CSV.
    Text,
    /// JSON (a BAM log or not: the caller decides).
    Json,
    Npz,
    Npy,
    /// `torch.save`'s zip format (read).
    PyTorch,
    /// `torch.save`'s legacy format: pickles back to back (not read).
    LegacyPyTorch,
    /// A zip archive of something else.
    Zip,
    Parquet,
    Mcap,
    Ros1Bag,
    Sqlite,
    Hdf5,
    Pickle,
    Binary,
}

/// The kind of `bytes` (the whole file), `path` only for its extension.
pub fn sniff(path: &Path, bytes: &[u8]) -> Kind {
    let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase()).unwrap_or_default();
    if bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06") {
        let names: Vec<String> = zip::ZipArchive::new(std::io::Cursor::new(bytes))
            .map(|z| z.file_names().filter_map(|n| n.ok().map(|n| n.into_owned())).collect())
            .unwrap_or_default();
        if names.iter().any(|n| n.ends_with("data.pkl")) || ext == "pt" || ext == "pth" {
            return Kind::PyTorch;
        }
        if names.iter().any(|n| n.ends_with(".npy")) || ext == "npz" {
            return Kind::Npz;
        }
        return Kind::Zip;
    }
    if super::npy::is_npy(bytes) {
        return Kind::Npy;
    }
    if super::lerobot::is_parquet(bytes) {
        return Kind::Parquet;
    }
    if bytes.starts_with(b"\x89MCAP") {
        return Kind::Mcap;
    }
    if bytes.starts_with(b"#ROSBAG") {
        return Kind::Ros1Bag;
    }
    if bytes.starts_with(b"SQLite format 3\0") {
        return Kind::Sqlite;
    }
    if bytes.starts_with(b"\x89HDF\r\n\x1a\n") {
        return Kind::Hdf5;
    }
    if bytes.first() == Some(&0x80) && matches!(bytes.get(1), Some(2..=5)) {
        return if ext == "pt" || ext == "pth" { Kind::LegacyPyTorch } else { Kind::Pickle };
    }
    let head = &bytes[..bytes.len().min(4096)];
    if head.contains(&0) {
        return Kind::Binary;
    }
    let text = String::from_utf8_lossy(head);
    match text.trim_start_matches('\u{feff}').trim_start().chars().next() {
        Some('{' | '[') => Kind::Json,
        _ => Kind::Text,
    }
}

const READ: &str = "modellint reads recordings as CSV (`modellint docs recording-format`), BAM \
                    servo logs (JSON), NumPy .npz and PyTorch .pt dicts of joint arrays, \
                    LeRobot parquet and MCAP (ROS 2) files";

/// Reads a log of a binary kind: `None` for text (CSV or JSON, read by the caller), else its
/// recordings (several for a LeRobot file of several episodes) or an error naming the kind.
pub fn read_log(
    path: &Path,
    bytes: &[u8],
    opts: &ParseOptions,
) -> Option<Result<Vec<Recording>, RecordingError>> {
    let err = |m: String| RecordingError::new(path, None, None, m);
    let name = file_name(path);
    let kind = sniff(path, bytes);
    if matches!(kind, Kind::Text | Kind::Json) {
        // A mapping given for a BAM log would be ignored: an error, not a silence. (A CSV is
        // read through it: its columns renamed, `csv_map`.)
        if kind == Kind::Json && !opts.log_map.is_empty() {
            return Some(Err(err(format!(
                "--log-map and the --log-* flags apply to CSV, .npz, .pt, parquet and MCAP logs; \
                 {name} is JSON (a BAM servo log's keys are fixed)"
            ))));
        }
        return None;
    }
    let map = match opts.log_map.resolve() {
        Ok(m) => m,
        Err(e) => return Some(Err(e)),
    };
    let one = |cols: Result<Columns, String>| -> Result<Vec<Recording>, RecordingError> {
        let cols = cols.map_err(|m| err(format!("{}: {m}", kind_name(kind))))?;
        Ok(vec![assemble(path, cols, &map, opts)?])
    };
    Some(match kind {
        Kind::Text | Kind::Json => unreachable!("returned above"),
        Kind::Npz => one(super::npy::npz_columns(bytes, &map)),
        Kind::Mcap => one(super::rosbag::mcap_columns(bytes, &map)),
        Kind::Parquet => (|| {
            let eps = super::lerobot::lerobot_columns(path, &map)
                .map_err(|m| err(format!("{}: {m}", kind_name(kind))))?;
            let many = eps.len() > 1;
            eps.into_iter()
                .map(|(ep, cols)| {
                    // Several episodes in one file: each named `FILE#episode_N`.
                    let src = match (many, ep) {
                        (true, Some(k)) => PathBuf::from(format!("{}#episode_{k}", path.display())),
                        _ => path.to_path_buf(),
                    };
                    assemble(&src, cols, &map, opts)
                })
                .collect()
        })(),
        Kind::Npy => Err(err(format!(
            "{name} is a single NumPy array (.npy); modellint reads a dict of joint arrays: \
             save one with numpy.savez('run.npz', dof_pos=…, des_dof_pos=…, t=…)"
        ))),
        Kind::PyTorch => one(super::torch_pt::pt_columns(bytes, &map)),
        Kind::LegacyPyTorch => Err(err(format!(
            "{name} is a PyTorch file of the legacy format (torch < 1.6, or \
             _use_new_zipfile_serialization=False); it is not read: save it again with a current \
             torch.save (the zip format) or as numpy.savez('run.npz', **{{k: v.numpy() for k, v \
             in d.items()}})"
        ))),
        Kind::Zip => Err(err(format!(
            "{name} is a zip archive of neither .npy arrays nor a PyTorch file. {READ}"
        ))),
        Kind::Ros1Bag => Err(err(format!(
            "{name} is a ROS 1 bag; it is not read: convert it to MCAP (`mcap convert {name} out.mcap`) and read that"
        ))),
        Kind::Sqlite => Err(err(format!(
            "{name} is an SQLite database (a ROS 2 bag's .db3 storage?); it is not read: convert \
             the bag to MCAP (`ros2 bag convert`, storage_id: mcap) and read that"
        ))),
        Kind::Hdf5 => Err(err(format!("{name} is an HDF5 file; it is not read. {READ}"))),
        Kind::Pickle => Err(err(format!(
            "{name} is a Python pickle; it is not read (loading one runs code). {READ}"
        ))),
        Kind::Binary => {
            Err(err(format!("{name} is a binary file of a kind modellint does not know. {READ}")))
        }
    })
}

/// The file's name (the error's location already gives its path).
fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned())
}

fn kind_name(k: Kind) -> &'static str {
    match k {
        Kind::Npz => "NumPy .npz",
        Kind::PyTorch => super::torch_pt::FORMAT,
        Kind::Parquet => "LeRobot parquet",
        Kind::Mcap => "MCAP",
        _ => "log",
    }
}

/// The error for JSON that is not a BAM log: what it is (its top-level keys; the answer key of
/// a simulated dataset) and what is expected.
pub fn not_bam_json(path: &Path, text: &str) -> RecordingError {
    let name = file_name(path);
    let v: Result<serde_json::Value, _> = serde_json::from_str(text);
    let what = match &v {
        Err(e) => {
            return RecordingError::new(
                path,
                Some(e.line().max(1)),
                None,
                format!("{name} looks like JSON but does not parse ({e}). {READ}"),
            );
        }
        Ok(serde_json::Value::Object(o)) => {
            let keys: Vec<&str> = o.keys().map(String::as_str).take(8).collect();
            let schema = o.get("schema").and_then(|s| s.as_str()).unwrap_or("");
            if schema.contains("truth") {
                format!(
                    "{name} is the answer key of a simulated dataset (schema '{schema}'), not a \
                     recording: give the episodes/ directory beside it (or the dataset \
                     directory)"
                )
            } else {
                format!(
                    "{name} is JSON with the keys {}{}, not a BAM servo log (an object with \
                     \"entries\", each with \"timestamp\", \"position\", \"goal_position\")",
                    keys.join(", "),
                    if o.len() > keys.len() { ", …" } else { "" }
                )
            }
        }
        Ok(serde_json::Value::Array(a)) => {
            format!("{name} is a JSON array ({} elements), not a BAM servo log", a.len())
        }
        Ok(_) => format!("{name} is a JSON value, not a BAM servo log"),
    };
    RecordingError::new(path, Some(1), None, format!("{what}. {READ}"))
}
