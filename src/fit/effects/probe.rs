//! The diagnosis's default probe of a parameter: one step of a fixed fraction of its range
//! ([`Effect::probes`](super::Effect::probes), [`Effect::screened`](super::Effect::screened)).

/// The linearised re-ranking's probe step [fraction of a parameter's range].
pub const PROBE_STEP: f64 = 0.05;

/// A parameter's default probe value: `start` moved by [`PROBE_STEP`] of `[lo, hi]`, up, or
/// down when up would leave the bounds.
pub fn probe_step(start: f64, lo: f64, hi: f64) -> f64 {
    let step = PROBE_STEP * (hi - lo);
    if start + step <= hi { start + step } else { start - step }
}
