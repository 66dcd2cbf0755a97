//! `--format json`: schema `modellint/findings`, version 1 (docs/schemas/findings.md).

use serde_json::{Value, json};

use super::position;
use crate::finding::{Finding, Severity};
use crate::model::source::SourceMap;

pub const SCHEMA_VERSION: u32 = 1;

pub fn finding_value(map: &SourceMap, f: &Finding) -> Value {
    let p = position(map, f.primary);
    let labels: Vec<Value> = f
        .labels
        .iter()
        .map(|l| {
            let lp = position(map, l.loc);
            json!({ "file": lp.file, "line": lp.line, "column": lp.column, "message": l.text })
        })
        .collect();
    json!({
        "rule": f.rule,
        "severity": f.severity.as_str(),
        "message": f.message,
        "note": f.note,
        "help": f.help,
        "file": p.file,
        "line": p.line,
        "column": p.column,
        "end_line": p.end_line,
        "end_column": p.end_column,
        "element": f.element,
        "measured": f.measured,
        "expected": f.expected,
        "data": f.data,
        "labels": labels,
        "probe": f.probe,
    })
}

pub fn render(map: &SourceMap, model: &str, findings: &[Finding]) -> String {
    let count = |s: Severity| findings.iter().filter(|f| f.severity == s).count();
    let v = json!({
        "schema": "modellint/findings",
        "version": SCHEMA_VERSION,
        "tool": { "name": "modellint", "version": env!("CARGO_PKG_VERSION") },
        "model": model,
        "summary": { "error": count(Severity::Error), "warning": count(Severity::Warning), "info": count(Severity::Info) },
        "findings": findings.iter().map(|f| finding_value(map, f)).collect::<Vec<_>>(),
    });
    let mut s = serde_json::to_string_pretty(&v).unwrap_or_default();
    s.push('\n');
    s
}
