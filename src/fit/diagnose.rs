//! Diagnosis: which missing physics do the replay residuals (real − sim) look like?
//!
//! Per joint, the residual `r = q_real − q_sim` is compared with one signature feature per
//! effect ([`crate::fit::effects::Effect::signature`], in each effect's file; the table is in
//! docs/fitting.md, generated from the effects' doc comments), computed from the *simulated*
//! trajectory (clean) and the command ([`Samples`]). For a stiff servo, r ≈ −Δτ / kp.
//!
//! `c` is the least-squares coefficient of r on f (both centred, except for raw features). The
//! score is the residual mean square that feature explains (`c²·Σf²/n`), reported as an RMS in
//! radians; candidates are ranked by it.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::fit::effects::{self, JointTarget};
use crate::model::{ActuatorKind, Robot};
use crate::sim2real::metrics::{gap_mask, pearson, zoh_at};
use crate::sim2real::recording::{Recording, derivative};
use crate::sim2real::replay::Episode;

#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    pub effect: &'static str,
    pub joint: String,
    /// RMS of the residual this effect's signature explains [rad].
    pub explained_rms: f64,
    /// RMS of the joint's residual [rad].
    pub residual_rms: f64,
    pub evidence: BTreeMap<String, f64>,
}

/// One joint's scored samples over the episodes (non-finite and post-gap samples left out), from
/// which every effect computes its signature feature.
pub struct Samples<'a> {
    /// The recordings and their replays with the current model.
    pub recs: &'a [Recording],
    pub eps: &'a [Episode],
    /// The joint's name.
    pub joint: &'a str,
    /// Residual q_real − q_sim [rad].
    pub r: Vec<f64>,
    /// Simulated velocity [rad/s] and acceleration [rad/s²].
    pub qd: Vec<f64>,
    pub qdd: Vec<f64>,
    /// Servo error: command in force − q_sim [rad].
    pub u: Vec<f64>,
    /// Servo torque kp·u − kd·q̇ (the recording's kp/kd columns when present) [N·m].
    pub tau: Vec<f64>,
    /// q_sim − keyframe position [rad].
    pub qrel: Vec<f64>,
    /// (episode index, sample index) of each kept sample.
    pub at: Vec<(usize, usize)>,
    /// RMS of `qd` (at least 1e-6) and of `u` (at least 1e-9).
    pub qd_rms: f64,
    pub u_rms: f64,
}

/// An effect's signature on one joint: the feature the residual is regressed on.
pub struct Signature {
    /// One value per sample of [`Samples`].
    pub feature: Vec<f64>,
    /// Regress without centring (the feature's mean carries the signal: a bias, a lag).
    pub raw: bool,
    /// Evidence of its own: (key, value).
    pub evidence: Vec<(&'static str, f64)>,
    /// Evidence key for the physical value a stiff servo implies, −c·kp (only with a kp).
    pub implied: Option<&'static str>,
}

impl Signature {
    /// A centred feature with no evidence of its own.
    pub fn centred(feature: Vec<f64>) -> Signature {
        Signature { feature, raw: false, evidence: vec![], implied: None }
    }
}

pub(crate) fn mean(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { x.iter().sum::<f64>() / x.len() as f64 }
}

fn rms(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt() }
}

/// Least squares of `r` on `f` (centred unless `raw`): (coefficient, explained mean square, corr).
pub(crate) fn explain(r: &[f64], f: &[f64], raw: bool) -> (f64, f64, f64) {
    let n = r.len().min(f.len());
    if n < 3 {
        return (0.0, 0.0, 0.0);
    }
    let (mr, mf) = if raw { (0.0, 0.0) } else { (mean(&r[..n]), mean(&f[..n])) };
    let (mut sff, mut srf) = (0.0, 0.0);
    for i in 0..n {
        sff += (f[i] - mf).powi(2);
        srf += (f[i] - mf) * (r[i] - mr);
    }
    if sff <= 1e-300 {
        return (0.0, 0.0, 0.0);
    }
    let c = srf / sff;
    let corr = if raw {
        let srr: f64 = r[..n].iter().map(|v| v * v).sum();
        if srr > 0.0 { srf / (sff * srr).sqrt() } else { 0.0 }
    } else {
        pearson(&r[..n], &f[..n]).unwrap_or(0.0)
    };
    (c, c * c * sff / n as f64, corr)
}

pub(crate) fn percentile(x: &[f64], p: f64) -> f64 {
    let mut v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// Ranked candidates for every (effect, joint) over the given episodes. `joints`: the joints to
/// diagnose (all recorded joints when empty). `allowed`: effect ids to consider (all when empty).
/// Within a joint, candidates come in registry order ([`effects::all`]) before the (stable) sort.
/// Samples up to `gap_mask_s` after a gap in a recording are left out ([`gap_mask`]).
pub fn diagnose(
    robot: &Robot,
    recs: &[Recording],
    eps: &[Episode],
    joints: &[String],
    allowed: &[String],
    gap_mask_s: f64,
) -> Vec<Candidate> {
    let mut names: Vec<String> = Vec::new();
    for r in recs {
        for j in &r.joints {
            if (joints.is_empty() || joints.contains(&j.name)) && !names.contains(&j.name) {
                names.push(j.name.clone());
            }
        }
    }
    let ok = |id: &str| allowed.is_empty() || allowed.iter().any(|a| a == id);
    let mut out = Vec::new();
    for name in &names {
        let Some(joint) = robot.joint(name) else { continue };
        let key_q = robot.key.qpos.get(joint.qposadr).copied().unwrap_or(0.0);
        let (kp, kv) = robot
            .actuators_on_joint(joint.id)
            .iter()
            .find_map(|a| match a.kind {
                ActuatorKind::Position { kp, kv } => Some((kp, kv)),
                _ => None,
            })
            .unwrap_or((0.0, 0.0));
        let mut s = Samples {
            recs,
            eps,
            joint: name,
            r: vec![],
            qd: vec![],
            qdd: vec![],
            u: vec![],
            tau: vec![],
            qrel: vec![],
            at: vec![],
            qd_rms: 0.0,
            u_rms: 0.0,
        };
        for (e, (rec, ep)) in recs.iter().zip(eps).enumerate() {
            let Some(k) = rec.joints.iter().position(|j| j.name == *name) else { continue };
            let jt = &rec.joints[k];
            let cmd = jt.q_cmd.as_deref().unwrap_or(&jt.q);
            let qdd = derivative(&ep.t, &ep.qd_sim[k]);
            let scored = gap_mask(&rec.t, gap_mask_s);
            for i in (0..rec.t.len()).filter(|&i| scored[i]) {
                let (qr, qs, qd) = (jt.q[i], ep.q_sim[k][i], ep.qd_sim[k][i]);
                if !(qr.is_finite() && qs.is_finite() && qd.is_finite() && qdd[i].is_finite()) {
                    continue;
                }
                let u = zoh_at(&rec.t, cmd, rec.t[i]) - qs;
                let kp_i = jt.kp.as_ref().map_or(kp, |v| v[i]);
                let kd_i = jt.kd.as_ref().map_or(kv, |v| v[i]);
                s.r.push(qr - qs);
                s.qd.push(qd);
                s.qdd.push(qdd[i]);
                s.u.push(u);
                s.tau.push(kp_i * u - kd_i * qd);
                s.qrel.push(qs - key_q);
                s.at.push((e, i));
            }
        }
        if s.r.len() < 10 {
            continue;
        }
        let res_rms = rms(&s.r);
        s.qd_rms = rms(&s.qd).max(1e-6);
        s.u_rms = rms(&s.u).max(1e-9);
        let target = JointTarget::of(robot, name);
        for effect in effects::all() {
            if !ok(effect.id()) || target.as_ref().is_some_and(|t| !effect.acts_on(t)) {
                continue;
            }
            let sig = effect.signature(&s);
            let (c, ems, corr) = explain(&s.r, &sig.feature, sig.raw);
            let mut ev = BTreeMap::new();
            ev.insert("coef".to_string(), c);
            ev.insert("corr".to_string(), corr);
            ev.insert(
                "explained_share".to_string(),
                if res_rms > 0.0 { ems / (res_rms * res_rms) } else { 0.0 },
            );
            for (k, v) in sig.evidence {
                ev.insert(k.to_string(), v);
            }
            if let Some(k) = sig.implied
                && kp > 0.0
            {
                // r ≈ −Δτ/kp for a stiff servo: the implied value is −c·kp.
                ev.insert(k.to_string(), -c * kp);
            }
            out.push(Candidate {
                effect: effect.id(),
                joint: name.clone(),
                explained_rms: ems.sqrt(),
                residual_rms: res_rms,
                evidence: ev,
            });
        }
    }
    out.sort_by(|a, b| b.explained_rms.total_cmp(&a.explained_rms));
    out
}
