//! `--format sarif`: SARIF 2.1.0, as GitHub code scanning accepts it.

use serde_json::{Value, json};

use super::position;
use crate::finding::{Finding, Severity};
use crate::model::source::SourceMap;
use crate::rules::all_meta;

fn level(s: Severity) -> &'static str {
    match s {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Info => "note",
    }
}

fn first_paragraph(docs: &str) -> String {
    docs.lines()
        .map(|l| l.strip_prefix(' ').unwrap_or(l))
        .skip_while(|l| l.starts_with('#') || l.trim().is_empty())
        .take_while(|l| !l.trim().is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// One SARIF run holding the results of every model; models that could not be loaded become
/// tool execution notifications (and `executionSuccessful: false`).
pub fn render(models: &[(&SourceMap, &[Finding])], errors: &[super::NotLinted]) -> String {
    let metas = all_meta();
    let rules: Vec<Value> = metas
        .iter()
        .map(|m| {
            json!({
                "id": m.id,
                "name": m.id,
                "shortDescription": { "text": first_paragraph(m.docs) },
                "fullDescription": { "text": first_paragraph(m.docs) },
                "help": { "text": m.docs.lines().map(|l| l.strip_prefix(' ').unwrap_or(l)).collect::<Vec<_>>().join("\n"), "markdown": crate::rules::doc_page(m) },
                "defaultConfiguration": { "level": level(m.default_level) },
                "properties": { "tags": [m.group] },
            })
        })
        .collect();
    let results: Vec<Value> = models
        .iter()
        .flat_map(|(map, findings)| findings.iter().map(move |f| (*map, f)))
        .map(|(map, f)| {
            let p = position(map, f.primary);
            let idx = metas.iter().position(|m| m.id == f.rule).unwrap_or(0);
            let mut text = f.message.clone();
            if let Some(n) = &f.note {
                text.push_str(&format!(" Why: {n}"));
            }
            if let Some(h) = &f.help {
                text.push_str(&format!(" Fix: {h}"));
            }
            let related: Vec<Value> = f
                .labels
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    let lp = position(map, l.loc);
                    json!({ "id": i, "message": { "text": l.text }, "physicalLocation": {
                        "artifactLocation": { "uri": uri(&lp.file) },
                        "region": { "startLine": lp.line, "startColumn": lp.column } } })
                })
                .collect();
            json!({
                "ruleId": f.rule,
                "ruleIndex": idx,
                "level": level(f.severity),
                "message": { "text": text },
                "locations": [{ "physicalLocation": {
                    "artifactLocation": { "uri": uri(&p.file) },
                    "region": { "startLine": p.line, "startColumn": p.column, "endLine": p.end_line, "endColumn": p.end_column.max(p.column) }
                }, "logicalLocations": [{ "name": f.element, "kind": "element" }] }],
                "relatedLocations": related,
                "properties": { "element": f.element, "measured": f.measured, "expected": f.expected, "probe": f.probe },
            })
        })
        .collect();
    let v = json!({
        "$schema": "https://json.schemastore.org/sarif-2.1.0.json",
        "version": "2.1.0",
        "runs": [{
            "tool": { "driver": {
                "name": "modellint",
                "version": env!("CARGO_PKG_VERSION"),
                "informationUri": "https://github.com/modellint/modellint",
                "rules": rules,
            } },
            "results": results,
            "invocations": [{
                "executionSuccessful": errors.is_empty(),
                "toolExecutionNotifications": errors.iter().map(|e| {
                    let mut n = json!({ "level": "error", "message": { "text": format!("could not load {}: {}", e.path, e.message) } });
                    if let Some(line) = e.line {
                        n["locations"] = json!([{ "physicalLocation": { "artifactLocation": { "uri": uri(&e.file) },
                            "region": { "startLine": line, "startColumn": e.column.unwrap_or(1) } } }]);
                    }
                    n
                }).collect::<Vec<_>>(),
            }],
        }],
    });
    let mut s = serde_json::to_string_pretty(&v).unwrap_or_default();
    s.push('\n');
    s
}

/// Relative paths stay relative (GitHub resolves them against the checkout); `\` → `/`.
fn uri(path: &str) -> String {
    path.replace('\\', "/").trim_start_matches("./").to_string()
}
