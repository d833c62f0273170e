//! Illumination is not ink: the stretches of tracked pieces that are edges of light, not lines
//! of graphite, cut out before the pieces are linked.
//!
//! - A hard shadow's edge (a phone's or a hand's, sharp-edged) darkens the paper on one side
//!   only: across it the image is a single step, where a pencil line is a valley with paper on
//!   both sides. Along each piece the darkness of its centre is compared with that of its two
//!   flanks (each flank the lightest of a few offsets, so a neighbouring mark does not darken
//!   it); where one flank is about as dark as the centre and the other is light, for at least
//!   [`CentrelineParams::step_run_mm`], the stretch is a step of light and is cut out.
//! - A scan's page edge inside the trace area (the print off-centre on the page), with the lid
//!   beyond it and the edge's shadow on the lid: a straight line along the sheet's y axis
//!   outside the printed ring, where no printed mark lies; such pieces are the page's own edge
//!   and are dropped.

use super::{CentrelineParams, Piece};
use crate::trace::chain::PieceMm;
use crate::trace::ink::InkModel;
use crate::trace::paper::PaperMap;
use crate::trace::plane::unit;
use image::RgbImage;

/// Darkness of the pixel holding `p` (px) against the paper level `paper` (one level for a
/// whole profile: the paper map itself follows a shadow, over a few blocks); `None` outside the
/// image.
fn dark_at(img: &RgbImage, ink: &InkModel, paper: [f32; 3], p: [f64; 2]) -> Option<f32> {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (x, y) = (p[0].floor() as i64, p[1].floor() as i64);
    if x < 0 || y < 0 || x >= w || y >= h {
        return None;
    }
    let px = img.get_pixel(x as u32, y as u32);
    Some(ink.darkness_on(&px.0, paper))
}

/// Centre, and the flanks' offsets across, mm.
const CENTRE_MM: [f64; 3] = [-0.12, 0.0, 0.12];

/// Per point of `pts` (px): the centre's darkness and each flank's, averaged over the
/// neighbours within `half_window` points; `None` where a sample falls outside the image.
fn profile(
    img: &RgbImage,
    ink: &InkModel,
    paper: &PaperMap,
    pts: &[[f64; 2]],
    px_per_mm: f64,
    cp: &CentrelineParams,
) -> Vec<Option<[f64; 3]>> {
    let n = pts.len();
    let flanks = cp.step_flank_mm;
    // Per point: centre, and each flank offset on both sides.
    let raw: Vec<Option<(f64, [[f64; 3]; 2])>> = (0..n)
        .map(|i| {
            let (a, b) = (pts[i.saturating_sub(2)], pts[(i + 2).min(n - 1)]);
            let t = unit([b[0] - a[0], b[1] - a[1]])?;
            let nrm = [-t[1], t[0]];
            let level = paper.at(pts[i][0], pts[i][1]);
            let at = |off_mm: f64| {
                let o = off_mm * px_per_mm;
                dark_at(
                    img,
                    ink,
                    level,
                    [pts[i][0] + o * nrm[0], pts[i][1] + o * nrm[1]],
                )
                .map(f64::from)
            };
            let mut c = 0.0;
            for o in CENTRE_MM {
                c += at(o)?;
            }
            let mut sides = [[0.0; 3]; 2];
            for (s, sign) in [(0, -1.0), (1, 1.0)] {
                for (k, f) in flanks.iter().enumerate() {
                    sides[s][k] = at(sign * f)?;
                }
            }
            Some((c / CENTRE_MM.len() as f64, sides))
        })
        .collect();
    let half = (cp.step_window_mm * px_per_mm / step_px(pts).max(1e-9)).round() as usize;
    (0..n)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(half), (i + half).min(n - 1));
            let mut c = 0.0;
            let mut sides = [[0.0; 3]; 2];
            let mut m = 0.0;
            for r in raw[lo..=hi].iter().flatten() {
                c += r.0;
                for (acc, flank) in sides.iter_mut().zip(&r.1) {
                    for (a, v) in acc.iter_mut().zip(flank) {
                        *a += v;
                    }
                }
                m += 1.0;
            }
            if m < 1.0 {
                return None;
            }
            // Each flank: its lightest offset.
            let side = |s: usize| sides[s].iter().copied().fold(f64::INFINITY, f64::min) / m;
            Some([c / m, side(0), side(1)])
        })
        .collect()
}

/// Mean distance between successive points, px.
fn step_px(pts: &[[f64; 2]]) -> f64 {
    if pts.len() < 2 {
        return 1.0;
    }
    let total: f64 = pts
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    total / (pts.len() - 1) as f64
}

/// Whether a point's profile `[centre, flank, flank]` is a step of light: one flank about as
/// dark as the centre, the other light.
fn is_step(v: [f64; 3], cp: &CentrelineParams) -> bool {
    let (ca, cb) = (v[0] - v[1], v[0] - v[2]);
    let (lo, hi) = (ca.min(cb), ca.max(cb));
    hi >= cp.step_min_contrast && lo < cp.step_ratio * hi
}

/// `pieces` with their stretches of steps of light cut out (see the module documentation).
pub(crate) fn cut_light_steps(
    pieces: Vec<Piece>,
    img: &RgbImage,
    ink: &InkModel,
    paper: &PaperMap,
    px_per_mm: f64,
    cp: &CentrelineParams,
) -> Vec<Piece> {
    let mut out = Vec::with_capacity(pieces.len());
    for piece in pieces {
        let n = piece.pts_px.len();
        if n < 3 {
            out.push(piece);
            continue;
        }
        let prof = profile(img, ink, paper, &piece.pts_px, px_per_mm, cp);
        let step: Vec<bool> = prof
            .iter()
            .map(|v| v.is_some_and(|v| is_step(v, cp)))
            .collect();
        // Runs of steps at least `step_run_mm` long.
        let min_run = (cp.step_run_mm * px_per_mm / step_px(&piece.pts_px).max(1e-9)).ceil();
        let mut cut = vec![false; n];
        let mut i = 0;
        while i < n {
            if !step[i] {
                i += 1;
                continue;
            }
            let j = (i..n).find(|&j| !step[j]).unwrap_or(n);
            if (j - i) as f64 >= min_run {
                cut[i..j].fill(true);
            }
            i = j;
        }
        if !cut.iter().any(|&c| c) {
            out.push(piece);
            continue;
        }
        // A closed piece cut anywhere opens there: begin at its first cut point.
        let (pts, cut) = if piece.closed {
            let first = cut.iter().position(|&c| c).unwrap_or(0);
            let mut p = piece.pts_px[first..].to_vec();
            p.extend_from_slice(&piece.pts_px[..first]);
            let mut c = cut[first..].to_vec();
            c.extend_from_slice(&cut[..first]);
            (p, c)
        } else {
            (piece.pts_px, cut)
        };
        let mut run: Vec<[f64; 2]> = Vec::new();
        for (p, c) in pts.into_iter().zip(cut) {
            if c {
                if run.len() >= 2 {
                    out.push(Piece {
                        pts_px: std::mem::take(&mut run),
                        closed: false,
                    });
                }
                run.clear();
            } else {
                run.push(p);
            }
        }
        if run.len() >= 2 {
            out.push(Piece {
                pts_px: run,
                closed: false,
            });
        }
    }
    out
}

/// Whether a piece in sheet mm is the page's own edge: straight (RMS off its line at most
/// [`CentrelineParams::page_edge_rms_mm`]), along the sheet's y axis (within
/// [`CentrelineParams::page_edge_max_deg`]), at least [`CentrelineParams::page_edge_min_mm`]
/// long, and wholly beyond [`CentrelineParams::page_edge_from_mm`] from the centre across.
pub(crate) fn is_page_edge(piece: &PieceMm, cp: &CentrelineParams) -> bool {
    let pts = &piece.pts;
    if pts.len() < 3 || pts.iter().any(|p| p[0].abs() < cp.page_edge_from_mm) {
        return false;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p[0]).sum::<f64>() / n,
        pts.iter().map(|p| p[1]).sum::<f64>() / n,
    );
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in pts {
        let (dx, dy) = (p[0] - mx, p[1] - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    // The principal direction and the spread across it.
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let (s, c) = angle.sin_cos();
    let across: f64 = pts
        .iter()
        .map(|p| (-(p[0] - mx) * s + (p[1] - my) * c).powi(2))
        .sum::<f64>()
        / n;
    let along_len = pts
        .iter()
        .map(|p| (p[0] - mx) * c + (p[1] - my) * s)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let len = along_len.1 - along_len.0;
    // Off the y axis, degrees (the line's direction either way).
    let off_y_deg = (90.0 - angle.to_degrees().abs()).abs();
    len >= cp.page_edge_min_mm
        && across.sqrt() <= cp.page_edge_rms_mm
        && off_y_deg <= cp.page_edge_max_deg
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cp() -> CentrelineParams {
        CentrelineParams::default()
    }

    #[test]
    fn a_step_is_a_step_and_a_line_is_not() {
        // Centre as dark as one flank, the other light: a step.
        assert!(is_step([0.4, 0.38, 0.0], &cp()));
        // Darker than both flanks: a line.
        assert!(!is_step([0.4, 0.02, 0.05], &cp()));
        // A line beside a shadow, darker than the dark flank too.
        assert!(!is_step([0.7, 0.35, 0.0], &cp()));
        // Nothing there: not a step.
        assert!(!is_step([0.01, 0.0, 0.0], &cp()));
    }

    #[test]
    fn page_edge_is_a_straight_line_along_y_in_the_margin() {
        let edge = PieceMm {
            pts: (0..200)
                .map(|i| [-101.0 + 0.001 * i as f64, -100.0 + i as f64])
                .collect(),
            closed: false,
        };
        assert!(is_page_edge(&edge, &cp()));
        let inside = PieceMm {
            pts: (0..200).map(|i| [-60.0, -100.0 + i as f64]).collect(),
            closed: false,
        };
        assert!(!is_page_edge(&inside, &cp()));
        let slanted = PieceMm {
            pts: (0..100)
                .map(|i| [96.0 + 0.1 * i as f64, i as f64])
                .collect(),
            closed: false,
        };
        assert!(!is_page_edge(&slanted, &cp()));
    }
}
