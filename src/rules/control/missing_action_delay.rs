use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// When the spec gives the hardware's action delay (`robot.action_delay_steps = [min, max]`
    /// control steps at `robot.control_hz`), checks that the model delays its actuators
    /// (`<actuator delay>` in seconds, MuJoCo ≥ 3.17): reports a model with no delayed actuator
    /// at all, and actuators whose delay exceeds the hardware's maximum.
    ///
    /// ## Why is this bad?
    /// The real firmware and bus delay every command by up to `max` control periods. A policy
    /// trained without that latency reacts to state it will not see in time on hardware and
    /// oscillates or falls; the delay is part of the identified system (Asimov system identification §4–5). A delay
    /// longer than the hardware's makes the policy needlessly sluggish.
    ///
    /// ## How it is confirmed
    /// Static: compares the compiled `actuator_delay` with the spec. (If the training stack applies
    /// the delay itself, suppress this finding with the reason.)
    ///
    /// ## How to fix
    /// Add `delay="<max_steps / control_hz>"` to the actuators (or their default class), or model
    /// the randomised delay in the training stack and suppress this rule with that reason.
    pub MissingActionDelay { id: "missing-action-delay", group: "control", level: Severity::Warning, probe: None, options: [] }
}

impl Rule for MissingActionDelay {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let Some(spec) = cx.spec else { return };
        let (Some(steps), Some(hz)) = (&spec.robot.action_delay_steps, &spec.robot.control_hz)
        else {
            return;
        };
        let [lo, hi] = *steps.get_ref();
        let hz = *hz.get_ref();
        if !(hi > 0.0) || cx.robot.actuators.is_empty() {
            return;
        }
        let (lo_s, hi_s) = (lo / hz, hi / hz);
        let spec_loc = spec.loc(steps.span());
        let spec_text = format!(
            "spec: {}–{} control steps at {} Hz = {}–{} ms",
            fmt_num(lo, 3),
            fmt_num(hi, 3),
            fmt_num(hz, 4),
            fmt_num(lo_s * 1e3, 3),
            fmt_num(hi_s * 1e3, 3)
        );
        let delayed: Vec<_> = cx.robot.actuators.iter().filter(|a| a.delay > 0.0).collect();
        if delayed.is_empty() {
            let a = &cx.robot.actuators[0];
            let f = cx
                .at_elem(
                    ElemKind::Actuator,
                    a.id,
                    &a.name,
                    format!(
                        "no actuator has an action delay, but the hardware delays commands by up to {} ms ({} control steps at {} Hz)",
                        fmt_num(hi_s * 1e3, 3),
                        fmt_num(hi, 3),
                        fmt_num(hz, 4)
                    ),
                )
                .label("delay = 0 on all actuators")
                .secondary(spec_loc, spec_text)
                .note("a policy trained without the real command latency reacts to state it will not see in time on hardware; the delay is part of the identified system (Asimov system identification §5)")
                .help(format!(
                    "add delay=\"{}\" (seconds, with nsample for the history buffer) to the actuators' default class, or randomise the delay in {}–{} ms in the training stack and suppress this finding with that reason",
                    fmt_num(hi_s, 3),
                    fmt_num(lo_s * 1e3, 3),
                    fmt_num(hi_s * 1e3, 3)
                ))
                .subject(Subject::Model)
                .measured(0.0, "s")
                .expected(hi_s, "s")
                .with("expected_delay_s", hi_s);
            out.push(f);
            return;
        }
        let tol = 1e-9 + 1e-6 * hi_s;
        let too_long: Vec<_> = delayed.iter().filter(|a| a.delay > hi_s + tol).collect();
        let Some(first) = too_long.first() else { return };
        let names: Vec<&str> = too_long.iter().map(|a| a.name.as_str()).collect();
        let max = too_long.iter().map(|a| a.delay).fold(0.0, f64::max);
        let f = cx
            .at_attr(
                ElemKind::Actuator,
                first.id,
                &first.name,
                "delay",
                format!(
                    "actuator delay {} ms exceeds the hardware's maximum {} ms on {} actuator(s): {}",
                    fmt_num(max * 1e3, 3),
                    fmt_num(hi_s * 1e3, 3),
                    too_long.len(),
                    names.join(", ")
                ),
            )
            .label(format!("delay = {} s", fmt_num(first.delay, 3)))
            .secondary(spec_loc, spec_text)
            .note("a longer delay than the hardware's trains a needlessly sluggish policy that under-uses the real bandwidth")
            .help(format!("set delay ≤ {} s", fmt_num(hi_s, 3)))
            .subject(Subject::Actuator(first.id))
            .measured(max, "s")
            .expected(hi_s, "s")
            .with("expected_delay_s", hi_s);
        out.push(f);
    }
}
