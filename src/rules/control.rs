//! Rules of the `control` group.
pub mod drive_friction_mismatch;
pub mod gains_unstable_for_timestep;
pub mod keyframe_floor;
pub mod keyframe_motor_ctrl;
pub mod keyframe_scan;
pub mod keyframe_servo_ctrl;
pub mod keyframe_state;
pub mod missing_action_delay;
pub mod non_earth_gravity;
pub mod passive_joint_friction;
pub mod servo_sag;
pub mod servo_stall_band;
pub mod solimp_out_of_range;
pub mod solref_below_timestep;
pub mod spring_overpowers_actuator;
pub mod underdamped_pd_gains;
pub mod unstable_simulation;
