//! Lint and probe timings (issue targets: static lint of models/asimov.xml < 50 ms including the
//! MuJoCo compile; mesh-heavy models within 1.2× of MuJoCo's own compile; all probes for a 23-DoF
//! humanoid < 1 s on one core). Prints figures; asserts nothing.
//! Usage: cargo run --release --example lint_bench [-- MODEL SPEC ...]

use std::time::Instant;

use modellint::lint::{LintInput, load, run_rules};
use mujoco_rs::prelude::*;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn bench(model: &str, spec: Option<&str>) {
    let input = LintInput {
        model: model.into(),
        spec: spec.map(Into::into),
        config: None,
        select: vec![],
        ignore: vec![],
    };
    let reps = 7;
    let mut compile = Vec::new();
    let mut lint = Vec::new();
    let mut probes = Vec::new();
    let mut probe_steps = 0usize;
    for _ in 0..reps {
        let t = Instant::now();
        let m = MjModel::from_xml(model).expect("model compiles");
        compile.push(t.elapsed().as_secs_f64());
        drop(m);
        let t = Instant::now();
        let l = load(&input).expect("loads");
        let mut f = run_rules(&l);
        lint.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        modellint::lint::confirm(&l, &mut f);
        probes.push(t.elapsed().as_secs_f64());
        probe_steps = f.iter().filter_map(|x| x.probe.as_ref()).map(|p| p.steps).sum();
    }
    // Bare stepping loop on the same model: the physical limit for probe throughput.
    let m = MjModel::from_xml(model).unwrap();
    let mut d = MjData::new(&m);
    if m.ffi().nkey > 0 {
        let _ = d.reset_keyframe(0);
    }
    let n = 20_000;
    let t = Instant::now();
    for _ in 0..n {
        d.step();
    }
    let bare = n as f64 / t.elapsed().as_secs_f64();
    // Per-rule cost on a loaded model.
    let l = load(&input).unwrap();
    let mut per_rule = Vec::new();
    for rule in modellint::rules::registry() {
        let meta = rule.meta();
        let cx = modellint::rules::Context {
            robot: &l.robot,
            spec: l.spec.as_ref(),
            sources: &l.sources,
            options: Default::default(),
            meta,
            level: meta.default_level,
        };
        let t = Instant::now();
        let mut out = Vec::new();
        for _ in 0..3 {
            out.clear();
            rule.check(&cx, &mut out);
        }
        per_rule.push((t.elapsed().as_secs_f64() / 3.0, meta.id));
    }
    per_rule.sort_by(|a, b| b.0.total_cmp(&a.0));
    let (c, l, p) = (median(compile), median(lint), median(probes));
    println!("{model}");
    println!("  MuJoCo compile alone      {:8.1} ms", c * 1e3);
    println!("  static lint (load+rules)  {:8.1} ms  ({:.2}× the compile)", l * 1e3, l / c);
    println!(
        "  probes                    {:8.1} ms  ({probe_steps} steps, {:.0} steps/s)",
        p * 1e3,
        probe_steps as f64 / p.max(1e-9)
    );
    let top: Vec<String> =
        per_rule.iter().take(3).map(|(t, id)| format!("{id} {:.1} ms", t * 1e3)).collect();
    println!("  costliest rules           {}", top.join(", "));
    println!(
        "  bare mj_step loop         {:8.0} steps/s (probe throughput {:.2}× of it)",
        bare,
        probe_steps as f64 / p.max(1e-9) / bare
    );
}

fn main() {
    modellint::model::mj::silence_warnings();
    rayon::ThreadPoolBuilder::new().num_threads(1).build_global().ok();
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() {
        bench("models/asimov.xml", None);
        let t1 = "../shared/data/models/booster_t1/scene.xml";
        if std::path::Path::new(t1).exists() {
            bench(t1, Some("fixtures/booster_t1.toml"));
        } else {
            println!("(../shared absent: Booster T1 skipped)");
        }
    } else {
        for pair in args.chunks(2) {
            bench(&pair[0], pair.get(1).map(String::as_str));
        }
    }
}
