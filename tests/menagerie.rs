//! Regression corpus: what modellint says about real third-party models (MuJoCo Menagerie, in
//! ../shared/data). A change in the report shows up as a snapshot diff; UPDATE_SNAPSHOTS=1
//! rewrites them. Skips visibly when ../shared is absent.

use std::path::{Path, PathBuf};

use modellint::lint::{LintInput, load, run_rules};

fn shared() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    p.is_dir().then_some(p)
}

fn check(model: &str, spec: Option<&str>, snap: &str) {
    let Some(_) = shared() else {
        eprintln!("skipping {model}: ../shared/data is absent");
        return;
    };
    let input = LintInput {
        model: PathBuf::from(model),
        spec: spec.map(PathBuf::from),
        config: None,
        select: vec![],
        ignore: vec![],
    };
    let l = load(&input).unwrap_or_else(|e| panic!("{e}"));
    let mut f = run_rules(&l);
    modellint::lint::confirm(&l, &mut f);
    let text = modellint::output::text::render(&l.sources, &f, false);
    let path = Path::new("tests/snapshots").join(snap);
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some() {
        std::fs::write(&path, &text).unwrap();
        return;
    }
    let want = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        want == text,
        "{} changed; review and run with UPDATE_SNAPSHOTS=1\n--- got\n{text}",
        path.display()
    );
}

#[test]
fn booster_t1_report() {
    check(
        "../shared/data/models/booster_t1/t1.xml",
        Some("fixtures/booster_t1.toml"),
        "booster_t1.txt",
    );
}

#[test]
fn unitree_h1_report() {
    check(
        "../shared/data/models/unitree_h1/h1.xml",
        Some("fixtures/unitree_h1.toml"),
        "unitree_h1.txt",
    );
}

/// What a new user sees: the model alone, no spec (issue 13: lint what the file itself shows).
#[test]
fn booster_t1_report_without_spec() {
    check("../shared/data/models/booster_t1/t1.xml", None, "booster_t1_nospec.txt");
}

#[test]
fn unitree_h1_report_without_spec() {
    check("../shared/data/models/unitree_h1/h1.xml", None, "unitree_h1_nospec.txt");
}

#[test]
fn both_scenes_load() {
    if shared().is_none() {
        eprintln!("skipping: ../shared/data is absent");
        return;
    }
    for m in
        ["../shared/data/models/booster_t1/scene.xml", "../shared/data/models/unitree_h1/scene.xml"]
    {
        let input =
            LintInput { model: m.into(), spec: None, config: None, select: vec![], ignore: vec![] };
        let l = load(&input).unwrap_or_else(|e| panic!("{m}: {e}"));
        assert!(l.robot.joints.len() > 19, "{m}");
        assert!(l.robot.key.key.is_some(), "{m} has a keyframe");
    }
}

/// Issue 45, "a pre-commit run on two Menagerie robot folders prints each finding once, one line
/// each": every model file of both folders (each scene and the robot file it includes, as
/// pre-commit passes the staged files) through the hook's command. Each robot file is skipped as
/// included by its scene, every stdout line is one `file:line:col: level rule message`, and no
/// line appears twice.
#[test]
fn hook_on_two_robot_folders_prints_each_finding_once() {
    let Some(data) = shared() else {
        eprintln!("skipping: ../shared/data is absent");
        return;
    };
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in ["booster_t1", "unitree_h1"] {
        let mut xml: Vec<PathBuf> = std::fs::read_dir(data.join("models").join(dir))
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "xml"))
            .collect();
        xml.sort();
        assert!(xml.len() >= 2, "{dir}: a scene and its robot file");
        files.extend(xml);
    }
    let hooks = std::fs::read_to_string(".pre-commit-hooks.yaml").unwrap();
    let entry = hooks.lines().find_map(|l| l.trim().strip_prefix("entry: modellint ")).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args(&files)
        .args(entry.split_whitespace())
        .arg("--no-cache")
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.matches("included by").count(), 2, "{stderr}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(!lines.is_empty(), "{stderr}");
    for l in &lines {
        let mut it = l.splitn(4, ':');
        let (file, line, col) =
            (it.next().unwrap(), it.next().unwrap_or(""), it.next().unwrap_or(""));
        let rest = it.next().unwrap_or("");
        assert!(file.ends_with(".xml") || file.ends_with(".toml"), "{l}");
        assert!(line.parse::<usize>().is_ok() && col.parse::<usize>().is_ok(), "{l}");
        let level = rest.split_whitespace().next().unwrap_or("");
        assert!(["error", "warning", "info"].contains(&level), "{l}");
    }
    let mut uniq = lines.clone();
    uniq.sort();
    uniq.dedup();
    assert_eq!(uniq.len(), lines.len(), "a finding printed twice:\n{stdout}");
}
