#![no_main]
//! Arbitrary bytes as a hardware spec TOML against a fixed joint list.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("modellint-fuzz-spec-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("spec.toml");
    if std::fs::write(&path, data).is_ok() {
        let mut map = modellint::model::source::SourceMap::default();
        let joints = vec!["left_knee".to_string(), "right_knee".to_string(), "left_toe".to_string()];
        let _ = modellint::spec::load(&mut map, &path, &joints);
    }
});
