//! Output formats. Each takes the same findings and source map; one file per format.

pub mod github;
pub mod json;
pub mod sarif;
pub mod text;

use crate::finding::Finding;
use crate::model::source::{Loc, SourceMap};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Human-readable, with the offending XML underlined.
    Text,
    /// Versioned JSON (docs/schemas/findings.md).
    Json,
    /// SARIF 2.1.0 for GitHub code scanning.
    Sarif,
    /// GitHub Actions workflow annotations.
    Github,
}

/// `--color` of the command line (any subcommand): 0 auto, 1 always, 2 never. Set once by the CLI.
static COLOR_CHOICE: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(0);

pub fn set_color_choice(choice: &str) {
    let v = match choice {
        "always" => 1,
        "never" => 2,
        _ => 0,
    };
    COLOR_CHOICE.store(v, std::sync::atomic::Ordering::Relaxed);
}

/// Colour for messages on stderr: `--color always/never`, else when stderr is a terminal and
/// NO_COLOR is unset.
pub fn color_on_stderr() -> bool {
    use std::io::IsTerminal;
    match COLOR_CHOICE.load(std::sync::atomic::Ordering::Relaxed) {
        1 => true,
        2 => false,
        _ => std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
    }
}

/// File path, 1-based line/column of start, and of end.
pub struct Position {
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub end_line: usize,
    pub end_column: usize,
}

pub fn position(map: &SourceMap, loc: Loc) -> Position {
    if loc.file >= map.files.len() {
        return Position { file: String::new(), line: 1, column: 1, end_line: 1, end_column: 1 };
    }
    let f = map.file(loc.file);
    let (line, column) = f.line_col(loc.start);
    let (end_line, end_column) = f.line_col(loc.end.max(loc.start));
    Position { file: f.path.display().to_string(), line, column, end_line, end_column }
}

pub fn render(format: Format, map: &SourceMap, model: &str, findings: &[Finding], color: bool) -> String {
    match format {
        Format::Text => text::render(map, findings, color),
        Format::Json => json::render(map, model, findings),
        Format::Sarif => sarif::render(map, findings),
        Format::Github => github::render(map, findings),
    }
}
