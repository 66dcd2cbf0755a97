//! Rules of the `contact` group.
pub mod contact_margin;
pub mod feet;
pub mod foot_collision_geometry;
pub mod foot_radius;
pub mod links_without_collision;
pub mod pose;
pub mod robot_never_collides;
pub mod toe_tilt;
pub mod token_collision;
pub mod torsional_friction;
pub mod welded_legged_base;
