//! The two-stage reader against the `image` crate: the same pixels and maps for every colour
//! type, depth and filter; damaged files are errors that say what is wrong, never a panic.

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

/// [`read_batched`] at the test's limit with the tuned prepare numbers.
fn read<R: BufRead + Seek>(
    input: R,
    batch_bytes: usize,
) -> Result<Option<(RgbImage, Prepared)>, ImageError> {
    read_batched(input, batch_bytes, MAX, &PrepareParams::default())
}

fn read_both(bytes: &[u8], batch_bytes: usize) -> (RgbImage, Prepared) {
    read(Cursor::new(bytes), batch_bytes)
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

/// `raw` as a zlib stream of stored (uncompressed) deflate blocks.
fn stored_zlib(raw: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = if raw.is_empty() {
        vec![&[]]
    } else {
        raw.chunks(65_535).collect()
    };
    for (i, b) in blocks.iter().enumerate() {
        out.push(u8::from(i + 1 == blocks.len()));
        let len = b.len() as u16;
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(b);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &x in raw {
        a = (a + u32::from(x)) % 65_521;
        b = (b + a) % 65_521;
    }
    out.extend_from_slice(&((b << 16) | a).to_be_bytes());
    out
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
    chunk(b"IDAT", &stored_zlib(raw));
    chunk(b"IEND", &[]);
    out
}

fn message(bytes: &[u8]) -> String {
    match read(Cursor::new(bytes), BATCH_BYTES) {
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
    assert!(m.contains("filter method 7"), "{m}");

    let m = message(&by_hand(4, 3, 0, 0, &raw[..7]));
    assert!(m.contains("not have enough data"), "{m}");

    let mut crc = good.clone();
    let at = crc.len() - 12 - 5; // inside the IDAT chunk's data
    crc[at] ^= 0x10;
    let m = message(&crc);
    assert!(m.contains("CRC") || m.contains("zlib"), "{m}");

    let m = message(&good[..good.len() - 20]);
    assert!(m.contains("cut short"), "{m}");

    let mut long = good.clone();
    // The IDAT chunk's length, 2 GB: the file ends long before.
    long[33..37].copy_from_slice(&0x8000_0000u32.to_be_bytes());
    let m = message(&long);
    assert!(m.contains("cut short"), "{m}");

    // 60 000 x 60 000 RGB is 10.8 GB: refused from the header, before anything is allocated.
    assert!(matches!(
        read(Cursor::new(by_hand(60_000, 60_000, 2, 0, &[])), BATCH_BYTES),
        Err(ImageError::Limits(_))
    ));
}

/// A `w` x `h` PNG of `colour` at `depth` with samples from `seed`, a palette of 256 entries for
/// an indexed one, and `trns` as its `tRNS` chunk.
fn encode_expanded(
    (w, h): (u32, u32),
    colour: png::ColorType,
    depth: png::BitDepth,
    trns: Option<&[u8]>,
    seed: u32,
) -> Vec<u8> {
    let bits = depth as usize * colour.samples();
    let row_bytes = (w as usize * bits).div_ceil(8);
    let mut state = seed | 1;
    let data: Vec<u8> = (0..row_bytes * h as usize)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 7) as u8
        })
        .collect();
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(colour);
    enc.set_depth(depth);
    if colour == png::ColorType::Indexed {
        enc.set_palette(
            (0..768u32)
                .map(|i| (i * 37 % 251) as u8)
                .collect::<Vec<u8>>(),
        );
    }
    if let Some(t) = trns {
        enc.set_trns(t.to_vec());
    }
    let mut writer = enc.write_header().expect("header");
    writer.write_image_data(&data).expect("data");
    drop(writer);
    out
}

#[test]
fn palette_low_bit_grey_and_transparency_read_as_the_image_crate_does() {
    use png::{BitDepth as D, ColorType as C};
    let cases: [(C, D, Option<&[u8]>); 11] = [
        (C::Indexed, D::Eight, None),
        (C::Indexed, D::Eight, Some(&[0, 128, 255])),
        (C::Indexed, D::Four, None),
        (C::Indexed, D::One, Some(&[7])),
        (C::Grayscale, D::One, None),
        (C::Grayscale, D::Two, None),
        (C::Grayscale, D::Four, Some(&[0, 3])),
        (C::Grayscale, D::Eight, Some(&[0, 200])),
        (C::Grayscale, D::Sixteen, Some(&[1, 2])),
        (C::Rgb, D::Eight, Some(&[0, 9, 0, 9, 0, 9])),
        (C::Rgb, D::Sixteen, Some(&[1, 2, 3, 4, 5, 6])),
    ];
    for (i, (colour, depth, trns)) in cases.into_iter().enumerate() {
        let bytes = encode_expanded((97, 61), colour, depth, trns, 17 + i as u32);
        let want = image::load_from_memory(&bytes)
            .expect("image crate")
            .into_rgb8();
        let built = Prepared::build(&want);
        let (got, prepared) = read_both(&bytes, 1);
        let case = format!("{colour:?} {depth:?} tRNS {trns:?}");
        assert!(got == want, "{case}: pixels differ");
        assert_eq!(prepared.map.min_red, built.map.min_red, "{case}");
        assert_eq!(prepared.paper.level, built.paper.level, "{case}");
    }
}

#[test]
fn interlaced_and_endless_row_files_are_left_to_the_image_crate() {
    // 6 M pixels in one row: 18 MB a row.
    let wide = by_hand(6_000_000, 1, 2, 0, &[]);
    assert!(read(Cursor::new(&wide), BATCH_BYTES)
        .expect("no error")
        .is_none());
    let raw = [0u8, 0, 1, 1, 0, 0, 1, 0, 1, 0];
    let interlaced = by_hand(4, 2, 0, 1, &raw);
    assert!(read(Cursor::new(&interlaced), BATCH_BYTES)
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
        let _ = read(Cursor::new(&bytes), 1);
    }
}
