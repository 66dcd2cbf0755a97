//! Rules of the `inertia` group.
pub mod armature_mismatch;
pub mod parallel_ankle_armature;
