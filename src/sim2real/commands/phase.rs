//! Where the control ticks are, from the rows alone: the phase of the tick grid that the
//! recorded command changes agree with ([`tick_phase`]), and a control rate slightly off on
//! the recording's clock ([`fit_rate`]).

use super::*;

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
