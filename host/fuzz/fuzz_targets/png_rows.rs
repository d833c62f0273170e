//! Arbitrary bytes as a PNG for the two-thread reader of `rigctl trace` (`trace::read_png`: the
//! `png` crate's rows turned into RGB, and the maps built, on a second thread): never a panic or
//! a hang, and whenever both it and the `image` crate decode the bytes, the same pixels. Small
//! images only: 64 x 64 pixels at most, refused from the header (so the `image` crate, given the
//! same header, decodes no more).
#![no_main]

use image::ImageFormat;
use libfuzzer_sys::fuzz_target;
use rigctl::trace::{read_png, PrepareParams};
use std::io::Cursor;

/// Largest image read, bytes of RGB (64 x 64 pixels).
const MAX_RGB_BYTES: usize = 64 * 64 * 3;

fuzz_target!(|data: &[u8]| {
    let Ok(Some((ours, _maps))) = read_png(Cursor::new(data), MAX_RGB_BYTES, &PrepareParams::default()) else {
        return;
    };
    if let Ok(theirs) = image::load_from_memory_with_format(data, ImageFormat::Png) {
        assert!(theirs.into_rgb8() == ours, "pixels differ from the image crate's");
    }
});
