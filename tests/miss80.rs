//! The classes of issue 45 the seventeenth round left open, end to end from the CLI. Bad input:
//! a numeric attribute of a URDF or MJCF model that does not read as numbers is an error at the
//! file, line and column of its value (exit 2), never a silent "not stated". Mirror pairs that
//! collide differently (`mirror-asymmetry`), and a robot file without a floor whose feet start
//! below z = 0 (`keyframe-state`). Expected places, names, counts and depths are worked out here
//! from the written text, not read from the tool.

mod common;

use std::path::PathBuf;
use std::process::Command;

use common::lint::{findings, measured, message, of, of_message};
use common::xml_text::{attr, tags};

/// A small URDF: every numeric attribute the URDF specification defines, each once, written so
/// that `attr="value"` is unique in the text.
const URDF: &str = r#"<robot name="r">
  <link name="base">
    <inertial><origin xyz="0 0 0.01" rpy="0 0 0"/><mass value="2"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <collision><origin xyz="0 0 0.02" rpy="0 0 0.1"/><geometry><cylinder radius="0.05" length="0.2"/></geometry></collision>
  </link>
  <link name="a">
    <inertial><mass value="1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
    <visual><geometry><sphere radius="0.04"/></geometry><material name="m"><color rgba="1 0 0 1"/></material></visual>
    <collision><geometry><box size="0.06 0.05 0.04"/></geometry></collision>
  </link>
  <joint name="j" type="revolute"><origin xyz="0 0 0.15" rpy="0 0.1 0"/>
    <parent link="base"/><child link="a"/><axis xyz="0 1 0"/>
    <limit lower="-1.2" upper="1.3" effort="7" velocity="5"/>
    <dynamics damping="0.3" friction="0.04"/>
    <safety_controller soft_lower_limit="-1.1" soft_upper_limit="1.2" k_position="10" k_velocity="2"/>
  </joint>
</robot>
"#;

/// The same in MJCF, with the numeric attributes MuJoCo's schema reads on bodies, joints,
/// geoms, inertials and actuators.
const MJCF: &str = r#"<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="base" pos="0 0 0.5">
      <freejoint/>
      <inertial pos="0 0 0" mass="2" diaginertia="0.02 0.03 0.04"/>
      <geom type="box" size="0.1 0.1 0.05" friction="0.8 0.01 0.001"/>
      <body name="arm" pos="0 0 0.1" euler="0 0 0.2">
        <joint name="j" axis="0 1 0" range="-1.1 1.1" damping="0.3" armature="0.01"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.02" mass="0.4"/>
      </body>
    </body>
  </worldbody>
  <actuator><position joint="j" kp="20" ctrlrange="-1 1" forcerange="-5 5"/></actuator>
</mujoco>
"#;

/// (written attribute, substitute): each replaces the one `attr="value"` of the model text.
const URDF_CASES: &[(&str, &str)] = &[
    ("velocity=\"5\"", "velocity=\"abc\""),
    ("effort=\"7\"", "effort=\"7Nm\""),
    ("lower=\"-1.2\"", "lower=\"-1,2\""),
    ("upper=\"1.3\"", "upper=\"pi\""),
    ("damping=\"0.3\"", "damping=\"x\""),
    ("friction=\"0.04\"", "friction=\"0.04 0.1\""),
    ("<mass value=\"2\"", "<mass value=\"two\""),
    ("iyy=\"0.02\"", "iyy=\"1e\""),
    ("xyz=\"0 0 0.15\"", "xyz=\"0 0 ${h}\""),
    ("rpy=\"0 0.1 0\"", "rpy=\"0 0.1\""),
    ("<axis xyz=\"0 1 0\"", "<axis xyz=\"0 1 0 0\""),
    ("size=\"0.06 0.05 0.04\"", "size=\"0.06 0.05 O.04\""),
    ("length=\"0.2\"", "length=\"-\""),
    ("k_velocity=\"2\"", "k_velocity=\"fast\""),
    ("rgba=\"1 0 0 1\"", "rgba=\"red\""),
];

const MJCF_CASES: &[(&str, &str)] = &[
    ("damping=\"0.3\"", "damping=\"abc\""),
    ("range=\"-1.1 1.1\"", "range=\"-1.1 1x\""),
    ("mass=\"0.4\"", "mass=\"q\""),
    ("<body name=\"base\" pos=\"0 0 0.5\"", "<body name=\"base\" pos=\"0 0 high\""),
    ("diaginertia=\"0.02 0.03 0.04\"", "diaginertia=\"0.02 0.03 ..\""),
    ("kp=\"20\"", "kp=\"20,\""),
    ("friction=\"0.8 0.01 0.001\"", "friction=\"0.8 0.01 0.001 7\""),
    ("timestep=\"0.002\"", "timestep=\"2ms\""),
];

fn tmp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("modellint-miss80-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `modellint FILE --no-probe --no-cache --format concise`: (exit code, stderr).
fn lint(path: &std::path::Path) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg(path)
        .args(["--no-probe", "--no-cache", "--format", "concise"])
        .env_remove("GITHUB_ACTIONS")
        .output()
        .unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// 1-based line and column (bytes; the texts are ASCII) of the value of the substituted
/// attribute: just after its (last) `="`.
fn value_place(text: &str, written: &str) -> (usize, usize) {
    let at = text.find(written).unwrap();
    let value = at + written.rfind("=\"").unwrap() + 2;
    let line = text[..value].matches('\n').count() + 1;
    let col = value - text[..value].rfind('\n').map_or(0, |k| k + 1) + 1;
    (line, col)
}

/// The substituted attribute's name: the last one written.
fn attr_name(written: &str) -> &str {
    let eq = written.rfind('=').unwrap();
    written[..eq].rsplit([' ', '<']).next().unwrap()
}

#[test]
fn the_models_load_as_written() {
    let dir = tmp_dir("clean");
    for (name, text) in [("m.urdf", URDF), ("m.xml", MJCF)] {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        let (code, err) = lint(&p);
        assert!(code == 0 || code == 1, "{name}: exit {code}\n{err}");
    }
}

/// Each bad value, URDF and MJCF: exit 2, the error at the value's line and column, naming the
/// attribute and the written text (also `<limit velocity>`, which MuJoCo does not read).
#[test]
fn a_value_that_is_not_numbers_is_an_error_at_its_place() {
    let dir = tmp_dir("bad");
    for (ext, text, cases) in [("urdf", URDF, URDF_CASES), ("xml", MJCF, MJCF_CASES)] {
        for (i, (written, bad)) in cases.iter().enumerate() {
            assert_eq!(text.matches(written).count(), 1, "{written}");
            let broken = text.replacen(written, bad, 1);
            let p = dir.join(format!("case{i}.{ext}"));
            std::fs::write(&p, &broken).unwrap();
            let (code, err) = lint(&p);
            assert_eq!(code, 2, "{bad}: exit {code}\n{err}");
            let (line, col) = value_place(&broken, bad);
            let place = format!("case{i}.{ext}:{line}:{col}:");
            assert!(err.contains(&place), "{bad}: expected {place}\n{err}");
            let name = attr_name(bad);
            assert!(err.contains(&format!("'{name}'")), "{bad}: names no `{name}`\n{err}");
            let value = &bad[bad.rfind("=\"").unwrap() + 2..bad.len() - 1];
            assert!(err.contains(value), "{bad}: quotes no \"{value}\"\n{err}");
        }
    }
}

/// Values MuJoCo's compiler reads (C `strtod` syntax, surrounding blanks) or reads as not
/// stated (empty) are no error.
#[test]
fn values_mujoco_reads_are_no_error() {
    let dir = tmp_dir("good");
    let cases: &[(&str, &str)] = &[
        ("velocity=\"5\"", "velocity=\"0x1.4p2\""),
        ("effort=\"7\"", "effort=\" 7 \""),
        ("upper=\"1.3\"", "upper=\"+1.3\""),
        ("lower=\"-1.2\"", "lower=\"-12e-1\""),
        ("velocity=\"5\"", "velocity=\"\""),
        ("damping=\"0.3\"", "damping=\".3\""),
    ];
    for (i, (written, good)) in cases.iter().enumerate() {
        let p = dir.join(format!("good{i}.urdf"));
        std::fs::write(&p, URDF.replacen(written, good, 1)).unwrap();
        let (code, err) = lint(&p);
        assert!(code == 0 || code == 1, "{good}: exit {code}\n{err}");
    }
}

/// Garbage in every numeric attribute of both models: the tool exits 0, 1 or 2 and never
/// panics; an exit 2 always names a line of the file.
#[test]
fn garbage_values_never_panic() {
    const GARBAGE: &[&str] = &[
        "",
        " ",
        "nan",
        "-inf",
        "1e999",
        "0x",
        "--1",
        "1..2",
        "\u{00e9}",
        "1 2 3 4 5 6 7 8 9",
        "1e-400",
        "-0",
        "&#x30;",
        "1\t2",
        "+",
        ".",
        "e5",
        "0x1p",
        "9999999999999999999999",
    ];
    let dir = tmp_dir("fuzz");
    let mut runs = 0;
    for (ext, text, cases) in [("urdf", URDF, URDF_CASES), ("xml", MJCF, MJCF_CASES)] {
        for (i, (written, _)) in cases.iter().enumerate() {
            let name = attr_name(written);
            let head = &written[..written.rfind('=').unwrap()];
            // Spread the garbage over the attributes: a fixed stride, every value used.
            for (k, g) in GARBAGE.iter().enumerate().filter(|(k, _)| (k + i) % 4 == 0) {
                let broken = text.replacen(written, &format!("{head}=\"{g}\""), 1);
                let p = dir.join(format!("fuzz{i}_{k}.{ext}"));
                std::fs::write(&p, &broken).unwrap();
                let (code, err) = lint(&p);
                runs += 1;
                assert!((0..=2).contains(&code), "{name}={g:?}: exit {code}\n{err}");
                assert!(!err.contains("panicked"), "{name}={g:?}: {err}");
                if code == 2 {
                    let file = format!("fuzz{i}_{k}.{ext}:");
                    assert!(err.contains(&file), "{name}={g:?}: no place\n{err}");
                }
            }
        }
    }
    assert!(runs >= 100, "{runs}");
}

const MA: &str = "fixtures/rules/mirror-asymmetry/";
const KS: &str = "fixtures/rules/keyframe-state/";

/// The `mirror-asymmetry` findings about collision filtering.
fn filtering(file: &str) -> Vec<serde_json::Value> {
    of_message(file, "mirror-asymmetry", "collides differently")
}

/// Each `<body name=…>` of the text, in order, with the `conaffinity` of the first geom written
/// after it (the body's own geom in these fixtures).
fn body_masks(text: &str) -> Vec<(String, String)> {
    let mut v = Vec::new();
    for (i, _) in text.match_indices("<body name=\"") {
        let name = attr(&text[i..], "name").unwrap().to_string();
        let g = &text[i + text[i..].find("<geom ").unwrap()..];
        let mask = attr(g, "conaffinity").unwrap_or("1").to_string();
        v.push((name, mask));
    }
    v
}

/// A part-numbered biped whose legs differ in conaffinity (Kayra's class): one finding, naming
/// the first left body in the file whose partner (`R` for `L` beside the part number) has other
/// masks, and that body's partner, with the count of such pairs.
#[test]
fn mirror_pairs_with_other_collision_masks_are_named() {
    let file = format!("{MA}invalid_collision_masks_by_side.xml");
    let text = std::fs::read_to_string(&file).unwrap();
    let bodies = body_masks(&text);
    let mask = |n: &str| bodies.iter().find(|(b, _)| b == n).map(|(_, m)| m.clone());
    let differing: Vec<(String, String)> = bodies
        .iter()
        .filter(|(n, _)| n.as_bytes()[0].is_ascii_digit() && n.as_bytes()[1] == b'L')
        .map(|(n, _)| (n.clone(), n.replacen('L', "R", 1)))
        .filter(|(l, r)| mask(r).is_some() && mask(l) != mask(r))
        .collect();
    assert_eq!(differing.len(), 3, "{bodies:?}");
    let found = filtering(&file);
    assert_eq!(found.len(), 1, "{found:#?}");
    let m = message(&found[0]);
    let (l, r) = &differing[0];
    assert!(
        m.starts_with(&format!("body `{r}` collides differently from its mirror `{l}`")),
        "{m}"
    );
    assert_eq!(found[0]["data"]["differing_pairs"].as_f64(), Some(differing.len() as f64));
    // Both masks are quoted from the file.
    for b in [l, r] {
        assert!(m.contains(&format!("conaffinity {}", mask(b).unwrap())), "{m}");
    }
}

/// An `<exclude>` written for one side only: the two excluded bodies' pairs differ, and the
/// finding names one of them with its mirror.
#[test]
fn an_exclude_on_one_side_only_is_named() {
    let file = format!("{MA}invalid_exclude_one_side.xml");
    let text = std::fs::read_to_string(&file).unwrap();
    let ex = tags(&text, "exclude");
    assert_eq!(ex.len(), 1);
    let sides: Vec<&str> = ["body1", "body2"].iter().map(|k| attr(ex[0], k).unwrap()).collect();
    let found = filtering(&file);
    assert_eq!(found.len(), 1, "{found:#?}");
    let m = message(&found[0]);
    assert!(
        sides.iter().any(|l| {
            let r = l.replacen("left", "right", 1);
            m.starts_with(&format!("body `{r}` collides differently from its mirror `{l}`"))
        }),
        "{m}"
    );
    assert_eq!(found[0]["data"]["differing_pairs"].as_f64(), Some(sides.len() as f64));
}

/// Side bits that mirror each other, excludes and pairs on both sides, unpaired side parts, and
/// a quadruped whose front legs touch each other and rear legs do not: no filtering finding.
#[test]
fn mirrored_collision_filtering_passes() {
    for f in ["valid_collision_masks_mirrored.xml", "valid_quadruped_masks_per_leg.xml"] {
        let file = format!("{MA}{f}");
        assert!(filtering(&file).is_empty(), "{f}: {:#?}", filtering(&file));
    }
}

/// The lowest point of the fixtures' quadruped legs below its trunk origin, from the written
/// text: the first hip body's `pos` z, the two capsules' `fromto` lengths, the foot's radius.
fn leg_reach(text: &str) -> f64 {
    let z = |v: &str| v.split_whitespace().nth(2).unwrap().parse::<f64>().unwrap();
    let hip = tags(text, "body").into_iter().find(|t| attr(t, "name") == Some("fl_hip")).unwrap();
    let caps: Vec<f64> = tags(text, "geom")
        .into_iter()
        .filter_map(|t| attr(t, "fromto"))
        .take(2)
        .map(|f| {
            let v: Vec<f64> = f.split_whitespace().map(|x| x.parse().unwrap()).collect();
            (v[5] - v[2]).abs()
        })
        .collect();
    let foot = tags(text, "geom").into_iter().find(|t| attr(t, "name") == Some("fl_foot")).unwrap();
    let r: f64 = attr(foot, "size").unwrap().parse().unwrap();
    -z(attr(hip, "pos").unwrap()) + caps.iter().sum::<f64>() + r
}

fn below_zero(file: &str) -> Vec<serde_json::Value> {
    of_message(file, "keyframe-state", "below z = 0")
}

/// A robot file with no floor: the feet start below z = 0 by the legs' reach less the base
/// height — the trunk's `pos`, or the free joint's height in the keyframe reset to.
#[test]
fn feet_below_z0_without_a_floor_are_reported() {
    for (f, key) in [
        ("invalid_below_implied_floor.xml", false),
        ("invalid_keyframe_below_implied_floor.xml", true),
    ] {
        let file = format!("{KS}{f}");
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(!text.contains("type=\"plane\""), "{f}: has a floor");
        let base = if key {
            let k = tags(&text, "key")[0];
            attr(k, "qpos").unwrap().split_whitespace().nth(2).unwrap().parse::<f64>().unwrap()
        } else {
            let t = tags(&text, "body")[0];
            attr(t, "pos").unwrap().split_whitespace().nth(2).unwrap().parse::<f64>().unwrap()
        };
        let depth = leg_reach(&text) - base;
        let found = below_zero(&file);
        assert_eq!(found.len(), 1, "{f}: {found:#?}");
        assert!(
            (measured(&found[0]) - depth).abs() < 1e-6,
            "{f}: {} vs {depth}",
            measured(&found[0])
        );
    }
}

/// Designs that must not fire: a keyframe that sets the base height, feet within `sink_depth`
/// below z = 0, a floor of the file's own elsewhere, an arm on a pedestal, a robot 1 m up.
#[test]
fn no_floor_designs_that_stand_pass() {
    for f in [
        "valid_keyframe_sets_base_height.xml",
        "valid_within_sink_depth.xml",
        "valid_floor_elsewhere.xml",
        "valid_arm_on_pedestal.xml",
        "valid_no_floor.xml",
    ] {
        let file = format!("{KS}{f}");
        let all = findings(&file);
        assert!(of(&all, "keyframe-state").is_empty(), "{f}: {all:#?}");
    }
    // The 15 mm of valid_within_sink_depth is under the rule's 20 mm, from the text.
    let text = std::fs::read_to_string(format!("{KS}valid_within_sink_depth.xml")).unwrap();
    let base: f64 = attr(tags(&text, "body")[0], "pos")
        .unwrap()
        .split_whitespace()
        .nth(2)
        .unwrap()
        .parse()
        .unwrap();
    let depth = leg_reach(&text) - base;
    assert!(depth > 0.0 && depth < 0.02, "{depth}");
}
