//! Options of the gap computation: spectra and decomposition segments, lag range, constants.

use crate::sim2real::metrics::GapConstants;

/// Welch segment duration [s]: 0.25 Hz resolution, eight bins in the 0–2 Hz band where a
/// robot's motion lives (a segment counted in samples made the resolution the log rate / 256:
/// a 1 Hz motion read "3.9 Hz" at 1 kHz and "39 Hz" at 10 kHz).
pub const SPECTRUM_SEGMENT_S: f64 = 4.0;
/// Decomposition segment duration [s]: eight times the lag search range
/// ([`GapOptions::max_lag_s`]), short enough that a free response off equilibrium stays in one
/// segment (see `locate::decompose_segments`).
pub const DECOMPOSE_SEGMENT_S: f64 = 2.0;

#[derive(Debug, Clone)]
pub struct GapOptions {
    pub constants: GapConstants,
    /// Welch segment duration [s]: the spectra's frequency resolution is its inverse, whatever
    /// the log rate (each segment is zero-padded to the next power of two of its samples).
    pub segment_s: f64,
    /// Welch overlap fraction.
    pub overlap: f64,
    /// Duration of the error decomposition's segments [s] (`locate::decompose_segments`).
    pub decompose_segment_s: f64,
    /// Uniform rate for spectra and decomposition; default: mean sample rate of the dataset.
    pub uniform_rate_hz: Option<f64>,
    /// Lag search range of the decomposition [s].
    pub max_lag_s: f64,
}

impl Default for GapOptions {
    fn default() -> Self {
        GapOptions {
            constants: GapConstants::default(),
            segment_s: SPECTRUM_SEGMENT_S,
            overlap: 0.5,
            decompose_segment_s: DECOMPOSE_SEGMENT_S,
            uniform_rate_hz: None,
            max_lag_s: 0.25,
        }
    }
}
