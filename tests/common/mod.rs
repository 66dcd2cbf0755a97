//! Helpers shared by the integration tests (`mod common;`). Each test binary uses a subset.
#![allow(dead_code)]

pub mod indep;
pub mod lint;
pub mod xml_text;

use std::path::{Path, PathBuf};

use modellint::fit::select::Selected;
use modellint::model::{Robot, source::SourceMap};
use modellint::sim2real::recording::{Recording, read_csv};
use modellint::synth::{self, Settings, truth::Hidden};

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn load(path: &Path) -> Robot {
    let mut map = SourceMap::default();
    modellint::model::load(&mut map, path, None)
        .unwrap_or_else(|e| panic!("{} does not load: {e}", path.display()))
}

/// `effect` with `params` (the effect's order, the rest at their defaults) hidden on `joint`, as
/// the independent synth takes it.
pub fn hidden(effect: &str, joint: &str, params: &[f64]) -> Hidden {
    let e = modellint::fit::effects::by_id(effect).unwrap_or_else(|| panic!("effect {effect}"));
    let defs = e.params();
    Hidden {
        effect: e.id(),
        joint: joint.into(),
        params: (0..defs.len())
            .map(|i| params.get(i).copied().unwrap_or(defs[i].default))
            .collect(),
    }
}

/// Recordings of `robot` with `hidden` made by the independent synth (`modellint::synth`: its own
/// MuJoCo loop, controller and recorder clocks, noise, quantisation, drops), written as CSV into
/// `dir` and read back with the reader `fit` uses, as a user's files are. The episodes stay in
/// `dir/episodes` (the caller removes `dir`).
pub fn synth_into(
    dir: &Path,
    robot: &Robot,
    joints: &[String],
    hidden: &[Hidden],
    s: &Settings,
) -> (Vec<Recording>, synth::Dataset) {
    let ds = synth::generate(robot, joints, hidden, s, &|_, _| {}).expect("synth");
    let _ = std::fs::remove_dir_all(dir);
    let files = synth::write::write(&ds, dir).expect("write synth dataset");
    let recs = files
        .iter()
        .map(|f| read_csv(f).unwrap_or_else(|e| panic!("{}: {e}", f.display())))
        .collect();
    (recs, ds)
}

/// [`synth_into`] in a temporary directory removed afterwards.
pub fn synth_recordings(
    tag: &str,
    robot: &Robot,
    joints: &[String],
    hidden: &[Hidden],
    s: &Settings,
) -> Vec<Recording> {
    let dir = std::env::temp_dir().join(format!("modellint_test_{tag}_{}", std::process::id()));
    let (recs, _) = synth_into(&dir, robot, joints, hidden, s);
    let _ = std::fs::remove_dir_all(&dir);
    recs
}

/// A kept effect as `fit` reports it (only the fields write-back reads matter).
pub fn kept(effect: &str, joint: &str, params: &[(&str, f64)]) -> Selected {
    Selected {
        effect: effect.into(),
        joints: vec![joint.into()],
        params: params.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
        stderr: Default::default(),
        identifiable: true,
        unidentified: vec![],
        evidence: Default::default(),
        heldout_improvement: 0.5,
        heldout_rmse_before: 0.0,
        heldout_rmse_after: 0.0,
        window_improvement: 0.0,
        window_improvement_se: 0.0,
        bic_before: 0.0,
        bic_after: 0.0,
        values: params.iter().map(|p| p.1).collect(),
    }
}
