//! Recordings of a robot with its own physics (`bench/independent_py/chainsim.py`: a numpy
//! planar chain, no MuJoCo; committed in `fixtures/independent_py/`, see its README): the
//! three-joint leg with a 0.6 kg payload composed into its shank by hand must come out as a
//! `link_mass` on the knee with the payload's mass within 10 % and its place within 10 % of the
//! link's length; the same leg with nothing concealed must give nothing. Every expected value is read from the simulator's `truth.json`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn case(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/independent_py").join(name)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("read")).expect("json")
}

/// `modellint fit --format json` on a case.
fn fit(name: &str) -> serde_json::Value {
    let d = case(name);
    let o = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg("fit")
        .arg(d.join("nominal.xml"))
        .arg(d.join("episodes"))
        .args(["--format", "json", "--quiet"])
        .output()
        .expect("run modellint");
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("fit JSON")
}

fn v3(v: &serde_json::Value) -> [f64; 3] {
    let a: Vec<f64> = v.as_array().expect("array").iter().map(|x| x.as_f64().unwrap()).collect();
    [a[0], a[1], a[2]]
}

#[test]
fn a_payload_composed_by_the_robots_own_physics_is_found_on_the_knee() {
    let truth = json(&case("KR1_shank_payload/truth.json"));
    assert_eq!(truth["simulator"], "chainsim.py", "not the own-physics simulator's recording");
    let shank = &truth["resolved"]["_bodies"]["shank"];
    let mass = shank["payload"]["mass"].as_f64().unwrap();
    let pos = v3(&shank["payload"]["pos"]);
    let com = v3(&shank["nominal_com"]);
    let len = 2.0 * (com[0] * com[0] + com[1] * com[1] + com[2] * com[2]).sqrt();
    // The payload's distance from the modelled centre of mass, along the joint → centre line.
    let along = (0..3).map(|k| (pos[k] - com[k]) * com[k]).sum::<f64>() / (0.5 * len);
    let v = fit("KR1_shank_payload");
    let mp = v["missing_physics"].as_array().unwrap();
    let found: Vec<(String, String)> = mp
        .iter()
        .map(|m| (m["effect"].as_str().unwrap().into(), m["joints"].to_string()))
        .collect();
    assert_eq!(found, [("link_mass".to_string(), r#"["knee"]"#.to_string())], "{found:?}");
    let p = &mp[0]["params"];
    let (dm, off) = (p["added_mass"].as_f64().unwrap(), p["offset"].as_f64().unwrap());
    assert!((dm - mass).abs() <= 0.1 * mass, "added mass {dm} for {mass}");
    assert!((off - along).abs() <= 0.1 * len, "offset {off} for {along} (link {len} m)");
}

/// The same leg with nothing concealed gives nothing: it moves in continuous time (RK4 at
/// 4 kHz) against a model stepped at 1 ms, and the model's own discretisation (the replay's
/// distance from its continuous-time limit, extrapolated from replays at 1, ½ and ¼ ms) is
/// floor, not physics. (Counted from the ¼ ms replay alone it came out as a 0.81 ms action
/// delay on all three joints.)
#[test]
fn the_own_physics_leg_without_a_payload_gives_nothing() {
    let v = fit("KR0_leg_none");
    assert_eq!(v["missing_physics"].as_array().map(Vec::len), Some(0), "{}", v["missing_physics"]);
    assert_eq!(v["unexplained"].as_array().map(Vec::len), Some(0), "{}", v["unexplained"]);
}
