//! Test support: a fixture model recorded by the synth, written as CSV logs and read back as
//! `fit` reads them (the recordings reach the fit through the file format, as a user's do).

use crate::model::Robot;
use crate::model::source::SourceMap;
use crate::sim2real::recording::{Recording, read_csv};

use super::Settings;
use super::truth::Hidden;

/// The model at `fixture` (a path under the crate's root) and its recordings by the synth with
/// the `hidden` effects on `joints` under `settings`. Each call writes its own temporary
/// directory (tests run in parallel) and removes it.
pub fn recorded(
    fixture: &str,
    joints: &[String],
    hidden: &[Hidden],
    settings: &Settings,
) -> (Robot, Vec<Recording>) {
    static CALL: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(fixture);
    let robot = crate::model::load(&mut SourceMap::default(), &path, None).expect("fixture");
    let ds = super::generate(&robot, joints, hidden, settings, &|_, _| {}).expect("synth");
    let dir = std::env::temp_dir().join(format!(
        "modellint_recorded_{}_{}",
        std::process::id(),
        CALL.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    let files = super::write::write(&ds, &dir).expect("write");
    let recs = files.iter().map(|f| read_csv(f).expect("read")).collect();
    let _ = std::fs::remove_dir_all(&dir);
    (robot, recs)
}

/// The pendulum servo (`fixtures/synth/pendulum_servo.xml`, joint `servo`) recorded with
/// `hidden` (effect id, its parameters) when given, `episodes` × 3 s, synth seed `seed`.
pub fn pendulum(
    hidden: Option<(&'static str, Vec<f64>)>,
    episodes: usize,
    seed: u64,
) -> (Robot, Vec<Recording>) {
    let hidden: Vec<Hidden> = hidden
        .map(|(effect, params)| Hidden { effect, joint: "servo".into(), params })
        .into_iter()
        .collect();
    let s = Settings { episodes, duration_s: 3.0, seed, ..Settings::default() };
    recorded("fixtures/synth/pendulum_servo.xml", &["servo".to_string()], &hidden, &s)
}
