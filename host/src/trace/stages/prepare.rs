//! The whole-image passes (the local paper level and the coarse map of darkest red values),
//! computed band by band: a band is a run of image rows that holds whole blocks of both maps,
//! so bands are independent. They run on several threads over a decoded image, or on a worker
//! thread while a PNG is still being decoded ([`crate::trace::load`]). Every band's result depends on
//! its rows alone and the bands are put together in order, so the maps are the same whatever
//! the number of threads.

mod params;

pub use params::PrepareParams;

use crate::trace::paper::{BlockMap, PaperMap};
use crate::trace::raster::CoarseMap;
use crate::trace::tone::Tone;
use image::RgbImage;

/// The whole-image maps of one image, ready for [`crate::trace::trace_prepared`].
#[derive(Debug, Clone)]
pub struct Prepared {
    pub(crate) paper: PaperMap,
    pub(crate) map: CoarseMap,
    /// Width and height of the image the maps were built from, pixels.
    size: [usize; 2],
    /// The tone curve the image was linearised through while it was read (the file said so),
    /// or [`Tone::assumed`] (left to [`crate::trace::trace_prepared`] to measure).
    pub(crate) tone: Tone,
    /// The numbers the maps were built with.
    params: PrepareParams,
}

impl Prepared {
    /// The tone curve the image was linearised through, and how it was known.
    pub fn tone(&self) -> &Tone {
        &self.tone
    }

    /// Whether these are the maps of an image of `img`'s size, built with `params`.
    pub fn fits(&self, img: &RgbImage, params: &PrepareParams) -> bool {
        self.size == [img.width() as usize, img.height() as usize] && self.params == *params
    }

    /// Builds the maps of `img` with the tuned numbers ([`Self::build_with`]).
    pub fn build(img: &RgbImage) -> Self {
        Self::build_with(img, &PrepareParams::default())
    }

    /// Builds the maps of `img`, with the bands shared among the available cores.
    pub fn build_with(img: &RgbImage, params: &PrepareParams) -> Self {
        let mut acc = Bands::new(img.width() as usize, img.height() as usize, params);
        let rows = acc.band_rows;
        let raw = img.as_raw();
        let band_bytes = 3 * acc.iw * rows;
        let bands: Vec<&[u8]> = raw.chunks(band_bytes.max(1)).collect();
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .clamp(1, params.max_threads)
            .min(bands.len().max(1));
        let per = bands.len().div_ceil(threads.max(1)).max(1);
        let geometry = acc.geometry();
        let results: Vec<Vec<BandMaps>> = std::thread::scope(|s| {
            let handles: Vec<_> = bands
                .chunks(per)
                .enumerate()
                .map(|(t, group)| {
                    s.spawn(move || {
                        group
                            .iter()
                            .enumerate()
                            .map(|(i, b)| geometry.band((t * per + i) * rows, b))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| {
                    h.join()
                        .unwrap_or_else(|payload| std::panic::resume_unwind(payload))
                })
                .collect()
        });
        for b in results.into_iter().flatten() {
            acc.push(b);
        }
        acc.finish()
    }
}

/// Block sizes and image size: what a band needs to be reduced on its own.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Geometry {
    iw: usize,
    ih: usize,
    paper_block: usize,
    coarse_k: usize,
}

/// One band reduced: its rows of both maps.
pub(crate) struct BandMaps {
    min_red: Vec<u8>,
    level: Vec<[f32; 3]>,
}

impl Geometry {
    /// Reduces the band of rows starting at image row `y0` (a multiple of the band height);
    /// `rows` holds whole RGB rows.
    pub(crate) fn band(&self, y0: usize, rows: &[u8]) -> BandMaps {
        let n_rows = rows.len() / (3 * self.iw).max(1);
        BandMaps {
            min_red: CoarseMap::band(rows, self.iw, n_rows, self.coarse_k),
            level: PaperMap::band(rows, self.iw, self.ih, y0, n_rows, self.paper_block),
        }
    }
}

/// Band results gathered in order.
pub(crate) struct Bands {
    pub(crate) iw: usize,
    ih: usize,
    /// Rows per band: a multiple of both block sizes.
    pub(crate) band_rows: usize,
    paper_block: usize,
    coarse_k: usize,
    min_red: Vec<u8>,
    level: Vec<[f32; 3]>,
    params: PrepareParams,
}

impl Bands {
    pub(crate) fn new(iw: usize, ih: usize, params: &PrepareParams) -> Self {
        let paper_block = PaperMap::block_size_for_dims(iw, ih).max(params.min_paper_block_px);
        let coarse_k = CoarseMap::block_size_for_dims(iw, ih);
        let l = lcm(paper_block, coarse_k);
        let band_rows = l * params.min_band_rows.div_ceil(l);
        Self {
            iw,
            ih,
            band_rows,
            paper_block,
            coarse_k,
            min_red: Vec::new(),
            level: Vec::new(),
            params: *params,
        }
    }

    pub(crate) fn geometry(&self) -> Geometry {
        Geometry {
            iw: self.iw,
            ih: self.ih,
            paper_block: self.paper_block,
            coarse_k: self.coarse_k,
        }
    }

    /// Appends the next band's maps (bands must come in image order).
    pub(crate) fn push(&mut self, b: BandMaps) {
        self.min_red.extend(b.min_red);
        self.level.extend(b.level);
    }

    pub(crate) fn finish(self) -> Prepared {
        let k = self.coarse_k;
        let (cw, ch) = (self.iw.div_ceil(k), self.ih.div_ceil(k));
        let mut min_red = self.min_red;
        min_red.resize(cw * ch, 255);
        let b = self.paper_block;
        let (pw, ph) = (self.iw.div_ceil(b), self.ih.div_ceil(b));
        let mut level = self.level;
        level.resize(pw * ph, [255.0; 3]);
        Prepared {
            paper: PaperMap::from_block_levels(b, pw, ph, &level),
            map: CoarseMap {
                k,
                w: cw,
                h: ch,
                min_red,
            },
            size: [self.iw, self.ih],
            tone: Tone::assumed(),
            params: self.params,
        }
    }
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

fn lcm(a: usize, b: usize) -> usize {
    let (a, b) = (a.max(1), b.max(1));
    a / gcd(a, b) * b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn banded_maps_equal_whole_image_maps() {
        // An odd size, so that the last band and the last blocks are partial.
        let (w, h) = (1303u32, 1777u32);
        let mut img = RgbImage::new(w, h);
        for (x, y, p) in img.enumerate_pixels_mut() {
            let v = ((x * 7 + y * 13) % 251) as u8;
            *p = image::Rgb([v, v.wrapping_mul(3), 255 - v]);
        }
        let prepared = Prepared::build(&img);
        let paper = PaperMap::build(&img, PaperMap::block_size_for(&img));
        let map = CoarseMap::build(&img, CoarseMap::block_size_for(&img));
        assert_eq!(prepared.map.min_red, map.min_red);
        assert_eq!((prepared.map.w, prepared.map.h), (map.w, map.h));
        assert_eq!(prepared.paper.level, paper.level);
        assert_eq!((prepared.paper.w, prepared.paper.h), (paper.w, paper.h));
        // Band by band in one thread, as while decoding.
        let mut acc = Bands::new(w as usize, h as usize, &PrepareParams::default());
        let g = acc.geometry();
        let rows = acc.band_rows;
        for (i, band) in img.as_raw().chunks(3 * w as usize * rows).enumerate() {
            acc.push(g.band(i * rows, band));
        }
        let serial = acc.finish();
        assert_eq!(serial.map.min_red, map.min_red);
        assert_eq!(serial.paper.level, paper.level);
    }
}
