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
}

crate::held_variant!(ALONG_HELD, ComOffset, "com_offset~along", 0, [1, 2]);
crate::held_variant!(ACROSS_HELD, ComOffset, "com_offset~across", 1, [0, 2]);
