//! Reading recordings from the command line's paths: files as given, directories expanded to
//! their recordings, each file read as BAM JSON (sniffed) or CSV.

use std::path::{Path, PathBuf};

use crate::sim2real::bam;
use crate::sim2real::recording::{self, Recording, RecordingError};

/// Reads one recording file: BAM JSON (sniffed) or CSV.
pub fn read_recording(path: &Path) -> Result<Recording, RecordingError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| RecordingError::new(path, None, None, format!("cannot read file: {e}")))?;
    if bam::is_bam_json(&text) {
        Ok(bam::bam_recording(bam::parse_bam(path, &text)?))
    } else {
        recording::parse_csv(path, &text)
    }
}

/// Expands the command-line inputs: files as given, directories to their `*.csv` (and BAM
/// `*.json`) files in sorted order.
pub fn expand_inputs(inputs: &[PathBuf]) -> Result<Vec<PathBuf>, RecordingError> {
    let mut out = Vec::new();
    for p in inputs {
        if p.is_dir() {
            let rd = std::fs::read_dir(p).map_err(|e| {
                RecordingError::new(p, None, None, format!("cannot read directory: {e}"))
            })?;
            let mut files: Vec<PathBuf> = rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| {
                    f.is_file()
                        && f.extension().is_some_and(|x| {
                            x.eq_ignore_ascii_case("csv") || x.eq_ignore_ascii_case("json")
                        })
                })
                .collect();
            files.sort();
            if files.is_empty() {
                return Err(RecordingError::new(
                    p,
                    None,
                    None,
                    "directory holds no *.csv or *.json recordings",
                ));
            }
            out.extend(files);
        } else if p.is_file() {
            out.push(p.clone());
        } else {
            return Err(RecordingError::new(p, None, None, "no such file or directory"));
        }
    }
    Ok(out)
}
