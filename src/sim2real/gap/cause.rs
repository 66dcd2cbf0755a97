//! One line per joint on what its error looks like: an offset, a lag, a gain, a residual — or
//! a joint that moves against its replay.

use super::JointGap;
use crate::sim2real::locate::Explained;

/// A recorded joint whose correlation with its replay is at most this moves *against* it (a
/// correlation of −1 is the replay mirrored): a reversed encoder, a joint axis of the other
/// sign in the model, or a column of another joint. No physics the fit knows makes a servo
/// follow its command the other way; the offset, lag or gain that explains most of the error is
/// then beside the point.
pub const MIRRORED_CORRELATION: f64 = -0.5;

/// The summary of `j`'s error decomposition.
pub(super) fn summary(j: &JointGap) -> String {
    let d = &j.decomposition;
    if let Some(c) = j.corr.filter(|&c| c <= MIRRORED_CORRELATION) {
        return format!(
            "moves against the replay (correlation {c:.2}): a reversed encoder or joint axis \
             (the recording's sign or the model's axis), or another joint's column"
        );
    }
    match d.dominant {
        Explained::Offset => format!("constant offset: real − sim = {:+.2}°", d.bias.to_degrees()),
        Explained::Lag => format!("time lag: real lags sim by {:.1} ms", d.lag_s * 1e3),
        Explained::Amplitude => format!("amplitude: real/sim = {:.3}", d.gain),
        Explained::Residual => format!(
            "unexplained residual ({:.2}° of {:.2}° RMS): not a simple offset, lag or gain",
            d.residual_rms.to_degrees(),
            d.total_rms.to_degrees()
        ),
        Explained::None => "no significant error".to_string(),
    }
}
