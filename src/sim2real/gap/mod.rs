//! The sim-to-real gap of a dataset: the seed study's metrics (§5, eqs 2–12) per joint, body
//! region, episode and dataset, plus error localisation. [`GapReport`] is the reusable result
//! (the fit command prints one before and one after fitting).
//!
//! * Position/velocity MAE, RMSE, max (eqs 2–4) are pooled over all samples (Σ|e|/N), per joint
//!   over its episodes, per region over its joints, for the dataset over everything.
//! * Correlation (eq 5) is computed per joint and episode; a joint's `corr` is the mean over its
//!   episodes, `correlation_mean` (ρ̄ of eq 8) the mean over joints.
//! * Gap scores (eqs 6–9) from the pooled position RMSE, velocity RMSE and ρ̄ with
//!   [`GapConstants`].
//! * Spectra (eqs 10–12): positions resampled to one uniform rate (the dataset's mean sample
//!   rate, rounded), Welch PSD with 4 s Hann windows ([`SPECTRUM_SEGMENT_S`]) and 50 % overlap
//!   per episode,
//!   averaged over episodes weighted by their samples; symmetric KL between the averaged real
//!   and simulated PSDs, band powers (0–2, 2–10, ≥10 Hz), dominant frequency.
//! * Localisation: joints and regions ranked by their share of the total squared position
//!   error, the frequency band with the largest band-power mismatch, motion phases
//!   (locate::phase_errors), and per joint the bias / lag / gain / residual decomposition
//!   (locate::decompose_segments, on the spectra's segments) naming the dominant component.
//!
//! Diverged episodes are excluded from every pooled number and listed in `diverged`.

pub mod cause;
pub mod motion;
mod options;
mod text;

pub use options::{DECOMPOSE_SEGMENT_S, GapOptions, SPECTRUM_SEGMENT_S};

use serde::Serialize;

use crate::sim2real::locate::{self, Explained};
use crate::sim2real::metrics::{self, Accum, ErrorStats, GapConstants};
use crate::sim2real::recording::{Recording, derivative};
use crate::sim2real::replay::Episode;
use crate::sim2real::spectral::{self, BandPower};

#[derive(Debug, Clone, Serialize)]
pub struct BandPowers {
    pub real: BandPower,
    pub sim: BandPower,
}

/// Error decomposition of one joint, pooled over episodes (sample-weighted means).
#[derive(Debug, Clone, Serialize)]
pub struct Decomposition {
    pub bias: f64,
    pub lag_s: f64,
    pub gain: f64,
    pub residual_rms: f64,
    pub total_rms: f64,
    /// Dominant component (the one carrying most squared error over episodes).
    pub dominant: Explained,
}

#[derive(Debug, Clone, Serialize)]
pub struct Phases {
    pub reversal: ErrorStats,
    pub high_accel: ErrorStats,
    pub high_load: Option<ErrorStats>,
    pub other: ErrorStats,
}

#[derive(Debug, Clone, Serialize)]
pub struct JointGap {
    pub name: String,
    pub region: String,
    pub samples: usize,
    pub mae: f64,
    pub rmse: f64,
    pub max: f64,
    pub corr: Option<f64>,
    pub vel_mae: f64,
    pub vel_rmse: f64,
    pub spectral_kl: f64,
    /// Share of the recorded variance that is motion, not noise ([`motion::share`]): the joint's
    /// weight in `correlation_mean`, `spectral_kl` and its region's `corr`.
    pub motion_share: f64,
    pub dominant_hz_real: f64,
    pub dominant_hz_sim: f64,
    pub band_power: BandPowers,
    pub decomposition: Decomposition,
    pub phases: Phases,
}

#[derive(Debug, Clone, Serialize)]
pub struct RegionGap {
    pub region: String,
    pub joints: usize,
    pub mae: f64,
    pub rmse: f64,
    pub max: f64,
    pub corr: Option<f64>,
    pub vel_mae: f64,
    pub vel_rmse: f64,
    pub spectral_kl: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct EpisodeJoint {
    pub name: String,
    pub mae: f64,
    pub rmse: f64,
    pub corr: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct EpisodeGap {
    pub source: String,
    pub samples: usize,
    pub duration_s: f64,
    pub position_mae: f64,
    pub position_rmse: f64,
    pub position_max: f64,
    pub velocity_mae: f64,
    pub velocity_rmse: f64,
    pub correlation_mean: Option<f64>,
    pub gap_overall: f64,
    pub diverged: Option<String>,
    pub per_joint: Vec<EpisodeJoint>,
}

#[derive(Debug, Clone, Serialize)]
pub struct Share {
    pub name: String,
    pub rmse: f64,
    /// Fraction of the dataset's total squared position error.
    pub share: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct BandMismatch {
    pub band: String,
    pub real: f64,
    pub sim: f64,
    /// |sim − real| as a fraction of the total real power (all bands).
    pub mismatch: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct PhaseShare {
    pub phase: String,
    pub rmse: f64,
    pub mae: f64,
    pub samples: usize,
    /// RMSE in this phase over RMSE outside all phases.
    pub ratio_to_other: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct JointCause {
    pub name: String,
    pub dominant: Explained,
    pub bias: f64,
    pub lag_s: f64,
    pub gain: f64,
    pub summary: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct Localisation {
    pub joints: Vec<Share>,
    pub regions: Vec<Share>,
    pub worst_band: Option<String>,
    pub bands: Vec<BandMismatch>,
    pub phases: Vec<PhaseShare>,
    pub causes: Vec<JointCause>,
}

/// Averaged PSDs of one joint (for plots; not serialised).
#[derive(Debug, Clone, Default)]
pub struct JointPsd {
    pub freqs: Vec<f64>,
    pub real: Vec<f64>,
    pub sim: Vec<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct GapReport {
    pub position_mae: f64,
    pub position_rmse: f64,
    pub position_max: f64,
    pub velocity_mae: f64,
    pub velocity_rmse: f64,
    pub correlation_mean: f64,
    pub gap_kinematic: f64,
    pub gap_dynamic: f64,
    pub gap_control: f64,
    pub gap_overall: f64,
    pub spectral_kl: f64,
    pub episodes: usize,
    pub samples: usize,
    pub duration_s: f64,
    pub uniform_rate_hz: f64,
    pub constants: GapConstants,
    pub per_joint: Vec<JointGap>,
    pub per_region: Vec<RegionGap>,
    pub per_episode: Vec<EpisodeGap>,
    pub localisation: Localisation,
    /// Sources of episodes that diverged (excluded from pooled metrics).
    pub diverged: Vec<String>,
    /// What reading the recordings found out (e.g. a control tick origin estimated from the
    /// rows, `sim2real::replay::origin_messages`); also printed on stderr. Absent when empty.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The replay at a quarter of the model's timestep against the replay at its own
    /// (`sim2real::replay::timestep_check`), when both ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timestep: Option<crate::sim2real::replay::TimestepCheck>,
    #[serde(skip)]
    pub psd: Vec<JointPsd>,
}

/// Body region of a joint: the robot spec's `region` for it, else [`region_from_name`].
pub fn joint_region(spec: Option<&crate::spec::Spec>, name: &str) -> String {
    spec.and_then(|s| s.joint(name))
        .and_then(|f| f.region)
        .unwrap_or_else(|| region_from_name(name))
}

/// Body region of a joint from its name ([`crate::model::region::from_name`], the classifier
/// `init-spec` uses too), else "other".
pub fn region_from_name(name: &str) -> String {
    crate::model::region::from_name(name).unwrap_or("other").to_string()
}

#[derive(Default)]
struct JointAcc {
    name: String,
    pos: Accum,
    vel: Accum,
    corrs: Vec<f64>,
    /// Noise and spread sums of squares of the recorded positions ([`motion`]).
    motion: (f64, f64),
    psd_w: f64,
    psd: JointPsd,
    /// `psd` is from episodes at least one Welch segment long.
    psd_full: bool,
    dec_w: f64,
    bias: f64,
    lag: f64,
    gain: f64,
    res_sq: f64,
    tot_sq: f64,
    votes: Vec<(Explained, f64)>,
    ph: [Accum; 4],
    has_load: bool,
}

fn stats_to_accum(s: &ErrorStats) -> Accum {
    let mut a = Accum::new();
    if s.n > 0 {
        let n = s.n as f64;
        a.sum_abs = s.mae * n;
        a.sum_sq = s.rmse * s.rmse * n;
        a.max = s.max;
        a.n = s.n;
    }
    a
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// (value, motion share) of the joints with a finite value of `f`.
fn shape_of<'a>(
    js: impl Iterator<Item = &'a JointGap>,
    f: impl Fn(&JointGap) -> Option<f64>,
) -> Vec<(f64, f64)> {
    js.filter_map(|j| f(j).filter(|x| x.is_finite()).map(|x| (x, j.motion_share))).collect()
}

/// The joints' spectral KL weighted by their motion shares (NaN when none has one).
fn members_kl<'a>(js: impl Iterator<Item = &'a JointGap>) -> f64 {
    motion::weighted_mean(&shape_of(js, |j| Some(j.spectral_kl))).unwrap_or(f64::NAN)
}

/// Computes the report for episodes replayed from `recs` (paired by index). `region` maps a
/// joint name to its region (spec, else [`region_from_name`]).
pub fn compute(
    recs: &[Recording],
    eps: &[Episode],
    region: &dyn Fn(&str) -> String,
    opts: &GapOptions,
) -> GapReport {
    let c = &opts.constants;
    // Uniform rate: mean sample rate over the non-diverged dataset.
    let ok: Vec<usize> =
        (0..recs.len().min(eps.len())).filter(|&i| eps[i].diverged.is_none()).collect();
    let (mut tot_int, mut tot_dur) = (0usize, 0.0);
    for &i in &ok {
        tot_int += recs[i].t.len().saturating_sub(1);
        tot_dur += recs[i].duration();
    }
    let fs = opts.uniform_rate_hz.unwrap_or_else(|| {
        if tot_dur > 0.0 { (tot_int as f64 / tot_dur).round().max(1.0) } else { 100.0 }
    });

    let dec_seg = ((opts.decompose_segment_s * fs).round() as usize).max(2);
    let mut joints: Vec<JointAcc> = Vec::new();
    let mut per_episode = Vec::new();
    let mut diverged = Vec::new();
    let (mut all_pos, mut all_vel) = (Accum::new(), Accum::new());
    let (mut samples, mut duration) = (0usize, 0.0);
    for (ei, (rec, ep)) in recs.iter().zip(eps).enumerate() {
        let src = rec.source.display().to_string();
        let is_ok = ep.diverged.is_none();
        if !is_ok {
            diverged.push(format!("{src}: {}", ep.diverged.as_deref().unwrap_or("")));
        } else {
            samples += rec.t.len();
            duration += rec.duration();
        }
        let (mut ep_pos, mut ep_vel) = (Accum::new(), Accum::new());
        let mut ep_corr = Vec::new();
        let mut ep_joints = Vec::new();
        for (k, name) in ep.joints.iter().enumerate() {
            let Some(jt) = rec.joint(name) else { continue };
            let qs = &ep.q_sim[k];
            let qds = &ep.qd_sim[k];
            let qd_real_owned;
            let qd_real: &[f64] = match &jt.qd {
                Some(v) => v,
                None => {
                    qd_real_owned = derivative(&rec.t, &jt.q);
                    &qd_real_owned
                }
            };
            let st = metrics::error_stats(qs, &jt.q);
            let corr = metrics::pearson(qs, &jt.q);
            let (nz, sp) = motion::noise_and_spread(&jt.q);
            ep_joints.push(EpisodeJoint { name: name.clone(), mae: st.mae, rmse: st.rmse, corr });
            ep_pos.add(qs, &jt.q);
            ep_vel.add(qds, qd_real);
            if let Some(r) = corr {
                ep_corr.push((r, motion::share(nz, sp)));
            }
            if !is_ok {
                continue;
            }
            let _ = ei;
            let ji = match joints.iter().position(|j| j.name == *name) {
                Some(i) => i,
                None => {
                    joints.push(JointAcc { name: name.clone(), ..Default::default() });
                    joints.len() - 1
                }
            };
            let ja = &mut joints[ji];
            ja.motion = (ja.motion.0 + nz, ja.motion.1 + sp);
            ja.pos.add(qs, &jt.q);
            ja.vel.add(qds, qd_real);
            if let Some(r) = corr {
                ja.corrs.push(r);
            }
            // Uniform resampling for spectra and decomposition.
            let (_, ru) = metrics::resample_uniform(&rec.t, &jt.q, fs);
            let (_, su) = metrics::resample_uniform(&rec.t, qs, fs);
            let nperseg = ((opts.segment_s * fs).round() as usize).max(2);
            let nfft = nperseg.min(ru.len()).next_power_of_two();
            let (f, pr) = spectral::welch_psd_nfft(&ru, fs, nperseg, Some(nfft), opts.overlap);
            let (_, ps) = spectral::welch_psd_nfft(&su, fs, nperseg, Some(nfft), opts.overlap);
            if !f.is_empty() {
                let w = ru.len() as f64;
                // Episodes shorter than a segment have a different grid: they only count when no
                // full-length episode exists (the longest short one wins).
                let full = ru.len() >= nperseg;
                let cur_full = ja.psd_full;
                if ja.psd.freqs.is_empty() || (!cur_full && (full || f.len() > ja.psd.freqs.len()))
                {
                    ja.psd_full = full;
                    ja.psd = JointPsd {
                        freqs: f,
                        real: pr.iter().map(|x| x * w).collect(),
                        sim: ps.iter().map(|x| x * w).collect(),
                    };
                    ja.psd_w = w;
                } else if f.len() == ja.psd.freqs.len() && full {
                    for (a, b) in ja.psd.real.iter_mut().zip(&pr) {
                        *a += b * w;
                    }
                    for (a, b) in ja.psd.sim.iter_mut().zip(&ps) {
                        *a += b * w;
                    }
                    ja.psd_w += w;
                }
            }
            for (d, w) in locate::decompose_segments(1.0 / fs, &su, &ru, opts.max_lag_s, dec_seg) {
                if d.total_rms.is_finite() && w > 0.0 {
                    ja.dec_w += w;
                    ja.bias += d.bias * w;
                    ja.lag += d.lag_s * w;
                    ja.gain += d.gain * w;
                    ja.res_sq +=
                        if d.residual_rms.is_finite() { d.residual_rms.powi(2) * w } else { 0.0 };
                    ja.tot_sq += d.total_rms.powi(2) * w;
                    match ja.votes.iter_mut().find(|v| v.0 == d.explained) {
                        Some(v) => v.1 += d.total_rms.powi(2) * w,
                        None => ja.votes.push((d.explained, d.total_rms.powi(2) * w)),
                    }
                }
            }
            let ph = locate::phase_errors(
                &rec.t,
                &jt.q,
                qd_real,
                jt.q_cmd.as_deref(),
                jt.tau.as_deref(),
                qs,
            );
            ja.ph[0].merge(&stats_to_accum(&ph.reversal));
            ja.ph[1].merge(&stats_to_accum(&ph.high_accel));
            if let Some(h) = &ph.high_load {
                ja.ph[2].merge(&stats_to_accum(h));
                ja.has_load = true;
            }
            ja.ph[3].merge(&stats_to_accum(&ph.other));
        }
        let ps = ep_pos.finish();
        let vs = ep_vel.finish();
        let cm = motion::weighted_mean(&ep_corr);
        let g = metrics::gap_scores(ps.rmse, vs.rmse, cm.unwrap_or(0.0), c);
        per_episode.push(EpisodeGap {
            source: src,
            samples: rec.t.len(),
            duration_s: rec.duration(),
            position_mae: ps.mae,
            position_rmse: ps.rmse,
            position_max: ps.max,
            velocity_mae: vs.mae,
            velocity_rmse: vs.rmse,
            correlation_mean: cm,
            gap_overall: g.overall,
            diverged: ep.diverged.clone(),
            per_joint: ep_joints,
        });
        if is_ok {
            all_pos.merge(&ep_pos);
            all_vel.merge(&ep_vel);
        }
    }

    let mut per_joint = Vec::new();
    let mut psd = Vec::new();
    for ja in &joints {
        let p = ja.pos.finish();
        let v = ja.vel.finish();
        let w = ja.psd_w.max(1e-300);
        let pr: Vec<f64> = ja.psd.real.iter().map(|x| x / w).collect();
        let pss: Vec<f64> = ja.psd.sim.iter().map(|x| x / w).collect();
        let f = &ja.psd.freqs;
        let dw = ja.dec_w.max(1e-300);
        let dominant = ja.votes.iter().cloned().fold(None::<(Explained, f64)>, |b, v| match b {
            Some(b) if b.1 >= v.1 => Some(b),
            _ => Some(v),
        });
        per_joint.push(JointGap {
            name: ja.name.clone(),
            region: region(&ja.name),
            samples: p.n,
            mae: p.mae,
            rmse: p.rmse,
            max: p.max,
            corr: mean(&ja.corrs),
            vel_mae: v.mae,
            vel_rmse: v.rmse,
            spectral_kl: spectral::symmetric_kl(&pr, &pss),
            motion_share: motion::share(ja.motion.0, ja.motion.1),
            dominant_hz_real: spectral::dominant_frequency(f, &pr),
            dominant_hz_sim: spectral::dominant_frequency(f, &pss),
            band_power: BandPowers {
                real: spectral::band_power(f, &pr),
                sim: spectral::band_power(f, &pss),
            },
            decomposition: Decomposition {
                bias: ja.bias / dw,
                lag_s: ja.lag / dw,
                gain: ja.gain / dw,
                residual_rms: (ja.res_sq / dw).sqrt(),
                total_rms: (ja.tot_sq / dw).sqrt(),
                dominant: dominant.map_or(Explained::None, |d| d.0),
            },
            phases: Phases {
                reversal: ja.ph[0].finish(),
                high_accel: ja.ph[1].finish(),
                high_load: ja.has_load.then(|| ja.ph[2].finish()),
                other: ja.ph[3].finish(),
            },
        });
        psd.push(JointPsd { freqs: f.clone(), real: pr, sim: pss });
    }

    // Regions, in first-seen order.
    let mut per_region: Vec<RegionGap> = Vec::new();
    let mut region_sq: Vec<(String, f64, usize)> = Vec::new();
    let mut names: Vec<String> = Vec::new();
    for j in &per_joint {
        if !names.contains(&j.region) {
            names.push(j.region.clone());
        }
    }
    for r in &names {
        let members: Vec<usize> =
            (0..per_joint.len()).filter(|&i| per_joint[i].region == *r).collect();
        let (mut pa, mut va) = (Accum::new(), Accum::new());
        for &i in &members {
            pa.merge(&joints[i].pos);
            va.merge(&joints[i].vel);
        }
        let (p, v) = (pa.finish(), va.finish());
        let corrs = shape_of(members.iter().map(|&i| &per_joint[i]), |j| j.corr);
        region_sq.push((r.clone(), pa.sum_sq, pa.n));
        per_region.push(RegionGap {
            region: r.clone(),
            joints: members.len(),
            mae: p.mae,
            rmse: p.rmse,
            max: p.max,
            corr: motion::weighted_mean(&corrs),
            vel_mae: v.mae,
            vel_rmse: v.rmse,
            spectral_kl: members_kl(members.iter().map(|&i| &per_joint[i])),
        });
    }

    let pos = all_pos.finish();
    let vel = all_vel.finish();
    let corr_mean =
        motion::weighted_mean(&shape_of(per_joint.iter(), |j| j.corr)).unwrap_or(f64::NAN);
    let g = metrics::gap_scores(pos.rmse, vel.rmse, corr_mean, c);

    // Localisation.
    let total_sq = all_pos.sum_sq.max(1e-300);
    let mut jshare: Vec<Share> = joints
        .iter()
        .zip(&per_joint)
        .map(|(a, j)| Share { name: j.name.clone(), rmse: j.rmse, share: a.pos.sum_sq / total_sq })
        .collect();
    jshare.sort_by(|a, b| b.share.total_cmp(&a.share));
    let mut rshare: Vec<Share> = region_sq
        .iter()
        .map(|(r, sq, n)| Share {
            name: r.clone(),
            rmse: (sq / (*n).max(1) as f64).sqrt(),
            share: sq / total_sq,
        })
        .collect();
    rshare.sort_by(|a, b| b.share.total_cmp(&a.share));
    let (mut br, mut bs) = ([0.0; 3], [0.0; 3]);
    for j in &per_joint {
        let (r, s) = (&j.band_power.real, &j.band_power.sim);
        for (k, (x, y)) in
            [(r.low, s.low), (r.mid, s.mid), (r.high, s.high)].into_iter().enumerate()
        {
            if x.is_finite() && y.is_finite() {
                br[k] += x;
                bs[k] += y;
            }
        }
    }
    let real_total = br.iter().sum::<f64>().max(1e-300);
    let mut bands: Vec<BandMismatch> = ["0-2 Hz", "2-10 Hz", ">10 Hz"]
        .iter()
        .enumerate()
        .map(|(k, b)| BandMismatch {
            band: b.to_string(),
            real: br[k],
            sim: bs[k],
            mismatch: (bs[k] - br[k]).abs() / real_total,
        })
        .collect();
    bands.sort_by(|a, b| b.mismatch.total_cmp(&a.mismatch));
    let worst_band = bands.first().filter(|b| b.mismatch > 0.0).map(|b| b.band.clone());
    let mut ph_all = [Accum::new(), Accum::new(), Accum::new(), Accum::new()];
    for ja in &joints {
        for (acc, ph) in ph_all.iter_mut().zip(&ja.ph) {
            acc.merge(ph);
        }
    }
    let other_rmse = ph_all[3].finish().rmse;
    let mut phases: Vec<PhaseShare> =
        ["velocity reversal", "high commanded acceleration", "high load"]
            .iter()
            .enumerate()
            .filter(|(k, _)| ph_all[*k].n > 0)
            .map(|(k, name)| {
                let s = ph_all[k].finish();
                PhaseShare {
                    phase: name.to_string(),
                    rmse: s.rmse,
                    mae: s.mae,
                    samples: s.n,
                    ratio_to_other: s.rmse / other_rmse,
                }
            })
            .collect();
    phases.sort_by(|a, b| b.ratio_to_other.total_cmp(&a.ratio_to_other));
    let causes = jshare
        .iter()
        .filter_map(|s| per_joint.iter().find(|j| j.name == s.name))
        .map(|j| {
            let d = &j.decomposition;
            let summary = cause::summary(j);
            JointCause {
                name: j.name.clone(),
                dominant: d.dominant,
                bias: d.bias,
                lag_s: d.lag_s,
                gain: d.gain,
                summary,
            }
        })
        .collect();

    GapReport {
        position_mae: pos.mae,
        position_rmse: pos.rmse,
        position_max: pos.max,
        velocity_mae: vel.mae,
        velocity_rmse: vel.rmse,
        correlation_mean: corr_mean,
        gap_kinematic: g.kinematic,
        gap_dynamic: g.dynamic,
        gap_control: g.control,
        gap_overall: g.overall,
        spectral_kl: members_kl(per_joint.iter()),
        episodes: ok.len(),
        samples,
        duration_s: duration,
        uniform_rate_hz: fs,
        constants: c.clone(),
        per_joint,
        per_region,
        per_episode,
        localisation: Localisation {
            joints: jshare,
            regions: rshare,
            worst_band,
            bands,
            phases,
            causes,
        },
        diverged,
        notes: Vec::new(),
        warnings: Vec::new(),
        timestep: None,
        psd,
    }
}

#[cfg(test)]
mod tests;
