//! NumPy arrays: the `.npy` format (version 1–3 headers: `descr`, `fortran_order`, `shape`) and
//! `.npz` archives of them (`numpy.savez`, `savez_compressed`: a zip of `KEY.npy` members).
//!
//! Read are little- and big-endian floats (`f2` is not), signed and unsigned integers, booleans,
//! and unicode strings (`<U…`, for joint-name arrays). Object arrays (pickles) are refused: they
//! would run code on load.

use std::collections::BTreeMap;
use std::io::Read;

/// One array: its shape and its values, in C order (a Fortran-order array is transposed on read).
#[derive(Debug, Clone, PartialEq)]
pub enum NpyData {
    Num(Vec<f64>),
    Str(Vec<String>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    pub shape: Vec<usize>,
    pub data: NpyData,
}

impl NpyArray {
    /// The dtype in words, for messages.
    pub fn kind(&self) -> &'static str {
        match self.data {
            NpyData::Num(_) => "numbers",
            NpyData::Str(_) => "strings",
        }
    }
}

const MAGIC: &[u8] = b"\x93NUMPY";

/// Whether `bytes` start like a `.npy` file.
pub fn is_npy(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

/// Parses one `.npy` file's bytes. Errors are plain messages (the caller adds file and member).
pub fn parse_npy(bytes: &[u8]) -> Result<NpyArray, String> {
    if !is_npy(bytes) {
        return Err("not a .npy array (no \\x93NUMPY magic)".into());
    }
    let major = *bytes.get(6).ok_or("truncated header")?;
    let (hlen, start): (usize, usize) = match major {
        1 => (u16::from_le_bytes([at(bytes, 8)?, at(bytes, 9)?]) as usize, 10),
        2 | 3 => {
            let b = [at(bytes, 8)?, at(bytes, 9)?, at(bytes, 10)?, at(bytes, 11)?];
            (u32::from_le_bytes(b) as usize, 12)
        }
        v => return Err(format!("unsupported .npy format version {v}")),
    };
    let header = bytes.get(start..start.saturating_add(hlen)).ok_or("truncated header")?;
    let header = std::str::from_utf8(header).map_err(|_| "header is not text")?;
    let descr = dict_value(header, "descr").ok_or("header has no 'descr'")?;
    let descr = descr.trim_matches(|c| c == '\'' || c == '"');
    let fortran = dict_value(header, "fortran_order").ok_or("header has no 'fortran_order'")?;
    let fortran = match fortran {
        "True" => true,
        "False" => false,
        v => return Err(format!("fortran_order {v}")),
    };
    let shape = parse_shape(dict_value(header, "shape").ok_or("header has no 'shape'")?)?;
    let count = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d)).ok_or("shape overflows")?;
    let body = &bytes[start + hlen..];
    let data = decode(descr, body, count)?;
    let data = if fortran && shape.len() > 1 { to_c_order(data, &shape) } else { data };
    Ok(NpyArray { shape, data })
}

fn at(b: &[u8], i: usize) -> Result<u8, String> {
    b.get(i).copied().ok_or_else(|| "truncated header".to_string())
}

/// The text of `key`'s value in a header dict `{'descr': '<f8', 'fortran_order': False, 'shape': (3, 2), }`.
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let k = header.find(&format!("'{key}'")).or_else(|| header.find(&format!("\"{key}\"")))?;
    let rest = header[k + key.len() + 2..].trim_start().strip_prefix(':')?.trim_start();
    let end = if rest.starts_with('(') {
        rest.find(')')? + 1
    } else if let Some(q) = rest.chars().next().filter(|c| *c == '\'' || *c == '"') {
        rest[1..].find(q)? + 2
    } else {
        rest.find([',', '}']).unwrap_or(rest.len())
    };
    Some(rest[..end].trim())
}

fn parse_shape(s: &str) -> Result<Vec<usize>, String> {
    let inner = s.trim().strip_prefix('(').and_then(|s| s.strip_suffix(')')).ok_or("bad shape")?;
    inner
        .split(',')
        .map(str::trim)
        .filter(|x| !x.is_empty())
        .map(|x| x.trim_end_matches('L').parse::<usize>().map_err(|_| format!("bad shape '{s}'")))
        .collect()
}

fn decode(descr: &str, body: &[u8], count: usize) -> Result<NpyData, String> {
    let (order, rest) = match descr.as_bytes().first() {
        Some(b'<' | b'=' | b'|') => (false, &descr[1..]),
        Some(b'>') => (true, &descr[1..]),
        _ => (false, descr),
    };
    let kind = rest.chars().next().ok_or("empty dtype")?;
    if kind == 'O' {
        return Err("an object array (pickled Python objects): not read".into());
    }
    let size: usize =
        rest[kind.len_utf8()..].parse().map_err(|_| format!("unsupported dtype '{descr}'"))?;
    let width = if kind == 'U' { 4 * size } else { size };
    let need = count.checked_mul(width).ok_or("shape overflows")?;
    if body.len() < need {
        return Err(format!(
            "data truncated: {} bytes for {count} values of '{descr}'",
            body.len()
        ));
    }
    let chunks = body[..need].chunks_exact(width.max(1));
    let word = |c: &[u8]| -> [u8; 8] {
        let mut b = [0u8; 8];
        if order {
            for (i, x) in c.iter().rev().enumerate() {
                b[i] = *x;
            }
        } else {
            b[..c.len()].copy_from_slice(c);
        }
        b
    };
    let signed = |b: [u8; 8], n: usize| -> f64 {
        let shift = 64 - 8 * n as u32;
        ((i64::from_le_bytes(b) << shift) >> shift) as f64
    };
    let v: Vec<f64> = match (kind, size) {
        ('f', 8) => chunks.map(|c| f64::from_le_bytes(word(c))).collect(),
        ('f', 4) => chunks
            .map(|c| {
                let b = word(c);
                f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64
            })
            .collect(),
        ('i', 1 | 2 | 4 | 8) => chunks.map(|c| signed(word(c), size)).collect(),
        ('u', 1 | 2 | 4 | 8) => chunks.map(|c| u64::from_le_bytes(word(c)) as f64).collect(),
        ('b', 1) => chunks.map(|c| f64::from(c[0] != 0)).collect(),
        ('U', _) => {
            let strings = body[..need]
                .chunks_exact(width.max(1))
                .map(|c| {
                    c.chunks_exact(4)
                        .map(|u| {
                            let b = [u[0], u[1], u[2], u[3]];
                            if order { u32::from_be_bytes(b) } else { u32::from_le_bytes(b) }
                        })
                        .take_while(|&u| u != 0)
                        .map(|u| char::from_u32(u).unwrap_or('\u{fffd}'))
                        .collect()
                })
                .collect();
            return Ok(NpyData::Str(strings));
        }
        _ => {
            return Err(format!(
                "unsupported dtype '{descr}' (read: floats f4/f8, integers, bool, unicode)"
            ));
        }
    };
    Ok(NpyData::Num(v))
}

/// Fortran (column-major) data → C order.
fn to_c_order(data: NpyData, shape: &[usize]) -> NpyData {
    let n: usize = shape.iter().product();
    // Index in Fortran order of the C-order flat index i.
    let f_index = |mut i: usize| {
        let mut idx = 0;
        let mut stride = 1;
        let mut coords = vec![0; shape.len()];
        for d in (0..shape.len()).rev() {
            coords[d] = i % shape[d];
            i /= shape[d];
        }
        for d in 0..shape.len() {
            idx += coords[d] * stride;
            stride *= shape[d];
        }
        idx
    };
    match data {
        NpyData::Num(v) => NpyData::Num((0..n).map(|i| v[f_index(i)]).collect()),
        NpyData::Str(v) => NpyData::Str((0..n).map(|i| v[f_index(i)].clone()).collect()),
    }
}

/// The members of an `.npz` archive: (key without `.npy`, array), in archive order. A member
/// that fails to parse is an error naming it.
pub fn parse_npz(bytes: &[u8]) -> Result<Vec<(String, NpyArray)>, String> {
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| format!("not a readable zip archive: {e}"))?;
    let mut out = Vec::new();
    for i in 0..zip.len() {
        let mut f = zip.by_index(i).map_err(|e| format!("zip member {i}: {e}"))?;
        let name = f.name().map_err(|e| format!("zip member {i}: {e}"))?.into_owned();
        let Some(key) = name.strip_suffix(".npy") else { continue };
        let mut buf = Vec::new();
        f.read_to_end(&mut buf).map_err(|e| format!("member '{name}': {e}"))?;
        let a = parse_npy(&buf).map_err(|e| format!("array '{key}': {e}"))?;
        out.push((key.to_string(), a));
    }
    Ok(out)
}

/// Default keys of the measured positions, the command, the velocities, the torques, the time
/// and the joint names in a `.npz` of joint arrays (Isaac Gym / Isaac Lab / legged_gym names
/// first).
const MEASURED: &[&str] = &["dof_pos", "joint_pos", "qpos", "q", "position", "positions"];
const COMMAND: &[&str] =
    &["des_dof_pos", "dof_pos_des", "target_dof_pos", "joint_pos_target", "q_cmd", "q_des"];
const VELOCITY: &[&str] = &["dof_vel", "joint_vel", "qvel", "qd", "velocity"];
const EFFORT: &[&str] = &["dof_torque", "joint_effort", "tau", "torque", "effort"];
const TIME: &[&str] = &["t", "time", "timestamp", "timestamps"];
const NAMES: &[&str] = &["joint_names", "dof_names", "names"];

/// The [`super::mapping::Columns`] of an `.npz` of joint arrays (`n × k`, time first; `n` for
/// one joint).
pub(crate) fn npz_columns(
    bytes: &[u8],
    map: &super::mapping::LogMap,
) -> Result<super::mapping::Columns, String> {
    arrays_columns(parse_npz(bytes)?, map, "NumPy .npz")
}

/// The [`super::mapping::Columns`] of named joint arrays (an `.npz`'s, a PyTorch `.pt` dict's):
/// `n × k`, time first; `n` for one joint.
pub(crate) fn arrays_columns(
    arrays: Vec<(String, NpyArray)>,
    map: &super::mapping::LogMap,
    format: &'static str,
) -> Result<super::mapping::Columns, String> {
    use super::mapping::{Columns, columns_of, pick};
    let keys: Vec<String> = arrays.iter().map(|(k, _)| k.clone()).collect();
    let get = |k: &str| arrays.iter().find(|(n, _)| n == k).map(|(_, a)| a);
    let num = |k: &str| -> Result<(&NpyArray, &Vec<f64>), String> {
        let a = get(k).ok_or_else(|| format!("no array '{k}'"))?;
        match &a.data {
            NpyData::Num(v) => Ok((a, v)),
            NpyData::Str(_) => Err(format!("array '{k}' holds strings, not numbers")),
        }
    };
    let measured = pick(map.measured.as_deref(), MEASURED, &keys, "array")?.ok_or_else(|| {
        format!(
            "no array of measured joint positions (looked for {}; it has: {}): name it with \
             --log-measured KEY",
            MEASURED.join(", "),
            super::mapping::list(&keys)
        )
    })?;
    let (qa, qv) = num(&measured)?;
    let (n, k) = match qa.shape[..] {
        [n] => (n, 1),
        [n, k] => (n, k),
        _ => {
            return Err(format!(
                "array '{measured}' has shape {:?}: expected (time, joint)",
                qa.shape
            ));
        }
    };
    let matrix = |key: &str| -> Result<Vec<Vec<f64>>, String> {
        let (a, v) = num(key)?;
        let (an, ak) = match a.shape[..] {
            [an] => (an, 1),
            [an, ak] => (an, ak),
            _ => (0, 0),
        };
        if (an, ak) != (n, k) {
            return Err(format!(
                "array '{key}' has shape {:?}, '{measured}' has {:?}: they must match (time, joint)",
                a.shape, qa.shape
            ));
        }
        Ok(columns_of(v, n, k))
    };
    let command = pick(map.command.as_deref(), COMMAND, &keys, "array")?;
    let velocity = pick(map.velocity.as_deref(), VELOCITY, &keys, "array")?;
    let effort = pick(map.effort.as_deref(), EFFORT, &keys, "array")?;
    let time_key = pick(map.time.as_deref(), TIME, &keys, "array")?;
    let t = match time_key.clone() {
        Some(tk) => {
            let (a, v) = num(&tk)?;
            if v.len() != n || a.shape.len() != 1 {
                return Err(format!(
                    "time array '{tk}' has shape {:?}, '{measured}' has {n} rows (time first: \
                     arrays are (time, joint))",
                    a.shape
                ));
            }
            v.clone()
        }
        None => {
            let dt = match map.dt {
                Some(dt) => dt,
                None => match get("dt").map(|a| &a.data) {
                    Some(NpyData::Num(v)) if v.len() == 1 => v[0],
                    _ => {
                        return Err(format!(
                            "no time: none of the arrays {} and no 'dt'; give --log-time KEY or \
                             --log-dt SECONDS",
                            TIME.join(", ")
                        ));
                    }
                },
            };
            if !(dt.is_finite() && dt > 0.0) {
                return Err(format!("dt must be positive, found {dt}"));
            }
            (0..n).map(|i| i as f64 * dt).collect()
        }
    };
    let names = match pick(None, NAMES, &keys, "array")? {
        Some(nk) => match get(&nk).map(|a| &a.data) {
            Some(NpyData::Str(s)) => Some(s.clone()),
            _ => None,
        },
        None => None,
    };
    let q_cmd = command.as_deref().map(matrix).transpose()?;
    let scalar = |k: &str| match get(k).map(|a| (&a.data, a.shape.is_empty())) {
        Some((NpyData::Num(v), true)) => v.first().copied().filter(|x| x.is_finite() && *x > 0.0),
        _ => None,
    };
    let control_rate_hz = scalar("control_rate_hz").or_else(|| scalar("fps"));
    let mut meta = BTreeMap::new();
    for (key, a) in &arrays {
        // Scalars (a rate, a seed) are kept as metadata.
        if let (NpyData::Num(v), true) = (&a.data, a.shape.is_empty()) {
            let prefix = if format == super::torch_pt::FORMAT { "pt" } else { "npz" };
            meta.insert(format!("{prefix}.{key}"), format!("{}", v[0]));
        }
    }
    Ok(Columns {
        format,
        t,
        names,
        measured_key: measured.clone(),
        command_key: command.clone(),
        velocity_key: velocity.clone(),
        effort_key: effort.clone(),
        time_key,
        keys: keys.clone(),
        q: columns_of(qv, n, k),
        q_cmd,
        qd: velocity.as_deref().map(matrix).transpose()?,
        tau: effort.as_deref().map(matrix).transpose()?,
        meta,
        control_rate_hz,
        ..Default::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy(descr: &str, fortran: bool, shape: &str, body: &[u8]) -> Vec<u8> {
        let mut h = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
            if fortran { "True" } else { "False" }
        );
        while (10 + h.len() + 1) % 64 != 0 {
            h.push(' ');
        }
        h.push('\n');
        let mut b = MAGIC.to_vec();
        b.extend([1, 0]);
        b.extend((h.len() as u16).to_le_bytes());
        b.extend(h.as_bytes());
        b.extend(body);
        b
    }

    fn f8(shape: &str, v: &[f64]) -> NpyArray {
        let body: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        parse_npy(&npy("<f8", false, shape, &body)).unwrap()
    }

    /// The error of the arrays `pos` (3 rows, joints a and b), `target` under `map`.
    fn error_of(pos: &[f64], target: &[f64], map: &super::super::mapping::LogMap) -> String {
        let arrays = vec![
            ("time".to_string(), f8("(3,)", &[0.0, 0.01, 0.02])),
            ("pos".to_string(), f8("(3, 2)", pos)),
            ("target".to_string(), f8("(3, 2)", target)),
        ];
        let mut map = map.clone();
        map.measured = Some("pos".into());
        map.command = Some("target".into());
        map.joints = Some(vec!["a".into(), "b".into()]);
        let cols = arrays_columns(arrays, &map, "NumPy .npz").unwrap();
        let path = std::path::Path::new("log.npz");
        let opts = super::super::ParseOptions::default();
        match super::super::mapping::assemble(path, cols, &map, &opts) {
            Ok(_) => String::new(),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn a_non_finite_value_is_named_by_array_row_and_column() {
        let map = super::super::mapping::LogMap::default();
        let ok = [0.1, 0.2, 0.1, 0.2, 0.1, 0.2];
        let e = error_of(&[0.1, 0.2, 0.1, 0.2, 0.1, f64::NAN], &ok, &map);
        assert!(e.contains("'pos' row 2 (0-based, time 0.02 s), column 1 (joint 'b')"), "{e}");
        let e = error_of(&ok, &[0.1, 0.2, f64::INFINITY, 0.2, 0.1, 0.2], &map);
        assert!(e.contains("'target' row 1 (0-based, time 0.01 s), column 0 (joint 'a')"), "{e}");
        // A skipped joint's values are not read.
        let skip = super::super::mapping::LogMap { skip: vec!["b".into()], ..map.clone() };
        assert_eq!(error_of(&[0.1, f64::NAN, 0.1, 0.2, 0.1, 0.2], &ok, &skip), "");
    }

    #[test]
    fn reads_dtypes_orders_and_refuses_objects() {
        let body: Vec<u8> =
            [1.0f64, 2.0, 3.0, 4.0, 5.0, 6.0].iter().flat_map(|x| x.to_le_bytes()).collect();
        let c = parse_npy(&npy("<f8", false, "(2, 3)", &body)).unwrap();
        assert_eq!(
            (c.shape.clone(), c.data),
            (vec![2, 3], NpyData::Num(vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]))
        );
        let f = parse_npy(&npy("<f8", true, "(2, 3)", &body)).unwrap();
        assert_eq!(f.data, NpyData::Num(vec![1.0, 3.0, 5.0, 2.0, 4.0, 6.0]));
        let be: Vec<u8> = [-2i32, 7].iter().flat_map(|x| x.to_be_bytes()).collect();
        assert_eq!(
            parse_npy(&npy(">i4", false, "(2,)", &be)).unwrap().data,
            NpyData::Num(vec![-2.0, 7.0])
        );
        let s: Vec<u8> = "ab\0\0c\0\0\0".chars().flat_map(|c| (c as u32).to_le_bytes()).collect();
        assert_eq!(
            parse_npy(&npy("<U4", false, "(2,)", &s)).unwrap().data,
            NpyData::Str(vec!["ab".into(), "c".into()])
        );
        assert!(parse_npy(&npy("|O", false, "(2,)", &[0; 16])).unwrap_err().contains("object"));
        assert!(parse_npy(&npy("<f8", false, "(3,)", &[0; 16])).unwrap_err().contains("truncated"));
        assert!(parse_npy(b"\x93NUMPY").is_err());
        assert!(parse_npy(b"PK").is_err());
    }
}
