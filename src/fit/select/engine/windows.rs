//! A simulation's errors against its recordings: the scored samples' sum of squares and the
//! per-window RMSEs the held-out gate pairs ([`super::super::verdict`]).

use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::Episode;

use super::{Engine, Errors};

impl Engine<'_> {
    /// The errors of episodes `eps` simulated (or predicted) for `recs`: over the fitted
    /// joints' scored samples (outside the gap mask), their sum of squares and count and the
    /// RMSE of every `window_s` window of each joint. `None` when a sample the recording holds
    /// was not simulated (a diverged episode).
    pub(in crate::fit::select) fn errors_of(
        &self,
        recs: &[Recording],
        eps: Vec<Episode>,
    ) -> Option<Errors> {
        let mut sse = 0.0;
        let mut n = 0usize;
        let mut win = Vec::new();
        for (rec, ep) in recs.iter().zip(&eps) {
            let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
            for (k, jt) in rec.joints.iter().enumerate() {
                if !self.joints.contains(&jt.name) {
                    continue;
                }
                let t0 = rec.t[0];
                let mut w = (0usize, 0.0, 0usize);
                // One sample index into four parallel arrays (t, mask, real, sim).
                #[allow(clippy::needless_range_loop)]
                for i in 0..rec.t.len() {
                    if !scored[i] {
                        continue;
                    }
                    let e = jt.q[i] - ep.q_sim[k][i];
                    if !e.is_finite() {
                        if jt.q[i].is_finite() {
                            return None;
                        }
                        continue;
                    }
                    let wi = ((rec.t[i] - t0) / self.opts.window_s) as usize;
                    if wi != w.0 && w.2 > 0 {
                        win.push((jt.name.clone(), (w.1 / w.2 as f64).sqrt()));
                        w = (wi, 0.0, 0);
                    }
                    w.0 = wi;
                    w.1 += e * e;
                    w.2 += 1;
                    sse += e * e;
                    n += 1;
                }
                if w.2 > 0 {
                    win.push((jt.name.clone(), (w.1 / w.2 as f64).sqrt()));
                }
            }
        }
        Some(Errors { sse, n, windows: win, eps })
    }
}
