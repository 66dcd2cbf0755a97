//! Rules of the `control` group.
pub mod gains_unstable_for_timestep;
pub mod missing_action_delay;
pub mod underdamped_pd_gains;
pub mod unstable_simulation;
