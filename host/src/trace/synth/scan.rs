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

use super::desk::{cumulative_arc, desk};
use super::device::DeviceTone;
use super::draw::{disc, hash, mul, paper, rect, stroke_coverage, triangular, Placement};
use crate::sheet::{
    fiducial_centres_mm, orientation_dot_mm, ring_dots_mm, scale_bar_rects_mm, ReferencePath,
    FIDUCIAL_DIAMETER_MM, FIDUCIAL_SPACING_MM, ORIENTATION_DOT_DIAMETER_MM, PAGE_HEIGHT_MM,
    PAGE_WIDTH_MM, RING_DOT_DIAMETER_MM,
};
use image::RgbImage;

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
    /// More pencil runs on the same sheet (a second drawing), each a centreline in sheet mm and
    /// whether it closes; drawn as the first, without its skips or faint stretches.
    pub more_pencil_mm: Vec<(Vec<[f64; 2]>, bool)>,
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
    /// The page's centre in sheet mm: the print off-centre on the page (a printer's margin), so
    /// that one page edge may fall inside the trace area (with `desk_level` set).
    pub page_offset_mm: [f64; 2],
    /// The shadow the page's edge casts on the lid beyond it, `[width_mm, depth]` (with
    /// `desk_level` set); `None`: none.
    pub lid_shadow: Option<[f64; 2]>,
    /// The tone curve the device writes through (a photo applies it after its light, blur and
    /// noise, before JPEG).
    pub device_tone: DeviceTone,
}

impl Default for RenderSpec {
    fn default() -> Self {
        Self {
            dpi: 600.0,
            pencil_mm: Vec::new(),
            pencil_closed: false,
            more_pencil_mm: Vec::new(),
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
            page_offset_mm: [0.0, 0.0],
            lid_shadow: None,
            device_tone: DeviceTone::Linear,
        }
    }
}

/// Width of the printed reference line, mm.
const REFERENCE_WIDTH_MM: f64 = 0.3;
/// Transmittance of the red ink per channel.
const RED_INK: [f64; 3] = [0.9, 0.12, 0.12];

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
    let runs = std::iter::once((&spec.pencil_mm, spec.pencil_closed, true))
        .chain(spec.more_pencil_mm.iter().map(|(p, c)| (p, *c, false)));
    for (run, (pencil_mm, closed, first)) in runs.enumerate() {
        if pencil_mm.len() < 2 {
            continue;
        }
        let cov = stroke_coverage(&img, &place, pencil_mm, closed, 0.5 * spec.pencil_width_mm);
        let arc = cumulative_arc(pencil_mm);
        let raw: &mut [u8] = img.as_mut();
        for (idx, c, seg) in cov {
            let s_mm = arc[seg];
            if first && spec.skips_mm.iter().any(|k| s_mm >= k[0] && s_mm <= k[1]) {
                continue;
            }
            let mean = spec
                .faint_mm
                .iter()
                .filter(|_| first)
                .find(|f| s_mm >= f[0] && s_mm <= f[1])
                .map_or(spec.pencil_darkness, |f| f[2]);
            let n = triangular(hash(spec.seed ^ 0x5bd1_e995 ^ run as u64, idx as u64));
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
        desk(
            &mut img,
            &place,
            level,
            spec.page_offset_mm,
            spec.lid_shadow,
        );
    }
    spec.device_tone.apply(&mut img);
    img
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
