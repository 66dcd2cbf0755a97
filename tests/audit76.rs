//! The class the seventeenth round (issue 45) found missed, end to end from the CLI on fixtures
//! written from it: a robot modelled at ten times its size (`robot-scale`). The masses are summed
//! here from the fixtures' written `mass` attributes and the scale law (lengths ×10, volume
//! ×1000) is checked between a fixture and its copy in metres, not read from the tool.

mod common;

use std::process::Command;

use common::lint::{findings, measured, message, of, real_robot_files};
use common::xml_text::{attr, tags};

const RS: &str = "fixtures/rules/robot-scale/";

/// The findings of `robot-scale` with `min_bulk_density` raised so high that every robot is
/// reported: each tree's measured mass per volume, and its message.
fn forced(file: &str) -> Vec<(f64, String)> {
    let cfg = std::env::temp_dir().join(format!("audit76_forced_{}.toml", std::process::id()));
    std::fs::write(&cfg, "[rules.robot-scale]\nmin_bulk_density = 1e9\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .args([file, "--no-probe", "--no-cache", "--format", "json", "--select", "robot-scale"])
        .arg("--config")
        .arg(&cfg)
        .env_remove("GITHUB_ACTIONS")
        .output()
        .unwrap();
    let json: serde_json::Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{file}: {e}: {}", String::from_utf8_lossy(&out.stderr)));
    json["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["rule"] == "robot-scale")
        .map(|f| (measured(f), message(f).to_string()))
        .collect()
}

/// The sum of the `mass` attributes written on the fixture's geoms of moving bodies (the world
/// body's scenery is written before the first `<body`).
fn written_mass(text: &str) -> f64 {
    let robot = &text[text.find("<body ").unwrap()..];
    tags(robot, "geom")
        .iter()
        .filter_map(|g| attr(g, "mass"))
        .map(|m| m.parse::<f64>().unwrap())
        .sum()
}

/// The three extents "a × b × c m" of a `robot-scale` message.
fn extents(msg: &str) -> [f64; 3] {
    let i = msg.find("spans ").unwrap() + "spans ".len();
    let v: Vec<f64> =
        msg[i..].split(" m ").next().unwrap().split(" × ").map(|x| x.parse().unwrap()).collect();
    [v[0], v[1], v[2]]
}

/// The kg figure "weighs X kg" of a `robot-scale` message.
fn weighs(msg: &str) -> f64 {
    let i = msg.find("weighs ").unwrap() + "weighs ".len();
    msg[i..].split(' ').next().unwrap().parse().unwrap()
}

/// A robot written ten times its size with its real masses is reported once, with its written
/// mass and a density below the default; its copy in metres is not, and measures 1000 times
/// denser with extents a tenth as large.
#[test]
fn a_biped_at_ten_times_its_size_is_lighter_than_its_box() {
    let big = format!("{RS}invalid_decimetre_biped.xml");
    let small = format!("{RS}valid_biped_in_metres.xml");
    let mass = written_mass(&std::fs::read_to_string(&big).unwrap());
    let all = findings(&big);
    let got = of(&all, "robot-scale");
    assert_eq!(got.len(), 1, "{all:?}");
    let msg = message(got[0]);
    assert!((weighs(msg) - mass).abs() < 1e-3, "{msg} (written {mass} kg)");
    let e = extents(msg);
    let density = measured(got[0]);
    assert!(density < 2.0, "{density}");
    // The message's extents and mass give the measured density (to the message's 3 digits).
    assert!((mass / (e[0] * e[1] * e[2]) / density - 1.0).abs() < 0.01, "{msg}");
    assert!(of(&findings(&small), "robot-scale").is_empty());
    let f = forced(&small);
    assert_eq!(f.len(), 1, "{f:?}");
    assert!((f[0].0 / density / 1000.0 - 1.0).abs() < 1e-6, "{} vs {density}", f[0].0);
    let es = extents(&f[0].1);
    for (big, small) in e.iter().zip(es.iter()) {
        assert!((big / small - 10.0).abs() < 0.02, "{e:?} vs {es:?}");
    }
}

/// The pose judged is the keyframe's: the bent arm's message names it, and its box is the
/// bent arm's (wider than tall above its base, unlike the arm straight up at qpos0).
#[test]
fn an_arm_at_ten_times_its_size_is_judged_in_its_keyframe() {
    let file = format!("{RS}invalid_decimetre_arm_keyframe.xml");
    let text = std::fs::read_to_string(&file).unwrap();
    let all = findings(&file);
    let got = of(&all, "robot-scale");
    assert_eq!(got.len(), 1, "{all:?}");
    let msg = message(got[0]);
    assert!(msg.contains("at keyframe `home`") && msg.contains("body `base`"), "{msg}");
    assert!((weighs(msg) - written_mass(&text)).abs() < 1e-3, "{msg}");
    let e = extents(msg);
    assert!(e[0] > e[2] && e[0] < 6.0, "{e:?}: the table (12 m) is the world's, not the arm's");
}

/// Each tree is judged on its own box: two arms 5 m apart on a world-body table, and a loose
/// crate with no joint, give one result per arm, each smaller than a metre; the slender snake
/// (long, thin, light) is not reported.
#[test]
fn trees_are_judged_alone_and_slender_robots_are_not_light() {
    let file = format!("{RS}valid_arms_and_scenery.xml");
    assert!(of(&findings(&file), "robot-scale").is_empty());
    let f = forced(&file);
    assert_eq!(f.len(), 2, "{f:?}");
    for (_, msg) in &f {
        assert!(extents(msg).iter().all(|&x| x < 1.0), "{msg}");
        assert!((weighs(msg) - 0.45).abs() < 1e-3, "{msg}");
    }
    assert!(of(&findings(&format!("{RS}valid_slender_snake.xml")), "robot-scale").is_empty());
}

/// The real robots the repository keeps are not reported.
#[test]
fn real_robots_are_not_reported() {
    for file in real_robot_files() {
        assert!(of(&findings(&file), "robot-scale").is_empty(), "{file}");
    }
}
