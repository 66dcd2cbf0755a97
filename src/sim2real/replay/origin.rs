//! Where a recording's control ticks are when it does not say (`control_t0_s` absent), and
//! whether the rows agree with it when it does.
//!
//! Without `control_t0_s` the ticks used to be put at the first row's time. A recorder that
//! samples asynchronously (most do: a logging thread beside the control loop) starts anywhere
//! within a tick, so every command then switched up to one tick early or late in the replay —
//! a lag the fit explained as wrong gains, armature or damping (an independent humanoid
//! simulator's clean logs, 50 Hz control, ~200 Hz recorder: knee kp × 1.08, kd × 0.74). The rows
//! themselves show where the ticks are: see [`tick_phase`].

use std::path::PathBuf;

use crate::sim2real::commands::{
    RateFit, TickPhase, agreement_at, fit_rate, grid_agreement, tick_phase_q, time_quantum,
};
use crate::sim2real::recording::Recording;

use super::{ReplayOptions, timing_of};

/// Fewest command changes between close rows before the rows' phase overrules the first row's
/// time, or is held against a declared `control_t0_s`.
pub const MIN_CHANGES: usize = 8;

/// Share of the command changes one tick grid must agree with for the command column to be a
/// per-tick command at the given rate.
const GRID_SHARE: f64 = 0.9;

/// Below this [`TickPhase::margin`] the command's shape does not tell the phases the changes
/// allow apart.
const SHAPE_MARGIN: f64 = 1.05;

/// A declared `control_t0_s` outside the phases the command's shape chose is reported only from
/// this margin on.
const SHAPE_WARN_MARGIN: f64 = 1.5;

/// What [`resolve_tick_origin`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TickOrigin {
    /// No control rate (each goal holds from its own timestamp), no recorded command, or a
    /// declared origin with too few command changes to check it.
    Unknown,
    /// No `control_t0_s`, and fewer than [`MIN_CHANGES`] command changes between rows less
    /// than a tick apart (a logger locked to the controller, a command held for seconds): the
    /// first row's time is used as a tick, unchecked.
    Unobservable,
    /// The origin in use (declared, or the first row's time) agrees with the rows.
    Agrees,
    /// No `control_t0_s`, and the rows put the ticks elsewhere than the first row: the origin
    /// is now `t0`, the middle of the phases the rows allow (± `half_width` s), found from the
    /// `changes` alone or (`by_shape`) with the command's shape choosing among several phases
    /// the changes allow.
    Estimated { t0: f64, half_width: f64, changes: usize, by_shape: bool, period: f64 },
    /// No `control_t0_s`, and `optima` phase intervals fit the changes and the command's shape
    /// equally well (a recorder slower than the controller, a command of steps and holds): the
    /// origin is `t0` — the first row's time when it is one of them (`kept`).
    Ambiguous { t0: f64, optima: usize, kept: bool },
    /// The declared `control_t0_s` contradicts `missed` of the `changes`, or (`missed` 0) the
    /// command's shape clearly prefers other phases (kept: it is the user's; the rows suggest
    /// `suggested`).
    Contradicted { declared: f64, suggested: f64, half_width: f64, missed: usize, changes: usize },
    /// No tick grid at this rate agrees with more than `agree` of the `changes`: the command
    /// column changes within ticks (an interpolated target?) or the rate is wrong.
    NoGrid { rate: f64, agree: usize, changes: usize },
}

/// How far from the nominal rate [`resolve_rate`] looks (± 0.5 %).
const RATE_SEARCH: f64 = 0.005;

/// What [`resolve_rate`] found: the control rate in use fits no tick grid as well as one
/// nearby, and the recording's clock was rescaled to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateFix {
    /// The rate in use (`control_rate_hz` or `--control-hz`) and how many of the command
    /// changes its best grid agrees with.
    pub declared: f64,
    pub declared_agree: usize,
    /// The rate the changes fit on the recording's own clock ([`fit_rate`]).
    pub fit: RateFit,
}

/// Metadata key: the factor [`resolve_rate`] scaled the recording's times by.
pub const KEY_TIME_SCALE: &str = "time_scale";

/// Metadata key: the resolution of the timestamps before [`resolve_rate`] rescaled them (1 ms
/// stamps are off every decimal grid after it), scaled with them.
pub const KEY_TIME_QUANTUM: &str = "time_quantum_s";

/// A recording whose command changes within the ticks of the control rate in use: more than
/// 1 − [`GRID_SHARE`] of the ticks that hold rows hold rows that disagree on the command
/// (`TickStats::conflicting`; stamp jitter at a tick's edge makes a few). The replay keeps one
/// command per tick, so the others are lost: the rate is wrong (a `--control-hz` below the
/// controller's) or the column is not the command in force (a setpoint interpolated per row).
#[derive(Debug, Clone, PartialEq)]
pub struct OffGrid {
    /// The control rate in use [Hz].
    pub rate: f64,
    /// Ticks that hold rows, and how many of them hold rows with different commands.
    pub occupied: usize,
    pub conflicting: usize,
    /// The median interval between command changes [s].
    pub median_change_s: f64,
}

/// [`OffGrid`] for `rec` under `opts`, `None` when its command is one per tick (or the rows
/// disagree in fewer than [`MIN_CHANGES`] ticks).
pub fn off_grid(rec: &Recording, opts: &ReplayOptions) -> Option<OffGrid> {
    let (Some(rate), timing, tick0) = timing_of(rec, opts) else { return None };
    // Only the recorded commands: a joint without one (a passive joint, a mimic) is replayed
    // on its measured positions, which change on every row whatever the control rate.
    let cmds: Vec<&[f64]> = rec.joints.iter().filter_map(|j| j.q_cmd.as_deref()).collect();
    if cmds.is_empty() {
        return None;
    }
    let st = crate::sim2real::commands::reconstruct(
        &rec.t,
        &cmds,
        Some(rate),
        tick0,
        timing,
        opts.command_fill,
    )
    .ok()?
    .stats()?;
    if st.conflicting < MIN_CHANGES
        || (st.conflicting as f64) <= (1.0 - GRID_SHARE) * st.occupied as f64
    {
        return None;
    }
    let at: Vec<f64> = (1..rec.t.len())
        .filter(|&i| cmds.iter().any(|c| c[i] != c[i - 1]))
        .map(|i| rec.t[i])
        .collect();
    let mut dt: Vec<f64> = at.windows(2).map(|w| w[1] - w[0]).collect();
    dt.sort_by(f64::total_cmp);
    let median_change_s = *dt.get(dt.len() / 2)?;
    Some(OffGrid { rate, occupied: st.occupied, conflicting: st.conflicting, median_change_s })
}

/// When the recorded command changes miss every tick grid at the control rate in use (more than
/// 2 % of them at its best phase), but fit one at a rate within ± 0.5 % of it (missing at most
/// half as many) — a logger's clock that drifts against the controller's, or a controller off
/// its nominal rate (a policy loop timed by `sleep`) — the recording's times are rescaled about
/// its tick origin (or first row) so that the ticks come at the rate in use: the physics steps
/// stay on the ticks, and the motion's own time changes by the clocks' ppm. At 100 ppm a 50 Hz
/// grid slides a tenth of a tick over 20 s and the rows near the tick edges land in the wrong
/// tick (an independent simulator's humanoid logs: position MAE 0.54 → 0.77 mrad, peaks 9 mrad).
pub fn resolve_rate(rec: &mut Recording, opts: &ReplayOptions) -> Option<RateFix> {
    let (Some(rate), _, tick0) = timing_of(rec, opts) else { return None };
    let cmds: Vec<&[f64]> = rec.joints.iter().filter_map(|j| j.q_cmd.as_deref()).collect();
    if cmds.is_empty() {
        return None;
    }
    // Misses at the best phase, or at the declared origin (a slow drift leaves the best phase
    // a few misses, spread over both ends; the origin declared at the log's start misses the
    // late ones).
    let (best, changes) = grid_agreement(&rec.t, &cmds, rate);
    let agree = match rec.control_t0_s {
        Some(t0) => best.min(agreement_at(&rec.t, &cmds, rate, t0)),
        None => best,
    };
    let missed = changes - agree;
    // A command that changes within ticks (interpolated per row) fits no grid at any rate:
    // nothing to search for.
    if changes < MIN_CHANGES || missed <= rate_slack(changes) || 2 * best < changes {
        return None;
    }
    let fit = fit_rate(&rec.t, &cmds, rate, RATE_SEARCH)?;
    let fit_missed = fit.changes - fit.agree;
    if fit.agree < MIN_CHANGES || (fit.agree as f64) < GRID_SHARE * fit.changes as f64 {
        return None;
    }
    // Either the fitted rate's best phase clearly beats the given rate's, or (a slow drift the
    // best phase absorbs) the declared origin, which missed the changes at the given rate,
    // agrees at the fitted one. A wrong origin at the right rate does neither: at any rate
    // near it the declared origin still misses the changes at the log's start.
    let nominal_missed = changes - best;
    let grid_better = fit_missed < nominal_missed && 2 * fit_missed <= nominal_missed;
    let origin_better = rec.control_t0_s.is_some_and(|t0| {
        let at_fit = fit.changes - agreement_at(&rec.t, &cmds, fit.rate, t0).min(fit.changes);
        2 * at_fit <= missed && at_fit <= rate_slack(fit.changes)
    });
    if !(grid_better || origin_better) {
        return None;
    }
    let scale = fit.rate / rate;
    let quantum = time_quantum(&rec.t) * scale;
    for x in &mut rec.t {
        *x = tick0 + (*x - tick0) * scale;
    }
    for j in &mut rec.joints {
        if let Some(qd) = j.qd.as_mut() {
            for v in qd {
                *v /= scale;
            }
        }
    }
    rec.meta.insert(KEY_TIME_SCALE.to_string(), format!("{scale}"));
    rec.meta.insert(KEY_TIME_QUANTUM.to_string(), format!("{quantum}"));
    Some(RateFix { declared: rate, declared_agree: agree, fit })
}

/// Command changes no phase of the right grid may miss before the rate is questioned (rows
/// stamped late by a busy logger, a timestamp rounded across an edge).
fn rate_slack(changes: usize) -> usize {
    (changes / 50).max(2)
}

/// The warning for the [`RateFix`]es of several files.
pub fn rate_messages(items: &[(PathBuf, RateFix)]) -> Option<String> {
    if items.is_empty() {
        return None;
    }
    let list: Vec<String> = items
        .iter()
        .map(|(p, f)| {
            format!(
                "{}: ticks at {:.5} ± {:.5} Hz on its clock ({:+.0} ppm; {} of {} changes fit, \
                 {} at {} Hz)",
                file_name(p),
                f.fit.rate,
                f.fit.half_width,
                1e6 * (f.fit.rate / f.declared - 1.0),
                f.fit.agree,
                f.fit.changes,
                f.declared_agree,
                f.declared
            )
        })
        .collect();
    Some(format!(
        "the command changes fit a tick grid at a rate slightly off the control rate given (a \
         logger's clock drifting against the controller's, or a controller off its nominal \
         rate) — {}: each file's times are rescaled to put its ticks at the rate given",
        some_of(&list)
    ))
}

/// Checks the recording's tick origin against its rows and, when `control_t0_s` is absent and
/// the first row's time contradicts them, sets it to the rows' estimate (so that the replay,
/// every slice of the recording and the fit's windows all use it).
pub fn resolve_tick_origin(rec: &mut Recording, opts: &ReplayOptions) -> TickOrigin {
    let (Some(rate), _, tick0) = timing_of(rec, opts) else { return TickOrigin::Unknown };
    // Only recorded commands say where the ticks are (a joint without q_cmd is replayed to its
    // q, which changes at every row).
    let cmds: Vec<&[f64]> = rec.joints.iter().filter_map(|j| j.q_cmd.as_deref()).collect();
    let unseen = if rec.control_t0_s.is_none() && !cmds.is_empty() {
        TickOrigin::Unobservable
    } else {
        TickOrigin::Unknown
    };
    // Rescaled times ([`resolve_rate`]) keep the resolution their stamps had.
    let quantum = rec
        .meta
        .get(KEY_TIME_QUANTUM)
        .and_then(|q| q.parse::<f64>().ok())
        .unwrap_or_else(|| time_quantum(&rec.t));
    let Some(tp) = tick_phase_q(&rec.t, &cmds, rate, tick0, quantum) else { return unseen };
    if tp.changes < MIN_CHANGES {
        return unseen;
    }
    judge(rec, rate, &tp)
}

fn judge(rec: &mut Recording, rate: f64, tp: &TickPhase) -> TickOrigin {
    let TickPhase { changes, agree, agree_candidate, width, optima, .. } = *tp;
    if (agree as f64) < GRID_SHARE * changes as f64 {
        return TickOrigin::NoGrid { rate, agree, changes };
    }
    let first = rec.t[0];
    match rec.control_t0_s {
        None => {
            let ambiguous = optima > 1 && tp.margin.is_some_and(|m| m < SHAPE_MARGIN);
            if ambiguous {
                // The first row's time stays when the changes allow it.
                let kept = agree_candidate >= agree;
                let t0 = if kept { first } else { tp.origin_at_or_before(first, rate) };
                if !kept {
                    rec.control_t0_s = Some(t0);
                }
                return TickOrigin::Ambiguous { t0, optima, kept };
            }
            if tp.candidate_chosen {
                return TickOrigin::Agrees;
            }
            let t0 = tp.origin_at_or_before(first, rate);
            rec.control_t0_s = Some(t0);
            TickOrigin::Estimated {
                t0,
                half_width: 0.5 * width,
                changes,
                by_shape: optima > 1,
                period: 1.0 / rate,
            }
        }
        // A declared origin a few changes off (timestamp jitter, a slightly wrong rate over a
        // long log) is not worth a warning; one that misses many is.
        Some(declared) => {
            let missed = agree - agree_candidate.min(agree);
            let suggested = tp.origin_nearest(declared, rate);
            // The shape's choice overrules a declared value only when it is far (a tenth of
            // a tick) from it: timestamp jitter splits the right phase into neighbouring parts.
            let by_shape = !tp.candidate_in_run
                && optima > 1
                && tp.margin.is_some_and(|m| m >= SHAPE_WARN_MARGIN)
                && (suggested - declared).abs() > 0.1 / rate;
            if missed <= (changes / 20).max(2) && !by_shape {
                return TickOrigin::Agrees;
            }
            TickOrigin::Contradicted {
                declared,
                suggested,
                half_width: 0.5 * width,
                missed,
                changes,
            }
        }
    }
}

fn file_name(p: &std::path::Path) -> String {
    p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// Lists up to three items, then "and N more".
fn some_of(items: &[String]) -> String {
    let mut s = items.iter().take(3).cloned().collect::<Vec<_>>().join("; ");
    if items.len() > 3 {
        s.push_str(&format!("; and {} more", items.len() - 3));
    }
    s
}

/// One note and warnings summing up the origins of a set of recordings: `(notes, warnings)`.
pub fn origin_messages(items: &[(PathBuf, TickOrigin)]) -> (Vec<String>, Vec<String>) {
    let (mut notes, mut warnings) = (Vec::new(), Vec::new());
    let mut est = Vec::new();
    let mut widest: f64 = 0.0;
    let mut contra = Vec::new();
    let mut nogrid = Vec::new();
    let mut ambiguous = Vec::new();
    let mut unseen = Vec::new();
    let mut wide = Vec::new();
    for (p, o) in items {
        match *o {
            TickOrigin::Estimated { t0, half_width, period, .. } if half_width > 0.25 * period => {
                wide.push(format!(
                    "{}: control_t0_s = {t0:.6}, the phases allowed span {:.1} of the {:.1} ms tick",
                    file_name(p),
                    2e3 * half_width,
                    1e3 * period
                ));
            }
            TickOrigin::Estimated { t0, half_width, changes, by_shape, .. } => {
                widest = widest.max(half_width);
                let how = if by_shape { " and the command's shape" } else { "" };
                est.push(format!(
                    "{}: control_t0_s = {t0:.6} (from {changes} changes{how})",
                    file_name(p)
                ));
            }
            TickOrigin::Ambiguous { t0, optima, kept } => {
                let what = if kept { "the first row's time" } else { "one of them" };
                ambiguous.push(format!(
                    "{}: {optima} tick phases fit equally; {what} is used ({t0:.6})",
                    file_name(p)
                ));
            }
            TickOrigin::Contradicted { declared, suggested, half_width, missed, changes } => {
                let why = if missed > 0 {
                    format!("disagrees with {missed} of {changes} command changes")
                } else {
                    "makes the command jump back and forth between ticks".to_string()
                };
                contra.push(format!(
                    "{}: control_t0_s {declared} {why}; the rows put the ticks at {suggested:.6} ± {:.3} ms",
                    file_name(p),
                    half_width * 1e3
                ));
            }
            TickOrigin::NoGrid { rate, agree, changes } => nogrid.push(format!(
                "{}: at best {agree} of {changes} command changes fit one {rate} Hz tick grid",
                file_name(p)
            )),
            TickOrigin::Unobservable => unseen.push(file_name(p)),
            TickOrigin::Unknown | TickOrigin::Agrees => {}
        }
    }
    if !est.is_empty() {
        notes.push(format!(
            "{} of {} recordings have no control_t0_s and their first row is not on a control tick: the ticks' \
             phase was estimated from where the command changes between rows (to ± {:.3} ms) — {}. Declare \
             `# control_t0_s:` (the time of any control tick) to use your own",
            est.len(),
            items.len(),
            widest * 1e3,
            some_of(&est)
        ));
    }
    if !ambiguous.is_empty() {
        warnings.push(format!(
            "no control_t0_s, and the rows cannot place the control ticks (rows seldom less than a tick apart, \
             timestamps that jitter, or a command of steps and holds): {}. Commands may switch up to one tick early or late in the replay; \
             declare `# control_t0_s:` (the time of any control tick) if the logger knows it",
            some_of(&ambiguous)
        ));
    }
    if !wide.is_empty() {
        warnings.push(format!(
            "no control_t0_s, and the rows leave most of a tick open for the ticks' phase (a logger locked to the \
             controller: its rows keep one phase): the ticks are put just before the rows that show each new \
             command — {}. If the rows are stamped before the ticks instead, every command switches most of a tick \
             early; declare `# control_t0_s:` if the logger knows when the controller ticks",
            some_of(&wide)
        ));
    }
    if !unseen.is_empty() {
        notes.push(format!(
            "{} of {} recordings have no control_t0_s and too few command changes between rows less than a tick \
             apart to place the control ticks (a logger locked to the controller, or a command held for long): \
             their first row's time is taken as a tick — {}. If the logger knows when the controller ticks, \
             declare `# control_t0_s:`",
            unseen.len(),
            items.len(),
            some_of(&unseen)
        ));
    }
    if !contra.is_empty() {
        warnings.push(format!(
            "the declared control tick origin contradicts the rows (each row's command is the one in force at its \
             time, so the command can only change across a tick): {}. The declared value is used; if it is wrong, \
             the replay switches every command at the wrong time and the fit reads that as gains or damping",
            some_of(&contra)
        ));
    }
    if !nogrid.is_empty() {
        warnings.push(format!(
            "the command column changes between rows that no tick grid separates: {}. Is control_rate_hz right, \
             and is q_cmd the command in force per control tick (not a target interpolated per row)?",
            some_of(&nogrid)
        ));
    }
    (notes, warnings)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim2real::recording::JointTrace;

    /// Rows of an asynchronous recorder (`rec_hz`, intervals ± `jitter` × 50 %, a deterministic
    /// sequence) from 7.31 ms on, logging the command `f(tick time)` of the ticks
    /// `tick_t0 + k / rate`.
    fn log_of(
        tick_t0: f64,
        rate: f64,
        rec_hz: f64,
        jitter: f64,
        f: impl Fn(f64) -> f64,
    ) -> Recording {
        let mut t = Vec::new();
        let mut x: f64 = 0.00731;
        let mut s: u64 = 12345;
        while x < 10.0 {
            t.push((x * 1e6).round() / 1e6);
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let u = (s >> 11) as f64 / (1u64 << 53) as f64;
            x += (1.0 + jitter * (u - 0.5)) / rec_hz;
        }
        let cmd: Vec<f64> =
            t.iter().map(|&x| f(tick_t0 + ((x - tick_t0) * rate + 1e-9).floor() / rate)).collect();
        let mut j = JointTrace::new("j", cmd.clone());
        j.q_cmd = Some(cmd);
        let mut r = Recording::at_100hz(t, vec![j]);
        r.control_rate_hz = Some(rate);
        r
    }

    /// A 100 Hz command logged at ~1 kHz beside a joint with no command (a passive or mimic
    /// joint: its positions change on every row): the command is on its ticks, no off-grid
    /// warning. The same rows with that joint's positions as a command column are off grid.
    #[test]
    fn a_joint_without_a_command_does_not_make_the_command_off_grid() {
        let mut r = log_of(0.0, 100.0, 1000.0, 0.6, |x| (3.0 * x).sin());
        r.control_t0_s = Some(0.0);
        let free: Vec<f64> = r.t.iter().map(|&x| 0.3 * (7.0 * x).sin()).collect();
        r.joints.push(JointTrace::new("ankle", free.clone()));
        assert!(off_grid(&r, &ReplayOptions::default()).is_none());
        r.joints[1].q_cmd = Some(free);
        assert!(off_grid(&r, &ReplayOptions::default()).is_some());
    }

    /// A ramp of 0.5 rad/s, logged at ~`rec_hz`.
    fn async_log(tick_t0: f64, rate: f64, rec_hz: f64, _seconds: f64) -> Recording {
        log_of(tick_t0, rate, rec_hz, 0.6, |x| 0.5 * x)
    }

    /// Phase error of `t0` against ticks at `truth + k / rate`, in seconds (−½ … ½ tick).
    fn phase_err(t0: f64, truth: f64, rate: f64) -> f64 {
        (((t0 - truth) * rate + 0.5).rem_euclid(1.0) - 0.5) / rate
    }

    /// A controller 300 ppm slow against the logger's clock (ticks at 49.985 Hz, 50 declared,
    /// 10 s at ~200 Hz): the rows' changes fit the slower rate, and the times are rescaled so
    /// that the ticks come at 50 Hz through the declared origin; an exact log, and one whose
    /// declared origin alone is wrong, are left alone.
    #[test]
    fn a_drifting_clock_is_rescaled_to_the_declared_rate() {
        let truth = 50.0 * (1.0 - 300e-6);
        let mut r = async_log(0.0071, truth, 200.0, 10.0);
        r.control_rate_hz = Some(50.0);
        r.control_t0_s = Some(0.0071);
        let before = r.clone();
        let fix = resolve_rate(&mut r, &ReplayOptions::default()).expect("drift found");
        assert!((fix.fit.rate / truth - 1.0).abs() < 50e-6, "{fix:?}");
        assert!(
            fix.fit.agree + 2 >= fix.fit.changes && fix.declared_agree + 20 < fix.fit.changes,
            "{fix:?}"
        );
        // Tick k (at 0.0071 + k / truth on the log's clock) is now at 0.0071 + k / 50.
        let cmds = [r.joints[0].q_cmd.as_deref().unwrap()];
        let agree = agreement_at(&r.t, &cmds, 50.0, 0.0071);
        let (_, changes) = grid_agreement(&r.t, &cmds, 50.0);
        assert!(changes - agree <= rate_slack(changes), "{agree} of {changes}");
        let last = before.t.len() - 1;
        let scaled = 0.0071 + (before.t[last] - 0.0071) * fix.fit.rate / 50.0;
        assert!((r.t[last] - scaled).abs() < 1e-9 && r.meta.contains_key(KEY_TIME_SCALE));
        // The stamps' 1 µs resolution is kept (rescaled, they are off the decimal grid).
        let q: f64 = r.meta[KEY_TIME_QUANTUM].parse().unwrap();
        assert!((q - 1e-6 * fix.fit.rate / 50.0).abs() < 1e-15, "{q}");
        let msg = rate_messages(&[(PathBuf::from("ep.csv"), fix)]).unwrap();
        assert!(msg.contains("ep.csv: ticks at 49.98") && msg.contains(" ppm; 49"), "{msg}");
        // The exact rate: nothing to do.
        let mut exact = async_log(0.0071, 50.0, 200.0, 10.0);
        exact.control_t0_s = Some(0.0071);
        assert_eq!(resolve_rate(&mut exact, &ReplayOptions::default()), None);
        // The right rate with a wrong origin is the origin's problem, not the rate's.
        exact.control_t0_s = Some(0.0171);
        assert_eq!(resolve_rate(&mut exact, &ReplayOptions::default()), None);
    }

    #[test]
    fn a_recorder_slower_than_the_controller_is_placed_by_the_commands_shape() {
        // 88 Hz rows beside 100 Hz ticks at phase 3.7 ms (independent_arm2's logging): rows less
        // than a tick apart are rare and several phases fit every change; the command's shape
        // (a chirp-like smooth motion) picks the right one.
        let f = |x: f64| 0.3 * (2.0 * std::f64::consts::PI * (0.4 + 0.05 * x) * x).sin();
        let mut r = log_of(0.0037, 100.0, 88.0, 0.3, f);
        let o = resolve_tick_origin(&mut r, &ReplayOptions::default());
        let TickOrigin::Estimated { t0, by_shape, .. } = o else { panic!("{o:?}") };
        assert!(by_shape, "{o:?}");
        assert!(phase_err(t0, 0.0037, 100.0).abs() < 100e-6, "{o:?}");
        // A command of steps and holds: the shape does not tell; said, and the first row kept
        // when the changes allow it.
        let step = |x: f64| 0.1 * ((x * 13.0).floor() % 3.0);
        let mut r = log_of(0.0037, 100.0, 88.0, 0.3, step);
        let o = resolve_tick_origin(&mut r, &ReplayOptions::default());
        assert!(matches!(o, TickOrigin::Ambiguous { kept: true, .. }), "{o:?}");
        assert_eq!(r.control_t0_s, None);
        let (notes, w) = origin_messages(&[(PathBuf::from("s.csv"), o)]);
        assert!(notes.is_empty() && w[0].contains("s.csv: "), "{w:?}");
    }

    #[test]
    fn an_asynchronous_log_without_control_t0_gets_the_ticks_phase_from_its_rows() {
        // Ticks at 0.0123 + k/50; the first row at 7.31 ms is 15 ms after the tick before it.
        let mut r = async_log(0.0123, 50.0, 200.0, 10.0);
        let o = resolve_tick_origin(&mut r, &ReplayOptions::default());
        let TickOrigin::Estimated { t0, half_width, changes, by_shape, .. } = o else {
            panic!("{o:?}")
        };
        // The grid point at or before the first row: 0.0123 − 0.02.
        assert!((t0 - (0.0123 - 0.02)).abs() < 50e-6, "t0 {t0}");
        assert!(half_width < 100e-6, "half width {half_width}");
        assert!(changes > 400 && !by_shape, "{o:?}");
        assert_eq!(r.control_t0_s, Some(t0));
        // A second pass agrees with what the first set.
        assert_eq!(resolve_tick_origin(&mut r, &ReplayOptions::default()), TickOrigin::Agrees);
    }

    #[test]
    fn rows_that_start_on_a_tick_keep_the_first_rows_time() {
        let mut r = async_log(0.00731, 50.0, 200.0, 10.0);
        assert_eq!(resolve_tick_origin(&mut r, &ReplayOptions::default()), TickOrigin::Agrees);
        assert_eq!(r.control_t0_s, None);
    }

    #[test]
    fn a_declared_origin_the_rows_contradict_is_kept_and_reported() {
        let mut r = async_log(0.0123, 50.0, 200.0, 10.0);
        r.control_t0_s = Some(0.0);
        let o = resolve_tick_origin(&mut r, &ReplayOptions::default());
        let TickOrigin::Contradicted { declared, suggested, .. } = o else { panic!("{o:?}") };
        assert_eq!(declared, 0.0);
        assert!((suggested - (0.0123 - 0.02)).abs() < 50e-6, "{suggested}");
        assert_eq!(r.control_t0_s, Some(0.0));
        let (notes, warnings) = origin_messages(&[(PathBuf::from("a/ep.csv"), o)]);
        assert!(notes.is_empty());
        assert!(warnings[0].contains("ep.csv: control_t0_s 0 disagrees"), "{warnings:?}");
        // The right one, declared, is quiet.
        r.control_t0_s = Some(0.0123 + 3.0 * 0.02);
        assert_eq!(resolve_tick_origin(&mut r, &ReplayOptions::default()), TickOrigin::Agrees);
    }

    #[test]
    fn a_command_that_changes_within_ticks_fits_no_grid() {
        // The same rows, but the command is interpolated per row (changes at every row).
        let mut r = async_log(0.0123, 50.0, 200.0, 10.0);
        let c: Vec<f64> = r.t.iter().map(|&x| 0.3 * x).collect();
        r.joints[0].q_cmd = Some(c);
        let o = resolve_tick_origin(&mut r, &ReplayOptions::default());
        assert!(matches!(o, TickOrigin::NoGrid { rate: 50.0, .. }), "{o:?}");
        assert_eq!(r.control_t0_s, None);
        let (_, w) = origin_messages(&[(PathBuf::from("x.csv"), o)]);
        assert!(w[0].contains("x.csv: at best"), "{w:?}");
    }

    #[test]
    fn without_a_rate_or_with_a_held_command_nothing_is_said() {
        let mut r = async_log(0.0123, 50.0, 200.0, 10.0);
        r.control_rate_hz = None;
        assert_eq!(resolve_tick_origin(&mut r, &ReplayOptions::default()), TickOrigin::Unknown);
        let mut r = async_log(0.0123, 50.0, 200.0, 10.0);
        let n = r.t.len();
        r.joints[0].q_cmd = Some(vec![0.2; n]);
        // (without control_t0_s, the first row's time is used unchecked: said in a note)
        let o = resolve_tick_origin(&mut r, &ReplayOptions::default());
        assert_eq!(o, TickOrigin::Unobservable);
        let (notes, w) = origin_messages(&[(PathBuf::from("h.csv"), o)]);
        assert!(w.is_empty() && notes[0].contains("too few command changes"), "{notes:?}");
        r.control_t0_s = Some(0.0);
        assert_eq!(resolve_tick_origin(&mut r, &ReplayOptions::default()), TickOrigin::Unknown);
        // A joint without q_cmd (replayed to its q, which changes at every row) says nothing
        // about the ticks: the other joint's commands place them.
        let mut r = async_log(0.0123, 50.0, 200.0, 10.0);
        let q: Vec<f64> = r.t.iter().map(|&x| (3.0 * x).sin()).collect();
        r.joints.push(JointTrace::new("passive", q));
        let o = resolve_tick_origin(&mut r, &ReplayOptions::default());
        assert!(matches!(o, TickOrigin::Estimated { .. }), "{o:?}");
        r.joints.remove(0);
        r.control_t0_s = None;
        assert_eq!(resolve_tick_origin(&mut r, &ReplayOptions::default()), TickOrigin::Unknown);
        // --control-hz gives a rate to a recording without one.
        let mut r = async_log(0.0123, 50.0, 200.0, 10.0);
        r.control_rate_hz = None;
        let o = ReplayOptions { control_hz: Some(50.0), ..Default::default() };
        assert!(matches!(resolve_tick_origin(&mut r, &o), TickOrigin::Estimated { .. }));
    }
}
