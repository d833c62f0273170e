//! Arbitrary bytes as a scanned sheet (PNG or JPEG, small images only: at most 256 x 256 and
//! 4 MiB decoded): decoding and tracing, with fiducials and with a fixed scale, never panic.
#![no_main]

use image::{ImageReader, Limits};
use indicatif::ProgressBar;
use libfuzzer_sys::fuzz_target;
use rigctl::trace::{trace_image, Mapping, TraceOptions};
use std::io::Cursor;

fuzz_target!(|data: &[u8]| {
    let Ok(reader) = ImageReader::new(Cursor::new(data)).with_guessed_format() else {
        return;
    };
    let mut reader = reader;
    let mut limits = Limits::default();
    limits.max_image_width = Some(256);
    limits.max_image_height = Some(256);
    limits.max_alloc = Some(4 << 20);
    reader.limits(limits);
    let Ok(img) = reader.decode() else {
        return;
    };
    let img = img.into_rgb8();
    let _ = trace_image(&img, &TraceOptions::default(), &ProgressBar::hidden());
    let scale = TraceOptions {
        mapping: Mapping::Scale { mm_per_px: 0.1 },
        ..TraceOptions::default()
    };
    let _ = trace_image(&img, &scale, &ProgressBar::hidden());
});
