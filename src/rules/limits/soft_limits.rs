use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, ProbeStatus, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::model::{ActuatorKind, JointType, Transmission};
use crate::probe::limit::LimitHit;
use crate::probe::{Claim, LimitApproach, Verdict};
use crate::rules::{Context, Rule, RuleMeta, claim_each, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Checks the training range of every position actuator on a hinge or slide joint: its
    /// `ctrlrange` should be the spec's `robot.soft_limit_factor` (default 0.9) × the joint's
    /// hardware `range`, centred on it. Without a spec it still reports a ctrlrange that covers
    /// the whole joint range (or is unlimited), which lets the policy command the hard stops. It
    /// also reports an actuated hinge/slide joint with no range at all. Actuators that share the
    /// problem through one `<default class>` are reported once.
    ///
    /// ## Why is this bad?
    /// Training is meant to use soft limits, typically 0.9 of the hardware range (Asimov system identification §8):
    /// commanding the hard stops produces hard-stop impacts, exploitation of boundary states and
    /// shock loads near the limits on the real robot.
    ///
    /// ## How it is confirmed
    /// Probe `limit-approach`: the actuator is commanded to the ends of its ctrlrange and the
    /// probe checks whether the joint reaches its hard stop (constraint force at the limit).
    ///
    /// ## How to fix
    /// Set `ctrlrange` to the centred soft range given in the help (or
    /// `inheritrange="<factor>"` on the position actuator), and give every actuated joint its
    /// hardware `range`.
    pub SoftLimits {
        id: "soft-limits",
        group: "limits",
        level: Severity::Warning,
        probe: LimitApproach,
        options: [opt("tolerance", 0.02, "fraction of joint range", "allowed deviation of each ctrlrange end from the soft range")],
    }
}

fn unit(t: JointType) -> &'static str {
    if t == JointType::Slide { "m" } else { "rad" }
}

fn rng(r: [f64; 2], u: &str) -> String {
    format!("[{}, {}] {u}", fmt_num(r[0], 4), fmt_num(r[1], 4))
}

/// What the `limit-approach` probe checks: commanding the actuator's ctrlrange extremes drives
/// its joint into the hard stop.
#[derive(Debug)]
pub struct ReachesHardStop {
    pub actuator: usize,
}

impl Claim for ReachesHardStop {
    type Probe = LimitApproach;
    fn key(&self, _: &Loaded) -> Result<usize, &'static str> {
        Ok(self.actuator)
    }
    fn judge(&self, _: &Loaded, h: &LimitHit) -> Verdict {
        let m = BTreeMap::from([
            ("hit".to_string(), if h.hit { 1.0 } else { 0.0 }),
            ("impact_velocity".to_string(), h.impact_velocity),
            ("max_limit_force".to_string(), h.max_limit_force),
        ]);
        if h.hit {
            Verdict::new(
                ProbeStatus::Confirmed,
                m,
                format!(
                    "commanding the ctrlrange extreme drove the joint into its hard stop at {} rad/s (limit force up to {} N·m)",
                    fmt_num(h.impact_velocity, 3),
                    fmt_num(h.max_limit_force, 3)
                ),
            )
        } else {
            Verdict::new(
                ProbeStatus::Refuted,
                m,
                "the commanded extremes never reached the hard stop",
            )
        }
    }
}

/// Attaches [`ReachesHardStop`] to the findings about one actuator.
pub fn claim_hard_stops(findings: &mut [Finding]) {
    claim_each(findings, |f| match f.subject {
        Subject::Actuator(actuator) => Some(ReachesHardStop { actuator }),
        _ => None,
    });
}

impl Rule for SoftLimits {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let first = out.len();
        self.check_ranges(cx, out);
        claim_hard_stops(&mut out[first..]);
    }
}

impl SoftLimits {
    fn check_ranges(&self, cx: &Context, out: &mut Vec<Finding>) {
        let tol = cx.opt("tolerance");
        let factor = cx.spec.map(|s| s.soft_limit_factor());
        let factor_loc =
            cx.spec.and_then(|s| s.robot.soft_limit_factor.as_ref().map(|f| s.loc(f.span())));
        // Findings that come from one default-class attribute are merged: key = span of the value.
        let mut groups: BTreeMap<(usize, usize, usize, u8), Vec<Finding>> = BTreeMap::new();
        for j in cx.robot.joints.iter().filter(|j| j.is_scalar()) {
            let acts = cx.robot.actuators_on_joint(j.id);
            if acts.is_empty() {
                continue;
            }
            let u = unit(j.jtype);
            if !j.limited {
                let a = acts[0];
                let f = cx
                    .at_elem(ElemKind::Joint, j.id, &j.name, format!("actuated joint `{}` has no range (limited=\"false\")", j.name))
                    .label("no range")
                    .note("without a hardware range the simulated joint can turn past the real robot's hard stops, and no soft training range can be derived")
                    .help("give the joint its hardware range=\"lo hi\" (and limited=\"true\" if autolimits is off)")
                    .subject(Subject::Actuator(a.id));
                out.push(f);
                continue;
            }
            for a in acts {
                if !matches!(a.kind, ActuatorKind::Position { .. })
                    || !matches!(a.trn, Transmission::Joint | Transmission::JointInParent)
                {
                    continue;
                }
                // A ctrlrange written in degrees is its own finding (ctrlrange-in-degrees).
                if super::ctrlrange_in_degrees::looks_like_degrees(cx.robot, a, 0.05) {
                    continue;
                }
                let g = if a.gear != 0.0 { a.gear } else { 1.0 };
                // Position target is in actuator length = gear·q; refer it to the joint.
                let c = if a.ctrllimited {
                    let (x, y) = (a.ctrlrange[0] / g, a.ctrlrange[1] / g);
                    [x.min(y), x.max(y)]
                } else {
                    [f64::NEG_INFINITY, f64::INFINITY]
                };
                let r = j.range;
                let span = r[1] - r[0];
                let eps = 1e-9 * span.max(1.0);
                let mid = 0.5 * (r[0] + r[1]);
                let covers = c[0] <= r[0] + eps && c[1] >= r[1] - eps;
                let exp = factor.map(|fct| [mid - 0.5 * fct * span, mid + 0.5 * fct * span]);
                let dev = exp.map(|e| ((c[0] - e[0]).abs()).max((c[1] - e[1]).abs()) / span);
                let within_spec = dev.is_some_and(|d| d <= tol);
                let (kind, msg) = if !a.ctrllimited {
                    (
                        0u8,
                        format!(
                            "position actuator `{}` has no ctrlrange: the policy can command any target on joint `{}` (range {})",
                            a.name,
                            j.name,
                            rng(r, u)
                        ),
                    )
                } else if covers && !within_spec {
                    let wider = c[0] < r[0] - eps || c[1] > r[1] + eps;
                    (
                        1,
                        format!(
                            "position actuator `{}` ctrlrange {} {} joint `{}`'s hardware range {}",
                            a.name,
                            rng(c, u),
                            if wider { "is wider than" } else { "equals" },
                            j.name,
                            rng(r, u)
                        ),
                    )
                } else if let (Some(e), Some(d)) = (exp, dev) {
                    if d <= tol {
                        continue;
                    }
                    (
                        2,
                        format!(
                            "position actuator `{}` ctrlrange {} is not the soft range {} ({} × joint `{}` range {}, centred)",
                            a.name,
                            rng(c, u),
                            rng(e, u),
                            fmt_num(factor.unwrap_or(0.9), 3),
                            j.name,
                            rng(r, u)
                        ),
                    )
                } else {
                    continue;
                };
                let attr = if cx.robot.elem(ElemKind::Actuator, a.id, &a.name).is_some_and(|e| {
                    !e.attrs.contains_key("ctrlrange") && e.attrs.contains_key("inheritrange")
                }) {
                    "inheritrange"
                } else {
                    "ctrlrange"
                };
                let fct = factor.unwrap_or(0.9);
                let soft = exp.unwrap_or([mid - 0.5 * fct * span, mid + 0.5 * fct * span]);
                let mut f = cx
                    .at_attr(ElemKind::Actuator, a.id, &a.name, attr, msg)
                    .note("training should use soft limits inside the hardware range (typically 0.9 of it, Asimov system identification §8); commanding the hard stops trains hard-stop impacts and boundary exploitation that shock-load the real joints")
                    .help(format!(
                        "set ctrlrange=\"{} {}\" ({} × range, centred), or inheritrange=\"{}\"",
                        fmt_num(soft[0] * g, 4),
                        fmt_num(soft[1] * g, 4),
                        fmt_num(fct, 3),
                        fmt_num(fct, 3)
                    ))
                    .label(if a.ctrllimited { format!("ctrlrange {}", rng(c, u)) } else { "unlimited".into() })
                    .subject(Subject::Actuator(a.id))
                    .with("ctrl_lo", c[0])
                    .with("ctrl_hi", c[1])
                    .with("range_lo", r[0])
                    .with("range_hi", r[1])
                    .with("soft_lo", soft[0])
                    .with("soft_hi", soft[1]);
                if let (2, Some(loc)) = (kind, factor_loc) {
                    f = f.secondary(loc, format!("spec soft_limit_factor = {}", fmt_num(fct, 3)));
                }
                let (loc, class) = cx.robot.attr_loc(ElemKind::Actuator, a.id, &a.name, attr);
                let key = if class.is_some() {
                    (loc.file, loc.start, loc.end, kind)
                } else {
                    (usize::MAX, a.id, 0, kind)
                };
                groups.entry(key).or_default().push(f);
            }
        }
        for (_, mut fs) in groups {
            if fs.len() == 1 {
                out.extend(fs);
                continue;
            }
            let n = fs.len();
            let names: Vec<String> =
                fs.iter().map(|f| f.element.trim_start_matches("actuator ").to_string()).collect();
            let mut f = fs.remove(0);
            let what = match f.message.contains("no ctrlrange") {
                true => "have no ctrlrange".to_string(),
                false if f.message.contains("is not the soft range") => {
                    "are not at the spec's soft range".to_string()
                }
                false => "cover their joints' whole hardware range".to_string(),
            };
            f.help = Some(format!(
                "set each actuator's ctrlrange to the centred soft range, e.g. inheritrange=\"{}\" in the default class",
                fmt_num(factor.unwrap_or(0.9), 3)
            ));
            f.message = format!(
                "{n} position actuators {what} through one default class: {} (first: {})",
                names.join(", "),
                f.message
            );
            out.push(f);
        }
    }
}
