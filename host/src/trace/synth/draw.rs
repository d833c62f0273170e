//! The drawing primitives of a simulated scan: the page's placement on the scanner glass, the
//! noisy paper, antialiased strokes, discs and rectangles (coverage from the signed distance to
//! the outline), and the deterministic noise.

use super::scan::RenderSpec;
use crate::sheet::{PAGE_HEIGHT_MM, PAGE_WIDTH_MM};
use image::{Rgb, RgbImage};

/// Darkness of black print.
const BLACK_DARKNESS: f64 = 0.93;

/// The page's placement: affine maps between pixel coordinates (pixel `(c, r)` covers
/// `[c, c+1) x [r, r+1)`) and sheet mm.
pub(super) struct Placement {
    /// sheet = a * pixel + b
    to_sheet: [[f64; 3]; 2],
    /// pixel = a * sheet + b
    to_pixel: [[f64; 3]; 2],
    ppmm: f64,
}

impl Placement {
    pub(super) fn new(spec: &RenderSpec) -> Self {
        let ppmm = spec.dpi / 25.4;
        let (c, s) = (
            spec.rotation_deg.to_radians().cos(),
            spec.rotation_deg.to_radians().sin(),
        );
        let (cx, cy) = (PAGE_WIDTH_MM / 2.0, PAGE_HEIGHT_MM / 2.0);
        let m = if spec.mirrored { -1.0 } else { 1.0 };
        // sheet (x, y) -> page (cx + m x, cy - y) -> glass: centre + R (page - centre) + shift.
        // glass_x = cx + c*m*x + s*y + shift_x ; glass_y = cy + s*m*x - c*y + shift_y
        let to_pixel = [
            [ppmm * c * m, ppmm * s, ppmm * (cx + spec.shift_mm[0])],
            [ppmm * s * m, -ppmm * c, ppmm * (cy + spec.shift_mm[1])],
        ];
        let det = to_pixel[0][0] * to_pixel[1][1] - to_pixel[0][1] * to_pixel[1][0];
        let inv = [
            [to_pixel[1][1] / det, -to_pixel[0][1] / det],
            [-to_pixel[1][0] / det, to_pixel[0][0] / det],
        ];
        let (tx, ty) = (to_pixel[0][2], to_pixel[1][2]);
        let to_sheet = [
            [inv[0][0], inv[0][1], -(inv[0][0] * tx + inv[0][1] * ty)],
            [inv[1][0], inv[1][1], -(inv[1][0] * tx + inv[1][1] * ty)],
        ];
        Self {
            to_sheet,
            to_pixel,
            ppmm,
        }
    }

    /// Pixels per mm.
    pub(super) fn ppmm(&self) -> f64 {
        self.ppmm
    }

    pub(super) fn sheet(&self, px: [f64; 2]) -> [f64; 2] {
        apply(&self.to_sheet, px)
    }

    /// Pixel bounding box `[x0, y0, x1, y1)` of a sheet-mm box, clipped to the image.
    fn pixel_box(&self, min: [f64; 2], max: [f64; 2], img: &RgbImage) -> [u32; 4] {
        let corners = [
            [min[0], min[1]],
            [max[0], min[1]],
            [min[0], max[1]],
            [max[0], max[1]],
        ];
        let px: Vec<[f64; 2]> = corners.iter().map(|c| apply(&self.to_pixel, *c)).collect();
        let lo = |k: usize| {
            px.iter()
                .map(|p| p[k])
                .fold(f64::INFINITY, f64::min)
                .floor()
                - 1.0
        };
        let hi = |k: usize| {
            px.iter()
                .map(|p| p[k])
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil()
                + 1.0
        };
        let clip = |v: f64, n: u32| v.clamp(0.0, n as f64) as u32;
        [
            clip(lo(0), img.width()),
            clip(lo(1), img.height()),
            clip(hi(0), img.width()),
            clip(hi(1), img.height()),
        ]
    }
}

fn apply(m: &[[f64; 3]; 2], p: [f64; 2]) -> [f64; 2] {
    [
        m[0][0] * p[0] + m[0][1] * p[1] + m[0][2],
        m[1][0] * p[0] + m[1][1] * p[1] + m[1][2],
    ]
}

pub(super) fn paper(img: &mut RgbImage, spec: &RenderSpec) {
    let level = 255.0 * spec.paper_level;
    let sd = 255.0 * spec.paper_noise;
    for (idx, px) in img.as_mut().chunks_exact_mut(3).enumerate() {
        let hv = hash(spec.seed, idx as u64);
        let lum = triangular(hv) * sd;
        let tint = (((hv >> 20) & 0xFFFF) as f64 / 65536.0 - 0.5) * 0.5 * sd;
        px[0] = (level + lum + tint).round().clamp(0.0, 255.0) as u8;
        px[1] = (level + lum).round().clamp(0.0, 255.0) as u8;
        px[2] = (level + lum - tint).round().clamp(0.0, 255.0) as u8;
    }
}

/// Coverage `(pixel index, coverage, segment)` of a stroke of half width `half_w_mm` around a polyline,
/// one entry per pixel (the largest over the segments, i.e. from the nearest segment).
pub(super) fn stroke_coverage(
    img: &RgbImage,
    place: &Placement,
    pts: &[[f64; 2]],
    closed: bool,
    half_w_mm: f64,
) -> Vec<(u32, f64, usize)> {
    let mut cov: Vec<(u32, f32, u32)> = Vec::new();
    let margin = half_w_mm + 2.0 / place.ppmm;
    let n = pts.len();
    let segs = if closed { n } else { n.saturating_sub(1) };
    let width = img.width();
    for i in 0..segs {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        let min = [a[0].min(b[0]) - margin, a[1].min(b[1]) - margin];
        let max = [a[0].max(b[0]) + margin, a[1].max(b[1]) + margin];
        let [x0, y0, x1, y1] = place.pixel_box(min, max, img);
        for y in y0..y1 {
            for x in x0..x1 {
                let s = place.sheet([x as f64 + 0.5, y as f64 + 0.5]);
                let d = segment_distance(s, a, b);
                let c = (0.5 - (d - half_w_mm) * place.ppmm).clamp(0.0, 1.0);
                if c > 0.0 {
                    cov.push((y * width + x, c as f32, i as u32));
                }
            }
        }
    }
    cov.sort_unstable_by(|p, q| p.0.cmp(&q.0).then(q.1.total_cmp(&p.1)));
    cov.dedup_by_key(|p| p.0);
    cov.into_iter()
        .map(|(i, c, seg)| (i, c as f64, seg as usize))
        .collect()
}

pub(super) fn disc(img: &mut RgbImage, place: &Placement, centre: [f64; 2], radius_mm: f64) {
    let m = radius_mm + 2.0 / place.ppmm;
    let [x0, y0, x1, y1] = place.pixel_box(
        [centre[0] - m, centre[1] - m],
        [centre[0] + m, centre[1] + m],
        img,
    );
    for y in y0..y1 {
        for x in x0..x1 {
            let s = place.sheet([x as f64 + 0.5, y as f64 + 0.5]);
            let d = (s[0] - centre[0]).hypot(s[1] - centre[1]) - radius_mm;
            darken(img, x, y, (0.5 - d * place.ppmm).clamp(0.0, 1.0));
        }
    }
}

pub(super) fn rect(img: &mut RgbImage, place: &Placement, min: [f64; 2], max: [f64; 2]) {
    let m = 2.0 / place.ppmm;
    let [x0, y0, x1, y1] = place.pixel_box([min[0] - m, min[1] - m], [max[0] + m, max[1] + m], img);
    let (cx, cy) = (0.5 * (min[0] + max[0]), 0.5 * (min[1] + max[1]));
    let (hx, hy) = (0.5 * (max[0] - min[0]), 0.5 * (max[1] - min[1]));
    for y in y0..y1 {
        for x in x0..x1 {
            let s = place.sheet([x as f64 + 0.5, y as f64 + 0.5]);
            let d = ((s[0] - cx).abs() - hx).max((s[1] - cy).abs() - hy);
            darken(img, x, y, (0.5 - d * place.ppmm).clamp(0.0, 1.0));
        }
    }
}

fn darken(img: &mut RgbImage, x: u32, y: u32, coverage: f64) {
    if coverage <= 0.0 {
        return;
    }
    let Rgb(mut v) = *img.get_pixel(x, y);
    for c in v.iter_mut() {
        *c = mul(*c, 1.0 - coverage * BLACK_DARKNESS);
    }
    img.put_pixel(x, y, Rgb(v));
}

pub(super) fn mul(v: u8, f: f64) -> u8 {
    (v as f64 * f).round().clamp(0.0, 255.0) as u8
}

fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// splitmix64 of the seed and a counter.
pub(super) fn hash(seed: u64, i: u64) -> u64 {
    let mut z = seed
        .wrapping_add(i.wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Zero-mean, unit-variance triangular noise: the sum of two uniforms, 32 bits of a hash each.
pub(super) fn triangular(h: u64) -> f64 {
    let u1 = (h & 0xFFFF_FFFF) as f64 / 4_294_967_296.0;
    let u2 = (h >> 32) as f64 / 4_294_967_296.0;
    (u1 + u2 - 1.0) * 6f64.sqrt()
}
