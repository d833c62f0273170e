//! A non-interlaced PNG of 8- or 16-bit samples (grey, grey + alpha, RGB, RGBA) read in two
//! stages that run at once: this thread reads the chunks and inflates the image data; a second
//! thread unfilters each row into the RGB image and reduces every finished band of rows to the
//! whole-image maps ([`super::prepare`]). Inflating one zlib stream is sequential and is most
//! of the time a large scan takes to read, so on two cores unfiltering and the maps come almost
//! free. Other PNGs (palette, 1-4 bit grey, interlaced, rows over 16 MB, a malformed header)
//! are left to the `image` crate, which also words their errors.
//!
//! The image is the one the `image` crate's `into_rgb8` gives: grey copied to the three
//! channels, alpha (and `tRNS`) dropped, 16-bit samples rounded to 8 bits. Every chunk's CRC is
//! checked.

use super::prepare::{BandMaps, Bands, Geometry, Prepared};
use image::error::{DecodingError, ImageFormatHint, LimitError, LimitErrorKind};
use image::{ImageError, ImageFormat, RgbImage};
use std::io::Read;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};

/// The deflate window: how far back a match may reach, bytes.
const LOOKBACK: usize = 32 << 10;
/// Bytes of a chunk read at a time.
const PIECE: usize = 64 << 10;
/// Inflated rows handed to the unfiltering thread at a time (at least two rows), and image
/// data gathered across chunks before it is inflated, bytes. Writers cut the image data into
/// chunks of 8-64 KB; the inflater runs its fast loop over long inputs (a Pillow-written A4
/// 600 dpi scan is read 10-15 % faster than chunk by chunk).
const BATCH_BYTES: usize = 1 << 20;
/// Rows longer than this (bytes; 5.5 M RGB pixels) are no scan: such files are left to the
/// `image` crate and its limits, so a file cannot make the two stages hold huge batches.
const MAX_ROW_BYTES: usize = 16 << 20;

fn bad(msg: impl Into<String>) -> ImageError {
    ImageError::Decoding(DecodingError::new(
        ImageFormatHint::Exact(ImageFormat::Png),
        msg.into(),
    ))
}

fn too_large() -> ImageError {
    ImageError::Limits(LimitError::from_kind(LimitErrorKind::InsufficientMemory))
}

/// Reads a PNG (from its signature) as RGB with its whole-image maps, refusing an image of more
/// than `max_rgb_bytes` (3 per pixel) from its header, before anything is allocated. `None`
/// when the file is of a kind left to the `image` crate (palette, 1-4 bit grey, interlaced,
/// rows over 16 MB, a malformed header) or is not a PNG.
pub fn read_png<R: Read>(
    input: R,
    max_rgb_bytes: usize,
) -> Result<Option<(RgbImage, Prepared)>, ImageError> {
    read_batched(input, BATCH_BYTES, max_rgb_bytes)
}

fn read_batched<R: Read>(
    input: R,
    batch_bytes: usize,
    max_rgb_bytes: usize,
) -> Result<Option<(RgbImage, Prepared)>, ImageError> {
    let mut chunks = Chunks::new(input);
    let mut signature = [0u8; 8];
    if chunks.input.read_exact(&mut signature).is_err() {
        return Ok(None);
    }
    if &signature != b"\x89PNG\r\n\x1a\n" {
        return Ok(None);
    }
    let header = match chunks.next()? {
        Some((13, ty)) if &ty == b"IHDR" => {
            let mut ihdr = [0u8; 13];
            chunks.body(13, ty, |p| {
                ihdr.copy_from_slice(p);
                Ok(())
            })?;
            match Header::parse(&ihdr) {
                Some(h) => h,
                None => return Ok(None),
            }
        }
        _ => return Ok(None),
    };
    let rgb_bytes = header
        .width
        .checked_mul(header.height)
        .and_then(|n| n.checked_mul(3))
        .filter(|&n| n <= max_rgb_bytes)
        .ok_or_else(too_large)?;
    let stride = header.row_bytes() + 1;
    if stride > MAX_ROW_BYTES {
        return Ok(None);
    }
    let batch_rows = (batch_bytes / stride).max(2);
    let mut rgb = vec![0u8; rgb_bytes];
    let mut bands = Bands::new(header.width, header.height);
    let geometry = bands.geometry();
    let band_rows = bands.band_rows;

    let (tx, rx) = sync_channel::<Batch>(4);
    let (spare_tx, spare_rx) = sync_channel::<Vec<u8>>(2);
    let (inflated, unfiltered) = std::thread::scope(|s| {
        let rgb = &mut rgb;
        let worker = s.spawn(move || unfilter_all(header, rx, spare_tx, rgb, geometry, band_rows));
        let mut inflate = Inflate {
            d: Box::new(fdeflate::Decompressor::new()),
            buf: vec![0u8; LOOKBACK + batch_rows * stride],
            filled: 0,
            row_at: 0,
            stride,
            rows_left: header.height,
            tx,
            spare: spare_rx,
            gather_bytes: batch_bytes,
            gathered: Vec::new(),
        };
        inflate.d.ignore_adler32();
        let inflated = inflate_chunks(&mut chunks, &mut inflate);
        drop(inflate);
        let unfiltered = worker
            .join()
            .unwrap_or_else(|payload| std::panic::resume_unwind(payload));
        (inflated, unfiltered)
    });
    // The unfiltering thread stops first only on an error of its own; the inflating side then
    // sees a closed channel, which is not the error to report.
    let maps = unfiltered?;
    inflated?;
    for m in maps {
        bands.push(m);
    }
    let prepared = bands.finish();
    let img = RgbImage::from_raw(header.width as u32, header.height as u32, rgb)
        .ok_or_else(|| ImageError::Limits(LimitError::from_kind(LimitErrorKind::DimensionError)))?;
    Ok(Some((img, prepared)))
}

/// The chunks after `IHDR`: image data inflated, the rest checked and skipped, until every row
/// is out.
fn inflate_chunks<R: Read>(
    chunks: &mut Chunks<R>,
    inflate: &mut Inflate,
) -> Result<(), ImageError> {
    while inflate.rows_left > 0 {
        let Some((len, ty)) = chunks.next()? else {
            break;
        };
        match &ty {
            b"IDAT" => chunks.body(len, ty, |p| inflate.take(p))?,
            b"IEND" => break,
            _ => chunks.body(len, ty, |_| Ok(()))?,
        }
    }
    inflate.finish()
}

/// What the file's header says, for the kinds read here.
#[derive(Debug, Clone, Copy)]
struct Header {
    width: usize,
    height: usize,
    /// 1 or 2.
    bytes_per_sample: usize,
    /// 1 (grey), 2 (grey + alpha), 3 (RGB) or 4 (RGBA).
    channels: usize,
}

impl Header {
    /// `None` for anything but a valid non-interlaced 8- or 16-bit grey / RGB image.
    fn parse(ihdr: &[u8; 13]) -> Option<Self> {
        let be = |i: usize| u32::from_be_bytes([ihdr[i], ihdr[i + 1], ihdr[i + 2], ihdr[i + 3]]);
        let (width, height) = (be(0), be(4));
        let [depth, colour, compression, filter, interlace] =
            [ihdr[8], ihdr[9], ihdr[10], ihdr[11], ihdr[12]];
        let channels = match colour {
            0 => 1,
            4 => 2,
            2 => 3,
            6 => 4,
            _ => return None,
        };
        let ok = width > 0
            && height > 0
            && width <= i32::MAX as u32
            && height <= i32::MAX as u32
            && (depth == 8 || depth == 16)
            && compression == 0
            && filter == 0
            && interlace == 0;
        ok.then_some(Self {
            width: width as usize,
            height: height as usize,
            bytes_per_sample: usize::from(depth / 8),
            channels,
        })
    }

    /// Bytes of one pixel.
    fn bpp(&self) -> usize {
        self.channels * self.bytes_per_sample
    }

    fn row_bytes(&self) -> usize {
        self.width * self.bpp()
    }
}

/// The file read chunk by chunk, a piece at a time.
struct Chunks<R> {
    input: R,
    piece: Vec<u8>,
}

impl<R: Read> Chunks<R> {
    fn new(input: R) -> Self {
        Self {
            input,
            piece: vec![0u8; PIECE],
        }
    }

    /// The next chunk's length and type; `None` where the file ends between chunks.
    fn next(&mut self) -> Result<Option<(usize, [u8; 4])>, ImageError> {
        let mut head = [0u8; 8];
        let mut got = 0;
        while got < head.len() {
            match self.input.read(&mut head[got..]) {
                Ok(0) if got == 0 => return Ok(None),
                Ok(0) => return Err(bad("the file ends inside a chunk header")),
                Ok(n) => got += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(ImageError::IoError(e)),
            }
        }
        let len = u32::from_be_bytes([head[0], head[1], head[2], head[3]]);
        let ty = [head[4], head[5], head[6], head[7]];
        if len > i32::MAX as u32 {
            return Err(bad(format!(
                "a {} chunk declares {len} bytes (at most 2^31 - 1)",
                String::from_utf8_lossy(&ty)
            )));
        }
        Ok(Some((len as usize, ty)))
    }

    /// Hands the body of a chunk of `len` bytes to `each` a piece at a time, then checks the
    /// chunk's CRC.
    fn body(
        &mut self,
        len: usize,
        ty: [u8; 4],
        mut each: impl FnMut(&[u8]) -> Result<(), ImageError>,
    ) -> Result<(), ImageError> {
        let name = || String::from_utf8_lossy(&ty).into_owned();
        let mut crc = crc32fast::Hasher::new();
        crc.update(&ty);
        let Self { input, piece } = self;
        let mut left = len;
        while left > 0 {
            let n = left.min(piece.len());
            read_exact(input, &mut piece[..n], || format!("the {} chunk", name()))?;
            crc.update(&piece[..n]);
            each(&piece[..n])?;
            left -= n;
        }
        let mut stored = [0u8; 4];
        read_exact(input, &mut stored, || {
            format!("the CRC of the {} chunk", name())
        })?;
        if u32::from_be_bytes(stored) != crc.finalize() {
            return Err(bad(format!(
                "the CRC of a {} chunk does not match its data",
                name()
            )));
        }
        Ok(())
    }
}

/// `read_exact`, with a file that ends early worded as ending inside `what()`.
fn read_exact<R: Read>(
    input: &mut R,
    buf: &mut [u8],
    what: impl FnOnce() -> String,
) -> Result<(), ImageError> {
    input.read_exact(buf).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => bad(format!("the file ends inside {}", what())),
        _ => ImageError::IoError(e),
    })
}

/// Rows of filtered image data (each a filter byte and the row), `rows` of them from `from`.
struct Batch {
    data: Vec<u8>,
    from: usize,
    rows: usize,
}

/// The image data inflated into a buffer that keeps the deflate window in front of the rows
/// not yet sent.
struct Inflate {
    d: Box<fdeflate::Decompressor>,
    buf: Vec<u8>,
    /// Bytes of `buf` inflated.
    filled: usize,
    /// Where the first row not yet sent begins in `buf`.
    row_at: usize,
    stride: usize,
    rows_left: usize,
    tx: SyncSender<Batch>,
    spare: Receiver<Vec<u8>>,
    /// Image data not yet inflated, inflated once it reaches `gather_bytes` (the batch size).
    gathered: Vec<u8>,
    gather_bytes: usize,
}

impl Inflate {
    /// Takes a piece of image data, inflating what has gathered once it is long enough.
    fn take(&mut self, piece: &[u8]) -> Result<(), ImageError> {
        self.gathered.extend_from_slice(piece);
        if self.gathered.len() >= self.gather_bytes {
            self.feed_gathered()?;
        }
        Ok(())
    }

    fn feed_gathered(&mut self) -> Result<(), ImageError> {
        let gathered = std::mem::take(&mut self.gathered);
        let fed = self.feed(&gathered);
        self.gathered = gathered;
        self.gathered.clear();
        fed
    }

    fn feed(&mut self, mut input: &[u8]) -> Result<(), ImageError> {
        while !input.is_empty() && self.rows_left > 0 && !self.d.is_done() {
            let (used, made) = self
                .d
                .read(input, &mut self.buf, self.filled, false)
                .map_err(|e| bad(format!("the image data is not a valid zlib stream ({e:?})")))?;
            input = &input[used..];
            self.filled += made;
            if self.filled == self.buf.len() {
                self.ship()?;
            } else if used == 0 && made == 0 {
                break;
            }
        }
        Ok(())
    }

    /// After the last image data: what the decompressor still holds, then the last rows.
    fn finish(&mut self) -> Result<(), ImageError> {
        self.feed_gathered()?;
        while self.rows_left > 0 && !self.d.is_done() {
            let (_, made) = self
                .d
                .read(&[], &mut self.buf, self.filled, false)
                .map_err(|e| bad(format!("the image data is not a valid zlib stream ({e:?})")))?;
            self.filled += made;
            if self.filled < self.buf.len() {
                break;
            }
            self.ship()?;
        }
        self.ship()?;
        if self.rows_left > 0 {
            return Err(bad(format!(
                "the image data ends {} row(s) before the last row",
                self.rows_left
            )));
        }
        Ok(())
    }

    /// Sends the whole rows inflated so far and carries the window (and a part row) over into
    /// a fresh buffer.
    fn ship(&mut self) -> Result<(), ImageError> {
        let rows = ((self.filled - self.row_at) / self.stride).min(self.rows_left);
        let end = self.row_at + rows * self.stride;
        let keep_from = end.min(self.filled.saturating_sub(LOOKBACK));
        let mut next = self
            .spare
            .try_recv()
            .unwrap_or_else(|_| vec![0u8; self.buf.len()]);
        let carried = self.filled - keep_from;
        next[..carried].copy_from_slice(&self.buf[keep_from..self.filled]);
        let full = std::mem::replace(&mut self.buf, next);
        let from = self.row_at;
        self.filled = carried;
        self.row_at = end - keep_from;
        self.rows_left -= rows;
        if rows > 0 {
            self.tx
                .send(Batch {
                    data: full,
                    from,
                    rows,
                })
                .map_err(|_| bad("unfiltering stopped"))?;
        }
        Ok(())
    }
}

/// The second stage: rows unfiltered into `rgb` and every finished band reduced to its maps.
fn unfilter_all(
    header: Header,
    rx: Receiver<Batch>,
    spare: SyncSender<Vec<u8>>,
    rgb: &mut [u8],
    geometry: Geometry,
    band_rows: usize,
) -> Result<Vec<BandMaps>, ImageError> {
    let row_bytes = header.row_bytes();
    let stride = row_bytes + 1;
    let w3 = 3 * header.width;
    let mut prev = vec![0u8; row_bytes];
    let mut cur = vec![0u8; row_bytes];
    let mut maps = Vec::new();
    let mut y = 0usize;
    for batch in rx {
        for r in 0..batch.rows {
            let at = batch.from + r * stride;
            let row = &batch.data[at..at + stride];
            unfilter(row[0], header.bpp(), &prev, &row[1..], &mut cur).map_err(|kind| {
                bad(format!(
                    "row {y} has filter type {kind} (PNG defines 0 to 4)"
                ))
            })?;
            to_rgb(&cur, header, &mut rgb[y * w3..(y + 1) * w3]);
            std::mem::swap(&mut prev, &mut cur);
            y += 1;
            if y.is_multiple_of(band_rows) || y == header.height {
                let y0 = (y - 1) / band_rows * band_rows;
                maps.push(geometry.band(y0, &rgb[y0 * w3..y * w3]));
            }
        }
        let _ = spare.try_send(batch.data);
    }
    Ok(maps)
}

/// Undoes one row's filter; `Err` with the filter type when it is not one of PNG's five.
fn unfilter(kind: u8, bpp: usize, prev: &[u8], row: &[u8], out: &mut [u8]) -> Result<(), u8> {
    match bpp {
        1 => unfilter_n::<1>(kind, prev, row, out),
        2 => unfilter_n::<2>(kind, prev, row, out),
        3 => unfilter_n::<3>(kind, prev, row, out),
        4 => unfilter_n::<4>(kind, prev, row, out),
        6 => unfilter_n::<6>(kind, prev, row, out),
        _ => unfilter_n::<8>(kind, prev, row, out),
    }
}

/// [`unfilter`] for `N` bytes per pixel, pixel by pixel with the left neighbours carried.
fn unfilter_n<const N: usize>(kind: u8, prev: &[u8], row: &[u8], out: &mut [u8]) -> Result<(), u8> {
    let px = out
        .chunks_exact_mut(N)
        .zip(row.chunks_exact(N))
        .zip(prev.chunks_exact(N));
    match kind {
        0 => out.copy_from_slice(row),
        1 => {
            let mut a = [0u8; N];
            for ((o, r), _) in px {
                for k in 0..N {
                    a[k] = r[k].wrapping_add(a[k]);
                }
                o.copy_from_slice(&a);
            }
        }
        2 => {
            for ((o, r), b) in px {
                for k in 0..N {
                    o[k] = r[k].wrapping_add(b[k]);
                }
            }
        }
        3 => {
            let mut a = [0u8; N];
            for ((o, r), b) in px {
                for k in 0..N {
                    let mean = ((u16::from(a[k]) + u16::from(b[k])) / 2) as u8;
                    a[k] = r[k].wrapping_add(mean);
                }
                o.copy_from_slice(&a);
            }
        }
        4 => {
            let (mut a, mut c) = ([0u8; N], [0u8; N]);
            for ((o, r), b) in px {
                for k in 0..N {
                    a[k] = r[k].wrapping_add(paeth(a[k], b[k], c[k]));
                }
                o.copy_from_slice(&a);
                c.copy_from_slice(b);
            }
        }
        other => return Err(other),
    }
    Ok(())
}

/// PNG's Paeth predictor: of left, up and up-left, the one nearest to left + up - up-left.
fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let (a, b, c) = (i16::from(a), i16::from(b), i16::from(c));
    let pa = (b - c).abs();
    let pb = (a - c).abs();
    let pc = (a + b - 2 * c).abs();
    let best = if pa <= pb && pa <= pc {
        a
    } else if pb <= pc {
        b
    } else {
        c
    };
    best as u8
}

/// One unfiltered row as RGB.
fn to_rgb(src: &[u8], header: Header, dst: &mut [u8]) {
    match (header.bytes_per_sample, header.channels) {
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
mod tests {
    use super::*;
    use std::io::Cursor;

    /// The size limit of the command (`files::MAX_RGB_BYTES`).
    const MAX: usize = 512 << 20;

    /// 16-bit RGBA samples with noise, flat runs and repeated rows (matches reaching far back).
    fn samples(w: usize, h: usize) -> Vec<[u16; 4]> {
        let mut state = 0x2545_f491_u32;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        let mut px = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let p = if y % 7 == 3 && y > 0 {
                    px[(y - 1) * w + x]
                } else if (x / 40 + y / 9) % 3 == 0 {
                    [40_000, 39_000, 38_000, 65_535]
                } else {
                    let r = next();
                    [
                        r as u16,
                        (r >> 16) as u16,
                        (x * 300 + y) as u16,
                        (r >> 8) as u16,
                    ]
                };
                px.push(p);
            }
        }
        px
    }

    /// `colour` as a PNG with `filter`, its image data cut into IDAT chunks of `chunk` bytes.
    fn encode(
        w: usize,
        h: usize,
        colour: png::ColorType,
        depth: png::BitDepth,
        filter: png::Filter,
        chunk: usize,
    ) -> Vec<u8> {
        let channels = match colour {
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Rgb => 3,
            _ => 4,
        };
        let mut data = Vec::new();
        for p in samples(w, h) {
            for &v in &p[..channels] {
                match depth {
                    png::BitDepth::Sixteen => data.extend_from_slice(&v.to_be_bytes()),
                    _ => data.push((v >> 8) as u8),
                }
            }
        }
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, w as u32, h as u32);
        enc.set_color(colour);
        enc.set_depth(depth);
        enc.set_filter(filter);
        let mut writer = enc.write_header().expect("header");
        let mut stream = writer.stream_writer_with_size(chunk).expect("stream");
        std::io::Write::write_all(&mut stream, &data).expect("data");
        stream.finish().expect("finish");
        drop(writer);
        out
    }

    fn read_both(bytes: &[u8], batch_bytes: usize) -> (RgbImage, Prepared) {
        read_batched(Cursor::new(bytes), batch_bytes, MAX)
            .expect("read")
            .expect("a kind read here")
    }

    #[test]
    fn every_filter_colour_type_and_depth_reads_as_the_image_crate_does() {
        let (w, h) = (203, 131);
        let colours = [
            png::ColorType::Grayscale,
            png::ColorType::GrayscaleAlpha,
            png::ColorType::Rgb,
            png::ColorType::Rgba,
        ];
        let filters = [
            png::Filter::NoFilter,
            png::Filter::Sub,
            png::Filter::Up,
            png::Filter::Avg,
            png::Filter::Paeth,
            png::Filter::Adaptive,
        ];
        for colour in colours {
            for depth in [png::BitDepth::Eight, png::BitDepth::Sixteen] {
                for filter in filters {
                    let bytes = encode(w, h, colour, depth, filter, 997);
                    let want = image::load_from_memory(&bytes)
                        .expect("image crate")
                        .into_rgb8();
                    let built = Prepared::build(&want);
                    // Two rows a batch (the window carried over again and again) and the default.
                    for batch in [1, BATCH_BYTES] {
                        let (got, prepared) = read_both(&bytes, batch);
                        let case = format!("{colour:?} {depth:?} {filter:?} batch {batch}");
                        assert!(got == want, "{case}: pixels differ");
                        assert_eq!(prepared.map.min_red, built.map.min_red, "{case}");
                        assert_eq!(prepared.paper.level, built.paper.level, "{case}");
                    }
                }
            }
        }
    }

    /// A PNG put together by hand: signature, IHDR, `idat` (zlib) in one chunk, IEND.
    fn by_hand(w: u32, h: u32, colour: u8, interlace: u8, raw: &[u8]) -> Vec<u8> {
        let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
        let mut chunk = |ty: &[u8; 4], data: &[u8]| {
            out.extend_from_slice(&(data.len() as u32).to_be_bytes());
            out.extend_from_slice(ty);
            out.extend_from_slice(data);
            let mut crc = crc32fast::Hasher::new();
            crc.update(ty);
            crc.update(data);
            out.extend_from_slice(&crc.finalize().to_be_bytes());
        };
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&w.to_be_bytes());
        ihdr.extend_from_slice(&h.to_be_bytes());
        ihdr.extend_from_slice(&[8, colour, 0, 0, interlace]);
        chunk(b"IHDR", &ihdr);
        if colour == 3 {
            chunk(b"PLTE", &[0, 0, 0, 255, 255, 255]);
        }
        chunk(b"IDAT", &fdeflate::compress_to_vec(raw));
        chunk(b"IEND", &[]);
        out
    }

    fn message(bytes: &[u8]) -> String {
        match read_batched(Cursor::new(bytes), BATCH_BYTES, MAX) {
            Err(e) => e.to_string(),
            Ok(_) => "read without an error".into(),
        }
    }

    #[test]
    fn damaged_files_are_errors_that_say_what_is_wrong() {
        // 4 x 3 grey: each row a filter byte and 4 samples.
        let mut raw = Vec::new();
        for y in 0..3u8 {
            raw.push(1);
            raw.extend_from_slice(&[y, 1, 2, 3]);
        }
        let good = by_hand(4, 3, 0, 0, &raw);
        let (img, _) = read_both(&good, BATCH_BYTES);
        assert_eq!(img.get_pixel(3, 2).0, [2 + 6, 8, 8], "Sub filter undone");

        let mut bad_filter = raw.clone();
        bad_filter[5] = 7;
        let m = message(&by_hand(4, 3, 0, 0, &bad_filter));
        assert!(m.contains("row 1 has filter type 7"), "{m}");

        let m = message(&by_hand(4, 3, 0, 0, &raw[..7]));
        assert!(m.contains("ends 2 row(s) before the last row"), "{m}");

        let mut crc = good.clone();
        let at = crc.len() - 12 - 5; // inside the IDAT chunk's data
        crc[at] ^= 0x10;
        let m = message(&crc);
        assert!(m.contains("CRC") || m.contains("zlib"), "{m}");

        let m = message(&good[..good.len() - 20]);
        assert!(m.contains("ends inside"), "{m}");

        let mut long = good.clone();
        long[33..37].copy_from_slice(&0x8000_0000u32.to_be_bytes()); // the IDAT chunk's length
        let m = message(&long);
        assert!(m.contains("at most 2^31 - 1"), "{m}");

        // 60 000 x 60 000 RGB is 10.8 GB: refused from the header, before anything is allocated.
        assert!(matches!(
            read_batched(
                Cursor::new(by_hand(60_000, 60_000, 2, 0, &[])),
                BATCH_BYTES,
                MAX
            ),
            Err(ImageError::Limits(_))
        ));
    }

    #[test]
    fn palette_interlaced_and_endless_row_files_are_left_to_the_image_crate() {
        // 6 M pixels in one row: 18 MB a row.
        let wide = by_hand(6_000_000, 1, 2, 0, &[]);
        assert!(read_batched(Cursor::new(&wide), BATCH_BYTES, MAX)
            .expect("no error")
            .is_none());
        let raw = [0u8, 0, 1, 1, 0, 0, 1, 0, 1, 0];
        let palette = by_hand(4, 2, 3, 0, &raw);
        assert!(read_batched(Cursor::new(&palette), BATCH_BYTES, MAX)
            .expect("no error")
            .is_none());
        let interlaced = by_hand(4, 2, 0, 1, &raw);
        assert!(read_batched(Cursor::new(&interlaced), BATCH_BYTES, MAX)
            .expect("no error")
            .is_none());
    }

    #[test]
    fn no_damage_to_a_file_makes_reading_panic() {
        let good = encode(
            61,
            47,
            png::ColorType::Rgb,
            png::BitDepth::Eight,
            png::Filter::Adaptive,
            300,
        );
        let mut state = 0x9e37_79b9_u32;
        for _ in 0..3000 {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let mut bytes = good.clone();
            let flips = 1 + (state >> 28) as usize;
            for f in 0..flips {
                let r = state
                    .rotate_left(7 * f as u32 + 3)
                    .wrapping_mul(2_654_435_761);
                let at = r as usize % bytes.len();
                bytes[at] ^= 1 << (r >> 29);
            }
            if state & 7 == 0 {
                bytes.truncate(state as usize % bytes.len());
            }
            // An error or an image, never a panic (a panic fails the test).
            let _ = read_batched(Cursor::new(&bytes), 1, MAX);
        }
    }
}
