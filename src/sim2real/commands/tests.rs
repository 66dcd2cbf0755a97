use super::*;

fn ticks(s: &Schedule) -> (i64, Vec<Vec<f64>>) {
    match s {
        Schedule::Ticks { k0, cmd, .. } => (*k0, cmd.clone()),
        _ => panic!("expected ticks"),
    }
}

#[test]
fn rows_map_to_the_tick_they_fall_in_and_exact_stamps_to_their_own_tick() {
    // 100 Hz ticks; rows at 0.000 (exactly tick 0), 0.013 (tick 1), 0.030 (exactly tick 3,
    // printed value not exactly representable), 0.0299 (tick 2).
    assert_eq!(tick_of(0.0, 0.0, 100.0, CommandTiming::InForce), 0);
    assert_eq!(tick_of(0.013, 0.0, 100.0, CommandTiming::InForce), 1);
    assert_eq!(tick_of(0.03, 0.0, 100.0, CommandTiming::InForce), 3);
    assert_eq!(tick_of(0.07, 0.0, 100.0, CommandTiming::InForce), 7);
    assert_eq!(tick_of(0.0299, 0.0, 100.0, CommandTiming::InForce), 2);
    assert_eq!(tick_of(0.013, 0.0, 100.0, CommandTiming::SentAfter), 2);
    assert_eq!(tick_of(0.03, 0.0, 100.0, CommandTiming::SentAfter), 3);
    // Phase: ticks at 0.004 + k/100.
    assert_eq!(tick_of(0.013, 0.004, 100.0, CommandTiming::InForce), 0);
    assert_eq!(tick_of(0.014, 0.004, 100.0, CommandTiming::InForce), 1);
}

#[test]
fn exact_tick_sequence_from_an_asynchronous_log() {
    // Controller: tick k sends c_k = k·0.1 for k = 0..=9 except a step at tick 5 → 2.0.
    let truth = [0.0, 0.1, 0.2, 0.3, 0.4, 2.0, 2.0, 2.0, 2.0, 2.0];
    // Recorder rows (in force): no row in ticks 2 (ramp) and 5 (step).
    let t = [0.001, 0.0125, 0.031, 0.045, 0.067, 0.078, 0.081, 0.095];
    let c: Vec<f64> = t.iter().map(|&x: &f64| truth[(x * 100.0).floor() as usize]).collect();
    let s = reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
    let (k0, cmd) = ticks(&s);
    assert_eq!(k0, 0);
    // Tick 2 interpolated on the ramp (0.2); tick 5 held from tick 4 across the step (0.4).
    let want = [0.0, 0.1, 0.2, 0.3, 0.4, 0.4, 2.0, 2.0, 2.0, 2.0];
    for (k, w) in want.iter().enumerate() {
        assert!((cmd[0][k] - w).abs() < 1e-12, "tick {k}: {} vs {w}", cmd[0][k]);
    }
    let st = s.stats().unwrap();
    assert_eq!((st.ticks, st.empty, st.interpolated, st.conflicting), (10, 2, 1, 0));
    // Lookups: in force over [t_k, t_{k+1}).
    assert_eq!(s.at(0, 0.0199), 0.1);
    assert_eq!(s.at(0, 0.02), 0.2);
    assert_eq!(s.at(0, 0.0645), 2.0);
    assert_eq!(s.at(0, -1.0), 0.0);
    assert_eq!(s.at(0, 5.0), 2.0);
}

#[test]
fn rows_logged_at_the_ticks_keep_their_own_tick() {
    // A logger that reads state then sends: rows exactly at t_k carry c_k.
    let t: Vec<f64> = (0..6).map(|k| k as f64 * 0.01).collect();
    let c = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
    let s = reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
    for (k, &ck) in c.iter().enumerate() {
        assert_eq!(s.at(0, k as f64 * 0.01 + 0.005), ck);
        assert_eq!(s.at(0, k as f64 * 0.01), ck);
    }
}

#[test]
fn sent_after_shifts_each_row_to_the_next_tick() {
    // Rows sampled mid-tick log the command sent at the next tick.
    let t = [0.005, 0.015, 0.025];
    let c = [1.0, 2.0, 3.0];
    let s =
        reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::SentAfter, Fill::Ramps).unwrap();
    assert_eq!(s.at(0, 0.012), 1.0);
    assert_eq!(s.at(0, 0.022), 2.0);
    assert_eq!(s.at(0, 0.031), 3.0);
    // Before the first tick a row shows: the tick no row logs, along the ramp (1, 2, 3).
    assert_eq!(s.at(0, 0.005), 0.0);
    let f = reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
    assert_eq!(f.at(0, 0.012), 2.0);
}

/// A `sent_after` log that starts mid-tick: the tick in force at its first row is
/// extrapolated along a ramp or a smooth curve, held before a step or a hold, and not
/// added when the first row sits exactly on its tick.
#[test]
fn sent_after_fills_the_tick_before_the_first_row() {
    let t = [0.013, 0.023, 0.033, 0.043];
    let at_start = |c: &[f64]| {
        let s =
            reconstruct(&t, &[c], Some(100.0), 0.0, CommandTiming::SentAfter, Fill::Ramps).unwrap();
        assert_eq!(s.at(0, 0.02), c[0]);
        s.at(0, 0.013)
    };
    // Ramp: rows log ticks 2..5 (0.02 … 0.05); tick 1 (0.01–0.02) is one slope back.
    assert!((at_start(&[0.2, 0.3, 0.4, 0.5]) - 0.1).abs() < 1e-12);
    // Smooth: slopes 0.10 then 0.08, the first slope back.
    assert!((at_start(&[1.0, 1.1, 1.18, 1.24]) - 0.9).abs() < 1e-12);
    // A step right after the first logged tick, and a hold: the first command held.
    assert_eq!(at_start(&[0.0, 0.5, 0.5, 0.5]), 0.0);
    assert_eq!(at_start(&[0.7, 0.7, 0.7, 0.7]), 0.7);
    // First row exactly on its tick: it logs the command sent there; nothing before it.
    let on = [0.02, 0.03, 0.04];
    let s = reconstruct(
        &on,
        &[&[0.2, 0.3, 0.4]],
        Some(100.0),
        0.0,
        CommandTiming::SentAfter,
        Fill::Ramps,
    )
    .unwrap();
    assert_eq!(s.stats().unwrap().ticks, 3);
    assert_eq!(s.at(0, 0.02), 0.2);
}

#[test]
fn conflicting_rows_in_one_tick_are_counted() {
    let t = [0.001, 0.004, 0.011, 0.015];
    let c = [1.0, 1.5, 2.0, 2.0];
    let s = reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
    assert_eq!(s.stats().unwrap().conflicting, 1);
    // The tick's command is that of its row nearest the tick's middle (0.005): 0.004's.
    assert_eq!(s.at(0, 0.005), 1.5);
    // A row stamped at the tick that still logs the previous command (sampled just before
    // it) does not make the tick stale: ticks [0.01, 0.02) and [0.02, 0.03).
    let t = [0.006, 0.010, 0.013, 0.016, 0.020, 0.024, 0.027];
    let c = [1.0, 1.0, 2.0, 2.0, 2.0, 3.0, 3.0];
    let s = reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
    assert_eq!(s.stats().unwrap().conflicting, 2);
    assert_eq!((s.at(0, 0.011), s.at(0, 0.021)), (2.0, 3.0));
    // Rows that agree keep the first row's command (nothing to decide).
    assert_eq!(s.at(0, 0.001), 1.0);
}

#[test]
fn without_a_rate_each_goal_holds_from_its_timestamp() {
    let t = [0.0, 0.0037, 0.0091];
    let c = [1.0, 2.0, 3.0];
    let s = reconstruct(&t, &[&c], None, 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
    assert_eq!(s.at(0, 0.0036), 1.0);
    assert_eq!(s.at(0, 0.0037), 2.0);
    assert_eq!(s.at(0, 0.05), 3.0);
}

/// A 200 Hz log of a 50 Hz controller with its times in milliseconds (250 ticks per row)
/// or nanoseconds (2.5 × 10⁸: before this check, a 4.8 TB tick table and an abort) is an
/// error; the same log in seconds, and a 1 kHz controller logged at 25 Hz (40), are not.
#[test]
fn the_tick_phase_is_where_every_command_change_allows_an_edge() {
    // 10 Hz ticks at 0.05 + k/10; rows every 30 ms, each logging the command in force (a
    // row exactly at a tick carries that tick's command). Changes: 0.03 → 0.06 (edge 0.05),
    // 0.12 → 0.15 (edge 0.15, on the row), 0.24 → 0.27 (edge 0.25). Phases (mod 0.1) allowed:
    // [0.03, 0.06] ∩ [0.02, 0.05] ∩ [0.04, 0.07] = [0.04, 0.05], each end 0.5 ms wider (the
    // times are multiples of 1 ms: a row's true time is within 0.5 ms of its stamp).
    let t: Vec<f64> = (0..10).map(|i| 0.03 * i as f64).collect();
    let c: Vec<f64> = t.iter().map(|&x| ((x - 0.05) * 10.0 + 1e-9).floor()).collect();
    let p = tick_phase(&t, &[&c], 10.0, t[0]).expect("changes");
    assert_eq!((p.changes, p.agree, p.optima), (3, 3, 1));
    assert!((p.start.rem_euclid(0.1) - 0.0395).abs() < 2e-6, "{p:?}");
    assert!((p.width - 0.011).abs() < 3e-6, "{p:?}");
    // The first row (phase 0) is outside: it agrees with the changes around 0.05 and 0.15?
    // No: [0.03, 0.06] and [0.02, 0.05] do not hold 0 (mod 0.1); [0.04, 0.07] neither.
    assert_eq!(p.agree_candidate, 0);
    // The estimate: the first row's phase (0 ≡ 0.1) is not allowed, so the end of the
    // allowed phases before it (the tick precedes the rows showing a new command), kept one
    // timestamp quantum inside (times in multiples of 1 ms; each change's interval was
    // widened by half of it at each end: [0.0395, 0.0505]): 0.0495, the truth 0.05.
    assert!((p.origin_at_or_before(0.0, 10.0) - (0.0495 - 0.1)).abs() < 2e-6, "{p:?}");
    // Scored at the true origin: all three.
    assert_eq!(tick_phase(&t, &[&c], 10.0, 0.05).expect("changes").agree_candidate, 3);
    // Rows a whole tick apart say nothing.
    let t2: Vec<f64> = (0..5).map(|i| 0.1 * i as f64 + 0.01).collect();
    assert_eq!(tick_phase(&t2, &[&t2], 10.0, 0.0), None);
}

#[test]
fn rows_too_many_ticks_apart_are_an_error_not_an_allocation() {
    let secs: Vec<f64> = (0..50).map(|i| i as f64 * 0.005).collect();
    let c = [0.0; 50];
    let run = |t: &[f64], rate: f64| {
        reconstruct(t, &[&c], Some(rate), t[0], CommandTiming::InForce, Fill::Ramps)
    };
    assert!(run(&secs, 50.0).is_ok());
    let ms: Vec<f64> = secs.iter().map(|x| x * 1e3).collect();
    match run(&ms, 50.0) {
        Err(ScheduleError::SparseRows { ticks_per_row, rows: 50 }) => {
            assert!((ticks_per_row - 250.0).abs() < 1e-6, "{ticks_per_row}")
        }
        other => panic!("{other:?}"),
    }
    let ns: Vec<f64> = secs.iter().map(|x| 1.7642e18 + x * 1e9).collect();
    assert!(matches!(run(&ns, 50.0), Err(ScheduleError::SparseRows { .. })));
    let at_25hz: Vec<f64> = (0..50).map(|i| i as f64 * 0.04).collect();
    assert!(run(&at_25hz, 1000.0).is_ok());
    let msg = run(&ms, 50.0).unwrap_err().to_string();
    assert!(msg.contains("seconds") && msg.contains("2.500e2"), "{msg}");
}

#[test]
fn all_rows_in_one_tick_and_bad_rates_are_errors() {
    let t = [0.0, 0.1, 0.2];
    let c = [0.0; 3];
    assert_eq!(
        reconstruct(&t, &[&c], Some(1.0), 0.0, CommandTiming::InForce, Fill::Ramps),
        Err(ScheduleError::OneTick { tick: 0, rows: 3 })
    );
    assert!(matches!(
        reconstruct(&t, &[&c], Some(0.0), 0.0, CommandTiming::InForce, Fill::Ramps),
        Err(ScheduleError::BadRate(_))
    ));
    assert!(matches!(
        reconstruct(&t, &[&c], Some(f64::NAN), 0.0, CommandTiming::InForce, Fill::Ramps),
        Err(ScheduleError::BadRate(_))
    ));
}

#[test]
fn a_step_on_one_joint_and_a_ramp_on_another_in_the_same_gap() {
    let t = [0.001, 0.011, 0.031, 0.041];
    let step = [0.0, 0.0, 1.0, 1.0];
    let ramp = [0.0, 0.1, 0.3, 0.4];
    let s = reconstruct(&t, &[&step, &ramp], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps)
        .unwrap();
    assert_eq!(s.at(0, 0.025), 0.0);
    assert!((s.at(1, 0.025) - 0.2).abs() < 1e-12);
}

#[test]
fn the_alternative_fills_take_each_end_of_the_gap() {
    // Tick 2 has no row; the step from 0 to 1 happened at tick 2 or tick 3.
    let t = [0.001, 0.011, 0.031, 0.041];
    let step = [0.0, 0.0, 1.0, 1.0];
    let at = |fill| {
        reconstruct(&t, &[&step], Some(100.0), 0.0, CommandTiming::InForce, fill)
            .unwrap()
            .at(0, 0.025)
    };
    assert_eq!(at(Fill::Ramps), 0.0);
    assert_eq!(at(Fill::Hold), 0.0);
    assert_eq!(at(Fill::Next), 1.0);
    // Known ticks are the same whatever the fill.
    let s =
        reconstruct(&t, &[&step], Some(100.0), 0.0, CommandTiming::InForce, Fill::Next).unwrap();
    assert_eq!((s.at(0, 0.015), s.at(0, 0.035)), (0.0, 1.0));
}

/// Rows in every tick except `missing`, each logging its tick's command mid-tick.
fn log_without(truth: &[f64], missing: &[usize]) -> Schedule {
    log_without_fill(truth, missing, Fill::Ramps)
}

#[test]
fn a_ramp_that_ends_or_starts_inside_a_gap_keeps_its_corner() {
    // Ramped step at 0.03 rad per tick from 0 to 0.135: ticks 0, .03, .06, .09, .12, .135, …
    let up = [0.0, 0.03, 0.06, 0.09, 0.12, 0.135, 0.135, 0.135, 0.135];
    // Tick 4 missing: the ramp's last full tick (linear interpolation: 0.1125).
    let s = log_without(&up, &[4]);
    assert!((s.at(0, 0.045) - 0.12).abs() < 1e-9, "{}", s.at(0, 0.045));
    // Tick 5 missing: the corner itself (linear: 0.1275).
    let s = log_without(&up, &[5]);
    assert!((s.at(0, 0.055) - 0.135).abs() < 1e-9, "{}", s.at(0, 0.055));
    // A hold, then a ramp of −0.02 per tick starting half-way through tick 3.
    let down = [0.5, 0.5, 0.5, 0.5, 0.49, 0.47, 0.45, 0.43, 0.41, 0.39, 0.37];
    let s = log_without(&down, &[4]);
    assert!((s.at(0, 0.045) - 0.49).abs() < 1e-9, "{}", s.at(0, 0.045));
    // A ramp through the gap stays a ramp; both ends missing ticks on one ramp.
    let s = log_without(&down, &[5, 6]);
    assert!((s.at(0, 0.055) - 0.47).abs() < 1e-9 && (s.at(0, 0.065) - 0.45).abs() < 1e-9);
    assert_eq!(s.stats().unwrap().interpolated, 2);
}

#[test]
fn smooth_motion_is_filled_by_a_cubic_even_at_its_extremum() {
    // 0.2·sin(0.3 k): tick 5 sits by the peak, where the slopes beside the gap have opposite
    // signs (a "factor of 3 of the slope across" test held it: 13 mrad off; linear: 8.9).
    let truth: Vec<f64> = (0..12).map(|k| 0.2 * (0.3 * k as f64).sin()).collect();
    for k in [2, 5, 8] {
        let s = log_without(&truth, &[k]);
        let err = s.at(0, k as f64 * 0.01 + 0.005) - truth[k];
        assert!(err.abs() < 5e-4, "tick {k}: {err}");
    }
}

/// As [`log_without`], with the fill given.
fn log_without_fill(truth: &[f64], missing: &[usize], fill: Fill) -> Schedule {
    let (mut t, mut c) = (Vec::new(), Vec::new());
    for (k, &x) in truth.iter().enumerate() {
        if !missing.contains(&k) {
            t.push(k as f64 * 0.01 + 0.004);
            c.push(x);
        }
    }
    reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, fill).unwrap()
}

#[test]
fn the_alternative_fill_moves_a_smooth_gap_by_the_cubics_own_error_nearby() {
    // Tick-to-tick roughness ±5 mrad (filtered random motion has it): the cubic through
    // k ± 1, k ± 2 misses every known tick by 8/3 × 5 mrad, and so the alternative fill
    // moves the missing tick 10 by √2 × 13.3 mrad (by hand: p(x) = α + βx² through
    // −c, c at |x| = 1, 2 gives p(0) = −5c/3).
    let c = 0.005;
    let rough: Vec<f64> = (0..21).map(|k| if k % 2 == 0 { c } else { -c }).collect();
    let ramps = log_without_fill(&rough, &[10], Fill::Ramps).at(0, 0.105);
    let next = log_without_fill(&rough, &[10], Fill::Next).at(0, 0.105);
    let want = std::f64::consts::SQRT_2 * 8.0 / 3.0 * c;
    assert!(((next - ramps).abs() - want).abs() < 1e-12, "{ramps} {next} {want}");
    // A sine the cubic predicts to 0.3 mrad (its fourth derivative / 6) is moved by √2 ×
    // that, not by its 9 mrad curvature; known ticks are never moved.
    let sine: Vec<f64> = (0..21).map(|k| 0.2 * (0.3 * k as f64).sin()).collect();
    let ramps = log_without_fill(&sine, &[10], Fill::Ramps);
    let next = log_without_fill(&sine, &[10], Fill::Next);
    let d = (next.at(0, 0.105) - ramps.at(0, 0.105)).abs();
    assert!(d > 1e-5 && d < 1e-3, "{d}");
    for k in [0usize, 5, 9, 11, 20] {
        let t = k as f64 * 0.01 + 0.005;
        assert_eq!(next.at(0, t), ramps.at(0, t), "tick {k}");
    }
    // A step is still taken from its other end, unmoved.
    let step: Vec<f64> = (0..12).map(|k| if k >= 5 { 0.3 } else { 0.0 }).collect();
    assert_eq!(log_without_fill(&step, &[5], Fill::Next).at(0, 0.055), 0.3);
}

#[test]
fn a_step_on_top_of_slow_motion_is_still_held() {
    // Slow drift of 1 mrad per tick, a 0.3 rad step at tick 5, no row in tick 5.
    let truth: Vec<f64> =
        (0..10).map(|k| 0.001 * k as f64 + if k >= 5 { 0.3 } else { 0.0 }).collect();
    let s = log_without(&truth, &[5]);
    assert!((s.at(0, 0.055) - truth[4]).abs() < 1e-12);
    assert_eq!(s.stats().unwrap().interpolated, 0);
}
