use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::probe::impulse::{DIVERGED, StepResponse, measured_map};
use crate::probe::{Claim, ImpulseResponse, Preconditions, Verdict};
use crate::rules::control::underdamped_pd_gains::{GainSource, pd_joints};
use crate::rules::{Context, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every PD-controlled joint, compares ω_n·dt (ω_n = √(kp/I), I = the joint's diagonal
    /// mass-matrix entry at the keyframe, dt = `<option timestep>`) with the stability bound of
    /// the integrator. The stiffness term kp is integrated explicitly by every MuJoCo integrator,
    /// so the undamped bound is `max_omega_dt` (2 for semi-implicit Euler). `Euler` also treats
    /// the actuator's kv explicitly, which shrinks the bound to max_omega_dt·(√(ζ²+1) − ζ);
    /// `RK4` extends it by √2; `implicit`/`implicitfast` integrate damping implicitly and keep
    /// the undamped bound. Above the bound → error; above `accuracy_fraction` of it → warning.
    ///
    /// ## Why is this bad?
    /// Beyond the bound the joint diverges numerically (the simulation explodes or chatters);
    /// near it the discrete-time response is far from the continuous one, so the policy trains on
    /// dynamics no hardware has.
    ///
    /// ## How it is confirmed
    /// Probe `impulse-response`: the joint is kicked at the keyframe and the response checked for
    /// growth (unstable) or for a period/decay far from the continuous prediction.
    ///
    /// ## How to fix
    /// Lower the timestep until ω_n·dt is well inside the bound, lower kp, or add the joint's
    /// real reflected inertia (armature) if it is missing. Prefer `implicitfast` with stiff PD.
    pub GainsUnstableForTimestep {
        id: "gains-unstable-for-timestep",
        group: "control",
        level: Severity::Error,
        probe: ImpulseResponse,
        options: [
            opt("max_omega_dt", 2.0, "", "stability bound on ω_n·dt for explicit stiffness (undamped)"),
            opt("accuracy_fraction", 0.5, "", "warn above this fraction of the bound (loss of accuracy)"),
        ],
    }
}

/// What the `impulse-response` probe checks: the integrated step response diverges, or its
/// natural frequency is more than 10 % off the analytic one.
#[derive(Debug)]
pub struct DistortedByTimestep {
    pub joint: usize,
    /// The analytic ω_n of the finding, rad/s.
    pub omega_n: f64,
}

impl Claim for DistortedByTimestep {
    type Probe = ImpulseResponse;
    fn key(&self, _: &Loaded) -> Result<usize, &'static str> {
        Ok(self.joint)
    }
    fn judge(&self, _: &Loaded, r: &StepResponse) -> Verdict {
        let m = measured_map(r);
        let pre = r.preconditions();
        if r.diverged {
            return Verdict::confirmed(&Preconditions::new(), m, DIVERGED);
        }
        let p = self.omega_n;
        match r.omega_n {
            // A distorted response need not follow the step or decay: that is the consequence
            // claimed. It must still be the servo's response (no dry friction, clear of stops).
            Some(w) if ((w - p) / p).abs() > 0.1 => Verdict::confirmed(
                &r.dynamics_preconditions(),
                m,
                format!(
                    "integration distorts the response: measured ω_n = {} rad/s vs {} rad/s analytic",
                    fmt_num(w, 3),
                    fmt_num(p, 3)
                ),
            ),
            _ => Verdict::refuted_or_inconclusive(
                &pre,
                m,
                format!("stable and accurate step response (ζ = {})", r.zeta_text()),
            ),
        }
    }
}

/// Stability bound on ω_n·dt for integrator `integrator` with explicitly integrated damping
/// ratio `zeta_explicit` (only MuJoCo's Euler treats actuator kv explicitly).
pub fn omega_dt_bound(integrator: i32, base: f64, zeta_explicit: f64) -> f64 {
    match integrator {
        // Semi-implicit Euler with explicit damping: stable iff (ωh)² + 4ζωh < 4.
        0 => base * ((zeta_explicit * zeta_explicit + 1.0).sqrt() - zeta_explicit),
        // RK4: stability interval on the imaginary axis is 2√2.
        1 => base * std::f64::consts::SQRT_2,
        _ => base,
    }
}

fn integrator_name(i: i32) -> &'static str {
    match i {
        0 => "Euler",
        1 => "RK4",
        2 => "implicit",
        3 => "implicitfast",
        _ => "unknown",
    }
}

impl Rule for GainsUnstableForTimestep {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let dt = cx.robot.opt.timestep;
        let integ = cx.robot.opt.integrator;
        let (base, frac) = (cx.opt("max_omega_dt"), cx.opt("accuracy_fraction"));
        for p in pd_joints(cx.robot, cx.spec) {
            let w = p.omega_n();
            let wdt = w * dt;
            // Euler integrates joint damping implicitly but actuator kv explicitly.
            let zeta_explicit =
                if integ == 0 { p.kd_ctrl / (2.0 * (p.kp * p.inertia).sqrt()) } else { 0.0 };
            let bound = omega_dt_bound(integ, base, zeta_explicit);
            let unstable = wdt >= bound;
            if !(unstable || wdt > frac * bound) {
                continue;
            }
            let j = &cx.robot.joints[p.joint];
            let msg = if unstable {
                format!(
                    "joint `{}` is numerically unstable: ω_n·dt = {} (ω_n {} rad/s, dt {} s) ≥ {} bound {}",
                    j.name,
                    fmt_num(wdt, 3),
                    fmt_num(w, 4),
                    fmt_num(dt, 3),
                    integrator_name(integ),
                    fmt_num(bound, 3)
                )
            } else {
                format!(
                    "joint `{}` is close to the {} stability bound: ω_n·dt = {} (ω_n {} rad/s, dt {} s), bound {}",
                    j.name,
                    integrator_name(integ),
                    fmt_num(wdt, 3),
                    fmt_num(w, 4),
                    fmt_num(dt, 3),
                    fmt_num(bound, 3)
                )
            };
            let mut f = match p.source {
                GainSource::Actuator(aid) => {
                    let a = &cx.robot.actuators[aid];
                    cx.at_attr(ElemKind::Actuator, aid, &a.name, "kp", msg)
                }
                GainSource::SpecMotor(_) => cx.at_elem(ElemKind::Joint, j.id, &j.name, msg),
            };
            if !unstable && cx.level == cx.meta.default_level {
                f.severity = Severity::Warning;
            }
            let dt_ok = frac * bound / w;
            f = f
                .note(format!(
                    "kp {} N·m/rad against I {} kg·m² (armature {} kg·m²) is integrated explicitly; {}",
                    fmt_num(p.kp, 4),
                    fmt_num(p.inertia, 4),
                    fmt_num(p.armature, 4),
                    if unstable {
                        "past the bound the joint's response grows each step and the simulation blows up"
                    } else {
                        "this close to the bound the discrete response is far from the continuous one, so the policy trains on dynamics the hardware does not have"
                    }
                ))
                .help(if integ == 0 {
                    format!(
                        "switch to integrator=\"implicitfast\" (it integrates the actuator's kv implicitly), or lower the timestep to ≤ {} s",
                        fmt_num(dt_ok, 3)
                    )
                } else {
                    format!(
                        "lower the timestep to ≤ {} s, or lower kp to ≤ {} N·m/rad",
                        fmt_num(dt_ok, 3),
                        fmt_num((frac * bound / dt).powi(2) * p.inertia, 4)
                    )
                })
                .label(format!("ω_n·dt = {}", fmt_num(wdt, 3)))
                .subject(Subject::Joint(j.id))
                .claim(DistortedByTimestep { joint: j.id, omega_n: w })
                .measured(wdt, "")
                .expected(bound, "")
                .with("omega_n", w)
                .with("dt", dt)
                .with("bound", bound)
                .with("kp", p.kp)
                .with("inertia", p.inertia);
            out.push(f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn bounds() {
        assert!((omega_dt_bound(3, 2.0, 0.0) - 2.0).abs() < 1e-12);
        assert!((omega_dt_bound(1, 2.0, 0.0) - 2.0 * 2f64.sqrt()).abs() < 1e-12);
        // Euler with ζ = 1 explicit: 2(√2 − 1).
        let b = omega_dt_bound(0, 2.0, 1.0);
        assert!((b - 2.0 * (2f64.sqrt() - 1.0)).abs() < 1e-12);
        // On the bound, (ωh)² + 4ζωh = 4.
        assert!((b * b + 4.0 * b - 4.0).abs() < 1e-12);
    }
}
