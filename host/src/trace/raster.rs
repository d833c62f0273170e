//! Whole-image passes over a scan: the paper level, the coarse block map of darkest red values
//! and connected components on a coarse mask. These are the only passes that touch every pixel;
//! everything after them works in small windows.

use super::paper::{BlockMap, PaperMap};
#[cfg(test)]
use image::RgbImage;

/// Per-channel paper level (median of a regular sample of pixels), 0..255.
#[cfg(test)]
pub(crate) fn paper_level(img: &RgbImage) -> [f32; 3] {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let step = (w.min(h) / 512).clamp(1, 8);
    let mut hist = [[0u32; 256]; 3];
    let raw = img.as_raw();
    let mut n = 0u64;
    for y in (0..h).step_by(step) {
        let row = &raw[3 * w * y..3 * w * (y + 1)];
        for px in row.chunks_exact(3).step_by(step) {
            for c in 0..3 {
                hist[c][px[c] as usize] += 1;
            }
            n += 1;
        }
    }
    let mut out = [255.0f32; 3];
    for c in 0..3 {
        let mut acc = 0u64;
        for (v, &count) in hist[c].iter().enumerate() {
            acc += count as u64;
            if 2 * acc >= n {
                out[c] = (v as f32).max(1.0);
                break;
            }
        }
    }
    out
}

/// The scan reduced to `k x k` blocks, each holding the darkest red value inside it. Red ink is
/// nearly invisible in the red channel, so this map shows graphite and black print only.
#[derive(Debug, Clone)]
pub(crate) struct CoarseMap {
    /// Block side, pixels.
    pub k: usize,
    pub w: usize,
    pub h: usize,
    pub min_red: Vec<u8>,
}

/// A map about 1240 blocks wide (0.17 mm blocks on an A4 scan).
impl BlockMap for CoarseMap {
    const BLOCKS_ACROSS: usize = 1240;
    const MIN_BLOCK_PX: usize = 1;
}

impl CoarseMap {
    /// The map in one pass (the reference for the banded build of [`super::stages::prepare`]).
    #[cfg(test)]
    pub fn build(img: &RgbImage, k: usize) -> Self {
        let (iw, ih) = (img.width() as usize, img.height() as usize);
        let (w, h) = (iw.div_ceil(k), ih.div_ceil(k));
        let mut min_red = vec![255u8; w * h];
        let raw = img.as_raw();
        for y in 0..ih {
            let row = &raw[3 * iw * y..3 * iw * (y + 1)];
            let out = &mut min_red[(y / k) * w..(y / k + 1) * w];
            for (block, o) in row.chunks(3 * k).zip(out.iter_mut()) {
                let m = block.iter().step_by(3).copied().min().unwrap_or(255);
                if m < *o {
                    *o = m;
                }
            }
        }
        Self { k, w, h, min_red }
    }

    /// The map's rows for a band of `n_rows` whole RGB image rows (`rows`, width `iw`) that
    /// starts at a multiple of `k`.
    pub(crate) fn band(rows: &[u8], iw: usize, n_rows: usize, k: usize) -> Vec<u8> {
        let k = k.max(1);
        let w = iw.div_ceil(k);
        let mut min_red = vec![255u8; w * n_rows.div_ceil(k)];
        for y in 0..n_rows {
            let row = &rows[3 * iw * y..3 * iw * (y + 1)];
            let out = &mut min_red[(y / k) * w..(y / k + 1) * w];
            if k == 4 {
                // The common case (A4 at 600 dpi): fixed-size blocks the compiler unrolls.
                let mut blocks = row.chunks_exact(12);
                for (b, o) in (&mut blocks).zip(out.iter_mut()) {
                    *o = (*o).min(b[0].min(b[3]).min(b[6].min(b[9])));
                }
                let rest = blocks.remainder();
                if let Some(o) = out.last_mut().filter(|_| !rest.is_empty()) {
                    *o = rest.iter().step_by(3).fold(*o, |m, &v| m.min(v));
                }
            } else {
                for (b, o) in row.chunks(3 * k).zip(out.iter_mut()) {
                    *o = b.iter().step_by(3).fold(*o, |m, &v| m.min(v));
                }
            }
        }
        min_red
    }

    /// For every block, `keep(darkest red value, red paper level at the block's centre)`
    /// ([`PaperMap::red_near`], looked up once per row and column).
    pub fn classify(&self, paper: &PaperMap, keep: impl Fn(u8, f32) -> bool) -> Vec<bool> {
        let cols: Vec<usize> = (0..self.w)
            .map(|bx| paper.col_of(self.block_centre_px(bx, 0)[0]))
            .collect();
        let mut out = vec![false; self.min_red.len()];
        for (by, (row, o)) in self
            .min_red
            .chunks_exact(self.w.max(1))
            .zip(out.chunks_exact_mut(self.w.max(1)))
            .enumerate()
        {
            let levels = &paper.level[paper.row_of(self.block_centre_px(0, by)[1]) * paper.w..];
            for ((v, o), &c) in row.iter().zip(o.iter_mut()).zip(&cols) {
                *o = keep(*v, levels[c][0]);
            }
        }
        out
    }

    /// Centre of block `(bx, by)` in pixel coordinates (pixel `(c, r)` covers
    /// `[c, c+1) x [r, r+1)`).
    pub fn block_centre_px(&self, bx: usize, by: usize) -> [f64; 2] {
        let k = self.k as f64;
        [(bx as f64 + 0.5) * k, (by as f64 + 0.5) * k]
    }
}

/// Statistics of one connected component of a coarse mask.
#[derive(Debug, Clone)]
pub(crate) struct Component {
    /// Number of blocks.
    pub area: usize,
    /// Bounding box in blocks, inclusive: `[x0, y0, x1, y1]`.
    pub bbox: [usize; 4],
    /// Mean block coordinate (block units, block centres at `i + 0.5`).
    pub centroid: [f64; 2],
}

/// 8-connected components of `mask` (`w x h`); returns the label map (0 = background,
/// component `i` has label `i + 1`) and the components.
pub(crate) fn components(mask: &[bool], w: usize, h: usize) -> (Vec<u32>, Vec<Component>) {
    let mut labels = vec![0u32; mask.len()];
    let mut comps = Vec::new();
    let mut stack = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || labels[start] != 0 {
            continue;
        }
        let label = comps.len() as u32 + 1;
        labels[start] = label;
        stack.push(start);
        let (mut area, mut sx, mut sy) = (0usize, 0.0f64, 0.0f64);
        let mut bbox = [usize::MAX, usize::MAX, 0, 0];
        while let Some(i) = stack.pop() {
            let (x, y) = (i % w, i / w);
            area += 1;
            sx += x as f64 + 0.5;
            sy += y as f64 + 0.5;
            bbox = [
                bbox[0].min(x),
                bbox[1].min(y),
                bbox[2].max(x),
                bbox[3].max(y),
            ];
            for ny in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                for nx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                    let j = ny * w + nx;
                    if mask[j] && labels[j] == 0 {
                        labels[j] = label;
                        stack.push(j);
                    }
                }
            }
        }
        comps.push(Component {
            area,
            bbox,
            centroid: [sx / area as f64, sy / area as f64],
        });
    }
    (labels, comps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn components_are_8_connected_and_counted() {
        #[rustfmt::skip]
        let m = [
            1, 0, 0, 0, 1,
            0, 1, 0, 0, 1,
            0, 0, 0, 0, 0,
            1, 1, 1, 0, 0,
        ];
        let mask: Vec<bool> = m.iter().map(|&v| v == 1).collect();
        let (labels, comps) = components(&mask, 5, 4);
        assert_eq!(comps.len(), 3);
        assert_eq!(comps[0].area, 2); // diagonal pair
        assert_eq!(comps[1].area, 2);
        assert_eq!(comps[2].area, 3);
        assert_eq!(comps[2].bbox, [0, 3, 2, 3]);
        assert_eq!(comps[2].centroid, [1.5, 3.5]);
        assert_eq!(labels[6], 1);
    }

    #[test]
    fn coarse_map_takes_block_minimum_of_red() {
        let mut img = RgbImage::from_pixel(10, 6, image::Rgb([250, 250, 250]));
        img.put_pixel(9, 5, image::Rgb([40, 250, 250]));
        img.put_pixel(0, 0, image::Rgb([250, 10, 10])); // red ink: invisible here
        let map = CoarseMap::build(&img, 4);
        assert_eq!((map.w, map.h), (3, 2));
        assert_eq!(map.min_red[0], 250);
        assert_eq!(map.min_red[5], 40);
        assert_eq!(paper_level(&img), [250.0, 250.0, 250.0]);
    }

    #[test]
    fn classify_looks_up_the_paper_level_of_each_block_centre() {
        let img = RgbImage::from_fn(203, 151, |x, y| {
            let v = ((x * 31 + y * 17) % 256) as u8;
            image::Rgb([v, 200, 200])
        });
        let paper = PaperMap::build(&img, 16);
        let map = CoarseMap::build(&img, 3);
        let got = map.classify(&paper, |v, level| (v as f32) < 0.5 * level);
        for (i, &g) in got.iter().enumerate() {
            let c = map.block_centre_px(i % map.w, i / map.w);
            let want = (map.min_red[i] as f32) < 0.5 * paper.red_near(c[0], c[1]);
            assert_eq!(g, want, "block {i}");
        }
        assert!(got.iter().any(|&g| g) && got.iter().any(|&g| !g));
    }
}
