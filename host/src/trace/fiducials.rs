//! Finding the sheet's fiducials in a scan: dark blobs on the coarse map, filtered by size and
//! shape, refined to sub-pixel centroids on the full image, then identified (four corners of a
//! square + the orientation dot near the top-left corner).

use super::raster::{components, CoarseMap};
use super::TraceError;
use crate::sheet::{
    FIDUCIAL_DIAMETER_MM, FIDUCIAL_SPACING_MM, ORIENTATION_DOT_DIAMETER_MM, ORIENTATION_DOT_MM,
};
use image::RgbImage;

/// A block is "black" when its darkest red value is below this fraction of the paper level
/// (black print reflects < 10 %; graphite 30-60 %).
const BLACK_FRACTION: f32 = 0.22;
/// Relative tolerance on the square's sides and diagonals.
const SQUARE_TOL: f64 = 0.05;

/// A dark disc found in the scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Sub-pixel centroid, pixel coordinates (pixel `(c, r)` covers `[c, c+1) x [r, r+1)`).
    pub centre_px: [f64; 2],
    /// Diameter of the disc of equal area, pixels.
    pub diameter_px: f64,
}

/// The identified fiducials of one scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fiducials {
    /// Corner discs in the order top-left, top-right, bottom-right, bottom-left (sheet sense).
    pub corners: [Disc; 4],
    /// The orientation dot.
    pub dot: Disc,
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
/// [`TraceError::NoOrientationDot`], [`TraceError::Mirrored`].
pub(crate) fn find(
    img: &RgbImage,
    map: &CoarseMap,
    paper: [f32; 3],
) -> Result<Fiducials, TraceError> {
    let discs = candidate_discs(img, map, paper);
    let corners = best_square(&discs).ok_or(TraceError::NoFiducials { discs: discs.len() })?;
    identify(corners, &discs)
}

/// Every disc-like dark blob, refined to sub-pixel centroids, largest first.
pub(crate) fn candidate_discs(img: &RgbImage, map: &CoarseMap, paper: [f32; 3]) -> Vec<Disc> {
    let black = (paper[0] * BLACK_FRACTION) as u8;
    let mask: Vec<bool> = map.min_red.iter().map(|&v| v < black).collect();
    let (_, comps) = components(&mask, map.w, map.h);
    let mut discs: Vec<Disc> = comps
        .iter()
        .filter(|c| {
            let bw = (c.bbox[2] - c.bbox[0] + 1) as f64;
            let bh = (c.bbox[3] - c.bbox[1] + 1) as f64;
            let fill = c.area as f64 / (bw * bh);
            c.area >= 12 && (0.75..=1.33).contains(&(bw / bh)) && (0.6..=0.92).contains(&fill)
        })
        .filter_map(|c| {
            let k = map.k as f64;
            let radius_px =
                0.5 * k * (c.bbox[2] - c.bbox[0] + 1).max(c.bbox[3] - c.bbox[1] + 1) as f64;
            refine(
                img,
                [c.centroid[0] * k, c.centroid[1] * k],
                radius_px * 1.4,
                paper,
            )
        })
        .collect();
    discs.sort_by(|a, b| b.diameter_px.total_cmp(&a.diameter_px));
    discs
}

/// Darkness-weighted centroid of a dark disc in a square window of half side `half_px`.
fn refine(img: &RgbImage, guess: [f64; 2], half_px: f64, paper: [f32; 3]) -> Option<Disc> {
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
            // Coverage estimate with a small floor so that paper noise carries no weight.
            let c = (((paper[0] - r) / span - 0.05) / 0.9).clamp(0.0, 1.0) as f64;
            sw += c;
            sx += c * (x as f64 + 0.5);
            sy += c * (y as f64 + 0.5);
        }
    }
    (sw > 0.0).then(|| Disc {
        centre_px: [sx / sw, sy / sw],
        diameter_px: 2.0 * (sw / std::f64::consts::PI).sqrt(),
    })
}

/// The four similar discs forming the most square quadrilateral whose side is about 30 disc
/// diameters, ordered around their centroid.
fn best_square(discs: &[Disc]) -> Option<[Disc; 4]> {
    let cand = &discs[..discs.len().min(16)];
    let n = cand.len();
    let expected_ratio = FIDUCIAL_SPACING_MM / FIDUCIAL_DIAMETER_MM;
    let mut best: Option<(f64, [Disc; 4])> = None;
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                for d in c + 1..n {
                    let quad = order_around_centroid([cand[a], cand[b], cand[c], cand[d]]);
                    let Some(score) = square_score(&quad, expected_ratio) else {
                        continue;
                    };
                    if best.as_ref().is_none_or(|(s, _)| score < *s) {
                        best = Some((score, quad));
                    }
                }
            }
        }
    }
    best.map(|(_, q)| q)
}

fn order_around_centroid(mut q: [Disc; 4]) -> [Disc; 4] {
    let cx = q.iter().map(|d| d.centre_px[0]).sum::<f64>() / 4.0;
    let cy = q.iter().map(|d| d.centre_px[1]).sum::<f64>() / 4.0;
    q.sort_by(|a, b| {
        let aa = (a.centre_px[1] - cy).atan2(a.centre_px[0] - cx);
        let ab = (b.centre_px[1] - cy).atan2(b.centre_px[0] - cx);
        aa.total_cmp(&ab)
    });
    q
}

/// Sum of relative deviations from a square with the expected side/diameter ratio; `None`
/// beyond tolerance.
fn square_score(q: &[Disc; 4], expected_ratio: f64) -> Option<f64> {
    let mean_d = q.iter().map(|d| d.diameter_px).sum::<f64>() / 4.0;
    if q.iter().any(|d| (d.diameter_px / mean_d - 1.0).abs() > 0.2) {
        return None;
    }
    let sides: Vec<f64> = (0..4)
        .map(|i| dist(q[i].centre_px, q[(i + 1) % 4].centre_px))
        .collect();
    let side = sides.iter().sum::<f64>() / 4.0;
    let diag = [
        dist(q[0].centre_px, q[2].centre_px),
        dist(q[1].centre_px, q[3].centre_px),
    ];
    let mut score = 0.0;
    for s in &sides {
        score += (s / side - 1.0).abs();
    }
    for g in diag {
        score += (g / (side * std::f64::consts::SQRT_2) - 1.0).abs();
    }
    let ratio_err = (side / mean_d / expected_ratio - 1.0).abs();
    (score <= 6.0 * SQUARE_TOL && ratio_err < 0.2).then_some(score + ratio_err)
}

/// Finds the orientation dot and labels the corners; refuses mirrored scans.
fn identify(square: [Disc; 4], discs: &[Disc]) -> Result<Fiducials, TraceError> {
    let side = (0..4)
        .map(|i| dist(square[i].centre_px, square[(i + 1) % 4].centre_px))
        .sum::<f64>()
        / 4.0;
    let mean_d = square.iter().map(|d| d.diameter_px).sum::<f64>() / 4.0;
    let dot_offset =
        (FIDUCIAL_SPACING_MM / 2.0 - ORIENTATION_DOT_MM[1]) / FIDUCIAL_SPACING_MM * side;
    let dot_ratio = ORIENTATION_DOT_DIAMETER_MM / FIDUCIAL_DIAMETER_MM;
    // (dot, index of its corner, index of the neighbouring corner it points to)
    let mut found: Vec<(Disc, usize, usize)> = Vec::new();
    for d in discs {
        if square.iter().any(|s| s.centre_px == d.centre_px)
            || (d.diameter_px / mean_d / dot_ratio - 1.0).abs() > 0.3
        {
            continue;
        }
        for i in 0..4 {
            let off = dist(d.centre_px, square[i].centre_px);
            if (off / dot_offset - 1.0).abs() > 0.25 {
                continue;
            }
            for j in [(i + 1) % 4, (i + 3) % 4] {
                let u = unit(square[i].centre_px, square[j].centre_px);
                let v = [
                    d.centre_px[0] - square[i].centre_px[0],
                    d.centre_px[1] - square[i].centre_px[1],
                ];
                let along = u[0] * v[0] + u[1] * v[1];
                let across = (u[0] * v[1] - u[1] * v[0]).abs();
                if along > 0.0 && across < 0.2 * dot_offset {
                    found.push((*d, i, j));
                }
            }
        }
    }
    let (dot, tl, bl) = match found.as_slice() {
        [one] => *one,
        [] => return Err(TraceError::NoOrientationDot),
        _ => {
            return Err(TraceError::AmbiguousOrientation {
                candidates: found.len(),
            })
        }
    };
    let tr = if bl == (tl + 1) % 4 {
        (tl + 3) % 4
    } else {
        (tl + 1) % 4
    };
    let br = (tl + 2) % 4;
    let (p_tl, p_tr, p_bl) = (
        square[tl].centre_px,
        square[tr].centre_px,
        square[bl].centre_px,
    );
    // Image rows grow downwards: for an unmirrored scan TL->TR x TL->BL is positive.
    let cross =
        (p_tr[0] - p_tl[0]) * (p_bl[1] - p_tl[1]) - (p_tr[1] - p_tl[1]) * (p_bl[0] - p_tl[0]);
    if cross < 0.0 {
        return Err(TraceError::Mirrored);
    }
    Ok(Fiducials {
        corners: [square[tl], square[tr], square[br], square[bl]],
        dot,
    })
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn unit(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    let d = dist(a, b).max(1e-12);
    [(b[0] - a[0]) / d, (b[1] - a[1]) / d]
}
