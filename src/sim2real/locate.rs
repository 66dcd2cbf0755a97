//! Where does one joint's error come from? [`decompose`] splits sim-vs-real error into offset,
//! time lag, amplitude (gain) and a residual; [`phase_errors`] reports the error separately in
//! motion phases (velocity reversals, high commanded acceleration, high load) where friction,
//! backlash, actuator limits and compliance show.

use super::metrics::{Accum, ErrorStats};
use serde::Serialize;

/// Result of [`decompose`]. Model:
/// `real(t) ≈ gain·(sim(t − lag_s) − mean_sim) + mean_sim + bias`.
#[derive(Debug, Clone, Serialize)]
pub struct ErrorDecomposition {
    /// mean(real) − mean(sim).
    pub bias: f64,
    /// Positive: the real signal lags (is delayed with respect to) the simulated one.
    pub lag_s: f64,
    pub gain: f64,
    /// RMS of what is left after removing bias, lag and gain (over the samples where the
    /// shifted simulation is defined).
    pub residual_rms: f64,
    /// RMS of sim − real.
    pub total_rms: f64,
    pub explained: Explained,
}

/// The component whose removal alone lowers the RMS error most; `Residual` when the three
/// together leave more than half of the RMS error; `None` when there is no error to speak of
/// (total RMS below 1e-3 of the signals' standard deviation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Explained {
    Offset,
    Lag,
    Amplitude,
    Residual,
    None,
}

fn rms_of(it: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for e in it {
        s += e * e;
        n += 1;
    }
    if n == 0 { f64::NAN } else { (s / n as f64).sqrt() }
}

/// Value of `x` at fractional index `p` (linear interpolation), `None` outside `[0, len−1]`.
fn at_frac(x: &[f64], p: f64) -> Option<f64> {
    if p.is_nan() || p < 0.0 || p > (x.len() - 1) as f64 {
        return None;
    }
    let j = p.floor() as usize;
    let a = p - j as f64;
    if j + 1 >= x.len() || a == 0.0 { Some(x[j]) } else { Some(x[j] * (1.0 - a) + x[j + 1] * a) }
}

/// Decomposes the error between `sim` and `real`, both sampled uniformly every `t_uniform_dt`
/// seconds (see `metrics::resample_uniform`), searching lags within ±`max_lag_s`.
///
/// The lag maximises the normalised cross-correlation of the mean-removed signals over integer
/// shifts, refined to sub-sample precision by a parabola through the peak and its neighbours;
/// the gain is the least-squares fit of the shifted, mean-removed signals. Inputs are compared
/// over their common length; with fewer than 3 samples, a non-positive step or non-finite
/// values the lag is 0, the gain 1 and `explained` is `None`.
pub fn decompose(
    t_uniform_dt: f64,
    sim: &[f64],
    real: &[f64],
    max_lag_s: f64,
) -> ErrorDecomposition {
    let n = sim.len().min(real.len());
    let (sim, real) = (&sim[..n], &real[..n]);
    let total_rms = rms_of(sim.iter().zip(real).map(|(s, r)| s - r));
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len().max(1) as f64;
    let (ms, mr) = (mean(sim), mean(real));
    let bias = mr - ms;
    let degenerate = ErrorDecomposition {
        bias,
        lag_s: 0.0,
        gain: 1.0,
        residual_rms: rms_of(sim.iter().zip(real).map(|(s, r)| s + bias - r)),
        total_rms,
        explained: Explained::None,
    };
    if n < 3 || t_uniform_dt.is_nan() || t_uniform_dt <= 0.0 || !total_rms.is_finite() {
        return degenerate;
    }
    let s0: Vec<f64> = sim.iter().map(|v| v - ms).collect();
    let r0: Vec<f64> = real.iter().map(|v| v - mr).collect();
    let std_s = rms_of(s0.iter().copied());
    let std_r = rms_of(r0.iter().copied());
    let scale = std_s.max(std_r);
    if total_rms <= 1e-12 || total_rms <= 1e-3 * scale {
        return degenerate;
    }

    // Lag: normalised cross-correlation c(k) = Σ r0[i]·s0[i−k] / √(Σr0² Σs0²) over the overlap.
    let kmax = if max_lag_s.is_finite() && max_lag_s > 0.0 {
        ((max_lag_s / t_uniform_dt).round() as usize).min(n / 2)
    } else {
        0
    };
    let corr = |k: isize| -> f64 {
        let lo = k.max(0) as usize;
        let hi = (n as isize + k.min(0)) as usize;
        let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
        for i in lo..hi {
            let (a, b) = (r0[i], s0[(i as isize - k) as usize]);
            sab += a * b;
            saa += a * a;
            sbb += b * b;
        }
        if saa > 0.0 && sbb > 0.0 { sab / (saa * sbb).sqrt() } else { f64::NEG_INFINITY }
    };
    let km = kmax as isize;
    let cs: Vec<f64> = (-km..=km).map(corr).collect();
    let mut best = km as usize; // index of k = 0
    for (idx, c) in cs.iter().enumerate() {
        if *c > cs[best] {
            best = idx;
        }
    }
    let mut lag_samples = best as f64 - km as f64;
    if best > 0 && best + 1 < cs.len() {
        let (a, b, c) = (cs[best - 1], cs[best], cs[best + 1]);
        let denom = a - 2.0 * b + c;
        if a.is_finite() && c.is_finite() && denom < 0.0 {
            lag_samples += (0.5 * (a - c) / denom).clamp(-0.5, 0.5);
        }
    }
    if !cs[best].is_finite() {
        lag_samples = 0.0;
    }
    let lag_s = lag_samples * t_uniform_dt;

    // Shifted simulation (mean removed) where defined.
    let shifted: Vec<(usize, f64)> =
        (0..n).filter_map(|i| at_frac(&s0, i as f64 - lag_samples).map(|v| (i, v))).collect();
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for &(i, v) in &shifted {
        sxy += r0[i] * v;
        sxx += v * v;
    }
    let gain = if sxx > 0.0 { sxy / sxx } else { 1.0 };
    let residual_rms = rms_of(shifted.iter().map(|&(i, v)| r0[i] - gain * v));

    // What each component alone removes.
    let rms_offset = rms_of(s0.iter().zip(&r0).map(|(s, r)| s - r));
    let rms_lag = rms_of(shifted.iter().map(|&(i, v)| v - r0[i] - bias));
    let rms_gain = rms_of(s0.iter().zip(&r0).map(|(s, r)| gain * s - r - bias));
    let candidates = [
        (Explained::Offset, total_rms - rms_offset),
        (Explained::Lag, total_rms - rms_lag),
        (Explained::Amplitude, total_rms - rms_gain),
    ];
    let explained = if residual_rms.is_nan() || residual_rms > 0.5 * total_rms {
        Explained::Residual
    } else {
        let mut pick = candidates[0];
        for c in &candidates[1..] {
            if c.1 > pick.1 {
                pick = *c;
            }
        }
        pick.0
    };
    ErrorDecomposition { bias, lag_s, gain, residual_rms, total_rms, explained }
}

/// [`decompose`] on consecutive segments of `seg` samples (the last one takes the remainder; a
/// series shorter than two segments is one), each with its number of samples as weight.
///
/// A pure lag is `real(t) = sim(t − lag)` only where both are driven by the command: a start
/// from a state off equilibrium moves the real and simulated joint alike (the same free response
/// from the same recorded state, not shifted), and shifting that motion by the lag makes an error
/// the data do not have. Over a whole episode that span can outweigh the lag everywhere else
/// (a two-joint arm's elbow falling 0.38 rad in its first 0.2 s: "unexplained" though both
/// joints had the same 10 ms delay). Per segment, that span is one segment's explanation and
/// weighs by the error it holds, which an unshifted free response keeps small.
pub fn decompose_segments(
    t_uniform_dt: f64,
    sim: &[f64],
    real: &[f64],
    max_lag_s: f64,
    seg: usize,
) -> Vec<(ErrorDecomposition, f64)> {
    let n = sim.len().min(real.len());
    let k = (n / seg.max(1)).max(1);
    (0..k)
        .map(|i| {
            let (lo, hi) = (i * n / k, (i + 1) * n / k);
            (decompose(t_uniform_dt, &sim[lo..hi], &real[lo..hi], max_lag_s), (hi - lo) as f64)
        })
        .collect()
}

/// Position error (sim − real) per motion phase. The first three sets may overlap; `other` is
/// every sample in none of them.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseWindows {
    pub reversal: ErrorStats,
    pub high_accel: ErrorStats,
    pub high_load: Option<ErrorStats>,
    pub other: ErrorStats,
}

/// Half-width of the window around a velocity reversal [s].
pub const REVERSAL_WINDOW_S: f64 = 0.030;
/// Fraction of samples in the high-acceleration and high-load sets.
pub const TOP_FRACTION: f64 = 0.10;

/// Splits the error of `sim` against `q_real` by phase (all series share the time axis `t`,
/// irregular spacing allowed; compared over their common length):
/// * `reversal`: samples within ±30 ms of a zero crossing of `qd_real` that separates two
///   excursions beyond a small threshold (10 % of RMS(qd_real)) of opposite sign, so that
///   jitter around standstill does not count;
/// * `high_accel`: the 10 % of samples with the largest |commanded acceleration| (second
///   derivative of `q_cmd`, or of `q_real` when there is no command), zero-acceleration
///   samples excluded;
/// * `high_load`: the 10 % with the largest |tau|, when `tau` is given.
pub fn phase_errors(
    t: &[f64],
    q_real: &[f64],
    qd_real: &[f64],
    q_cmd: Option<&[f64]>,
    tau: Option<&[f64]>,
    sim: &[f64],
) -> PhaseWindows {
    let mut n = t.len().min(q_real.len()).min(qd_real.len()).min(sim.len());
    if let Some(c) = q_cmd {
        n = n.min(c.len());
    }
    if let Some(c) = tau {
        n = n.min(c.len());
    }
    let (t, q_real, qd, sim) = (&t[..n], &q_real[..n], &qd_real[..n], &sim[..n]);

    let mut reversal = vec![false; n];
    for tc in reversal_times(t, qd) {
        let lo = t.partition_point(|&x| x < tc - REVERSAL_WINDOW_S);
        let hi = t.partition_point(|&x| x <= tc + REVERSAL_WINDOW_S);
        for r in &mut reversal[lo..hi.max(lo)] {
            *r = true;
        }
    }
    let cmd = q_cmd.map_or(q_real, |c| &c[..n]);
    let accel = second_derivative(t, cmd);
    let high_accel = top_fraction(&accel);
    let high_load = tau.map(|x| top_fraction(&x[..n]));

    let stats = |mask: &dyn Fn(usize) -> bool| {
        let mut a = Accum::new();
        for i in (0..n).filter(|&i| mask(i)) {
            a.push(sim[i] - q_real[i]);
        }
        a.finish()
    };
    PhaseWindows {
        reversal: stats(&|i| reversal[i]),
        high_accel: stats(&|i| high_accel[i]),
        high_load: high_load.as_ref().map(|h| stats(&|i| h[i])),
        other: stats(&|i| {
            !reversal[i] && !high_accel[i] && !high_load.as_ref().is_some_and(|h| h[i])
        }),
    }
}

/// Times of genuine velocity reversals (see [`phase_errors`]).
fn reversal_times(t: &[f64], qd: &[f64]) -> Vec<f64> {
    let thr = (0.1 * rms_of(qd.iter().copied())).max(1e-12);
    let mut out = Vec::new();
    let mut state = 0.0f64; // sign of the last excursion beyond thr
    let mut last_nz: Option<usize> = None;
    let mut last_cross: Option<f64> = None;
    for i in 0..t.len() {
        let v = qd[i];
        if !v.is_finite() || v == 0.0 {
            continue;
        }
        if let Some(j) = last_nz
            && qd[j].signum() != v.signum()
        {
            last_cross = Some(if j + 1 == i {
                t[j] + (t[i] - t[j]) * qd[j] / (qd[j] - v)
            } else {
                0.5 * (t[j + 1] + t[i - 1])
            });
        }
        last_nz = Some(i);
        if v.abs() > thr {
            if state != 0.0
                && state != v.signum()
                && let Some(tc) = last_cross
            {
                out.push(tc);
            }
            state = v.signum();
        }
    }
    out
}

/// Second derivative on an irregular grid (three-point formula), ends copied from neighbours.
fn second_derivative(t: &[f64], x: &[f64]) -> Vec<f64> {
    let n = t.len().min(x.len());
    if n < 3 {
        return vec![0.0; n];
    }
    let mut a = vec![0.0; n];
    for i in 1..n - 1 {
        let (h0, h1) = (t[i] - t[i - 1], t[i + 1] - t[i]);
        a[i] = 2.0 * (h0 * x[i + 1] - (h0 + h1) * x[i] + h1 * x[i - 1]) / (h0 * h1 * (h0 + h1));
    }
    a[0] = a[1];
    a[n - 1] = a[n - 2];
    a
}

/// Mask of the ceil(10 %) samples with the largest |x| (ties by index), zeros and NaN excluded.
fn top_fraction(x: &[f64]) -> Vec<bool> {
    let mut idx: Vec<usize> = (0..x.len()).filter(|&i| x[i].is_finite() && x[i] != 0.0).collect();
    idx.sort_by(|&a, &b| x[b].abs().total_cmp(&x[a].abs()).then(a.cmp(&b)));
    let k = (x.len() as f64 * TOP_FRACTION).ceil() as usize;
    let mut mask = vec![false; x.len()];
    for &i in idx.iter().take(k) {
        mask[i] = true;
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 0.004;

    fn signal(t: f64) -> f64 {
        0.2 + 0.6 * (2.0 * std::f64::consts::PI * 0.7 * t).sin()
            + 0.3 * (2.0 * std::f64::consts::PI * 1.9 * t + 0.4).sin()
    }

    fn sim() -> Vec<f64> {
        (0..2500).map(|i| signal(i as f64 * DT)).collect()
    }

    #[test]
    fn pure_offset() {
        let s = sim();
        let r: Vec<f64> = s.iter().map(|v| v + 0.05).collect();
        let d = decompose(DT, &s, &r, 0.2);
        assert!((d.bias - 0.05).abs() < 1e-6, "{d:?}");
        assert!((d.total_rms - 0.05).abs() < 1e-9);
        assert!(d.lag_s.abs() < 1e-9 && (d.gain - 1.0).abs() < 1e-9, "{d:?}");
        assert!(d.residual_rms < 1e-9);
        assert_eq!(d.explained, Explained::Offset);
    }

    #[test]
    fn pure_lag_sub_sample() {
        let s = sim();
        // 30 ms = 7.5 samples at 4 ms: real is delayed
        let r: Vec<f64> = (0..s.len()).map(|i| signal(i as f64 * DT - 0.030)).collect();
        let d = decompose(DT, &s, &r, 0.2);
        assert!((d.lag_s - 0.030).abs() < 0.002, "{d:?}");
        assert!((d.gain - 1.0).abs() < 0.01, "{d:?}");
        assert_eq!(d.explained, Explained::Lag, "{d:?}");
        assert!(d.residual_rms < 0.1 * d.total_rms, "{d:?}");
        // real leading gives a negative lag; integer shift at 5 ms sampling
        let s5: Vec<f64> = (0..2000).map(|i| signal(i as f64 * 0.005)).collect();
        let r5: Vec<f64> = (0..2000).map(|i| signal(i as f64 * 0.005 + 0.030)).collect();
        let d = decompose(0.005, &s5, &r5, 0.2);
        assert!((d.lag_s + 0.030).abs() < 0.002, "{d:?}");
        assert_eq!(d.explained, Explained::Lag);
    }

    #[test]
    fn pure_amplitude() {
        let s = sim();
        let m = s.iter().sum::<f64>() / s.len() as f64;
        let r: Vec<f64> = s.iter().map(|v| 1.2 * (v - m) + m).collect();
        let d = decompose(DT, &s, &r, 0.2);
        assert!((d.gain - 1.2).abs() < 0.01, "{d:?}");
        assert!(d.bias.abs() < 1e-9 && d.lag_s.abs() < 1e-3, "{d:?}");
        assert_eq!(d.explained, Explained::Amplitude);
        let json = serde_json::to_string(&d).expect("serialises");
        assert!(json.contains("\"explained\":\"amplitude\""), "{json}");
    }

    #[test]
    fn noise_is_residual_and_identity_is_none() {
        let s = sim();
        let mut seed = 11u64;
        let r: Vec<f64> = s
            .iter()
            .map(|v| {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                v + 0.5 * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
            })
            .collect();
        assert_eq!(decompose(DT, &s, &r, 0.2).explained, Explained::Residual);
        let d = decompose(DT, &s, &s, 0.2);
        assert_eq!(d.explained, Explained::None);
        assert_eq!(d.total_rms, 0.0);
        assert_eq!(decompose(DT, &s[..2], &s[..2], 0.2).explained, Explained::None);
        assert_eq!(decompose(0.0, &s, &r, 0.2).explained, Explained::None);
    }

    #[test]
    fn phase_windows() {
        // 1 Hz sine position, irregular sampling; sim error 0.1 near reversals, 0 elsewhere.
        let mut t = Vec::new();
        let mut x = 0.0;
        for i in 0..1000 {
            t.push(x);
            x += if i % 2 == 0 { 0.004 } else { 0.006 };
        }
        let w = 2.0 * std::f64::consts::PI;
        let q: Vec<f64> = t.iter().map(|&s| (w * s).sin()).collect();
        let qd: Vec<f64> = t.iter().map(|&s| w * (w * s).cos()).collect();
        // velocity reversals at t = 0.25 + 0.5 k
        let near_rev = |s: f64| ((s - 0.25) / 0.5 - ((s - 0.25) / 0.5).round()).abs() * 0.5 <= 0.03;
        let sim: Vec<f64> =
            t.iter().zip(&q).map(|(&s, &v)| if near_rev(s) { v + 0.1 } else { v }).collect();
        let tau: Vec<f64> = t.to_vec();
        let p = phase_errors(&t, &q, &qd, None, Some(&tau), &sim);
        assert!(p.reversal.n > 0);
        assert!((p.reversal.mae - 0.1).abs() < 0.02, "{p:?}");
        assert!(p.other.mae < 0.01, "{p:?}");
        // |accel| of a sine peaks at the position extremes = velocity reversals
        assert_eq!(p.high_accel.n, 100);
        assert!(p.high_accel.mae > 0.05, "{p:?}");
        let hl = p.high_load.expect("tau given");
        assert_eq!(hl.n, 100); // the last 10 % of samples (largest tau)
        let total = p.reversal.n + p.other.n;
        assert!(total <= 1000);
        // no reversal in a monotone motion, and jitter below threshold is ignored
        let qd2: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, _)| 1.0 + if i % 2 == 0 { 0.01 } else { -0.01 })
            .collect();
        let p2 = phase_errors(&t, &q, &qd2, Some(&q), None, &sim);
        assert_eq!(p2.reversal.n, 0);
        assert!(p2.high_load.is_none());
    }
}
