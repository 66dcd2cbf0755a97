//! Source text of every file a model was read from, and an owned XML tree with exact spans.
//!
//! roxmltree gives byte ranges for elements and attribute values; this module copies them into
//! an owned tree (`XNode`) with `<include>` expanded in place, so that every value a rule reads
//! can be traced back to the file, line and column that set it.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::error::LoadError;

/// One file read while loading a model (the model itself, included files, spec, config).
#[derive(Debug, Clone)]
pub struct SourceFile {
    pub path: PathBuf,
    pub text: String,
    line_starts: Vec<usize>,
}

impl SourceFile {
    pub fn new(path: PathBuf, text: String) -> Self {
        let mut line_starts = vec![0];
        for (i, b) in text.bytes().enumerate() {
            if b == b'\n' {
                line_starts.push(i + 1);
            }
        }
        SourceFile { path, text, line_starts }
    }

    /// 1-based (line, column) of a byte offset; the column counts characters.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let line = match self.line_starts.binary_search(&offset) {
            Ok(i) => i,
            Err(i) => i - 1,
        };
        let start = self.line_starts[line];
        let col = self.text.get(start..offset).map(|s| s.chars().count()).unwrap_or(offset - start);
        (line + 1, col + 1)
    }
}

/// All source files of one run, addressed by index.
#[derive(Debug, Clone, Default)]
pub struct SourceMap {
    pub files: Vec<SourceFile>,
    /// Content after a file's root element (MuJoCo ignores it; modellint reports it).
    pub trailing: Vec<Loc>,
    /// Start tags whose prefix no `xmlns` declares (MuJoCo skips them; modellint reports them
    /// and reads the file as MuJoCo does, `crate::model::xml_prefix`): name loc, name, prefix.
    pub undeclared: Vec<UndeclaredName>,
}

/// A start tag with an undeclared prefix: the name's location, the name, the prefix.
pub type UndeclaredName = (Loc, String, String);

impl SourceMap {
    pub fn add(&mut self, path: PathBuf, text: String) -> usize {
        self.files.push(SourceFile::new(path, text));
        self.files.len() - 1
    }
    pub fn file(&self, id: usize) -> &SourceFile {
        &self.files[id]
    }
}

/// A byte range in one source file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Loc {
    pub file: usize,
    pub start: usize,
    pub end: usize,
}

#[derive(Debug, Clone)]
pub struct XAttr {
    pub name: String,
    pub value: String,
    /// Span of the attribute value (without quotes).
    pub loc: Loc,
}

/// An XML comment directly before an element (used for inline suppressions).
#[derive(Debug, Clone)]
pub struct XComment {
    pub text: String,
    pub loc: Loc,
}

/// Owned element with spans; `<include>` elements are replaced by the included file's children.
#[derive(Debug, Clone)]
pub struct XNode {
    pub tag: String,
    pub attrs: Vec<XAttr>,
    pub children: Vec<XNode>,
    /// Span of the element's tag name in its start tag (the tightest span for the element).
    pub loc: Loc,
    /// Span of the whole element.
    pub full: Loc,
    /// Comments between the previous sibling element and this one.
    pub comments: Vec<XComment>,
}

impl XNode {
    pub fn attr(&self, name: &str) -> Option<&XAttr> {
        self.attrs.iter().find(|a| a.name == name)
    }
    pub fn get(&self, name: &str) -> Option<&str> {
        self.attr(name).map(|a| a.value.as_str())
    }
    pub fn name(&self) -> Option<&str> {
        self.get("name")
    }
    pub fn children_tagged<'a>(&'a self, tag: &'a str) -> impl Iterator<Item = &'a XNode> + 'a {
        self.children.iter().filter(move |c| c.tag == tag)
    }
    /// Depth-first pre-order walk.
    pub fn walk<'a>(&'a self, f: &mut dyn FnMut(&'a XNode)) {
        f(self);
        for c in &self.children {
            c.walk(f);
        }
    }
}

/// Reads a file into the source map, with a clear error on failure.
pub fn read_source(map: &mut SourceMap, path: &Path) -> Result<usize, LoadError> {
    let bytes = std::fs::read(path).map_err(|e| LoadError::io(path, &e))?;
    let located = |line: usize, column: usize, message: String| LoadError {
        line: Some(line),
        column: Some(column),
        ..LoadError::plain(path, message)
    };
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        // Line and column (in characters) of the first invalid byte.
        let valid = String::from_utf8_lossy(&e.as_bytes()[..at]).into_owned();
        let line = valid.matches('\n').count() + 1;
        let column = valid.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        located(line, column, format!("not valid UTF-8 (byte {at})"))
    })?;
    if text.trim().is_empty() {
        return Err(located(1, 1, "file is empty".to_string()));
    }
    Ok(map.add(path.to_path_buf(), text))
}

/// Parses an XML file (and, for MJCF, the files it includes) into an owned tree.
pub fn parse_xml_tree(
    map: &mut SourceMap,
    path: &Path,
    expand_includes: bool,
) -> Result<XNode, LoadError> {
    let mut stack = BTreeSet::new();
    parse_file(map, path, expand_includes, &mut stack, None)
}

fn parse_file(
    map: &mut SourceMap,
    path: &Path,
    expand_includes: bool,
    stack: &mut BTreeSet<PathBuf>,
    included_from: Option<Loc>,
) -> Result<XNode, LoadError> {
    let canon = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let file_id = match read_source(map, path) {
        Ok(id) => id,
        Err(e) => {
            return Err(match included_from {
                Some(loc) => LoadError::at(
                    map,
                    loc,
                    format!("included file {}: {}", path.display(), e.message),
                ),
                None => e,
            });
        }
    };
    if !stack.insert(canon.clone()) {
        let loc = included_from.unwrap_or(Loc { file: file_id, start: 0, end: 0 });
        return Err(LoadError::at(
            map,
            loc,
            format!("include cycle: {} includes itself (directly or indirectly)", path.display()),
        ));
    }
    let mut text = map.file(file_id).text.clone();
    if let Some((copy, tags)) = crate::model::xml_prefix::renamed_undeclared(&text) {
        // Same length as the file: every range of the copy is a range of the file.
        text = copy;
        for t in tags {
            map.undeclared.push((
                Loc { file: file_id, start: t.start, end: t.end },
                t.name,
                t.prefix,
            ));
        }
    }
    let opts = || roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    let doc = match roxmltree::Document::parse_with_options(&text, opts()) {
        Ok(doc) => doc,
        Err(e) => match root_end(&text) {
            // MuJoCo (tinyxml2) stops reading after the root element: accept what precedes the
            // junk, and remember where the junk is.
            Some(end) => {
                let junk_start = end + text[end..].len() - text[end..].trim_start().len();
                map.trailing.push(Loc {
                    file: file_id,
                    start: junk_start,
                    end: text.trim_end().len().max(junk_start),
                });
                roxmltree::Document::parse_with_options(&text[..end], opts()).map_err(|e| {
                    let pos = e.pos();
                    LoadError::at_line(
                        map,
                        file_id,
                        pos.row as usize,
                        pos.col as usize,
                        format!("malformed XML: {e}"),
                    )
                })?
            }
            None => {
                let pos = e.pos();
                // A file that does not even start as XML is not a model at all (a spec, a log).
                let msg = if text.trim_start().starts_with('<') || text.trim().is_empty() {
                    format!("malformed XML: {e}")
                } else {
                    let ext = path.extension().and_then(|x| x.to_str()).unwrap_or("");
                    let hint = match ext {
                        "toml" => {
                            "; a .toml beside a model is its hardware spec (--spec FILE.toml)"
                        }
                        "csv" | "json" | "npz" | "parquet" | "mcap" | "pt" => {
                            "; recordings go to `modellint gap MODEL LOGS` or `modellint fit MODEL LOGS`"
                        }
                        _ => "",
                    };
                    format!("not XML, so not a robot model (MJCF .xml or URDF .urdf){hint}")
                };
                return Err(LoadError::at_line(
                    map,
                    file_id,
                    pos.row as usize,
                    pos.col as usize,
                    msg,
                ));
            }
        },
    };
    let root = doc.root_element();
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let node = convert(map, file_id, root, &base_dir, expand_includes, stack)?;
    stack.remove(&canon);
    Ok(node)
}

/// Name of a file's root element, read without a full parse (first start tag that is not a
/// declaration, comment or processing instruction). `None` when the file cannot be read or has
/// no element.
pub fn root_tag(path: &Path) -> Option<String> {
    let text = std::fs::read(path).ok()?;
    let text = String::from_utf8_lossy(&text);
    root_name(&text)
}

fn root_name(text: &str) -> Option<String> {
    let mut i = 0;
    loop {
        let lt = i + text[i..].find('<')?;
        let rest = &text[lt + 1..];
        if let Some(comment) = rest.strip_prefix("!--") {
            i = lt + 4 + comment.find("-->")? + 3;
            continue;
        }
        if rest.starts_with('?') || rest.starts_with('!') {
            i = lt + 1;
            continue;
        }
        let n: String =
            rest.chars().take_while(|c| !c.is_whitespace() && *c != '>' && *c != '/').collect();
        return (!n.is_empty()).then_some(n);
    }
}

/// Byte offset just after the root element's closing tag, when the file is well-formed up to
/// there and only trailing content (e.g. a second `</mujoco>`) makes it malformed.
fn root_end(text: &str) -> Option<usize> {
    let opts = || roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    let name = root_name(text)?;
    let close = format!("</{name}");
    let mut from = 0;
    while let Some(p) = text[from..].find(&close) {
        let after = from + p + close.len();
        let gt = after + text[after..].find('>')?;
        if !text[after..gt].trim().is_empty() {
            from = after;
            continue;
        }
        let end = gt + 1;
        if roxmltree::Document::parse_with_options(&text[..end], opts()).is_ok() {
            return (!text[end..].trim().is_empty()).then_some(end);
        }
        from = end;
    }
    None
}

fn convert(
    map: &mut SourceMap,
    file: usize,
    n: roxmltree::Node,
    base_dir: &Path,
    expand_includes: bool,
    stack: &mut BTreeSet<PathBuf>,
) -> Result<XNode, LoadError> {
    let range = n.range();
    let tag = n.tag_name().name().to_string();
    // The tag name sits right after '<'.
    let loc =
        Loc { file, start: range.start + 1, end: (range.start + 1 + tag.len()).min(range.end) };
    let attrs = n
        .attributes()
        .map(|a| {
            let r = a.range_value();
            XAttr {
                name: a.name().to_string(),
                value: a.value().to_string(),
                loc: Loc { file, start: r.start, end: r.end },
            }
        })
        .collect();
    let mut children = Vec::new();
    let mut pending_comments = Vec::new();
    for c in n.children() {
        if c.is_comment() {
            let r = c.range();
            pending_comments.push(XComment {
                text: c.text().unwrap_or("").to_string(),
                loc: Loc { file, start: r.start, end: r.end },
            });
            continue;
        }
        if !c.is_element() {
            continue;
        }
        if expand_includes && c.tag_name().name() == "include" {
            let Some(attr) = c.attributes().find(|a| a.name() == "file") else {
                let r = c.range();
                return Err(LoadError::at(
                    map,
                    Loc { file, start: r.start, end: r.end },
                    "<include> without a file attribute".into(),
                ));
            };
            let r = attr.range_value();
            let inc_loc = Loc { file, start: r.start, end: r.end };
            let inc_path = base_dir.join(attr.value());
            let inc = parse_file(map, &inc_path, true, stack, Some(inc_loc))?;
            // MuJoCo includes the children of the included file's root element.
            let mut first = true;
            for mut ic in inc.children {
                if first {
                    let mut cm = std::mem::take(&mut pending_comments);
                    cm.append(&mut ic.comments);
                    ic.comments = cm;
                    first = false;
                }
                children.push(ic);
            }
            continue;
        }
        let mut child = convert(map, file, c, base_dir, expand_includes, stack)?;
        child.comments = std::mem::take(&mut pending_comments);
        children.push(child);
    }
    Ok(XNode {
        tag,
        attrs,
        children,
        loc,
        full: Loc { file, start: range.start, end: range.end },
        comments: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_is_one_based_and_counts_chars() {
        let f = SourceFile::new("x".into(), "ab\ncdé\nf".into());
        assert_eq!(f.line_col(0), (1, 1));
        assert_eq!(f.line_col(3), (2, 1));
        assert_eq!(f.line_col(7), (2, 4));
        assert_eq!(f.line_col(8), (3, 1));
    }

    #[test]
    fn root_name_skips_declarations_and_comments() {
        assert_eq!(
            root_name("<?xml version=\"1.0\"?>\n<!-- a <b> -->\n<package format=\"3\">").as_deref(),
            Some("package")
        );
        assert_eq!(root_name("<!DOCTYPE x>\n<mujoco/>").as_deref(), Some("mujoco"));
        assert_eq!(root_name("no element"), None);
    }

    #[test]
    fn root_end_finds_the_end_before_trailing_junk() {
        let t = "<mujoco><worldbody/></mujoco>\n</mujoco>\n";
        assert_eq!(root_end(t), Some(29));
        assert_eq!(root_end("<mujoco><a></mujoco>"), None);
        assert_eq!(root_end("<mujoco></mujoco>\n"), None);
    }

    #[test]
    fn include_cycle_is_an_error_not_a_hang() {
        let dir = std::env::temp_dir().join(format!("modellint-cycle-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("a.xml"), "<mujoco><include file=\"b.xml\"/></mujoco>").unwrap();
        std::fs::write(dir.join("b.xml"), "<mujoco><include file=\"a.xml\"/></mujoco>").unwrap();
        let mut map = SourceMap::default();
        let err = parse_xml_tree(&mut map, &dir.join("a.xml"), true).unwrap_err();
        assert!(err.message.contains("include cycle"), "{}", err.message);
        assert_eq!(err.line, Some(1));
    }
}
