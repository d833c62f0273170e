//! The local paper level: photos are lit unevenly (a gradient across the sheet, the phone's
//! shadow), so "dark" is measured against the paper around a pixel, not one global level.
//!
//! The image is cut into square blocks; each block's paper level per channel is a high
//! percentile of its pixels (the paper is the brightest large thing in a block), the map is
//! max-filtered over 3 x 3 blocks (blocks covered by a fiducial or a line take their
//! neighbours' paper) and smoothed; a pixel's level is interpolated bilinearly between block
//! centres.

#[cfg(test)]
use image::RgbImage;

/// Block-wise paper level with bilinear interpolation.
#[derive(Debug, Clone)]
pub(crate) struct PaperMap {
    /// Block side, pixels.
    pub block: usize,
    pub w: usize,
    pub h: usize,
    /// Level per block and channel, 0..255.
    pub level: Vec<[f32; 3]>,
}

/// A whole-image map of square blocks whose side follows the image's short side: the paper
/// level ([`PaperMap`]) and the coarse map of darkest values
/// ([`super::raster::CoarseMap`]).
pub(crate) trait BlockMap {
    /// Blocks across the image's short side (about).
    const BLOCKS_ACROSS: usize;
    /// The smallest block side, pixels.
    const MIN_BLOCK_PX: usize;

    /// Block side for an image of `w` x `h` pixels.
    fn block_size_for_dims(w: usize, h: usize) -> usize {
        (w.min(h) / Self::BLOCKS_ACROSS).max(Self::MIN_BLOCK_PX)
    }

    /// [`Self::block_size_for_dims`] of `img`.
    #[cfg(test)]
    fn block_size_for(img: &RgbImage) -> usize {
        Self::block_size_for_dims(img.width() as usize, img.height() as usize)
    }
}

/// Blocks of about 1/150 of the short side (1.4 mm on an A4 scan), at least 8 pixels.
impl BlockMap for PaperMap {
    const BLOCKS_ACROSS: usize = 150;
    const MIN_BLOCK_PX: usize = 8;
}

/// Percentile of a block's pixels taken as its paper level.
const PAPER_PERCENTILE: f64 = 0.8;

impl PaperMap {
    /// Builds the map with blocks of `block` pixels in one pass (the reference for the banded
    /// build of [`super::stages::prepare`]).
    #[cfg(test)]
    pub fn build(img: &RgbImage, block: usize) -> Self {
        let block = block.max(4);
        let (iw, ih) = (img.width() as usize, img.height() as usize);
        let (w, h) = (iw.div_ceil(block), ih.div_ceil(block));
        let level = Self::band(img.as_raw(), iw, ih, 0, ih, block);
        Self::from_block_levels(block, w, h, &level)
    }

    /// The raw paper level (a high percentile per channel, sampling every second pixel of
    /// every second row) of the block rows of a band of `n_rows` image rows starting at `y0`
    /// (a multiple of `block`); `rows` holds those RGB rows.
    pub(crate) fn band(
        rows: &[u8],
        iw: usize,
        ih: usize,
        y0: usize,
        n_rows: usize,
        block: usize,
    ) -> Vec<[f32; 3]> {
        let w = iw.div_ceil(block);
        let (by0, by1) = (y0 / block, (y0 + n_rows).min(ih).div_ceil(block));
        let mut level = vec![[255.0f32; 3]; w * by1.saturating_sub(by0)];
        let mut hist = [[0u32; 256]; 3];
        for by in by0..by1 {
            for bx in 0..w {
                for hc in hist.iter_mut() {
                    hc.fill(0);
                }
                let mut n = 0u32;
                let (x0, x1) = (bx * block, ((bx + 1) * block).min(iw));
                for y in (by * block..((by + 1) * block).min(ih).min(y0 + n_rows)).step_by(2) {
                    let row = &rows[3 * iw * (y - y0)..3 * iw * (y - y0 + 1)];
                    for px in row[3 * x0..3 * x1].chunks_exact(6) {
                        hist[0][px[0] as usize] += 1;
                        hist[1][px[1] as usize] += 1;
                        hist[2][px[2] as usize] += 1;
                        n += 1;
                    }
                    if (x1 - x0) % 2 == 1 {
                        let px = &row[3 * (x1 - 1)..3 * x1];
                        for c in 0..3 {
                            hist[c][px[c] as usize] += 1;
                        }
                        n += 1;
                    }
                }
                let target = ((n as f64 * PAPER_PERCENTILE).ceil() as u32).max(1);
                let out = &mut level[(by - by0) * w + bx];
                for c in 0..3 {
                    let mut acc = 0u32;
                    for (v, &k) in hist[c].iter().enumerate() {
                        acc += k;
                        if acc >= target {
                            out[c] = (v as f32).max(1.0);
                            break;
                        }
                    }
                }
            }
        }
        level
    }

    /// The map from the raw block levels (`w x h` blocks of `block` pixels): max-filtered over
    /// 3 x 3 blocks and smoothed.
    pub(crate) fn from_block_levels(block: usize, w: usize, h: usize, raw: &[[f32; 3]]) -> Self {
        let level = smooth(&max_filter(raw, w, h), w, h);
        Self { block, w, h, level }
    }

    /// Red paper level of the block holding pixel coordinates `(x, y)` (no interpolation: for
    /// thresholds).
    #[cfg(test)]
    pub fn red_near(&self, x: f64, y: f64) -> f32 {
        self.level[self.row_of(y) * self.w + self.col_of(x)][0]
    }

    /// The map max-filtered `passes` more times over 3 x 3 blocks: the paper's level next to a
    /// mark several blocks wide (a corner disc), where this map holds the mark itself.
    pub fn ceiling(&self, passes: usize) -> Self {
        let mut level = self.level.clone();
        for _ in 0..passes {
            level = max_filter(&level, self.w, self.h);
        }
        Self {
            level,
            ..self.clone()
        }
    }

    /// Block column holding pixel x coordinate `x`.
    #[inline]
    pub fn col_of(&self, x: f64) -> usize {
        ((x.max(0.0) as usize) / self.block).min(self.w - 1)
    }

    /// Block row holding pixel y coordinate `y`.
    #[inline]
    pub fn row_of(&self, y: f64) -> usize {
        ((y.max(0.0) as usize) / self.block).min(self.h - 1)
    }

    /// Paper level at pixel coordinates `(x, y)` (pixel centres at `i + 0.5`).
    #[inline]
    pub fn at(&self, x: f64, y: f64) -> [f32; 3] {
        let b = self.block as f64;
        let fx = (x / b - 0.5).clamp(0.0, (self.w - 1) as f64);
        let fy = (y / b - 0.5).clamp(0.0, (self.h - 1) as f64);
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.w - 1), (y0 + 1).min(self.h - 1));
        let (ax, ay) = ((fx - x0 as f64) as f32, (fy - y0 as f64) as f32);
        let l = |xx: usize, yy: usize| self.level[yy * self.w + xx];
        let (a, b2, c, d) = (l(x0, y0), l(x1, y0), l(x0, y1), l(x1, y1));
        let mut out = [0.0f32; 3];
        for k in 0..3 {
            out[k] = (1.0 - ay) * ((1.0 - ax) * a[k] + ax * b2[k])
                + ay * ((1.0 - ax) * c[k] + ax * d[k]);
        }
        out
    }
}

fn max_filter(level: &[[f32; 3]], w: usize, h: usize) -> Vec<[f32; 3]> {
    let mut out = level.to_vec();
    for y in 0..h {
        for x in 0..w {
            let mut m = [0.0f32; 3];
            for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                    let v = level[yy * w + xx];
                    for c in 0..3 {
                        m[c] = m[c].max(v[c]);
                    }
                }
            }
            out[y * w + x] = m;
        }
    }
    out
}

fn smooth(level: &[[f32; 3]], w: usize, h: usize) -> Vec<[f32; 3]> {
    let mut out = level.to_vec();
    for y in 0..h {
        for x in 0..w {
            let (mut s, mut n) = ([0.0f32; 3], 0.0f32);
            for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                    let v = level[yy * w + xx];
                    for c in 0..3 {
                        s[c] += v[c];
                    }
                    n += 1.0;
                }
            }
            out[y * w + x] = s.map(|v| v / n);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_is_followed_and_dark_marks_ignored() {
        let mut img = RgbImage::new(400, 100);
        for (x, _, p) in img.enumerate_pixels_mut() {
            let v = (120.0 + 0.3 * x as f64) as u8;
            *p = image::Rgb([v, v, v]);
        }
        for y in 40..60 {
            for x in 190..210 {
                img.put_pixel(x, y, image::Rgb([10, 10, 10]));
            }
        }
        let map = PaperMap::build(&img, 16);
        for x in [20.0, 200.0, 380.0] {
            let expect = 120.0 + 0.3 * x;
            let got = map.at(x, 50.0)[0] as f64;
            assert!((got - expect).abs() < 8.0, "x {x}: {got} vs {expect}");
        }
    }
}
