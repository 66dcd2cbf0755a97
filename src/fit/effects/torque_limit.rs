use super::*;
use crate::declare_effect;
use crate::fit::diagnose::percentile;

declare_effect! {
    /// Motor torque saturation (peak torque, torque–speed line).
    ///
    /// DC-motor torque–speed line: the servo torque is clipped to
    /// [sat·(−1 − q̇/v_lim), sat·(1 − q̇/v_lim)] ∩ [−effort, effort] (Isaac Lab's DCMotor law).
    /// Only `effort_limit` is fitted; the line parameters start unlimited. The diagnosis's probe
    /// starts at the 80th percentile of the servo torque.
    ///
    /// ## Simulation
    /// hook: servo torque clipped to the DC-motor line ∩ ±effort
    ///
    /// ## Signature
    /// `sign(τ)·max(|τ| − P80|τ|, 0)` (error growing beyond a torque level)
    ///
    /// ## Evidence
    /// `tau_p80` (P80 |τ|, the probe's start)
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

/// Evidence: the 80th percentile of |servo torque| [N·m].
const TAU_P80: &str = "tau_p80";

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
        let p80 = percentile(&s.tau.iter().map(|x| x.abs()).collect::<Vec<_>>(), 0.8);
        let sat = s.tau.iter().map(|t| t.signum() * (t.abs() - p80).max(0.0)).collect();
        Signature { evidence: vec![(TAU_P80, p80)], ..Signature::centred(sat) }
    }
    /// A limit at the 80th percentile of the servo torque (a step of the unlimited default would
    /// change nothing).
    fn probe(
        &self,
        _start: f64,
        lo: f64,
        _hi: f64,
        evidence: &BTreeMap<String, f64>,
    ) -> Option<f64> {
        evidence.get(TAU_P80).copied().filter(|v| *v > lo)
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

    /// The probe starts at P80 |τ| when that is above the lower bound, else not at all.
    #[test]
    fn probe_starts_at_the_torque_percentile() {
        let (lo, hi) = (TorqueLimit::META.params[0].lo, TorqueLimit::META.params[0].hi);
        let ev = |v: f64| BTreeMap::from([(TAU_P80.to_string(), v)]);
        assert_eq!(TorqueLimit.probe(hi, lo, hi, &ev(2.5)), Some(2.5));
        assert_eq!(TorqueLimit.probe(hi, lo, hi, &ev(lo)), None);
        assert_eq!(TorqueLimit.probe(hi, lo, hi, &BTreeMap::new()), None);
    }
}
