#![no_main]
//! Arbitrary bytes as an MJCF/URDF file: the loader must return Ok or a located error, never
//! panic or crash (MuJoCo's compiler included).
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("modellint-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("model.xml");
    if std::fs::write(&path, data).is_ok() {
        let mut map = modellint::model::source::SourceMap::default();
        let _ = modellint::model::load(&mut map, &path, None);
    }
});
