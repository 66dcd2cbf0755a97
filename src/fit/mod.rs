//! Fitting: name the missing physics, add it, fit it, show the held-out improvement.
pub mod optim;
pub mod stats;
pub mod servo;
pub mod servo_fit;
