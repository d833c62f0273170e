//! The written points a band is followed through: every point of every path and of the strays
//! with its direction over a zigzag pass's teeth, none where the path turns a corner.

use super::params::LinesParams;
use super::{arc, unit};
use crate::trace::band::{Cloud, Dot, Source};
use crate::trace::paths::DrawnPath;
use crate::trace::plane::sub;

/// Directions along `pts` for following a band: the chord over `LinesParams::band_dir_half_mm` either
/// side (over a zigzag pass's teeth), none (zero) where the path turns a corner (by more than
/// `LinesParams::corner_deg` between the chords before and after a point): a band is not followed round
/// a pass's corner into the line it turns into.
fn band_directions(pts: &[[f64; 2]], s: &[f64], lp: &LinesParams) -> Vec<[f64; 2]> {
    let n = pts.len();
    let cos_corner = lp.corner_deg.to_radians().cos();
    let h = lp.band_dir_half_mm;
    (0..n)
        .map(|i| {
            let a = s[..i].partition_point(|&v| v < s[i] - h).min(n - 1);
            let b = (i + s[i..].partition_point(|&v| v <= s[i] + h)).min(n - 1);
            let (back, ahead) = (sub(pts[i], pts[a]), sub(pts[b], pts[i]));
            let (lb, la) = (back[0].hypot(back[1]), ahead[0].hypot(ahead[1]));
            if lb > 0.5 * h
                && la > 0.5 * h
                && (back[0] * ahead[0] + back[1] * ahead[1]) / (lb * la) < cos_corner
            {
                [0.0, 0.0]
            } else {
                unit(sub(pts[b], pts[a]))
            }
        })
        .collect()
}

/// The written points of the paths and of the strays (`strays`: their points, mm), with
/// their directions; `first[i]..first[i + 1]` are path `i`'s.
pub(super) fn cloud(
    paths: &[DrawnPath],
    strays: &[Vec<[f64; 2]>],
    lp: &LinesParams,
) -> (Cloud, Vec<usize>) {
    let mut dots = Vec::new();
    let mut first = Vec::with_capacity(paths.len() + 1);
    let add = |pts: &[[f64; 2]], src: Source, dots: &mut Vec<Dot>| {
        if pts.len() < 2 {
            return;
        }
        let s = arc(pts);
        for (p, dir) in pts.iter().zip(band_directions(pts, &s, lp)) {
            dots.push(Dot { p: *p, dir, src });
        }
    };
    for (i, p) in paths.iter().enumerate() {
        first.push(dots.len());
        add(&p.stroke.points_mm, Source::Path(i), &mut dots);
    }
    first.push(dots.len());
    for s in strays {
        if arc(s).last().copied().unwrap_or(0.0) >= lp.min_dot_mark_mm {
            add(s, Source::Stray, &mut dots);
        }
    }
    (Cloud::new(dots, lp), first)
}
