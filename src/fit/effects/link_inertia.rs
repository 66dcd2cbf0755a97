use super::*;
use crate::declare_effect;

declare_effect! {
    /// A link's rotational inertia about its centre of mass other than modelled (a box-guessed inertia), kept physically valid.
    ///
    /// MuJoCo-native: the child body's inertia in the model copy. The body's mass distribution
    /// is stretched by `√inertia_scale` in the plane perpendicular to the joint axis (through
    /// the second moments Σ = ½ tr(I)·1 − I, the covariance part of the pseudo-inertia, which a
    /// real body has positive semi-definite): the inertia about the axis through the centre of
    /// mass becomes `inertia_scale` × the modelled one, and every value is a rigid body that
    /// exists (the triangle inequality holds by construction). Mass and centre of mass are
    /// unchanged. A candidate only on a link that another joint also moves (the shank under
    /// the hip, a thigh under a free base): on a link only its own joint moves (the first link
    /// of a fixed-base chain, a pendulum) the moment about the axis adds exactly what armature
    /// adds, and the two could not be told apart (it is still fitted there when told).
    ///
    /// ## Simulation
    /// the child body's `body_inertia`, `body_iquat` (second moments scaled in the joint's plane)
    ///
    /// ## Signature
    /// `q̈` (as armature; ranked by the simulated sensitivity)
    ///
    /// ## Write-back
    /// the child body's `<inertial>` (`pos`, `quat`, `mass`, `diaginertia` of the fitted body)
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters (set the link's inertia in the asset)
    pub LinkInertia {
        id: "link_inertia",
        entry: Model,
        params: [ParamDef { name: "inertia_scale", unit: "", lo: 0.25, hi: 4.0, default: 1.0 }],
    }
}

impl Effect for LinkInertia {
    fn param_meaning(&self) -> &'static [(&'static str, &'static str)] {
        &[(
            "inertia_scale",
            "× the child body's modelled moment of inertia about the axis through its centre of \
             mass parallel to the joint axis (1 = as modelled); mass and centre of mass unchanged",
        )]
    }
    /// At its start a scale of one ([`super::inertial::scale_extent`] leaves the body).
    fn neutral_start(&self) -> bool {
        true
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        if let Some(b) = t.body {
            let s = 0.5 * p[0].max(1e-6).ln();
            inertial::scale_extent(m, b.body, &b.joint_frame(), [s, s, 0.0]);
        }
    }
    inertial::body_effect_methods!(qdd);
    fn acts_on(&self, t: &JointTarget) -> bool {
        t.body.is_some_and(|b| b.carried)
    }
    /// A body of neither mass nor inertia: no scale of its inertia is any
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
