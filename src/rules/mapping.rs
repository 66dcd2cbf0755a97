//! Rules of the `mapping` group.
pub mod actuator_mapping;
pub mod passive_joint_spring;
pub mod urdf_mjcf_drift;
pub mod missing_actuators;
