//! Body effects on recordings of the independent simulator (`bench/independent_py/realsim.py`,
//! committed in `fixtures/independent_py/`, see its README): a concealed payload on the shank of
//! a three-joint leg must come out as a `link_mass` on the knee's child body with the payload's
//! mass within 10 % and its place within 10 % of the link's length, written back into the
//! shank's `<inertial>`; the same leg with nothing concealed must give nothing. Every expected
//! value is read from the simulator's `truth.json`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn case(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/independent_py").join(name)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("read")).expect("json")
}

/// `modellint fit --format json` on a case (extra arguments appended).
fn fit(name: &str, extra: &[&str]) -> serde_json::Value {
    let d = case(name);
    let o = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg("fit")
        .arg(d.join("nominal.xml"))
        .arg(d.join("episodes"))
        .args(["--format", "json", "--quiet"])
        .args(extra)
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
fn a_payload_on_the_shank_is_found_and_written_into_its_inertial() {
    let truth = json(&case("R1_shank_payload/truth.json"));
    let shank = &truth["resolved"]["_bodies"]["shank"];
    let mass = shank["payload"]["mass"].as_f64().unwrap();
    let pos = v3(&shank["payload"]["pos"]);
    let com = v3(&shank["nominal_com"]);
    let len = 2.0 * (com[0] * com[0] + com[1] * com[1] + com[2] * com[2]).sqrt();
    // The payload's distance from the modelled centre of mass, along the joint → centre line.
    let along = (0..3).map(|k| (pos[k] - com[k]) * com[k]).sum::<f64>() / (0.5 * len);
    let out = std::env::temp_dir().join(format!("modellint-indep-body-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let written = out.join("fitted.xml");
    let v = fit("R1_shank_payload", &["--write-model", written.to_str().unwrap()]);
    let mp = v["missing_physics"].as_array().unwrap();
    let found: Vec<(String, String)> = mp
        .iter()
        .map(|m| (m["effect"].as_str().unwrap().into(), m["joints"].to_string()))
        .collect();
    assert_eq!(found, [("link_mass".to_string(), r#"["knee"]"#.to_string())], "{found:?}");
    // With the payload fitted, nothing is left above the floors.
    assert_eq!(v["unexplained"].as_array().map(Vec::len), Some(0), "{}", v["unexplained"]);
    let p = &mp[0]["params"];
    let (dm, off) = (p["added_mass"].as_f64().unwrap(), p["offset"].as_f64().unwrap());
    assert!((dm - mass).abs() <= 0.1 * mass, "added mass {dm} for {mass}");
    assert!((off - along).abs() <= 0.1 * len, "offset {off} for {along} (link {len} m)");
    // The written model's shank is the nominal shank plus the fitted point: mass and centre of
    // mass as the truth's composite body within the same 10 %.
    let mut map = modellint::model::source::SourceMap::default();
    let robot = modellint::model::load(&mut map, &written, None).expect("the written model loads");
    let b = robot.mj.body_mass();
    let ipos = robot.mj.body_ipos();
    let id = robot.joint("knee").unwrap().id;
    let body = robot.mj.jnt_bodyid()[id] as usize;
    let m0 = shank["nominal_mass"].as_f64().unwrap();
    assert!((b[body] - (m0 + mass)).abs() <= 0.1 * mass, "written mass {}", b[body]);
    let c_true: Vec<f64> = (0..3).map(|k| (m0 * com[k] + mass * pos[k]) / (m0 + mass)).collect();
    let dc: f64 = (0..3).map(|k| (ipos[body][k] - c_true[k]).powi(2)).sum::<f64>().sqrt();
    assert!(dc <= 0.1 * len * mass / (m0 + mass), "written centre of mass off by {dc} m");
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn the_same_leg_without_a_payload_gives_nothing() {
    let v = fit("R0_none", &[]);
    assert_eq!(v["missing_physics"].as_array().map(Vec::len), Some(0), "{}", v["missing_physics"]);
    assert_eq!(v["unexplained"].as_array().map(Vec::len), Some(0), "{}", v["unexplained"]);
}

/// Told to explain the payload with joint effects only, the fit keeps what helps and says
/// that the knee's residual is still far above its floor, where and how large.
#[test]
fn a_payload_the_effects_allowed_cannot_name_is_an_unexplained_residual() {
    let v = fit("R1_shank_payload", &["--effects", "armature,viscous_damping"]);
    let u = v["unexplained"].as_array().unwrap();
    let knee = u.iter().find(|x| x["joint"] == "knee").expect("the knee is unexplained");
    assert!(knee["residual_rms"].as_f64().unwrap() > 3.0 * knee["floor_rms"].as_f64().unwrap());
    let w = v["warnings"].to_string();
    assert!(w.contains("unexplained residual on knee"), "{w}");
}
