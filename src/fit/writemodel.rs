//! `fit --write-model OUT.xml`: write the fitted values into the file that holds each element.
//!
//! A Menagerie layout keeps the robot in one file (`t1.xml`) and a scene that includes it
//! (`scene.xml`). The elements to edit (joints, actuators) are searched in the model file and in
//! every file it includes. Each file that gets an edit is written as a copy beside OUT.xml
//! (`<OUT stem>_<file stem>.xml`), and the includes that lead to it are redirected to the copy; the
//! original files are never touched. When OUT.xml is in another directory than the model, every
//! file of the include tree is copied and relative asset paths (`<compiler meshdir/texturedir/
//! assetdir>`, `file=` of assets when no such directory is set) are rebased, so that MuJoCo finds
//! the meshes from the new place.
//!
//! The written model is loaded again (MuJoCo compiles it): a model that does not load is an error,
//! not a file left behind silently. A fitted value whose element is in none of the files is an
//! error too (exit 2 in the CLI): a `--write-model` that writes nothing it was asked to is never
//! a success.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Component, Path, PathBuf};

use crate::fit::select::Selected;
use crate::fit::writeback::{edit_file, unwritten};
use crate::model::Robot;

/// Outcome of a successful write: every file written (OUT.xml first) and notes for the user.
#[derive(Debug, Default)]
pub struct Written {
    pub files: Vec<PathBuf>,
    pub notes: Vec<String>,
    /// Whether any fitted value was written into the model (else it is the input, re-pathed).
    pub changed: bool,
}

struct Src {
    path: PathBuf,
    text: String,
    /// (byte range of the `file` attribute value, index of the included file in the list).
    includes: Vec<(std::ops::Range<usize>, usize)>,
}

fn parse(text: &str) -> Result<roxmltree::Document<'_>, String> {
    let opts = roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    roxmltree::Document::parse_with_options(text, opts).map_err(|e| e.to_string())
}

/// The model file and every file it includes (depth first, each once), as the loader reads them:
/// an include path is relative to the including file's directory.
fn closure(model: &Path) -> Result<Vec<Src>, String> {
    let mut files: Vec<Src> = Vec::new();
    let mut index: BTreeMap<PathBuf, usize> = BTreeMap::new();
    let mut todo = vec![model.to_path_buf()];
    let canon = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    index.insert(canon(model), 0);
    while let Some(p) = todo.pop() {
        let text =
            std::fs::read_to_string(&p).map_err(|e| format!("cannot read {}: {e}", p.display()))?;
        files.push(Src { path: p.clone(), text, includes: vec![] });
        let me = files.len() - 1;
        let base = p.parent().map(Path::to_path_buf).unwrap_or_default();
        let found: Vec<(std::ops::Range<usize>, PathBuf)> = {
            let doc = parse(&files[me].text).map_err(|e| format!("{}: {e}", p.display()))?;
            doc.descendants()
                .filter(|n| n.has_tag_name("include"))
                .filter_map(|n| {
                    n.attributes()
                        .find(|a| a.name() == "file")
                        .map(|a| (a.range_value(), base.join(a.value())))
                })
                .collect()
        };
        for (range, inc) in found {
            let key = canon(&inc);
            let id = match index.get(&key) {
                Some(&id) => id,
                None => {
                    let id = index.len();
                    index.insert(key, id);
                    todo.insert(0, inc);
                    id
                }
            };
            files[me].includes.push((range, id));
        }
    }
    // `index` numbers files in discovery order, `files` is in read order: the same with a FIFO queue.
    Ok(files)
}

/// Relative path from directory `from` to `to` (both absolute), or `to` when none exists (no
/// common root: another drive). Relative even when only the root is shared (/tmp/out vs
/// /work/models: `../../work/models`): the written model and the original tree then move
/// together, as a repository checkout does, and no machine's absolute path is written into it.
fn relative(from: &Path, to: &Path) -> PathBuf {
    let f: Vec<Component> = from.components().collect();
    let t: Vec<Component> = to.components().collect();
    let common = f.iter().zip(&t).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return to.to_path_buf();
    }
    let mut r = PathBuf::new();
    for _ in common..f.len() {
        r.push("..");
    }
    for c in &t[common..] {
        r.push(c.as_os_str());
    }
    if r.as_os_str().is_empty() { PathBuf::from(".") } else { r }
}

fn slash(p: &Path) -> String {
    p.to_string_lossy().replace('\\', "/")
}

/// Text edits (range, replacement) that rebase relative asset paths by `rel`.
fn rebase_edits(
    text: &str,
    rel: &Path,
    dirs_set: &BTreeSet<&'static str>,
) -> Result<Vec<(std::ops::Range<usize>, String)>, String> {
    let doc = parse(text)?;
    let mut edits = Vec::new();
    let rebase = |v: &str| -> Option<String> {
        let p = Path::new(v);
        if v.is_empty() || p.is_absolute() { None } else { Some(slash(&rel.join(p))) }
    };
    for n in doc.descendants().filter(|n| n.is_element()) {
        let tag = n.tag_name().name();
        for a in n.attributes() {
            let dir_kind = match (tag, a.name()) {
                ("compiler", "meshdir" | "texturedir" | "assetdir") => None,
                ("mesh" | "skin" | "hfield", "file") => Some("meshdir"),
                (
                    "texture",
                    "file" | "fileright" | "fileleft" | "fileup" | "filedown" | "filefront"
                    | "fileback",
                ) => Some("texturedir"),
                _ => continue,
            };
            if dir_kind.is_some_and(|k| dirs_set.contains(k) || dirs_set.contains("assetdir")) {
                continue;
            }
            if let Some(v) = rebase(a.value()) {
                edits.push((a.range_value(), v));
            }
        }
    }
    Ok(edits)
}

fn apply(text: &str, mut edits: Vec<(std::ops::Range<usize>, String)>) -> String {
    edits.sort_by_key(|e| std::cmp::Reverse(e.0.start));
    let mut out = text.to_string();
    for (r, v) in edits {
        out.replace_range(r, &v);
    }
    out
}

/// Writes the fitted model to `out` (and edited copies of included files beside it). `Err` when
/// an MJCF-expressible value found no element in any file, or the written model does not load.
pub fn write_model(
    model: &Path,
    robot: &Robot,
    selected: &[Selected],
    out: &Path,
) -> Result<Written, String> {
    let files = closure(model)?;
    if parse(&files[0].text).is_ok_and(|d| d.root_element().has_tag_name("robot")) {
        return Err(format!(
            "--write-model {}: {} is URDF; the fitted values are written into MJCF only (load the URDF in MuJoCo, save it as MJCF, fit that)",
            out.display(),
            model.display()
        ));
    }
    let mut found = BTreeSet::new();
    let mut edited: Vec<Option<String>> = Vec::new();
    let mut notes = Vec::new();
    for f in &files {
        let before = found.len();
        let (text, w) = edit_file(&f.text, robot, selected, &mut found)
            .map_err(|e| format!("{}: {e}", f.path.display()))?;
        notes.extend(w);
        edited.push((found.len() > before && text != f.text).then_some(text));
    }
    let missing = unwritten(selected, &found, "in the model or the files it includes");
    let (hard, soft): (Vec<String>, Vec<String>) = missing
        .into_iter()
        .partition(|w| w.ends_with("not written") && !w.contains("see --write-actuators"));
    if !hard.is_empty() {
        return Err(format!("--write-model {}: {}", out.display(), hard.join("; ")));
    }
    notes.extend(soft);
    let changed = edited.iter().any(Option::is_some);
    if selected.is_empty() {
        notes.push(format!(
            "no missing physics was selected: {} is the input model, unchanged but for its paths",
            out.display()
        ));
    } else if !changed {
        let effects: Vec<String> =
            selected.iter().map(|s| format!("{} on {}", s.effect, s.joints.join(","))).collect();
        notes.push(format!(
            "nothing of the fit has an MJCF form ({}): {} is the input model, unchanged but for \
             its paths; the fitted values are in --write-actuators",
            effects.join("; "),
            out.display()
        ));
    }

    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let model_dir =
        abs(model.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")));
    let out_dir_raw = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(out_dir_raw)
        .map_err(|e| format!("cannot create {}: {e}", out_dir_raw.display()))?;
    let out_dir = abs(out_dir_raw);
    let moved = model_dir != out_dir;

    // Files to write: the model itself, every edited file and the files that include them; all of
    // the include tree when the output directory differs (their relative paths need rebasing).
    let n = files.len();
    let mut write = vec![false; n];
    write[0] = true;
    for i in 0..n {
        write[i] |= moved || edited[i].is_some();
    }
    loop {
        let mut changed = false;
        for i in 0..n {
            if !write[i] && files[i].includes.iter().any(|(_, c)| write[*c]) {
                write[i] = true;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    if abs(out) == abs(model) || (1..n).any(|i| abs(&files[i].path) == abs(out)) {
        return Err(format!(
            "--write-model {}: would overwrite the input model; choose another file name",
            out.display()
        ));
    }
    let stem =
        out.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "fitted".into());
    let mut names: Vec<PathBuf> = Vec::with_capacity(n);
    let mut taken: BTreeSet<String> = BTreeSet::new();
    taken.insert(out.file_name().map(|s| s.to_string_lossy().to_string()).unwrap_or_default());
    for (i, f) in files.iter().enumerate() {
        if i == 0 {
            names.push(out.to_path_buf());
            continue;
        }
        let fstem = f
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_else(|| "include".into());
        let mut name = format!("{stem}_{fstem}.xml");
        let mut k = 2;
        while !taken.insert(name.clone()) {
            name = format!("{stem}_{fstem}_{k}.xml");
            k += 1;
        }
        names.push(out_dir_raw.join(name));
    }
    let rel = relative(&out_dir, &model_dir);
    // Asset directories set anywhere in the include tree (compiler settings are global).
    let mut dirs_set: BTreeSet<&'static str> = BTreeSet::new();
    for f in &files {
        if let Ok(doc) = parse(&f.text) {
            for c in doc.descendants().filter(|n| n.has_tag_name("compiler")) {
                for k in ["meshdir", "texturedir", "assetdir"] {
                    if c.attribute(k).is_some() {
                        dirs_set.insert(k);
                    }
                }
            }
        }
    }

    let mut written = Vec::new();
    for i in (0..n).filter(|&i| write[i]) {
        let f = &files[i];
        let base = edited[i].clone().unwrap_or_else(|| f.text.clone());
        // Edits to `base`: includes redirected to copies (or rebased), asset paths rebased.
        let mut edits = Vec::new();
        // Includes: the attribute ranges refer to the original text; joint/actuator edits may have
        // shifted them, so locate includes in `base` again by document order.
        let doc = parse(&base).map_err(|e| format!("{}: {e}", f.path.display()))?;
        let inc_ranges: Vec<std::ops::Range<usize>> = doc
            .descendants()
            .filter(|n| n.has_tag_name("include"))
            .filter_map(|n| n.attributes().find(|a| a.name() == "file").map(|a| a.range_value()))
            .collect();
        for (r, (_, child)) in inc_ranges.into_iter().zip(&f.includes) {
            let target = if write[*child] {
                names[*child].file_name().map(PathBuf::from).unwrap_or_default()
            } else if moved {
                // Unreachable: every file is written when moved. Kept for clarity.
                rel.join(files[*child].path.strip_prefix(&model_dir).unwrap_or(&files[*child].path))
            } else {
                continue;
            };
            edits.push((r, slash(&target)));
        }
        if moved {
            edits.extend(
                rebase_edits(&base, &rel, &dirs_set)
                    .map_err(|e| format!("{}: {e}", f.path.display()))?,
            );
        }
        let text = apply(&base, edits);
        std::fs::write(&names[i], &text)
            .map_err(|e| format!("cannot write {}: {e}", names[i].display()))?;
        written.push(names[i].clone());
    }
    for i in (1..n).filter(|&i| edited[i].is_some()) {
        notes.push(format!(
            "fitted values for {} written to {} (a copy; the included file is unchanged)",
            files[i].path.display(),
            names[i].display()
        ));
    }

    // The written model must load, and must be the one the fit was made for.
    let mut map = crate::model::source::SourceMap::default();
    crate::model::load(&mut map, out, None).map_err(|e| {
        format!("--write-model {}: the written model does not load: {e}", out.display())
    })?;
    Ok(Written { files: written, notes, changed })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_between_directories() {
        assert_eq!(
            relative(Path::new("/a/b/out"), Path::new("/a/models/t1")),
            PathBuf::from("../../models/t1")
        );
        assert_eq!(relative(Path::new("/a/b"), Path::new("/a/b")), PathBuf::from("."));
        assert_eq!(relative(Path::new("/a/b"), Path::new("/a/b/c")), PathBuf::from("c"));
        assert_eq!(
            relative(Path::new("/tmp/out"), Path::new("/work/m")),
            PathBuf::from("../../work/m")
        );
    }

    #[test]
    fn asset_paths_are_rebased_unless_a_directory_setting_covers_them() {
        let xml = r#"<mujoco><compiler meshdir="assets"/><asset><mesh file="a.stl"/><texture file="t.png"/><mesh file="/abs.stl"/></asset></mujoco>"#;
        let mut dirs = BTreeSet::new();
        dirs.insert("meshdir");
        let out = apply(xml, rebase_edits(xml, Path::new("../m"), &dirs).unwrap());
        assert!(out.contains(r#"meshdir="../m/assets""#), "{out}");
        assert!(out.contains(r#"<mesh file="a.stl"/>"#), "{out}");
        assert!(out.contains(r#"<texture file="../m/t.png"/>"#), "{out}");
        assert!(out.contains(r#"<mesh file="/abs.stl"/>"#), "{out}");
    }
}
