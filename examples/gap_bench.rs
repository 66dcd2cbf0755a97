//! Replay throughput at the seed study's scale: 23 joints, 123 episodes, 3,687 s, 284,794
//! samples at irregular timestamps, on the Booster T1 (position actuators kp 75), against a bare
//! MuJoCo stepping loop over the same simulated time (same threads). Run with
//! `cargo run --release --example gap_bench [MODEL]` (bench/gap_bench.sh); set
//! GAP_BENCH_SCALE=0.1 for a tenth of the dataset. Prints wall times and their ratio.

use std::path::PathBuf;
use std::time::Instant;

use modellint::model::{mj, source::SourceMap};
use modellint::sim2real::gap::{self, GapOptions};
use modellint::sim2real::recording::{JointTrace, Recording};
use modellint::sim2real::replay::{self, ReplayOptions, Replayer};
use mujoco_rs::prelude::*;
use rayon::prelude::*;

const EPISODES: usize = 123;
const TOTAL_S: f64 = 3687.0;
const TOTAL_SAMPLES: usize = 284_794;

fn main() {
    let model = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/work/shared/data/models/booster_t1/scene.xml"));
    let scale: f64 =
        std::env::var("GAP_BENCH_SCALE").ok().and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let mut map = SourceMap::default();
    let robot = modellint::model::load(&mut map, &model, None).expect("model loads");
    let joints: Vec<_> = robot
        .joints
        .iter()
        .filter(|j| j.is_scalar() && !robot.actuators_on_joint(j.id).is_empty())
        .collect();
    println!(
        "model {} : {} actuated joints, timestep {} s",
        model.display(),
        joints.len(),
        robot.opt.timestep
    );

    // Episode lengths ~30 s ± 16 s, scaled to the totals; samples proportional to duration.
    let n_ep = ((EPISODES as f64 * scale).round() as usize).max(1);
    let raw: Vec<f64> = (0..EPISODES).map(|k| 30.0 + 16.0 * ((k as f64) * 1.3).sin()).collect();
    let sum: f64 = raw.iter().sum();
    let durs: Vec<f64> = raw.iter().map(|d| d * TOTAL_S / sum).collect();
    let mut counts: Vec<usize> =
        durs.iter().map(|d| (d / TOTAL_S * TOTAL_SAMPLES as f64).floor() as usize).collect();
    let short = TOTAL_SAMPLES - counts.iter().sum::<usize>();
    for c in counts.iter_mut().take(short) {
        *c += 1;
    }
    let mut recs = Vec::new();
    for k in 0..n_ep {
        let (dur, n) = (durs[k], counts[k]);
        let dt = dur / (n - 1) as f64;
        // Irregular: ±30 % jitter (deterministic), strictly increasing.
        let t: Vec<f64> = (0..n)
            .map(|i| {
                i as f64 * dt
                    + if i == 0 || i == n - 1 { 0.0 } else { 0.3 * dt * ((i * 7 + k) as f64).sin() }
            })
            .collect();
        let js = joints
            .iter()
            .enumerate()
            .map(|(ji, j)| {
                let q0 = robot.key.qpos.get(j.qposadr).copied().unwrap_or(0.0);
                let (a, f) = (0.15 + 0.05 * (ji % 3) as f64, 0.3 + 0.1 * ((ji + k) % 5) as f64);
                let mut lo = j.range[0];
                let mut hi = j.range[1];
                if !j.limited {
                    lo = -10.0;
                    hi = 10.0;
                }
                let q: Vec<f64> = t
                    .iter()
                    .map(|&x| {
                        (q0 + a * (2.0 * std::f64::consts::PI * f * x).sin().powi(2)).clamp(lo, hi)
                    })
                    .collect();
                let mut jt = JointTrace::new(j.name.clone(), q.clone());
                jt.q_cmd = Some(q);
                jt
            })
            .collect();
        recs.push(Recording {
            source: PathBuf::from(format!("episode_{k:03}.csv")),
            meta: Default::default(),
            control_rate_hz: Some(100.0),
            control_t0_s: None,
            t,
            joints: js,
            base: None,
        });
    }
    let samples: usize = recs.iter().map(|r| r.t.len()).sum();
    let sim_s: f64 = recs.iter().map(|r| r.duration()).sum();
    println!(
        "dataset: {} episodes, {} joints, {:.0} s, {} samples ({:.1} Hz mean), {} rayon threads",
        recs.len(),
        joints.len(),
        sim_s,
        samples,
        (samples - recs.len()) as f64 / sim_s,
        rayon::current_num_threads()
    );

    let rp = Replayer::new(&robot);
    let t_start = Instant::now();
    let eps: Vec<_> = replay::replay_all(&rp, &recs, &ReplayOptions::default(), None)
        .into_iter()
        .map(|e| e.expect("replay"))
        .collect();
    let t_replay = t_start.elapsed().as_secs_f64();
    let diverged = eps.iter().filter(|e| e.diverged.is_some()).count();
    let t1 = Instant::now();
    let rep = gap::compute(&recs, &eps, &gap::region_from_name, &GapOptions::default());
    let t_metrics = t1.elapsed().as_secs_f64();

    // Bare loop: same models, same simulated time, ctrl set every 10 steps, no sampling.
    let m = &robot.mj;
    let dt = mj::raw(m).opt.timestep;
    let t2 = Instant::now();
    let steps: usize = recs
        .par_iter()
        .map(|r| {
            let mut d = MjData::new(m);
            let nsteps = (r.duration() / dt).ceil() as usize;
            for s in 0..nsteps {
                if s % 10 == 0 {
                    let ctrl = d.ctrl_mut();
                    for (i, c) in ctrl.iter_mut().enumerate() {
                        *c = 0.1 * ((s as f64 * dt + i as f64) * 2.0).sin();
                    }
                }
                d.step();
            }
            nsteps
        })
        .sum();
    let t_bare = t2.elapsed().as_secs_f64();
    println!("replay (all episodes, parallel): {t_replay:.2} s wall  ({diverged} diverged)");
    println!("gap metrics (spectra, decomposition, phases): {t_metrics:.2} s wall");
    println!(
        "bare MuJoCo loop, {steps} steps: {t_bare:.2} s wall  ({:.1} µs/step/thread)",
        t_bare * 1e6 * rayon::current_num_threads() as f64 / steps as f64
    );
    println!(
        "replay / bare = {:.3}   (replay + metrics) / bare = {:.3}",
        t_replay / t_bare,
        (t_replay + t_metrics) / t_bare
    );
    println!(
        "dataset gap: MAE {:.3}° RMSE {:.3}° G {:.3}",
        rep.position_mae.to_degrees(),
        rep.position_rmse.to_degrees(),
        rep.gap_overall
    );
}
