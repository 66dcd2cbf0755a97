//! modellint: finds the robot-model mistakes that break sim-to-real transfer, confirms them with
//! MuJoCo probe simulations, and measures and closes the sim-to-real gap on real recordings.
pub mod cli;
pub mod config;
pub mod error;
pub mod finding;
pub mod fit;
pub mod lint;
pub mod model;
pub mod output;
pub mod probe;
pub mod rules;
pub mod sim2real;
pub mod spec;
pub mod spec_use;
pub mod synth;
pub mod util;
