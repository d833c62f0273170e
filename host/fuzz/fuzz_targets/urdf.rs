//! Arbitrary text as a URDF: no panic in parsing, chain extraction or import, whatever the
//! links named as base and tip.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rigctl::urdf::import::{import_chain, ImportOptions};
use rigctl::urdf::parse::Urdf;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(urdf) = Urdf::parse(text, "fuzz.urdf") else {
        return;
    };
    let links = urdf.links.clone();
    for tip in links.iter().take(4) {
        for base in std::iter::once(None).chain(links.iter().take(4).map(|l| Some(l.as_str()))) {
            let _ = urdf.chain(base, tip);
            let opts = ImportOptions {
                base_link: base,
                tip_link: tip,
                tool_mm: [0.0; 3],
            };
            let _ = import_chain(&urdf, &opts);
        }
    }
});
