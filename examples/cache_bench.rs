//! Lint cache and probe timings (targets: an unchanged re-lint of a mesh-heavy model, answered
//! from the cache of lint results keyed by every input's hash, < 100 ms; cold ≤ 1.0× MuJoCo's
//! own compile; all probes < 1 s per robot on 2 cores). Prints figures; asserts nothing. Runs the modellint binary as a pre-commit hook
//! would (wall time of the whole process), with a fresh cache directory.
//! Usage: cargo run --release --example cache_bench [-- MODEL ...]

use std::process::Command;
use std::time::Instant;

use mujoco_rs::prelude::*;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[repr(C)]
struct Rusage {
    utime: [i64; 2],
    stime: [i64; 2],
    rest: [i64; 14],
}

unsafe extern "C" {
    fn getrusage(who: i32, usage: *mut Rusage) -> i32;
}

/// CPU seconds (user + system) used by finished child processes so far.
fn children_cpu() -> f64 {
    const RUSAGE_CHILDREN: i32 = -1;
    let mut r = Rusage { utime: [0; 2], stime: [0; 2], rest: [0; 14] };
    // SAFETY: getrusage fills the struct (Linux x86-64/aarch64 layout: two timevals + 14 longs).
    unsafe { getrusage(RUSAGE_CHILDREN, &mut r) };
    (r.utime[0] + r.stime[0]) as f64 + (r.utime[1] + r.stime[1]) as f64 * 1e-6
}

/// (wall, CPU) seconds of one modellint process. On a loaded machine the wall time includes
/// waiting for a core; the CPU time is what the run costs.
fn run(bin: &str, args: &[&str], cache: &std::path::Path) -> (f64, f64) {
    let c0 = children_cpu();
    let t = Instant::now();
    let out = Command::new(bin)
        .args(args)
        .env("MODELLINT_CACHE_DIR", cache)
        .env_remove("GITHUB_ACTIONS")
        .output()
        .expect("modellint runs");
    let dt = t.elapsed().as_secs_f64();
    assert!(
        out.status.code().is_some_and(|c| c < 2),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (dt, children_cpu() - c0)
}

fn med2(v: &[(f64, f64)]) -> (f64, f64) {
    (median(v.iter().map(|x| x.0).collect()), median(v.iter().map(|x| x.1).collect()))
}

fn bench(bin: &str, model: &str) {
    let reps = 5;
    let cache = std::env::temp_dir().join(format!("modellint-cache-bench-{}", std::process::id()));
    // MuJoCo keeps decoded mesh files in an in-process asset cache, so only the first compile
    // of a model in a process is what a fresh `modellint` process pays.
    let mut compile = Vec::new();
    let t = Instant::now();
    let m = MjModel::from_xml(model).expect("model compiles");
    let first = t.elapsed().as_secs_f64();
    drop(m);
    for _ in 0..reps {
        let t = Instant::now();
        let m = MjModel::from_xml(model).expect("model compiles");
        compile.push(t.elapsed().as_secs_f64());
        drop(m);
    }
    let mut nocache = Vec::new();
    let mut cold = Vec::new();
    let mut warm = Vec::new();
    let mut probes_warm = Vec::new();
    for _ in 0..reps {
        let _ = std::fs::remove_dir_all(&cache);
        nocache.push(run(bin, &[model, "--no-probe", "--no-cache", "--format", "json"], &cache));
        cold.push(run(bin, &[model, "--no-probe", "--format", "json"], &cache));
        warm.push(run(bin, &[model, "--no-probe", "--format", "json"], &cache));
        probes_warm.push(run(bin, &[model, "--format", "json"], &cache));
    }
    let _ = std::fs::remove_dir_all(&cache);
    let c = first;
    let again = median(compile);
    let (n, k, w, p) = (med2(&nocache), med2(&cold), med2(&warm), med2(&probes_warm));
    println!("{model}                                   wall ms   CPU ms");
    println!(
        "  MuJoCo compile alone, first in process{:8.1}  (again in the same process: {:.1} ms)",
        c * 1e3,
        again * 1e3
    );
    println!(
        "  modellint --no-probe, --no-cache      {:8.1} {:8.1}  ({:.2}× the compile, wall)",
        n.0 * 1e3,
        n.1 * 1e3,
        n.0 / c
    );
    println!(
        "  modellint --no-probe, cold cache      {:8.1} {:8.1}  ({:.2}× the compile, wall; writes the .mjb)",
        k.0 * 1e3,
        k.1 * 1e3,
        k.0 / c
    );
    println!(
        "  modellint --no-probe, warm cache      {:8.1} {:8.1}  (target < 100 ms)",
        w.0 * 1e3,
        w.1 * 1e3
    );
    println!(
        "  modellint with probes, warm cache     {:8.1} {:8.1}  (probes ≈ {:.1} ms wall, {:.1} ms CPU; target < 1000 ms)",
        p.0 * 1e3,
        p.1 * 1e3,
        (p.0 - w.0) * 1e3,
        (p.1 - w.1) * 1e3
    );
}

fn main() {
    modellint::model::mj::silence_warnings();
    // The modellint binary built beside this example (target/release/examples/../modellint).
    let exe = std::env::current_exe().expect("own path");
    let bin_path =
        exe.parent().and_then(|p| p.parent()).map(|p| p.join("modellint")).expect("target dir");
    assert!(
        bin_path.is_file(),
        "build the binary first: cargo build --release ({})",
        bin_path.display()
    );
    let bin = bin_path.to_str().expect("utf-8 path");
    let args: Vec<String> = std::env::args().skip(1).collect();
    let models: Vec<String> = if args.is_empty() {
        let mut v = vec!["models/asimov.xml".to_string()];
        for m in [
            "../shared/data/models/booster_t1/scene.xml",
            "../shared/data/models/unitree_h1/scene.xml",
        ] {
            if std::path::Path::new(m).exists() {
                v.push(m.to_string());
            } else {
                println!("({m} absent: skipped)");
            }
        }
        v
    } else {
        args
    };
    for m in &models {
        bench(bin, m);
    }
}
