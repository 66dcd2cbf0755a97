#![no_main]
//! Arbitrary text as a CSV recording and as a BAM JSON log.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let p = std::path::Path::new("fuzz.csv");
        let _ = modellint::sim2real::recording::parse_csv(p, text);
        let _ = modellint::sim2real::bam::parse_bam(p, text);
    }
});
