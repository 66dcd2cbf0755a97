//! Diagnosis: which missing physics do the replay residuals (real − sim) look like?
//!
//! Per joint, the residual `r = q_real − q_sim` is compared with one signature feature per
//! effect, computed from the *simulated* trajectory (clean) and the command:
//!
//! | effect | feature f | physical reading (stiff servo: r ≈ −Δτ / kp) |
//! |---|---|---|
//! | action_delay | q_sim(t − L) − q_sim(t), L = lag of the cross-correlation peak | lag L |
//! | coulomb_friction | tanh(q̇/ε) | F ≈ −c·kp |
//! | stribeck_friction | sign(q̇)·exp(−(q̇/v_s)²) (sticking at reversals) | |
//! | load_dependent_friction | sign(q̇)·|τ| | |
//! | viscous_damping | q̇ | b ≈ −c·kp |
//! | armature | q̈ | ΔI ≈ −c·kp |
//! | position_offset | 1 (constant bias) | offset ≈ c |
//! | gain_error | servo error ctrl − q (and the amplitude ratio) | |
//! | torque_limit | sign(τ)·max(|τ| − P80|τ|, 0) (error growing beyond a torque level) | |
//! | backlash | sign of the servo error | |
//! | joint_stiffness | q − q_key (error ∝ deflection/load) | k ≈ −c·kp |
//!
//! `c` is the least-squares coefficient of r on f (both centred, except the constant). The
//! score is the residual mean square that feature explains (`c²·Σf²/n`), reported as an RMS in
//! radians; candidates are ranked by it.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::model::{ActuatorKind, Robot};
use crate::sim2real::metrics::{gap_mask, interp_at, pearson, zoh_at};
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

struct Samples {
    r: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    u: Vec<f64>,
    tau: Vec<f64>,
    qrel: Vec<f64>,
    /// (episode index, sample index) of each kept sample.
    at: Vec<(usize, usize)>,
}

fn mean(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { x.iter().sum::<f64>() / x.len() as f64 }
}

fn rms(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt() }
}

/// Least squares of `r` on `f` (centred unless `raw`): (coefficient, explained mean square, corr).
fn explain(r: &[f64], f: &[f64], raw: bool) -> (f64, f64, f64) {
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

fn percentile(x: &[f64], p: f64) -> f64 {
    let mut v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// Effects with a signature feature of their own in [`diagnose`].
const SIGNED: [&str; 11] = [
    "action_delay",
    "coulomb_friction",
    "viscous_damping",
    "armature",
    "position_offset",
    "gain_error",
    "stribeck_friction",
    "load_dependent_friction",
    "torque_limit",
    "backlash",
    "joint_stiffness",
];

/// Ranked candidates for every (effect, joint) over the given episodes. `joints`: the joints to
/// diagnose (all recorded joints when empty). `allowed`: effect ids to consider (all when empty).
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
            r: vec![],
            qd: vec![],
            qdd: vec![],
            u: vec![],
            tau: vec![],
            qrel: vec![],
            at: vec![],
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
        let qd_rms = rms(&s.qd).max(1e-6);
        let u_rms = rms(&s.u).max(1e-9);
        let p80 = percentile(&s.tau.iter().map(|x| x.abs()).collect::<Vec<_>>(), 0.8);
        let mut push = |effect: &'static str,
                        f: &[f64],
                        raw: bool,
                        extra: Vec<(&str, f64)>,
                        implied: Option<(&str, f64)>| {
            if !ok(effect) {
                return;
            }
            let (c, ems, corr) = explain(&s.r, f, raw);
            let mut ev = BTreeMap::new();
            ev.insert("coef".to_string(), c);
            ev.insert("corr".to_string(), corr);
            ev.insert(
                "explained_share".to_string(),
                if res_rms > 0.0 { ems / (res_rms * res_rms) } else { 0.0 },
            );
            for (k, v) in extra {
                ev.insert(k.to_string(), v);
            }
            if let Some((k, scale)) = implied
                && kp > 0.0
            {
                ev.insert(k.to_string(), scale * c * kp);
            }
            out.push(Candidate {
                effect,
                joint: name.clone(),
                explained_rms: ems.sqrt(),
                residual_rms: res_rms,
                evidence: ev,
            });
        };
        // Delay: lag L ∈ [0, 100 ms] maximising the fit of r by q_sim(t − L) − q_sim(t).
        if ok("action_delay") {
            let mut best = (0.0, f64::INFINITY, Vec::new());
            for l in 0..=100 {
                let lag = l as f64 * 1e-3;
                let f: Vec<f64> =
                    s.at.iter()
                        .map(|&(e, i)| {
                            let k = recs[e].joints.iter().position(|j| j.name == *name).unwrap();
                            let ep = &eps[e];
                            interp_at(&ep.t, &ep.q_sim[k], ep.t[i] - lag) - ep.q_sim[k][i]
                        })
                        .collect();
                let sse: f64 = s.r.iter().zip(&f).map(|(r, f)| (r - f).powi(2)).sum();
                if sse < best.1 {
                    best = (lag, sse, f);
                }
            }
            let (lag, _, f) = best;
            push("action_delay", &f, true, vec![("lag_s", lag)], None);
        }
        let sg: Vec<f64> = s.qd.iter().map(|v| (v / (0.02 * qd_rms)).tanh()).collect();
        push("coulomb_friction", &sg, false, vec![], Some(("implied_frictionloss", -1.0)));
        push("viscous_damping", &s.qd, false, vec![], Some(("implied_damping", -1.0)));
        push("armature", &s.qdd, false, vec![], Some(("implied_armature", -1.0)));
        push("position_offset", &vec![1.0; s.r.len()], true, vec![("bias_rad", mean(&s.r))], None);
        push("gain_error", &s.u, false, vec![], None);
        let vs = 0.2 * qd_rms;
        let st: Vec<f64> = s.qd.iter().map(|v| v.signum() * (-(v / vs).powi(2)).exp()).collect();
        push("stribeck_friction", &st, false, vec![], None);
        let ld: Vec<f64> =
            s.qd.iter().zip(&s.tau).map(|(v, t)| (v / (0.02 * qd_rms)).tanh() * t.abs()).collect();
        push("load_dependent_friction", &ld, false, vec![], None);
        let sat: Vec<f64> = s.tau.iter().map(|t| t.signum() * (t.abs() - p80).max(0.0)).collect();
        push("torque_limit", &sat, false, vec![("tau_p80", p80)], None);
        let bl: Vec<f64> = s.u.iter().map(|u| (u / (0.1 * u_rms)).tanh()).collect();
        push("backlash", &bl, false, vec![], None);
        push("joint_stiffness", &s.qrel, false, vec![], Some(("implied_stiffness", -1.0)));
        // Effects without a signature above (external-load friction, torque-off braking, motor
        // constants): the friction-like feature as a placeholder, so that they are candidates;
        // the greedy round ranks every candidate by its simulated sensitivity anyway.
        for e in crate::fit::effects::all() {
            if !SIGNED.contains(&e.id()) {
                push(e.id(), &sg, false, vec![], None);
            }
        }
    }
    out.sort_by(|a, b| b.explained_rms.total_cmp(&a.explained_rms));
    out
}
