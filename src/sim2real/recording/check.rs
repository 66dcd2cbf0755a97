//! Consistency checks of a parsed (or constructed) recording.

use super::{ParseOptions, Recording, RecordingError};

/// With many rows, the span may be this many median intervals per row
/// ([`super::MAX_SPAN_INTERVALS`] otherwise).
const MAX_INTERVALS_PER_ROW: f64 = 40.0;

impl Recording {
    /// Checks consistency (lengths, finiteness, strictly increasing time, at least two samples,
    /// positions not in degrees). Errors name the sample index (no line numbers).
    pub fn check(&self, opts: &ParseOptions) -> Result<(), RecordingError> {
        self.check_inner(opts, None)
    }

    /// [`Recording::check`] with the 1-based source line of every sample, when known (a BAM
    /// log's entries): errors then name the line.
    pub fn check_at_lines(
        &self,
        opts: &ParseOptions,
        row_lines: Option<&[usize]>,
    ) -> Result<(), RecordingError> {
        self.check_inner(opts, row_lines)
    }

    /// `row_lines[i]` is the 1-based source line of sample `i`, when known.
    pub(super) fn check_inner(
        &self,
        opts: &ParseOptions,
        row_lines: Option<&[usize]>,
    ) -> Result<(), RecordingError> {
        let line = |i: usize| row_lines.and_then(|r| r.get(i).copied());
        let at = |i: usize| match line(i) {
            Some(l) => format!("line {l}"),
            None => format!("sample {i}"),
        };
        let err = |i: usize, col: Option<&str>, msg: String| {
            RecordingError::new(&self.source, line(i), col, msg)
        };
        let n = self.t.len();
        if n < 2 {
            return Err(err(0, None, format!("need at least 2 samples, found {n}")));
        }
        for (i, &x) in self.t.iter().enumerate() {
            if !x.is_finite() {
                return Err(err(i, Some("t"), format!("non-finite time {x}")));
            }
            if i > 0 && x <= self.t[i - 1] {
                return Err(err(
                    i,
                    Some("t"),
                    format!(
                        "time not strictly increasing: t = {} s at {} is not after t = {} s at {}",
                        seconds_text(x),
                        at(i),
                        seconds_text(self.t[i - 1]),
                        at(i - 1)
                    ),
                ));
            }
        }
        // A time far from the others (a stamp in another unit, a corrupted value): the replay
        // would step across the whole span, and a control-tick schedule would hold a command
        // per tick of it.
        let mut dts: Vec<f64> = self.t.windows(2).map(|w| w[1] - w[0]).collect();
        dts.sort_by(f64::total_cmp);
        let median = dts[dts.len() / 2];
        let span = self.t[n - 1] - self.t[0];
        let limit = super::MAX_SPAN_INTERVALS.max(MAX_INTERVALS_PER_ROW * n as f64);
        if !(span / median <= limit) {
            let (i, gap) = self
                .t
                .windows(2)
                .map(|w| w[1] - w[0])
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((0, span));
            // The row on the far side: the first one when the jump follows it, else the next.
            let odd = if i == 0 { 0 } else { i + 1 };
            return Err(err(
                odd,
                Some("t"),
                format!(
                    "time jumps by {gap:.6e} s from t = {} at {} to t = {} at {}, while the median \
                     interval between rows is {median:.3e} s: the rows would span {:.3e} \
                     intervals (at most {limit:.0e}). A time stamp in another unit or a wrong \
                     value? (a long pause: split the recording there)",
                    self.t[i],
                    at(i),
                    self.t[i + 1],
                    at(i + 1),
                    span / median
                ),
            ));
        }
        let check_vec = |col: &str, v: &[f64]| -> Result<(), RecordingError> {
            if v.len() != n {
                return Err(err(
                    0,
                    Some(col),
                    format!("column '{col}' has {} samples, time has {n}", v.len()),
                ));
            }
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(err(
                    i,
                    Some(col),
                    format!("column '{col}': non-finite value {}", v[i]),
                ));
            }
            Ok(())
        };
        for j in &self.joints {
            let named = [
                ("q", Some(&j.q)),
                ("qd", j.qd.as_ref()),
                ("q_cmd", j.q_cmd.as_ref()),
                ("tau", j.tau.as_ref()),
                ("kp", j.kp.as_ref()),
                ("kd", j.kd.as_ref()),
            ];
            for (suffix, v) in named {
                if let Some(v) = v {
                    check_vec(&format!("{}.{suffix}", j.name), v)?;
                }
            }
            if let Some(e) = &j.enabled
                && e.len() != n
            {
                let col = format!("{}.enabled", j.name);
                return Err(err(
                    0,
                    Some(&col),
                    format!("column '{col}' has {} samples, time has {n}", e.len()),
                ));
            }
            let accumulates = opts.unlimited_joints.as_ref().is_some_and(|u| u.contains(&j.name));
            for (suffix, v) in [("q", Some(&j.q)), ("q_cmd", j.q_cmd.as_ref())] {
                let Some(v) = v.filter(|_| !accumulates) else { continue };
                if let Some(i) = v.iter().position(|x| x.abs() > opts.max_abs_rad) {
                    let col = format!("{}.{suffix}", j.name);
                    return Err(err(
                        i,
                        Some(&col),
                        format!(
                            "column '{col}': |{}| > {} rad at t = {}: looks like degrees (positions must be in radians: \
                         a CSV declares `# units: deg`, other logs take --log-units deg; a joint with no range in the \
                         model, a wheel, may turn past it)",
                            v[i], opts.max_abs_rad, self.t[i]
                        ),
                    ));
                }
            }
        }
        if let Some(b) = &self.base {
            if b.pos.len() != n || b.quat.len() != n {
                return Err(err(
                    0,
                    Some("base.x"),
                    format!("base pose has {}/{} samples, time has {n}", b.pos.len(), b.quat.len()),
                ));
            }
            let bad = b
                .pos
                .iter()
                .zip(b.quat.iter())
                .position(|(p, q)| p.iter().chain(q.iter()).any(|x| !x.is_finite()));
            if let Some(i) = bad {
                return Err(err(i, Some("base.x"), "base pose: non-finite value".into()));
            }
        }
        Ok(())
    }
}

/// A time as a message shows it: to the nanosecond (of a second), trailing zeros dropped, so a
/// stamp converted from milliseconds reads as written (0.285, not 0.28500000000000003).
pub(super) fn seconds_text(x: f64) -> String {
    let s = format!("{x:.9}");
    let s = s.trim_end_matches('0');
    s.strip_suffix('.').unwrap_or(s).to_string()
}
