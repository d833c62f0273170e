//! The light falling on the sheet, at the scale of shadows: a hard shadow across the sheet (a
//! phone or a hand between the light and the paper) is a step of illumination a few pixels wide,
//! which the block-wise paper level ([`super::paper`], 1.4 mm blocks max-filtered and smoothed)
//! carries a block or two into the shadow: there the paper looks darker than its level, and the
//! shadow's inside edge reads as a stroke, the red print inside it as a mark.
//!
//! This map is the image's greyscale closing (a max filter, then a min filter, over a square of
//! [`CLOSE_SHARE`] of the image's short side, 8 mm on an A4 scan) on cells of the coarse map's
//! blocks (0.17 mm on an A4 scan), per channel. A closing removes every dark thing narrower than
//! its square (graphite, print, fiducials, dust) and keeps a step where it is, to the cell. The
//! paper level used for darkness is the lower of the block-wise level and this one (with
//! [`TOLERANCE`] for the paper's noise): where no step is near, the block-wise level as before.

use super::camera::CameraModel;
use super::link::Gap;

/// A missing gap lies along a step of the light where the light within
/// [`STEP_RADIUS_MM`] of a point on it (its ends and every millimetre between) varies by more
/// than this share (a phone's shadow: 0.3-0.6).
const STEP_CONTRAST: f32 = 0.8;
const STEP_RADIUS_MM: f64 = 1.5;

/// The missing gaps (indices into `gaps`) along a step of the light in `il`, under the camera
/// `cam` (sheet mm to pixels) at `px_per_mm`.
pub(crate) fn gaps_at_steps(
    il: &Illumination,
    cam: &CameraModel,
    gaps: &[Gap],
    px_per_mm: f64,
) -> Vec<usize> {
    let radius_px = STEP_RADIUS_MM * px_per_mm;
    gaps.iter()
        .enumerate()
        .filter(|(_, g)| !g.bridged)
        .filter(|(_, g)| {
            let d = (g.to_mm[0] - g.from_mm[0]).hypot(g.to_mm[1] - g.from_mm[1]);
            let n = (d.ceil() as usize).clamp(1, 1000);
            (0..=n).any(|i| {
                let f = i as f64 / n as f64;
                let s = [
                    g.from_mm[0] + f * (g.to_mm[0] - g.from_mm[0]),
                    g.from_mm[1] + f * (g.to_mm[1] - g.from_mm[1]),
                ];
                il.contrast_near(cam.to_px(s), radius_px) < STEP_CONTRAST
            })
        })
        .map(|(i, _)| i)
        .collect()
}

/// The closing's square, as a share of the image's short side.
const CLOSE_SHARE: f64 = 8.0 / 210.0;
/// The block-wise paper level is believed unless it is this much above the closing's.
pub(crate) const TOLERANCE: f32 = 0.04;

/// The closing of the image on coarse cells.
#[derive(Debug, Clone)]
pub(crate) struct Illumination {
    /// Cell side, pixels.
    pub k: usize,
    pub w: usize,
    pub h: usize,
    /// Level per cell and channel, 0..255.
    pub level: Vec<[f32; 3]>,
    /// The least level over each cell and its eight neighbours (for a cell's darkest pixel:
    /// a cell on a shadow's edge holds both levels).
    pub low: Vec<[f32; 3]>,
}

impl Illumination {
    /// The mean RGB of each `k x k` cell of a band of `n_rows` whole image rows (`rows`, a
    /// multiple of `k` rows except at the image's end).
    pub(crate) fn band(rows: &[u8], iw: usize, n_rows: usize, k: usize) -> Vec<[f32; 3]> {
        let k = k.max(1);
        let w = iw.div_ceil(k);
        let bh = n_rows.div_ceil(k);
        let mut sum = vec![[0u32; 4]; w * bh];
        for y in 0..n_rows {
            let row = &rows[3 * iw * y..3 * iw * (y + 1)];
            let out = &mut sum[(y / k) * w..(y / k + 1) * w];
            for (x, px) in row.chunks_exact(3).enumerate() {
                let s = &mut out[x / k];
                s[0] += u32::from(px[0]);
                s[1] += u32::from(px[1]);
                s[2] += u32::from(px[2]);
                s[3] += 1;
            }
        }
        sum.iter()
            .map(|s| {
                let n = s[3].max(1) as f32;
                [s[0] as f32 / n, s[1] as f32 / n, s[2] as f32 / n]
            })
            .collect()
    }

    /// The closing of the cell means `mean` (`w x h` cells of `k` pixels) of an image `iw x
    /// ih` pixels.
    pub(crate) fn from_cells(
        k: usize,
        w: usize,
        h: usize,
        iw: usize,
        ih: usize,
        mean: &[[f32; 3]],
    ) -> Self {
        let side_px = CLOSE_SHARE * iw.min(ih) as f64;
        let r = ((0.5 * side_px / k.max(1) as f64).round() as usize).max(1);
        let mut level = mean.to_vec();
        level.resize(w * h, [255.0; 3]);
        let level = filter2(&filter2(&level, w, h, r, f32::max), w, h, r, f32::min);
        let low = filter2(&level, w, h, 1, f32::min);
        Self {
            k: k.max(1),
            w,
            h,
            level,
            low,
        }
    }

    /// The closing's level at pixel coordinates `(x, y)`, interpolated between cell centres.
    #[inline]
    pub fn at(&self, x: f64, y: f64) -> [f32; 3] {
        let b = self.k as f64;
        let fx = (x / b - 0.5).clamp(0.0, (self.w - 1) as f64);
        let fy = (y / b - 0.5).clamp(0.0, (self.h - 1) as f64);
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.w - 1), (y0 + 1).min(self.h - 1));
        let (ax, ay) = ((fx - x0 as f64) as f32, (fy - y0 as f64) as f32);
        let l = |xx: usize, yy: usize| self.level[yy * self.w + xx];
        let (a, b2, c, d) = (l(x0, y0), l(x1, y0), l(x0, y1), l(x1, y1));
        let mut out = [0.0f32; 3];
        for i in 0..3 {
            out[i] = (1.0 - ay) * ((1.0 - ax) * a[i] + ax * b2[i])
                + ay * ((1.0 - ax) * c[i] + ax * d[i]);
        }
        out
    }
}

impl Illumination {
    /// The least over the greatest light (green) within `radius_px` of pixel `p`: about 1 on
    /// evenly lit paper, the shadow's depth across a hard shadow's edge.
    pub fn contrast_near(&self, p: [f64; 2], radius_px: f64) -> f32 {
        let k = self.k as f64;
        let r = (radius_px / k).ceil() as i64;
        let (cx, cy) = ((p[0] / k).floor() as i64, (p[1] / k).floor() as i64);
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for y in (cy - r).max(0)..=(cy + r).min(self.h as i64 - 1) {
            for x in (cx - r).max(0)..=(cx + r).min(self.w as i64 - 1) {
                let v = self.level[y as usize * self.w + x as usize][1];
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        if hi > 0.0 && lo.is_finite() {
            lo / hi
        } else {
            1.0
        }
    }
}

/// `level` (`w x h`) filtered with `op` (max or min) over the square of radius `r` cells.
fn filter2(
    level: &[[f32; 3]],
    w: usize,
    h: usize,
    r: usize,
    op: fn(f32, f32) -> f32,
) -> Vec<[f32; 3]> {
    let mut out = level.to_vec();
    let mut line = Vec::new();
    for y in 0..h {
        line.clear();
        line.extend_from_slice(&out[y * w..(y + 1) * w]);
        sliding(&line, r, op, &mut out[y * w..(y + 1) * w]);
    }
    let mut col = Vec::with_capacity(h);
    let mut res = vec![[0.0f32; 3]; h];
    for x in 0..w {
        col.clear();
        col.extend((0..h).map(|y| out[y * w + x]));
        sliding(&col, r, op, &mut res);
        for (y, v) in res.iter().enumerate() {
            out[y * w + x] = *v;
        }
    }
    out
}

/// `out[i] = op` over `vals[i - r ..= i + r]` (clipped at the ends), per channel: blocks of
/// `2r + 1` with running prefix and suffix (van Herk / Gil-Werman), O(n) whatever `r`.
fn sliding(vals: &[[f32; 3]], r: usize, op: fn(f32, f32) -> f32, out: &mut [[f32; 3]]) {
    let n = vals.len();
    if n == 0 {
        return;
    }
    let win = 2 * r + 1;
    let mut pre = vals.to_vec();
    let mut suf = vals.to_vec();
    for i in 1..n {
        if i % win != 0 {
            for c in 0..3 {
                pre[i][c] = op(pre[i - 1][c], vals[i][c]);
            }
        }
    }
    for i in (0..n.saturating_sub(1)).rev() {
        if (i + 1) % win != 0 {
            for c in 0..3 {
                suf[i][c] = op(suf[i + 1][c], vals[i][c]);
            }
        }
    }
    for (i, o) in out.iter_mut().enumerate().take(n) {
        let lo = i.saturating_sub(r);
        let hi = (i + r).min(n - 1);
        // [lo, hi] spans at most one block boundary: the suffix of lo's block and the prefix
        // of hi's block cover it.
        for c in 0..3 {
            o[c] = if lo / win == hi / win {
                // Within one block: fold directly (only near the ends, where clipped).
                vals[lo..=hi].iter().fold(vals[lo][c], |m, v| op(m, v[c]))
            } else {
                op(suf[lo][c], pre[hi][c])
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(vals: &[[f32; 3]], r: usize, op: fn(f32, f32) -> f32) -> Vec<[f32; 3]> {
        (0..vals.len())
            .map(|i| {
                let (lo, hi) = (i.saturating_sub(r), (i + r).min(vals.len() - 1));
                let mut m = vals[lo];
                for v in &vals[lo..=hi] {
                    for c in 0..3 {
                        m[c] = op(m[c], v[c]);
                    }
                }
                m
            })
            .collect()
    }

    #[test]
    fn sliding_filters_equal_brute_force() {
        let vals: Vec<[f32; 3]> = (0..97)
            .map(|i| {
                let v = ((i * 37 + 11) % 53) as f32;
                [v, 100.0 - v, (i % 5) as f32]
            })
            .collect();
        for r in [1, 2, 5, 12, 60] {
            for op in [f32::max as fn(f32, f32) -> f32, f32::min] {
                let mut out = vec![[0.0; 3]; vals.len()];
                sliding(&vals, r, op, &mut out);
                assert_eq!(out, brute(&vals, r, op), "r {r}");
            }
        }
    }

    #[test]
    fn a_closing_keeps_a_step_and_fills_a_line() {
        // 200 x 100 cells: paper at 200, a shadow at 110 right of column 120, a dark line
        // three cells wide at column 50 and a disc-like blob.
        let (w, h) = (200, 100);
        let mut mean = vec![[200.0f32; 3]; w * h];
        for y in 0..h {
            for x in 0..w {
                let v = &mut mean[y * w + x];
                if x >= 120 {
                    *v = [110.0; 3];
                }
                if (50..53).contains(&x) || ((x as i64 - 90).pow(2) + (y as i64 - 50).pow(2) < 9) {
                    *v = v.map(|c| c * 0.4);
                }
            }
        }
        // Cells of 4 px, an image of 800 x 2000 px: a square of 8/210 of 800 px (30 px): 4
        // cells each side.
        let il = Illumination::from_cells(4, w, h, 800, 2000, &mean);
        for y in [10, 50, 90] {
            assert_eq!(il.level[y * w + 51], [200.0; 3]);
            assert_eq!(il.level[y * w + 119], [200.0; 3]);
            assert_eq!(il.level[y * w + 120], [110.0; 3]);
            assert_eq!(il.low[y * w + 119], [110.0; 3]);
        }
        assert_eq!(il.level[50 * w + 90], [200.0; 3]);
    }
}
