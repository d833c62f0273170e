//! Reading a scan or photo. A (non-interlaced) PNG is decoded row by row straight into the RGB
//! image while a second thread reduces each finished band of rows to the whole-image maps
//! ([`super::prepare`]): decoding a large scan is sequential (inflate), so the maps cost no
//! extra time on a machine with two cores, and nothing is copied after decoding. Other images
//! (JPEG, interlaced PNG) are decoded by the `image` crate and their maps built on all cores.
//! The trace is written as CSV.

use super::prepare::{Bands, Prepared};
use super::TraceError;
use crate::io::atomic::write_text_atomic;
use crate::io::finite::TextFormat;
use image::error::{DecodingError, ImageFormatHint, LimitError, LimitErrorKind};
use image::{ImageError, ImageFormat, RgbImage};
use std::fmt::Write as _;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// Largest decoded image accepted, bytes of RGB (the `image` crate's default allocation limit).
const MAX_RGB_BYTES: usize = 512 << 20;

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
/// is copied to the three channels; alpha is dropped).
pub fn load_prepared(path: &Path) -> Result<(RgbImage, Prepared), TraceError> {
    let read = |source| TraceError::Read {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(|e| read(ImageError::IoError(e)))?;
    let mut reader = BufReader::with_capacity(1 << 16, file);
    let is_png = reader
        .fill_buf()
        .map_err(|e| read(ImageError::IoError(e)))?
        .starts_with(b"\x89PNG\r\n\x1a\n");
    if is_png {
        if let Some(done) = png_streamed(reader).map_err(read)? {
            return Ok(done);
        }
    }
    let img = load_scan(path)?;
    let prepared = Prepared::build(&img);
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

fn png_error(e: png::DecodingError) -> ImageError {
    match e {
        png::DecodingError::IoError(io) => ImageError::IoError(io),
        other => ImageError::Decoding(DecodingError::new(
            ImageFormatHint::Exact(ImageFormat::Png),
            other,
        )),
    }
}

/// Decodes a non-interlaced PNG into RGB while building its maps; `None` when the file is of a
/// kind left to the `image` crate (interlaced, empty).
fn png_streamed<R: BufRead + std::io::Seek + Read>(
    input: R,
) -> Result<Option<(RgbImage, Prepared)>, ImageError> {
    let mut decoder = png::Decoder::new(input);
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(png_error)?;
    let (w, h) = (reader.info().width, reader.info().height);
    if reader.info().interlaced || w == 0 || h == 0 {
        return Ok(None);
    }
    let channels = match reader.output_color_type().0 {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Ok(None),
    };
    let (wu, hu) = (w as usize, h as usize);
    let bytes = wu
        .checked_mul(hu)
        .and_then(|n| n.checked_mul(3))
        .filter(|&n| n <= MAX_RGB_BYTES)
        .ok_or_else(|| {
            ImageError::Limits(LimitError::from_kind(LimitErrorKind::InsufficientMemory))
        })?;
    let mut scratch = vec![0u8; wu * channels];
    let mut buf = vec![0u8; bytes];
    let mut bands = Bands::new(wu, hu);
    let geometry = bands.geometry();
    let band_rows = bands.band_rows;
    let chunks = buf.chunks_mut(3 * wu * band_rows);
    let (tx, rx) = std::sync::mpsc::sync_channel::<(usize, &[u8])>(4);
    let (status, maps) = std::thread::scope(|s| {
        let worker = s.spawn(move || {
            rx.into_iter()
                .map(|(y0, band)| geometry.band(y0, band))
                .collect::<Vec<_>>()
        });
        let mut status = Ok(());
        'bands: for (i, chunk) in chunks.enumerate() {
            for row in chunk.chunks_exact_mut(3 * wu) {
                let got = if channels == 3 {
                    reader.read_row(row)
                } else {
                    reader.read_row(&mut scratch)
                };
                match got {
                    Ok(Some(_)) => {}
                    Ok(None) => {
                        status = Err(ImageError::Decoding(DecodingError::new(
                            ImageFormatHint::Exact(ImageFormat::Png),
                            "the image data ends before the last row",
                        )));
                        break 'bands;
                    }
                    Err(e) => {
                        status = Err(png_error(e));
                        break 'bands;
                    }
                }
                if channels != 3 {
                    to_rgb(&scratch, channels, row);
                }
            }
            let band: &[u8] = chunk;
            if tx.send((i * band_rows, band)).is_err() {
                break;
            }
        }
        drop(tx);
        let maps = worker
            .join()
            .unwrap_or_else(|payload| std::panic::resume_unwind(payload));
        (status, maps)
    });
    status?;
    for m in maps {
        bands.push(m);
    }
    let prepared = bands.finish();
    let img = RgbImage::from_raw(w, h, buf)
        .ok_or_else(|| ImageError::Limits(LimitError::from_kind(LimitErrorKind::DimensionError)))?;
    Ok(Some((img, prepared)))
}

/// One row of grey, grey + alpha or RGBA samples as RGB (alpha dropped, as `into_rgb8` does).
fn to_rgb(src: &[u8], channels: usize, dst: &mut [u8]) {
    for (s, d) in src.chunks_exact(channels).zip(dst.chunks_exact_mut(3)) {
        if channels <= 2 {
            d.fill(s[0]);
        } else {
            d.copy_from_slice(&s[..3]);
        }
    }
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
