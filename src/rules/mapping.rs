//! Rules of the `mapping` group.
pub mod actuator_mapping;
pub mod detached_limb;
pub mod free_passive_joint;
pub mod missing_actuators;
pub mod passive_joint_spring;
pub mod sensor_quantity;
pub mod touch_sensor_site;
pub mod urdf_mjcf_drift;
