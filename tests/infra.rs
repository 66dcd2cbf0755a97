//! Lint infrastructure end to end from the CLI: locations under `<include>`, trailing content
//! after the root element, several models per call, spec discovery, the compiled-model cache and
//! the self-collision probe. Expected lines come from the hand-built fixtures (fixtures/include,
//! fixtures/infra), not from modellint's own output.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

fn modellint(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args(args)
        .env_remove("GITHUB_ACTIONS")
        .env("MODELLINT_CACHE_DIR", cache_dir())
        .output()
        .unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

fn cache_dir() -> std::path::PathBuf {
    std::env::temp_dir().join(format!("modellint-infra-test-cache-{}", std::process::id()))
}

fn json(args: &[&str]) -> Value {
    let (code, out, err) = modellint(args);
    assert!(code == 0 || code == 1, "{args:?}: exit {code}\n{err}");
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("{args:?}: not JSON ({e}):\n{out}"))
}

/// (rule, file name, line, column, end line, [(label file name, line, column)]) of every finding.
type Where = (String, String, u64, u64, u64, Vec<(String, u64, u64)>);

fn base(p: &Value) -> String {
    Path::new(p.as_str().unwrap_or("")).file_name().map(|f| f.to_string_lossy().to_string()).unwrap_or_default()
}

fn locations(v: &Value) -> Vec<Where> {
    let mut out: Vec<Where> = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let labels = f["labels"].as_array().unwrap().iter().map(|l| (base(&l["file"]), l["line"].as_u64().unwrap(), l["column"].as_u64().unwrap())).collect();
            (
                f["rule"].as_str().unwrap().to_string(),
                base(&f["file"]),
                f["line"].as_u64().unwrap(),
                f["column"].as_u64().unwrap(),
                f["end_line"].as_u64().unwrap(),
                labels,
            )
        })
        .collect();
    out.sort();
    out
}

/// The scene adds world geoms before and after the included robot; MuJoCo numbers all world
/// geoms first. The self-collision of the two unnamed spheres must point at robot.xml line 18
/// (the sphere in arm_l's frame) with the other geom at line 24, whichever file is linted.
#[test]
fn include_keeps_every_location_on_its_own_element() {
    let robot = json(&["fixtures/include/robot.xml", "--format", "json", "--no-probe"]);
    let scene = json(&["fixtures/include/scene.xml", "--format", "json", "--no-probe"]);
    for v in [&robot, &scene] {
        let hits: Vec<&Value> = v["findings"].as_array().unwrap().iter().filter(|f| f["rule"] == "self-collision-at-keyframe").collect();
        assert_eq!(hits.len(), 1, "{v}");
        let f = hits[0];
        assert_eq!((base(&f["file"]).as_str(), f["line"].as_u64(), f["column"].as_u64()), ("robot.xml", Some(18), Some(12)), "{f}");
        let l = &f["labels"][0];
        assert_eq!((base(&l["file"]).as_str(), l["line"].as_u64()), ("robot.xml", Some(24)), "{f}");
    }
    let (r, s) = (locations(&robot), locations(&scene));
    assert_eq!(r, s, "robot vs scene locations differ");
    assert!(s.iter().all(|w| w.1 == "robot.xml"), "no finding may land on the scene's floor: {s:?}");
    // SARIF and GitHub annotations carry the same lines.
    let (_, sarif, _) = modellint(&["fixtures/include/scene.xml", "--format", "sarif", "--no-probe", "--select", "self-collision-at-keyframe"]);
    let v: Value = serde_json::from_str(&sarif).unwrap();
    let loc = &v["runs"][0]["results"][0]["locations"][0]["physicalLocation"];
    assert!(loc["artifactLocation"]["uri"].as_str().unwrap().ends_with("fixtures/include/robot.xml"), "{loc}");
    assert_eq!(loc["region"]["startLine"], 18);
    let (_, gh, _) = modellint(&["fixtures/include/scene.xml", "--format", "github", "--no-probe", "--select", "self-collision-at-keyframe"]);
    assert!(gh.contains("robot.xml,line=18,col=12,"), "{gh}");
}

#[test]
fn shared_scenes_and_robot_files_give_identical_locations() {
    let root = Path::new("../shared/data/models");
    if !root.is_dir() {
        eprintln!("skipping: ../shared/data/models is absent");
        return;
    }
    for (dir, robot) in [("booster_t1", "t1.xml"), ("unitree_h1", "h1.xml")] {
        let r = root.join(dir).join(robot);
        let s = root.join(dir).join("scene.xml");
        let r = json(&[r.to_str().unwrap(), "--format", "json", "--no-probe"]);
        let s = json(&[s.to_str().unwrap(), "--format", "json", "--no-probe"]);
        let (lr, ls) = (locations(&r), locations(&s));
        assert!(!lr.is_empty(), "{dir}: expected findings");
        assert!(lr.iter().any(|w| w.0 == "collision-visual-mismatch"), "{dir}: geom findings expected");
        assert_eq!(lr, ls, "{dir}: {robot} vs scene.xml locations differ");
    }
}

/// A second `</mujoco>` after the root (seen in a vendor's scene file): MuJoCo loads it, so
/// modellint lints it and reports the junk at its line.
#[test]
fn trailing_content_after_the_root_is_a_finding_not_an_error() {
    let (code, out, err) = modellint(&["fixtures/infra/trailing_close.xml", "--format", "json", "--no-probe"]);
    assert!(code == 0 || code == 1, "exit {code}: {err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let t: Vec<&Value> = v["findings"].as_array().unwrap().iter().filter(|f| f["rule"] == "trailing-xml-content").collect();
    assert_eq!(t.len(), 1, "{out}");
    assert_eq!((t[0]["line"].as_u64(), t[0]["column"].as_u64()), (Some(13), Some(1)), "{}", t[0]);
    // Real malformed XML (not just trailing content) stays exit 2.
    let (code, _, err) = modellint(&["fixtures/broken/malformed.xml"]);
    assert_eq!(code, 2, "{err}");
}
