//! Identifying the sheet's marks among the dark discs of an image, under any perspective within
//! 40 degrees: every convex quadrilateral of large discs is tried as the corner fiducials in each
//! of its eight labellings (four rotations, mirrored or not); a labelling is kept when the
//! homography through its corners puts a disc of the orientation dot's size where the dot is
//! printed. Among those, the one that also explains the most sheet-v2 ring dots wins; a mirrored
//! winner is refused.

use super::params::FiducialParams;
use super::{Disc, Fiducials};
use crate::sheet::{
    fiducial_centres_mm, orientation_dot_mm, ring_dots_mm, FIDUCIAL_DIAMETER_MM,
    FIDUCIAL_SPACING_MM, ORIENTATION_DOT_DIAMETER_MM, RING_DOT_DIAMETER_MM,
};
use crate::trace::plane::dist;
use crate::trace::{Homography, TraceError};

struct Labelling {
    corners: [Disc; 4],
    mirrored: bool,
    dot: Disc,
    dot_err_mm: f64,
    ring: Vec<(Disc, [f64; 2])>,
}

/// Finds the corner fiducials, the orientation dot and the ring dots among `discs` (largest
/// first).
pub(crate) fn identify(
    discs: &[Disc],
    spacing_mm: f64,
    params: &FiducialParams,
) -> Result<Fiducials, TraceError> {
    let (best, any_quad) = best_labelling(discs, spacing_mm, params);
    match best {
        Some(l) if l.mirrored => Err(TraceError::Mirrored),
        Some(l) => Ok(Fiducials {
            corners: l.corners,
            dot: l.dot,
            ring: l.ring,
        }),
        None if any_quad => Err(TraceError::NoOrientationDot),
        None => Err(TraceError::NoFiducials { discs: discs.len() }),
    }
}

/// The four corner discs of the best labelling, mirrored or not (for measuring the print's
/// black, where the sheet's sense does not matter).
pub(crate) fn corner_discs(
    discs: &[Disc],
    spacing_mm: f64,
    params: &FiducialParams,
) -> Option<[Disc; 4]> {
    best_labelling(discs, spacing_mm, params)
        .0
        .map(|l| l.corners)
}

/// The best labelling of `discs`, and whether any four of them made a plausible square.
fn best_labelling(
    discs: &[Disc],
    spacing_mm: f64,
    params: &FiducialParams,
) -> (Option<Labelling>, bool) {
    let cand = &discs[..discs.len().min(params.max_corner_candidates)];
    let n = cand.len();
    let mut best: Option<Labelling> = None;
    let mut any_quad = false;
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                for d in c + 1..n {
                    let Some(quad) = plausible_quad([cand[a], cand[b], cand[c], cand[d]]) else {
                        continue;
                    };
                    any_quad = true;
                    // One homography per quad; the eight labellings are the square's
                    // symmetries applied to its sheet coordinates.
                    let px: Vec<[f64; 2]> = quad.iter().map(|d| d.centre_px).collect();
                    let base = fiducial_centres_mm(spacing_mm);
                    let Some(h) = Homography::fit(&px, &base) else {
                        continue;
                    };
                    let mapped: Vec<[f64; 2]> =
                        discs.iter().map(|d| h.apply(d.centre_px)).collect();
                    for mirrored in [false, true] {
                        for rot in 0..4 {
                            let mut order = [0usize, 1, 2, 3];
                            if mirrored {
                                order.reverse();
                            }
                            order.rotate_left(rot);
                            // order[k] is the quad index labelled as corner k: the linear map
                            // taking base[order[k]] to base[k].
                            let m = symmetry(&base, &order);
                            let q = order.map(|i| quad[i]);
                            let sheet: Vec<[f64; 2]> = mapped
                                .iter()
                                .map(|p| [m[0] * p[0] + m[1] * p[1], m[2] * p[0] + m[3] * p[1]])
                                .collect();
                            if let Some(l) = label(q, mirrored, discs, &sheet, spacing_mm, params) {
                                if best.as_ref().is_none_or(|b| better(&l, b)) {
                                    best = Some(l);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    (best, any_quad)
}

fn better(a: &Labelling, b: &Labelling) -> bool {
    a.ring.len() > b.ring.len() || (a.ring.len() == b.ring.len() && a.dot_err_mm < b.dot_err_mm)
}

/// Four discs of similar size (within 2.5x: perspective) forming a convex quadrilateral whose sides are 10..60 disc
/// diameters, ordered clockwise on screen (image y down).
fn plausible_quad(q: [Disc; 4]) -> Option<[Disc; 4]> {
    let dmax = q.iter().map(|d| d.diameter_px).fold(0.0, f64::max);
    let dmin = q
        .iter()
        .map(|d| d.diameter_px)
        .fold(f64::INFINITY, f64::min);
    if dmin <= 0.0 || dmax / dmin > 2.5 {
        return None;
    }
    let cx = q.iter().map(|d| d.centre_px[0]).sum::<f64>() / 4.0;
    let cy = q.iter().map(|d| d.centre_px[1]).sum::<f64>() / 4.0;
    let mut q = q;
    q.sort_by(|a, b| {
        let aa = (a.centre_px[1] - cy).atan2(a.centre_px[0] - cx);
        let ab = (b.centre_px[1] - cy).atan2(b.centre_px[0] - cx);
        aa.total_cmp(&ab)
    });
    let mean_d = q.iter().map(|d| d.diameter_px).sum::<f64>() / 4.0;
    for i in 0..4 {
        let (p0, p1, p2) = (
            q[i].centre_px,
            q[(i + 1) % 4].centre_px,
            q[(i + 2) % 4].centre_px,
        );
        let side = dist(p0, p1) / mean_d;
        if !(10.0..=60.0).contains(&side) {
            return None;
        }
        let cross = (p1[0] - p0[0]) * (p2[1] - p1[1]) - (p1[1] - p0[1]) * (p2[0] - p1[0]);
        if cross <= 0.0 {
            return None;
        }
    }
    Some(q)
}

/// The 2 x 2 matrix (row-major) of the square's symmetry taking `base[order[k]]` to `base[k]`.
fn symmetry(base: &[[f64; 2]; 4], order: &[usize; 4]) -> [f64; 4] {
    // Solve M [b0 b1] = [n0 n1] with b = base[order[0..2]], n = base[0..2].
    let (b0, b1) = (base[order[0]], base[order[1]]);
    let (n0, n1) = (base[0], base[1]);
    let det = b0[0] * b1[1] - b1[0] * b0[1];
    let inv = [b1[1] / det, -b1[0] / det, -b0[1] / det, b0[0] / det];
    // M = N * B^-1, N = [[n0x n1x], [n0y n1y]], B^-1 = [[inv0 inv1], [inv2 inv3]]
    [
        n0[0] * inv[0] + n1[0] * inv[2],
        n0[0] * inv[1] + n1[0] * inv[3],
        n0[1] * inv[0] + n1[1] * inv[2],
        n0[1] * inv[1] + n1[1] * inv[3],
    ]
}

/// Tries `q` as (top-left, top-right, bottom-right, bottom-left); `sheet[i]` is disc `i` in the
/// sheet coordinates of that labelling.
fn label(
    q: [Disc; 4],
    mirrored: bool,
    discs: &[Disc],
    sheet: &[[f64; 2]],
    spacing_mm: f64,
    params: &FiducialParams,
) -> Option<Labelling> {
    let f = spacing_mm / FIDUCIAL_SPACING_MM;
    let tol = params.match_tol_mm * f;
    let dot_mm = orientation_dot_mm(spacing_mm);
    let corner_d = q[0].diameter_px;
    let is_corner = |d: &Disc| q.iter().any(|c| c.centre_px == d.centre_px);
    let dot_ratio = ORIENTATION_DOT_DIAMETER_MM / FIDUCIAL_DIAMETER_MM;
    let (dot, dot_err_mm) = discs
        .iter()
        .zip(sheet)
        .filter(|(d, _)| !is_corner(d))
        .filter(|(d, _)| (d.diameter_px / corner_d / dot_ratio - 1.0).abs() < 0.4)
        .map(|(d, s)| (*d, dist(*s, dot_mm)))
        .filter(|(_, e)| *e < tol)
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let ring_ratio = RING_DOT_DIAMETER_MM / FIDUCIAL_DIAMETER_MM;
    let small: Vec<(Disc, [f64; 2])> = discs
        .iter()
        .zip(sheet)
        .filter(|(d, _)| !is_corner(d) && d.centre_px != dot.centre_px)
        .filter(|(d, _)| (d.diameter_px / corner_d / ring_ratio - 1.0).abs() < 0.6)
        .map(|(d, s)| (*d, *s))
        .collect();
    let ring = ring_dots_mm(spacing_mm)
        .into_iter()
        .filter_map(|r| {
            small
                .iter()
                .map(|(d, m)| (*d, dist(*m, r)))
                .filter(|(_, e)| *e < tol)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(d, _)| (d, r))
        })
        .collect();
    Some(Labelling {
        corners: q,
        mirrored,
        dot,
        dot_err_mm,
        ring,
    })
}
