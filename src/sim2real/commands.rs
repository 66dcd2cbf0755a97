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
//! * A tick with no row is filled from the known ticks around it, by the command's shape there
//!   (`fill_gap`): a ramp that starts or ends inside the gap is continued to its corner, a ramp
//!   through it interpolated linearly, smooth motion by the cubic through two known ticks on
//!   each side; across a step the command before the gap is held.
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
    /// The rows are, at the median, more than [`MAX_TICKS_PER_ROW`] control ticks apart: the
    /// time unit is not seconds (milli-, micro-, nanoseconds) or the rate is far too high —
    /// and the commands of the ticks between rows are unknown either way.
    SparseRows { ticks_per_row: f64, rows: usize },
    /// The rows span more than [`MAX_SCHEDULE_TICKS`] control ticks (a time far from the
    /// others): one command per tick would not fit in memory.
    Span { ticks: f64 },
}

/// The most control ticks a schedule holds (10⁸: 28 h at 1 kHz). The recording's own check
/// ([`crate::sim2real::recording::MAX_SPAN_INTERVALS`]) rejects far shorter spans of a log's
/// rows first, at the line; this bound keeps a recording built in code from allocating past it.
pub const MAX_SCHEDULE_TICKS: f64 = 1e8;

/// The most control ticks a median row interval may span (a 1 kHz controller logged at
/// 25 Hz). Millisecond timestamps of a 200 Hz log at a 50 Hz rate give 250; nanoseconds, 10⁸.
pub const MAX_TICKS_PER_ROW: f64 = 40.0;

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
            ScheduleError::SparseRows { ticks_per_row, rows } => write!(
                f,
                "the {rows} rows are a median {ticks_per_row:.3e} control ticks apart (at most \
                 {MAX_TICKS_PER_ROW} make sense): are the times in seconds? (milliseconds: divide \
                 by 1000, nanoseconds by 1e9) — or is control_rate_hz far too high?"
            ),
            ScheduleError::Span { ticks } => write!(
                f,
                "the rows span {ticks:.3e} control ticks (at most {MAX_SCHEDULE_TICKS:.0e}): a \
                 time far from the others?"
            ),
        }
    }
}

/// How a tick without a row (or a dropped row) is filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Fill {
    /// Filled along the command's shape (a ramp's corner, a ramp, smooth motion: `fill_gap`),
    /// the command before the gap held across a step (the best guess; without a control rate,
    /// dropped rows' commands are interpolated).
    #[default]
    Ramps,
    /// The command before the gap held (the command changed at the first row after it).
    Hold,
    /// As [`Fill::Ramps`], but a step takes the command after the gap (it changed right after
    /// the last row before it): the other end of what the rows allow; and a gap filled as smooth
    /// motion is moved by √2 × how far the same cubic misses the known ticks nearby (a
    /// command's tick-to-tick roughness no row shows). The fit replays this alternative to
    /// measure the error command reconstruction alone leaves (its floor).
    /// Without a control rate: as [`Fill::Hold`].
    Next,
}

/// [`ScheduleError::SparseRows`] when the median interval of the increasing times `t` spans
/// more than [`MAX_TICKS_PER_ROW`] ticks of `rate`.
pub fn check_row_spacing(t: &[f64], rate: f64) -> Result<(), ScheduleError> {
    if t.len() < 2 {
        return Ok(());
    }
    let mut dts: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    dts.sort_by(f64::total_cmp);
    let ticks_per_row = dts[dts.len() / 2] * rate;
    if ticks_per_row <= MAX_TICKS_PER_ROW * (1.0 + 1e-9) {
        Ok(())
    } else {
        Err(ScheduleError::SparseRows { ticks_per_row, rows: t.len() })
    }
}

/// Where the recorded command changes put the control ticks' edges.
///
/// A row logs the command in force at its time, so when two rows less than one tick apart
/// carry different commands, a tick edge lies between them (for [`CommandTiming::SentAfter`] as
/// well: the two rows' commands belong to different ticks). Every such change is an interval
/// the tick grid must hit; the phases (time within a tick period) that hit the most of them
/// are where the ticks can be. A recorder faster than the controller puts rows at every phase,
/// so a few hundred changes pin the phase to tens of microseconds. A slower one (88 Hz beside
/// 100 Hz ticks) leaves rows less than a tick apart rarely, and several disjoint phase intervals
/// then agree with every change; among them the rows decide by the command's own shape
/// ([`roughness`]): a controller's command sampled on its true ticks is a smooth staircase, on a
/// wrong grid some rows land a tick early or late and the command jumps back and forth. A
/// recorder locked to the ticks leaves the whole span between two of its rows open (the first
/// row's time is then as good as any).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TickPhase {
    /// Command changes between rows less than one tick apart.
    pub changes: usize,
    /// How many of them the best phases agree with.
    pub agree: usize,
    /// The chosen phases: the grid `start + k / rate` for `start` in `[start, start + width]`.
    /// They agree with `agree` changes; among several such intervals, the one (or the part of
    /// one, between the phases of two rows) that leaves the command smoothest; on a tie the
    /// candidate's, else the widest.
    pub start: f64,
    pub width: f64,
    /// The estimate (one grid point): the candidate's phase when it is among the chosen ones,
    /// else their end before it; kept a timestamp quantum (at least 2 µs) inside the ends when
    /// they are that wide, so that no row stamped at an end is put into the wrong tick. Not the
    /// middle: a logger locked to the controller that stamps its rows just after each tick
    /// leaves nearly the whole period open, and its middle is half a tick from the truth.
    pub best: f64,
    /// How many changes the candidate origin agrees with.
    pub agree_candidate: usize,
    /// Disjoint phase intervals that tie for the most agreements (1: the changes alone decide).
    pub optima: usize,
    /// With several optima: the roughness of the smoothest other interval over the chosen
    /// one's (≥ 1; near 1: the command's shape does not tell them apart either).
    pub margin: Option<f64>,
    /// The candidate lies in the chosen phases.
    pub candidate_chosen: bool,
    /// The candidate lies in the interval of best agreement that holds the chosen phases (it may
    /// map a row or two near a tick edge to the other tick than the chosen phases do).
    pub candidate_in_run: bool,
}

impl TickPhase {
    /// The estimate, as the grid point at or before `t`.
    pub fn origin_at_or_before(&self, t: f64, rate: f64) -> f64 {
        t - (t - self.best).rem_euclid(1.0 / rate)
    }
    /// The estimate, as the grid point nearest `t`.
    pub fn origin_nearest(&self, t: f64, rate: f64) -> f64 {
        let p = 1.0 / rate;
        self.best + ((t - self.best) / p).round() * p
    }
}

/// The resolution of printed timestamps: the coarsest of 1 ms, 100 µs, 10 µs that every time is
/// a multiple of (within float printing error), else 1 µs.
pub fn time_quantum(t: &[f64]) -> f64 {
    for q in [1e-3, 1e-4, 1e-5] {
        if t.len() >= 4 && t.iter().all(|&x| ((x / q) - (x / q).round()).abs() < 1e-3) {
            return q;
        }
    }
    1e-6
}

/// Budget of (phase part × row) roughness evaluations per recording (~0.1 s).
const MAX_ROUGHNESS_WORK: usize = 20_000_000;

/// Finds the tick phase the rows' command changes agree with ([`TickPhase`]); `candidate` is the
/// origin the caller would use otherwise (a declared `control_t0_s`, or the first row's time),
/// scored alongside. `None` without any change between rows closer than a tick.
pub fn tick_phase(t: &[f64], cmds: &[&[f64]], rate: f64, candidate: f64) -> Option<TickPhase> {
    tick_phase_q(t, cmds, rate, candidate, time_quantum(t))
}

/// [`tick_phase`] for timestamps of resolution `quantum` (known from before a rescale that
/// left them off any decimal grid).
pub fn tick_phase_q(
    t: &[f64],
    cmds: &[&[f64]],
    rate: f64,
    candidate: f64,
    quantum: f64,
) -> Option<TickPhase> {
    if !(rate.is_finite() && rate > 0.0) || t.len() < 2 {
        return None;
    }
    let p = 1.0 / rate;
    let eps = change_eps_q(quantum, p);
    let origin = t[0];
    let phase = |x: f64| (x - origin).rem_euclid(p);
    let spans = change_spans(t, cmds, p, eps);
    if spans.is_empty() {
        return None;
    }
    let covers = |x: f64| spans.iter().filter(|&&(s, l)| (x - s).rem_euclid(p) <= l).count();
    let (best, runs) = best_runs(&spans, p);
    let cand = phase(candidate);
    let holds = |r: &(f64, f64)| (cand - r.0).rem_euclid(p) <= r.1 - r.0;
    let widest = |rs: &[(f64, f64)]| {
        rs.iter().copied().max_by(|a, b| (a.1 - a.0).total_cmp(&(b.1 - b.0))).unwrap_or((0.0, 0.0))
    };
    let mut pick = runs.iter().find(|r| holds(r)).copied().unwrap_or_else(|| widest(&runs));
    let mut pick_run = pick;
    let mut margin = None;
    if runs.len() > 1 {
        // Each interval maps the rows to ticks one way between the phases of two rows: score
        // every such part (within a budget of part × row evaluations) by the roughness it
        // leaves, take the smoothest, and compare it with the best of the other intervals.
        // Past the budget: each interval at its middle, and of those only the widest ones
        // (and the candidate's) the budget allows.
        let budget = (MAX_ROUGHNESS_WORK / t.len().max(1)).max(2);
        let mut parts: Vec<(usize, f64, f64)> = Vec::new();
        if runs.len() <= budget {
            let mut phases: Vec<f64> = t.iter().map(|&x| phase(x)).collect();
            phases.sort_by(f64::total_cmp);
            phases.dedup_by(|a, b| (*a - *b).abs() <= 1e-12);
            for (ri, &(a, b)) in runs.iter().enumerate() {
                let mut edges = vec![a];
                // Row phases inside (a, b), also one period back (a run may start below 0).
                let from = phases.partition_point(|&x| x <= a.max(0.0));
                edges.extend(phases[from..].iter().copied().take_while(|&x| x < b));
                if a < 0.0 {
                    let from = phases.partition_point(|&x| x - p <= a);
                    edges.extend(
                        phases[from..].iter().map(|&x| x - p).take_while(|&x| x < b.min(0.0)),
                    );
                }
                edges.sort_by(f64::total_cmp);
                edges.push(b);
                parts.extend(edges.windows(2).map(|w| (ri, w[0], w[1])));
            }
        }
        if parts.len() > budget || parts.is_empty() {
            let mut idx: Vec<usize> = (0..runs.len()).collect();
            idx.sort_by(|&x, &y| (runs[y].1 - runs[y].0).total_cmp(&(runs[x].1 - runs[x].0)));
            let own = (0..runs.len()).find(|&i| holds(&runs[i]));
            idx.truncate(budget - 1);
            if let Some(o) = own.filter(|o| !idx.contains(o)) {
                idx.push(o);
            }
            parts = idx.into_iter().map(|ri| (ri, runs[ri].0, runs[ri].1)).collect();
        }
        let costs: Vec<f64> = parts
            .iter()
            .map(|&(_, a, b)| roughness(t, cmds, rate, origin + 0.5 * (a + b)))
            .collect();
        let c0 = costs.iter().copied().fold(f64::INFINITY, f64::min);
        let tie: Vec<usize> = (0..parts.len()).filter(|&i| costs[i] <= c0).collect();
        let span = |i: usize| (parts[i].1, parts[i].2);
        let first = tie.iter().copied().find(|&i| holds(&span(i))).unwrap_or_else(|| {
            tie.iter()
                .copied()
                .max_by(|&x, &y| (span(x).1 - span(x).0).total_cmp(&(span(y).1 - span(y).0)))
                .unwrap_or(0)
        });
        let run = parts[first].0;
        // Neighbouring parts of the same interval that tie are one interval.
        let (mut lo, mut hi) = span(first);
        for &i in &tie {
            if parts[i].0 == run && (parts[i].1 - hi).abs() <= 1e-12 {
                hi = parts[i].2;
            }
        }
        for &i in tie.iter().rev() {
            if parts[i].0 == run && (parts[i].2 - lo).abs() <= 1e-12 {
                lo = parts[i].1;
            }
        }
        pick = (lo, hi);
        pick_run = runs[run];
        let others = (0..parts.len())
            .filter(|&i| parts[i].0 != run)
            .map(|i| costs[i])
            .fold(f64::INFINITY, f64::min);
        margin = Some(if c0 > 0.0 {
            others / c0
        } else if others > 0.0 {
            f64::INFINITY
        } else {
            1.0
        });
    }
    let (lo, hi) = pick;
    let m = (0.5 * (hi - lo)).min(2.0 * eps);
    // The candidate's offset after the interval's start; outside, the end before it: a row
    // logs the command in force, so the tick comes before the rows that show a new command
    // (rows locked just after the ticks leave the whole period but their own phases open, and
    // the end after them would put every command most of a tick early).
    let (w, c) = (hi - lo, (cand - lo).rem_euclid(p));
    let offset = if c <= w { c.clamp(m, w - m) } else { w - m };
    let chosen = lo + offset;
    Some(TickPhase {
        changes: spans.len(),
        agree: best as usize,
        start: origin + pick.0,
        width: pick.1 - pick.0,
        best: origin + chosen,
        agree_candidate: covers(cand),
        optima: runs.len(),
        margin,
        candidate_chosen: holds(&pick),
        candidate_in_run: holds(&pick_run),
    })
}

/// A row's true sampling time is within half the timestamps' resolution of its stamp (1 µs at
/// least): each change's interval is widened by that much at both ends.
fn change_eps(t: &[f64], p: f64) -> f64 {
    change_eps_q(time_quantum(t), p)
}

/// [`change_eps`] for timestamps of resolution `quantum`.
fn change_eps_q(quantum: f64, p: f64) -> f64 {
    1e-6_f64.max(TICK_EPS * p).max(0.5 * quantum)
}

/// (start phase after `t[0]`, length) of every command change between rows less than one
/// period `p` apart: each holds a tick edge.
fn change_spans(t: &[f64], cmds: &[&[f64]], p: f64, eps: f64) -> Vec<(f64, f64)> {
    let mut spans: Vec<(f64, f64)> = Vec::new();
    for i in 0..t.len().saturating_sub(1) {
        let len = t[i + 1] - t[i] + 2.0 * eps;
        if !(len < p) {
            continue;
        }
        if cmds.iter().any(|c| (c[i + 1] - c[i]).abs() > 1e-9) {
            spans.push(((t[i] - t[0] - eps).rem_euclid(p), len));
        }
    }
    spans
}

/// How many of the command changes the best phase of a `rate` grid agrees with, of how many.
pub fn grid_agreement(t: &[f64], cmds: &[&[f64]], rate: f64) -> (usize, usize) {
    let (agree, changes, _) = grid_agreement_width(t, cmds, rate, time_quantum(t));
    (agree, changes)
}

/// [`grid_agreement`] and the width [s] of the widest phase interval that agrees with that many,
/// for timestamps of resolution `quantum`.
fn grid_agreement_width(
    t: &[f64],
    cmds: &[&[f64]],
    rate: f64,
    quantum: f64,
) -> (usize, usize, f64) {
    if !(rate.is_finite() && rate > 0.0) || t.len() < 2 {
        return (0, 0, 0.0);
    }
    let p = 1.0 / rate;
    let spans = change_spans(t, cmds, p, change_eps_q(quantum, p));
    if spans.is_empty() {
        return (0, 0, 0.0);
    }
    let (best, runs) = best_runs(&spans, p);
    let width = runs.iter().map(|r| r.1 - r.0).fold(0.0, f64::max);
    (best as usize, spans.len(), width)
}

/// How many of the command changes the `rate` grid through `origin` agrees with.
pub fn agreement_at(t: &[f64], cmds: &[&[f64]], rate: f64, origin: f64) -> usize {
    if !(rate.is_finite() && rate > 0.0) || t.len() < 2 {
        return 0;
    }
    let p = 1.0 / rate;
    let x = (origin - t[0]).rem_euclid(p);
    change_spans(t, cmds, p, change_eps(t, p))
        .iter()
        .filter(|&&(s, l)| (x - s).rem_euclid(p) <= l)
        .count()
}

/// A control rate near `rate` that the command changes fit: [`fit_rate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateFit {
    /// The middle of the rates that agree with the most changes.
    pub rate: f64,
    /// Half the span of those rates.
    pub half_width: f64,
    pub agree: usize,
    pub changes: usize,
}

/// Most rates [`fit_rate`] tries.
const MAX_RATE_STEPS: usize = 4001;

/// The control rate within `rate` × (1 ± `rel`) whose best tick phase agrees with the most
/// command changes (a controller that runs slightly off its nominal rate, or a logger's clock
/// that drifts against the controller's: at 100 ppm the grid slides a tenth of a 50 Hz tick
/// over 20 s, and rows near the edges land in the wrong tick). Steps small enough that the
/// grid moves at most 1/50 tick over the log between two rates. Among the best rates (the run
/// of them nearest `rate`), the one that leaves the widest phase interval open: off the true
/// rate the changes' intervals slide against each other and their common part shrinks.
/// `None` without changes.
pub fn fit_rate(t: &[f64], cmds: &[&[f64]], rate: f64, rel: f64) -> Option<RateFit> {
    let (&first, &last) = (t.first()?, t.last()?);
    let span = last - first;
    if !(rate.is_finite() && rate > 0.0 && span > 0.0) {
        return None;
    }
    let step = (0.02 / (span * rate)).max(2.0 * rel / (MAX_RATE_STEPS - 1) as f64);
    let n = (rel / step).floor() as i64;
    let quantum = time_quantum(t);
    let mut scored: Vec<(f64, usize, usize, f64)> = Vec::with_capacity(2 * n as usize + 1);
    for i in -n..=n {
        let r = rate * (1.0 + i as f64 * step);
        let (agree, changes, width) = grid_agreement_width(t, cmds, r, quantum);
        scored.push((r, agree, changes, width));
    }
    let share = |x: &(f64, usize, usize, f64)| if x.2 == 0 { 0.0 } else { x.1 as f64 / x.2 as f64 };
    let best = scored.iter().map(share).fold(0.0, f64::max);
    if best <= 0.0 {
        return None;
    }
    // The run of best rates nearest the nominal one.
    let is_best = |x: &(f64, usize, usize, f64)| share(x) >= best - 1e-12;
    let centre = n as usize;
    let nearest =
        (0..scored.len()).filter(|&i| is_best(&scored[i])).min_by_key(|&i| i.abs_diff(centre))?;
    let (mut lo, mut hi) = (nearest, nearest);
    while lo > 0 && is_best(&scored[lo - 1]) {
        lo -= 1;
    }
    while hi + 1 < scored.len() && is_best(&scored[hi + 1]) {
        hi += 1;
    }
    // The widest open phase within the run (the middle of a tie).
    let wmax = scored[lo..=hi].iter().map(|x| x.3).fold(0.0, f64::max);
    let top: Vec<usize> = (lo..=hi).filter(|&i| scored[i].3 >= wmax - 1e-12).collect();
    let pick = scored[top[top.len() / 2]];
    Some(RateFit {
        rate: pick.0,
        half_width: 0.5 * (scored[hi].0 - scored[lo].0) + 0.5 * step * rate,
        agree: pick.1,
        changes: pick.2,
    })
}

/// The phase intervals in `[0, p)` (the first may start below 0 when it wraps) that lie in the
/// most of the closed circular intervals `spans` (start phase, length), and that count.
fn best_runs(spans: &[(f64, f64)], p: f64) -> (i64, Vec<(f64, f64)>) {
    // Sweep the period: +1 where an interval starts, −1 where it ends (starts first on ties,
    // the intervals are closed); the count at phase 0 is the number of wrapping intervals.
    let mut ev: Vec<(f64, i32)> = Vec::with_capacity(2 * spans.len());
    let mut count: i64 = 0;
    for &(s, l) in spans {
        let e = s + l;
        ev.push((s, 1));
        if e >= p {
            count += 1;
            ev.push((e - p, -1));
        } else {
            ev.push((e, -1));
        }
    }
    ev.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
    // Segments [from, to) of constant count around the period.
    let mut segs: Vec<(f64, f64, i64)> = Vec::new();
    let mut at = 0.0;
    for &(x, d) in &ev {
        if x > at {
            segs.push((at, x, count));
            at = x;
        }
        count += d as i64;
    }
    segs.push((at, p, count));
    let best = segs.iter().map(|s| s.2).max().unwrap_or(0);
    // Merge the best segments into intervals (also across the period's end).
    let mut runs: Vec<(f64, f64)> = Vec::new();
    for &(a, b, c) in &segs {
        if c != best {
            continue;
        }
        match runs.last_mut() {
            Some(r) if (r.1 - a).abs() <= 1e-15 => r.1 = b,
            _ => runs.push((a, b)),
        }
    }
    if runs.len() > 1 {
        let (f, l) = (runs[0], runs[runs.len() - 1]);
        if f.0 <= 1e-15 && (l.1 - p).abs() <= 1e-15 {
            runs.pop();
            runs[0] = (l.0 - p, f.1);
        }
    }
    (best, runs)
}

/// How far the rows' commands, mapped onto the tick grid `t0 + k / rate` (the first row of each
/// tick), are from a smooth staircase: the sum over rows and joints, where the command moves
/// through a tick (strictly monotone across its neighbours), of how far the tick's command
/// misses the cubic through the two ticks with rows on either side, in units of the
/// joint's median command change between such ticks and capped at [`ROUGH_CAP`] (a step costs
/// about the same on any grid; a smooth command sampled on the wrong grid costs where a row
/// landed a tick off).
fn roughness(t: &[f64], cmds: &[&[f64]], rate: f64, t0: f64) -> f64 {
    let mut ks: Vec<f64> = Vec::new();
    let mut rows: Vec<usize> = Vec::new();
    for (i, &x) in t.iter().enumerate() {
        let k = tick_of(x, t0, rate, CommandTiming::InForce);
        if ks.last() != Some(&(k as f64)) {
            ks.push(k as f64);
            rows.push(i);
        }
    }
    let n = rows.len();
    if n < 5 {
        return 0.0;
    }
    let mut total = 0.0;
    for c in cmds {
        let v: Vec<f64> = rows.iter().map(|&i| c[i]).collect();
        let mut d: Vec<f64> =
            v.windows(2).map(|w| (w[1] - w[0]).abs()).filter(|&x| x > 1e-9).collect();
        if d.is_empty() {
            continue;
        }
        d.sort_by(f64::total_cmp);
        let scale = d[d.len() / 2];
        for m in 2..n - 2 {
            // Only where the command moves through the tick (steps and holds look alike on
            // every grid).
            if !((v[m - 1] < v[m] && v[m] < v[m + 1]) || (v[m - 1] > v[m] && v[m] > v[m + 1])) {
                continue;
            }
            let xs = [ks[m - 2], ks[m - 1], ks[m + 1], ks[m + 2]];
            let ys = [v[m - 2], v[m - 1], v[m + 1], v[m + 2]];
            let r = (v[m] - lagrange(&xs, &ys, ks[m])).abs() / scale;
            if r.is_finite() {
                total += r.min(ROUGH_CAP);
            }
        }
    }
    total
}

/// Cap of one row's roughness, in median command changes.
const ROUGH_CAP: f64 = 3.0;

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
    check_row_spacing(t, rate)?;
    let ticks: Vec<i64> = t.iter().map(|&x| tick_of(x, t0, rate, timing)).collect();
    let (k0, k1) = (ticks[0], ticks[n - 1]);
    if n >= 2 && k0 == k1 {
        return Err(ScheduleError::OneTick { tick: k0, rows: n });
    }
    let span = k1 as f64 - k0 as f64 + 1.0;
    if !(span <= MAX_SCHEDULE_TICKS) {
        return Err(ScheduleError::Span { ticks: span });
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
    // A tick whose rows disagree (stamps rounded to 1 ms, stamp jitter, a first row stamped at
    // the tick but sampled before it): the row nearest the tick's middle, the one whose tick
    // is least in doubt. (The first row of such a tick carried the previous tick's command in
    // an independent tryout's logs: 78 mrad spikes in the replay.)
    if conflicting > 0 && timing == CommandTiming::InForce {
        let mid = |k: usize| t0 + ((k as i64 + k0) as f64 + 0.5) / rate;
        let mut i = 0;
        while i < n {
            let k = (ticks[i] - k0) as usize;
            let mut j = i;
            while j < n && ticks[j] == ticks[i] {
                j += 1;
            }
            let disagree = (i + 1..j).any(|m| cmds.iter().any(|c| (c[m] - c[i]).abs() > 1e-9));
            if disagree {
                rep[k] =
                    (i..j).min_by(|&a, &b| (t[a] - mid(k)).abs().total_cmp(&(t[b] - mid(k)).abs()));
            }
            i = j;
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
            any_ramp |= fill_gap(v, &known, w, fill);
        }
        if any_ramp {
            stats.interpolated += j - i - 1;
        }
    }
    // A `sent_after` log's first row is sampled before the first tick it shows: the command in
    // force there is the tick before, which no row logs. Held at the first logged command, it
    // switched a tick early (up to 34 mrad of start transient on an independent tryout's logs).
    // It is extrapolated along the first ticks' shape when they move on one slope (a ramp, or a
    // smooth curve whose slope changes by less than half from tick to tick); else held.
    let first_tick_t = t0 + k0 as f64 / rate;
    if timing == CommandTiming::SentAfter && t[0] < first_tick_t - TICK_EPS / rate {
        for v in out.iter_mut() {
            let before = match v.get(..3) {
                Some(&[a, b, c]) if a.is_finite() && b.is_finite() && c.is_finite() => {
                    let (s1, s2) = (b - a, c - b);
                    if (s1 - s2).abs() <= 1e-6 + 0.5 * s1.abs().max(s2.abs()) { a - s1 } else { a }
                }
                _ => v[0],
            };
            v.insert(0, before);
        }
        stats.ticks += 1;
        stats.interpolated += 1;
        return Ok(Schedule::Ticks { t0, rate, k0: k0 - 1, cmd: out, stats });
    }
    Ok(Schedule::Ticks { t0, rate, k0, cmd: out, stats })
}

/// Three known ticks lie on one line (a constant-rate ramp, or a hold) when the slopes on
/// either side of the middle one agree within this fraction (plus 1e-6 rad per tick, the
/// rounding of printed commands). A ramped step added to a slow drift still counts as a line;
/// a smooth command (a chirp, smooth random motion at 100 Hz) bends by more than this.
const LINE_TOL: f64 = 1e-2;

fn slope(v: &[f64], p: usize, q: usize) -> f64 {
    (v[q] - v[p]) / (q - p) as f64
}

fn collinear(s1: f64, s2: f64) -> bool {
    (s1 - s2).abs() <= 1e-6 + LINE_TOL * s1.abs().max(s2.abs())
}

/// Fills the empty ticks of one joint's gap between `known[w]` and `known[w + 1]`; returns
/// `false` when the gap was held (a step), `true` when it was filled along the command's shape.
///
/// The commands a controller sends are ramps, holds and smooth curves, and a missing tick is
/// filled by the shape the known ticks around it show (with a, b the commands at the gap's
/// ends, s_b, s_a the slopes just before and after it, g the slope across it):
/// * **corner** — a ramp beside the gap (three known ticks on a line on either side) that
///   starts or ends inside it (g between s_b and s_a): the ramp continues at its slope until it
///   meets the other side's line, `min`/`max(a + s_b·(k − i), b − s_a·(j − k))`. Linear
///   interpolation puts the corner's tick up to half a ramp step off (2.8 mrad on a ramped
///   step of the Asimov hip, 48 mrad on arm2's).
/// * **ramp** — a line beside the gap that continues across it (g = its slope): linear.
/// * **smooth** — a slope beside the gap at least a third of the slope across it (`is_smooth`):
///   the cubic through the two known ticks on each side (linear when a side has none).
/// * **step** — otherwise (flat on both sides, a jump across the gap): the command before the
///   gap held ([`Fill::Ramps`]) or the one after it ([`Fill::Next`]).
///
/// On noise-free synth recordings (async 88 Hz ± 15 % recorder, 100 Hz controller) this takes
/// the reconstructed command's RMS error against the exact per-tick commands from 0.95 to
/// 0.11 mrad on arm2's clean control, 0.45 to 0.09 on the Asimov legs, 1.70 to 0.19 on arm3
/// and 3.41 to 0.42 on the pendulum (mixed excitation); what is left is steps whose tick no row
/// shows, which the fit's reconstruction floor covers ([`Fill::Next`]).
///
/// [`Fill::Hold`] holds every gap.
fn fill_gap(v: &mut [f64], known: &[usize], w: usize, fill: Fill) -> bool {
    let (i, j) = (known[w], known[w + 1]);
    let (a, b) = (v[i], v[j]);
    let g = (b - a) / (j - i) as f64;
    let hold = if fill == Fill::Next { b } else { a };
    // Writes `f(k)` into every empty tick k of the gap.
    let set = |v: &mut [f64], f: &dyn Fn(usize) -> f64| {
        for (k, x) in v.iter_mut().enumerate().take(j).skip(i + 1) {
            *x = f(k);
        }
    };
    if fill == Fill::Hold {
        set(v, &|_| hold);
        return false;
    }
    let sb = (w >= 1).then(|| slope(v, known[w - 1], i));
    let sa = known.get(w + 2).map(|&q| slope(v, j, q));
    let line_before =
        w >= 2 && sb.is_some_and(|s| collinear(slope(v, known[w - 2], known[w - 1]), s));
    let line_after = w + 3 < known.len()
        && sa.is_some_and(|s| collinear(s, slope(v, known[w + 2], known[w + 3])));
    let linear = move |k: usize| a + g * (k - i) as f64;
    if let (Some(sb), Some(sa)) = (sb, sa)
        && (line_before || line_after)
        && (sb - g) * (g - sa) > 0.0
    {
        set(v, &|k| {
            let from_before = a + sb * (k - i) as f64;
            let from_after = b - sa * (j - k) as f64;
            if sb > sa { from_before.min(from_after) } else { from_before.max(from_after) }
        });
        return true;
    }
    let continues = |line: bool, s: Option<f64>| {
        line && s.is_some_and(|s| (g - s).abs() <= 1e-6 + LINE_TOL * s.abs())
    };
    if continues(line_before, sb) || continues(line_after, sa) {
        set(v, &linear);
        return true;
    }
    if !is_smooth(g, sb, sa) {
        set(v, &|_| hold);
        return false;
    }
    // The alternative fill moves a smooth gap by √2 × the cubic's own error on the known ticks
    // nearby, with a sign from the tick (half the mean square of the two replays' difference is
    // the floor, so √2 makes a smooth gap count its whole expected error; a step its half).
    let shift = if fill == Fill::Next {
        std::f64::consts::SQRT_2 * cubic_error_near(v, known, w) * pseudo_sign(i as u64)
    } else {
        0.0
    };
    match (w >= 1, known.get(w + 2)) {
        (true, Some(&q)) => {
            let xs = [known[w - 1], i, j, q].map(|x| x as f64);
            let ys = [v[known[w - 1]], a, b, v[q]];
            set(v, &|k| lagrange(&xs, &ys, k as f64) + shift);
        }
        _ => set(v, &|k| linear(k) + shift),
    }
    true
}

/// How far the cubic through two known ticks on either side misses a known tick, near the gap
/// after `known[w]`: the median |error| of leaving out, one at a time, the up to
/// [`CUBIC_PROBES`] known ticks closest to the gap whose two neighbours on each side are known
/// (0 when there is none). A chirp or a sine is predicted to micro-radians; a command with
/// tick-to-tick roughness (filtered random motion) is not, and neither is its missing tick.
fn cubic_error_near(v: &[f64], known: &[usize], w: usize) -> f64 {
    let is_known = |k: usize| known.binary_search(&k).is_ok();
    let mut errs: Vec<f64> = Vec::new();
    // Known ticks by distance from the gap: alternately before and after it.
    let (mut lo, mut hi) = (w as isize, w as isize + 1);
    while errs.len() < CUBIC_PROBES && (lo >= 0 || (hi as usize) < known.len()) {
        for idx in [lo, hi] {
            if idx < 0 || idx as usize >= known.len() || errs.len() >= CUBIC_PROBES {
                continue;
            }
            let m = known[idx as usize];
            if m >= 2 && [m - 2, m - 1, m + 1, m + 2].iter().all(|&k| is_known(k)) {
                let xs = [m - 2, m - 1, m + 1, m + 2].map(|x| x as f64);
                let ys = [v[m - 2], v[m - 1], v[m + 1], v[m + 2]];
                let e = v[m] - lagrange(&xs, &ys, m as f64);
                if e.is_finite() {
                    errs.push(e.abs());
                }
            }
        }
        lo -= 1;
        hi += 1;
        if hi - lo > 2 * CUBIC_REACH as isize {
            break;
        }
    }
    if errs.is_empty() {
        return 0.0;
    }
    errs.sort_by(f64::total_cmp);
    let n = errs.len();
    if n % 2 == 1 { errs[n / 2] } else { 0.5 * (errs[n / 2 - 1] + errs[n / 2]) }
}

/// Known ticks [`cubic_error_near`] leaves out, and how many known ticks on each side of the
/// gap it looks through for them.
const CUBIC_PROBES: usize = 5;
const CUBIC_REACH: usize = 12;

/// +1 or −1 from a number (a tick; a fixed hash: the same recording gives the same floor).
pub(crate) fn pseudo_sign(k: u64) -> f64 {
    let h = (k ^ 0x9E37_79B9_7F4A_7C15).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    if (h >> 31) & 1 == 0 { 1.0 } else { -1.0 }
}

/// The polynomial through the points (`xs`, `ys`) at `x`.
fn lagrange(xs: &[f64; 4], ys: &[f64; 4], x: f64) -> f64 {
    (0..4)
        .map(|m| {
            let w: f64 =
                (0..4).filter(|&n| n != m).map(|n| (x - xs[n]) / (xs[m] - xs[n])).product();
            w * ys[m]
        })
        .sum()
}

/// A gap is smooth motion, not a step, when a known slope beside it is at least a third of the
/// slope across it (an extremum of a chirp has a small slope across, larger ones beside); a step
/// jumps across the gap steeper than 3× anything beside it (flat on both sides, or a step on
/// top of slow motion).
fn is_smooth(gap: f64, before: Option<f64>, after: Option<f64>) -> bool {
    let side = [before, after]
        .into_iter()
        .flatten()
        .map(f64::abs)
        .fold(None, |m: Option<f64>, s| Some(m.map_or(s, |m| m.max(s))));
    side.is_some_and(|s| gap.abs() <= 3.0 * s)
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
        // Before the first tick a row shows: the tick no row logs, along the ramp (1, 2, 3).
        assert_eq!(s.at(0, 0.005), 0.0);
        let f =
            reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
        assert_eq!(f.at(0, 0.012), 2.0);
    }

    /// A `sent_after` log that starts mid-tick: the tick in force at its first row is
    /// extrapolated along a ramp or a smooth curve, held before a step or a hold, and not
    /// added when the first row sits exactly on its tick.
    #[test]
    fn sent_after_fills_the_tick_before_the_first_row() {
        let t = [0.013, 0.023, 0.033, 0.043];
        let at_start = |c: &[f64]| {
            let s = reconstruct(&t, &[c], Some(100.0), 0.0, CommandTiming::SentAfter, Fill::Ramps)
                .unwrap();
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
        let s =
            reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
        assert_eq!(s.stats().unwrap().conflicting, 1);
        // The tick's command is that of its row nearest the tick's middle (0.005): 0.004's.
        assert_eq!(s.at(0, 0.005), 1.5);
        // A row stamped at the tick that still logs the previous command (sampled just before
        // it) does not make the tick stale: ticks [0.01, 0.02) and [0.02, 0.03).
        let t = [0.006, 0.010, 0.013, 0.016, 0.020, 0.024, 0.027];
        let c = [1.0, 1.0, 2.0, 2.0, 2.0, 3.0, 3.0];
        let s =
            reconstruct(&t, &[&c], Some(100.0), 0.0, CommandTiming::InForce, Fill::Ramps).unwrap();
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
}
