//! Fixtures are tests: every rule has `fixtures/rules/<id>/invalid*.xml` (must produce that
//! rule's finding; rendered output is a reviewed snapshot `*.snap`) and `valid*.xml` (must
//! produce none of it). A spec `<stem>.toml` beside a fixture is used for it.
//! Set UPDATE_SNAPSHOTS=1 to rewrite snapshots, then review the diff.

use std::path::{Path, PathBuf};

use modellint::lint::{LintInput, load, run_rules};
use modellint::output::text;
use modellint::rules::all_meta;

fn fixtures(id: &str) -> Vec<PathBuf> {
    let dir = Path::new("fixtures/rules").join(id);
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|e| e == "xml" || e == "urdf")).collect())
        .unwrap_or_default();
    v.sort();
    v
}

fn lint_one(path: &Path, id: &str) -> (Vec<modellint::finding::Finding>, String) {
    let input = LintInput { model: path.to_path_buf(), spec: None, config: None, select: vec![id.to_string()], ignore: vec![] };
    let loaded = load(&input).unwrap_or_else(|e| panic!("fixture {} failed to load: {e}", path.display()));
    let mut findings = run_rules(&loaded);
    if id == "unstable-simulation" {
        // This rule exists only as a probe: run the simulations.
        modellint::probe::confirm_all(&loaded, &mut findings);
    }
    let rendered = text::render(&loaded.sources, &findings, false);
    (findings, rendered)
}

#[test]
fn every_rule_has_docs_and_fixtures() {
    for m in all_meta() {
        if m.group == "engine" {
            continue;
        }
        for h in ["## What it does", "## Why is this bad?", "## How it is confirmed", "## How to fix"] {
            assert!(m.docs.contains(h), "rule {} docs lack `{h}`", m.id);
        }
        let fx = fixtures(m.id);
        let name = |p: &PathBuf| p.file_name().unwrap().to_string_lossy().to_string();
        assert!(fx.iter().any(|p| name(p).starts_with("invalid")), "rule {} has no invalid fixture", m.id);
        assert!(fx.iter().any(|p| name(p).starts_with("valid")), "rule {} has no valid fixture", m.id);
    }
}

#[test]
fn fixtures_produce_exactly_their_findings() {
    let update = std::env::var_os("UPDATE_SNAPSHOTS").is_some();
    let mut failures = Vec::new();
    for m in all_meta() {
        for path in fixtures(m.id) {
            let stem = path.file_stem().unwrap().to_string_lossy().to_string();
            let (findings, rendered) = lint_one(&path, m.id);
            let mine = findings.iter().filter(|f| f.rule == m.id).count();
            if stem.starts_with("valid") {
                if mine != 0 {
                    failures.push(format!("{}: expected no `{}` finding, got:\n{rendered}", path.display(), m.id));
                }
                continue;
            }
            if mine == 0 {
                failures.push(format!("{}: expected a `{}` finding, got none", path.display(), m.id));
                continue;
            }
            let snap = path.with_extension("snap");
            if update {
                std::fs::write(&snap, &rendered).unwrap();
            } else {
                match std::fs::read_to_string(&snap) {
                    Ok(s) if s == rendered => {}
                    Ok(s) => failures.push(format!("{}: snapshot differs\n--- expected\n{s}\n--- got\n{rendered}", snap.display())),
                    Err(_) => failures.push(format!("{}: missing snapshot (run with UPDATE_SNAPSHOTS=1)", snap.display())),
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
