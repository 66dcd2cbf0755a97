//! Rules of the `limits` group.
pub mod soft_limits;
pub mod effort_limit_mismatch;
