//! What the replay inputs say about the control rate: recordings with a command and no rate,
//! a declared rate that `--control-hz` replaces, a command that changes between the ticks.

use crate::sim2real::recording::{self, Recording};
use crate::sim2real::replay::{self, ReplayOptions};
use crate::util::fmt_num;

/// For a recording with a command and no control rate (none in the file, no `--control-hz`,
/// not declared `control_rate_hz: none`, not a BAM servo log, whose servo takes each goal as
/// it arrives): `Some(median interval between the rows where the command changes)`, the inner
/// `None` when it changes fewer than 8 times.
pub(super) fn undeclared_rate(r: &Recording, opts: &ReplayOptions) -> Option<Option<f64>> {
    let declared = |k: &str, v: &str| r.meta.get(k).is_some_and(|x| x == v);
    if opts.control_hz.or(r.control_rate_hz).is_some()
        || declared(recording::KEY_CONTROL_RATE, recording::RATE_NONE)
        || declared("source_format", "bam")
    {
        return None;
    }
    let cmds: Vec<&[f64]> = r.joints.iter().filter_map(|j| j.q_cmd.as_deref()).collect();
    if cmds.is_empty() {
        return None;
    }
    let changes: Vec<f64> =
        (1..r.t.len()).filter(|&i| cmds.iter().any(|c| c[i] != c[i - 1])).map(|i| r.t[i]).collect();
    let mut dt: Vec<f64> = changes.windows(2).map(|w| w[1] - w[0]).collect();
    if dt.len() < 8 {
        return Some(None);
    }
    dt.sort_by(f64::total_cmp);
    Some(Some(dt[dt.len() / 2]))
}

/// The warning for the recordings [`undeclared_rate`] found: what the replay assumed (each
/// command held from its own row's time) and how to declare the rate.
pub(super) fn no_rate_warning(files: &[(String, Option<f64>)], total: usize) -> Option<String> {
    if files.is_empty() {
        return None;
    }
    let shown: Vec<String> = files
        .iter()
        .take(3)
        .map(|(f, dt)| match dt {
            Some(dt) => format!("{f} (its command changes every {:.1} ms, median)", dt * 1e3),
            None => f.clone(),
        })
        .collect();
    let more = if files.len() > 3 { ", …" } else { "" };
    Some(format!(
        "{} of {total} recordings have a command but no control rate: {}{more}. Each command was \
         replayed as held from its own row's time, so a command that a controller set at a tick \
         between two rows starts late by up to a row interval in the replay — a lag `fit` can \
         take for armature, damping or a slower servo. Declare the controller's rate: \
         `# control_rate_hz: 50` in a CSV header, `control_rate_hz = 50` in a --log-map file, a \
         scalar `control_rate_hz` in an .npz/.pt dict, or --control-hz 50 (Python: \
         control_hz=50); if each command really acts from its own time stamp (goals sent as \
         events, no control loop), declare `# control_rate_hz: none`",
        files.len(),
        shown.join(", ")
    ))
}

/// The warning for recordings whose declared control rate `--control-hz` replaces.
pub(super) fn overridden_rate_warning(
    files: &[(String, f64)],
    given: Option<f64>,
    total: usize,
) -> Option<String> {
    let (given, (_, first)) = (given?, files.first()?);
    let same = files.iter().all(|(_, d)| d == first);
    let shown: Vec<String> = files
        .iter()
        .take(3)
        .map(|(f, d)| if same { f.clone() } else { format!("{f} ({} Hz)", fmt_num(*d, 6)) })
        .collect();
    let more = if files.len() > 3 { ", …" } else { "" };
    let declared = if same {
        format!("the {} Hz they declare", fmt_num(*first, 6))
    } else {
        "the rates they declare".into()
    };
    Some(format!(
        "--control-hz {} replaces {declared} in {} of {total} recordings: {}{more}. A rate below \
         the controller's merges its ticks (the replay keeps one command of each merged tick and \
         applies it late, a lag `fit` takes for a delay); leave --control-hz out to use the files'",
        fmt_num(given, 6),
        files.len(),
        shown.join(", ")
    ))
}

/// The warning for recordings whose command changes between the control ticks
/// ([`replay::off_grid`]).
pub(super) fn off_grid_warning(
    files: &[(String, replay::OffGrid)],
    total: usize,
) -> Option<String> {
    let first = &files.first()?.1;
    let shown: Vec<String> = files
        .iter()
        .take(3)
        .map(|(f, o)| {
            format!(
                "{f} ({} of {} ticks at {} Hz hold different commands; a change every {:.1} ms, median)",
                o.conflicting,
                o.occupied,
                fmt_num(o.rate, 6),
                o.median_change_s * 1e3
            )
        })
        .collect();
    let more = if files.len() > 3 { ", …" } else { "" };
    Some(format!(
        "{} of {total} recordings have a command that changes within the ticks of the {} Hz \
         control rate in use: {}{more}. The replay keeps one command per tick and drops the \
         others, so the replay lags the robot. Either the rate is wrong (the controller's is \
         higher: check --control-hz and `control_rate_hz`) or the column is not the command in \
         force (a setpoint interpolated per row: declare `control_rate_hz: none`)",
        files.len(),
        fmt_num(first.rate, 6),
        shown.join(", ")
    ))
}
