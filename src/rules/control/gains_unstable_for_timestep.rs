use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::probe::impulse::{DIVERGED, StepResponse, measured_map};
use crate::probe::{Claim, ImpulseResponse, Preconditions, Verdict};
use crate::rules::control::underdamped_pd_gains::{GainSource, pd_joints};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every PD-controlled joint, compares ω_n·dt (ω_n = √(kp/I), I = the joint's diagonal
    /// mass-matrix entry at the keyframe, dt = `<option timestep>`) with the stability bound of
    /// the integrator the compiled model uses, splitting the joint's damping the way MuJoCo
    /// integrates it. The stiffness term kp is explicit under every integrator. `Euler` solves
    /// the joint's own and its actuator's `damping` implicitly (unless
    /// `<flag eulerdamp="disable"/>`) and the actuator's kv, tendon damping and back-EMF explicitly; `implicit`/`implicitfast` solve kv
    /// and all damping implicitly; `RK4` is explicit throughout. With ζ_i and ζ_e the implicit
    /// and explicit damping ratios (against 2√(kp·I)) and Δ = ζ_i − ζ_e, semi-implicit Euler
    /// (the first three) is stable iff ω_n·dt < `max_omega_dt`·(Δ + √(Δ² + 1)) (2 undamped;
    /// implicit damping widens it, explicit damping narrows it); RK4 while its amplification
    /// |1 + z + z²/2 + z³/6 + z⁴/24| < 1 at both poles z = dt·ω_n(−ζ ± √(ζ² − 1)) (2√2
    /// undamped, found by a scan, scaled by `max_omega_dt`/2). Other integrators get the
    /// undamped bound. Above the bound → error; above `accuracy_fraction` of it → warning.
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
            opt("max_omega_dt", 2.0, "", Domain::POSITIVE, "stability bound on ω_n·dt of an undamped joint under semi-implicit Euler; the damped and RK4 bounds scale with it"),
            opt("accuracy_fraction", 0.5, "", Domain::POSITIVE_FRACTION, "warn above this fraction of the bound (loss of accuracy)"),
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

/// `mjDSBL_DAMPER`: passive damping forces are off.
const DSBL_DAMPER: i32 = 1 << 6;
/// `mjDSBL_EULERDAMP`: the Euler integrator no longer integrates joint damping implicitly.
const DSBL_EULERDAMP: i32 = 1 << 15;

/// How one PD joint's damping enters MuJoCo's step: the damping ratios (against √(kp·I)) that
/// the integrator treats implicitly (solves with the velocity it produces) and explicitly
/// (evaluates at the old velocity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DampingSplit {
    pub implicit: f64,
    pub explicit: f64,
}

/// The split MuJoCo's integrators make: `Euler` solves (M + h·diag(damping)) for the joint's own
/// and its actuator's `damping` (`own_damping`; unless `eulerdamp` is disabled) and evaluates
/// every other force, the actuator's kv, tendon damping and back-EMF included, at the old velocity; `implicit` and
/// `implicitfast` put every velocity derivative of the passive and actuator forces (kv and all
/// damping) in the implicit solve; `RK4` is explicit throughout. Other integrators: no damping
/// credited (the undamped bound).
pub fn damping_split(
    integrator: i32,
    disableflags: i32,
    kv: f64,
    own_damping: f64,
    other_damping: f64,
    crit: f64,
) -> DampingSplit {
    let (own, other) =
        if disableflags & DSBL_DAMPER != 0 { (0.0, 0.0) } else { (own_damping, other_damping) };
    let (implicit, explicit) = match integrator {
        0 if disableflags & DSBL_EULERDAMP == 0 => (own, kv + other),
        0 | 1 => (0.0, kv + own + other),
        2 | 3 => (kv + own + other, 0.0),
        _ => (0.0, 0.0),
    };
    DampingSplit { implicit: implicit / crit, explicit: explicit / crit }
}

/// Stability bound on ω_n·dt for integrator `integrator`, for a joint whose damping the
/// integrator splits as `z`. `base` is the undamped semi-implicit Euler bound (2); the other
/// bounds scale with it.
///
/// Semi-implicit Euler (`Euler`, `implicit`, `implicitfast`: kp is always explicit) steps
/// M(v₁ − v₀) = h(−k·x₀ − b_e·v₀ − b_i·v₁), x₁ = x₀ + h·v₁; its step matrix has determinant
/// (1 − 2ζ_e·ωh)/(1 + 2ζ_i·ωh) and is stable iff (ωh)² < 4 + 4(ζ_i − ζ_e)·ωh, i.e.
/// ωh < 2(Δ + √(Δ² + 1)) with Δ = ζ_i − ζ_e: implicit damping widens the bound, explicit
/// damping narrows it. `RK4` is stable while |R(λh)| < 1 for both poles λ of the damped joint,
/// R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 (2√2 undamped); the bound is found by a scan.
pub fn omega_dt_bound(integrator: i32, base: f64, z: DampingSplit) -> f64 {
    if integrator == 1 {
        return base / 2.0 * rk4_bound(z.explicit);
    }
    let d = z.implicit - z.explicit;
    base * (d + (d * d + 1.0).sqrt())
}

/// Smallest ω_n·h at which RK4 amplifies a mode of ẍ + 2ζω_n·ẋ + ω_n²·x = 0 (scan in steps of
/// 1e-3, then bisection). Every pole has |λ| ≥ ω_n·(ζ − √(ζ² − 1)) and RK4 is unstable beyond
/// |z| = 2.79 on any ray, so the bound is below 3.
fn rk4_bound(zeta: f64) -> f64 {
    let amp = |x: f64| -> f64 {
        // Poles of the normalised joint, ω_n = 1: −ζ ± √(ζ² − 1).
        let disc = zeta * zeta - 1.0;
        let poles: [(f64, f64); 2] = if disc >= 0.0 {
            [(-zeta + disc.sqrt(), 0.0), (-zeta - disc.sqrt(), 0.0)]
        } else {
            [(-zeta, (-disc).sqrt()), (-zeta, -(-disc).sqrt())]
        };
        poles
            .iter()
            .map(|&(re, im)| {
                let (a, b) = (re * x, im * x);
                // R(z) by Horner: 1 + z(1 + z/2(1 + z/3(1 + z/4))).
                let mut r = (1.0, 0.0);
                for k in [4.0, 3.0, 2.0, 1.0] {
                    let (zr, zi) = (a / k, b / k);
                    r = (1.0 + zr * r.0 - zi * r.1, zr * r.1 + zi * r.0);
                }
                (r.0 * r.0 + r.1 * r.1).sqrt()
            })
            .fold(0.0, f64::max)
    };
    // An undamped joint sits on |R| = 1 to within rounding near the origin: grows means
    // |R| > 1 by more than rounding.
    let grows = |x: f64| amp(x) > 1.0 + 1e-12;
    let step = 1e-3;
    let mut hi = step;
    while !grows(hi) && hi < 4.0 {
        hi += step;
    }
    let mut lo = hi - step;
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if grows(mid) { hi = mid } else { lo = mid }
    }
    0.5 * (lo + hi)
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
            let j = &cx.robot.joints[p.joint];
            // What Euler adds to M's diagonal: the joint's own damping and its actuator's
            // (checked against MuJoCo: an actuator-damped joint is stable past the explicit bound).
            let own: f64 = j
                .damping_parts
                .iter()
                .filter(|q| {
                    matches!(
                        q.source,
                        crate::model::PartSource::Joint | crate::model::PartSource::Actuator(..)
                    )
                })
                .map(|q| q.value)
                .sum();
            let split = damping_split(
                integ,
                cx.robot.opt.disableflags,
                p.kd_ctrl,
                own,
                p.kd - p.kd_ctrl - own,
                2.0 * (p.kp * p.inertia).sqrt(),
            );
            let bound = omega_dt_bound(integ, base, split);
            let unstable = wdt >= bound;
            if !(unstable || wdt > frac * bound) {
                continue;
            }
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
                    "kp {} N·m/rad against I {} kg·m² (armature {} kg·m²) is integrated explicitly; {} integrates damping ζ {} implicitly and ζ {} explicitly; {}",
                    fmt_num(p.kp, 4),
                    fmt_num(p.inertia, 4),
                    fmt_num(p.armature, 4),
                    integrator_name(integ),
                    fmt_num(split.implicit, 3),
                    fmt_num(split.explicit, 3),
                    if unstable {
                        "past the bound the joint's response grows each step and the simulation blows up"
                    } else {
                        "this close to the bound the discrete response is far from the continuous one, so the policy trains on dynamics the hardware does not have"
                    }
                ))
                // Explicit damping narrows the bound whatever kp is (RK4's fast pole is kd/I):
                // the cure is to integrate it implicitly.
                .help(if split.explicit > 0.0 && matches!(integ, 0 | 1) {
                    format!(
                        "switch to integrator=\"implicitfast\" (it integrates the actuator's kv and all damping implicitly), or lower the timestep to ≤ {} s",
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
                .with("zeta_implicit", split.implicit)
                .with("zeta_explicit", split.explicit)
                .with("kp", p.kp)
                .with("inertia", p.inertia);
            out.push(f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Growth of |x| over 2000 steps of the joint ẍ = −ω²x − 2ζ_e·ω·ẋ(old) − 2ζ_i·ω·ẋ(new),
    /// stepped as MuJoCo's semi-implicit Euler does (ω = 1, h = `x`), or by classic RK4 on
    /// the ODE with all damping explicit.
    fn growth(integrator: i32, wh: f64, z: DampingSplit) -> f64 {
        let (mut q, mut v) = (1.0f64, 0.0f64);
        let h = wh;
        let f = |q: f64, v: f64| -q - 2.0 * z.explicit * v;
        for _ in 0..2000 {
            if integrator == 1 {
                let k1 = (v, f(q, v));
                let k2 = (v + h / 2.0 * k1.1, f(q + h / 2.0 * k1.0, v + h / 2.0 * k1.1));
                let k3 = (v + h / 2.0 * k2.1, f(q + h / 2.0 * k2.0, v + h / 2.0 * k2.1));
                let k4 = (v + h * k3.1, f(q + h * k3.0, v + h * k3.1));
                q += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
                v += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
            } else {
                v = (v + h * f(q, v)) / (1.0 + 2.0 * z.implicit * h);
                q += h * v;
            }
        }
        q.abs().max(v.abs())
    }

    #[test]
    fn bounds_separate_growing_from_decaying_steps() {
        let cases = [
            (0, DampingSplit { implicit: 0.0, explicit: 0.0 }),
            (0, DampingSplit { implicit: 0.0, explicit: 1.0 }),
            // Allegro-like: joint damping 46 × critical, applied implicitly by Euler.
            (0, DampingSplit { implicit: 46.0, explicit: 0.0 }),
            (0, DampingSplit { implicit: 0.8, explicit: 0.3 }),
            (3, DampingSplit { implicit: 1.37, explicit: 0.0 }),
            (1, DampingSplit { implicit: 0.0, explicit: 0.0 }),
            (1, DampingSplit { implicit: 0.0, explicit: 0.5 }),
            (1, DampingSplit { implicit: 0.0, explicit: 3.0 }),
        ];
        for (integ, z) in cases {
            let b = omega_dt_bound(integ, 2.0, z);
            assert!(growth(integ, 0.98 * b, z) < 10.0, "{integ} {z:?}: stable below {b}");
            assert!(!(growth(integ, 1.02 * b, z) < 1e3), "{integ} {z:?}: unstable above {b}");
        }
        // Known values: undamped Euler 2, RK4 2√2; Euler with ζ = 1 explicit 2(√2 − 1).
        let none = DampingSplit { implicit: 0.0, explicit: 0.0 };
        assert!((omega_dt_bound(3, 2.0, none) - 2.0).abs() < 1e-12);
        assert!((omega_dt_bound(1, 2.0, none) - 2.0 * 2f64.sqrt()).abs() < 1e-9);
        let b = omega_dt_bound(0, 2.0, DampingSplit { implicit: 0.0, explicit: 1.0 });
        assert!((b - 2.0 * (2f64.sqrt() - 1.0)).abs() < 1e-12);
    }

    #[test]
    fn integrators_split_damping_as_mujoco_does() {
        let s = |i, fl| damping_split(i, fl, 2.0, 3.0, 5.0, 1.0);
        assert_eq!(s(0, 0), DampingSplit { implicit: 3.0, explicit: 7.0 });
        assert_eq!(s(0, DSBL_EULERDAMP), DampingSplit { implicit: 0.0, explicit: 10.0 });
        assert_eq!(s(1, 0), DampingSplit { implicit: 0.0, explicit: 10.0 });
        assert_eq!(s(2, 0), DampingSplit { implicit: 10.0, explicit: 0.0 });
        assert_eq!(s(3, DSBL_DAMPER), DampingSplit { implicit: 2.0, explicit: 0.0 });
    }
}
