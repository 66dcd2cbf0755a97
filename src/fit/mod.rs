//! Fitting: name the missing physics, add it, fit it, show the held-out improvement.
pub mod absent;
pub mod cmd;
pub mod cmd_rotate;
pub mod contact;
pub mod diagnose;
pub mod effects;
pub mod floor_rival;
pub mod optim;
pub mod report;
pub mod rollout;
pub mod rotation;
pub mod select;
pub mod split;
pub mod stats;
pub mod unexplained;
pub mod writeback;
pub mod writemodel;
