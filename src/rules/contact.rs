//! Rules of the `contact` group.
pub mod toe_tilt;
pub mod foot_collision_geometry;
pub mod feet;
