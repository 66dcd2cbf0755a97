use super::*;
use crate::declare_effect;

declare_effect! {
    /// A link heavier than modelled: a point mass on the joint's child body (a payload, a battery, cables).
    ///
    /// MuJoCo-native: the child body's mass properties in the model copy. The point mass
    /// `added_mass` ≥ 0 sits `offset` from the modelled centre of mass along the link's axis
    /// (from the joint to that centre, or to its first child body), `across` it (joint axis ×
    /// link axis; where the link lies along its own joint's axis, the axis of the nearest joint
    /// that swings it × link axis) and `normal` to both (along × across); the body's new mass,
    /// centre of mass and inertia follow by the parallel-axis theorem ([`super::inertial`]), so
    /// every value is a rigid body that exists. Gravity sees the composite body's mass and first
    /// moment — the mass and the components of the point's place a rotation moves — wherever
    /// another joint carries the link; `normal` is a parameter only where a rotation moves the
    /// body along it (a carrying joint whose axis is not parallel, a ball or free joint): in a
    /// planar chain a place along the joints' axis moves no torque and is not fitted.
    /// The place of a mass that comes out as nothing is not determined and is reported as not
    /// identified. The search sees it as any other effect: gravity makes it a pose-dependent
    /// load on the joint and every joint above it, which a joint stiffness (spring to one pose)
    /// or an offset does not have.
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
            ParamDef { name: "across", unit: "m", lo: -0.5, hi: 0.5, default: 0.0 },
            ParamDef { name: "normal", unit: "m", lo: -0.5, hi: 0.5, default: 0.0 },
        ],
    }
}

impl Effect for LinkMass {
    /// At its start no added mass ([`super::inertial::add_point_mass`] adds nothing).
    fn neutral_start(&self) -> bool {
        true
    }
    /// Added mass up to twice the body's subtree mass (at least 1 kg); the point within one
    /// link length of the modelled centre of mass, along the link, across it and normal to it
    /// (normal: none where no rotation moves the body that way,
    /// [`inertial::BodyAxes::normal_seen`]).
    fn bounds(&self, _m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        let Some(b) = t.body else {
            return (vec![0.0; 4], vec![0.0; 4]);
        };
        let hi = (2.0 * b.subtree_mass).max(1.0);
        let n = b.normal_bound(b.length);
        (vec![0.0, -b.length, -b.length, -n], vec![hi, b.length, b.length, n])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        if let Some(b) = t.body {
            let across = p.get(2).copied().unwrap_or(0.0);
            let normal = p.get(3).copied().unwrap_or(0.0);
            inertial::add_point_mass(m, b.body, p[0], b.point(p[1], across, normal));
        }
    }
    /// The point's place along the link and across it (its mass is no place: held at 0 the
    /// effect is absent, which the whole rival tests).
    fn held_components(&self) -> Vec<(usize, &'static dyn Effect)> {
        vec![(1, &OFFSET_HELD), (2, &ACROSS_HELD)]
    }
    inertial::body_effect_methods!(tau);
    fn param_meaning(&self) -> &'static [(&'static str, &'static str)] {
        &[
            (
                "added_mass",
                "kg added to the child body's modelled mass (a point mass; the body's mass \
                 becomes its modelled mass + added_mass)",
            ),
            (
                "offset",
                "m from the body's modelled centre of mass to the added point, along the link \
                 (from the joint towards that centre)",
            ),
            (
                "across",
                "m from the modelled centre of mass, across the link (joint axis × link axis; \
                 where the link lies along that axis, the axis of the nearest joint that swings \
                 it × link axis)",
            ),
            (
                "normal",
                "m from the modelled centre of mass, normal to both (along × across); fixed at 0 \
                 where no rotation moves the link that way (every joint axis parallel to it)",
            ),
        ]
    }
}

crate::held_variant!(OFFSET_HELD, LinkMass, "link_mass~offset", 1, [0, 2, 3]);
crate::held_variant!(ACROSS_HELD, LinkMass, "link_mass~across", 2, [0, 1, 3]);
