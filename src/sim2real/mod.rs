//! Sim-to-real gap measurement: recordings, importers, the seed study's metrics, spectra and
//! error localisation.

pub mod bam;
pub mod cmd;
pub mod commands;
pub mod gap;
pub mod input;
mod input_checks;
mod input_rate;
pub mod locate;
pub mod metrics;
pub mod recording;
pub mod replay;
pub mod report;
pub mod spectral;
pub mod svg;
