//! Arbitrary text as a sheet placement file and as a potentiometer calibration file: no panic;
//! an accepted calibration maps counts to finite travel.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rigctl::fusion::placement::SheetPlacement;
use rigctl::fusion::potcal::PotCalibration;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("fuzz.toml");
    let _ = SheetPlacement::from_toml_str(text, path);
    if let Ok(cal) = PotCalibration::from_toml_str(text, path) {
        let _ = cal.travel_mm(2048.0);
    }
});
