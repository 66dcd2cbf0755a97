use super::*;
use crate::declare_effect;

declare_effect! {
    /// A link heavier than modelled: a point mass on the joint's child body (a payload, a battery, cables).
    ///
    /// MuJoCo-native: the child body's mass properties in the model copy. The point mass
    /// `added_mass` ≥ 0 sits on the link's axis (from the joint to the body's modelled centre of
    /// mass, or to its first child body), `offset` from the modelled centre of mass; the body's
    /// new mass, centre of mass and inertia follow by the parallel-axis theorem
    /// ([`super::inertial`]), so every value is a rigid body that exists. The search sees it as
    /// any other effect: gravity makes it a pose-dependent load on the joint and every joint
    /// above it, which a joint stiffness (spring to one pose) or an offset does not have.
    ///
    /// ## Simulation
    /// the child body's `body_mass`, `body_ipos`, `body_inertia`, `body_iquat`: body + point mass (parallel-axis theorem)
    ///
    /// ## Signature
    /// servo torque `τ` (the load grows with the mass; ranked by the simulated sensitivity)
    ///
    /// ## Write-back
    /// the child body's `<inertial>` (`pos`, `quat`, `mass`, `diaginertia` of the fitted body)
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters (set the link's mass properties in the asset)
    pub LinkMass {
        id: "link_mass",
        entry: Model,
        params: [
            ParamDef { name: "added_mass", unit: "kg", lo: 0.0, hi: 5.0, default: 0.0 },
            ParamDef { name: "offset", unit: "m", lo: -0.5, hi: 0.5, default: 0.0 },
        ],
    }
}

impl Effect for LinkMass {
    /// Added mass up to twice the body's subtree mass (at least 1 kg); the point within one
    /// link length of the modelled centre of mass.
    fn bounds(&self, _m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        let Some(b) = t.body else {
            return (vec![0.0, 0.0], vec![0.0, 0.0]);
        };
        (vec![0.0, -b.length], vec![(2.0 * b.subtree_mass).max(1.0), b.length])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        if let Some(b) = t.body {
            inertial::add_point_mass(m, b.body, p[0], b.point(p[1], 0.0));
        }
    }
    inertial::body_effect_methods!(tau);
}
