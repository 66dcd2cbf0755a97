//! A deterministic mini-fuzz of the loaders (the cargo-fuzz targets in fuzz/ need nightly):
//! truncations and byte flips of real inputs must give Ok or a located error, never a panic or
//! a crash inside MuJoCo's compiler.

use std::path::Path;

fn variants(text: &str, n: usize) -> Vec<Vec<u8>> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut seed = 0x1234_5678_u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    for k in 0..n {
        let cut = (bytes.len() * k) / n;
        out.push(bytes[..cut].to_vec());
        let mut flipped = bytes.to_vec();
        for _ in 0..4 {
            let i = (next() as usize) % flipped.len();
            flipped[i] = b"<>\"=/ 0.-e9nNaI"[(next() as usize) % 15];
        }
        out.push(flipped);
    }
    out
}

/// The error names the mutated file (the model has no includes) with a line and column inside
/// it, and `location()` is exactly `file:line:col`.
fn assert_located(e: &modellint::error::LoadError, path: &Path, bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    assert_eq!(e.file, path, "error names another file: {e}");
    let (Some(line), Some(col)) = (e.line, e.column) else {
        panic!("error without line:col: {e}");
    };
    let lines: Vec<&str> = text.split('\n').collect();
    assert!(
        line >= 1 && line <= lines.len(),
        "line {line} outside the file ({} lines): {e}",
        lines.len()
    );
    let width = lines[line - 1].chars().count();
    assert!(col >= 1 && col <= width + 1, "column {col} outside line {line} ({width} chars): {e}");
    assert_eq!(e.location(), format!("{}:{line}:{col}", path.display()));
}

#[test]
fn mutated_models_never_panic() {
    modellint::model::mj::silence_warnings();
    let dir = std::env::temp_dir().join(format!("modellint-mut-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = std::fs::read_to_string("models/asimov.xml").unwrap();
    let (mut ok, mut err) = (0, 0);
    for (i, v) in variants(&src, 30).into_iter().enumerate() {
        let p = dir.join(format!("m{i}.xml"));
        std::fs::write(&p, &v).unwrap();
        let mut map = modellint::model::source::SourceMap::default();
        match modellint::model::load(&mut map, &p, None) {
            Ok(_) => ok += 1,
            Err(e) => {
                assert_located(&e, &p, &v);
                err += 1;
            }
        }
    }
    assert!(err > 20, "most truncations are errors ({ok} ok, {err} errors)");
}

#[test]
fn mutated_specs_and_recordings_never_panic() {
    let dir = std::env::temp_dir().join(format!("modellint-mut-spec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let spec = std::fs::read_to_string("models/asimov.toml").unwrap();
    let joints: Vec<String> = ["left_hip_pitch", "left_knee", "left_toe", "right_knee"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for (i, v) in variants(&spec, 30).into_iter().enumerate() {
        let p = dir.join(format!("s{i}.toml"));
        std::fs::write(&p, &v).unwrap();
        let mut map = modellint::model::source::SourceMap::default();
        let _ = modellint::spec::load(&mut map, &p, &joints);
    }
    let csv = "# control_rate_hz: 100\nt,a.q,a.q_cmd\n0,0.1,0.1\n0.01,0.2,0.2\n0.02,0.3,0.3\n";
    for v in variants(csv, 30) {
        let text = String::from_utf8_lossy(&v);
        let _ = modellint::sim2real::recording::parse_csv(Path::new("x.csv"), &text);
    }
}
