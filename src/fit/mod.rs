//! Fitting: name the missing physics, add it, fit it, show the held-out improvement.
pub mod optim;
pub mod stats;
