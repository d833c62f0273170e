//! Arbitrary text as a URDF: no panic in parsing, chain extraction or import. The tip link and
//! the base link (besides the root) are chosen from the parsed links by a number derived from
//! the input (its length and last byte), so each input costs one parse and two imports rather
//! than every pair of links; across inputs every pair is tried.
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
    let n = urdf.links.len();
    if n == 0 {
        return;
    }
    let pick = data.len() + usize::from(data.last().copied().unwrap_or(0));
    let tip = urdf.links[pick % n].as_str();
    let base = urdf.links[(pick / n) % n].as_str();
    for base_link in [None, Some(base)] {
        let _ = urdf.chain(base_link, tip);
        let opts = ImportOptions {
            base_link,
            tip_link: tip,
            tool_mm: [0.0; 3],
        };
        let _ = import_chain(&urdf, &opts);
    }
});
