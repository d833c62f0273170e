//! A printed reference path as dark as the pencil: a greyscale scan, or the path printed in grey
//! or black. The tracer tells the pencil from the red print by colour ([`super::ink`]); without
//! red ink the print is graphite to it, and the longest line it links is the printed path.
//! Found by its geometry: the printed circle or line is known in sheet mm, and its centres lie on
//! it to within the mapping's error. Where most of one printed path is seen that way, every
//! tracked point within [`STRIP_MM`] of it is left out (the pencil crossing it becomes a short
//! gap, bridged and listed; the pencil running along it a longer one, missing: exit 1), and the
//! run says so.

use super::chain::{polyline_length, PieceMm, Stroke};
use super::stages::link::length_near;
use crate::sheet::ReferencePath;

/// Centres within this of a printed path are seen on it, mm (the mapping's error and the
/// centres' scatter on a crisp printed line).
const ON_PRINT_MM: f64 = 0.1;
/// The share of a printed path seen on it that makes it a grey print.
const SEEN_SHARE: f64 = 0.4;
/// Tracked points within this of a grey print are left out, mm (the print's half width and the
/// pencil's, whose centres the print pulls aside).
pub const STRIP_MM: f64 = 0.6;

/// A free end of the path this near a grey print may go on under it, mm: where the pencil
/// comes within a few millimetres of the print, the tracker may have followed the print instead
/// (the two merge in its window), and that stretch was left out with the print.
const END_NEAR_MM: f64 = 3.0;

/// A printed path found in grey.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GreyPrint {
    pub path: ReferencePath,
    /// Length of it seen (centres within [`ON_PRINT_MM`]), mm.
    pub seen_mm: f64,
    /// Length of the printed path, mm.
    pub printed_mm: f64,
}

impl GreyPrint {
    /// The free ends of `path` that meet the print (it may go on under the print, unseen); none
    /// for a closed path.
    pub(crate) fn ends_meeting(&self, path: &Stroke) -> Vec<[f64; 2]> {
        match (path.closed, path.points_mm.first(), path.points_mm.last()) {
            (false, Some(a), Some(b)) => [*a, *b]
                .into_iter()
                .filter(|p| self.path.distance_mm(*p) <= END_NEAR_MM)
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// The grey print among `pieces`, if most of a printed path is seen on them.
pub(crate) fn find(pieces: &[PieceMm]) -> Option<GreyPrint> {
    [ReferencePath::Circle, ReferencePath::Line]
        .into_iter()
        .map(|path| GreyPrint {
            path,
            seen_mm: length_near(pieces, path, ON_PRINT_MM),
            printed_mm: path.length_mm(),
        })
        .filter(|g| g.seen_mm >= SEEN_SHARE * g.printed_mm)
        .max_by(|a, b| (a.seen_mm / a.printed_mm).total_cmp(&(b.seen_mm / b.printed_mm)))
}

/// `pieces` without their points within [`STRIP_MM`] of `print` (a piece is split where it
/// comes that near; what is left shorter than two points or 0.5 mm is dropped).
pub(crate) fn strip(pieces: Vec<PieceMm>, print: &GreyPrint) -> Vec<PieceMm> {
    let mut out = Vec::new();
    for piece in pieces {
        let near: Vec<bool> = piece
            .pts
            .iter()
            .map(|p| print.path.distance_mm(*p) <= STRIP_MM)
            .collect();
        if !near.iter().any(|n| *n) {
            out.push(piece);
            continue;
        }
        // A closed piece is cut open where it first comes near, so its runs do not wrap.
        let n = piece.pts.len();
        let start = if piece.closed {
            near.iter().position(|v| *v).unwrap_or(0)
        } else {
            0
        };
        let mut run: Vec<[f64; 2]> = Vec::new();
        let mut flush = |run: &mut Vec<[f64; 2]>| {
            if run.len() >= 2 && polyline_length(run, false) >= 0.5 {
                out.push(PieceMm {
                    pts: std::mem::take(run),
                    closed: false,
                });
            }
            run.clear();
        };
        for k in 0..n {
            let i = (start + k) % n;
            if near[i] {
                flush(&mut run);
            } else {
                run.push(piece.pts[i]);
            }
        }
        flush(&mut run);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc(r: f64, c: [f64; 2], from_deg: f64, to_deg: f64) -> PieceMm {
        let n = ((to_deg - from_deg).abs() * 4.0) as usize;
        PieceMm {
            pts: (0..=n)
                .map(|i| {
                    let a = (from_deg + (to_deg - from_deg) * i as f64 / n as f64).to_radians();
                    [c[0] + r * a.cos(), c[1] + r * a.sin()]
                })
                .collect(),
            closed: false,
        }
    }

    #[test]
    fn a_grey_printed_circle_is_found_and_the_pencil_crossing_it_kept_apart() {
        // The printed circle in three pieces (cut where the pencil crosses it), and a pencil
        // circle of 60 mm radius centred 60 mm off: it crosses the printed one twice.
        let mut pieces = vec![
            arc(100.0, [0.0, 0.0], 5.0, 150.0),
            arc(100.0, [0.0, 0.0], 155.0, 300.0),
        ];
        let pencil = PieceMm {
            closed: true,
            ..arc(60.0, [60.0, 0.0], 0.0, 359.75)
        };
        pieces.push(pencil.clone());
        let print = find(&pieces).expect("grey print");
        assert_eq!(print.path, ReferencePath::Circle);
        assert!(print.seen_mm > 0.4 * print.printed_mm, "{print:?}");
        let kept = strip(pieces, &print);
        // The printed pieces are gone; the pencil circle is cut at its two crossings.
        assert_eq!(kept.len(), 2, "{}", kept.len());
        let total: f64 = kept.iter().map(|p| polyline_length(&p.pts, false)).sum();
        let whole = polyline_length(&pencil.pts, true);
        // The circles cross at 33.6 deg: each crossing leaves out 2 x STRIP_MM / sin(33.6 deg).
        let cut = 2.0 * 2.0 * STRIP_MM / 33.56f64.to_radians().sin();
        // (and up to a segment of 0.26 mm more on each side of each cut)
        assert!(
            (whole - total - cut).abs() < 1.1,
            "{total} of {whole}, cut {cut}"
        );
        for p in &kept {
            assert!(p
                .pts
                .iter()
                .all(|q| ReferencePath::Circle.distance_mm(*q) > STRIP_MM));
        }
    }

    #[test]
    fn a_pencil_near_the_printed_path_is_no_grey_print() {
        // A pencil circle 0.5 mm outside the printed one over half its length, and no print:
        // nothing within 0.1 mm of it.
        let pieces = vec![arc(100.5, [0.0, 0.0], 0.0, 180.0)];
        assert!(find(&pieces).is_none());
        // The pencil on the printed line for a quarter of it is not a print either.
        let line = PieceMm {
            pts: (0..=200).map(|i| [-100.0 + 0.25 * i as f64, 0.0]).collect(),
            closed: false,
        };
        assert!(find(&[line]).is_none());
    }
}
