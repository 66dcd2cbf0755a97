//! `--format json`: schema `modellint/findings`, version 1 (docs/schemas/findings.md).

use serde_json::{Value, json};

use super::{NotLinted, Report, SpecInfo, position};
use crate::finding::{Finding, Severity};
use crate::model::source::SourceMap;

pub const SCHEMA_VERSION: u32 = 1;
pub const SET_SCHEMA_VERSION: u32 = 1;
/// Version of the `modellint/gap` and `modellint/fit` JSON (`gap`/`fit --format json`).
pub const RESULT_SCHEMA_VERSION: u32 = 1;

/// Adds the keys every JSON result of modellint starts with, as lint's: `schema`
/// (`modellint/<what>`), `version` (of that schema) and `tool` {name, version}.
pub fn stamp(v: &mut Value, what: &str) {
    if let Some(o) = v.as_object_mut() {
        o.insert("schema".into(), json!(format!("modellint/{what}")));
        o.insert("version".into(), json!(RESULT_SCHEMA_VERSION));
        o.insert(
            "tool".into(),
            json!({ "name": "modellint", "version": env!("CARGO_PKG_VERSION") }),
        );
    }
}

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

fn spec_value(s: &SpecInfo) -> Value {
    json!({ "path": s.path, "searched": s.searched, "skipped_rules": s.skipped_rules, "weakened_rules": s.weakened_rules })
}

/// One model: schema `modellint/findings` version 1 (what a single path always produces).
pub fn model_value(
    map: &SourceMap,
    model: &str,
    findings: &[Finding],
    spec: Option<&SpecInfo>,
) -> Value {
    let count = |s: Severity| findings.iter().filter(|f| f.severity == s).count();
    let mut v = json!({
        "schema": "modellint/findings",
        "version": SCHEMA_VERSION,
        "tool": { "name": "modellint", "version": env!("CARGO_PKG_VERSION") },
        "model": model,
        "summary": { "error": count(Severity::Error), "warning": count(Severity::Warning), "info": count(Severity::Info) },
        "findings": findings.iter().map(|f| finding_value(map, f)).collect::<Vec<_>>(),
    });
    if let Some(s) = spec {
        v["spec"] = spec_value(s);
    }
    v
}

pub fn render(
    map: &SourceMap,
    model: &str,
    findings: &[Finding],
    spec: Option<&SpecInfo>,
) -> String {
    pretty(&model_value(map, model, findings, spec))
}

fn pretty(v: &Value) -> String {
    let mut s = serde_json::to_string_pretty(v).unwrap_or_default();
    s.push('\n');
    s
}

fn not_linted(n: &NotLinted) -> Value {
    json!({ "path": n.path, "file": n.file, "line": n.line, "column": n.column, "message": n.message })
}

/// Several models: schema `modellint/findings-set` version 1, one `modellint/findings` object
/// per linted model, plus the paths skipped (not a robot model) and those that failed to load.
pub fn render_set(reports: &[Report], skipped: &[NotLinted], errors: &[NotLinted]) -> String {
    let all: Vec<&Finding> = reports.iter().flat_map(|r| r.findings.iter()).collect();
    let count = |s: Severity| all.iter().filter(|f| f.severity == s).count();
    let v = json!({
        "schema": "modellint/findings-set",
        "version": SET_SCHEMA_VERSION,
        "tool": { "name": "modellint", "version": env!("CARGO_PKG_VERSION") },
        "summary": { "models": reports.len(), "skipped": skipped.len(), "not_loaded": errors.len(),
                     "error": count(Severity::Error), "warning": count(Severity::Warning), "info": count(Severity::Info) },
        "models": reports.iter().map(|r| model_value(r.sources, &r.model, r.findings, r.spec.as_ref())).collect::<Vec<_>>(),
        "skipped": skipped.iter().map(not_linted).collect::<Vec<_>>(),
        "errors": errors.iter().map(not_linted).collect::<Vec<_>>(),
    });
    pretty(&v)
}
