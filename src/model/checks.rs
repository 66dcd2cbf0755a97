//! Checks on the source tree before MuJoCo compiles it: numeric attributes are finite, asset
//! files exist (each error points at the attribute).

use std::path::{Path, PathBuf};

use super::source::{SourceMap, XNode};
use crate::error::LoadError;

/// Attributes that hold names or paths, never numbers (skipped by the NaN/inf check).
const STRING_ATTRS: &[&str] = &[
    "name",
    "class",
    "childclass",
    "file",
    "joint",
    "joint1",
    "joint2",
    "body",
    "body1",
    "body2",
    "geom",
    "geom1",
    "geom2",
    "site",
    "site1",
    "site2",
    "tendon",
    "tendon1",
    "tendon2",
    "mesh",
    "material",
    "texture",
    "hfield",
    "target",
    "objname",
    "objtype",
    "type",
    "meshdir",
    "texturedir",
    "assetdir",
    "model",
    "prefix",
    "content_type",
    "refsite",
    "cranksite",
    "slidersite",
    "actuator",
    "plugin",
    "instance",
    "key",
    "mode",
    "link",
    "parent",
    "child",
    "filename",
    "version",
];

pub(super) fn check_numbers(map: &SourceMap, n: &XNode) -> Result<(), LoadError> {
    for a in &n.attrs {
        if STRING_ATTRS.contains(&a.name.as_str()) {
            continue;
        }
        let toks: Vec<&str> = a.value.split_whitespace().collect();
        if toks.is_empty() {
            continue;
        }
        let parsed: Vec<Option<f64>> = toks.iter().map(|t| t.parse::<f64>().ok()).collect();
        if parsed.iter().all(Option::is_some)
            && parsed.iter().any(|v| !v.unwrap_or(0.0).is_finite())
        {
            return Err(LoadError::at(
                map,
                a.loc,
                format!(
                    "<{}> attribute `{}` is not a finite number: \"{}\"",
                    n.tag, a.name, a.value
                ),
            ));
        }
    }
    for c in &n.children {
        check_numbers(map, c)?;
    }
    Ok(())
}

/// The numeric attributes of the URDF specification, by element: (tag, attribute, how many
/// numbers; 0 = any count). MuJoCo's URDF compiler reads most of them and rejects a value it
/// cannot read ("bad format in attribute", "does not have enough data", "has too much data");
/// modellint's own readers read some MuJoCo ignores (`<limit velocity>`), and ROS's parser
/// (urdfdom) rejects all of them, so none may pass as "not stated".
const URDF_NUMBERS: &[(&str, &str, usize)] = &[
    ("origin", "xyz", 3),
    ("origin", "rpy", 3),
    ("axis", "xyz", 3),
    ("mass", "value", 1),
    ("inertia", "ixx", 1),
    ("inertia", "ixy", 1),
    ("inertia", "ixz", 1),
    ("inertia", "iyy", 1),
    ("inertia", "iyz", 1),
    ("inertia", "izz", 1),
    ("limit", "lower", 1),
    ("limit", "upper", 1),
    ("limit", "effort", 1),
    ("limit", "velocity", 1),
    ("dynamics", "damping", 1),
    ("dynamics", "friction", 1),
    ("safety_controller", "soft_lower_limit", 1),
    ("safety_controller", "soft_upper_limit", 1),
    ("safety_controller", "k_position", 1),
    ("safety_controller", "k_velocity", 1),
    ("calibration", "rising", 1),
    ("calibration", "falling", 1),
    ("mimic", "multiplier", 1),
    ("mimic", "offset", 1),
    ("box", "size", 3),
    ("cylinder", "radius", 1),
    ("cylinder", "length", 1),
    ("capsule", "radius", 1),
    ("capsule", "length", 1),
    ("sphere", "radius", 1),
    // MuJoCo 3.17 reads exactly three (one or two: "does not have enough data"), as urdfdom does.
    ("mesh", "scale", 3),
    ("color", "rgba", 4),
];

/// URDF elements whose children [`URDF_NUMBERS`] covers: a `<gazebo>` or `<transmission>` block
/// (free-form, another tool's) is not walked.
const URDF_WALKED: &[&str] =
    &["robot", "link", "joint", "inertial", "visual", "collision", "geometry", "material"];

/// One number as MuJoCo's compiler reads it (C `strtod`, the whole token): Rust's decimal
/// syntax, or a C hexadecimal float (`0x1p-3`).
pub(crate) fn c_number(tok: &str) -> Option<f64> {
    if let Ok(v) = tok.parse::<f64>() {
        return Some(v);
    }
    let (neg, body) = match tok.as_bytes().first() {
        Some(b'-') => (true, &tok[1..]),
        Some(b'+') => (false, &tok[1..]),
        _ => (false, tok),
    };
    let hex = body.strip_prefix("0x").or_else(|| body.strip_prefix("0X"))?;
    let (mant, exp) = match hex.find(['p', 'P']) {
        Some(k) => (&hex[..k], hex[k + 1..].parse::<i32>().ok()?),
        None => (hex, 0),
    };
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    if int.is_empty() && frac.is_empty() {
        return None;
    }
    let mut v = 0.0f64;
    for c in int.chars() {
        v = v * 16.0 + f64::from(c.to_digit(16)?);
    }
    let mut scale = 1.0 / 16.0;
    for c in frac.chars() {
        v += f64::from(c.to_digit(16)?) * scale;
        scale /= 16.0;
    }
    let v = v * 2f64.powi(exp);
    Some(if neg { -v } else { v })
}

/// URDF: every attribute of [`URDF_NUMBERS`] holds numbers, as many as the specification
/// takes; an error at the attribute otherwise. An empty value is not stated, as MuJoCo reads it.
pub(super) fn check_urdf_numbers(map: &SourceMap, n: &XNode) -> Result<(), LoadError> {
    for &(tag, name, count) in URDF_NUMBERS.iter().filter(|(t, _, _)| *t == n.tag) {
        let Some(a) = n.attr(name) else { continue };
        let toks: Vec<&str> = a.value.split_whitespace().collect();
        if toks.is_empty() {
            continue;
        }
        let value = &a.value;
        let n_toks = toks.len();
        let why = if let Some(bad) = toks.iter().find(|t| c_number(t).is_none()) {
            let of = if n_toks > 1 { format!(" in \"{value}\"") } else { String::new() };
            format!("bad format in attribute '{name}': \"{bad}\"{of} is not a number")
        } else if count > 0 && n_toks != count {
            let what = if n_toks < count { "does not have enough" } else { "has too much" };
            format!(
                "attribute '{name}' {what} data: \"{value}\" is {n_toks} numbers, URDF takes {count}"
            )
        } else {
            continue;
        };
        return Err(LoadError::at(map, a.loc, format!("URDF <{tag}>: {why}")));
    }
    if URDF_WALKED.contains(&n.tag.as_str()) {
        for c in &n.children {
            check_urdf_numbers(map, c)?;
        }
    }
    Ok(())
}

/// URDF: two `<link>`s (or two `<joint>`s) with one name. MuJoCo rejects
/// it as "repeated URDF name" without saying which or where; here it is the second one's `name`.
pub(super) fn check_urdf_names(map: &SourceMap, root: &XNode) -> Result<(), LoadError> {
    for tag in ["link", "joint"] {
        let mut seen: Vec<&str> = Vec::new();
        for c in root.children_tagged(tag) {
            let Some(a) = c.attr("name") else { continue };
            if seen.contains(&a.value.as_str()) {
                return Err(LoadError::at(
                    map,
                    a.loc,
                    format!("URDF: a second <{tag}> named \"{}\" (names must be unique)", a.value),
                ));
            }
            seen.push(&a.value);
        }
    }
    Ok(())
}

/// Asset attributes that name files MuJoCo reads (cube and skybox textures use the six faces).
const FILE_ATTRS: &[&str] =
    &["file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"];

/// Checks that every asset file the model names exists, pointing at the attribute when not, and
/// returns them (the inputs of the compile, for the cache key).
pub(super) fn check_assets(
    map: &SourceMap,
    root: &XNode,
    model_dir: &Path,
) -> Result<Vec<PathBuf>, LoadError> {
    let mut files = Vec::new();
    let mut meshdir = None;
    let mut texturedir = None;
    for c in root.children_tagged("compiler") {
        if let Some(d) = c.get("assetdir") {
            meshdir.get_or_insert(d.to_string());
            texturedir.get_or_insert(d.to_string());
        }
        if let Some(d) = c.get("meshdir") {
            meshdir = Some(d.to_string());
        }
        if let Some(d) = c.get("texturedir") {
            texturedir = Some(d.to_string());
        }
    }
    for asset in root.children_tagged("asset") {
        for a in &asset.children {
            let dir = match a.tag.as_str() {
                "mesh" | "hfield" | "skin" => &meshdir,
                "texture" => &texturedir,
                _ => &None,
            };
            for f in FILE_ATTRS.iter().filter_map(|n| a.attr(n)) {
                let p = Path::new(&f.value);
                let full = if p.is_absolute() {
                    p.to_path_buf()
                } else {
                    model_dir.join(dir.as_deref().unwrap_or("")).join(p)
                };
                if !full.is_file() {
                    return Err(LoadError::at(
                        map,
                        f.loc,
                        format!(
                            "<{}> file not found: {} (looked for {})",
                            a.tag,
                            f.value,
                            full.display()
                        ),
                    ));
                }
                files.push(full);
            }
        }
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::c_number;

    /// C `strtod` syntax, the whole token: decimal and hexadecimal floats; nothing after them.
    #[test]
    fn numbers_read_as_mujoco_reads_them() {
        for (t, v) in [("1.5", 1.5), ("+2.", 2.0), (".3", 0.3), ("-12e-1", -1.2), ("0x10", 16.0)] {
            assert_eq!(c_number(t), Some(v), "{t}");
        }
        assert_eq!(c_number("0x1.4p2"), Some(5.0));
        assert_eq!(c_number("-0X.8"), Some(-0.5));
        for t in ["abc", "1.5x", "2,", "0x", "0x1p", "--1", "1..2", "", "e5", "0xg"] {
            assert_eq!(c_number(t), None, "{t}");
        }
    }
}
