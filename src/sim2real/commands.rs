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

mod phase;
#[cfg(test)]
mod tests;

pub use phase::*;

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
