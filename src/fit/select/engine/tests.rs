use super::fitting::{ends_on_bound, grid_best};
use super::floors::{discretisation_part, zero_at_every_order};
use super::*;
use crate::fit::effects::{Backlash, CoulombFriction, Effect, StribeckFriction, ViscousDamping};
use crate::fit::optim::Bounds;
use crate::sim2real::commands::pseudo_sign;
use crate::synth::{self, Settings};

/// The lightly damped pendulum servo, clean (the exact model), logged exactly at the control
/// ticks (no command to reconstruct) with velocity noise `qd_noise` and nothing else.
fn pendulum_at_ticks(qd_noise: f64) -> (crate::model::Robot, Vec<Recording>) {
    pendulum_with(&[], qd_noise)
}

/// [`pendulum_at_ticks`] with `hidden` effects in the robot that records.
fn pendulum_with(
    hidden: &[crate::synth::truth::Hidden],
    qd_noise: f64,
) -> (crate::model::Robot, Vec<Recording>) {
    let s = Settings {
        episodes: 3,
        duration_s: 3.0,
        log_at_ticks: true,
        noise: 0.0,
        quant_bits: 0,
        qd_noise,
        drop: 0.0,
        seed: 5,
        ..Settings::default()
    };
    synth::recorded::recorded(
        "fixtures/synth/pendulum_servo.xml",
        &["servo".to_string()],
        hidden,
        &s,
    )
}

/// [`pendulum_at_ticks`]' replay floor [rad RMS] with the replay started at the first row.
fn start_floor(qd_noise: f64) -> f64 {
    let (robot, recs) = pendulum_at_ticks(qd_noise);
    let opts = FitOptions { estimate_start: false, ..FitOptions::default() };
    let engine = Engine::new(&robot, &recs, &opts);
    let errs = engine.errors(&recs, &[]).expect("replay");
    let f = engine.floors(&recs, &[], &errs);
    assert_eq!(f.len(), 1);
    f[0].reconstruction.sqrt()
}

#[test]
fn a_fit_stuck_on_a_bound_gets_a_grid_start() {
    let b = Bounds { lo: vec![0.3, 0.2], hi: vec![3.0, 5.0] };
    // Ended on kd's upper bound from (1, 1): a restart; started there, or interior: none.
    assert!(ends_on_bound(&[0.99, 5.0], &[1.0, 1.0], &b));
    assert!(ends_on_bound(&[0.3004, 1.2], &[1.0, 1.0], &b));
    assert!(!ends_on_bound(&[0.99, 5.0], &[1.0, 5.0], &b));
    assert!(!ends_on_bound(&[0.4, 2.0], &[1.0, 1.0], &b));
    // Two basins: a narrow one at (0.4, 2) and a wide shallow one towards the corner. The
    // grid is log-spaced on positive bounds and its best point is in the narrow basin.
    let obj = |x: &[f64]| {
        let narrow = ((x[0] / 0.4).ln().powi(2) + (x[1] / 2.0).ln().powi(2)).min(0.6);
        narrow + 0.3 * (1.0 - x[1] / 5.0)
    };
    let g = grid_best(&obj, &b).expect("finite");
    assert_eq!(g.len(), 2);
    assert!((g[0] / 0.4).ln().abs() < 0.2 && (g[1] / 2.0).ln().abs() < 0.3, "{g:?}");
    // Three parameters on a zero lower bound: 3 linear points each, at 20 / 50 / 80 % (27
    // evaluations, all inside the box).
    let lin = Bounds { lo: vec![0.0, 0.0, 0.0], hi: vec![1.0, 1.0, 1.0] };
    let count = std::cell::Cell::new(0usize);
    let _ = grid_best(
        &|x: &[f64]| {
            count.set(count.get() + 1);
            if x.iter().all(|v| (0.2..=0.8).contains(v)) { 1.0 } else { f64::NAN }
        },
        &lin,
    );
    assert_eq!(count.get(), 27);
    // Every point fails: no start.
    assert!(grid_best(&|_: &[f64]| f64::NAN, &b).is_none());
    // Two parameters on positive bounds: 5 points each at 10 … 90 % of the log range.
    let g = grid_best(&|x: &[f64]| x[0] + x[1], &b).expect("finite");
    assert!((g[0] - 0.3 * 10f64.powf(0.1)).abs() < 1e-12, "{g:?}");
}

/// Exact positions, exact commands, the exact model: the only error left is the first row's
/// noisy velocity, ringing in the lightly damped servo. Started at the first row, the
/// residual is that ringing; with the start estimated from the episode it must vanish (the
/// true start explains the data exactly), and the floor's start part with it.
#[test]
fn an_estimated_start_removes_the_first_rows_noise() {
    let (robot, recs) = pendulum_at_ticks(0.04);
    let rms = |estimate_start: bool| {
        let opts = FitOptions { estimate_start, ..FitOptions::default() };
        let engine = Engine::new(&robot, &recs, &opts);
        let errs = engine.errors(&recs, &[]).expect("replay");
        let f = engine.floors(&recs, &[], &errs);
        (errs.rmse(), f[0].reconstruction.sqrt())
    };
    let (read, read_floor) = rms(false);
    let (est, est_floor) = rms(true);
    assert!(read > 2e-5, "the first row's velocity noise rings: {read}");
    assert!(est < read / 10.0, "estimated start: {est} vs first row {read}");
    assert!(est_floor < read_floor / 3.0, "floor {est_floor} vs {read_floor}");
}

/// A joint whose model can stick (here Coulomb friction, kept at zero so that the
/// simulation is the nominal one) is left out of the start estimate: its residual is the
/// one of the replay started at the first row, to the last bit; with a smooth effect kept
/// (viscous damping, also zero) the start is still estimated.
#[test]
fn a_joint_that_can_stick_keeps_its_first_row() {
    let (robot, recs) = pendulum_at_ticks(0.04);
    let kept = |id: &str| Applied {
        effect: crate::fit::effects::by_id(id).expect("effect"),
        joints: vec!["servo".into()],
        params: vec![0.0],
    };
    let rms = |estimate_start: bool, applied: &[Applied]| {
        let opts = FitOptions { estimate_start, ..FitOptions::default() };
        Engine::new(&robot, &recs, &opts).errors(&recs, applied).expect("replay").rmse()
    };
    let read = rms(false, &[]);
    assert_eq!(rms(true, &[kept(CoulombFriction.id())]).to_bits(), read.to_bits());
    assert_eq!(rms(true, &[kept(Backlash.id())]).to_bits(), read.to_bits());
    assert!(rms(true, &[kept(ViscousDamping.id())]) < read / 10.0);
    // Once the friction is kept, the sensitivities are measured with it and the joint
    // takes part again; a model without it is now the one left alone.
    let opts = FitOptions { estimate_start: true, ..FitOptions::default() };
    let engine = Engine::new(&robot, &recs, &opts);
    engine.set_start_model(&[kept(CoulombFriction.id()), kept(ViscousDamping.id())]);
    let with = engine.errors(&recs, &[kept(CoulombFriction.id())]).expect("replay").rmse();
    assert!(with < read / 10.0, "{with} vs {read}");
    let without = engine.errors(&recs, &[]).expect("replay").rmse();
    assert_eq!(without.to_bits(), read.to_bits());
}

/// The replay starts from the first row; a noisy first velocity makes a lightly damped servo
/// ring, and the floor counts it: nothing with exact readings logged at the ticks, and an
/// RMS that doubles with the velocity noise (the response is linear in the start error).
/// A servo too stiff for its model's 5 ms step, recorded in nearly continuous time: MuJoCo
/// stepped by hand at 5 ms / 16, one row at each 100 Hz tick with the tick's command and a
/// small noise. The model's own replay misses it by its discretisation alone; the floor
/// counts that part (about the replays' own difference) and the search stops there with
/// nothing fitted. Recorded at the model's own steps, the floor has no timestep part.
#[test]
fn recordings_in_continuous_time_count_the_timestep_as_floor() {
    let xml = r#"<mujoco><option gravity="0 0 0" timestep="0.005" integrator="implicitfast"/>
  <worldbody><body><joint name="j" type="hinge" axis="0 1 0" damping="0.02"/>
<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/></body></worldbody>
  <actuator><position joint="j" kp="20" kv="0.3"/></actuator></mujoco>"#;
    let (robot, dir) = crate::sim2real::replay::tests::robot_from_xml("disc-floor", xml);
    // `sub` physics steps per model step; rows at the ticks (10 ms = 2 model steps).
    let record = |sub: usize| -> Vec<Recording> {
        let mut m = robot.mj.clone();
        m.opt_mut().timestep = 0.005 / sub as f64;
        (0..4)
            .map(|e| {
                let ticks = 300usize;
                // A new level every 0.2–0.3 s, from a fixed sequence.
                let cmd: Vec<f64> =
                    (0..ticks).map(|k| 0.4 * ((k / (20 + 5 * e) + e) as f64 * 2.3).sin()).collect();
                let mut d = mujoco_rs::prelude::MjData::new(&m);
                let (mut q, mut qd) = (Vec::new(), Vec::new());
                for (k, c) in cmd.iter().enumerate() {
                    let noise = 2e-4 * pseudo_sign((e * 1000 + k) as u64);
                    q.push(d.qpos()[0] + noise);
                    qd.push(d.qvel()[0]);
                    d.ctrl_mut()[0] = *c;
                    for _ in 0..2 * sub {
                        d.step();
                    }
                }
                let mut j = crate::sim2real::recording::JointTrace::new("j", q);
                j.q_cmd = Some(cmd);
                j.qd = Some(qd);
                Recording {
                    source: format!("ep{e}.csv").into(),
                    meta: Default::default(),
                    control_rate_hz: Some(100.0),
                    control_t0_s: Some(0.0),
                    t: (0..ticks).map(|k| k as f64 * 0.01).collect(),
                    joints: vec![j],
                    base: None,
                }
            })
            .collect()
    };
    let opts = FitOptions { estimate_start: false, ..FitOptions::default() };
    // The floor and what its measured parts replayed, in multiples of the dataset.
    let floor_of = |recs: &[Recording]| {
        let engine = Engine::new(&robot, recs, &opts);
        let errs = engine.errors(recs, &[]).expect("replay");
        let before = engine.rollout_stats().simulated_s;
        let f = engine.floors(recs, &[], &errs).remove(0);
        let secs: f64 = recs.iter().map(|r| r.t.last().unwrap() - r.t[0]).sum();
        (f, (engine.rollout_stats().simulated_s - before) / secs)
    };
    // Continuous time: the residual is well above noise, the timestep part carries it; its
    // value needs the replay at dt/4 (the reconstruction's replay and those at dt/2 and dt/4).
    let cont = record(16);
    let (f, cost) = floor_of(&cont);
    assert!((cost - 3.0).abs() < 1e-6, "{cost} replays");
    // The part is extrapolated to continuous time from the replays at dt, dt/2 and dt/4: about
    // all of the residual above the noise (the recordings, at dt/16, still hold 1/16 of a
    // first-order method's error, so the part may exceed it a little).
    assert!(f.ms > 5.0 * (f.white + f.reconstruction), "{f:?}");
    let above = f.ms - f.white - f.reconstruction;
    assert!(f.discretisation > 0.8 * above && f.discretisation < 1.5 * above, "{f:?}");
    assert!(f.reached(opts.policy.white_ratio), "{f:?}");
    let out = super::super::fit(&robot, &cont, &opts);
    assert!(out.selected.is_empty() && out.stopped_at_floor, "{:?}", out.selected);
    // The model's own steps: no timestep part, the floor is the noise.
    // The replay at dt/2 already shows the recordings farther from every continuous-time
    // limit a first-order or better integrator allows: the one at dt/4 is not made.
    let own = record(1);
    let (f, cost) = floor_of(&own);
    assert_eq!(f.discretisation, 0.0, "{f:?}");
    assert!((cost - 2.0).abs() < 1e-6, "{cost} replays");
    assert!(f.reached(opts.policy.white_ratio), "{f:?}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The timestep's part: the recordings count as finer than the model on a majority of
/// the joints that moved (the finer replay closer at all, on joints whose residual that
/// difference and the floor can explain); then every joint gets its replays' difference.
/// Hand-made mean squares [coarse, fine, diff].
#[test]
fn the_timestep_part_needs_most_joints_closer_to_the_finer_replay() {
    let base = [1.0, 1.0, 1.0];
    // Two of three joints closer to the finer replay by its whole shift: all three count.
    let finer = [[3.0, 1.0, 2.0], [2.0, 1.5, 0.5], [1.5, 1.4, 0.5]];
    assert_eq!(discretisation_part(&finer, &base), vec![2.0, 0.5, 0.5]);
    // One of three (the others farther from the finer replay): none.
    let one = [[3.0, 1.0, 2.0], [1.0, 1.5, 0.5], [1.0, 1.5, 0.5]];
    assert_eq!(discretisation_part(&one, &base), vec![0.0; 3]);
    // Closer by a little is a vote: chainsim KR1's kept payload (tests/independent_chain.rs),
    // (coarse − fine) / diff per joint hip −0.58, knee 0.41, ankle 0.93 — two of three.
    let kr1 = [[3.0, 3.58, 1.0], [3.0, 2.59, 1.0], [3.0, 2.07, 1.0]];
    assert_eq!(discretisation_part(&kr1, &base), vec![1.0; 3]);
    // As close as the coarse replay is not closer: one vote of three, none.
    let tie = [[2.0, 2.0, 1.0], [2.0, 2.0, 1.0], [3.0, 2.07, 1.0]];
    assert_eq!(discretisation_part(&tie, &base), vec![0.0; 3]);
    // A residual far beyond the floor and the shift (a missing effect): no vote, however
    // much closer the finer replay happens to be.
    let big = [[40.0, 30.0, 2.0], [30.0, 25.0, 0.5], [1.5, 1.2, 0.5]];
    assert_eq!(discretisation_part(&big, &base), vec![0.0; 3]);
    // No joint moved between the replays.
    assert_eq!(discretisation_part(&[[1.0, 1.0, 0.0]], &[1.0]), vec![0.0]);
}

/// The replay at dt / r² is skipped only when no continuous-time limit a first-order or better
/// integrator allows (q(dt/r) + t (q(dt/r) − q(dt)), t in [0, 1/(r − 1)]) could give the
/// timestep a part: on pseudo-random replays, residuals and floors (some joints explainable by
/// the timestep, some not), every such limit, made sample by sample, gives none. And the test is
/// not idle: it skips on some data and measures on data where some limit gives a part.
#[test]
fn the_finest_replay_is_skipped_only_when_no_limit_could_give_a_part() {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut u = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let (mut skipped, mut needed) = (0, 0);
    for case in 0..400 {
        let r = 2 + case % 2;
        let top = 1.0 / (r as f64 - 1.0);
        let joints = 1 + case % 4;
        let n = 60;
        // Per joint: the coarse replay a, the finer b, the recordings q.
        let mut reps = Vec::new();
        let mut base = Vec::new();
        for _ in 0..joints {
            let (miss, shift, toward) = (u().abs() * 3.0, u().abs(), u());
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
            let b: Vec<f64> = a.iter().map(|x| x + shift * (0.1 + 0.05 * u()) * x.cos()).collect();
            // The recordings: toward (or away from) the finer replays, a missing effect, noise.
            let q: Vec<f64> = a
                .iter()
                .zip(&b)
                .map(|(x, y)| x + toward * 2.0 * (y - x) + miss * 0.05 * u())
                .collect();
            reps.push((q, a, b));
            base.push(1e-4 * u().abs());
        }
        let ms = |v: Vec<f64>| v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64;
        let bracket: Vec<[f64; 4]> = reps
            .iter()
            .map(|(q, a, b)| {
                let d = |f: &dyn Fn(usize) -> f64| (0..n).map(f).collect::<Vec<f64>>();
                let x = d(&|i| (q[i] - b[i]) * (b[i] - a[i])).iter().sum::<f64>() / n as f64;
                [ms(d(&|i| q[i] - a[i])), ms(d(&|i| q[i] - b[i])), x, ms(d(&|i| b[i] - a[i]))]
            })
            .collect();
        let skip = zero_at_every_order(&bracket, &base, r);
        let mut some_part = false;
        for k in 0..=40 {
            let t = top * k as f64 / 40.0;
            let sums: Vec<[f64; 3]> = reps
                .iter()
                .map(|(q, a, b)| {
                    let inf: Vec<f64> = (0..n).map(|i| b[i] + t * (b[i] - a[i])).collect();
                    let d = |f: &dyn Fn(usize) -> f64| ms((0..n).map(f).collect());
                    [d(&|i| q[i] - a[i]), d(&|i| q[i] - inf[i]), d(&|i| a[i] - inf[i])]
                })
                .collect();
            let part = discretisation_part(&sums, &base);
            some_part |= part.iter().any(|p| *p > 0.0);
            assert!(!(skip && some_part), "case {case} at t = {t}: {bracket:?} {base:?}");
        }
        skipped += usize::from(skip);
        needed += usize::from(!skip && some_part);
    }
    assert!(skipped > 40 && needed > 40, "skipped {skipped}, needed {needed}");
}

#[test]
fn the_floor_counts_the_start_state_noise() {
    let exact = start_floor(0.0);
    assert!(exact < 1e-6, "{exact}");
    let (a, b) = (start_floor(0.02), start_floor(0.04));
    assert!(a > 2e-5, "{a}");
    assert!((b / a - 2.0).abs() < 0.3, "{a} {b}");
}

/// [`Engine::at_floor`] on the exact model of a noisy recording (0.5 mrad position noise, a
/// 12-bit encoder): the residual is the noise, within `white_ratio` of its white floor, so the
/// answer (at the floor, as the full floors say) comes without a replay; the full floors need
/// their three (reconstruction, dt / 2, dt / 4).
#[test]
fn a_white_residual_is_at_the_floor_without_a_replay() {
    let s = Settings {
        episodes: 2,
        duration_s: 3.0,
        log_at_ticks: true,
        noise: 5e-4,
        quant_bits: 12,
        drop: 0.0,
        seed: 5,
        ..Settings::default()
    };
    let (robot, recs) = synth::recorded::recorded(
        "fixtures/synth/pendulum_servo.xml",
        &["servo".to_string()],
        &[],
        &s,
    );
    let opts = FitOptions { estimate_start: false, ..FitOptions::default() };
    let engine = Engine::new(&robot, &recs, &opts);
    let errs = engine.errors(&recs, &[]).expect("replay");
    let before = engine.rollout_stats().rollouts;
    assert!(engine.at_floor(&recs, &[], &errs));
    assert_eq!(engine.rollout_stats().rollouts, before, "at_floor replayed");
    let ratio = opts.policy.white_ratio;
    let full = engine.floors(&recs, &[], &errs);
    assert!(full.iter().all(|f| f.ms <= ratio * f.white && f.reached(ratio)), "{full:?}");
    assert!(engine.rollout_stats().rollouts > before, "the full floors replay");
}

/// A re-fit from an answer (multiple shooting's windows, `reshoot`) of a non-smooth
/// three-parameter effect runs one simplex from the answer: it lands on the truth, no worse than
/// the full fit from the effect's start (the nested Coulomb fit, then two simplices), for at
/// most half of its rollouts. (The full fit ignores a start for a non-smooth effect: the re-fit
/// cost as much as the search's own fit.)
#[test]
fn a_refit_of_a_non_smooth_answer_starts_from_it() {
    let truth = [0.06, 0.03, 0.2];
    let hidden = [crate::synth::truth::Hidden {
        effect: StribeckFriction.id(),
        joint: "servo".into(),
        params: truth.to_vec(),
    }];
    let (robot, recs) = pendulum_with(&hidden, 0.0);
    let opts = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &opts);
    let joints = vec!["servo".to_string()];
    let e: &'static dyn Effect = &StribeckFriction;
    // The search's answer, a little off (as on other data).
    let start = [0.063, 0.0285, 0.18];
    let count = || engine.rollouts.stats().rollouts;
    let n0 = count();
    let (p, f) = engine.refit_from(&recs, &[], (e, &joints), &start);
    let n1 = count();
    let (p_full, f_full) = engine.fit_from(&recs, &[], (e, &joints), Some(&start));
    let n2 = count();
    let (refit, full) = (n1 - n0, n2 - n1);
    use crate::fit::effects::Applied;
    for (i, t) in truth.iter().enumerate() {
        assert!((p[i] - t).abs() <= 0.1 * t, "re-fit {p:?} for {truth:?}");
    }
    // As good as the full fit: it closes at least 99 % of what the full fit closes of the
    // start's training RMSE (both land within 1e-7 rad of zero on these noiseless recordings).
    let mut at_start = p.clone();
    at_start[..3].copy_from_slice(&start);
    let f0 =
        engine.score(&recs, &[Applied { effect: e, joints: joints.clone(), params: at_start }]);
    assert!(
        f0 - f >= 0.99 * (f0 - f_full),
        "re-fit RMSE {f} against the full fit's {f_full} ({p_full:?}), {f0} at the start"
    );
    assert!(2 * refit <= full, "re-fit {refit} rollouts against the full fit's {full}");
}

#[test]
fn a_simulation_is_counted_once_whatever_the_memo_and_threads_did() {
    let (robot, recs) = pendulum_at_ticks(0.0);
    let opts = FitOptions { estimate_start: false, ..FitOptions::default() };
    let engine = Engine::new(&robot, &recs, &opts);
    let damping: &'static dyn Effect = &ViscousDamping;
    let set =
        |d: f64| vec![Applied { effect: damping, joints: vec!["servo".into()], params: vec![d] }];
    let first = engine.errors(&recs, &set(0.0)).expect("replay");
    // More distinct simulations than the recent memo holds: the first is evicted.
    for i in 1..=RECENT + 1 {
        engine.errors(&recs, &set(0.01 * i as f64)).expect("replay");
    }
    let n = recs.len();
    let before = engine.rollout_stats();
    assert_eq!(before.rollouts, (RECENT + 2) * n);
    assert_eq!(engine.simulations(), RECENT + 2);
    // Asked again: replayed (same answer), not counted.
    let again = engine.errors(&recs, &set(0.0)).expect("replay");
    assert_eq!(again.sse.to_bits(), first.sse.to_bits());
    assert_eq!(engine.rollout_stats().rollouts, before.rollouts);
    assert_eq!(engine.rollout_stats().simulated_s, before.simulated_s);
    assert_eq!(engine.simulations(), RECENT + 2);
    // Many threads asking for one new simulation together: counted once.
    let sse: Vec<u64> = (0..8)
        .into_par_iter()
        .map(|_| engine.errors(&recs, &set(0.5)).expect("replay").sse.to_bits())
        .collect();
    assert!(sse.iter().all(|&s| s == sse[0]));
    assert_eq!(engine.rollout_stats().rollouts, before.rollouts + n);
    assert_eq!(engine.simulations(), RECENT + 3);
}

/// [`Reach`]: on the pendulum with a damping of 0.03 hidden (no noise), the model at the
/// floor is the damping fitted and taken 10 % low (what is left stands for the noise). A
/// candidate is judged on the probes' data only (no replay of anything else), and only once a
/// screen made them; the damping itself (as good as the floor model or better) is within
/// reach, a position offset (which cannot mimic a damping) is not.
///
/// [`Reach`]: super::super::reach::Reach
#[test]
fn an_alias_is_judged_within_reach_of_the_floor_on_the_probes_data_alone() {
    use super::super::reach::Reach;
    use crate::fit::effects::PositionOffset;
    let hidden = [crate::synth::truth::Hidden {
        effect: ViscousDamping.id(),
        joint: "servo".into(),
        params: vec![0.03],
    }];
    let (robot, recs) = pendulum_with(&hidden, 0.0);
    let opts = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &opts);
    let g = vec!["servo".to_string()];
    let (p, _) = engine.fit_one(&recs, &[], &ViscousDamping, &g);
    let p = vec![0.9 * p[0]];
    let floor = [Applied { effect: &ViscousDamping, joints: g.clone(), params: p }];
    // No screen made the probes' data on this base yet.
    assert!(Reach::new(&engine, &recs, &[], &floor).is_none());
    let probes = engine.probe_set(&recs, &[], || vec![recs[0].clone()]);
    let probe_s = probes[0].t.last().unwrap() - probes[0].t[0];
    let reach = Reach::new(&engine, &recs, &[], &floor).expect("probes held");
    let allowed = [ViscousDamping.id().to_string(), PositionOffset.id().to_string()];
    let s = crate::fit::select::Search {
        engine: &engine,
        train: &recs,
        heldout: &recs,
        allowed: &allowed,
    };
    let before = engine.rollout_stats();
    assert!(reach.out_of_reach(&s, None, (&ViscousDamping, &g)).is_none());
    let far = reach.out_of_reach(&s, None, (&PositionOffset, &g));
    let (_, f) = far.expect("a position offset cannot come near a damping");
    let floor_rmse = engine.errors(&probes, &floor).expect("replay").rmse();
    assert!(f > opts.policy.floor_screen_ratio * floor_rmse, "{f} vs {floor_rmse}");
    let after = engine.rollout_stats();
    let budget = 2 * (opts.policy.screen_evals + 1);
    assert!(after.simulated_s - before.simulated_s <= budget as f64 * probe_s + 1e-9);
}

/// Replays are booked to the round reported before them (`"end"` after the rounds), and the
/// totals by round equal those by phase; round 0's trust record of a candidate stands.
#[test]
fn replays_are_booked_to_their_round_and_round_zeros_trust_stands() {
    let (robot, recs) = pendulum_at_ticks(0.0);
    let opts = FitOptions { estimate_start: false, ..FitOptions::default() };
    let engine = Engine::new(&robot, &recs, &opts);
    let damping: &'static dyn Effect = &ViscousDamping;
    let set =
        |d: f64| vec![Applied { effect: damping, joints: vec!["servo".into()], params: vec![d] }];
    let n = recs.len();
    engine.report(0, Phase::Diagnose, None);
    engine.errors(&recs, &set(0.01)).expect("replay");
    engine.report(0, Phase::Screen, None);
    engine.errors(&recs, &set(0.02)).expect("replay");
    engine.report(1, Phase::Add, None);
    engine.errors(&recs, &set(0.03)).expect("replay");
    engine.report(2, Phase::Reshoot, None);
    engine.errors(&recs, &set(0.04)).expect("replay");
    let by_round = engine.rollouts_by_round();
    let rollouts: Vec<(&str, usize)> = by_round.iter().map(|(k, v)| (k.as_str(), v.0)).collect();
    assert_eq!(rollouts, [("0", 2 * n), ("1", n), ("end", n)]);
    let by_round_phase = engine.rollouts_by_round_phase();
    let by_rp: Vec<(&str, &str, usize)> =
        by_round_phase.iter().map(|((r, p), v)| (r.as_str(), *p, v.0)).collect();
    assert_eq!(
        by_rp,
        [("0", "diagnose", n), ("0", "screen", n), ("1", "add", n), ("end", "reshoot", n)]
    );
    // A round's own steps booked apart from `add` stay in the round.
    for p in [
        Phase::LeadFit,
        Phase::Judge,
        Phase::EarlyPair,
        Phase::Refine,
        Phase::RoundErrors,
        Phase::Reach,
    ] {
        assert_eq!(super::round_key(p, 3), "3", "{}", p.name());
    }
    let rounds_s: f64 = by_round.values().map(|v| v.1).sum();
    let phases_s: f64 = engine.rollouts_by_phase().values().map(|v| v.1).sum();
    assert!((rounds_s - phases_s).abs() < 1e-9);
    assert!((rounds_s - engine.rollout_stats().simulated_s).abs() < 1e-9);
    let g = ["servo".to_string()];
    assert_eq!(engine.trusted((damping, &g)), None);
    engine.note_trust((damping, &g), true);
    engine.note_trust((damping, &g), false);
    assert_eq!(engine.trusted((damping, &g)), Some(true));
}

/// What a candidate cost on a base ([`Engine::spent_with`]) is the rollout service's own count
/// of the simulations that ran it, on any dataset and at any values: each counted once (a
/// simulation asked for again is not), the base's replay and another candidate's not at all.
#[test]
fn a_candidate_costs_the_seconds_of_its_own_simulations_counted_once() {
    let (robot, recs) = pendulum_at_ticks(0.0);
    let opts = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &opts);
    let g = vec!["servo".to_string()];
    let with = |e: &'static dyn Effect, p: f64| {
        vec![Applied { effect: e, joints: g.clone(), params: vec![p] }]
    };
    let secs = |r: &[Recording]| r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>();
    // The base's replay (and whatever it measures once per recording) is not the candidate's.
    let _ = engine.errors(&recs, &[]);
    assert_eq!(engine.spent_with(&[], (&ViscousDamping, &g)), 0.0);
    let before = engine.rollout_stats().simulated_s;
    for p in [0.1, 0.2, 0.1] {
        let _ = engine.errors(&recs, &with(&ViscousDamping, p));
    }
    let _ = engine.errors(&recs[..1], &with(&ViscousDamping, 0.3));
    let cost = engine.rollout_stats().simulated_s - before;
    // Two values on the whole set (the third is the first again) and one on a part of it.
    let want = 2.0 * secs(&recs) + secs(&recs[..1]);
    assert!((cost - want).abs() < 1e-3, "{cost} s replayed for {want}");
    let spent = engine.spent_with(&[], (&ViscousDamping, &g));
    assert!((spent - cost).abs() < 1e-3, "{spent} s for {cost} s replayed");
    // Another candidate, or the same one on the candidate's base, has its own count.
    assert_eq!(engine.spent_with(&[], (&CoulombFriction, &g)), 0.0);
    let on = with(&ViscousDamping, 0.1);
    let _ = engine.errors(&recs, &[on.clone(), with(&CoulombFriction, 0.05)].concat());
    assert_eq!(engine.spent_with(&[], (&ViscousDamping, &g)), spent);
    let other = engine.spent_with(&on, (&CoulombFriction, &g));
    assert!((other - secs(&recs)).abs() < 1e-3, "{other} s");
}

/// A round that stops at the floor replays the training set and its floors only (the
/// reconstruction replay and the discretisation's replay at dt/2; recorded at the model's own
/// step, the pendulum is farther from every continuous-time limit that replay allows, and the
/// one at dt/4 is not made): neither the held-out set nor the screen's data, which only a
/// round with something left to explain needs.
#[test]
fn a_round_at_the_floor_replays_neither_the_heldout_set_nor_the_screens_data() {
    let (robot, recs) = pendulum_at_ticks(0.0);
    let opts = FitOptions { estimate_start: false, ..FitOptions::default() };
    let out = crate::fit::select::fit(&robot, &recs, &opts);
    assert!(out.stopped_at_floor && out.applied.is_empty(), "{:?}", out.warnings);
    let secs = |r: &[Recording]| r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>();
    let (train, heldout) = (secs(&out.train), secs(&out.heldout));
    assert!(train > 0.0 && heldout > 0.0);
    let round0 = &out.cost.simulated_s_by_round_phase["0"];
    assert_eq!(round0.keys().copied().collect::<Vec<_>>(), ["diagnose"]);
    let diagnose = round0["diagnose"];
    assert!((diagnose - 3.0 * train).abs() <= 0.1, "{diagnose} s for {train} s of training");
}
