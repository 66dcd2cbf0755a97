//! `--format github`: workflow commands that GitHub Actions shows as annotations.

use super::position;
use crate::finding::{Finding, Severity};
use crate::model::source::SourceMap;

fn escape_data(s: &str) -> String {
    s.replace('%', "%25").replace('\r', "%0D").replace('\n', "%0A")
}

fn escape_prop(s: &str) -> String {
    escape_data(s).replace(':', "%3A").replace(',', "%2C")
}

pub fn render(map: &SourceMap, findings: &[Finding]) -> String {
    let mut out = String::new();
    for f in findings {
        let p = position(map, f.primary);
        let level = match f.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Info => "notice",
        };
        let mut msg = f.message.clone();
        if let Some(h) = &f.help {
            msg.push_str("\nhelp: ");
            msg.push_str(h);
        }
        out.push_str(&format!(
            "::{level} file={},line={},col={},endLine={},endColumn={},title={}::{}\n",
            escape_prop(&p.file),
            p.line,
            p.column,
            p.end_line,
            p.end_column,
            escape_prop(&format!("modellint {}", f.rule)),
            escape_data(&msg)
        ));
    }
    out
}

/// Models that could not be loaded (exit 2), as error annotations at the problem's location.
pub fn render_errors(errors: &[super::NotLinted]) -> String {
    let mut out = String::new();
    for e in errors {
        out.push_str(&format!(
            "::error file={},line={},col={},title={}::{}\n",
            escape_prop(&e.file),
            e.line.unwrap_or(1),
            e.column.unwrap_or(1),
            escape_prop("modellint could not load the model"),
            escape_data(&e.message)
        ));
    }
    out
}
