//! Sim-to-real gap measurement: recordings, importers, the seed study's metrics, spectra and
//! error localisation.

pub mod bam;
pub mod commands;
pub mod locate;
pub mod metrics;
pub mod recording;
pub mod spectral;
pub mod svg;
pub mod replay;
pub mod gap;
pub mod cmd;
pub mod report;
