//! A deterministic mini-fuzz of the loaders (the cargo-fuzz targets in fuzz/ need nightly):
//! truncations and byte flips of real inputs, and property tests (proptest) over mutated MJCF,
//! URDF, spec TOML and recording CSV, must give Ok or a located error, never a panic or a crash
//! inside MuJoCo's compiler.

use std::path::{Path, PathBuf};

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

// ---------------------------------------------------------------------------------------------
// Property tests (proptest on stable Rust, issue 48): the shipped fixtures — MJCF models, a
// URDF, hardware spec TOML, a recording CSV — mutated at the line, number, attribute and byte
// level (lines deleted, duplicated, swapped; numbers made NaN, inf, huge, negative, degrees,
// milliseconds; attribute values replaced; truncation) and fed to the library entry points and
// the built binary. Properties: no panic; every rejection is an `Err` / exit 2 whose message
// names the mutated file and a line inside it. A fixed seed and a bounded number of cases per
// input class (PROPTEST_CASES does not change them) keep the run deterministic and short.

use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};

/// Values a mutated number or attribute takes: non-finite, huge, tiny, negative, degrees for
/// radians, malformed.
const VALUES: [&str; 24] = [
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e999",
    "1e-320",
    "-1",
    "0",
    "-0",
    "90",
    "180",
    "57.29578",
    "1000",
    "1e9",
    "",
    "abc",
    "1e",
    "0x10",
    "--1",
    "1,2",
    "-1e-9",
    "4294967296",
];
/// Extra values for a whole attribute / TOML value: vectors of the wrong size, markup.
const ATTRS: [&str; 10] = [
    "nan nan nan",
    "1 2",
    "0 0 0 0",
    "-1 -1 -1",
    "1e308 1e308 1e308",
    "true",
    "[1]",
    "\"",
    "<",
    "&amp",
];
/// Unit mistakes: every number on a line scaled (ms, ns, degrees, sign, zero).
const SCALES: [f64; 6] = [1000.0, 0.001, 1e9, -1.0, 57.29578, 0.0];

#[derive(Debug, Clone)]
enum Op {
    DeleteLine(Index),
    DuplicateLine(Index),
    SwapLines(Index, Index),
    Truncate(Index),
    Number(Index, usize),
    Value(Index, usize),
    ScaleLine(Index, usize),
    Byte(Index, u8),
    /// CSV: a column removed from the header and every row (a logger that left out a signal).
    DeleteColumn(Index),
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        2 => any::<Index>().prop_map(Op::DeleteLine),
        2 => any::<Index>().prop_map(Op::DuplicateLine),
        2 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Op::SwapLines(a, b)),
        1 => any::<Index>().prop_map(Op::Truncate),
        3 => (any::<Index>(), 0..VALUES.len()).prop_map(|(i, v)| Op::Number(i, v)),
        3 => (any::<Index>(), 0..VALUES.len() + ATTRS.len()).prop_map(|(i, v)| Op::Value(i, v)),
        2 => (any::<Index>(), 0..SCALES.len()).prop_map(|(i, s)| Op::ScaleLine(i, s)),
        2 => (any::<Index>(), prop::sample::select(b"<>\"=/ ,.-e9nNaI#\n[]".to_vec()))
            .prop_map(|(i, b)| Op::Byte(i, b)),
    ]
}

fn ops() -> impl Strategy<Value = Vec<Op>> {
    prop::collection::vec(op(), 1..4)
}

/// For a CSV: the mutations above and removed columns.
fn csv_ops() -> impl Strategy<Value = Vec<Op>> {
    prop::collection::vec(
        prop_oneof![4 => op(), 1 => any::<Index>().prop_map(Op::DeleteColumn)],
        1..4,
    )
}

/// Byte ranges of the numbers in `text` (not inside names such as `joint1`).
fn numbers(text: &str) -> Vec<std::ops::Range<usize>> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            || ((b[i] == b'-' || b[i] == b'.') && b.get(i + 1).is_some_and(u8::is_ascii_digit));
        let inside_name = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if starts && !inside_name {
            let s = i;
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_digit()
                    || b[i] == b'.'
                    || ((b[i] == b'e' || b[i] == b'E')
                        && b.get(i + 1).is_some_and(|c| c.is_ascii_digit() || *c == b'-'))
                    || ((b[i] == b'-' || b[i] == b'+') && matches!(b[i - 1], b'e' | b'E')))
            {
                i += 1;
            }
            out.push(s..i);
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of attribute values and strings (`"…"`) and of TOML values (`key = value`).
fn values(text: &str) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut open = None;
    for (i, c) in text.char_indices() {
        if c == '"' {
            match open.take() {
                Some(s) => out.push(s..i),
                None => open = Some(i + 1),
            }
        } else if c == '\n' {
            open = None;
        }
    }
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        if let Some(eq) = line.find(" = ") {
            let end = line.trim_end().len();
            if eq + 3 <= end && !line.trim_start().starts_with('#') {
                out.push(at + eq + 3..at + end);
            }
        }
        at += line.len();
    }
    out
}

fn apply(text: &str, ops: &[Op]) -> String {
    let mut s = text.to_string();
    for op in ops {
        let mut lines: Vec<String> = s.split('\n').map(str::to_string).collect();
        match op {
            Op::DeleteLine(i) => {
                lines.remove(i.index(lines.len()));
                s = lines.join("\n");
            }
            Op::DuplicateLine(i) => {
                let k = i.index(lines.len());
                let l = lines[k].clone();
                lines.insert(k, l);
                s = lines.join("\n");
            }
            Op::SwapLines(a, b) => {
                let (a, b) = (a.index(lines.len()), b.index(lines.len()));
                lines.swap(a, b);
                s = lines.join("\n");
            }
            Op::Truncate(i) => {
                let mut cut = i.index(s.len() + 1);
                while !s.is_char_boundary(cut) {
                    cut -= 1;
                }
                s.truncate(cut);
            }
            Op::Number(i, v) => {
                let r = numbers(&s);
                if !r.is_empty() {
                    s.replace_range(r[i.index(r.len())].clone(), VALUES[*v]);
                }
            }
            Op::Value(i, v) => {
                let r = values(&s);
                if !r.is_empty() {
                    let new = VALUES.iter().chain(ATTRS.iter()).nth(*v).copied().unwrap_or("");
                    s.replace_range(r[i.index(r.len())].clone(), new);
                }
            }
            Op::ScaleLine(i, f) => {
                let k = i.index(lines.len());
                let line = lines[k].clone();
                let mut out = line.clone();
                for r in numbers(&line).into_iter().rev() {
                    if let Ok(x) = line[r.clone()].parse::<f64>() {
                        out.replace_range(r, &format!("{}", x * SCALES[*f]));
                    }
                }
                lines[k] = out;
                s = lines.join("\n");
            }
            Op::Byte(i, b) => {
                let k = i.index(s.len().max(1)).min(s.len().saturating_sub(1));
                if s.is_char_boundary(k) && s.as_bytes().get(k).is_some_and(u8::is_ascii) {
                    s.replace_range(k..k + 1, &(*b as char).to_string());
                }
            }
            Op::DeleteColumn(i) => {
                let Some(h) = lines.iter().position(|l| l.starts_with("t,")) else { continue };
                let k = i.index(lines[h].split(',').count());
                for l in &mut lines[h..] {
                    let mut f: Vec<&str> = l.split(',').collect();
                    if k < f.len() {
                        f.remove(k);
                    }
                    *l = f.join(",");
                }
                s = lines.join("\n");
            }
        }
    }
    s
}

/// A runner with a fixed seed (one per input class) and `cases` cases; no failure files.
/// `MODELLINT_PROP_CASES=N` and `MODELLINT_PROP_SEED=K` run N cases from another seed (a longer
/// search by hand; `make test` and `.ci/run` use the fixed defaults).
fn runner(seed: u8, cases: u32) -> TestRunner {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let cases = env("MODELLINT_PROP_CASES").map_or(cases, |n| n as u32);
    let mut key = [seed; 32];
    if let Some(s) = env("MODELLINT_PROP_SEED") {
        key[..8].copy_from_slice(&s.to_le_bytes());
    }
    let config =
        Config { cases, max_shrink_iters: 200, failure_persistence: None, ..Config::default() };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &key))
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("modellint-prop-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `e` names `path` with a line (and a column, when `col`) inside `text`.
fn located(
    e: &modellint::error::LoadError,
    path: &Path,
    text: &str,
    col: bool,
) -> Result<(), TestCaseError> {
    let lines = text.split('\n').count();
    prop_assert_eq!(&e.file, path, "error names another file: {}", e);
    let Some(line) = e.line else {
        return Err(TestCaseError::fail(format!("error without a line: {e}")));
    };
    prop_assert!(
        line >= 1 && line <= lines,
        "line {} outside the file ({} lines): {}",
        line,
        lines,
        e
    );
    if col {
        prop_assert!(e.column.is_some(), "error without a column: {}", e);
    }
    Ok(())
}

/// The models: every shipped MJCF without includes or meshes, and a URDF.
const MODELS: [&str; 7] = [
    "models/asimov.xml",
    "fixtures/gap/arm3.xml",
    "fixtures/bam_xl330/rig.xml",
    "fixtures/synth/pendulum_servo.xml",
    "fixtures/synth/heavy_knee.xml",
    "fixtures/probes/servo_damped.xml",
    "fixtures/rules/urdf-mjcf-drift/urdf/valid.urdf",
];

fn lint_input(model: PathBuf, spec: Option<PathBuf>) -> modellint::lint::LintInput {
    modellint::lint::LintInput { model, spec, config: None, select: vec![], ignore: vec![] }
}

/// Mutated MJCF and URDF: `lint::load` is `Ok` (then the static rules run without a panic) or
/// an error at a line and column of the mutated file.
#[test]
fn property_mutated_models_load_or_fail_at_a_line() {
    modellint::model::mj::silence_warnings();
    let dir = tmp("models");
    let sources: Vec<String> = MODELS.iter().map(|m| std::fs::read_to_string(m).unwrap()).collect();
    let (ok, err) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
    let strategy = (0..MODELS.len(), ops());
    runner(1, 96)
        .run(&strategy, |(m, ops)| {
            let text = apply(&sources[m], &ops);
            let name = Path::new(MODELS[m]).file_name().unwrap();
            let p = dir.join(name);
            std::fs::write(&p, &text).unwrap();
            match modellint::lint::load(&lint_input(p.clone(), None)) {
                Ok(l) => {
                    let _ = modellint::lint::run_rules(&l);
                    ok.set(ok.get() + 1);
                }
                Err(e) => {
                    located(&e, &p, &text, true)?;
                    err.set(err.get() + 1);
                }
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("mutated models: {} loaded, {} located errors", ok.get(), err.get());
    assert!(ok.get() > 0 && err.get() > 0, "{} ok, {} errors", ok.get(), err.get());
    std::fs::remove_dir_all(&dir).ok();
}

/// Mutated hardware specs beside their models (asimov, the BAM rig): loaded with the model and
/// the static rules run, or an error at a line of the spec.
#[test]
fn property_mutated_specs_load_or_fail_at_a_line() {
    modellint::model::mj::silence_warnings();
    let dir = tmp("specs");
    let pairs = [
        ("models/asimov.xml", "models/asimov.toml"),
        ("fixtures/bam_xl330/rig.xml", "fixtures/bam_xl330/rig.toml"),
    ];
    let specs: Vec<String> =
        pairs.iter().map(|(_, s)| std::fs::read_to_string(s).unwrap()).collect();
    let (ok, err) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
    runner(2, 96)
        .run(&(0..pairs.len(), ops()), |(k, ops)| {
            let text = apply(&specs[k], &ops);
            let p = dir.join(Path::new(pairs[k].1).file_name().unwrap());
            std::fs::write(&p, &text).unwrap();
            match modellint::lint::load(&lint_input(PathBuf::from(pairs[k].0), Some(p.clone()))) {
                Ok(l) => {
                    let _ = modellint::lint::run_rules(&l);
                    ok.set(ok.get() + 1);
                }
                Err(e) => {
                    located(&e, &p, &text, true)?;
                    err.set(err.get() + 1);
                }
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("mutated specs: {} loaded, {} located errors", ok.get(), err.get());
    assert!(ok.get() > 0 && err.get() > 0, "{} ok, {} errors", ok.get(), err.get());
    std::fs::remove_dir_all(&dir).ok();
}

/// A recording of fixtures/gap/arm3.xml written here (not by modellint): 100 Hz ticks, rows at
/// ~120 Hz for 1.5 s, every column kind.
fn arm3_recording() -> String {
    let mut s = String::from(
        "# control_rate_hz: 100\n# robot: arm3\n# split: train\n\
         t,shoulder_pitch.q,shoulder_pitch.qd,shoulder_pitch.q_cmd,shoulder_pitch.kp,\
         shoulder_pitch.kd,shoulder_pitch.enabled,elbow_pitch.q,elbow_pitch.q_cmd,\
         elbow_pitch.tau,wrist_pitch.q,wrist_pitch.q_cmd\n",
    );
    for i in 0..180 {
        let t = i as f64 / 120.0;
        let tick = (t * 100.0).floor() / 100.0;
        let c = |w: f64| 0.3 * (w * tick).sin();
        let q = |w: f64| 0.28 * (w * (t - 0.02)).sin();
        s.push_str(&format!(
            "{t:.5},{:.5},{:.4},{:.5},50,1.5,1,{:.5},{:.5},0.1,{:.5},{:.5}\n",
            q(2.0),
            0.56 * (2.0 * t).cos(),
            c(2.0),
            q(3.0),
            c(3.0),
            q(1.5),
            c(1.5)
        ));
    }
    s
}

/// `msg` starts with `path:LINE:` for a line inside `text`.
fn names_a_line(msg: &str, path: &Path, text: &str) -> Result<(), TestCaseError> {
    let head = format!("{}:", path.display());
    let Some(rest) = msg.strip_prefix(&head) else {
        return Err(TestCaseError::fail(format!("error does not start with {head}: {msg}")));
    };
    let line: Option<usize> = rest.split(':').next().and_then(|l| l.parse().ok());
    let n = text.split('\n').count();
    match line {
        Some(l) if l >= 1 && l <= n => Ok(()),
        _ => Err(TestCaseError::fail(format!("error without a line inside the file: {msg}"))),
    }
}

/// Mutated recordings: read for a replay against arm3 as `gap` and `fit` read them
/// ([`modellint::sim2real::input::read_for_replay`]), replayed and scored; a rejection names
/// the file and a line inside it.
#[test]
fn property_mutated_recordings_replay_or_fail_at_a_line() {
    modellint::model::mj::silence_warnings();
    use modellint::sim2real::{gap, input, recording::ParseOptions, replay};
    let dir = tmp("recs");
    let robot = {
        let mut map = modellint::model::source::SourceMap::default();
        modellint::model::load(&mut map, Path::new("fixtures/gap/arm3.xml"), None).unwrap()
    };
    let base = arm3_recording();
    let opts = replay::ReplayOptions::default();
    let (ok, err) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
    let no_cmd = std::cell::Cell::new(0);
    runner(3, 128)
        .run(&csv_ops(), |ops| {
            let text = apply(&base, &ops);
            let p = dir.join("rec.csv");
            std::fs::write(&p, &text).unwrap();
            match input::read_for_replay(
                std::slice::from_ref(&p),
                &robot,
                &opts,
                &ParseOptions::default(),
            ) {
                Ok(inp) => {
                    // Every joint of arm3 is driven: none may be replayed without its command.
                    for r in &inp.recs {
                        for j in &r.joints {
                            prop_assert!(j.q_cmd.is_some(), "{} read without a command", j.name);
                        }
                    }
                    let replayer = replay::Replayer::new(&robot);
                    let mut eps = Vec::new();
                    for r in replay::replay_all(&replayer, &inp.recs, &opts, None) {
                        match r {
                            Ok(e) => eps.push(e),
                            Err(e) => names_a_line(&e.to_string(), &p, &text)?,
                        }
                    }
                    if eps.len() == inp.recs.len() {
                        let _ = gap::compute(
                            &inp.recs,
                            &eps,
                            &|_| String::new(),
                            &gap::GapOptions::default(),
                        );
                    }
                    ok.set(ok.get() + 1);
                }
                Err(e) => {
                    names_a_line(&e, &p, &text)?;
                    // A header that lost a driven joint's q_cmd column (and nothing else wrong
                    // before it): the error is that, at the header line.
                    if let Some((h, header)) =
                        text.split('\n').enumerate().find(|(_, l)| l.starts_with("t,"))
                    {
                        let cols: Vec<&str> = header.split(',').collect();
                        let lost =
                            ["shoulder_pitch", "elbow_pitch", "wrist_pitch"].iter().find(|j| {
                                cols.contains(&format!("{j}.q").as_str())
                                    && !cols.contains(&format!("{j}.q_cmd").as_str())
                            });
                        if let Some(j) = lost
                            && e.contains("has positions but no")
                        {
                            no_cmd.set(no_cmd.get() + 1);
                            prop_assert!(
                                e.starts_with(&format!("{}:{}: ", p.display(), h + 1))
                                    && e.contains(&format!("'{j}.q_cmd' column")),
                                "{}",
                                e
                            );
                        }
                    }
                    err.set(err.get() + 1);
                }
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
    eprintln!(
        "mutated recordings: {} replayed, {} located errors ({} of them a lost q_cmd column)",
        ok.get(),
        err.get(),
        no_cmd.get()
    );
    assert!(ok.get() > 0 && err.get() > 0, "{} ok, {} errors", ok.get(), err.get());
    std::fs::remove_dir_all(&dir).ok();
}

/// A BAM servo log written here, one entry per line (a sine on the rig's servo, 1.5 s).
fn bam_log() -> String {
    let e: Vec<String> = (0..300)
        .map(|i| {
            let t = 0.005 * i as f64 + 0.0012;
            format!(
                "  {{\"timestamp\": {t:.4}, \"position\": {:.5}, \"speed\": {:.4}, \"goal_position\": {:.5}, \"torque_enable\": true, \"load\": 12}}",
                0.3 * (2.0 * t).sin(),
                0.6 * (2.0 * t).cos(),
                0.31 * (2.0 * t + 0.05).sin()
            )
        })
        .collect();
    format!(
        "{{\"mass\": 0.49, \"length\": 0.1, \"kp\": 400, \"vin\": 7.4, \"motor\": \"xl330\",\n \"trajectory\": \"sin\",\n \"entries\": [\n{}\n]}}\n",
        e.join(",\n")
    )
}

/// Mutated BAM logs read for a replay against the rig (as `gap` and `fit` read them), replayed:
/// a rejection names the file and a line inside it.
#[test]
fn property_mutated_bam_logs_replay_or_fail_at_a_line() {
    modellint::model::mj::silence_warnings();
    use modellint::sim2real::{input, recording::ParseOptions, replay};
    let dir = tmp("bam");
    let robot = {
        let mut map = modellint::model::source::SourceMap::default();
        modellint::model::load(&mut map, Path::new("fixtures/bam_xl330/rig.xml"), None).unwrap()
    };
    let base = bam_log();
    let opts = replay::ReplayOptions::default();
    let (ok, err) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
    runner(5, 96)
        .run(&ops(), |ops| {
            let text = apply(&base, &ops);
            let p = dir.join("log.json");
            std::fs::write(&p, &text).unwrap();
            match input::read_for_replay(
                std::slice::from_ref(&p),
                &robot,
                &opts,
                &ParseOptions::default(),
            ) {
                Ok(inp) => {
                    for r in &inp.recs {
                        prop_assert!(r.joints.iter().all(|j| j.q_cmd.is_some()));
                    }
                    let replayer = replay::Replayer::new(&robot);
                    for r in replay::replay_all(&replayer, &inp.recs, &opts, None) {
                        if let Err(e) = r {
                            names_a_line(&e.to_string(), &p, &text)?;
                        }
                    }
                    ok.set(ok.get() + 1);
                }
                Err(e) => {
                    names_a_line(&e, &p, &text)?;
                    err.set(err.get() + 1);
                }
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("mutated BAM logs: {} replayed, {} located errors", ok.get(), err.get());
    assert!(ok.get() > 0 && err.get() > 0, "{} ok, {} errors", ok.get(), err.get());
    std::fs::remove_dir_all(&dir).ok();
}

/// The built binary on a few mutated inputs of each kind: exit 0, 1 or 2, never a panic or a
/// signal; exit 2 names the mutated file with a line.
#[test]
fn property_the_binary_exits_2_with_a_location() {
    let dir = tmp("bin");
    let bin = env!("CARGO_BIN_EXE_modellint");
    let base = arm3_recording();
    let model = std::fs::read_to_string("fixtures/gap/arm3.xml").unwrap();
    let spec = std::fs::read_to_string("fixtures/bam_xl330/rig.toml").unwrap();
    let counts = std::cell::RefCell::new([0usize; 3]);
    runner(4, 24)
        .run(&(0..3usize, ops()), |(kind, ops)| {
            let (file, args): (PathBuf, Vec<String>) = match kind {
                0 => {
                    let p = dir.join("rec.csv");
                    std::fs::write(&p, apply(&base, &ops)).unwrap();
                    (
                        p.clone(),
                        vec!["gap".into(), "fixtures/gap/arm3.xml".into(), p.display().to_string()],
                    )
                }
                1 => {
                    let p = dir.join("arm3.xml");
                    std::fs::write(&p, apply(&model, &ops)).unwrap();
                    (p.clone(), vec![p.display().to_string(), "--no-probe".into()])
                }
                _ => {
                    let p = dir.join("rig.toml");
                    std::fs::write(&p, apply(&spec, &ops)).unwrap();
                    let args = vec![
                        "fixtures/bam_xl330/rig.xml".into(),
                        "--no-probe".into(),
                        "--spec".into(),
                        p.display().to_string(),
                    ];
                    (p, args)
                }
            };
            let o = std::process::Command::new(bin).args(&args).output().unwrap();
            let stderr = String::from_utf8_lossy(&o.stderr);
            prop_assert!(!stderr.contains("panicked"), "{:?}: {}", args, stderr);
            let code = o.status.code();
            prop_assert!(matches!(code, Some(0..=2)), "{:?}: exit {:?}\n{}", args, code, stderr);
            if code == Some(2) {
                let text = std::fs::read_to_string(&file).unwrap();
                let at = stderr.find(&format!("{}:", file.display()));
                let Some(at) = at else {
                    return Err(TestCaseError::fail(format!(
                        "{args:?}: exit 2 without the file: {stderr}"
                    )));
                };
                names_a_line(stderr[at..].lines().next().unwrap_or(""), &file, &text)?;
            }
            counts.borrow_mut()[kind] += 1;
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("binary runs per kind (csv, mjcf, spec): {:?}", counts.borrow());
    std::fs::remove_dir_all(&dir).ok();
}

// Minimised cases the property tests found, as regular regression tests.

/// A URDF with a `<link>` line duplicated: MuJoCo says "repeated URDF name" with neither the
/// name nor a line; the error is at the second link's name.
#[test]
fn urdf_with_a_repeated_link_name_fails_at_the_second() {
    let dir = tmp("urdf-dup");
    let src = std::fs::read_to_string("fixtures/rules/urdf-mjcf-drift/urdf/valid.urdf").unwrap();
    let lines: Vec<&str> = src.lines().collect();
    let k = lines.iter().position(|l| l.contains("<link name=\"thigh\"")).unwrap();
    let mut dup = lines.clone();
    dup.insert(k + 1, lines[k]);
    let text = dup.join("\n");
    let p = dir.join("dup.urdf");
    std::fs::write(&p, &text).unwrap();
    let e = modellint::lint::load(&lint_input(p.clone(), None)).err().expect("rejected");
    assert_eq!((e.file.as_path(), e.line), (p.as_path(), Some(k + 2)), "{e}");
    assert!(e.message.contains("second <link> named \"thigh\""), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A recording whose first time is -1e308 (a number flipped by the property test): the
/// control-tick schedule of its span aborted with "capacity overflow"; now an error at that
/// row's line, from the reader (`gap` / `fit`) and from the replay's own check.
#[test]
fn a_time_far_from_the_others_is_an_error_at_its_line() {
    use modellint::sim2real::recording::parse_csv;
    let rec = arm3_recording();
    let mut lines: Vec<String> = rec.lines().map(str::to_string).collect();
    let first = lines.iter().position(|l| l.starts_with("0.00000,")).unwrap();
    lines[first] = lines[first].replacen("0.00000", "-1e308", 1);
    let e = parse_csv(Path::new("far.csv"), &(lines.join("\n") + "\n")).unwrap_err();
    assert_eq!(e.line, Some(first + 1), "{e}");
    assert!(e.message.contains("time jumps by") && e.message.contains("another unit"), "{e}");
    // A late row 10^6 s after the others, without a control rate: the replay would have
    // stepped across the whole span.
    let mut lines: Vec<String> =
        rec.lines().filter(|l| !l.starts_with("# control_rate_hz")).map(str::to_string).collect();
    let last = lines.len() - 1;
    lines[last] = lines[last].replacen(lines[last].split(',').next().unwrap(), "1000000", 1);
    let e = parse_csv(Path::new("late.csv"), &(lines.join("\n") + "\n")).unwrap_err();
    assert_eq!(e.line, Some(last + 1), "{e}");
    // A schedule built in code over such a span is an error, not an allocation.
    let mut t: Vec<f64> = (0..10).map(|i| i as f64 * 0.01).collect();
    t.push(1e9);
    let c = vec![0.0; t.len()];
    let r = modellint::sim2real::commands::reconstruct(
        &t,
        &[&c[..]],
        Some(100.0),
        0.0,
        Default::default(),
        Default::default(),
    );
    assert!(matches!(r, Err(modellint::sim2real::commands::ScheduleError::Span { .. })), "{r:?}");
}

/// A spec whose `[robot] keyframe` names no keyframe of the model: the error is at that key in
/// the spec (it named the model file, without a line).
#[test]
fn a_spec_keyframe_the_model_lacks_fails_at_the_key() {
    let dir = tmp("keyframe");
    let src = std::fs::read_to_string("models/asimov.toml").unwrap();
    let text = src.replace("keyframe = \"stand\"", "keyframe = \"nan\"");
    assert_ne!(text, src);
    let p = dir.join("asimov.toml");
    std::fs::write(&p, &text).unwrap();
    let line = 1 + text.lines().position(|l| l.starts_with("keyframe = ")).unwrap();
    let input = lint_input(PathBuf::from("models/asimov.xml"), Some(p.clone()));
    let e = modellint::lint::load(&input).err().expect("rejected");
    assert_eq!((e.file.as_path(), e.line, e.column), (p.as_path(), Some(line), Some(12)), "{e}");
    assert!(e.message.contains("keyframe `nan`"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
