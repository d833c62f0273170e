//! Arbitrary text as a model file: no panic; a model that loads evaluates FK at q = 0 without
//! panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rigctl::model::{Model, Tilt};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(model) = Model::from_toml_str(text, "fuzz.toml") {
        let q = vec![0.0; model.n_joints()];
        let _ = model.fk(&q, Tilt::Off);
        let _ = model.to_toml_string();
    }
});
