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
//! of the replay on the start model — the nominal model with the kept effects that let a joint
//! stick (dry friction, a dead band: a sticking joint keeps its start error until it breaks
//! away, where the smooth model's dies out), measured again when those change — and every
//! simulation of that recording is corrected by
//! `J·δ` with δ = (JᵀWJ + P)⁻¹ JᵀW r (W: 1/σ² of each scored joint's position reading; P: the
//! inverse covariance of the first row's readings; r: the position residual after the rows the
//! prior already holds), scaled down as a whole until no component exceeds 3σ of its prior. An
//! effect cannot hide in it: δ is at most a few reading errors, and `J` is the transient of a
//! start error (stored only until it has died out). A joint whose sticking effects differ from
//! the start model's (a friction candidate before it is kept) is left out: neither corrected nor
//! in the data term.

use nalgebra::{DMatrix, DVector};

use crate::fit::effects::{Applied, model_with};
use crate::fit::rollout::Rollouts;
use crate::fit::stats::{residual_runs, white_floor};
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::{Recording, derivative};
use crate::sim2real::replay::{Episode, ReplayOptions};

/// The smallest prior σ of a start position [rad] (exact readings have no white floor).
const MIN_SIGMA_Q: f64 = 1e-5;
/// The smallest prior σ of a start velocity [rad/s].
const MIN_SIGMA_QD: f64 = 1e-4;
/// The largest correction, in prior σ.
const CLAMP: f64 = 3.0;
/// A column's response is kept up to its last sample that moves a joint by at least this much
/// for a one-σ start error [rad]: after it, the start error has died out.
const NEGLIGIBLE: f64 = 1e-8;

/// A recording's identity for the sensitivity memo: its file, time base, length, joints, and
/// a hash of what the replay reads after the first row (positions, commands, gains). A copy
/// with its first row moved, or its missing commands written out from the positions, shares
/// its sensitivity.
pub(super) fn key(rec: &Recording) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: f64| {
        h ^= x.to_bits();
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    };
    for &t in &rec.t {
        eat(t);
    }
    for jt in &rec.joints {
        for v in [Some(&jt.q), jt.q_cmd.as_ref().or(Some(&jt.q)), jt.kp.as_ref(), jt.kd.as_ref()]
            .into_iter()
            .flatten()
        {
            v.iter().skip(1).for_each(|&x| eat(x));
        }
        if let Some(e) = &jt.enabled {
            e.iter().for_each(|&x| eat(f64::from(u8::from(x))));
        }
    }
    eat(rec.control_rate_hz.unwrap_or(f64::NAN));
    eat(rec.control_t0_s.unwrap_or(f64::NAN));
    let names: Vec<&str> = rec.joints.iter().map(|j| j.name.as_str()).collect();
    format!("{}|{}|{}|{h:x}", rec.source.display(), rec.t.len(), names.join(","))
}

/// One start coordinate's response: ∂q_sim and ∂q̇_sim of recorded joint k at sample i, at
/// `k·len + i`, for the first `len` samples (zero after).
#[derive(Debug)]
struct Column {
    len: usize,
    q: Vec<f64>,
    qd: Vec<f64>,
}

/// How one recording's replay answers a change of its start state.
#[derive(Debug)]
pub(super) struct StartSens {
    n: usize,
    /// (q₀, q̇₀) of each recorded joint in turn.
    cols: Vec<Column>,
    /// Weight of each (k, i) in the data term, at `k·n + i`: 1/σ² of joint k's reading, 0
    /// where the sample is not scored (the rows the prior holds, after a gap, not finite, a
    /// joint not fitted).
    w: Vec<f64>,
    /// P, the prior precision of the start coordinates.
    prior: DMatrix<f64>,
    /// JᵀWJ of the rows of each recorded joint in turn: the data term is their sum.
    gram: Vec<DMatrix<f64>>,
    /// (JᵀWJ + P)⁻¹ with every joint taking part.
    ainv: DMatrix<f64>,
    /// Prior σ of each column.
    sigma: Vec<f64>,
}

impl StartSens {
    /// Measures the response of `rec`'s replay with `applied` to each start coordinate;
    /// the data term weighs the joints of `scored` only. `None` when a replay fails or
    /// diverges, or the recording is too short.
    pub(super) fn measure(
        rollouts: &Rollouts<'_>,
        rec: &Recording,
        replay: &ReplayOptions,
        gap_mask_s: f64,
        scored_joints: &[String],
        applied: &[Applied],
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
        let mj = model_with(rollouts.robot(), applied);
        let run = |r: &Recording| -> Option<Episode> { rollouts.run_on(&mj, r, applied, replay) };
        let ep0 = run(&base)?;
        let scored = gap_mask(&rec.t, gap_mask_s);
        let runs = |real: &[f64], sim: &[f64]| residual_runs(&scored, real, sim);
        let h1 = rec.t[1] - rec.t[0];
        let mut sigma = Vec::with_capacity(m);
        // Prior precision: per joint a 2 × 2 block. Without a velocity column the first
        // velocity is (q₁ − q₀)/h of two readings of σ each: its error is correlated with the
        // first position's, and q₁ is in the prior, not in the data term.
        let mut p = DMatrix::zeros(m, m);
        for (k, jt) in rec.joints.iter().enumerate() {
            let sq = white_floor(&runs(&jt.q, &ep0.q_sim[k])).1.sqrt().max(MIN_SIGMA_Q);
            if !sq.is_finite() || !(h1 > 0.0) {
                return None;
            }
            let (a, b) = (2 * k, 2 * k + 1);
            match &jt.qd {
                Some(qd) => {
                    let sqd = white_floor(&runs(qd, &ep0.qd_sim[k])).1.sqrt().max(MIN_SIGMA_QD);
                    if !sqd.is_finite() {
                        return None;
                    }
                    sigma.extend([sq, sqd]);
                    p[(a, a)] = 1.0 / (sq * sq);
                    p[(b, b)] = 1.0 / (sqd * sqd);
                }
                None => {
                    // Covariance [[σ², −σ²/h], [−σ²/h, 2σ²/h²]], inverse [[2, h], [h, h²]]/σ².
                    sigma.extend([sq, std::f64::consts::SQRT_2 * sq / h1]);
                    let s2 = sq * sq;
                    p[(a, a)] = 2.0 / s2;
                    p[(a, b)] = h1 / s2;
                    p[(b, a)] = h1 / s2;
                    p[(b, b)] = h1 * h1 / s2;
                }
            }
        }
        let mut cols = Vec::with_capacity(m);
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
            let dq = |kk: usize, i: usize| (ep.q_sim[kk][i] - ep0.q_sim[kk][i]) / h;
            let dqd = |kk: usize, i: usize| (ep.qd_sim[kk][i] - ep0.qd_sim[kk][i]) / h;
            let len = (0..n)
                .rev()
                .find(|&i| (0..nj).any(|kk| !(dq(kk, i).abs() * h < NEGLIGIBLE)))
                .map_or(1, |i| i + 1);
            let mut q = Vec::with_capacity(nj * len);
            let mut qd = Vec::with_capacity(nj * len);
            for kk in 0..nj {
                q.extend((0..len).map(|i| dq(kk, i)));
                qd.extend((0..len).map(|i| dqd(kk, i)));
            }
            cols.push(Column { len, q, qd });
        }
        let mut w = vec![0.0; nj * n];
        for (k, jt) in rec.joints.iter().enumerate() {
            if !scored_joints.contains(&jt.name) {
                continue;
            }
            let wk = 1.0 / (sigma[2 * k] * sigma[2 * k]);
            let first = if jt.qd.is_some() { 1 } else { 2 };
            for i in first..n {
                let finite = cols.iter().all(|c| i >= c.len || c.q[k * c.len + i].is_finite());
                if scored[i] && jt.q[i].is_finite() && finite {
                    w[k * n + i] = wk;
                }
            }
        }
        let mut gram = vec![DMatrix::zeros(m, m); nj];
        for (k, g) in gram.iter_mut().enumerate() {
            for c in 0..m {
                for d in c..m {
                    let (cc, cd) = (&cols[c], &cols[d]);
                    let mut s = 0.0;
                    for i in 0..cc.len.min(cd.len) {
                        let wi = w[k * n + i];
                        if wi != 0.0 {
                            s += wi * cc.q[k * cc.len + i] * cd.q[k * cd.len + i];
                        }
                    }
                    g[(c, d)] = s;
                    g[(d, c)] = s;
                }
            }
        }
        let ainv = gram.iter().fold(p.clone(), |a, g| a + g).cholesky()?.inverse();
        Some(StartSens { n, cols, w, prior: p, gram, ainv, sigma })
    }

    /// (JᵀWJ + P)⁻¹ over the start coordinates of the joints in `kept` (index into them: the
    /// i-th kept coordinate), with only their rows in the data term.
    fn inverse(&self, kept: &[bool]) -> Option<DMatrix<f64>> {
        if kept.iter().all(|&k| k) {
            return Some(self.ainv.clone());
        }
        let idx: Vec<usize> = (0..self.cols.len()).filter(|&c| kept[c / 2]).collect();
        let mut a = self.prior.select_rows(&idx).select_columns(&idx);
        for (g, _) in self.gram.iter().zip(kept).filter(|(_, k)| **k) {
            a += g.select_rows(&idx).select_columns(&idx);
        }
        Some(a.cholesky()?.inverse())
    }

    /// The start correction of `rec` simulated as `ep` (see the module docs), one value per
    /// start coordinate (zero for the joints not in `kept`, whose rows are not in the data
    /// term either); `None` when the residual is not finite where it is scored, or the shapes
    /// do not match.
    fn correction(&self, rec: &Recording, ep: &Episode, kept: &[bool]) -> Option<Vec<f64>> {
        let n = self.n;
        let nj = rec.joints.len();
        if rec.t.len() != n || ep.q_sim.len() != nj || self.cols.len() != 2 * nj || kept.len() != nj
        {
            return None;
        }
        if !kept.iter().any(|&k| k) {
            return Some(vec![0.0; 2 * nj]);
        }
        let idx: Vec<usize> = (0..self.cols.len()).filter(|&c| kept[c / 2]).collect();
        let mut b = DVector::zeros(idx.len());
        for (bc, col) in b.iter_mut().zip(idx.iter().map(|&c| &self.cols[c])) {
            for (k, jt) in rec.joints.iter().enumerate().filter(|(k, _)| kept[*k]) {
                for i in 0..col.len {
                    let wi = self.w[k * n + i];
                    if wi == 0.0 {
                        continue;
                    }
                    let r = jt.q[i] - ep.q_sim[k][i];
                    if !r.is_finite() {
                        return None;
                    }
                    *bc += wi * col.q[k * col.len + i] * r;
                }
            }
        }
        let d = self.inverse(kept)? * b;
        // Scaled as a whole (not clamped per component: the others were chosen to go with it).
        let over = d
            .iter()
            .zip(idx.iter().map(|&c| self.sigma[c]))
            .map(|(x, s)| x.abs() / (CLAMP * s))
            .fold(1.0, f64::max);
        let mut out = vec![0.0; 2 * nj];
        for (&c, x) in idx.iter().zip(d.iter()) {
            out[c] = x / over;
        }
        Some(out)
    }

    /// Moves `ep` (a simulation of `rec`) by its start correction (unchanged when there is
    /// none, see [`StartSens::correction`]). Only the joints in `kept` (one flag per recorded
    /// joint) take part: their start is estimated from their own rows, and only their
    /// simulation is moved. A joint that can stay where it starts (dry friction, a dead band;
    /// [`Effect::holds_start`]) keeps its start error for as long as it sticks; a response
    /// measured without that effect has died out long before: the wrong shape.
    ///
    /// [`Effect::holds_start`]: crate::fit::effects::Effect::holds_start
    pub(super) fn apply(&self, rec: &Recording, ep: &mut Episode, kept: &[bool]) {
        let Some(d) = self.correction(rec, ep, kept) else { return };
        for (col, &x) in self.cols.iter().zip(&d) {
            if x == 0.0 {
                continue;
            }
            for (k, (qs, qds)) in ep.q_sim.iter_mut().zip(ep.qd_sim.iter_mut()).enumerate() {
                if !kept[k] {
                    continue;
                }
                for i in 0..col.len {
                    let (dq, dqd) = (col.q[k * col.len + i] * x, col.qd[k * col.len + i] * x);
                    if dq.is_finite() {
                        qs[i] += dq;
                    }
                    if dqd.is_finite() {
                        qds[i] += dqd;
                    }
                }
            }
        }
    }
}
