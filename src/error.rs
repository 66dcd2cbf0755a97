//! Errors that stop modellint from doing its job (exit code 2): unreadable or malformed inputs.

use std::path::{Path, PathBuf};

use crate::model::source::{Loc, SourceMap};

/// A precise, located error: `file:line:col: message`.
#[derive(Debug, Clone)]
pub struct LoadError {
    pub file: PathBuf,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub message: String,
    /// Source text and byte range, when known, so the error can be rendered with a snippet.
    pub snippet: Option<(String, std::ops::Range<usize>)>,
}

impl LoadError {
    pub fn plain(path: &Path, message: String) -> Self {
        LoadError { file: path.to_path_buf(), line: None, column: None, message, snippet: None }
    }
    pub fn io(path: &Path, e: &std::io::Error) -> Self {
        let what = match e.kind() {
            std::io::ErrorKind::NotFound => "file not found".to_string(),
            std::io::ErrorKind::PermissionDenied => "permission denied".to_string(),
            _ if path.is_dir() => "is a directory, expected a file".to_string(),
            _ => format!("cannot read: {e}"),
        };
        Self::plain(path, what)
    }
    pub fn at(map: &SourceMap, loc: Loc, message: String) -> Self {
        let f = map.file(loc.file);
        let (line, col) = f.line_col(loc.start);
        LoadError {
            file: f.path.clone(),
            line: Some(line),
            column: Some(col),
            message,
            snippet: Some((f.text.clone(), loc.start..loc.end.max(loc.start))),
        }
    }
    pub fn at_line(map: &SourceMap, file: usize, line: usize, col: usize, message: String) -> Self {
        let f = map.file(file);
        LoadError {
            file: f.path.clone(),
            line: Some(line),
            column: Some(col),
            message,
            snippet: None,
        }
    }
    /// `file:line:col` (as much of it as is known).
    pub fn location(&self) -> String {
        match (self.line, self.column) {
            (Some(l), Some(c)) => format!("{}:{}:{}", self.file.display(), l, c),
            (Some(l), None) => format!("{}:{}", self.file.display(), l),
            _ => self.file.display().to_string(),
        }
    }
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.location(), self.message)
    }
}

impl std::error::Error for LoadError {}

/// Why `gap` or `fit` could not do its job (exit 2): the CLI prints it, the Python API raises it.
#[derive(Debug, Clone)]
pub enum CmdError {
    /// The model or its spec could not be loaded (`file:line:col`, rendered with a snippet).
    Load(LoadError),
    /// One line: an unreadable recording (`file:line: message`), an invalid option.
    Message(String),
    /// Already said as warnings on the way (e.g. no episode could be held out): the CLI prints
    /// nothing more; the text is what the Python API raises.
    Said(String),
}

impl std::fmt::Display for CmdError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CmdError::Load(e) => e.fmt(f),
            CmdError::Message(m) | CmdError::Said(m) => f.write_str(m),
        }
    }
}

impl From<String> for CmdError {
    fn from(m: String) -> Self {
        CmdError::Message(m)
    }
}
