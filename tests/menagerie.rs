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
