//! Where MuJoCo's compile errors point: the file, line and element a message names, so that a
//! load error says where to look even when MuJoCo reports line 0 or no line at all.

use super::Format;
use super::source::{Loc, SourceMap};
use crate::error::LoadError;

/// "Error opening file 'X'" (a missing file) or "no decoder found for mesh file 'X'" (a mesh
/// format MuJoCo cannot read, e.g. a URDF's COLLADA `.dae`): the attribute that names X (by its
/// file name), at its file:line.
pub(super) fn missing_file_location(
    map: &SourceMap,
    first_file: usize,
    msg: &str,
) -> Option<LoadError> {
    const CASES: [(&str, &str); 2] = [
        ("Error opening file '", "file not found"),
        (
            "no decoder found for mesh file '",
            "MuJoCo cannot read this mesh format: it reads STL, OBJ and MSH meshes; convert the file",
        ),
    ];
    let (i, why) =
        CASES.iter().find_map(|(pat, why)| msg.find(pat).map(|k| (k + pat.len(), *why)))?;
    let name = msg[i..].split('\'').next()?;
    let base = name.rsplit(['/', '\\']).next().filter(|b| !b.is_empty())?;
    for f in first_file..map.files.len() {
        let text = &map.file(f).text;
        for pat in ["filename=\"", "file=\""] {
            let mut from = 0;
            while let Some(k) = text[from..].find(pat) {
                let vs = from + k + pat.len();
                let ve = text[vs..].find('"').map_or(text.len(), |e| vs + e);
                if text[vs..ve].ends_with(base) {
                    return Some(LoadError::at(
                        map,
                        Loc { file: f, start: vs, end: ve },
                        format!("{msg} ({why})"),
                    ));
                }
                from = ve;
            }
        }
    }
    None
}

/// MuJoCo reports XML problems as "... line N, column M" or with a file name; map them back.
pub(super) fn mujoco_error_location(
    map: &SourceMap,
    first_file: usize,
    msg: &str,
) -> Option<LoadError> {
    let lower = msg.to_lowercase();
    let li = lower.find("line ")?;
    let rest = &msg[li + 5..];
    let line: usize = rest.split(|c: char| !c.is_ascii_digit()).next()?.parse().ok()?;
    if line == 0 {
        // MuJoCo's "line 0": the element has no recorded line; `mujoco_element_location` finds it.
        return None;
    }
    let col = lower
        .find("column ")
        .and_then(|ci| msg[ci + 7..].split(|c: char| !c.is_ascii_digit()).next()?.parse().ok());
    // Prefer the file MuJoCo names, else the top-level model.
    let file = (first_file..map.files.len())
        .find(|&i| {
            map.file(i).path.file_name().and_then(|f| f.to_str()).is_some_and(|f| msg.contains(f))
        })
        .unwrap_or(first_file);
    // "Element name 'X', id N, line L" (a compile error, no column): the column of X's
    // `name` value on that line.
    let col = col.or_else(|| {
        let i = msg.find("Element name '")? + "Element name '".len();
        let name = &msg[i..i + msg[i..].find('\'')?];
        let text = map.file(file).text.lines().nth(line - 1)?;
        ['"', '\''].iter().find_map(|q| text.find(&format!("name={q}{name}{q}")).map(|k| k + 7))
    });
    Some(LoadError::at_line(map, file, line, col.unwrap_or(1), msg.to_string()))
}

/// MuJoCo's "Element name 'X', id N" with no usable line (its message cut at the error buffer's
/// end, or "line 0"): the element of the kind the message names (body, geom, joint, mesh, site)
/// whose `name` is X, else any element named X; for an unnamed body of a one-file MJCF model
/// (no include, replicate or attach), the N-th `<body>` in document order, which is MuJoCo's
/// body id N (the world is 0).
pub(super) fn mujoco_element_location(
    map: &SourceMap,
    first_file: usize,
    format: Format,
    msg: &str,
) -> Option<LoadError> {
    let i = msg.find("Element name '")? + "Element name '".len();
    let name = &msg[i..i + msg[i..].find('\'')?];
    let after = &msg[i + name.len()..];
    let id: Option<usize> = after
        .find("id ")
        .and_then(|k| after[k + 3..].split(|c: char| !c.is_ascii_digit()).next()?.parse().ok());
    let lower = msg.to_lowercase();
    let kinds: &[&str] = if lower.contains("bod") {
        &["body", "link"]
    } else if lower.contains("geom") {
        &["geom", "collision"]
    } else if lower.contains("joint") {
        &["joint"]
    } else if lower.contains("mesh") {
        &["mesh"]
    } else if lower.contains("site") {
        &["site"]
    } else {
        &[]
    };
    let tag_before = |text: &str, at: usize| -> String {
        let open = text[..at].rfind('<').map_or(0, |o| o + 1);
        text[open..at].split(|c: char| c.is_whitespace()).next().unwrap_or("").to_string()
    };
    if !name.is_empty() {
        let mut any = None;
        for f in first_file..map.files.len() {
            let text = &map.file(f).text;
            for q in ['"', '\''] {
                let pat = format!("name={q}{name}{q}");
                let mut from = 0;
                while let Some(k) = text[from..].find(&pat) {
                    let at = from + k;
                    from = at + pat.len();
                    if !text[..at].ends_with(char::is_whitespace) {
                        continue;
                    }
                    let loc = Loc { file: f, start: at + 6, end: at + 6 + name.len() };
                    if kinds.contains(&tag_before(text, at).as_str()) {
                        return Some(LoadError::at(map, loc, msg.to_string()));
                    }
                    any.get_or_insert(loc);
                }
            }
        }
        return any.map(|loc| LoadError::at(map, loc, msg.to_string()));
    }
    let text = &map.file(first_file).text;
    let one_file = map.files.len() == first_file + 1
        && !["<include", "<replicate", "<attach"].iter().any(|t| text.contains(t));
    if format != Format::Mjcf || !one_file || kinds.first() != Some(&"body") {
        return None;
    }
    let n = id.filter(|&n| n >= 1)?;
    let starts = text.match_indices("<body").filter(|(k, t)| {
        text[k + t.len()..].starts_with(|c: char| c.is_whitespace() || c == '>' || c == '/')
    });
    let (k, _) = starts.clone().nth(n - 1)?;
    Some(LoadError::at(map, Loc { file: first_file, start: k + 1, end: k + 5 }, msg.to_string()))
}

/// MuJoCo's value errors ("bad format in attribute 'X'", "attribute 'X' does not have enough
/// data", "… has too much data", then "Element 'T', line L"): the attribute X of the `<T>` on
/// line L (MuJoCo gives the element's line only), or, with no usable line, the first `<T>` whose
/// X does not read as numbers. The message gains the written value.
pub(super) fn bad_value_location(
    map: &SourceMap,
    first_file: usize,
    msg: &str,
) -> Option<LoadError> {
    if !["bad format in attribute", "does not have enough data", "has too much data"]
        .iter()
        .any(|p| msg.contains(p))
    {
        return None;
    }
    let quoted = |after: &str| -> Option<&str> {
        let i = msg.find(after)? + after.len();
        Some(&msg[i..i + msg[i..].find('\'')?])
    };
    let (attr, tag) = (quoted("attribute '")?, quoted("Element '")?);
    let line: Option<usize> = msg
        .find("', line ")
        .and_then(|k| msg[k + 8..].split(|c: char| !c.is_ascii_digit()).next()?.parse().ok())
        .filter(|&l| l > 0);
    let named = (first_file..map.files.len()).find(|&i| {
        map.file(i).path.file_name().and_then(|f| f.to_str()).is_some_and(|f| msg.contains(f))
    });
    let mut unread = None;
    for f in first_file..map.files.len() {
        let file = map.file(f);
        let text = &file.text;
        for q in ['"', '\''] {
            let pat = format!("{attr}={q}");
            let mut from = 0;
            while let Some(k) = text[from..].find(&pat) {
                let at = from + k;
                from = at + pat.len();
                let vs = from;
                let ve = text[vs..].find(q).map_or(text.len(), |e| vs + e);
                if !text[..at].ends_with(char::is_whitespace) {
                    continue;
                }
                let open = text[..at].rfind('<').unwrap_or(0);
                let own = text[open + 1..]
                    .split(|c: char| c.is_whitespace() || c == '>' || c == '/')
                    .next()
                    .unwrap_or("");
                if own != tag || text[open..at].contains('>') {
                    continue;
                }
                let loc = Loc { file: f, start: vs, end: ve };
                let value = &text[vs..ve];
                let found = || {
                    let tail = format!(" (the <{tag}> attribute `{attr}` = \"{value}\")");
                    Some(LoadError::at(map, loc, format!("{}{tail}", msg.trim_end())))
                };
                let on_line = line.is_some_and(|l| {
                    named.is_none_or(|n| n == f)
                        && file.line_col(open).0 <= l
                        && file.line_col(at).0 >= l
                });
                if on_line {
                    return found();
                }
                let reads = value.split_whitespace().all(|t| super::checks::c_number(t).is_some());
                if line.is_none() && !reads && unread.is_none() {
                    unread = found();
                }
            }
        }
    }
    unread
}

/// MuJoCo errors about one attribute that MuJoCo does not locate (an unnamed element in an
/// included file: "line 0"): message fragment, element tag, attribute.
const ATTRIBUTE_ERRORS: &[(&str, &str, &str)] = &[
    // `shellinertia` on a mesh geom: MuJoCo 3.2+ takes a mesh's inertia from the mesh asset
    // (`<mesh inertia="shell">`) and rejects the geom attribute.
    ("inertia should be specified in the mesh asset", "geom", "shellinertia"),
];

/// MuJoCo's schema error for an attribute it does not know ("Schema violation: unrecognized
/// attribute: 'apirate'\nElement 'option', line 0" — an element of an included file): the
/// element's tag and the attribute.
fn unrecognized_attribute(msg: &str) -> Option<(&str, &str)> {
    let quoted = |after: &str| -> Option<&str> {
        let i = msg.find(after)? + after.len();
        Some(&msg[i..i + msg[i..].find('\'')?])
    };
    Some((quoted("Element '")?, quoted("unrecognized attribute: '")?))
}

/// For an error of `ATTRIBUTE_ERRORS`, or an attribute MuJoCo's schema does not know: the first
/// element of that tag that writes the attribute (preferring one that names a `mesh`), with
/// how many elements write it.
pub(super) fn attribute_error_location(
    map: &SourceMap,
    first_file: usize,
    msg: &str,
) -> Option<LoadError> {
    let (tag, attr) = match ATTRIBUTE_ERRORS.iter().find(|(m, _, _)| msg.contains(m)) {
        Some(&(_, tag, attr)) => (tag, attr),
        None => unrecognized_attribute(msg)?,
    };
    let pat = format!("{attr}=");
    let (mut first, mut with_mesh, mut count) = (None, None, 0usize);
    for f in first_file..map.files.len() {
        let text = &map.file(f).text;
        let mut from = 0;
        while let Some(k) = text[from..].find(&pat) {
            let at = from + k;
            from = at + pat.len();
            if !text[..at].ends_with(char::is_whitespace) {
                continue;
            }
            let open = text[..at].rfind('<').unwrap_or(0);
            let name_end = text[open + 1..]
                .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
                .map_or(text.len(), |e| open + 1 + e);
            if &text[open + 1..name_end] != tag {
                continue;
            }
            count += 1;
            let close = text[at..].find('>').map_or(text.len(), |e| at + e);
            let loc = Loc { file: f, start: at, end: at + attr.len() };
            first.get_or_insert(loc);
            if with_mesh.is_none() && text[open..close].contains(" mesh=") {
                with_mesh = Some(loc);
            }
        }
    }
    let loc = with_mesh.or(first)?;
    let more =
        if count > 1 { format!("; {count} <{tag}> elements write it") } else { String::new() };
    Some(LoadError::at(map, loc, format!("{msg} (the <{tag}> attribute `{attr}`{more})")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// MuJoCo's "line 0" and its cut messages point at the element they name, not at 0:1.
    #[test]
    fn an_unknown_attribute_is_read_from_the_schema_message() {
        let msg = "XML Error: Schema violation: unrecognized attribute: 'apirate'\nElement 'option', line 0\n";
        assert_eq!(unrecognized_attribute(msg), Some(("option", "apirate")));
        assert_eq!(unrecognized_attribute("XML Error: unknown element 'foo'"), None);
    }

    #[test]
    fn line_zero_names_the_element() {
        let text = std::fs::read_to_string("fixtures/broken/massless_unnamed_body.xml").unwrap();
        let body_line = text.lines().position(|l| l.contains("<body pos")).unwrap() + 1;
        let mut map = SourceMap::default();
        let f = map.add(PathBuf::from("m.xml"), text);
        let unnamed = "Error: mass and inertia of moving bodies must be larger than mjMINVAL\nElement name '', id 2, line 0";
        assert!(mujoco_error_location(&map, f, unnamed).is_none());
        let e = mujoco_element_location(&map, f, Format::Mjcf, unnamed).expect("located");
        assert_eq!(e.line, Some(body_line), "{}", e.location());
        let named = "Error: mass and inertia of moving bodies must be larger than mjMINVAL\nElement name 'upper', id 1,";
        let e = mujoco_element_location(&map, f, Format::Mjcf, named).expect("located");
        assert_eq!(e.line, Some(4), "{}", e.location());
        // No such body, or a kind it cannot count in a URDF: no location is guessed.
        let far = "Error: mass and inertia of moving bodies\nElement name '', id 9, line 0";
        assert!(mujoco_element_location(&map, f, Format::Mjcf, far).is_none());
        assert!(mujoco_element_location(&map, f, Format::Urdf, unnamed).is_none());
    }
}
