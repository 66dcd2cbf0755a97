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
