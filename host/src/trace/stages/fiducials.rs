//! Finding the sheet's fiducials in a scan: dark blobs on the coarse map, filtered by size and
//! shape, refined to sub-pixel centroids on the full image, then identified (four corners of a
//! square + the orientation dot near the top-left corner).

mod identify;
mod params;

pub use params::FiducialParams;

use crate::trace::paper::PaperMap;
use crate::trace::plane::dist;
use crate::trace::raster::{components, CoarseMap};
use crate::trace::TraceError;
use image::RgbImage;

/// A dark disc found in the scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Sub-pixel centroid, pixel coordinates (pixel `(c, r)` covers `[c, c+1) x [r, r+1)`).
    pub centre_px: [f64; 2],
    /// Diameter of the disc of equal area, pixels.
    pub diameter_px: f64,
}

/// The identified fiducials of one scan.
#[derive(Debug, Clone, PartialEq)]
pub struct Fiducials {
    /// Corner discs in the order top-left, top-right, bottom-right, bottom-left (sheet sense).
    pub corners: [Disc; 4],
    /// The orientation dot.
    pub dot: Disc,
    /// Sheet-v2 ring dots found, with their nominal sheet positions (mm).
    pub ring: Vec<(Disc, [f64; 2])>,
}

impl Fiducials {
    /// Mean side of the fiducial square, pixels.
    pub fn side_px(&self) -> f64 {
        (0..4)
            .map(|i| {
                dist(
                    self.corners[i].centre_px,
                    self.corners[(i + 1) % 4].centre_px,
                )
            })
            .sum::<f64>()
            / 4.0
    }
}

/// Finds and identifies the fiducials. Errors: [`TraceError::NoFiducials`],
/// [`TraceError::NoOrientationDot`], [`TraceError::AmbiguousOrientation`],
/// [`TraceError::Mirrored`].
pub(crate) fn find(
    img: &RgbImage,
    map: &CoarseMap,
    paper: &PaperMap,
    spacing_mm: f64,
    params: &FiducialParams,
) -> Result<Fiducials, TraceError> {
    let discs = candidate_discs(img, map, paper, params.black_fraction);
    identify::identify(&discs, spacing_mm, params)
}

/// The print's black relative to the paper around it, as the image holds it: the median over
/// the four corner discs of the median red value within a quarter of each disc's diameter of
/// its centre, over the median in a ring 0.8-1.1 diameters from it (the paper). The marks are
/// searched for as [`find`] does, and where that finds none again more leniently (a black
/// lifted by a tone curve: under half the paper level around, [`PaperMap::ceiling`]). `None` when no marks are found.
pub(crate) fn black_of_paper(
    img: &RgbImage,
    map: &CoarseMap,
    paper: &PaperMap,
    spacing_mm: f64,
    params: &FiducialParams,
) -> Option<f64> {
    let corners = match find(img, map, paper, spacing_mm, params) {
        Ok(f) => f.corners,
        Err(_) => {
            // Against the paper around the marks: inside a disc several blocks wide the paper
            // map holds the disc, which a black lifted by a tone curve is not far below.
            let ceiling = paper.ceiling(3);
            let discs = candidate_discs(img, map, &ceiling, params.encoded_black_fraction);
            identify::corner_discs(&discs, spacing_mm, params)?
        }
    };
    let raw = img.as_raw();
    let (w, h) = (img.width() as i64, img.height() as i64);
    // The median red value at distances r0..r1 (pixels) from `c`.
    let median_within = |c: [f64; 2], r0: f64, r1: f64| -> Option<f64> {
        let mut v: Vec<u8> = Vec::new();
        let (x0, x1) = ((c[0] - r1).floor() as i64, (c[0] + r1).ceil() as i64);
        let (y0, y1) = ((c[1] - r1).floor() as i64, (c[1] + r1).ceil() as i64);
        for y in y0.max(0)..y1.min(h) {
            for x in x0.max(0)..x1.min(w) {
                let d = (x as f64 + 0.5 - c[0]).hypot(y as f64 + 0.5 - c[1]);
                if d >= r0 && d <= r1 {
                    v.push(raw[3 * (y * w + x) as usize]);
                }
            }
        }
        if v.is_empty() {
            return None;
        }
        v.sort_unstable();
        Some(f64::from(v[v.len() / 2]))
    };
    let mut ratios: Vec<f64> = corners
        .iter()
        .filter_map(|d| {
            // The disc's core, and the paper in a ring clear of its blurred edge (the paper map
            // inside a disc several blocks wide holds the disc, not the paper).
            let core = median_within(d.centre_px, 0.0, 0.25 * d.diameter_px)?;
            let level = median_within(d.centre_px, 0.8 * d.diameter_px, 1.1 * d.diameter_px)?;
            (level > 1.0).then(|| core / level)
        })
        .collect();
    if ratios.is_empty() {
        return None;
    }
    ratios.sort_by(f64::total_cmp);
    Some(0.5 * (ratios[(ratios.len() - 1) / 2] + ratios[ratios.len() / 2]))
}

/// Every disc-like dark blob (its blocks under `black_fraction` of the paper), refined to sub-pixel centroids, largest first.
pub(crate) fn candidate_discs(
    img: &RgbImage,
    map: &CoarseMap,
    paper: &PaperMap,
    black_fraction: f32,
) -> Vec<Disc> {
    let mask = map.classify(paper, |v, level| (v as f32) < level * black_fraction);
    let (_, comps) = components(&mask, map.w, map.h);
    let mut discs: Vec<Disc> = comps
        .iter()
        .filter(|c| {
            let bw = (c.bbox[2] - c.bbox[0] + 1) as f64;
            let bh = (c.bbox[3] - c.bbox[1] + 1) as f64;
            let fill = c.area as f64 / (bw * bh);
            c.area >= 12 && (0.5..=2.0).contains(&(bw / bh)) && (0.55..=0.95).contains(&fill)
        })
        .filter_map(|c| {
            let k = map.k as f64;
            let radius_px =
                0.5 * k * (c.bbox[2] - c.bbox[0] + 1).max(c.bbox[3] - c.bbox[1] + 1) as f64;
            let guess = [c.centroid[0] * k, c.centroid[1] * k];
            let first = refine(img, guess, radius_px * 1.4, paper)?;
            refine(img, first.centre_px, radius_px * 1.3, paper)
        })
        .collect();
    discs.sort_by(|a, b| b.diameter_px.total_cmp(&a.diameter_px));
    discs
}

/// Darkness-weighted centroid of a dark disc in a square window of half side `half_px`.
fn refine(img: &RgbImage, guess: [f64; 2], half_px: f64, paper: &PaperMap) -> Option<Disc> {
    let paper = paper.at(guess[0], guess[1]);
    let (w, h) = (img.width() as i64, img.height() as i64);
    let x0 = ((guess[0] - half_px).floor() as i64).clamp(0, w);
    let x1 = ((guess[0] + half_px).ceil() as i64).clamp(0, w);
    let y0 = ((guess[1] - half_px).floor() as i64).clamp(0, h);
    let y1 = ((guess[1] + half_px).ceil() as i64).clamp(0, h);
    let raw = img.as_raw();
    let mut ink = 255u8;
    for y in y0..y1 {
        for x in x0..x1 {
            ink = ink.min(raw[3 * (y * w + x) as usize]);
        }
    }
    let span = paper[0] - ink as f32;
    if span <= 1.0 {
        return None;
    }
    let (mut sw, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
    for y in y0..y1 {
        for x in x0..x1 {
            let r = raw[3 * (y * w + x) as usize] as f32;
            // Coverage estimate, then only its top quarter: graphite (at most ~75 % of the
            // print's darkness) touching a printed dot carries no weight, while any monotone
            // weight of a symmetric dot keeps its centre.
            let c = (((paper[0] - r) / span - 0.05) / 0.9).clamp(0.0, 1.0) as f64;
            let c = ((c - 0.75) / 0.25).clamp(0.0, 1.0);
            sw += c;
            sx += c * (x as f64 + 0.5);
            sy += c * (y as f64 + 0.5);
        }
    }
    (sw > 0.0).then(|| Disc {
        centre_px: [sx / sw, sy / sw],
        // Equal-area diameter of the thresholded dot (about one pixel short of the print).
        diameter_px: 2.0 * (sw / std::f64::consts::PI).sqrt() + 1.0,
    })
}
