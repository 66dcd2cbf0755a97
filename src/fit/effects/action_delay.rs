//! Action delay: the servo acts on the command issued `delay_s` earlier. A FIFO of the held
//! targets, one entry per physics step; fractional delays interpolate linearly between steps.
use super::*;

pub struct ActionDelay;

const P: &[ParamDef] = &[ParamDef { name: "delay_s", unit: "s", lo: 0.0, hi: 0.1, default: 0.0 }];

impl Effect for ActionDelay {
    fn id(&self) -> &'static str {
        "action_delay"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Command
    }
    fn describe(&self) -> &'static str {
        "transport delay between the policy's command and the servo (bus, firmware, filtering)"
    }
    fn torque(
        &self,
        st: &mut EffectState,
        _q: f64,
        _qd: f64,
        _q_target: f64,
        io: &mut StepIo,
        dt: f64,
        p: &[f64],
    ) {
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
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Actuator(vec![("delay", p[0])])
    }
}
