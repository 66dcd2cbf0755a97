//! How much of a joint's recorded position is motion rather than measurement noise, measured
//! from the recording itself — the weight of the joint in the shape scores (correlation,
//! spectral KL). A joint that does not move (an idle leg on a stand) records its sensor's noise:
//! its correlation with any replay is the noise's, and its spectrum is the noise's, whatever the
//! model. Weighting every joint by its motion share needs no threshold: a joint at its noise
//! floor weighs ~0, one moving far above it ~1.
//!
//! Noise: white measurement noise of variance σ² gives the second difference
//! `q[i+1] − 2q[i] + q[i−1]` a variance of 6σ², while smooth motion sampled far above its
//! bandwidth adds little to it (a 1 Hz motion sampled at 100 Hz keeps (2π·0.01)² ≈ 0.4 % of its
//! variance there). Spread: the squared deviations of the positions about their mean.

/// (noise, spread) sums of squares of one recorded position trace over its samples: the noise
/// variance from its second differences × the number of samples, and the squared deviations
/// about its mean [rad² or m²]. (0, 0) with fewer than 3 finite samples.
pub fn noise_and_spread(q: &[f64]) -> (f64, f64) {
    let q: Vec<f64> = q.iter().copied().filter(|x| x.is_finite()).collect();
    let n = q.len();
    if n < 3 {
        return (0.0, 0.0);
    }
    let mean = q.iter().sum::<f64>() / n as f64;
    let spread = q.iter().map(|x| (x - mean).powi(2)).sum::<f64>();
    let d2 = q.windows(3).map(|w| (w[2] - 2.0 * w[1] + w[0]).powi(2)).sum::<f64>();
    (d2 / (n - 2) as f64 / 6.0 * n as f64, spread)
}

/// The share of the recorded variance that is motion, `max(0, 1 − noise / spread)`, in [0, 1]
/// (0 for a trace that does not vary at all).
pub fn share(noise: f64, spread: f64) -> f64 {
    if spread > 0.0 { (1.0 - noise / spread).clamp(0.0, 1.0) } else { 0.0 }
}

/// Mean of the values weighted by their weights; the plain mean when every weight is 0 (nothing
/// moves above its noise: no weighting can tell the joints apart). `None` when empty.
pub fn weighted_mean(v: &[(f64, f64)]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let w: f64 = v.iter().map(|x| x.1).sum();
    Some(if w > 0.0 {
        v.iter().map(|(x, k)| x * k).sum::<f64>() / w
    } else {
        v.iter().map(|x| x.0).sum::<f64>() / v.len() as f64
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-noise of unit variance (a sum of incommensurate sines is not white;
    /// this LCG is, enough for the estimate).
    fn noise(n: usize, sigma: f64) -> Vec<f64> {
        let mut s: u64 = 12345;
        (0..n)
            .map(|_| {
                let mut u = 0.0;
                for _ in 0..12 {
                    s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    u += (s >> 11) as f64 / (1u64 << 53) as f64;
                }
                sigma * (u - 6.0)
            })
            .collect()
    }

    #[test]
    fn a_still_joint_weighs_nothing_and_a_moving_one_all() {
        let n = 2000;
        let e = noise(n, 5e-4);
        let (nz, sp) = noise_and_spread(&e);
        assert!(share(nz, sp) < 0.1, "noise only: {}", share(nz, sp));
        // The estimate is the noise's variance (σ² = 2.5e-7 rad²).
        assert!((nz / n as f64 / 2.5e-7 - 1.0).abs() < 0.15, "{}", nz / n as f64);
        let moving: Vec<f64> = (0..n)
            .map(|i| 0.3 * (2.0 * std::f64::consts::PI * 0.8 * i as f64 * 0.01).sin() + e[i])
            .collect();
        let (nz, sp) = noise_and_spread(&moving);
        assert!(share(nz, sp) > 0.99, "moving: {}", share(nz, sp));
        assert_eq!(weighted_mean(&[(0.3, 0.0), (0.99, 1.0)]), Some(0.99));
        assert_eq!(weighted_mean(&[(0.2, 0.0), (0.4, 0.0)]), Some(0.30000000000000004));
    }
}
