use super::*;
use crate::declare_effect;

declare_effect! {
    /// A link's centre of mass elsewhere than modelled (a battery or a motor placed off the CAD's guess).
    ///
    /// MuJoCo-native: the child body's mass distribution translated in the model copy —
    /// `along` the link's axis (from the joint to the modelled centre of mass, or to its first
    /// child body), `across` it (joint axis × link axis; where the link lies along its own
    /// joint's axis, the axis of the nearest joint that swings it × link axis) and `normal` to
    /// both (along × across: the joint axis, or the second perpendicular to a link lying along
    /// it); mass and the inertia about the centre of mass unchanged. `normal` is a parameter
    /// only where a rotation moves the body along it (a carrying joint whose axis is not
    /// parallel, a ball or free joint): in a planar chain a shift along the joints' axis moves
    /// no torque and no motion.
    ///
    /// ## Simulation
    /// the child body's `body_ipos` moved (`body_inertia`, `body_iquat` about it kept)
    ///
    /// ## Signature
    /// servo torque `τ` (gravity's moment arm changes with the pose; ranked by the simulated sensitivity)
    ///
    /// ## Write-back
    /// the child body's `<inertial>` (`pos`, `quat`, `mass`, `diaginertia` of the fitted body)
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters (set the link's centre of mass in the asset)
    pub ComOffset {
        id: "com_offset",
        entry: Model,
        params: [
            ParamDef { name: "along", unit: "m", lo: -0.25, hi: 0.25, default: 0.0 },
            ParamDef { name: "across", unit: "m", lo: -0.25, hi: 0.25, default: 0.0 },
            ParamDef { name: "normal", unit: "m", lo: -0.25, hi: 0.25, default: 0.0 },
        ],
    }
}

impl Effect for ComOffset {
    fn param_meaning(&self) -> &'static [(&'static str, &'static str)] {
        &[
            (
                "along",
                "m the centre of mass moves from where the model has it, along the link (from the \
                 joint towards that centre); mass unchanged",
            ),
            (
                "across",
                "m it moves across the link (joint axis × link axis; where the link lies along \
                 that axis, the axis of the nearest joint that swings it × link axis)",
            ),
            (
                "normal",
                "m it moves normal to both (along × across); fixed at 0 where no rotation moves \
                 the link that way (every joint axis parallel to it)",
            ),
        ]
    }
    /// At its start no shift ([`super::inertial::shift`] leaves the body as it is).
    fn neutral_start(&self) -> bool {
        true
    }
    /// Half a link length either way along, across and normal to the link (normal: none
    /// where no rotation moves the body that way, [`inertial::BodyAxes::normal_seen`]).
    fn bounds(&self, _m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        let h = t.body.map_or(0.0, |b| 0.5 * b.length);
        let n = t.body.map_or(0.0, |b| b.normal_bound(h));
        (vec![-h, -h, -n], vec![h, h, n])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        if let Some(b) = t.body {
            let normal = p.get(2).copied().unwrap_or(0.0);
            let d = b.point(p[0], p[1], normal) - b.point(0.0, 0.0, 0.0);
            inertial::shift(m, b.body, d);
        }
    }
    /// Every direction: on an upright trunk a shift `along` changes only gravity's stiffness
    /// while one `across` tilts the load, on a hanging shank the reverse dominates; below a
    /// yaw joint whose link hangs along its axis, the carrying pitch sees one perpendicular
    /// and the roll the other. A direction that is no parameter (bounds of zero width) is not
    /// probed.
    fn screened(&self) -> usize {
        3
    }
    /// Each direction of the shift: on a trunk standing on the feet a centre moved along it
    /// changes gravity's pitch stiffness over them, as a softer floor does.
    fn held_components(&self) -> Vec<(usize, &'static dyn Effect)> {
        vec![(0, &ALONG_HELD), (1, &ACROSS_HELD)]
    }
    inertial::body_effect_methods!(tau);
    /// A body of neither mass nor inertia: its centre of mass moves nothing
    /// ([`unmoved::massless`]).
    fn unmoved(
        &self,
        m: &MjModel,
        t: &JointTarget,
        _start: &[f64],
        _jv: (usize, f64),
        _seen: Seen,
    ) -> Option<Unmoved> {
        unmoved::massless(m, t).then_some(Unmoved::MasslessBody)
    }
}

crate::held_variant!(ALONG_HELD, ComOffset, "com_offset~along", 0, [1, 2]);
crate::held_variant!(ACROSS_HELD, ComOffset, "com_offset~across", 1, [0, 2]);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::{Applied, hinge_recording, hinge_robot, simulate};
    use crate::sim2real::replay::ReplayOptions;

    /// A shift of a body's centre of mass changes no replay where the body has neither mass nor
    /// inertia (the pendulum fixture's arm: a massless capsule carrying the bob's body), and is
    /// judged so; on a link with mass it is not judged so, and it changes the replay.
    #[test]
    fn a_massless_body_is_judged_unmoved_and_replays_unchanged() {
        let (pendulum, recs) = crate::synth::recorded::pendulum(None, 2, 3);
        let dir = std::env::temp_dir().join(format!("modellint-massless-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let link = hinge_robot(&dir, "link.xml", "", "", r#"kp="50" kv="2""#);
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.005).collect();
        let cmd: Vec<f64> = t.iter().map(|&t| if t < 0.1 { 0.0 } else { 0.4 }).collect();
        let link_recs = vec![hinge_recording(t, cmd)];
        let o = ReplayOptions::default();
        let seen = Seen { servo: None, speed: f64::INFINITY };
        for (robot, joint, recs, massless) in
            [(&pendulum, "servo", &recs, true), (&link, "j", &link_recs, false)]
        {
            let target = JointTarget::of(robot, joint).unwrap();
            let start = ComOffset.initial(&robot.mj, &target);
            for (j, v) in [(0, 0.01), (1, -0.01)] {
                let judged = ComOffset.unmoved(&robot.mj, &target, &start, (j, v), seen);
                assert_eq!(judged.is_some(), massless, "{joint}");
                let mut p = start.clone();
                p[j] = v;
                let shift = Applied { effect: &ComOffset, joints: vec![joint.into()], params: p };
                let base = simulate(robot, recs, &[], &o);
                let moved = simulate(robot, recs, &[shift], &o);
                let same = base.iter().zip(&moved).all(|(a, b)| {
                    a.as_ref().unwrap().q_sim == b.as_ref().unwrap().q_sim
                });
                assert_eq!(same, massless, "{joint}: parameter {j} at {v}");
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
