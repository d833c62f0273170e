//! Reading a scan or photo. A non-interlaced PNG is decoded by the `png` crate on one thread
//! while a second turns its rows into the RGB image and reduces each finished band of rows to
//! the whole-image maps ([`super::png_read`]). Other images (JPEG, interlaced PNG) are decoded
//! by the `image` crate and their maps built on all cores. The trace is written as CSV.

use super::stages::prepare::{PrepareParams, Prepared};
use super::TraceError;
use crate::io::atomic::write_text_atomic;
use crate::io::finite::TextFormat;
use image::{ImageError, RgbImage};
use std::fmt::Write as _;
use std::io::BufReader;
use std::path::Path;

/// Largest decoded image accepted, bytes of RGB (the `image` crate's default allocation limit).
pub const MAX_RGB_BYTES: usize = 512 << 20;

/// Reads a scan (PNG or JPEG) as RGB.
pub fn load_scan(path: &Path) -> Result<RgbImage, TraceError> {
    let read = |source| TraceError::Read {
        path: path.to_path_buf(),
        source,
    };
    Ok(image::ImageReader::open(path)
        .map_err(|e| read(ImageError::IoError(e)))?
        .with_guessed_format()
        .map_err(|e| read(ImageError::IoError(e)))?
        .decode()
        .map_err(read)?
        .into_rgb8())
}

/// Reads a scan (PNG or JPEG) as RGB together with its whole-image maps, for
/// [`super::trace_prepared`]. The image is the same as [`load_scan`]'s (8-bit samples; grey
/// is copied to the three channels; alpha is dropped), linearised when a PNG names its tone
/// curve (its `sRGB`, `iCCP` or `gAMA` chunk: [`super::tone`]).
pub fn load_prepared(path: &Path) -> Result<(RgbImage, Prepared), TraceError> {
    load_prepared_with(path, &PrepareParams::default())
}

/// [`load_prepared`] with the maps built with `params`.
pub fn load_prepared_with(
    path: &Path,
    params: &PrepareParams,
) -> Result<(RgbImage, Prepared), TraceError> {
    let read = |source| TraceError::Read {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(|e| read(ImageError::IoError(e)))?;
    // Not a PNG (a JPEG), or a kind of PNG left to the `image` crate: `None`.
    let reader = BufReader::with_capacity(1 << 16, file);
    if let Some(done) = super::png_read::read_png(reader, MAX_RGB_BYTES, params).map_err(read)? {
        return Ok(done);
    }
    // JPEG (or a PNG left to the `image` crate): its tone curve is measured on the print
    // ([`super::trace_prepared`]); a JPEG's ICC profile is not read.
    let img = load_scan(path)?;
    let prepared = Prepared::build_with(&img, params);
    Ok((img, prepared))
}

/// Writes points as CSV `x,y` (mm, 4 decimals), atomically.
pub fn write_csv(path: &Path, points_mm: &[[f64; 2]]) -> Result<(), TraceError> {
    let mut text = String::from("x,y\n");
    for p in points_mm {
        let _ = writeln!(text, "{:.4},{:.4}", p[0], p[1]);
    }
    write_text_atomic(path, TextFormat::Csv, &text)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streamed_png_equals_image_crate_decoding_in_every_colour_type() {
        let dir = tempfile::tempdir().expect("tempdir");
        let (w, h) = (301u32, 517u32);
        let rgb = RgbImage::from_fn(w, h, |x, y| {
            image::Rgb([(x % 256) as u8, (y % 256) as u8, ((x * y) % 256) as u8])
        });
        let grey = image::DynamicImage::ImageRgb8(rgb.clone()).into_luma8();
        let rgba = image::DynamicImage::ImageRgb8(rgb.clone()).into_rgba8();
        let cases: Vec<(&str, image::DynamicImage)> = vec![
            ("rgb.png", rgb.into()),
            ("grey.png", grey.into()),
            ("rgba.png", rgba.into()),
        ];
        for (name, img) in cases {
            let p = dir.path().join(name);
            img.save(&p).expect("save");
            let (got, prepared) = load_prepared(&p).expect("load_prepared");
            let want = load_scan(&p).expect("load_scan");
            assert_eq!(got, want, "{name}");
            let built = Prepared::build(&want);
            assert_eq!(prepared.map.min_red, built.map.min_red, "{name}");
            assert_eq!(prepared.paper.level, built.paper.level, "{name}");
        }
    }

    #[test]
    fn truncated_png_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().expect("tempdir");
        let p = dir.path().join("t.png");
        RgbImage::from_fn(200, 300, |x, y| image::Rgb([(x ^ y) as u8, 3, 9]))
            .save(&p)
            .expect("save");
        let bytes = std::fs::read(&p).expect("read");
        std::fs::write(&p, &bytes[..bytes.len() / 2]).expect("write");
        assert!(matches!(load_prepared(&p), Err(TraceError::Read { .. })));
    }
}
