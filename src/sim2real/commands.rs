//! Command reconstruction: which position command was in force at each moment of a recording.
//!
//! A recording logs, per row, `q_cmd` = the command in force at that row's time (the default
//! [`CommandTiming::InForce`]). With a control rate, the robot's controller sent one command per
//! control tick k at `t_k = control_t0_s + k / rate`, held over `[t_k, t_{k+1})`:
//!
//! ```text
//! controller ticks   t_0        t_1        t_2        t_3        t_4
//!                     |----c0----|----c1----|----c2----|----c3----|
//! recorder rows         r0   r1      r2                    r3 r4
//!                       c0   c0      c1      (no row)      c3 c3
//! reconstructed         c0           c1     c2 = filled    c3
//! ```
//!
//! * The command of tick k comes from the rows inside `[t_k, t_{k+1})`; a row stamped exactly at
//!   `t_k` (a logger that reads the state, then sends the tick's command) belongs to tick k.
//! * A tick with no row is filled from the known ticks around it: linearly interpolated across a
//!   ramp (the slope beside the gap matches the slope across it), held across a step.
//! * [`CommandTiming::SentAfter`]: loggers that record the command *sent after* the sample; the
//!   row's command belongs to the first tick at or after the row (`ceil` instead of `floor`).
//! * Without a control rate, each goal is held from its own timestamp (servos that take each
//!   goal as it arrives); the commands of dropped rows are interpolated
//!   ([`fill_dropped_rows`]).
//!
//! This module is the single place that decides the command timing; the replay only asks
//! [`Schedule::at`].

use crate::sim2real::metrics::{fill_dropped_rows, has_gap};

/// Metadata key / CLI values for [`CommandTiming`].
pub const KEY_COMMAND_TIMING: &str = "command_timing";

/// What a row's `q_cmd` means relative to the control ticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CommandTiming {
    /// The command in force at the row's time (tick `floor((t − t0)·rate)`).
    #[default]
    InForce,
    /// The command sent right after the row was sampled (tick `ceil((t − t0)·rate)`).
    SentAfter,
}

impl CommandTiming {
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim().replace('-', "_").as_str() {
            "in_force" => Some(CommandTiming::InForce),
            "sent_after" => Some(CommandTiming::SentAfter),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            CommandTiming::InForce => "in_force",
            CommandTiming::SentAfter => "sent_after",
        }
    }
}

/// Tolerance, in control ticks, for a timestamp to count as "exactly at" a tick (10 ns at 100 Hz:
/// absorbs the rounding of printed timestamps like 0.03, never a real sampling offset).
const TICK_EPS: f64 = 1e-6;

/// The tick a row at `t` belongs to.
pub fn tick_of(t: f64, t0: f64, rate: f64, timing: CommandTiming) -> i64 {
    let x = (t - t0) * rate;
    match timing {
        CommandTiming::InForce => (x + TICK_EPS).floor() as i64,
        CommandTiming::SentAfter => (x - TICK_EPS).ceil() as i64,
    }
}

/// The reconstructed command of every recorded joint over time.
#[derive(Debug, Clone, PartialEq)]
pub enum Schedule {
    /// One command per control tick: `cmd[j][k − k0]` is joint j's command over
    /// `[t0 + k/rate, t0 + (k+1)/rate)`. Before the first tick the first command holds, after
    /// the last the last.
    Ticks { t0: f64, rate: f64, k0: i64, cmd: Vec<Vec<f64>>, stats: TickStats },
    /// Each goal held from its own timestamp `t[i]` on (before `t[0]`: the first goal).
    Events { t: Vec<f64>, cmd: Vec<Vec<f64>> },
}

/// How the rows covered the control ticks.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TickStats {
    pub ticks: usize,
    /// Ticks with no row (filled).
    pub empty: usize,
    /// Filled ticks interpolated as a ramp (the rest were held).
    pub interpolated: usize,
    /// Ticks whose rows disagree on the command (beyond 1e-9 rad on some joint): a sign that
    /// the command column is not the command in force, or that the control rate is wrong.
    pub conflicting: usize,
    /// Ticks with at least one row.
    pub occupied: usize,
}

impl Schedule {
    /// Joint `j`'s command in force at time `t`.
    pub fn at(&self, j: usize, t: f64) -> f64 {
        match self {
            Schedule::Ticks { t0, rate, k0, cmd, .. } => {
                let c = &cmd[j];
                let k = ((t - t0) * rate + TICK_EPS).floor() as i64 - k0;
                c[k.clamp(0, c.len() as i64 - 1) as usize]
            }
            Schedule::Events { t: te, cmd } => {
                let i = te.partition_point(|&x| x <= t + 1e-12);
                cmd[j][i.saturating_sub(1)]
            }
        }
    }

    pub fn stats(&self) -> Option<TickStats> {
        match self {
            Schedule::Ticks { stats, .. } => Some(*stats),
            Schedule::Events { .. } => None,
        }
    }
}

/// Why a recording's timestamps cannot be mapped onto control ticks.
#[derive(Debug, Clone, PartialEq)]
pub enum ScheduleError {
    /// The rate is not a positive finite number.
    BadRate(f64),
    /// Every row falls into one tick: the rate (or the time unit) is wrong.
    OneTick { tick: i64, rows: usize },
}

impl std::fmt::Display for ScheduleError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ScheduleError::BadRate(r) => {
                write!(f, "control rate must be a positive number of Hz, got {r}")
            }
            ScheduleError::OneTick { tick, rows } => write!(
                f,
                "all {rows} rows fall into control tick {tick}: control_rate_hz is too low for these timestamps \
                 (are the times in seconds?)"
            ),
        }
    }
}

/// How a tick without a row (or a dropped row) is filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Fill {
    /// Interpolated across a ramp, the command before the gap held across a step (the best
    /// guess; without a control rate, dropped rows' commands are interpolated).
    #[default]
    Ramps,
    /// The command before the gap held (the command changed at the first row after it).
    Hold,
    /// As [`Fill::Ramps`], but a step takes the command after the gap (it changed right after
    /// the last row before it): the other end of what the rows allow. The fit replays this
    /// alternative to measure the error command reconstruction alone leaves (its floor).
    /// Without a control rate: as [`Fill::Hold`].
    Next,
}

/// Reconstructs the command schedule of the joints `cmds` (one trace per joint, sampled at `t`,
/// increasing). `rate = None`: [`Schedule::Events`]. `fill` says what an empty tick (or dropped
/// row) gets.
pub fn reconstruct(
    t: &[f64],
    cmds: &[&[f64]],
    rate: Option<f64>,
    t0: f64,
    timing: CommandTiming,
    fill: Fill,
) -> Result<Schedule, ScheduleError> {
    let Some(rate) = rate else {
        if fill == Fill::Ramps && has_gap(t) {
            let mut tt = Vec::new();
            let mut cc = Vec::with_capacity(cmds.len());
            for c in cmds {
                let (tf, xf) = fill_dropped_rows(t, c);
                tt = tf;
                cc.push(xf);
            }
            if cmds.is_empty() {
                tt = t.to_vec();
            }
            return Ok(Schedule::Events { t: tt, cmd: cc });
        }
        return Ok(Schedule::Events {
            t: t.to_vec(),
            cmd: cmds.iter().map(|c| c.to_vec()).collect(),
        });
    };
    if !(rate.is_finite() && rate > 0.0) {
        return Err(ScheduleError::BadRate(rate));
    }
    let n = t.len();
    if n == 0 {
        return Ok(Schedule::Ticks {
            t0,
            rate,
            k0: 0,
            cmd: vec![Vec::new(); cmds.len()],
            stats: TickStats::default(),
        });
    }
    let ticks: Vec<i64> = t.iter().map(|&x| tick_of(x, t0, rate, timing)).collect();
    let (k0, k1) = (ticks[0], ticks[n - 1]);
    if n >= 2 && k0 == k1 {
        return Err(ScheduleError::OneTick { tick: k0, rows: n });
    }
    let len = (k1 - k0 + 1) as usize;
    // Representative row of each tick: the first row of the tick (in force: closest to the
    // tick's start); for SentAfter the last row before the tick (closest to the sending time).
    let mut rep: Vec<Option<usize>> = vec![None; len];
    let mut conflicting = 0usize;
    let mut last_conflict_tick = None;
    for i in 0..n {
        let k = (ticks[i] - k0) as usize;
        match rep[k] {
            None => rep[k] = Some(i),
            Some(r) => {
                if cmds.iter().any(|c| (c[i] - c[r]).abs() > 1e-9) && last_conflict_tick != Some(k)
                {
                    conflicting += 1;
                    last_conflict_tick = Some(k);
                }
                if timing == CommandTiming::SentAfter {
                    rep[k] = Some(i);
                }
            }
        }
    }
    let known: Vec<usize> = (0..len).filter(|&k| rep[k].is_some()).collect();
    let mut stats =
        TickStats { ticks: len, occupied: known.len(), conflicting, ..Default::default() };
    let mut out = Vec::with_capacity(cmds.len());
    for c in cmds {
        let mut v = vec![f64::NAN; len];
        for &k in &known {
            v[k] = c[rep[k].expect("known")];
        }
        out.push(v);
    }
    // Fill the empty ticks between known ones, per gap (the same decision for every joint of a
    // gap would hide a step on one joint behind a ramp on another: decide per joint).
    for w in 0..known.len().saturating_sub(1) {
        let (i, j) = (known[w], known[w + 1]);
        if j - i < 2 {
            continue;
        }
        stats.empty += j - i - 1;
        let mut any_ramp = false;
        for v in out.iter_mut() {
            let (a, b) = (v[i], v[j]);
            let gap_slope = (b - a) / (j - i) as f64;
            let before = (w > 0).then(|| {
                let p = known[w - 1];
                (a - v[p]) / (i - p) as f64
            });
            let after = known.get(w + 2).map(|&q| (v[q] - b) / (q - j) as f64);
            if fill != Fill::Hold && is_ramp(gap_slope, before, after) {
                any_ramp = true;
                for (k, x) in v.iter_mut().enumerate().take(j).skip(i + 1) {
                    *x = a + gap_slope * (k - i) as f64;
                }
            } else if fill == Fill::Next {
                for x in v.iter_mut().take(j).skip(i + 1) {
                    *x = b;
                }
            } else {
                for x in v.iter_mut().take(j).skip(i + 1) {
                    *x = a;
                }
            }
        }
        if any_ramp {
            stats.interpolated += j - i - 1;
        }
    }
    Ok(Schedule::Ticks { t0, rate, k0, cmd: out, stats })
}

/// A gap is part of a ramp when the command changes across it and a known slope beside it has
/// the same sign and is within a factor of 3 of the slope across it; a step (flat on both sides,
/// jump across the gap) is held.
fn is_ramp(gap: f64, before: Option<f64>, after: Option<f64>) -> bool {
    if gap.abs() < 1e-12 {
        return false;
    }
    [before, after].into_iter().flatten().any(|s| {
        let r = s / gap;
        (1.0 / 3.0..=3.0).contains(&r)
    })
}

#[cfg(test)]
mod tests {
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
        let s =
            reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
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
        let s =
            reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
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
        let s = reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::SentAfter, Fill::Ramps)
            .unwrap();
        assert_eq!(s.at(0, 0.012), 1.0);
        assert_eq!(s.at(0, 0.022), 2.0);
        assert_eq!(s.at(0, 0.031), 3.0);
        let f =
            reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
        assert_eq!(f.at(0, 0.012), 2.0);
    }

    #[test]
    fn conflicting_rows_in_one_tick_are_counted() {
        let t = [0.001, 0.004, 0.011, 0.015];
        let c = [1.0, 1.5, 2.0, 2.0];
        let s =
            reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
        assert_eq!(s.stats().unwrap().conflicting, 1);
        assert_eq!(s.at(0, 0.005), 1.0);
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
        let s =
            reconstruct(&t, &[&step, &ramp], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps)
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
        let s = reconstruct(&t, &[&step], Some(100.0), 0.0, CommandTiming::InForce, Fill::Next)
            .unwrap();
        assert_eq!((s.at(0, 0.015), s.at(0, 0.035)), (0.0, 1.0));
    }
}
