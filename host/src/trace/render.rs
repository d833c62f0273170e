//! A simulated scan of a traced sheet, for simulation and tests: an A4 page at a given dpi,
//! placed on the scanner glass with a small rotation and shift (optionally mirrored), showing
//! noisy paper, the black fiducials and scale bar, the red reference path and a graphite pencil
//! stroke with grain.
//!
//! Layers multiply (paper x ink x graphite x black), as light through stacked absorbers. Edges
//! are antialiased analytically: a pixel's coverage by a shape is `clamp(0.5 - d, 0, 1)` with
//! `d` the signed distance (in pixels) from the pixel centre to the shape's outline, which is
//! exact for edges along the pixel grid and symmetric about any edge, so a centroid across a
//! stroke is unbiased. Noise is a hash of (seed, pixel), so a render is deterministic and does
//! not depend on the order of the work.

use super::render_extras::{cumulative_arc, desk};
use crate::sheet::{
    fiducial_centres_mm, orientation_dot_mm, ring_dots_mm, scale_bar_rects_mm, ReferencePath,
    FIDUCIAL_DIAMETER_MM, FIDUCIAL_SPACING_MM, ORIENTATION_DOT_DIAMETER_MM, PAGE_HEIGHT_MM,
    PAGE_WIDTH_MM, RING_DOT_DIAMETER_MM,
};
use image::{Rgb, RgbImage};

/// What to render. Start from [`RenderSpec::default`] and set the pencil path.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSpec {
    /// Scan resolution, dots per inch (the image is the A4 page at this resolution:
    /// 2480 x 3508 px at 300 dpi, 4961 x 7016 px at 600 dpi).
    pub dpi: f64,
    /// The pencil's centreline in (physical) sheet mm: origin at the fiducial square's centre,
    /// x right, y up. Empty: no pencil.
    pub pencil_mm: Vec<[f64; 2]>,
    /// Whether the pencil path closes on itself.
    pub pencil_closed: bool,
    /// Width of the graphite stroke, mm.
    pub pencil_width_mm: f64,
    /// Mean darkness of the graphite (fraction of light absorbed), 0..1.
    pub pencil_darkness: f64,
    /// Relative standard deviation of the graphite's per-pixel grain.
    pub pencil_grain: f64,
    /// Printed red reference path, if any.
    pub reference: Option<ReferencePath>,
    /// Whether the fiducials (and the scale bar) are printed.
    pub fiducials: bool,
    /// Printer scale: the printed content is this factor times its nominal size (the pencil is
    /// not scaled). The fiducial spacing is then `180 * print_scale` mm.
    pub print_scale: f64,
    /// Rotation of the page on the scanner glass, degrees (in image coordinates, y down).
    pub rotation_deg: f64,
    /// Shift of the page on the scanner glass, mm (image x right, y down).
    pub shift_mm: [f64; 2],
    /// Scan the page mirrored (left-right), as a wrongly flipped scan would be.
    pub mirrored: bool,
    /// Paper level, 0..1 of full scale.
    pub paper_level: f64,
    /// Standard deviation of the paper noise, fraction of full scale.
    pub paper_noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// Print the sheet-v2 ring of 43 dots.
    pub ring: bool,
    /// Pencil skips: arc-length intervals `[s0, s1]` (mm from the path's start) left unwritten.
    pub skips_mm: Vec<[f64; 2]>,
    /// Faint graphite: `[s0, s1, darkness]`, the pencil's mean darkness over that arc-length
    /// interval.
    pub faint_mm: Vec<[f64; 3]>,
    /// Dust specks `[x, y, radius]` (sheet mm), dark grey-black.
    pub dust_mm: Vec<[f64; 3]>,
    /// Paper fibres `[x0, y0, x1, y1]` (sheet mm): thin grey segments 0.08 mm wide.
    pub fibres_mm: Vec<[f64; 4]>,
    /// Level (0..1) of whatever the scanner sees outside the page (desk, lid); `None`: paper.
    pub desk_level: Option<f64>,
}

impl Default for RenderSpec {
    fn default() -> Self {
        Self {
            dpi: 600.0,
            pencil_mm: Vec::new(),
            pencil_closed: false,
            pencil_width_mm: 0.5,
            pencil_darkness: 0.52,
            pencil_grain: 0.12,
            reference: Some(ReferencePath::Circle),
            fiducials: true,
            print_scale: 1.0,
            rotation_deg: 0.0,
            shift_mm: [0.0, 0.0],
            mirrored: false,
            paper_level: 0.94,
            paper_noise: 0.012,
            seed: 1,
            ring: false,
            skips_mm: Vec::new(),
            faint_mm: Vec::new(),
            dust_mm: Vec::new(),
            fibres_mm: Vec::new(),
            desk_level: None,
        }
    }
}

/// Width of the printed reference line, mm.
const REFERENCE_WIDTH_MM: f64 = 0.3;
/// Transmittance of the red ink per channel.
const RED_INK: [f64; 3] = [0.9, 0.12, 0.12];
/// Darkness of black print.
const BLACK_DARKNESS: f64 = 0.93;

/// Renders the scan described by `spec`.
pub fn render_scan(spec: &RenderSpec) -> RgbImage {
    let ppmm = spec.dpi / 25.4;
    let (w, h) = (
        (PAGE_WIDTH_MM * ppmm).round() as u32,
        (PAGE_HEIGHT_MM * ppmm).round() as u32,
    );
    let place = Placement::new(spec);
    let mut img = RgbImage::new(w.max(1), h.max(1));
    paper(&mut img, spec);

    let scale = spec.print_scale;
    if let Some(path) = spec.reference {
        let pts: Vec<[f64; 2]> = path
            .polyline_mm(0.05)
            .iter()
            .map(|p| [p[0] * scale, p[1] * scale])
            .collect();
        let cov = stroke_coverage(
            &img,
            &place,
            &pts,
            path.is_closed(),
            0.5 * REFERENCE_WIDTH_MM * scale,
        );
        let raw: &mut [u8] = img.as_mut();
        for (idx, c, _) in cov {
            let i = 3 * idx as usize;
            for ch in 0..3 {
                raw[i + ch] = mul(raw[i + ch], 1.0 - c * (1.0 - RED_INK[ch]));
            }
        }
    }
    if spec.pencil_mm.len() >= 2 {
        let cov = stroke_coverage(
            &img,
            &place,
            &spec.pencil_mm,
            spec.pencil_closed,
            0.5 * spec.pencil_width_mm,
        );
        let arc = cumulative_arc(&spec.pencil_mm);
        let raw: &mut [u8] = img.as_mut();
        for (idx, c, seg) in cov {
            let s_mm = arc[seg];
            if spec.skips_mm.iter().any(|k| s_mm >= k[0] && s_mm <= k[1]) {
                continue;
            }
            let mean = spec
                .faint_mm
                .iter()
                .find(|f| s_mm >= f[0] && s_mm <= f[1])
                .map_or(spec.pencil_darkness, |f| f[2]);
            let n = triangular(hash(spec.seed ^ 0x5bd1_e995, idx as u64));
            let dark = (mean * (1.0 + spec.pencil_grain * n)).clamp(0.0, 0.97);
            let i = 3 * idx as usize;
            for ch in 0..3 {
                raw[i + ch] = mul(raw[i + ch], 1.0 - c * dark);
            }
        }
    }
    for f in &spec.fibres_mm {
        let cov = stroke_coverage(&img, &place, &[[f[0], f[1]], [f[2], f[3]]], false, 0.04);
        let raw: &mut [u8] = img.as_mut();
        for (idx, c, _) in cov {
            let i = 3 * idx as usize;
            for ch in 0..3 {
                raw[i + ch] = mul(raw[i + ch], 1.0 - c * 0.45);
            }
        }
    }
    for d in &spec.dust_mm {
        disc(&mut img, &place, [d[0], d[1]], d[2]);
    }
    if spec.ring && spec.fiducials {
        for c in ring_dots_mm(FIDUCIAL_SPACING_MM * spec.print_scale) {
            disc(
                &mut img,
                &place,
                c,
                0.5 * RING_DOT_DIAMETER_MM * spec.print_scale,
            );
        }
    }
    if spec.fiducials {
        let s = FIDUCIAL_SPACING_MM * scale;
        for c in fiducial_centres_mm(s) {
            disc(&mut img, &place, c, 0.5 * FIDUCIAL_DIAMETER_MM * scale);
        }
        disc(
            &mut img,
            &place,
            orientation_dot_mm(s),
            0.5 * ORIENTATION_DOT_DIAMETER_MM * scale,
        );
        for r in scale_bar_rects_mm() {
            let min = [r.min[0] * scale, r.min[1] * scale];
            let max = [r.max[0] * scale, r.max[1] * scale];
            rect(&mut img, &place, min, max);
        }
    }
    if let Some(level) = spec.desk_level {
        desk(&mut img, &place, level);
    }
    img
}

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
    fn new(spec: &RenderSpec) -> Self {
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

fn paper(img: &mut RgbImage, spec: &RenderSpec) {
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
fn stroke_coverage(
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

fn disc(img: &mut RgbImage, place: &Placement, centre: [f64; 2], radius_mm: f64) {
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

fn rect(img: &mut RgbImage, place: &Placement, min: [f64; 2], max: [f64; 2]) {
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
fn hash(seed: u64, i: u64) -> u64 {
    let mut z = seed
        .wrapping_add(i.wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Zero-mean, unit-variance triangular noise: the sum of two uniforms, 32 bits of a hash each.
fn triangular(h: u64) -> f64 {
    let u1 = (h & 0xFFFF_FFFF) as f64 / 4_294_967_296.0;
    let u2 = (h >> 32) as f64 / 4_294_967_296.0;
    (u1 + u2 - 1.0) * 6f64.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a4_size_and_fiducial_position() {
        let spec = RenderSpec {
            dpi: 100.0,
            reference: None,
            ..RenderSpec::default()
        };
        let img = render_scan(&spec);
        assert_eq!((img.width(), img.height()), (827, 1169));
        // top-left fiducial centre: page (15, 58.5) mm -> pixel (59.06, 230.3)
        let p = img.get_pixel(59, 230);
        assert!(p[0] < 40, "{p:?}");
        let paper = img.get_pixel(400, 100);
        assert!(paper[0] > 220, "{paper:?}");
        assert_eq!(render_scan(&spec), img, "deterministic");
    }
}
