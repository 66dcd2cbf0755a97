//! URDF `package://NAME/path` mesh references, resolved the way ROS does: `--package NAME=DIR`
//! first, then the directories of `ROS_PACKAGE_PATH` (a package is `ENTRY/NAME`, or `ENTRY`
//! itself when its name is NAME). MuJoCo does not know `package://`, so the URDF it compiles is
//! a copy with absolute mesh paths (and `strippath="false"`), written to the temp directory on
//! the same lines as the original, so that MuJoCo's line numbers still point into the user's file.
//! An unknown package or a missing mesh is an error at the `filename` attribute (file:line).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::error::LoadError;
use crate::model::source::{Loc, SourceMap};

static PACKAGES: Mutex<Vec<(String, PathBuf)>> = Mutex::new(Vec::new());

/// `--package NAME=DIR` of the command line (set once by the CLI).
pub fn set_packages(p: Vec<(String, PathBuf)>) {
    if let Ok(mut g) = PACKAGES.lock() {
        *g = p;
    }
}

/// Parses `NAME=DIR` (clap value parser).
pub fn parse_package_arg(s: &str) -> Result<(String, PathBuf), String> {
    match s.split_once('=') {
        Some((n, d)) if !n.is_empty() && !d.is_empty() => Ok((n.to_string(), PathBuf::from(d))),
        _ => Err(format!("expected NAME=DIR, got `{s}`")),
    }
}

fn find_package(name: &str) -> (Option<PathBuf>, Vec<PathBuf>) {
    let mut searched = Vec::new();
    if let Ok(g) = PACKAGES.lock()
        && let Some((_, d)) = g.iter().find(|(n, _)| n == name)
    {
        return (Some(d.clone()), searched);
    }
    if let Some(rpp) = std::env::var_os("ROS_PACKAGE_PATH") {
        for entry in std::env::split_paths(&rpp).filter(|e| !e.as_os_str().is_empty()) {
            if entry.file_name().is_some_and(|f| f == name) && entry.is_dir() {
                return (Some(entry), searched);
            }
            let cand = entry.join(name);
            if cand.is_dir() {
                return (Some(cand), searched);
            }
            searched.push(entry);
        }
    }
    (None, searched)
}

/// For a URDF whose meshes use `package://`: the path of a resolved copy to give MuJoCo (the
/// caller deletes it). `Ok(None)` when nothing needs resolving.
pub fn resolved_copy(map: &SourceMap, file: usize) -> Result<Option<PathBuf>, LoadError> {
    let src = map.file(file);
    let text = src.text.clone();
    if !text.contains("package://") {
        return Ok(None);
    }
    let model_dir = src.path.parent().map(Path::to_path_buf).unwrap_or_default();
    let opts = roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    // Read as the model was (`xml_prefix`): the copy has the file's length and offsets.
    let parsed = crate::model::xml_prefix::renamed_undeclared(&text).map(|(copy, _)| copy);
    let Ok(doc) = roxmltree::Document::parse_with_options(parsed.as_deref().unwrap_or(&text), opts)
    else {
        return Ok(None);
    };
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    for n in doc.descendants().filter(|n| n.has_tag_name("mesh")) {
        let Some(a) = n.attributes().find(|a| a.name() == "filename") else { continue };
        let v = a.value();
        let r = a.range_value();
        let loc = Loc { file, start: r.start, end: r.end };
        let full = if let Some(rest) = v.strip_prefix("package://") {
            let (name, sub) = rest.split_once('/').unwrap_or((rest, ""));
            let (dir, searched) = find_package(name);
            let Some(dir) = dir else {
                let where_ = if searched.is_empty() {
                    "ROS_PACKAGE_PATH is not set".to_string()
                } else {
                    format!(
                        "not in ROS_PACKAGE_PATH ({})",
                        searched
                            .iter()
                            .map(|p| p.display().to_string())
                            .collect::<Vec<_>>()
                            .join(":")
                    )
                };
                return Err(LoadError::at(
                    map,
                    loc,
                    format!("package `{name}` not found: {where_}; pass --package {name}=DIR"),
                ));
            };
            dir.join(sub)
        } else if let Some(p) = v.strip_prefix("file://") {
            PathBuf::from(p)
        } else if Path::new(v).is_absolute() {
            PathBuf::from(v)
        } else {
            model_dir.join(v)
        };
        if !full.is_file() {
            return Err(LoadError::at(
                map,
                loc,
                format!("mesh file not found: {v} (looked for {})", full.display()),
            ));
        }
        let abs = std::fs::canonicalize(&full).unwrap_or(full);
        let s = abs.to_string_lossy().replace('&', "&amp;").replace('"', "&quot;");
        edits.push((r, s));
    }
    // MuJoCo keeps the directories of mesh paths only with strippath="false".
    let root = doc.root_element();
    let compiler = root
        .children()
        .find(|c| c.has_tag_name("mujoco"))
        .and_then(|m| m.children().find(|c| c.has_tag_name("compiler")));
    match compiler {
        Some(c) => match c.attributes().find(|a| a.name() == "strippath") {
            Some(a) => edits.push((a.range_value(), "false".into())),
            None => {
                let at = c.range().start + "<compiler".len();
                edits.push((at..at, " strippath=\"false\"".into()));
            }
        },
        None if root.children().any(|c| c.has_tag_name("mujoco")) => {
            let m = root.children().find(|c| c.has_tag_name("mujoco")).expect("checked");
            let at = m.range().start + "<mujoco".len();
            // `<mujoco ...>`: the compiler goes right after the start tag's '>' (same line).
            let close = text[at..].find('>').map(|i| at + i + 1).unwrap_or(at);
            edits.push((close..close, "<compiler strippath=\"false\"/>".into()));
        }
        None => {
            let start = root.range().start;
            let close = text[start..].find('>').map(|i| start + i + 1).unwrap_or(start);
            edits.push((close..close, "<mujoco><compiler strippath=\"false\"/></mujoco>".into()));
        }
    }
    edits.sort_by_key(|e| std::cmp::Reverse(e.0.start));
    let mut out = text;
    for (r, s) in edits {
        out.replace_range(r, &s);
    }
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let stem = src
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into());
    let tmp =
        std::env::temp_dir().join(format!("modellint-{}-{n}-{stem}.urdf", std::process::id()));
    std::fs::write(&tmp, out)
        .map_err(|e| LoadError::plain(&tmp, format!("cannot write the resolved URDF: {e}")))?;
    Ok(Some(tmp))
}
