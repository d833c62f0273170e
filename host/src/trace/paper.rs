//! The local paper level: photos are lit unevenly (a gradient across the sheet, the phone's
//! shadow), so "dark" is measured against the paper around a pixel, not one global level.
//!
//! The image is cut into square blocks; each block's paper level per channel is a high
//! percentile of its pixels (the paper is the brightest large thing in a block), the map is
//! max-filtered over 3 x 3 blocks (blocks covered by a fiducial or a line take their
//! neighbours' paper) and smoothed; a pixel's level is interpolated bilinearly between block
//! centres.

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

/// Percentile of a block's pixels taken as its paper level.
const PAPER_PERCENTILE: f64 = 0.8;

impl PaperMap {
    /// Builds the map with blocks of `block` pixels (sampling every second pixel).
    pub fn build(img: &RgbImage, block: usize) -> Self {
        let block = block.max(4);
        let (iw, ih) = (img.width() as usize, img.height() as usize);
        let (w, h) = (iw.div_ceil(block), ih.div_ceil(block));
        let raw = img.as_raw();
        let mut level = vec![[255.0f32; 3]; w * h];
        let mut hist = vec![[0u32; 256]; 3];
        for by in 0..h {
            for bx in 0..w {
                for hc in hist.iter_mut() {
                    hc.fill(0);
                }
                let mut n = 0u32;
                for y in (by * block..((by + 1) * block).min(ih)).step_by(2) {
                    let row = &raw[3 * iw * y..3 * iw * (y + 1)];
                    for x in (bx * block..((bx + 1) * block).min(iw)).step_by(2) {
                        for c in 0..3 {
                            hist[c][row[3 * x + c] as usize] += 1;
                        }
                        n += 1;
                    }
                }
                let target = (n as f64 * PAPER_PERCENTILE).ceil() as u32;
                let out = &mut level[by * w + bx];
                for c in 0..3 {
                    let mut acc = 0u32;
                    for (v, &k) in hist[c].iter().enumerate() {
                        acc += k;
                        if acc >= target.max(1) {
                            out[c] = (v as f32).max(1.0);
                            break;
                        }
                    }
                }
            }
        }
        let level = smooth(&max_filter(&level, w, h), w, h);
        Self { block, w, h, level }
    }

    /// Block size for an image: about 1/150 of its short side (1.4 mm on an A4 scan), at least
    /// 8 pixels.
    pub fn block_size_for(img: &RgbImage) -> usize {
        (img.width().min(img.height()) as usize / 150).max(8)
    }

    /// Red paper level of the block holding pixel coordinates `(x, y)` (no interpolation: for
    /// thresholds).
    #[inline]
    pub fn red_near(&self, x: f64, y: f64) -> f32 {
        let bx = ((x.max(0.0) as usize) / self.block).min(self.w - 1);
        let by = ((y.max(0.0) as usize) / self.block).min(self.h - 1);
        self.level[by * self.w + bx][0]
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
