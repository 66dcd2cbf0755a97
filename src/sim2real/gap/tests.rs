//! Unit tests of the gap metrics.
use super::*;
use crate::sim2real::recording::JointTrace;

/// The same 1.1 Hz motion (real: sine plus a 10 % third harmonic; sim: the sine) logged at
/// 250 Hz, 1 kHz and 10 kHz for 8 s: the dominant frequency and the spectral KL are the
/// motion's, not the log rate's (with 256-sample segments they read rate / 256 and a KL
/// growing with the rate).
#[test]
fn spectra_do_not_depend_on_the_log_rate() {
    let mut kls = Vec::new();
    for rate in [250.0, 1000.0, 10000.0] {
        let n = (8.0 * rate) as usize + 1;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / rate).collect();
        let w = 2.0 * std::f64::consts::PI * 1.1;
        let sim: Vec<f64> = t.iter().map(|&t| 0.5 * (w * t).sin()).collect();
        let real: Vec<f64> =
            t.iter().map(|&t| 0.5 * (w * t).sin() + 0.05 * (3.0 * w * t).sin()).collect();
        let rec = Recording {
            source: "r.csv".into(),
            meta: Default::default(),
            control_rate_hz: None,
            control_t0_s: None,
            t: t.clone(),
            joints: vec![JointTrace::new("knee", real)],
            base: None,
        };
        let qd = derivative(&t, &sim);
        let ep = Episode {
            t,
            joints: vec!["knee".into()],
            q_sim: vec![sim],
            qd_sim: vec![qd],
            diverged: None,
            peaks: Default::default(),
        };
        let g = compute(&[rec], &[ep], &|_| "legs".into(), &GapOptions::default());
        let j = &g.per_joint[0];
        for hz in [j.dominant_hz_real, j.dominant_hz_sim] {
            assert!((hz - 1.1).abs() <= 1.0 / SPECTRUM_SEGMENT_S, "{rate} Hz: {hz}");
        }
        assert!(j.band_power.real.low > 10.0 * j.band_power.real.mid, "{rate} Hz");
        kls.push(j.spectral_kl);
    }
    let (lo, hi) = kls.iter().fold((f64::MAX, 0.0f64), |(a, b), &k| (a.min(k), b.max(k)));
    assert!(lo > 0.0 && hi < 1.5 * lo, "KL per rate {kls:?}");
}

#[test]
fn regions_from_t1_names() {
    for (n, r) in [
        ("Left_Knee_Pitch", "legs"),
        ("Right_Hip_Roll", "legs"),
        ("Left_Elbow_Yaw", "arms"),
        ("Right_Shoulder_Pitch", "arms"),
        ("AAHead_yaw", "head"),
        ("Head_pitch", "head"),
        ("Waist", "torso"),
        ("servo", "other"),
        ("FL_thigh_joint", "legs"),
        ("FL_calf_joint", "legs"),
    ] {
        assert_eq!(region_from_name(n), r, "{n}");
    }
}
