//! The committed recordings of the independent simulators (`fixtures/independent_py/`, made by
//! `bench/independent_py/realsim.py` and `chainsim.py`, see its README): the case's files,
//! its `truth.json`, `modellint fit` on it, and what the truth says a body effect must come out
//! as, in the fit's own terms.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The directory of a committed case.
pub fn case(name: &str) -> PathBuf {
    super::root().join("fixtures/independent_py").join(name)
}

pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("read")).expect("json")
}

/// The case's `truth.json`.
pub fn truth(name: &str) -> serde_json::Value {
    json(&case(name).join("truth.json"))
}

/// `modellint fit --format json --quiet` on a case's nominal model and episodes, `extra`
/// appended; the run must exit 0.
pub fn fit(name: &str, extra: &[&str]) -> serde_json::Value {
    let d = case(name);
    fit_at(&d.join("nominal.xml"), &d.join("episodes"), extra)
}

/// `modellint fit --format json --quiet MODEL EPISODES`, `extra` appended; the run must exit 0.
pub fn fit_at(model: &Path, episodes: &Path, extra: &[&str]) -> serde_json::Value {
    let o = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg("fit")
        .arg(model)
        .arg(episodes)
        .args(["--format", "json", "--quiet"])
        .args(extra)
        .output()
        .expect("run modellint");
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("fit JSON")
}

pub fn v3(v: &serde_json::Value) -> [f64; 3] {
    let a: Vec<f64> = v.as_array().expect("array").iter().map(|x| x.as_f64().unwrap()).collect();
    [a[0], a[1], a[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| a[k] * b[k]).sum()
}

/// A body of the truth (`resolved._bodies.NAME`) in the fit's terms: the link's direction `u`
/// (from the joint to the modelled centre of mass), `w` = joint axis × `u` (the fit's `across`)
/// and the link's length 2·|com|.
pub struct TruthBody<'a> {
    pub b: &'a serde_json::Value,
    pub com: [f64; 3],
    pub u: [f64; 3],
    pub w: [f64; 3],
    pub len: f64,
}

impl<'a> TruthBody<'a> {
    pub fn of(truth: &'a serde_json::Value, body: &str) -> TruthBody<'a> {
        let b = &truth["resolved"]["_bodies"][body];
        let com = v3(&b["nominal_com"]);
        let a = v3(&b["joint_axis"]);
        let n = dot(com, com).sqrt();
        let u = com.map(|x| x / n);
        let w = [a[1] * u[2] - a[2] * u[1], a[2] * u[0] - a[0] * u[2], a[0] * u[1] - a[1] * u[0]];
        TruthBody { b, com, u, w, len: 2.0 * n }
    }

    /// The payload's mass and its distance from the modelled centre of mass along the link.
    pub fn payload(&self) -> (f64, f64) {
        let (m, along, _) = self.payload_place();
        (m, along)
    }

    /// The payload's mass and its place from the modelled centre of mass, along the link and
    /// across it (joint axis × along).
    pub fn payload_place(&self) -> (f64, f64, f64) {
        let p = v3(&self.b["payload"]["pos"]);
        let d = [p[0] - self.com[0], p[1] - self.com[1], p[2] - self.com[2]];
        (self.b["payload"]["mass"].as_f64().unwrap(), dot(d, self.u), dot(d, self.w))
    }

    /// The centre-of-mass shift along and across the link.
    pub fn com_shift(&self) -> (f64, f64) {
        let d = v3(&self.b["com_shift"]);
        (dot(d, self.u), dot(d, self.w))
    }
}

/// The (effect, joints as JSON) pairs a fit lists as missing physics.
pub fn found(v: &serde_json::Value) -> Vec<(String, String)> {
    v["missing_physics"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| (m["effect"].as_str().unwrap().into(), m["joints"].to_string()))
        .collect()
}

/// The fit lists exactly one `link_mass` on `joint`, with the truth's payload mass within 10 %
/// and its place, along the link and across it, within 10 % of the link's length; returns the
/// listed effect.
pub fn assert_payload_found<'v>(
    v: &'v serde_json::Value,
    truth: &TruthBody,
    joint: &str,
) -> &'v serde_json::Value {
    assert_eq!(found(v), [("link_mass".into(), format!(r#"["{joint}"]"#))], "{:?}", found(v));
    let (mass, along, across) = truth.payload_place();
    let p = &v["missing_physics"][0]["params"];
    let (dm, off) = (p["added_mass"].as_f64().unwrap(), p["offset"].as_f64().unwrap());
    let c = p["across"].as_f64().unwrap();
    assert!((dm - mass).abs() <= 0.1 * mass, "added mass {dm} for {mass}");
    assert!(
        (off - along).abs() <= 0.1 * truth.len && (c - across).abs() <= 0.1 * truth.len,
        "place ({off}, {c}) for ({along}, {across}) (link {} m)",
        truth.len
    );
    &v["missing_physics"][0]
}

/// Nothing listed as missing physics and no joint left unexplained.
pub fn assert_nothing(v: &serde_json::Value) {
    assert_eq!(v["missing_physics"].as_array().map(Vec::len), Some(0), "{}", v["missing_physics"]);
    assert_eq!(v["unexplained"].as_array().map(Vec::len), Some(0), "{}", v["unexplained"]);
}
