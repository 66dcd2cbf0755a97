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
    /// One line per finding: `file:line:col: level rule message` (hooks, editors, grep).
    Concise,
}

/// One line per finding: `file:line:col: level rule message`.
pub fn concise(map: &SourceMap, findings: &[Finding]) -> String {
    let mut out = String::new();
    for f in findings {
        let p = position(map, f.primary);
        let msg = f.message.replace('\n', " ");
        out.push_str(&format!(
            "{}:{}:{}: {} {} {}\n",
            p.file,
            p.line,
            p.column,
            f.severity.as_str(),
            f.rule,
            msg
        ));
    }
    out
}

/// `--statistics`: findings per rule, most first (ties by rule id), each with its findings'
/// levels (a rule's findings can differ: a probe's verdict or a weaker case lowers one), then
/// the total.
pub fn statistics(findings: &[&Finding]) -> String {
    use crate::finding::Severity;
    let mut by: std::collections::BTreeMap<&str, Vec<Severity>> = std::collections::BTreeMap::new();
    for f in findings {
        by.entry(f.rule).or_default().push(f.severity);
    }
    let mut rows: Vec<(&str, Vec<Severity>)> = by.into_iter().collect();
    rows.sort_by(|a, b| b.1.len().cmp(&a.1.len()).then(a.0.cmp(b.0)));
    let mut out = String::new();
    for (rule, sevs) in &rows {
        let mut levels: Vec<Severity> = sevs.clone();
        levels.sort();
        levels.dedup();
        levels.reverse();
        let text = if levels.len() == 1 {
            levels[0].as_str().to_string()
        } else {
            let parts: Vec<String> = levels
                .iter()
                .map(|l| format!("{} {}", sevs.iter().filter(|x| *x == l).count(), l.as_str()))
                .collect();
            parts.join(", ")
        };
        out.push_str(&format!("{:>5}  {rule:<28} {text}\n", sevs.len()));
    }
    out.push_str(&format!("{:>5}  total\n", findings.len()));
    out
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

pub fn render(
    format: Format,
    map: &SourceMap,
    model: &str,
    findings: &[Finding],
    color: bool,
) -> String {
    match format {
        Format::Text => text::render(map, findings, color),
        Format::Json => json::render(map, model, findings, None),
        Format::Sarif => sarif::render(&[(map, findings)], &[]),
        Format::Github => github::render(map, findings),
        Format::Concise => concise(map, findings),
    }
}

/// Where the spec came from, for the JSON output.
#[derive(Debug, Clone, Default)]
pub struct SpecInfo {
    pub path: Option<String>,
    pub searched: Vec<String>,
    /// Rules skipped / weakened because there is no spec, or because the spec in use leaves
    /// their keys unset (`spec_use::waiting`).
    pub skipped_rules: Vec<String>,
    pub weakened_rules: Vec<String>,
}

/// One linted model.
pub struct Report<'a> {
    pub model: String,
    pub sources: &'a SourceMap,
    pub findings: &'a [Finding],
    pub spec: Option<SpecInfo>,
}

/// A path that was not linted: skipped (not a robot model) or failed to load (exit 2).
#[derive(Debug, Clone)]
pub struct NotLinted {
    pub path: String,
    /// `file:line:col` of the problem, when known.
    pub file: String,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub message: String,
}

impl NotLinted {
    pub fn from_error(path: &std::path::Path, e: &crate::error::LoadError) -> Self {
        NotLinted {
            path: path.display().to_string(),
            file: e.file.display().to_string(),
            line: e.line,
            column: e.column,
            message: e.message.clone(),
        }
    }
    pub fn skipped(path: &std::path::Path, why: String) -> Self {
        NotLinted {
            path: path.display().to_string(),
            file: path.display().to_string(),
            line: None,
            column: None,
            message: why,
        }
    }
}

/// Several models in one call (`modellint a.xml b.xml`): every format carries all of them.
/// Text and GitHub concatenate; JSON is a `modellint/findings-set` of per-model
/// `modellint/findings` objects (docs/schemas/findings.md); SARIF is one run with every result.
pub fn render_many(
    format: Format,
    reports: &[Report],
    skipped: &[NotLinted],
    errors: &[NotLinted],
    color: bool,
) -> String {
    match format {
        Format::Text => {
            let mut out = String::new();
            for r in reports {
                out.push_str(&text::render_titled(r.sources, r.findings, color, Some(&r.model)));
            }
            let all: Vec<&Finding> = reports.iter().flat_map(|r| r.findings.iter()).collect();
            let count =
                |s: crate::finding::Severity| all.iter().filter(|f| f.severity == s).count();
            out.push_str(&format!(
                "modellint: {} model(s) linted, {} skipped, {} could not be loaded: {} error(s), {} warning(s), {} info\n",
                reports.len(),
                skipped.len(),
                errors.len(),
                count(crate::finding::Severity::Error),
                count(crate::finding::Severity::Warning),
                count(crate::finding::Severity::Info)
            ));
            out
        }
        Format::Json => json::render_set(reports, skipped, errors),
        Format::Sarif => {
            let runs: Vec<(&SourceMap, &[Finding])> =
                reports.iter().map(|r| (r.sources, r.findings)).collect();
            sarif::render(&runs, errors)
        }
        Format::Github => {
            let mut out = String::new();
            for r in reports {
                out.push_str(&github::render(r.sources, r.findings));
            }
            out.push_str(&github::render_errors(errors));
            out
        }
        Format::Concise => {
            let mut out = String::new();
            for r in reports {
                out.push_str(&concise(r.sources, r.findings));
            }
            for e in errors {
                let at = match (e.line, e.column) {
                    (Some(l), Some(c)) => format!("{}:{l}:{c}", e.file),
                    (Some(l), None) => format!("{}:{l}:1", e.file),
                    _ => format!("{}:1:1", e.file),
                };
                out.push_str(&format!("{at}: error load {}\n", e.message.replace('\n', " ")));
            }
            out
        }
    }
}

#[cfg(test)]
mod statistics_tests {
    use super::*;
    use crate::finding::Severity;
    use crate::model::source::Loc;

    /// A rule whose findings carry different levels is counted per level, not shown at its
    /// strongest: three errors and one info are "3 error, 1 info".
    #[test]
    fn statistics_count_each_level_of_a_rule() {
        let loc = Loc { file: 0, start: 0, end: 0 };
        let f = |rule, s| Finding::new(rule, s, "m", loc);
        let all = [
            f("a-rule", Severity::Error),
            f("a-rule", Severity::Info),
            f("a-rule", Severity::Error),
            f("a-rule", Severity::Error),
            f("b-rule", Severity::Warning),
        ];
        let refs: Vec<&Finding> = all.iter().collect();
        let s = statistics(&refs);
        let rows: Vec<&str> = s.lines().collect();
        assert_eq!(
            rows[0].split_whitespace().collect::<Vec<_>>(),
            ["4", "a-rule", "3", "error,", "1", "info"],
            "{s}"
        );
        assert_eq!(
            rows[1].split_whitespace().collect::<Vec<_>>(),
            ["1", "b-rule", "warning"],
            "{s}"
        );
        assert_eq!(rows[2].split_whitespace().collect::<Vec<_>>(), ["5", "total"], "{s}");
    }
}
