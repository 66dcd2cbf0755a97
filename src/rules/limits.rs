//! Rules of the `limits` group.
mod actuator_effort;
pub mod ctrlrange_in_degrees;
pub mod effort_limit_mismatch;
pub(crate) mod legs;
pub mod placeholder_joint_limits;
pub mod range_in_radians;
pub mod soft_limits;
mod stated_limits;
pub(crate) mod urdf_damping_speed;
mod urdf_soft_limits;
pub mod wheel_spring;
