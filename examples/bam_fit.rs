//! BAM XL330 servo identification with held-out gains.
//!
//! `cargo run --release --example bam_fit -- ../shared/data/recordings/bam_xl330 [--evals N] [--cmaes] [--json OUT]`
//!
//! For each firmware P gain: fit on the 12 logs of the other three gains by greedy forward
//! selection of effects (src/fit/servo_fit.rs), evaluate on the 4 held-out logs. Prints the
//! per-fold table, the average held-out MAE and BAM's published anchors on the same 16 logs.

use std::path::PathBuf;
use std::time::Instant;

use modellint::fit::servo_fit::{self, FitOpts, Optimiser};
use modellint::model::source::SourceMap;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut dir = None;
    let mut o = FitOpts::default();
    let mut json = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--evals" => o.max_evals = it.next().and_then(|v| v.parse().ok()).expect("--evals N"),
            "--cmaes" => o.optimiser = Optimiser::Cmaes,
            "--json" => json = it.next().map(PathBuf::from),
            _ => dir = Some(PathBuf::from(a)),
        }
    }
    let mut dir = dir.unwrap_or_else(|| PathBuf::from("../shared/data/recordings/bam_xl330"));
    if !dir.is_dir() && dir.is_relative() {
        // A worktree under wt/ has the data at ../../shared: look beside the crate's ancestors.
        let rel: PathBuf =
            dir.components().skip_while(|c| matches!(c, std::path::Component::ParentDir)).collect();
        if let Some(d) = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .ancestors()
            .skip(1)
            .take(3)
            .map(|a| a.join(&rel))
            .find(|d| d.is_dir())
        {
            dir = d;
        }
    }
    let t0 = Instant::now();
    let rig = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/bam_xl330/rig.xml");
    let robot = modellint::model::load(&mut SourceMap::default(), &rig, None).expect("rig loads");
    let logs = servo_fit::load_logs(&dir).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2)
    });
    let (report, folds) =
        modellint::fit::servo_report::run(&robot, &logs, &o, &|m| eprintln!("{m}")).unwrap_or_else(
            |e| {
                eprintln!("error: {e}");
                std::process::exit(2)
            },
        );
    print!("{report}");
    eprintln!("total {:.0} s", t0.elapsed().as_secs_f64());
    if let Some(p) = json {
        std::fs::write(&p, serde_json::to_string_pretty(&folds).unwrap()).expect("write json");
    }
}
