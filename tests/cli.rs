//! End-to-end CLI behaviour: exit codes, precise errors on bad input, output formats.

mod common;

use common::lint::load_error;
use std::process::Command;

fn modellint(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args(args)
        .env_remove("GITHUB_ACTIONS")
        .env_remove("MUJOCO_PLUGIN_DIR")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Every broken input: exit 2, `file:line:col` (where a line exists) and a precise message, no panic.
#[test]
fn broken_inputs_exit_2_with_location() {
    let cases: &[(&[&str], &str, &str)] = &[
        (&["fixtures/broken/malformed.xml"], "fixtures/broken/malformed.xml:4:", "malformed XML"),
        (&["fixtures/broken/empty.xml"], "fixtures/broken/empty.xml", "empty"),
        (&["fixtures/broken/cycle_a.xml"], "cycle_", "include cycle"),
        (
            &["fixtures/broken/nan_attr.xml"],
            "fixtures/broken/nan_attr.xml:4:",
            "not a finite number",
        ),
        (
            &["fixtures/broken/missing_mesh.xml"],
            "fixtures/broken/missing_mesh.xml:3:",
            "file not found",
        ),
        (
            &["fixtures/broken/not_a_model.xml"],
            "fixtures/broken/not_a_model.xml:1:",
            "neither MJCF",
        ),
        (&["fixtures/broken/does_not_exist.xml"], "does_not_exist.xml", "file not found"),
        // A mesh format MuJoCo has no decoder for (a URDF's COLLADA): the filename attribute.
        (
            &["fixtures/broken/urdf_dae_collision.urdf"],
            "fixtures/broken/urdf_dae_collision.urdf:10:",
            "cannot read this mesh format",
        ),
        (&["models/asimov.toml"], "models/asimov.toml:1:1", "hardware spec (--spec"),
        // MuJoCo's message is cut before its line number: the element it names.
        (
            &["fixtures/broken/massless_body.xml"],
            "fixtures/broken/massless_body.xml:7:19:",
            "Element name 'forearm'",
        ),
        // MuJoCo's message outgrows mujoco-rs's 100-byte buffer: the whole message is read, and
        // the element it names located (a sensor naming a missing joint; a URDF link whose
        // inertia has a zero moment), not the root element.
        (
            &["fixtures/broken/sensor_unknown_joint.xml"],
            "fixtures/broken/sensor_unknown_joint.xml:12:",
            "Element name 'arm_left_shoulder_pitch_pos'",
        ),
        (
            &["fixtures/broken/urdf_inertia_not_positive.urdf"],
            "fixtures/broken/urdf_inertia_not_positive.urdf:11:",
            "Element name 'lower_link_with_a_long_enough_name'",
        ),
        // A MuJoCo plugin with no plugin library loaded: where, and what to set.
        (
            &["fixtures/broken/plugin_pid.xml"],
            "fixtures/broken/plugin_pid.xml:",
            "MUJOCO_PLUGIN_DIR",
        ),
        // An unnamed geom in an included file ("line 0"): the attribute MuJoCo rejects.
        (
            &["fixtures/broken/shell_inertia_scene.xml"],
            "fixtures/broken/shell_inertia_robot.xml:9:",
            "`shellinertia`",
        ),
        // An attribute MuJoCo's schema no longer knows, in an included file ("line 0").
        (
            &["fixtures/broken/unknown_attribute_scene.xml"],
            "fixtures/broken/unknown_attribute_robot.xml:4:",
            "`apirate`",
        ),
        (
            &["fixtures/broken/mujoco_rejects.xml"],
            "fixtures/broken/mujoco_rejects.xml",
            "MuJoCo could not compile",
        ),
        (
            &["fixtures/broken/ok.xml", "--spec", "fixtures/broken/unknown_key.toml"],
            "unknown_key.toml:3:",
            "bogus_key",
        ),
        (
            &["fixtures/broken/ok.xml", "--spec", "fixtures/broken/unknown_joint.toml"],
            "unknown_joint.toml:1:",
            "matches no joint",
        ),
        (
            &["fixtures/broken/ok.xml", "--spec", "fixtures/broken/bad_value.toml"],
            "bad_value.toml:2:",
            "positive",
        ),
        (
            &["fixtures/broken/ok.xml", "--spec", "fixtures/broken/control_period.toml"],
            "control_period.toml:3:",
            "the rate is 50 Hz",
        ),
        (&["fixtures/broken/ok.xml", "--select", "no-such-rule"], "command line", "unknown rule"),
    ];
    for (args, loc, msg) in cases {
        let (code, _out, err) = modellint(args);
        assert_eq!(code, 2, "{args:?}: exit {code}, stderr:\n{err}");
        assert!(err.contains(loc), "{args:?}: stderr lacks `{loc}`:\n{err}");
        assert!(err.contains(msg), "{args:?}: stderr lacks `{msg}`:\n{err}");
        assert!(!err.contains("panicked"), "{args:?} panicked:\n{err}");
    }
    // The hint names the near joint.
    let (_, _, err) =
        modellint(&["fixtures/broken/ok.xml", "--spec", "fixtures/broken/unknown_joint.toml"]);
    assert!(err.contains("hinge"), "{err}");
}

#[test]
fn json_output_is_versioned_and_complete() {
    let (code, out, err) = modellint(&["models/asimov.xml", "--format", "json", "--no-probe"]);
    assert!(code == 0 || code == 1, "exit {code}: {err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("valid JSON");
    assert_eq!(v["schema"], "modellint/findings");
    assert_eq!(v["version"], 1);
    let f = v["findings"].as_array().unwrap();
    assert!(!f.is_empty(), "the shipped model has real findings (underdamped hips)");
    for k in [
        "rule", "severity", "message", "file", "line", "column", "element", "help", "measured",
        "expected",
    ] {
        assert!(f[0].get(k).is_some(), "finding lacks `{k}`: {}", f[0]);
    }
    let under: Vec<_> = f.iter().filter(|x| x["rule"] == "underdamped-pd-gains").collect();
    assert_eq!(under.len(), 4, "hip pitch and hip roll of both legs");
    assert!(under[0]["measured"]["value"].as_f64().unwrap() < 0.7);
}

#[test]
fn probes_attach_outcomes_in_json() {
    let (_, out, _) = modellint(&["models/asimov.xml", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let f = v["findings"].as_array().unwrap();
    let p = f.iter().find(|x| x["rule"] == "underdamped-pd-gains").unwrap()["probe"].clone();
    assert_eq!(p["name"], "impulse-response");
    assert_eq!(p["status"], "confirmed");
    assert!(p["steps"].as_u64().unwrap() > 100);
    assert!(p["measured"]["zeta"].as_f64().unwrap() < 0.7);
}

#[test]
fn sarif_validates_against_the_2_1_0_schema() {
    // tests/data/sarif-schema-2.1.0.json is the OASIS SARIF 2.1.0 schema as shipped in the
    // serde-sarif 0.8.0 crate. Its `run.language` pattern has a stray `]` that a strict regex
    // engine rejects; repair it here (modellint never emits `language`).
    let text = include_str!("data/sarif-schema-2.1.0.json")
        .replace("^[a-zA-Z]{2}|^[a-zA-Z]{2}-[a-zA-Z]{2}]?$", "^[a-zA-Z]{2}(-[a-zA-Z]{2})?$");
    let schema: serde_json::Value = serde_json::from_str(&text).unwrap();
    let validator = jsonschema::validator_for(&schema).expect("schema compiles");
    for model in
        ["models/asimov.xml", "fixtures/rules/toe-tilt/invalid.xml", "fixtures/broken/ok.xml"]
    {
        let (code, out, err) = modellint(&[model, "--format", "sarif", "--no-probe"]);
        assert!(code == 0 || code == 1, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let errors: Vec<String> =
            validator.iter_errors(&v).map(|e| format!("{e} at {}", e.instance_path())).collect();
        assert!(errors.is_empty(), "{model}: SARIF invalid:\n{}", errors.join("\n"));
        assert_eq!(v["version"], "2.1.0");
    }
    // The validator is not vacuous: a wrong level is rejected.
    let (_, out, _) = modellint(&["models/asimov.xml", "--format", "sarif", "--no-probe"]);
    let mut v: serde_json::Value = serde_json::from_str(&out).unwrap();
    v["runs"][0]["results"][0]["level"] = serde_json::json!("catastrophic");
    assert!(!validator.is_valid(&v));
}

#[test]
fn github_format_is_chosen_automatically_in_actions() {
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args(["models/asimov.xml", "--no-probe"])
        .env("GITHUB_ACTIONS", "true")
        .output()
        .unwrap();
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(s.lines().any(|l| l.starts_with("::error file=models/asimov.xml,line=")), "{s}");
}

#[test]
fn fail_on_and_select_control_the_exit_code() {
    let (code, _, _) = modellint(&["models/asimov.xml", "--no-probe", "--select", "toe-tilt"]);
    assert_eq!(code, 0, "the reference model's feet are flat");
    let (code, _, _) =
        modellint(&["models/asimov.xml", "--no-probe", "--ignore", "underdamped-pd-gains"]);
    assert_eq!(code, 0, "only info findings remain");
    let (code, _, _) = modellint(&[
        "models/asimov.xml",
        "--no-probe",
        "--ignore",
        "underdamped-pd-gains",
        "--fail-on",
        "info",
    ]);
    assert_eq!(code, 1);
}

#[test]
fn output_is_deterministic() {
    let a = modellint(&["models/asimov.xml", "--format", "json"]).1;
    let b = modellint(&["models/asimov.xml", "--format", "json"]).1;
    assert_eq!(a, b);
}

#[test]
fn rule_docs_are_generated_and_current() {
    let (code, _, err) = modellint(&["gen-docs", "--check", "--out", "docs/rules"]);
    assert_eq!(code, 0, "{err}");
    let (code, out, _) = modellint(&["rules"]);
    assert_eq!(code, 0);
    for id in [
        "actuator-mapping",
        "armature-mismatch",
        "parallel-ankle-armature",
        "toe-tilt",
        "foot-collision-geometry",
        "soft-limits",
        "underdamped-pd-gains",
        "effort-limit-mismatch",
        "passive-joint-spring",
        "gains-unstable-for-timestep",
        "mirror-asymmetry",
        "missing-action-delay",
        "self-collision-at-keyframe",
        "collision-visual-mismatch",
        "urdf-mjcf-drift",
    ] {
        assert!(out.contains(id), "`modellint rules` lacks {id}");
    }
}

/// `fit --help` lists every effect (from the registry) with its summary; `--effects` refuses an
/// unknown id and names the known ones.
#[test]
fn fit_help_lists_the_effects() {
    let (code, out, err) = modellint(&["fit", "--help"]);
    assert_eq!(code, 0, "{err}");
    let effects = modellint::fit::effects::all();
    assert_eq!(effects.len(), 18);
    for e in &effects {
        let summary = modellint::fit::effects::docs::summary(e.meta());
        assert!(out.contains(&format!("  {:<24} {summary}", e.id())), "{} missing:\n{out}", e.id());
    }
    assert!(out.contains("  viscous_damping "), "{out}");
    let (code, _, err) =
        modellint(&["fit", "fixtures/gap/arm3.xml", "fixtures/gap", "--effects", "viscous_dmping"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("unknown effect `viscous_dmping`") && err.contains("viscous_damping"),
        "{err}"
    );
}

/// `modellint docs TOPIC` serves every page of docs/ (python.md was missing), and `--fail-on`
/// takes `warn` as the config's `level` does.
#[test]
fn docs_topics_and_fail_on_spellings() {
    let mut pages: Vec<String> = std::fs::read_dir("docs")
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| n.strip_suffix(".md").map(str::to_string))
        .collect();
    pages.sort();
    for p in &pages {
        let (code, out, err) = modellint(&["docs", p]);
        assert_eq!(code, 0, "docs {p}: {err}");
        assert_eq!(out, std::fs::read_to_string(format!("docs/{p}.md")).unwrap(), "docs {p}");
    }
    let (w, _, _) = modellint(&["models/asimov.xml", "--no-probe", "--fail-on", "warning"]);
    let (w2, _, err) = modellint(&["models/asimov.xml", "--no-probe", "--fail-on", "warn"]);
    assert_eq!((w, w2), (1, 1), "{err}");
}

#[test]
fn fit_window_must_be_a_positive_length() {
    // `--window 0` used to turn windowing (and the friction re-fit) off without a word.
    for bad in ["0", "-1", "NaN", "inf"] {
        let w = format!("--window={bad}");
        let (code, _, err) = modellint(&["fit", "fixtures/gap/arm3.xml", "fixtures/gap", &w]);
        assert_eq!(code, 2, "--window {bad}: {err}");
        assert!(err.contains("positive number of seconds"), "--window {bad}: {err}");
    }
    // A control period written where the rate belongs is refused before any work.
    for cmd in ["fit", "gap"] {
        let (code, _, err) =
            modellint(&[cmd, "fixtures/gap/arm3.xml", "fixtures/gap", "--control-hz", "0.01"]);
        assert_eq!(code, 2, "{cmd}: {err}");
        assert!(err.contains("the rate is 100 Hz"), "{cmd}: {err}");
    }
}

#[test]
fn fit_holdout_by_checks_its_input() {
    // A directory without recordings: a precise error, exit 2 (also through the deprecated
    // --servo alias).
    let (code, _, err) =
        modellint(&["fit", "fixtures/bam_xl330/rig.xml", "fixtures/broken", "--servo", "xl330"]);
    assert_eq!(code, 2, "{err}");
    let data = std::path::Path::new("../shared/data/recordings/bam_xl330");
    if !data.is_dir() {
        eprintln!("skipping the BAM part: ../shared/data is absent");
        return;
    }
    let d = data.to_str().unwrap();
    let rig = "fixtures/bam_xl330/rig.xml";
    // A key no log has, a value no log has: exit 2 before any fitting, naming the values.
    let (code, _, err) = modellint(&["fit", rig, d, "--holdout-by", "nokey"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no recording has the key `nokey`") && err.contains("kp"), "{err}");
    let (code, _, err) = modellint(&["fit", rig, d, "--holdout-by", "kp=300"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("100, 200, 400, 800"), "{err}");
    // Rotation writes no model; --servo is the deprecated spelling of --holdout-by kp.
    let (code, _, err) = modellint(&["fit", rig, d, "--servo", "xl330", "--report", "/tmp/x"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("deprecated") && err.contains("--holdout-by kp=VALUE"), "{err}");
}

#[test]
fn urdf_models_load_with_spans() {
    let mut map = modellint::model::source::SourceMap::default();
    let p = std::path::Path::new("fixtures/rules/urdf-mjcf-drift/urdf/valid.urdf");
    let r = modellint::model::load(&mut map, p, None).expect("URDF compiles in MuJoCo");
    assert_eq!(r.format, modellint::model::Format::Urdf);
    let j = r.joints.iter().find(|j| j.is_scalar()).expect("a hinge joint");
    assert!(j.limited, "URDF <limit> becomes a MuJoCo range");
    let loc = r.elem_loc(modellint::model::mjcf::ElemKind::Joint, j.id, &j.name);
    assert_eq!(map.file(loc.file).path, p, "the joint points into the URDF");
    assert!(map.file(loc.file).text[loc.start..loc.end].starts_with("joint"));
}

#[test]
fn inline_suppressions_need_a_reason_and_unused_ones_are_reported() {
    let (_, out, _) =
        modellint(&["fixtures/suppress/suppressed.xml", "--no-probe", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let rules: Vec<&str> =
        v["findings"].as_array().unwrap().iter().map(|f| f["rule"].as_str().unwrap()).collect();
    assert!(!rules.contains(&"underdamped-pd-gains"), "suppressed with a reason: {rules:?}");
    assert!(
        rules.contains(&"unused-suppression"),
        "the toe-tilt suppression matched nothing: {rules:?}"
    );
    assert!(rules.contains(&"invalid-suppression"), "a suppression without a reason: {rules:?}");
    // Without the comment the finding is there: the suppression is what removed it.
    let text = std::fs::read_to_string("fixtures/suppress/suppressed.xml").unwrap();
    let without: String = text
        .lines()
        .filter(|l| !l.contains("ignore[underdamped-pd-gains]"))
        .collect::<Vec<_>>()
        .join("\n");
    let p = std::env::temp_dir().join(format!("modellint-unsup-{}.xml", std::process::id()));
    std::fs::write(&p, without).unwrap();
    let (_, out, _) = modellint(&[p.to_str().unwrap(), "--no-probe", "--format", "json"]);
    assert!(out.contains("\"underdamped-pd-gains\""));
}

/// A suppression written inside `<default>`, where the gains are set, works like one on the
/// element: it removes the finding that points at the class's attribute, and an unused or
/// misspelled one there is reported (it was silently ignored).
#[test]
fn suppressions_inside_default_classes_are_applied_and_checked() {
    let (_, out, _) =
        modellint(&["fixtures/suppress/in_default.xml", "--no-probe", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let found: Vec<(String, String)> = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| (f["rule"].as_str().unwrap().to_string(), f["message"].to_string()))
        .collect();
    let has = |rule: &str, text: &str| found.iter().any(|(r, m)| r == rule && m.contains(text));
    assert!(!has("underdamped-pd-gains", "`hinge` "), "suppressed in class servo: {found:?}");
    assert!(has("underdamped-pd-gains", "`hinge2`"), "not suppressed (misspelled): {found:?}");
    assert!(has("invalid-suppression", "underdamped-pd-gain`"), "{found:?}");
    // The closest rule ids, as `--select` offers them.
    assert!(has("invalid-suppression", "(did you mean underdamped-pd-gains"), "{found:?}");
    assert!(has("unused-suppression", "soft-limits"), "{found:?}");
}

/// A suppression comment on a body's `<inertial>` covers the body's mass-property findings and
/// is checked like any other (it was neither applied nor reported).
#[test]
fn suppressions_on_an_inertial_are_applied_and_checked() {
    let (_, out, _) =
        modellint(&["fixtures/suppress/on_inertial.xml", "--no-probe", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let found: Vec<(String, String)> = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| (f["rule"].as_str().unwrap().to_string(), f["message"].to_string()))
        .collect();
    let has = |rule: &str, text: &str| found.iter().any(|(r, m)| r == rule && m.contains(text));
    assert!(!has("isotropic-base-inertia", "`trunk` "), "suppressed on trunk: {found:?}");
    assert!(has("isotropic-base-inertia", "`trunk2`"), "not suppressed (misspelled): {found:?}");
    assert!(has("invalid-suppression", "isotropic-base-inertai`"), "{found:?}");
    assert!(has("invalid-suppression", "(did you mean isotropic-base-inertia"), "{found:?}");
    assert!(has("unused-suppression", "isotropic-base-inertia"), "{found:?}");
}

#[test]
fn config_thresholds_and_errors() {
    let m = "fixtures/probes/servo_underdamped.xml";
    let (_, out, _) =
        modellint(&[m, "--no-probe", "--format", "json", "--select", "underdamped-pd-gains"]);
    assert!(out.contains("\"underdamped-pd-gains\""));
    let (code, out, err) = modellint(&[
        m,
        "--no-probe",
        "--format",
        "json",
        "--select",
        "underdamped-pd-gains",
        "--config",
        "fixtures/config/loose.toml",
    ]);
    assert_eq!(code, 0, "{err}");
    // (the rule id also appears in `spec.weakened_rules`: look at the findings only)
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        !v["findings"].as_array().unwrap().iter().any(|f| f["rule"] == "underdamped-pd-gains"),
        "threshold 0.2 < ζ 0.22"
    );
    let (code, _, err) = modellint(&[m, "--config", "fixtures/config/bad_option.toml"]);
    assert_eq!(code, 2);
    // The error points at the bad key's line (2), not at the `[rules.x]` header (1).
    assert!(err.contains("bad_option.toml:2:") && err.contains("min_damping"), "{err}");
    // A number written as a string: the message says what is expected (no empty "()").
    let (code, _, err) = modellint(&[m, "--config", "fixtures/config/quoted_number.toml"]);
    assert_eq!(code, 2, "{err}");
    let flat_q = err.split_whitespace().filter(|w| *w != "│").collect::<Vec<_>>().join(" ");
    assert!(
        err.contains("quoted_number.toml:3:")
            && flat_q.contains("min_damping_ratio must be a number > 0; got \"0.3\"")
            && flat_q.contains("without quotes")
            && !err.contains("()"),
        "{err}"
    );
    let (code, _, err) = modellint(&[m, "--config", "fixtures/config/bad_rule.toml"]);
    assert_eq!(code, 2);
    assert!(err.contains("bad_rule.toml:2:") && err.contains("no-such-rule"), "{err}");
    // An option that takes one of a few values (a contact dimension) names them.
    let (code, _, err) = modellint(&[m, "--config", "fixtures/config/bad_condim.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("bad_condim.toml:3:")
            && err.contains("must be one of")
            && err.contains("got 2"),
        "{err}"
    );
    // Every numeric option has a domain: a value outside it is rejected at its line, with the
    // domain named (a negative radius, a tolerance of the whole range), at the key's line.
    // (the message may wrap: compare it with its words joined, the frame's `│` dropped)
    let flat = |e: &str| e.split_whitespace().filter(|w| *w != "│").collect::<Vec<_>>().join(" ");
    let (code, _, err) = modellint(&[m, "--config", "fixtures/config/bad_min_radius.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("bad_min_radius.toml:3:")
            && flat(&err).contains("min_radius must be ≥ 0 (m), got -0.001"),
        "{err}"
    );
    let (code, _, err) = modellint(&[m, "--config", "fixtures/config/bad_fraction.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("bad_fraction.toml:3:")
            && flat(&err)
                .contains("tolerance must be ≥ 0 and < 1 (fraction of joint range), got 1.0"),
        "{err}"
    );
}

/// Recording metadata that cannot be right: exit 2 from `gap` and `fit` with file:line.
#[test]
fn bad_recording_timing_metadata_exits_2_with_file_and_line() {
    let dir = std::env::temp_dir().join(format!("modellint_meta_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bam_xl330/rig.xml");
    let cases = [
        (
            "split.csv",
            "# robot: rig\n# split: validation\nt,servo.q,servo.q_cmd\n0,0,0\n0.01,0,0\n",
            2,
            "train",
        ),
        (
            "rate.csv",
            "# control_rate_hz: 0\nt,servo.q,servo.q_cmd\n0,0,0\n0.01,0,0\n",
            1,
            "positive",
        ),
        (
            "negrate.csv",
            "# control_rate_hz: -100\nt,servo.q,servo.q_cmd\n0,0,0\n0.01,0,0\n",
            1,
            "positive",
        ),
        (
            "onetick.csv",
            "# a: b\n# c: d\n# control_rate_hz: 2\nt,servo.q,servo.q_cmd\n0,0,0\n0.1,0,0\n0.2,0,0\n0.49,0,0\n",
            3,
            "one control tick",
        ),
        (
            "timing.csv",
            "# command_timing: before\nt,servo.q,servo.q_cmd\n0,0,0\n0.01,0,0\n",
            1,
            "sent_after",
        ),
        // A 100 Hz log of a 100 Hz controller, times in milliseconds: 1000 ticks per row.
        (
            "millis.csv",
            "# control_rate_hz: 100\nt,servo.q,servo.q_cmd\n0,0,0\n10,0,0\n20,0,0\n",
            1,
            "in seconds",
        ),
    ];
    for (name, text, line, what) in cases {
        let f = dir.join(name);
        std::fs::write(&f, text).unwrap();
        for sub in ["gap", "fit"] {
            let (code, _, err) = modellint(&[sub, model, f.to_str().unwrap()]);
            assert_eq!(code, 2, "{sub} {name}: exit {code}\n{err}");
            let loc = format!("{}:{line}:", f.display());
            assert!(
                err.contains(&loc) && err.contains(what),
                "{sub} {name}: want `{loc}` and `{what}` in:\n{err}"
            );
            assert!(!err.contains("panicked"), "{err}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A log with extra signals (an IMU, a temperature per joint): exit 2 at the header line naming
/// the column and `--ignore-columns`; with the patterns, `gap` runs and prints what it found.
#[test]
fn extra_columns_are_skipped_with_ignore_columns() {
    let dir = std::env::temp_dir().join(format!("modellint_extra_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bam_xl330/rig.xml");
    let f = dir.join("extra.csv");
    let mut text = String::from("# robot: rig\nt,servo.q,servo.q_cmd,imu.wx,servo.temperature\n");
    for i in 0..200 {
        let t = i as f64 * 0.01;
        text.push_str(&format!("{t:.2},0,{:.3},0.5,41\n", if t < 1.0 { 0.0 } else { 0.2 }));
    }
    std::fs::write(&f, text).unwrap();
    let path = f.to_str().unwrap();
    let (code, _, err) = modellint(&["gap", model, path]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!("{path}:2:")) && err.contains("--ignore-columns '*.wx'"),
        "{err}"
    );
    let (code, out, err) =
        modellint(&["gap", model, path, "--ignore-columns", "imu.*,*.temperature"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("gap: 1 episode(s), 200 samples"), "{out}");
    let (code, _, err) =
        modellint(&["gap", model, path, "--ignore-columns", "a[", "--ignore-columns", "imu.*"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--ignore-columns a["), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `gap DIR --format json > DIR/gap.json` run twice: the shell creates the empty gap.json before
/// modellint reads the directory; it and the report it then holds are skipped with a note (and
/// in the JSON), not read as a broken BAM log.
#[test]
fn a_report_written_into_the_data_directory_is_not_read_as_a_recording() {
    let dir = std::env::temp_dir().join(format!("modellint_selfjson_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bam_xl330/rig.xml");
    let mut text = String::from("# robot: rig\nt,servo.q,servo.q_cmd\n");
    for i in 0..200 {
        let t = i as f64 * 0.01;
        text.push_str(&format!("{t:.2},0,{:.3}\n", if t < 1.0 { 0.0 } else { 0.2 }));
    }
    std::fs::write(dir.join("run.csv"), text).unwrap();
    let report = dir.join("gap.json");
    std::fs::write(&report, "").unwrap();
    let d = dir.to_str().unwrap();
    let (code, out, err) = modellint(&["gap", model, d, "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("not read") && err.contains("gap.json"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["notes"][0].as_str().unwrap().contains("gap.json"), "{out}");
    std::fs::write(&report, &out).unwrap();
    let (code, again, err) = modellint(&["gap", model, d, "--format", "json"]);
    assert_eq!((code, again), (0, out), "{err}");
    // Named on the command line, it is read (and is not a recording).
    let (code, _, err) = modellint(&["gap", model, report.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `fit --holdout-by KEY` end to end on recordings made by the independent synth (a clean
/// pendulum servo, nothing concealed), two episodes per value of a header key: two folds, every
/// episode held out exactly once, nothing kept (the truth), and the overall mean equal to the
/// mean of the per-episode MAEs printed.
#[test]
fn holdout_by_rotates_over_the_values_of_a_key() {
    let dir = std::env::temp_dir().join(format!("modellint_rotation_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_str().unwrap();
    let model = "fixtures/synth/pendulum_servo.xml";
    let args =
        ["synth", model, "--episodes", "4", "--duration", "3", "--heldout", "0", "--out", out];
    let (code, _, err) = modellint(&[&args[..], &["--quiet"]].concat());
    assert_eq!(code, 0, "{err}");
    for i in 0..4 {
        let f = dir.join(format!("episodes/ep_{i:02}.csv"));
        let text = std::fs::read_to_string(&f).unwrap();
        let batch = if i < 2 { "a" } else { "b" };
        std::fs::write(&f, format!("# batch: {batch}\n{text}")).unwrap();
    }
    let eps = dir.join("episodes");
    let (code, stdout, err) = modellint(&[
        "fit",
        model,
        eps.to_str().unwrap(),
        "--holdout-by",
        "batch",
        "--format",
        "json",
        "--quiet",
    ]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let folds = v["folds"].as_array().unwrap();
    let values: Vec<&str> = folds.iter().map(|f| f["value"].as_str().unwrap()).collect();
    assert_eq!(values, ["a", "b"]);
    let mut held: Vec<&str> = Vec::new();
    let mut maes = Vec::new();
    for f in folds {
        assert_eq!(f["train"], 2, "{f}");
        assert!(f["selected"].as_array().unwrap().is_empty(), "invented physics: {f}");
        for e in f["heldout"].as_array().unwrap() {
            held.push(e["source"].as_str().unwrap());
            maes.push(e["position_mae_before"].as_f64().unwrap());
        }
    }
    held.sort();
    assert_eq!(held, ["ep_00.csv", "ep_01.csv", "ep_02.csv", "ep_03.csv"]);
    let mean = maes.iter().sum::<f64>() / maes.len() as f64;
    assert!((v["position_mae_before"].as_f64().unwrap() - mean).abs() < 1e-12, "{v}");
    assert_eq!(v["episodes"], 4);
}

/// `--output-format concise`: one `file:line:col: level rule message` line per finding, and
/// `--statistics` counts them per rule.
#[test]
fn concise_output_and_statistics() {
    let (code, out, _) = modellint(&[
        "fixtures/rules/soft-limits/invalid.xml",
        "--no-probe",
        "--output-format",
        "concise",
        "--statistics",
    ]);
    assert_eq!(code, 1, "{out}");
    let lines: Vec<&str> = out.lines().collect();
    let findings: Vec<&str> =
        lines.iter().copied().filter(|l| l.starts_with("fixtures/")).collect();
    assert!(!findings.is_empty(), "{out}");
    for l in &findings {
        let mut parts = l.splitn(4, ':');
        let (file, line, col, rest) =
            (parts.next().unwrap(), parts.next().unwrap(), parts.next().unwrap(), parts.next());
        assert_eq!(file, "fixtures/rules/soft-limits/invalid.xml");
        assert!(line.parse::<usize>().is_ok() && col.parse::<usize>().is_ok(), "{l}");
        let rest = rest.unwrap().trim_start();
        let level = rest.split(' ').next().unwrap();
        assert!(["error", "warning", "info"].contains(&level), "{l}");
    }
    // The statistics: one row per rule with its count, and the total.
    let total = lines.iter().find(|l| l.trim_end().ends_with("total")).expect("a total line");
    assert_eq!(total.split_whitespace().next().unwrap(), findings.len().to_string());
    let soft = findings.iter().filter(|l| l.contains(" soft-limits ")).count();
    let row = lines.iter().find(|l| l.split_whitespace().nth(1) == Some("soft-limits")).unwrap();
    assert_eq!(row.split_whitespace().next().unwrap(), soft.to_string());
    // Same findings, same order as the text output's count.
    let (_, text, _) = modellint(&["fixtures/rules/soft-limits/invalid.xml", "--no-probe"]);
    let summary = text.lines().last().unwrap();
    let n: usize = summary
        .split([':', ','])
        .filter_map(|p| p.split_whitespace().next().and_then(|x| x.parse::<usize>().ok()))
        .sum();
    assert_eq!(n, findings.len(), "{summary}");
}

/// A scene and the robot file it includes, both given (as a hook passes every staged file):
/// the robot is linted once, inside the scene, and no finding is printed twice.
#[test]
fn a_scene_and_its_robot_file_are_linted_once() {
    let (_, out, err) = modellint(&[
        "fixtures/include/scene.xml",
        "fixtures/include/robot.xml",
        "--no-probe",
        "--output-format",
        "concise",
    ]);
    assert!(
        err.contains("skipping fixtures/include/robot.xml: included by fixtures/include/scene.xml"),
        "{err}"
    );
    let lines: Vec<&str> = out.lines().collect();
    let mut uniq = lines.clone();
    uniq.sort();
    uniq.dedup();
    assert_eq!(uniq.len(), lines.len(), "duplicated findings:\n{out}");
    // The robot alone gives the same robot-file findings as the scene pass (not fewer).
    let (_, alone, _) =
        modellint(&["fixtures/include/robot.xml", "--no-probe", "--output-format", "concise"]);
    assert!(!alone.is_empty() && !out.is_empty());
    // Given twice, one model is linted once.
    let (_, twice, _) = modellint(&[
        "fixtures/include/robot.xml",
        "fixtures/include/robot.xml",
        "--no-probe",
        "--output-format",
        "concise",
    ]);
    assert_eq!(twice, alone);
    // The pre-commit hook uses the concise form.
    let hooks = std::fs::read_to_string(".pre-commit-hooks.yaml").unwrap();
    assert!(
        hooks.contains("entry: modellint --no-probe --skip-non-models --output-format concise"),
        "{hooks}"
    );
    // ... and runs on a staged spec too (it lints the model beside it).
    assert!(hooks.contains("files: \\.(xml|urdf|toml)$"), "{hooks}");
}

/// The lint cache stays under its cap (least recently used out) and `cache clean`
/// empties it.
#[test]
fn cache_is_capped_and_cleaned() {
    let dir = std::env::temp_dir().join(format!("modellint-cli-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_str().unwrap();
    let run = |model: &str, cap_mb: &str| {
        Command::new(env!("CARGO_BIN_EXE_modellint"))
            .args([model, "--no-probe", "--cache-dir", d])
            .env("MODELLINT_CACHE_MAX_MB", cap_mb)
            .output()
            .unwrap()
    };
    let count = || {
        std::fs::read_dir(&dir)
            .map(|r| {
                r.filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "lint"))
                    .count()
            })
            .unwrap_or(0)
    };
    // Entries are the printed results: invalid.xml 3 kB, the scene 8.6 kB, valid.xml 1.7 kB.
    run("fixtures/rules/soft-limits/invalid.xml", "100");
    run("fixtures/include/scene.xml", "100");
    assert_eq!(count(), 2);
    // A cap of 0.004 MB holds the small valid.xml entry alone: the older two are evicted.
    run("fixtures/rules/soft-limits/valid.xml", "0.004");
    assert_eq!(count(), 1);
    // --cache-max beside the variable, and before it: the flag's 100 MB keeps both entries
    // although the variable says 0.004 MB.
    let with_flag = |model: &str, flag: &str, env: &str, more: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_modellint"))
            .args([model, "--no-probe", "--cache-dir", d, "--cache-max", flag])
            .args(more)
            .env("MODELLINT_CACHE_MAX_MB", env)
            .output()
            .unwrap()
    };
    with_flag("fixtures/rules/soft-limits/invalid.xml", "100", "0.004", &[]);
    assert_eq!(count(), 2);
    // Another result (with --statistics, a new entry) under the flag's 0.004 MB: alone again.
    with_flag("fixtures/rules/soft-limits/valid.xml", "0.004", "100", &["--statistics"]);
    assert_eq!(count(), 1);
    let bad = with_flag("fixtures/include/scene.xml", "-3", "100", &[]);
    assert_eq!(bad.status.code(), Some(2));
    let (code, out, _) = modellint(&["cache", "clean", "--dir", d]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("removed 1 cache entry"), "{out}");
    assert_eq!(count(), 0);
    // The lint's own flag is accepted as well.
    let (code, out, err) = modellint(&["cache", "clean", "--cache-dir", d]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("removed 0 cache entries"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// An unnamed world geom is named by its rank among the world geoms of its own file and by
/// MuJoCo's geom id: the scene's floor and box come before the included robot file's world
/// geoms, so the solref box (the robot file's 2nd world geom) is MuJoCo's geom 3 (checked with
/// MuJoCo's Python bindings: `MjModel.from_xml_path(scene).geom_solref[3]` is 0.0005). It was
/// "no. 4 of body `world`": neither file's order nor MuJoCo's id.
#[test]
fn an_unnamed_world_geom_is_named_as_its_file_and_mujoco_number_it() {
    let (_, out, err) = modellint(&[
        "fixtures/model/world_geoms/scene.xml",
        "--no-cache",
        "--select",
        "solref-below-timestep",
        "--format",
        "json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {err}"));
    let findings = v["findings"].as_array().expect("findings");
    let world: Vec<&str> = findings
        .iter()
        .filter_map(|f| f["message"].as_str())
        .filter(|m| m.contains("world body"))
        .collect();
    assert_eq!(world.len(), 1, "{out}");
    assert!(
        world[0]
            .starts_with("geom no. 2 of the world body in its file (MuJoCo geom id 3)'s contact"),
        "{}",
        world[0]
    );
    let f = findings.iter().find(|f| f["message"].as_str() == Some(world[0])).unwrap();
    assert_eq!(
        (f["file"].as_str(), f["line"].as_u64()),
        (Some("fixtures/model/world_geoms/robot.xml"), Some(5)),
        "{f}"
    );
}

/// `--package` is offered where a model is loaded (it resolves a URDF's `package://` meshes) and
/// nowhere else: it was a global flag shown in every subcommand's --help, doing nothing there.
#[test]
fn package_is_an_option_only_where_a_model_is_loaded() {
    let takes = |args: &[&str]| {
        let (c, out, err) = modellint(args);
        assert_eq!(c, 0, "{args:?}: {err}");
        out.contains("--package <NAME=DIR>")
    };
    for sub in ["init-spec", "gap", "fit", "synth"] {
        assert!(takes(&[sub, "--help"]), "{sub} --help lacks --package");
    }
    assert!(takes(&["--help"]), "the lint's --help lacks --package");
    for sub in ["rules", "rule", "gen-docs", "convert", "docs"] {
        assert!(!takes(&[sub, "--help"]), "{sub} --help offers --package");
    }
    assert!(!takes(&["cache", "clean", "--help"]), "cache clean --help offers --package");
    let (c, _, err) = modellint(&["rules", "--package", "a=b"]);
    assert!(c == 2 && err.contains("--package"), "{err}");
}

/// `--version` names the commit the binary was built from (`git rev-parse --short HEAD` of the
/// checkout; cargo rebuilds when HEAD moves), and only the package version without git.
#[test]
fn version_names_the_commit() {
    let (c, out, err) = modellint(&["--version"]);
    assert_eq!(c, 0, "{err}");
    let pkg = format!("modellint {}", env!("CARGO_PKG_VERSION"));
    let head = Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    match head {
        Some(h) => assert_eq!(out.trim(), format!("{pkg} (commit {h})")),
        None => assert_eq!(out.trim(), pkg),
    }
}

/// A URDF with several inertias MuJoCo rejects: MuJoCo names one; the load error lists every
/// one with its line and why (a negative principal moment, A + B < C, a moving link with mass
/// and no inertia), and not the foot whose zero inertia the fixed sole makes up for.
#[test]
fn urdf_load_error_lists_every_rejected_inertia() {
    let m = load_error("fixtures/broken/urdf_inertia_many_rejected.urdf");
    for want in [
        "the file states 3 inertials it rejects",
        "link `thigh` (line 13): principal moments -",
        "link `shin` (line 20): principal moments 4.400e-6 + 4.400e-6 < 4.000e-5 kg·m² (A + B ≥ C fails",
        "link `ankle` (line 27): moves on a joint with mass 0.3 kg and no inertia",
    ] {
        assert!(m.contains(want), "load error lacks `{want}`:\n{m}");
    }
    assert!(!m.contains("link `foot`"), "the foot's fused sole carries inertia:\n{m}");
    // One rejected inertia: MuJoCo's own message, no list.
    let one = load_error("fixtures/broken/urdf_inertia_not_positive.urdf");
    assert!(!one.contains("inertials it rejects"), "{one}");
}
