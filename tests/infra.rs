//! Lint infrastructure end to end from the CLI: locations under `<include>`, trailing content
//! after the root element, several models per call, spec discovery, the lint cache and
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
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
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
    Path::new(p.as_str().unwrap_or(""))
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_default()
}

fn locations(v: &Value) -> Vec<Where> {
    let mut out: Vec<Where> = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let labels = f["labels"]
                .as_array()
                .unwrap()
                .iter()
                .map(|l| {
                    (base(&l["file"]), l["line"].as_u64().unwrap(), l["column"].as_u64().unwrap())
                })
                .collect();
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
        let hits: Vec<&Value> = v["findings"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|f| f["rule"] == "self-collision-at-keyframe")
            .collect();
        assert_eq!(hits.len(), 1, "{v}");
        let f = hits[0];
        assert_eq!(
            (base(&f["file"]).as_str(), f["line"].as_u64(), f["column"].as_u64()),
            ("robot.xml", Some(18), Some(12)),
            "{f}"
        );
        let l = &f["labels"][0];
        assert_eq!((base(&l["file"]).as_str(), l["line"].as_u64()), ("robot.xml", Some(24)), "{f}");
    }
    let (r, mut s) = (locations(&robot), locations(&scene));
    // The scene's floor lets keyframe-state judge the start height (robot.xml alone has no
    // floor, so it is not judged there): that one finding is the scene's own, and it too
    // points at the robot's free body in robot.xml.
    let floor_only: Vec<Where> = s.iter().filter(|w| w.0 == "keyframe-state").cloned().collect();
    assert_eq!(floor_only.len(), 1, "{floor_only:?}");
    assert_eq!((floor_only[0].1.as_str(), floor_only[0].2), ("robot.xml", 13), "{floor_only:?}");
    assert!(r.iter().all(|w| w.0 != "keyframe-state"), "{r:?}");
    s.retain(|w| w.0 != "keyframe-state");
    assert_eq!(r, s, "robot vs scene locations differ");
    assert!(
        s.iter().all(|w| w.1 == "robot.xml"),
        "no finding may land on the scene's floor: {s:?}"
    );
    // SARIF and GitHub annotations carry the same lines.
    let (_, sarif, _) = modellint(&[
        "fixtures/include/scene.xml",
        "--format",
        "sarif",
        "--no-probe",
        "--select",
        "self-collision-at-keyframe",
    ]);
    let v: Value = serde_json::from_str(&sarif).unwrap();
    let loc = &v["runs"][0]["results"][0]["locations"][0]["physicalLocation"];
    assert!(
        loc["artifactLocation"]["uri"].as_str().unwrap().ends_with("fixtures/include/robot.xml"),
        "{loc}"
    );
    assert_eq!(loc["region"]["startLine"], 18);
    let (_, gh, _) = modellint(&[
        "fixtures/include/scene.xml",
        "--format",
        "github",
        "--no-probe",
        "--select",
        "self-collision-at-keyframe",
    ]);
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
        // The scene adds its floor: a finding about the feet on it may also point at the floor
        // geom (a label in scene.xml), which the robot file alone cannot have. Every location in
        // the robot file must be the same.
        let in_robot = |mut v: Vec<Where>| {
            for w in &mut v {
                w.5.retain(|l| l.0 != "scene.xml");
            }
            v
        };
        let (lr, ls) = (locations(&r), in_robot(locations(&s)));
        assert!(!lr.is_empty(), "{dir}: expected findings");
        assert!(
            lr.iter().any(|w| w.0 == "collision-visual-mismatch"),
            "{dir}: geom findings expected"
        );
        assert_eq!(lr, ls, "{dir}: {robot} vs scene.xml locations differ");
        // An unnamed geom is named the same whichever file is linted: by its place in its body,
        // not by MuJoCo's geom id, which the scene's floor shifts (booster t1.xml:70 was
        // "collision geom #4 of body `H2`" from t1.xml and "#5" from scene.xml).
        let texts = |v: &Value| {
            let mut t: Vec<(String, String)> = v["findings"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|f| f["rule"] == "collision-visual-mismatch")
                .map(|f| {
                    let s = |k: &str| f[k].as_str().unwrap_or("").to_string();
                    (s("message"), s("element"))
                })
                .collect();
            t.sort();
            t
        };
        assert_eq!(texts(&r), texts(&s), "{dir}: {robot} vs scene.xml names differ");
    }
}

/// A second `</mujoco>` after the root (seen in a vendor's scene file): MuJoCo loads it, so
/// modellint lints it and reports the junk at its line.
#[test]
fn trailing_content_after_the_root_is_a_finding_not_an_error() {
    let (code, out, err) =
        modellint(&["fixtures/infra/trailing_close.xml", "--format", "json", "--no-probe"]);
    assert!(code == 0 || code == 1, "exit {code}: {err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let t: Vec<&Value> = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["rule"] == "trailing-xml-content")
        .collect();
    assert_eq!(t.len(), 1, "{out}");
    assert_eq!((t[0]["line"].as_u64(), t[0]["column"].as_u64()), (Some(13), Some(1)), "{}", t[0]);
    // Real malformed XML (not just trailing content) stays exit 2.
    let (code, _, err) = modellint(&["fixtures/broken/malformed.xml"]);
    assert_eq!(code, 2, "{err}");
}

/// A scene without its own spec finds the spec beside the robot file it includes; the spec is
/// really used (its action delay makes `missing-action-delay` fire).
#[test]
fn spec_is_found_beside_the_included_robot_file() {
    let v = json(&["fixtures/infra/spec_scene/scene.xml", "--format", "json", "--no-probe"]);
    assert!(
        v["spec"]["path"].as_str().unwrap().ends_with("spec_scene/robot.toml"),
        "{}",
        v["spec"]
    );
    assert_eq!(v["spec"]["skipped_rules"].as_array().unwrap().len(), 0);
    assert!(
        v["findings"].as_array().unwrap().iter().any(|f| f["rule"] == "missing-action-delay"),
        "the spec's delay must be used"
    );
    let (_, _, err) = modellint(&["fixtures/infra/spec_scene/scene.xml", "--no-probe"]);
    assert!(!err.contains("no hardware spec"), "{err}");
}

/// No spec anywhere: said once on stderr, naming every place looked at and the rules that are
/// skipped or weakened; the same in JSON.
#[test]
fn missing_spec_is_reported_once_with_where_it_looked() {
    let (_, _, err) = modellint(&["fixtures/include/scene.xml", "--no-probe"]);
    assert_eq!(err.matches("no hardware spec found").count(), 1, "{err}");
    assert!(
        err.contains("fixtures/include/scene.toml") && err.contains("fixtures/include/robot.toml"),
        "{err}"
    );
    assert!(err.contains("skipped without a spec: missing-action-delay, urdf-mjcf-drift"), "{err}");
    assert!(err.contains("weakened without a spec: armature-mismatch"), "{err}");
    // Rules switched off are not listed.
    let (_, _, err) =
        modellint(&["fixtures/include/scene.xml", "--no-probe", "--ignore", "armature-mismatch"]);
    assert!(!err.contains("armature-mismatch"), "{err}");
    let v = json(&["fixtures/include/scene.xml", "--format", "json", "--no-probe"]);
    assert!(v["spec"]["path"].is_null(), "{}", v["spec"]);
    let searched: Vec<String> =
        v["spec"]["searched"].as_array().unwrap().iter().map(base).collect();
    assert_eq!(searched, ["scene.toml", "robot.toml"]);
    assert!(
        v["spec"]["skipped_rules"].as_array().unwrap().iter().any(|r| r == "missing-action-delay")
    );
    assert!(
        v["spec"]["weakened_rules"].as_array().unwrap().iter().any(|r| r == "armature-mismatch")
    );
    // A given spec is not searched for.
    let (_, _, err) = modellint(&["models/asimov.xml", "--no-probe"]);
    assert!(!err.contains("no hardware spec"), "models/asimov.toml is beside it: {err}");
}

fn package_xml() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("modellint-infra-pkg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("package.xml");
    std::fs::write(&p, "<?xml version=\"1.0\"?>\n<!-- ROS package manifest -->\n<package format=\"3\">\n  <name>robot_description</name>\n</package>\n").unwrap();
    p
}

/// `modellint a.xml b.xml`: every model linted, exit code = the highest; a ROS package.xml
/// among several paths is skipped with a note; alone it is an error (exit 2).
#[test]
fn several_models_per_call() {
    let pkg = package_xml();
    let pkg = pkg.to_str().unwrap();
    // Clean model alone: exit 0. Model with an error finding alone: exit 1.
    let (c_ok, _, _) = modellint(&["fixtures/infra/trailing_close.xml", "--no-probe"]);
    assert_eq!(c_ok, 0);
    let (c_bad, _, _) = modellint(&["models/asimov.xml", "--no-probe"]);
    assert_eq!(c_bad, 1);
    let (code, out, err) =
        modellint(&["fixtures/infra/trailing_close.xml", pkg, "models/asimov.xml", "--no-probe"]);
    assert_eq!(code, 1, "max(0, 1): {err}");
    assert!(
        err.contains("skipping") && err.contains("package.xml") && err.contains("<package>"),
        "{err}"
    );
    assert!(
        out.contains("trailing_close.xml: 0 error(s)")
            && out.contains("models/asimov.xml: 4 error(s)"),
        "{out}"
    );
    assert!(out.contains("2 model(s) linted, 1 skipped"), "{out}");
    // A model that cannot be loaded makes the call exit 2, and the others are still linted.
    let (code, out, err) =
        modellint(&["models/asimov.xml", "fixtures/broken/malformed.xml", "--no-probe"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("fixtures/broken/malformed.xml:4:"), "{err}");
    assert!(out.contains("models/asimov.xml: 4 error(s)"), "{out}");
    // Only non-models: nothing linted, exit 0 (a pre-commit run touching only package.xml).
    let (code, _, err) = modellint(&[pkg, pkg, "--no-probe"]);
    assert_eq!(code, 0, "{err}");
    // A single non-model path is still an error.
    let (code, _, err) = modellint(&[pkg, "--no-probe"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("neither MJCF"), "{err}");
    // ... unless skipping is asked for (the pre-commit hook passes the one staged file).
    let (code, _, err) = modellint(&[pkg, "--no-probe", "--skip-non-models"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("skipping") && err.contains("<package>"), "{err}");
    // (the lint cache keys on the option: the same path without it is an error again)
    let (code, _, _) = modellint(&[pkg, "--no-probe"]);
    assert_eq!(code, 2);
}

/// A hardware spec staged alone (the pre-commit hook passes `robot.toml`) lints the model of its
/// name beside it, exactly as that model given itself; a `.toml` with no model beside it is
/// skipped with a note under `--skip-non-models`, as the hook runs.
#[test]
fn a_spec_given_lints_its_model() {
    let (c_model, out_model, _) =
        modellint(&["models/asimov.xml", "--no-probe", "--output-format", "concise"]);
    let (code, out, err) = modellint(&[
        "models/asimov.toml",
        "--no-probe",
        "--skip-non-models",
        "--output-format",
        "concise",
    ]);
    assert_eq!((code, &out), (c_model, &out_model), "{err}");
    assert!(out.contains("models/asimov.xml:"), "{out}");
    assert!(err.contains("models/asimov.toml is the spec of models/asimov.xml"), "{err}");
    // Spec and model staged together: linted once.
    let (code, both, _) = modellint(&[
        "models/asimov.xml",
        "models/asimov.toml",
        "--no-probe",
        "--output-format",
        "concise",
    ]);
    assert_eq!((code, &both), (c_model, &out_model));
    let dir = std::env::temp_dir().join(format!("modellint-infra-toml-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lone = dir.join("modellint.toml");
    std::fs::write(&lone, "fail_on = \"warning\"\n").unwrap();
    let (code, out, err) = modellint(&[lone.to_str().unwrap(), "--no-probe", "--skip-non-models"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.is_empty() || !out.contains("error(s)"), "{out}");
    assert!(err.contains("skipping") && err.contains("a TOML file"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn several_models_in_every_format() {
    let pkg = package_xml();
    let pkg = pkg.to_str().unwrap();
    let args = [
        "models/asimov.xml",
        "fixtures/include/scene.xml",
        pkg,
        "fixtures/broken/malformed.xml",
        "--no-probe",
    ];
    let with = |fmt: &str| {
        let mut a = args.to_vec();
        a.extend(["--format", fmt]);
        let (code, out, err) = modellint(&a);
        assert_eq!(code, 2, "{fmt}: {err}");
        out
    };
    // JSON: a findings-set holding one complete single-model object per model.
    let v: Value = serde_json::from_str(&with("json")).unwrap();
    assert_eq!(v["schema"], "modellint/findings-set");
    assert_eq!(v["version"], 1);
    let models = v["models"].as_array().unwrap();
    assert_eq!(models.len(), 2);
    assert_eq!(models[0]["schema"], "modellint/findings");
    assert_eq!(models[0]["model"], "models/asimov.xml");
    assert_eq!(models[1]["model"], "fixtures/include/scene.xml");
    let single = json(&["models/asimov.xml", "--format", "json", "--no-probe"]);
    assert_eq!(models[0], single, "a model inside the set is exactly its single-model output");
    assert_eq!(v["skipped"][0]["path"], pkg);
    assert_eq!(v["errors"][0]["line"], 4);
    assert_eq!(v["summary"]["models"], 2);
    // SARIF: one run with the results of both models, the load failure as a notification.
    let s: Value = serde_json::from_str(&with("sarif")).unwrap();
    let uris: std::collections::BTreeSet<String> = s["runs"][0]["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"]
                .as_str()
                .unwrap()
                .to_string()
        })
        .collect();
    assert!(
        uris.contains("models/asimov.xml") && uris.contains("fixtures/include/robot.xml"),
        "{uris:?}"
    );
    assert_eq!(s["runs"][0]["invocations"][0]["executionSuccessful"], false);
    let text = include_str!("data/sarif-schema-2.1.0.json")
        .replace("^[a-zA-Z]{2}|^[a-zA-Z]{2}-[a-zA-Z]{2}]?$", "^[a-zA-Z]{2}(-[a-zA-Z]{2})?$");
    let schema: Value = serde_json::from_str(&text).unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    let errors: Vec<String> =
        validator.iter_errors(&s).map(|e| format!("{e} at {}", e.instance_path())).collect();
    assert!(errors.is_empty(), "{}", errors.join("\n"));
    // GitHub: annotations of both models, and the load failure at its line.
    let gh = with("github");
    assert!(gh.contains("::error file=models/asimov.xml,line="), "{gh}");
    assert!(gh.contains("file=fixtures/include/robot.xml,line=18,"), "{gh}");
    assert!(gh.contains("::error file=fixtures/broken/malformed.xml,line=4,"), "{gh}");
    // Text: both models' findings and summaries.
    let t = with("text");
    assert!(
        t.contains("models/asimov.xml: 4 error(s)") && t.contains("fixtures/include/scene.xml: "),
        "{t}"
    );
}

fn loaded(path: &str) -> modellint::lint::Loaded {
    let input = modellint::lint::LintInput {
        model: path.into(),
        spec: None,
        config: None,
        select: vec![],
        ignore: vec![],
    };
    modellint::lint::load(&input).unwrap_or_else(|e| panic!("{e}"))
}

fn geom(l: &modellint::lint::Loaded, name: &str) -> usize {
    l.robot.geoms.iter().position(|g| g.name == name).unwrap()
}

/// The probe measures the pair with MuJoCo: hand-computed overlap 0.04 + 0.04 − 0.05 = 30 mm,
/// a contact force, and the two hanging links swung apart (the contact acts 0.1 m below the
/// hinges). On the valid fixture the thighs are 0.16 − 2·0.04 = 80 mm apart: no force.
#[test]
fn self_collision_probe_measures_contacts_at_the_keyframe() {
    use modellint::probe::penetration;
    let l = loaded("fixtures/probes/self_collide_jolt.xml");
    let (a, b) = (geom(&l, "ball_l"), geom(&l, "ball_r"));
    let p = penetration::run(&l.robot, a, b).unwrap();
    assert!((p.depth0 + 0.03).abs() < 1e-6, "depth {}", p.depth0);
    assert!(p.contact_force > 1.0, "force {}", p.contact_force);
    assert!(p.separation_speed > penetration::JOLT_SPEED, "speed {}", p.separation_speed);
    assert!(p.clear_time.is_some() && p.dist_end > 0.0, "{p:?}");
    let l = loaded("fixtures/rules/self-collision-at-keyframe/valid.xml");
    let (a, b) = (geom(&l, "left_thigh_capsule"), geom(&l, "right_thigh_capsule"));
    let p = penetration::run(&l.robot, a, b).unwrap();
    assert_eq!(p.contact_force, 0.0);
    assert!((p.depth0 - 0.08).abs() < 1e-6, "distance {}", p.depth0);
    // End to end: the finding carries the confirmed probe instead of "skipped".
    let v = json(&[
        "fixtures/probes/self_collide_jolt.xml",
        "--format",
        "json",
        "--select",
        "self-collision-at-keyframe",
    ]);
    let f = &v["findings"][0];
    assert_eq!(f["probe"]["name"], "keyframe-penetration", "{f}");
    assert_eq!(f["probe"]["status"], "confirmed", "{f}");
    assert!(f["probe"]["measured"]["contact_force_n"].as_f64().unwrap() > 1.0);
    let v = json(&[
        "fixtures/rules/self-collision-at-keyframe/invalid.xml",
        "--format",
        "json",
        "--select",
        "self-collision-at-keyframe",
    ]);
    for f in v["findings"].as_array().unwrap() {
        assert_ne!(f["probe"]["status"], "skipped", "{f}");
    }
}

fn run_with_cache(args: &[&str], cache: &Path) -> (i32, String) {
    let (code, out, _) = run_with_cache_err(args, cache);
    (code, out)
}

/// Exit code, stdout and stderr, byte for byte.
fn run_with_cache_err(args: &[&str], cache: &Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args(args)
        .env_remove("GITHUB_ACTIONS")
        .env("MODELLINT_CACHE_DIR", cache)
        .output()
        .unwrap();
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code().unwrap_or(-1), text(&out.stdout), text(&out.stderr))
}

fn entries(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "lint"))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// The lint cache: the same findings with and without it, a new entry whenever the model XML
/// or a mesh it reads changes (never a stale result), and a corrupt entry is ignored.
#[test]
fn lint_cache_gives_the_same_findings_and_follows_every_input() {
    let root = std::env::temp_dir().join(format!("modellint-cache-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let cache = root.join("cache");
    let model_dir = root.join("model");
    std::fs::create_dir_all(&model_dir).unwrap();
    // A pendulum with a mesh bob, so the cache key must cover a mesh file.
    let obj = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    std::fs::write(model_dir.join("bob.obj"), obj).unwrap();
    let xml = |kp: &str| {
        format!(
            "<mujoco model=\"cached\">\n  <asset><mesh name=\"bob\" file=\"bob.obj\"/></asset>\n  <worldbody>\n    <body name=\"arm\" pos=\"0 0 1\">\n      <joint name=\"hinge\" axis=\"0 1 0\" range=\"-1 1\" armature=\"0.01\"/>\n      <geom type=\"capsule\" size=\"0.02\" fromto=\"0 0 0 0 0 -0.3\" mass=\"1\"/>\n      <geom type=\"mesh\" mesh=\"bob\" pos=\"0 0 -0.3\" mass=\"0.2\"/>\n    </body>\n  </worldbody>\n  <actuator><position joint=\"hinge\" kp=\"{kp}\" kv=\"0.1\" ctrlrange=\"-1 1\"/></actuator>\n</mujoco>\n"
        )
    };
    let model = model_dir.join("robot.xml");
    std::fs::write(&model, xml("50")).unwrap();
    let m = model.to_str().unwrap();
    let args = [m, "--format", "json"];
    let (c0, no_cache) = run_with_cache(&[m, "--format", "json", "--no-cache"], &cache);
    assert!(entries(&cache).is_empty(), "--no-cache must not write");
    let (c1, cold) = run_with_cache(&args, &cache);
    assert_eq!(entries(&cache).len(), 1, "the cold run stores its result");
    let (c2, warm) = run_with_cache(&args, &cache);
    assert_eq!(entries(&cache).len(), 1, "the warm run reuses it");
    assert_eq!((c0, c1), (c1, c2));
    assert_eq!(no_cache, cold);
    assert_eq!(no_cache, warm, "same findings (incl. probes) from the cache");
    // --cache-dir overrides the environment.
    let other = root.join("other");
    let (_, via_flag) =
        run_with_cache(&[m, "--format", "json", "--cache-dir", other.to_str().unwrap()], &cache);
    assert_eq!(via_flag, no_cache);
    assert_eq!(entries(&other).len(), 1);
    // A changed gain: a new entry, and the findings follow the file, not the cache.
    std::fs::write(&model, xml("5000")).unwrap();
    let (_, changed) = run_with_cache(&args, &cache);
    let (_, changed_nc) = run_with_cache(&[m, "--format", "json", "--no-cache"], &cache);
    assert_eq!(changed, changed_nc);
    assert_ne!(changed, warm, "kp 50 → 5000 changes the findings");
    assert_eq!(entries(&cache).len(), 2);
    // A changed mesh (the XML untouched): a new entry, and the result follows the mesh (the
    // bob's mass is spread over a taller tetrahedron: another inertia, other numbers).
    std::fs::write(model_dir.join("bob.obj"), obj.replace("v 0 0 0.1", "v 0 0 0.2")).unwrap();
    let (_, mesh_changed) = run_with_cache(&args, &cache);
    assert_eq!(entries(&cache).len(), 3, "the mesh is part of the key");
    let (_, mesh_nc) = run_with_cache(&[m, "--format", "json", "--no-cache"], &cache);
    assert_eq!(mesh_changed, mesh_nc, "no stale result after a mesh edit");
    // A corrupt entry is ignored: the model is compiled again, same output.
    for e in entries(&cache) {
        std::fs::write(e, b"not a MuJoCo model").unwrap();
    }
    let (_, after_corrupt) = run_with_cache(&args, &cache);
    let (_, nc) = run_with_cache(&[m, "--format", "json", "--no-cache"], &cache);
    assert_eq!(after_corrupt, nc);
    let _ = std::fs::remove_dir_all(&root);
}

/// The lint cache follows a file the model includes, and the spec found beside it: an edit of
/// either is never answered from an entry of the old text; text output and the notes on stderr
/// are byte-identical warm and cold.
#[test]
fn lint_cache_follows_included_files_and_the_spec() {
    let root = std::env::temp_dir().join(format!("modellint-cache-inc-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let cache = root.join("cache");
    let dir = root.join("model");
    std::fs::create_dir_all(&dir).unwrap();
    let robot = |range: &str| {
        format!(
            "<mujoco model=\"arm\">\n  <worldbody>\n    <body name=\"link\" pos=\"0 0 1\">\n      <joint name=\"hinge\" axis=\"0 1 0\" {range} armature=\"0.01\"/>\n      <geom type=\"capsule\" size=\"0.02\" fromto=\"0 0 0 0 0 -0.3\" mass=\"1\"/>\n    </body>\n  </worldbody>\n  <actuator><position joint=\"hinge\" kp=\"20\" kv=\"1\" ctrlrange=\"-1 1\"/></actuator>\n</mujoco>\n"
        )
    };
    std::fs::write(dir.join("robot.xml"), robot("range=\"-2 2\"")).unwrap();
    let scene = dir.join("scene.xml");
    std::fs::write(
        &scene,
        "<mujoco model=\"scene\">\n  <include file=\"robot.xml\"/>\n  <worldbody>\n    <geom name=\"floor\" type=\"plane\" size=\"0 0 0.05\"/>\n  </worldbody>\n</mujoco>\n",
    )
    .unwrap();
    let s = scene.to_str().unwrap();
    let args = [s, "--no-probe", "--color", "never"];
    let nc_args = [s, "--no-probe", "--color", "never", "--no-cache"];
    let cold = run_with_cache_err(&args, &cache);
    let warm = run_with_cache_err(&args, &cache);
    assert_eq!(entries(&cache).len(), 1);
    assert_eq!(cold, warm, "exit code, stdout and stderr byte-identical warm and cold");
    assert_eq!(cold, run_with_cache_err(&nc_args, &cache));
    assert!(cold.2.contains("no hardware spec found"), "{}", cold.2);
    // The included robot file loses its range: the scene's result changes with it.
    std::fs::write(dir.join("robot.xml"), robot("")).unwrap();
    let edited = run_with_cache_err(&args, &cache);
    assert_eq!(entries(&cache).len(), 2, "the included file is part of the key");
    assert_ne!(edited.1, warm.1, "an edit of the included file changes the findings");
    assert_eq!(edited, run_with_cache_err(&nc_args, &cache));
    // A spec appears beside the included robot file (found by the run): a new result.
    std::fs::write(dir.join("robot.toml"), "[robot]\nname = \"arm\"\n").unwrap();
    let with_spec = run_with_cache_err(&args, &cache);
    assert_eq!(entries(&cache).len(), 3, "the spec found is part of the key");
    assert!(!with_spec.2.contains("no hardware spec found"), "{}", with_spec.2);
    assert_eq!(with_spec, run_with_cache_err(&nc_args, &cache));
    let _ = std::fs::remove_dir_all(&root);
}
