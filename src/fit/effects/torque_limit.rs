use super::*;
use crate::declare_effect;
use crate::fit::diagnose::{explain, percentile};

declare_effect! {
    /// Motor torque saturation (peak torque, torque–speed line).
    ///
    /// DC-motor torque–speed line: the servo torque is clipped to
    /// [sat·(−1 − q̇/v_lim), sat·(1 − q̇/v_lim)] ∩ [−effort, effort] (Isaac Lab's DCMotor law).
    /// Only `effort_limit` is fitted (on a log scale); the line parameters start unlimited. The diagnosis scans
    /// torque levels (percentiles 80–99.8 of the servo torque) for the one whose excess explains
    /// the residual best: a limit reached rarely acts only in the few largest torques. The probe
    /// starts at that level.
    ///
    /// ## Simulation
    /// model: actuator `forcerange` ±effort (MuJoCo's own clamp); hook: servo torque clipped to
    /// the DC-motor line
    ///
    /// ## Signature
    /// `sign(τ)·max(|τ| − T, 0)` (error growing beyond a torque level T, the best of the
    /// percentiles 80, 90, 95, 98, 99, 99.5, 99.8 of |τ|)
    ///
    /// ## Evidence
    /// `tau_level` (T, the probe's start), `tau_percentile`
    ///
    /// ## Write-back
    /// position servo `forcelimited="true" forcerange` ±e / gear (inside its range)
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
    /// An actuator's torque is what saturates: none on a joint no actuator drives.
    fn acts_on(&self, t: &JointTarget) -> bool {
        t.driven()
    }
    fn fitted(&self) -> usize {
        1
    }
    /// A limit spans decades (0.05–50 N·m) and its optimum is narrow: below it the joint
    /// saturates where it did not, above it nothing changes.
    fn log_search(&self) -> bool {
        true
    }
    /// No limit: the top of the box ([`Self::bounds`]).
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        let (_, hi) = self.bounds(m, t);
        self.params().iter().zip(hi).map(|(d, h)| d.default.max(h)).collect()
    }
    /// The effort limit reaches at least the joint's declared torque (a `forcerange`, a motor's
    /// control range, the joint's `actuatorfrcrange`) and half a radian of its servo's error: a
    /// humanoid knee saturating at 120 N·m must be representable, not only the 50 N·m of a
    /// small leg.
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        let ps = self.params();
        let mut hi: Vec<f64> = ps.iter().map(|p| p.hi).collect();
        let joint = match (m.jnt_actfrclimited().get(t.jnt), m.jnt_actfrcrange().get(t.jnt)) {
            (Some(true), Some(r)) if r[0].is_finite() && r[1].is_finite() => {
                r[0].abs().max(r[1].abs())
            }
            _ => 0.0,
        };
        hi[0] = hi[0].max(t.max_torque).max(joint).max(0.5 * t.servo_kp);
        (ps.iter().map(|p| p.lo).collect(), hi)
    }
    /// The effort limit is MuJoCo's own actuator force clamp (`forcerange` ±effort / gear on the
    /// joint's position servos, inside any range the model already has). A clamp added in the
    /// hook instead leaves the servo's `kv` in an implicit integrator's velocity derivative
    /// while the torque is saturated: on Asimov's knee (kv 5, `implicitfast`, 2 ms) that phantom
    /// damping put the fitted limit 1.2–1.4 % high (2.027 for 2.0) and the held-out error at
    /// 1.5 × the floor. MuJoCo drops a clamped actuator from that derivative.
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        let e = p[0].max(0.0);
        let servos: Vec<(usize, f64)> = {
            let (gear, bias) = (m.actuator_gear(), m.actuator_biasprm());
            t.acts
                .iter()
                .filter(|&&a| bias.get(a).is_some_and(|b| b[1] != 0.0))
                .map(|&a| (a, gear.get(a).map_or(1.0, |g| if g[0] != 0.0 { g[0].abs() } else { 1.0 })))
                .collect()
        };
        for (a, g) in servos {
            let limited = m.actuator_forcelimited().get(a).copied().unwrap_or(false);
            let [lo0, hi0] = m.actuator_forcerange().get(a).copied().unwrap_or([-f64::INFINITY, f64::INFINITY]);
            let (lo0, hi0) = if limited { (lo0, hi0) } else { (f64::NEG_INFINITY, f64::INFINITY) };
            if let Some(x) = m.actuator_forcelimited_mut().get_mut(a) {
                *x = true;
            }
            if let Some(r) = m.actuator_forcerange_mut().get_mut(a) {
                *r = [lo0.max(-e / g).min(0.0), hi0.min(e / g).max(0.0)];
            }
        }
    }
    /// The torque–speed line, inside the effort clamp MuJoCo applies ([`Self::apply_model`]).
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { q, qd, io, p, .. } = cx;
        let raw = servo_torque(q, qd, io);
        let (e, sat, vl) = (p[0].max(0.0), p[1].max(0.0), p[2].max(1e-6));
        let hi = (sat * (1.0 - qd / vl)).clamp(0.0, e);
        let lo = (sat * (-1.0 - qd / vl)).clamp(-e, 0.0);
        if !(lo <= hi) {
            return; // a non-finite velocity
        }
        io.tau += raw.clamp(lo, hi) - raw.clamp(-e, e);
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
    /// An effort limit `v` above every force the joint's actuators applied at a step of the
    /// base replay clamps nothing: MuJoCo's `forcerange` clamp leaves each force inside (strictly,
    /// so no implicit derivative drops a clamped actuator) and this effect's hook adds exactly
    /// 0 (`raw.clamp(−e, e) − raw.clamp(−e, e)`) while the torque–speed line at its start values
    /// lies beyond ±v at the joint's peak speed. Only the effort is judged so.
    fn unmoved(
        &self,
        _m: &MjModel,
        _t: &JointTarget,
        start: &[f64],
        (j, v): (usize, f64),
        seen: Seen,
    ) -> Option<Unmoved> {
        let (sat, vl) = (*start.get(1)?, *start.get(2)?);
        let line_clear = vl > 0.0 && sat * (1.0 - seen.speed / vl) >= v;
        (j == 0 && line_clear && seen.servo.is_some_and(|f| f < v))
            .then_some(Unmoved::LimitAboveServoForce)
    }
    /// The judgement reads the servo's peak force and the joint's peak speed.
    fn unmoved_reads_peaks(&self) -> bool {
        true
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Actuator(vec![("forcerange", p[0])])
    }
    /// As the fit simulated it ([`Self::apply_model`]): on the position servo, ±effort / gear
    /// inside the range the actuator already has.
    fn actuator_attr(
        &self,
        _attr: &'static str,
        v: f64,
        act: &ActuatorSite,
    ) -> Result<Vec<(&'static str, String)>, String> {
        if act.kind.is_some_and(|k| !matches!(k, ActuatorKind::Position { .. })) {
            return Err(format!(
                "<{}> is not the joint's position servo (the limit was fitted on the servo)",
                act.tag
            ));
        }
        let g = if act.gear != 0.0 { act.gear.abs() } else { 1.0 };
        let [lo0, hi0] = act.forcerange.unwrap_or([f64::NEG_INFINITY, f64::INFINITY]);
        let (lo, hi) = (lo0.max(-v / g).min(0.0), hi0.min(v / g).max(0.0));
        Ok(vec![("forcelimited", "true".into()), ("forcerange", format!("{} {}", num(lo), num(hi)))])
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
    use crate::fit::effects::{Applied, by_id, hinge_recording, hinge_robot, simulate};
    use crate::sim2real::replay::ReplayOptions;

    fn robot(dir: &std::path::Path, name: &str, force: &str) -> crate::model::Robot {
        let act = format!(r#"kp="50" kv="2" {force}"#);
        hinge_robot(dir, name, r#"integrator="implicitfast""#, "", &act)
    }

    /// The fitted effort limit acts exactly like MuJoCo's own `forcerange` written in the MJCF,
    /// in an implicit integrator with a servo `kv` (Asimov: `implicitfast`, kv 5): a clamp
    /// added in the hook left the servo's damping in the integrator's velocity derivative while
    /// saturated (here 0.07 rad apart; on Asimov's knee the fitted limit came out 1.4 % high).
    #[test]
    fn effort_limit_equals_mujoco_forcerange_under_implicit_damping() {
        let dir = std::env::temp_dir().join(format!("modellint-tlimit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let free = robot(&dir, "free.xml", "");
        let clamped = robot(&dir, "clamped.xml", r#"forcelimited="true" forcerange="-3 3""#);
        // Steps at 100 Hz that saturate the servo (50 × 0.4 rad = 20 N·m against 3).
        let n = 200;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.005).collect();
        let cmd: Vec<f64> =
            t.iter().map(|&t| if t < 0.1 { 0.0 } else if t < 0.5 { 0.4 } else { -0.2 }).collect();
        let rec = hinge_recording(t, cmd);
        let o = ReplayOptions::default();
        let limit = Applied {
            effect: by_id("torque_limit").unwrap(),
            joints: vec!["j".into()],
            params: vec![3.0, 1e4, 1e4],
        };
        let recs = std::slice::from_ref(&rec);
        let a = simulate(&free, recs, &[limit], &o).remove(0).unwrap();
        let b = simulate(&clamped, recs, &[], &o).remove(0).unwrap();
        let c = simulate(&free, recs, &[], &o).remove(0).unwrap();
        let diff = |x: &[f64], y: &[f64]| {
            x.iter().zip(y).map(|(p, q)| (p - q).abs()).fold(0.0_f64, f64::max)
        };
        assert!(diff(&b.q_sim[0], &c.q_sim[0]) > 0.02, "the limit never acted");
        let worst = diff(&a.q_sim[0], &b.q_sim[0]);
        assert!(worst < 1e-9, "torque_limit vs MJCF forcerange differ by {worst} rad");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A limit above every force the servo applied in the base replay (its `StepPeaks`) is
    /// judged to change nothing, and replaying it gives the base replay to the last bit; a limit
    /// below that peak is not so judged, and it changes the replay. Under Euler and (a geared
    /// servo with a force range of its own) `implicitfast`; under RK4 the peak is not measured
    /// and nothing is judged; nor with a hook on the joint, nor another parameter.
    #[test]
    fn a_limit_above_the_servo_peak_changes_no_replay() {
        let dir = std::env::temp_dir().join(format!("modellint-tpeak-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.005).collect();
        let cmd: Vec<f64> =
            t.iter().map(|&t| if t < 0.1 { 0.0 } else if t < 0.5 { 0.4 } else { -0.2 }).collect();
        let rec = hinge_recording(t, cmd);
        let (recs, o) = (std::slice::from_ref(&rec), ReplayOptions::default());
        let cases = [
            ("euler.xml", "", ""),
            ("implicit.xml", r#"integrator="implicitfast""#, r#"gear="2" forcelimited="true" forcerange="-30 30""#),
            ("rk4.xml", r#"integrator="RK4""#, ""),
        ];
        for (name, option, force) in cases {
            let r = hinge_robot(&dir, name, option, "", &format!(r#"kp="50" kv="2" {force}"#));
            let base = simulate(&r, recs, &[], &o).remove(0).unwrap();
            let seen = Seen::of([(&base.peaks, 0)], false);
            let target = JointTarget::of(&r, "j").unwrap();
            let start = TorqueLimit.initial(&r.mj, &target);
            let judge = |v: f64, seen: Seen| TorqueLimit.unmoved(&r.mj, &target, &start, (0, v), seen);
            if name == "rk4.xml" {
                assert!(base.peaks.servo.is_empty() && seen.servo.is_none(), "{:?}", base.peaks);
                assert_eq!(judge(1e3, seen), None);
                continue;
            }
            let peak = base.peaks.servo[0];
            assert!(peak > 5.0 && base.peaks.speed[0] > 0.1, "{name}: {:?}", base.peaks);
            for (v, unchanged) in [(1.01 * peak, true), (0.9 * peak, false)] {
                let judged = judge(v, seen);
                assert_eq!(judged.is_some(), unchanged, "{name}: limit {v} of peak {peak}");
                let mut p = start.clone();
                p[0] = v;
                let limit = Applied { effect: &TorqueLimit, joints: vec!["j".into()], params: p };
                let ep = simulate(&r, recs, &[limit], &o).remove(0).unwrap();
                assert_eq!(ep.q_sim == base.q_sim, unchanged, "{name}: limit {v} of peak {peak}");
            }
            assert_eq!(judge(2.0 * peak, Seen::of([(&base.peaks, 0)], true)), None, "hooked");
            let other = TorqueLimit.unmoved(&r.mj, &target, &start, (1, 2.0 * peak), seen);
            assert_eq!(other, None, "only the effort is judged");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Effects that read the servo torque see it as MuJoCo clamps it: the replay hands the hook
    /// the servo's force range in joint torque (`forcerange` × gear, the fitted limit included),
    /// and `servo_torque` clamps to it (external-load friction adds it to the joint's other
    /// torques to decide whether the joint sticks).
    #[test]
    fn hooks_see_the_clamped_servo_torque() {
        use crate::sim2real::replay::{ActuatorHook, Replayer};
        struct Seen(Vec<Option<(f64, f64)>>);
        impl ActuatorHook for Seen {
            fn reset(&mut self, _joints: &[String], _dt: f64) {}
            fn before_step(
                &mut self,
                _t: f64,
                _j: usize,
                _q: f64,
                _qd: f64,
                _q_target: f64,
                out: &mut StepIo,
            ) {
                self.0.push(out.servo_range);
            }
        }
        let dir = std::env::temp_dir().join(format!("modellint-tseen-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let geared = robot(&dir, "geared.xml", r#"gear="2" forcelimited="true" forcerange="-3 1""#);
        let t: Vec<f64> = (0..20).map(|i| i as f64 * 0.005).collect();
        let rec = hinge_recording(t, vec![0.4; 20]);
        let o = ReplayOptions::default();
        let mut seen = Seen(vec![]);
        Replayer::new(&geared).replay(&rec, &o, Some(&mut seen)).unwrap();
        assert!(!seen.0.is_empty() && seen.0.iter().all(|r| *r == Some((-6.0, 2.0))), "{:?}", seen.0.first());
        // The fitted limit narrows the range: 1.5 N·m on a gear of 2 is ±0.75 of force.
        let limit = Applied {
            effect: by_id("torque_limit").unwrap(),
            joints: vec!["j".into()],
            params: vec![1.5, 1e4, 1e4],
        };
        let m = crate::fit::effects::model_with(&geared, &[limit]);
        let mut seen = Seen(vec![]);
        Replayer::with_model(&geared, &m).replay(&rec, &o, Some(&mut seen)).unwrap();
        assert!(seen.0.iter().all(|r| *r == Some((-1.5, 1.5))), "{:?}", seen.0.first());
        let io = StepIo {
            ctrl: 1.0,
            kp: 50.0,
            enabled: true,
            servo_range: Some((-1.5, 1.5)),
            ..Default::default()
        };
        assert_eq!(servo_torque(0.0, 0.0, &io), 1.5);
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The write-back writes what the fit simulated: ±effort / gear on the position servo,
    /// inside the range it has; never on another actuator of the joint.
    #[test]
    fn write_back_divides_by_the_gear_inside_the_existing_range() {
        let site = |kind, forcerange| ActuatorSite {
            tag: "position",
            kind: Some(kind),
            timestep: 0.002,
            gear: 2.0,
            forcerange,
        };
        let servo = ActuatorKind::Position { kp: 50.0, kv: 2.0 };
        let got = TorqueLimit.actuator_attr("forcerange", 3.0, &site(servo, None)).unwrap();
        assert_eq!(got[1], ("forcerange", "-1.5 1.5".to_string()));
        let got = TorqueLimit.actuator_attr("forcerange", 3.0, &site(servo, Some([-1.0, 2.0])));
        assert_eq!(got.unwrap()[1], ("forcerange", "-1 1.5".to_string()));
        let vel = ActuatorKind::Velocity { kv: 1.0 };
        assert!(TorqueLimit.actuator_attr("forcerange", 3.0, &site(vel, None)).is_err());
    }

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
