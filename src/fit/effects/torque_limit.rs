use super::*;
use crate::declare_effect;
use crate::fit::diagnose::{explain, percentile};

declare_effect! {
    /// Motor torque saturation (peak torque, torque–speed line).
    ///
    /// DC-motor torque–speed line: the servo torque is clipped to
    /// [sat·(−1 − q̇/v_lim), sat·(1 − q̇/v_lim)] ∩ [−effort, effort] (Isaac Lab's DCMotor law).
    /// Only `effort_limit` is fitted; the line parameters start unlimited. The diagnosis scans
    /// torque levels (percentiles 80–99.8 of the servo torque) for the one whose excess explains
    /// the residual best: a limit reached rarely acts only in the few largest torques. The probe
    /// starts at that level.
    ///
    /// ## Simulation
    /// hook: servo torque clipped to the DC-motor line ∩ ±effort
    ///
    /// ## Signature
    /// `sign(τ)·max(|τ| − T, 0)` (error growing beyond a torque level T, the best of the
    /// percentiles 80, 90, 95, 98, 99, 99.5, 99.8 of |τ|)
    ///
    /// ## Evidence
    /// `tau_level` (T, the probe's start), `tau_percentile`
    ///
    /// ## Write-back
    /// actuator `forcelimited="true" forcerange="-e e"`
    ///
    /// ## Isaac Lab / mjlab
    /// `effort_limit` field
    pub TorqueLimit {
        id: "torque_limit",
        entry: Torque,
        params: [
            ParamDef { name: "effort_limit", unit: "N·m", lo: 0.05, hi: 50.0, default: 50.0 },
            ParamDef { name: "saturation_effort", unit: "N·m", lo: 0.05, hi: 1e4, default: 1e4 },
            ParamDef { name: "velocity_limit", unit: "rad/s", lo: 0.5, hi: 1e4, default: 1e4 },
        ],
    }
}

/// Evidence: the torque level whose excess explains the residual best [N·m].
const TAU_LEVEL: &str = "tau_level";
/// Evidence: that level's percentile of |servo torque|.
const TAU_PERCENTILE: &str = "tau_percentile";
/// Evidence: the 95th and 99th percentiles of |servo torque| [N·m] (probe levels).
const TAU_P95: &str = "tau_p95";
const TAU_P99: &str = "tau_p99";
/// Percentiles of |τ| scanned for the saturation level.
const LEVELS: [f64; 7] = [0.8, 0.9, 0.95, 0.98, 0.99, 0.995, 0.998];

impl Effect for TorqueLimit {
    fn fitted(&self) -> usize {
        1
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { q, qd, io, p, .. } = cx;
        let raw = servo_torque(q, qd, io);
        let (e, sat, vl) = (p[0].max(0.0), p[1].max(0.0), p[2].max(1e-6));
        let hi = (sat * (1.0 - qd / vl)).clamp(0.0, e);
        let lo = (sat * (-1.0 - qd / vl)).clamp(-e, 0.0);
        io.tau += raw.clamp(lo, hi) - raw;
    }
    fn signature(&self, s: &Samples) -> Signature {
        let abs: Vec<f64> = s.tau.iter().map(|x| x.abs()).collect();
        let excess =
            |t: f64| s.tau.iter().map(|x| x.signum() * (x.abs() - t).max(0.0)).collect::<Vec<_>>();
        // The level whose excess explains the most (ties: the lower percentile, scanned first).
        let mut best: Option<(f64, f64, f64, Vec<f64>)> = None;
        for p in LEVELS {
            let t = percentile(&abs, p);
            let f = excess(t);
            let (_, ems, _) = explain(&s.r, &f, false);
            if best.as_ref().is_none_or(|b| ems > b.0) {
                best = Some((ems, p, t, f));
            }
        }
        let (_, p, t, f) = best.unwrap_or((0.0, LEVELS[0], 0.0, excess(0.0)));
        let evidence = vec![
            (TAU_LEVEL, t),
            (TAU_PERCENTILE, p),
            (TAU_P95, percentile(&abs, 0.95)),
            (TAU_P99, percentile(&abs, 0.99)),
        ];
        Signature { evidence, ..Signature::centred(f) }
    }
    /// Limits at the diagnosed torque level and at the 95th and 99th percentiles (a step of the
    /// unlimited default would change nothing; a limit reached rarely shows only in the
    /// dynamics after each saturation, which the pointwise signature scan can miss).
    fn probes(
        &self,
        _start: f64,
        lo: f64,
        _hi: f64,
        evidence: &BTreeMap<String, f64>,
    ) -> Vec<f64> {
        let mut v: Vec<f64> = [TAU_LEVEL, TAU_P95, TAU_P99]
            .iter()
            .filter_map(|k| evidence.get(*k).copied())
            .filter(|v| *v > lo)
            .collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Actuator(vec![("forcerange", p[0])])
    }
    fn actuator_attr(
        &self,
        _attr: &'static str,
        v: f64,
        _act: &ActuatorSite,
    ) -> Result<Vec<(&'static str, String)>, String> {
        Ok(vec![("forcelimited", "true".into()), ("forcerange", format!("{} {}", num(-v), num(v)))])
    }
    fn isaaclab(&self, params: &BTreeMap<String, f64>, _timestep: f64) -> IsaacLab {
        IsaacLab::Field(format!(
            "effort_limit={},  # N·m",
            num(named(params, Self::META.params[0].name))
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probes are the diagnosed levels above the lower bound, sorted, without repeats.
    #[test]
    fn probes_are_the_torque_levels() {
        let (lo, hi) = (TorqueLimit::META.params[0].lo, TorqueLimit::META.params[0].hi);
        let ev = |a: f64, b: f64, c: f64| {
            BTreeMap::from([
                (TAU_LEVEL.to_string(), a),
                (TAU_P95.to_string(), b),
                (TAU_P99.to_string(), c),
            ])
        };
        assert_eq!(TorqueLimit.probes(hi, lo, hi, &ev(2.5, 3.0, 4.0)), vec![2.5, 3.0, 4.0]);
        assert_eq!(TorqueLimit.probes(hi, lo, hi, &ev(3.0, 3.0, 4.0)), vec![3.0, 4.0]);
        assert_eq!(TorqueLimit.probes(hi, lo, hi, &ev(lo, lo, 1.0)), vec![1.0]);
        assert!(TorqueLimit.probes(hi, lo, hi, &BTreeMap::new()).is_empty());
    }

    /// A limit reached only by the largest 1 % of torques is diagnosed at a high level, not at
    /// the 80th percentile (where its feature would be mostly noise).
    #[test]
    fn rare_saturation_picks_a_high_level() {
        let n = 2000;
        let tau: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() * (1.0 + (i % 97) as f64 / 97.0)).collect();
        let mut abs: Vec<f64> = tau.iter().map(|x| x.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let limit = abs[(0.99 * n as f64) as usize];
        // Residual: the torque lost above the limit, as a stiff servo shows it (r ≈ −Δτ/kp).
        let r: Vec<f64> = tau.iter().map(|t| -t.signum() * (t.abs() - limit).max(0.0) / 2.0).collect();
        let s = Samples {
            recs: &[],
            eps: &[],
            joint: "j",
            r,
            qd: vec![0.0; n],
            qdd: vec![0.0; n],
            u: vec![0.0; n],
            tau,
            qrel: vec![0.0; n],
            at: vec![],
            qd_rms: 1.0,
            u_rms: 1.0,
        };
        let sig = TorqueLimit.signature(&s);
        let ev: BTreeMap<_, _> = sig.evidence.into_iter().collect();
        assert!(ev[TAU_PERCENTILE] >= 0.98, "percentile {}", ev[TAU_PERCENTILE]);
        assert!((ev[TAU_LEVEL] - limit).abs() < 0.1 * limit, "level {} for {limit}", ev[TAU_LEVEL]);
    }
}
