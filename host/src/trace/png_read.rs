//! A non-interlaced PNG read in two stages that run at once: this thread decodes the rows with
//! the `png` crate (the chunks, every CRC checked, inflated and unfiltered, palette and 1-4 bit
//! samples expanded, `tRNS` turned to alpha); a second thread turns each batch of rows into the
//! RGB image and reduces every finished band of rows to the whole-image maps
//! ([`super::stages::prepare`]). Inflating one zlib stream is sequential and is most of the time a large
//! scan takes to read, so on two cores the RGB image and the maps come almost free. Interlaced
//! PNGs (their rows come pass by pass), rows over 16 MB and a malformed header are left to the
//! `image` crate, which also words their errors.
//!
//! The image is the one the `image` crate's `into_rgb8` gives (it decodes with the same crate
//! and the same expansion): grey copied to the three channels, alpha dropped, 16-bit samples
//! rounded to 8 bits; a file that names its tone curve (`sRGB`, `iCCP`, `gAMA`) is then
//! linearised through it row by row, before the maps are built ([`super::tone`]).

use super::stages::prepare::{BandMaps, Bands, Geometry, PrepareParams, Prepared};
use image::error::{
    DecodingError, ImageFormatHint, LimitError, LimitErrorKind, ParameterError, ParameterErrorKind,
};
use image::{ImageError, ImageFormat, RgbImage};
use std::io::{BufRead, ErrorKind, Read, Seek, SeekFrom};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};

/// Decoded rows handed to the second thread at a time, bytes (at least two rows).
const BATCH_BYTES: usize = 1 << 20;
/// Rows longer than this once expanded (bytes; 2 M RGBA pixels of 16 bits) are no scan: such
/// files are left to the `image` crate and its limits, so a file cannot make the two stages
/// hold huge batches.
const MAX_ROW_BYTES: usize = 16 << 20;
/// What the `png` crate may allocate beside the image (row buffers, metadata chunks) at least,
/// bytes: its default.
const MIN_DECODER_BYTES: usize = 64 << 20;

fn bad(msg: impl Into<String>) -> ImageError {
    ImageError::Decoding(DecodingError::new(
        ImageFormatHint::Exact(ImageFormat::Png),
        msg.into(),
    ))
}

fn too_large() -> ImageError {
    ImageError::Limits(LimitError::from_kind(LimitErrorKind::InsufficientMemory))
}

/// A `png` crate error as the `image` crate words it, a file cut short said so.
fn from_png(err: png::DecodingError) -> ImageError {
    match err {
        png::DecodingError::IoError(e) if e.kind() == ErrorKind::UnexpectedEof => {
            bad("the file is cut short: it ends inside its chunks")
        }
        png::DecodingError::IoError(e) => ImageError::IoError(e),
        err @ png::DecodingError::Format(_) => ImageError::Decoding(DecodingError::new(
            ImageFormatHint::Exact(ImageFormat::Png),
            err,
        )),
        err @ png::DecodingError::Parameter(_) => ImageError::Parameter(ParameterError::from_kind(
            ParameterErrorKind::Generic(err.to_string()),
        )),
        png::DecodingError::LimitsExceeded => too_large(),
    }
}

/// Reads a PNG (from its signature) as RGB with its whole-image maps, refusing an image of more
/// than `max_rgb_bytes` (3 per pixel) from its header, before anything is allocated. `None`
/// when the file is of a kind left to the `image` crate (interlaced, rows over 16 MB, a
/// malformed header) or is not a PNG; `input` is then where it was.
pub fn read_png<R: BufRead + Seek>(
    input: R,
    max_rgb_bytes: usize,
    params: &PrepareParams,
) -> Result<Option<(RgbImage, Prepared)>, ImageError> {
    read_batched(input, BATCH_BYTES, max_rgb_bytes, params)
}

fn read_batched<R: BufRead + Seek>(
    mut input: R,
    batch_bytes: usize,
    max_rgb_bytes: usize,
    params: &PrepareParams,
) -> Result<Option<(RgbImage, Prepared)>, ImageError> {
    if !is_png(&mut input)? {
        return Ok(None);
    }
    let limits = png::Limits {
        bytes: max_rgb_bytes.max(MIN_DECODER_BYTES),
    };
    let mut decoder = png::Decoder::new_with_limits(input, limits);
    decoder.set_transformations(png::Transformations::EXPAND);
    let Ok(info) = decoder.read_header_info() else {
        return Ok(None);
    };
    let (width, height) = (info.width as usize, info.height as usize);
    if info.interlaced || max_row_bytes(info) > MAX_ROW_BYTES {
        return Ok(None);
    }
    let rgb_bytes = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(3))
        .filter(|&n| n <= max_rgb_bytes)
        .ok_or_else(too_large)?;
    let mut reader = decoder.read_info().map_err(from_png)?;
    // The file's own word on its tone curve: the rows are linearised as they come.
    let tone = super::tone::from_png_info(reader.info());
    let lut = tone
        .as_ref()
        .filter(|t| t.curve != super::tone::ToneCurve::Linear)
        .map(|t| t.curve.lut());
    let layout = Layout::of(reader.output_color_type(), width)?;
    let batch_rows = (batch_bytes / layout.row_bytes.max(1)).max(2);
    let mut rgb = vec![0u8; rgb_bytes];
    let mut bands = Bands::new(width, height, params);
    let geometry = bands.geometry();
    let band_rows = bands.band_rows;

    let (tx, rx) = sync_channel::<Batch>(4);
    let (spare_tx, spare_rx) = sync_channel::<Vec<u8>>(2);
    let (decoded, maps) = std::thread::scope(|s| {
        let rgb = &mut rgb;
        let worker =
            s.spawn(move || to_rgb_all(layout, rx, spare_tx, rgb, geometry, band_rows, lut));
        let decoded = decode_rows(&mut reader, layout, height, batch_rows, &tx, &spare_rx);
        drop(tx);
        let maps = worker
            .join()
            .unwrap_or_else(|payload| std::panic::resume_unwind(payload));
        (decoded, maps)
    });
    decoded?;
    for m in maps {
        bands.push(m);
    }
    let mut prepared = bands.finish();
    if let Some(t) = tone {
        prepared.tone = t;
    }
    let img = RgbImage::from_raw(width as u32, height as u32, rgb)
        .ok_or_else(|| ImageError::Limits(LimitError::from_kind(LimitErrorKind::DimensionError)))?;
    Ok(Some((img, prepared)))
}

/// Whether `input` begins with PNG's signature; it is left where it was.
fn is_png<R: Read + Seek>(input: &mut R) -> Result<bool, ImageError> {
    let start = input.stream_position().map_err(ImageError::IoError)?;
    let mut signature = [0u8; 8];
    let read = input.read_exact(&mut signature);
    input
        .seek(SeekFrom::Start(start))
        .map_err(ImageError::IoError)?;
    Ok(read.is_ok() && &signature == b"\x89PNG\r\n\x1a\n")
}

/// The longest a row can be once expanded (`tRNS` is not known from the header: it may add an
/// alpha sample), bytes.
fn max_row_bytes(info: &png::Info) -> usize {
    let samples = match info.color_type {
        png::ColorType::Grayscale | png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb | png::ColorType::Rgba | png::ColorType::Indexed => 4,
    };
    let bytes_per_sample = if info.bit_depth == png::BitDepth::Sixteen {
        2
    } else {
        1
    };
    (info.width as usize).saturating_mul(samples * bytes_per_sample)
}

/// The samples of a decoded row.
#[derive(Debug, Clone, Copy)]
struct Layout {
    /// 1 or 2.
    bytes_per_sample: usize,
    /// 1 (grey), 2 (grey + alpha), 3 (RGB) or 4 (RGBA).
    channels: usize,
    row_bytes: usize,
}

impl Layout {
    fn of(
        (colour, depth): (png::ColorType, png::BitDepth),
        width: usize,
    ) -> Result<Self, ImageError> {
        let channels = match colour {
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            png::ColorType::Indexed => return Err(bad("the palette was not expanded")),
        };
        let bytes_per_sample = match depth {
            png::BitDepth::Eight => 1,
            png::BitDepth::Sixteen => 2,
            _ => return Err(bad("samples of under 8 bits were not expanded")),
        };
        Ok(Self {
            bytes_per_sample,
            channels,
            row_bytes: width * channels * bytes_per_sample,
        })
    }
}

/// Decoded rows, `rows` of them, one after the other.
struct Batch {
    data: Vec<u8>,
    rows: usize,
}

/// The first stage: `height` rows decoded and sent `batch_rows` at a time, then the rest of the
/// image data read as the `image` crate reads it.
fn decode_rows<R: BufRead + Seek>(
    reader: &mut png::Reader<R>,
    layout: Layout,
    height: usize,
    batch_rows: usize,
    tx: &SyncSender<Batch>,
    spare: &Receiver<Vec<u8>>,
) -> Result<(), ImageError> {
    let line = layout.row_bytes;
    let mut y = 0;
    while y < height {
        let rows = batch_rows.min(height - y);
        let mut data = spare.try_recv().unwrap_or_default();
        data.resize(rows * line, 0);
        for (r, row) in data.chunks_exact_mut(line.max(1)).enumerate() {
            if reader.read_row(row).map_err(from_png)?.is_none() {
                return Err(bad(format!(
                    "the image data ends {} row(s) before the last row",
                    height - y - r
                )));
            }
        }
        tx.send(Batch { data, rows })
            .map_err(|_| bad("building the RGB image stopped"))?;
        y += rows;
    }
    match reader.next_row().map_err(from_png)? {
        None => Ok(()),
        Some(_) => Err(bad("the image holds more rows than its header says")),
    }
}

/// The second stage: rows turned into `rgb` and every finished band reduced to its maps.
fn to_rgb_all(
    layout: Layout,
    rx: Receiver<Batch>,
    spare: SyncSender<Vec<u8>>,
    rgb: &mut [u8],
    geometry: Geometry,
    band_rows: usize,
    lut: Option<[u8; 256]>,
) -> Vec<BandMaps> {
    let w3 = 3 * (layout.row_bytes / (layout.channels * layout.bytes_per_sample));
    let height = rgb.len() / w3.max(1);
    let mut maps = Vec::new();
    let mut y = 0usize;
    for batch in rx {
        for row in batch
            .data
            .chunks_exact(layout.row_bytes.max(1))
            .take(batch.rows)
        {
            let dst = &mut rgb[y * w3..(y + 1) * w3];
            to_rgb(row, layout, dst);
            if let Some(lut) = &lut {
                for v in dst.iter_mut() {
                    *v = lut[*v as usize];
                }
            }
            y += 1;
            if y.is_multiple_of(band_rows) || y == height {
                let y0 = (y - 1) / band_rows * band_rows;
                maps.push(geometry.band(y0, &rgb[y0 * w3..y * w3]));
            }
        }
        let _ = spare.try_send(batch.data);
    }
    maps
}

/// One decoded row as RGB.
fn to_rgb(src: &[u8], layout: Layout, dst: &mut [u8]) {
    match (layout.bytes_per_sample, layout.channels) {
        (1, 3) => dst.copy_from_slice(src),
        (1, ch) => {
            for (s, d) in src.chunks_exact(ch).zip(dst.chunks_exact_mut(3)) {
                if ch <= 2 {
                    d.fill(s[0]);
                } else {
                    d.copy_from_slice(&s[..3]);
                }
            }
        }
        (_, ch) => {
            // 16-bit big-endian samples, rounded as round(v * 255 / 65535).
            let eight =
                |hi: u8, lo: u8| ((u32::from(u16::from_be_bytes([hi, lo])) + 128) / 257) as u8;
            for (s, d) in src.chunks_exact(2 * ch).zip(dst.chunks_exact_mut(3)) {
                if ch <= 2 {
                    d.fill(eight(s[0], s[1]));
                } else {
                    for k in 0..3 {
                        d[k] = eight(s[2 * k], s[2 * k + 1]);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
