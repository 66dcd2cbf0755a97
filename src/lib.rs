//! modellint: finds the robot-model mistakes that break sim-to-real transfer, confirms them with
//! MuJoCo probe simulations, and measures and closes the sim-to-real gap on real recordings.

// `!(x > 0.0)`, `!(a <= b)` are this crate's way of rejecting NaN together with out-of-range
// values (a NaN compares false, so the negation is true). The lint's suggested rewrite through
// `partial_cmp` hides that intent; rewrites as `x.is_nan() || x <= 0.0` are used where code is
// touched anyway.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
pub mod cli;
pub mod cli_logs;
pub mod config;
pub mod error;
pub mod finding;
pub mod fit;
pub mod lint;
pub mod lint_cache;
pub mod model;
pub mod output;
pub mod probe;
pub mod rules;
pub mod sim2real;
pub mod sink;
pub mod spec;
pub mod spec_init;
pub mod spec_use;
pub mod synth;
pub mod util;
