use super::*;
use crate::declare_effect;
use crate::sim2real::metrics::interp_at;

declare_effect! {
    /// Transport delay between the policy's command and the servo (bus, firmware, filtering).
    ///
    /// The servo acts on the command issued `delay_s` earlier: a FIFO of the held targets, one
    /// entry per physics step; fractional delays interpolate linearly between steps.
    ///
    /// ## Simulation
    /// command FIFO per physics step, linear interpolation for fractional steps
    ///
    /// ## Signature
    /// `q_sim(t−L) − q_sim(t)`, L at the cross-correlation peak (0–100 ms)
    ///
    /// ## Evidence
    /// `lag_s` (L)
    ///
    /// ## Write-back
    /// actuator `delay="…" nsample="round(delay/timestep)"`
    ///
    /// ## Isaac Lab / mjlab
    /// comment: the delay in physics steps for `DelayedPDActuatorCfg(min_delay, max_delay)`
    pub ActionDelay {
        id: "action_delay",
        entry: Command,
        params: [ParamDef { name: "delay_s", unit: "s", lo: 0.0, hi: 0.1, default: 0.0 }],
    }
}

/// Evidence: the lag of the best-fitting delayed trajectory [s].
const LAG: &str = "lag_s";

impl Effect for ActionDelay {
    /// An actuator's command is what is delayed: a joint no actuator drives (a passive joint,
    /// coupled to a driven one by an equality or a tendon) has none.
    fn acts_on(&self, t: &JointTarget) -> bool {
        t.driven()
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { st, io, dt, p, .. } = cx;
        let d = (p[0].max(0.0) / dt).min(1e5);
        st.fifo.push_back(io.ctrl);
        let k = d.floor() as usize;
        let a = d - k as f64;
        let len = st.fifo.len();
        let at = |back: usize| st.fifo[len - 1 - back.min(len - 1)];
        io.ctrl = (1.0 - a) * at(k) + a * at(k + 1);
        while st.fifo.len() > k + 2 {
            st.fifo.pop_front();
        }
    }
    fn smooth(&self) -> bool {
        true
    }
    /// At its start no delay: the command of the step itself.
    fn neutral_start(&self) -> bool {
        true
    }
    /// The lag L ∈ [0, 100 ms] (1 ms steps) whose q_sim(t − L) − q_sim(t) fits r best.
    fn signature(&self, s: &Samples) -> Signature {
        let mut best = (0.0, f64::INFINITY, Vec::new());
        for l in 0..=100 {
            let lag = l as f64 * 1e-3;
            let f: Vec<f64> =
                s.at.iter()
                    .map(|&(e, i)| {
                        let k = s.recs[e].joints.iter().position(|j| j.name == s.joint).unwrap();
                        let ep = &s.eps[e];
                        interp_at(&ep.t, &ep.q_sim[k], ep.t[i] - lag) - ep.q_sim[k][i]
                    })
                    .collect();
            let sse: f64 = s.r.iter().zip(&f).map(|(r, f)| (r - f).powi(2)).sum();
            if sse < best.1 {
                best = (lag, sse, f);
            }
        }
        let (lag, _, feature) = best;
        Signature { feature, raw: true, evidence: vec![(LAG, lag)], implied: None }
    }
    fn shown_evidence(&self) -> &'static [&'static str] {
        &[LAG]
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Actuator(vec![("delay", p[0])])
    }
    fn actuator_attr(
        &self,
        _attr: &'static str,
        v: f64,
        act: &ActuatorSite,
    ) -> Result<Vec<(&'static str, String)>, String> {
        let n = (v / act.timestep).round().max(1.0) as i64;
        Ok(vec![("delay", num(v)), ("nsample", n.to_string())])
    }
    fn isaaclab(&self, params: &BTreeMap<String, f64>, timestep: f64) -> IsaacLab {
        let d = named(params, Self::META.params[0].name);
        let steps = (d / timestep).round();
        IsaacLab::Comment(format!(
            "# action delay {} s = {} physics steps of {} s: DelayedPDActuatorCfg(min_delay={}, max_delay={})",
            num(d),
            num(steps),
            num(timestep),
            num(steps),
            num(steps)
        ))
    }
}
