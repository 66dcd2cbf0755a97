//! Rules of the `geometry` group.
pub mod collision_visual_mismatch;
pub mod mesh_scale;
pub mod mirror_asymmetry;
mod mirror_axes;
mod mirror_com;
mod mirror_filter;
mod mirror_hub;
mod mirror_limits;
mod mirror_places;
mod mirror_sites;
mod mirror_tensor;
pub mod oversized_collision;
pub mod oversized_weight;
pub mod robot_scale;
pub mod root_frame;
pub mod self_collision_at_keyframe;
pub mod shapes;
pub mod visual_mesh_collision;
