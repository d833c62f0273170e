//! Arbitrary bytes as a scanned sheet (PNG or JPEG): decoding and tracing never panic. Small
//! images only: the decoder refuses anything over 64 x 64 pixels from the header, before
//! allocating, and at most 1 MiB in all. An input is traced with fiducials or with a fixed
//! scale (chosen by its length's parity, so both paths are fuzzed without tracing twice).
#![no_main]

use image::{ImageReader, Limits};
use indicatif::ProgressBar;
use libfuzzer_sys::fuzz_target;
use rigctl::trace::{trace_image, Mapping, TraceOptions};
use std::io::Cursor;

/// Largest width and height decoded, px.
const MAX_SIDE_PX: u32 = 64;

fuzz_target!(|data: &[u8]| {
    let Ok(mut reader) = ImageReader::new(Cursor::new(data)).with_guessed_format() else {
        return;
    };
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_SIDE_PX);
    limits.max_image_height = Some(MAX_SIDE_PX);
    limits.max_alloc = Some(1 << 20);
    reader.limits(limits);
    let Ok(img) = reader.decode() else {
        return;
    };
    let img = img.into_rgb8();
    let options = if data.len() % 2 == 0 {
        TraceOptions::default()
    } else {
        TraceOptions {
            mapping: Mapping::Scale { mm_per_px: 0.1 },
            ..TraceOptions::default()
        }
    };
    let _ = trace_image(&img, &options, &ProgressBar::hidden());
});
