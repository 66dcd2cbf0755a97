//! `modellint FILE --no-probe --format json` from the CLI, and the findings' fields.

use std::process::Command;

/// The findings of `modellint FILE --no-probe --format json`.
pub fn findings(file: &str) -> Vec<serde_json::Value> {
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args([file, "--no-probe", "--format", "json", "--no-cache"])
        .env_remove("GITHUB_ACTIONS")
        .output()
        .unwrap();
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!("{file}: no JSON ({e}): {}", String::from_utf8_lossy(&out.stderr))
    });
    json["findings"].as_array().cloned().unwrap_or_default()
}

/// The findings of one rule.
pub fn of<'a>(all: &'a [serde_json::Value], rule: &str) -> Vec<&'a serde_json::Value> {
    all.iter().filter(|f| f["rule"] == rule).collect()
}

/// The findings of `rule` for `file` whose message contains `part`.
pub fn of_message(file: &str, rule: &str, part: &str) -> Vec<serde_json::Value> {
    findings(file).into_iter().filter(|f| f["rule"] == rule && message(f).contains(part)).collect()
}

pub fn message(f: &serde_json::Value) -> &str {
    f["message"].as_str().unwrap_or("")
}

/// The finding's measured value (NaN when it has none).
pub fn measured(f: &serde_json::Value) -> f64 {
    f["measured"]["value"].as_f64().unwrap_or(f64::NAN)
}

/// `models/asimov.xml` and the shared real robots (Booster T1, Unitree H1) when `../shared` is
/// there (each absent one is named on stderr): the robot files a class must not fire on.
pub fn real_robot_files() -> Vec<String> {
    let mut files = vec!["models/asimov.xml".to_string()];
    for m in ["booster_t1/t1.xml", "unitree_h1/h1.xml"] {
        let p = format!("../shared/data/models/{m}");
        if std::path::Path::new(&p).exists() {
            files.push(p);
        } else {
            eprintln!("skipped {p}: ../shared absent");
        }
    }
    files
}

/// The text of the load error `modellint::lint::load` gives for `model` (panics if it loads).
pub fn load_error(model: &str) -> String {
    let input = modellint::lint::LintInput {
        model: model.into(),
        spec: None,
        config: None,
        select: vec![],
        ignore: vec![],
    };
    match modellint::lint::load(&input) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("{model} must not load"),
    }
}

/// A rule option's documented default, read from `modellint rule RULE`'s options table.
pub fn option(rule: &str, name: &str) -> f64 {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args(["rule", rule])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let line = text
        .lines()
        .find(|l| l.starts_with(&format!("| `{name}` |")))
        .unwrap_or_else(|| panic!("option {name} not in the table:\n{text}"));
    line.split('|').nth(2).unwrap().trim().parse().unwrap()
}
