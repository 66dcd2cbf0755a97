//! Rules of the `inertia` group.
pub mod armature_mismatch;
mod armature_over_link;
pub mod copied_inertial;
mod copied_mass;
pub mod default_density_mass;
pub mod drive_family;
mod floated_root_inertia;
mod fused_placeholder;
pub mod inertia_exceeds_geometry;
pub mod inertial_overridden;
pub mod isotropic_base_inertia;
pub mod isotropic_link_inertia;
pub mod legged_urdf_armature;
mod light_density;
mod light_placeholder;
pub mod mass_budget;
pub mod parallel_ankle_armature;
pub mod passive_joint_armature;
pub mod repeated_class_mass;
pub mod transmission_armature;
mod urdf_no_inertial;
pub mod visual_geom_mass;
pub mod zero_armature;

use crate::finding::Finding;
use crate::model::mjcf::ElemKind;
use crate::model::{Joint, PartSource};
use crate::rules::Context;

/// A finding about a joint's armature, at the attribute that sets it: the joint's own
/// `armature` when it has one, else the first actuator's `armature` (MuJoCo ≥ 3.17), else the
/// joint element.
pub fn at_armature(cx: &Context, j: &Joint, msg: impl Into<String>) -> Finding {
    if j.own_armature() == 0.0 {
        let act = j.armature_parts.iter().find_map(|p| match p.source {
            PartSource::Actuator(a, _) | PartSource::TendonActuator(a, ..) => Some(a),
            _ => None,
        });
        if let Some(a) = act {
            let name = &cx.robot.actuators[a].name;
            let jloc = cx.robot.elem_loc(ElemKind::Joint, j.id, &j.name);
            return cx
                .at_attr(ElemKind::Actuator, a, name, "armature", msg)
                .secondary(jloc, format!("joint `{}`", j.name));
        }
    }
    cx.at_attr(ElemKind::Joint, j.id, &j.name, "armature", msg)
}
