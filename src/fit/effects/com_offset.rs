use super::*;
use crate::declare_effect;

declare_effect! {
    /// A link's centre of mass elsewhere than modelled (a battery or a motor placed off the CAD's guess).
    ///
    /// MuJoCo-native: the child body's mass distribution translated in the model copy —
    /// `along` the link's axis (from the joint to the modelled centre of mass, or to its first
    /// child body) and `across` it in the joint's plane of motion (joint axis × link axis); mass
    /// and the inertia about the centre of mass unchanged. A shift along the joint's own axis
    /// moves no torque about it and is not fitted.
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
            ("across", "m it moves across the link (joint axis × link axis)"),
        ]
    }
    /// At its start no shift ([`super::inertial::shift`] leaves the body as it is).
    fn neutral_start(&self) -> bool {
        true
    }
    /// Half a link length either way along and across.
    fn bounds(&self, _m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        let h = t.body.map_or(0.0, |b| 0.5 * b.length);
        (vec![-h, -h], vec![h, h])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        if let Some(b) = t.body {
            let d = b.point(p[0], p[1]) - b.point(0.0, 0.0);
            inertial::shift(m, b.body, d);
        }
    }
    /// Both directions: on an upright trunk a shift `along` changes only gravity's stiffness
    /// while one `across` tilts the load, on a hanging shank the reverse dominates.
    fn screened(&self) -> usize {
        2
    }
    /// Each direction of the shift: on a trunk standing on the feet a centre moved along it
    /// changes gravity's pitch stiffness over them, as a softer floor does.
    fn held_components(&self) -> Vec<(usize, &'static dyn Effect)> {
        vec![(0, &ALONG_HELD), (1, &ACROSS_HELD)]
    }
    inertial::body_effect_methods!(tau);
}

crate::held_variant!(ALONG_HELD, ComOffset, "com_offset~along", 0, [1]);
crate::held_variant!(ACROSS_HELD, ComOffset, "com_offset~across", 1, [0]);
