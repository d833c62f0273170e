//! Arbitrary bytes as a recording file: the strict and the salvaging reader must never panic;
//! a file the strict reader accepts is read identically by the salvaging one, with no damage.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rigctl::daq::recording::parse_recording;
use rigctl::daq::salvage::salvage;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.rec");
    let _ = parse_recording(path, data);
    let loose = salvage(path, data, false);
    if let Ok(strict) = salvage(path, data, true) {
        assert!(strict.damaged.is_empty());
        let loose = loose.expect("strict accepted, salvage must too");
        assert_eq!(strict.frames, loose.frames);
    }
});
