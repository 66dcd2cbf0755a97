//! The replay's start state, estimated instead of read.
//!
//! A replay starts every episode from its first row: the first position carries the noise and
//! quantisation of any reading, the first velocity the velocity noise (or, without a velocity
//! column, the difference of two noisy positions). A lightly damped servo rings from that start
//! error for seconds, and every fit of the episode sees the ringing as model error.
//!
//! Here each episode's start (q₀, q̇₀ of every recorded joint) is a nuisance parameter with the
//! first row as its prior: the maximum a posteriori correction δ of the start, given the rest of
//! the episode, under the linear response of the replay to its start state. The response
//! (`J`, one column per start coordinate) is measured once per recording by finite differences
//! of the nominal model's replay; every later simulation of that recording is corrected by
//! `J·δ` with δ = (JᵀWJ + P)⁻¹ JᵀW r (W: 1/σ² of each joint's position reading; P: 1/σ² of the
//! first row's position and velocity readings; r: the position residual after the first row),
//! each component clamped to 3σ of its prior. An effect cannot hide in it: δ is at most a few
//! reading errors, and `J` is a transient from the first row.

use nalgebra::DMatrix;

use crate::fit::effects::replay_with;
use crate::fit::stats::white_floor;
use crate::model::Robot;
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::{Recording, derivative};
use crate::sim2real::replay::{Episode, ReplayOptions};

/// The smallest prior σ of a start position [rad] (exact readings have no white floor).
const MIN_SIGMA_Q: f64 = 1e-5;
/// The smallest prior σ of a start velocity [rad/s].
const MIN_SIGMA_QD: f64 = 1e-4;
/// The largest correction, in prior σ.
const CLAMP: f64 = 3.0;

/// A recording's identity for the sensitivity memo: its file, first time, length and joints (a
/// copy with its first row moved, or its commands filled, shares its sensitivity).
pub(super) fn key(rec: &Recording) -> String {
    let names: Vec<&str> = rec.joints.iter().map(|j| j.name.as_str()).collect();
    format!(
        "{}|{:x}|{}|{}",
        rec.source.display(),
        rec.t.first().map_or(0, |t| t.to_bits()),
        rec.t.len(),
        names.join(",")
    )
}

/// How one recording's replay answers a change of its start state.
#[derive(Debug)]
pub(super) struct StartSens {
    n: usize,
    /// Columns: (q₀, q̇₀) of each recorded joint in turn.
    m: usize,
    /// ∂q_sim and ∂q̇_sim of recorded joint k at sample i by column c, at `(k·n + i)·m + c`.
    jq: Vec<f64>,
    jqd: Vec<f64>,
    /// Weight of each (k, i) in the data term: 1/σ² of joint k's reading, 0 where the sample is
    /// not scored (the first row, after a gap, not finite).
    w: Vec<f64>,
    /// (JᵀWJ + P)⁻¹.
    ainv: DMatrix<f64>,
    /// Prior σ of each column.
    sigma: Vec<f64>,
}

impl StartSens {
    /// Measures the response of `rec`'s replay on the nominal model to each start coordinate.
    /// `None` when a replay fails or diverges, or the recording is too short.
    pub(super) fn measure(
        robot: &Robot,
        rec: &Recording,
        replay: &ReplayOptions,
        gap_mask_s: f64,
    ) -> Option<StartSens> {
        let (n, nj) = (rec.t.len(), rec.joints.len());
        if n < 3 || nj == 0 {
            return None;
        }
        let m = 2 * nj;
        // The same replay with its commands and first velocity written out, so that moving
        // the first row moves nothing else.
        let mut base = rec.clone();
        for jt in &mut base.joints {
            if jt.q_cmd.is_none() {
                jt.q_cmd = Some(jt.q.clone());
            }
            if jt.qd.is_none() {
                let d0 = derivative(&rec.t[..3], &jt.q[..3])[0];
                jt.qd = Some(vec![d0; n]);
            }
        }
        let run = |r: &Recording| -> Option<Episode> {
            replay_with(robot, &robot.mj, r, &[], replay).ok().filter(|e| e.diverged.is_none())
        };
        let ep0 = run(&base)?;
        let scored = gap_mask(&rec.t, gap_mask_s);
        let runs = |real: &[f64], sim: &[f64]| -> Vec<Vec<f64>> {
            let mut out = vec![vec![]];
            for ((s, a), b) in scored.iter().zip(real).zip(sim) {
                let e = a - b;
                if *s && e.is_finite() {
                    out.last_mut().expect("one").push(e);
                } else if !out.last().expect("one").is_empty() {
                    out.push(vec![]);
                }
            }
            out
        };
        let mut sigma = Vec::with_capacity(m);
        for (k, jt) in rec.joints.iter().enumerate() {
            let sq = white_floor(&runs(&jt.q, &ep0.q_sim[k])).1.sqrt().max(MIN_SIGMA_Q);
            let sqd = match &jt.qd {
                Some(qd) => white_floor(&runs(qd, &ep0.qd_sim[k])).1.sqrt().max(MIN_SIGMA_QD),
                // The replay's first velocity is (q₁ − q₀) / (t₁ − t₀).
                None => (std::f64::consts::SQRT_2 * sq / (rec.t[1] - rec.t[0])).max(MIN_SIGMA_QD),
            };
            if !(sq.is_finite() && sqd.is_finite()) {
                return None;
            }
            sigma.push(sq);
            sigma.push(sqd);
        }
        let mut jq = vec![0.0; nj * n * m];
        let mut jqd = vec![0.0; nj * n * m];
        for (c, &h) in sigma.iter().enumerate() {
            let k = c / 2;
            let mut r = base.clone();
            let jt = &mut r.joints[k];
            if c % 2 == 0 {
                jt.q[0] += h;
            } else {
                jt.qd.as_mut().expect("written out")[0] += h;
            }
            let ep = run(&r)?;
            for kk in 0..nj {
                for i in 0..n {
                    let at = (kk * n + i) * m + c;
                    jq[at] = (ep.q_sim[kk][i] - ep0.q_sim[kk][i]) / h;
                    jqd[at] = (ep.qd_sim[kk][i] - ep0.qd_sim[kk][i]) / h;
                }
            }
        }
        let mut w = vec![0.0; nj * n];
        for (k, jt) in rec.joints.iter().enumerate() {
            let wk = 1.0 / (sigma[2 * k] * sigma[2 * k]);
            for i in 1..n {
                let row = &jq[(k * n + i) * m..(k * n + i + 1) * m];
                if scored[i] && jt.q[i].is_finite() && row.iter().all(|x| x.is_finite()) {
                    w[k * n + i] = wk;
                }
            }
        }
        let mut a = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
            m,
            sigma.iter().map(|s| 1.0 / (s * s)),
        ));
        for (ki, &wi) in w.iter().enumerate() {
            if wi == 0.0 {
                continue;
            }
            let row = &jq[ki * m..(ki + 1) * m];
            for c in 0..m {
                for d in 0..m {
                    a[(c, d)] += wi * row[c] * row[d];
                }
            }
        }
        let ainv = a.cholesky()?.inverse();
        Some(StartSens { n, m, jq, jqd, w, ainv, sigma })
    }

    /// The start correction of `rec` simulated as `ep` (see the module docs); `None` when the
    /// residual is not finite where it is scored, or the shapes do not match.
    pub(super) fn correction(&self, rec: &Recording, ep: &Episode) -> Option<Vec<f64>> {
        let (n, m) = (self.n, self.m);
        if rec.t.len() != n || ep.q_sim.len() * 2 != m || rec.joints.len() * 2 != m {
            return None;
        }
        let mut b = nalgebra::DVector::zeros(m);
        for (k, jt) in rec.joints.iter().enumerate() {
            for i in 0..n {
                let wi = self.w[k * n + i];
                if wi == 0.0 {
                    continue;
                }
                let r = jt.q[i] - ep.q_sim[k][i];
                if !r.is_finite() {
                    return None;
                }
                let row = &self.jq[(k * n + i) * m..(k * n + i + 1) * m];
                for c in 0..m {
                    b[c] += wi * row[c] * r;
                }
            }
        }
        let d = &self.ainv * b;
        Some(d.iter().zip(&self.sigma).map(|(x, s)| x.clamp(-CLAMP * s, CLAMP * s)).collect())
    }

    /// Moves `ep` (a simulation of `rec`) by its start correction. Returns the correction.
    pub(super) fn apply(&self, rec: &Recording, ep: &mut Episode) -> Option<Vec<f64>> {
        let d = self.correction(rec, ep)?;
        let (n, m) = (self.n, self.m);
        for (k, (qs, qds)) in ep.q_sim.iter_mut().zip(ep.qd_sim.iter_mut()).enumerate() {
            for i in 0..n {
                let at = (k * n + i) * m;
                let dq: f64 = self.jq[at..at + m].iter().zip(&d).map(|(j, x)| j * x).sum();
                let dqd: f64 = self.jqd[at..at + m].iter().zip(&d).map(|(j, x)| j * x).sum();
                if dq.is_finite() {
                    qs[i] += dq;
                }
                if dqd.is_finite() {
                    qds[i] += dqd;
                }
            }
        }
        Some(d)
    }
}
