//! Strokes in sheet mm: tracked pieces, their lengths, and resampling at a fixed arc-length
//! spacing.

use super::plane::dist;

/// A polyline in sheet mm, ordered along the pencil's path.
#[derive(Debug, Clone, PartialEq)]
pub struct Stroke {
    /// Points, mm, at most the requested spacing apart (for a closed stroke the last point is
    /// not repeated; the closing segment is also within the spacing).
    pub points_mm: Vec<[f64; 2]>,
    /// Whether the stroke closes on itself.
    pub closed: bool,
    /// Total length of the bridges across pencil skips, mm.
    pub bridged_mm: f64,
}

impl Stroke {
    /// Arc length, mm (including the closing segment of a closed stroke).
    pub fn length_mm(&self) -> f64 {
        polyline_length(&self.points_mm, self.closed)
    }
}

/// A tracked piece in sheet mm.
#[derive(Debug, Clone)]
pub(crate) struct PieceMm {
    pub pts: Vec<[f64; 2]>,
    pub closed: bool,
}

/// Length of a polyline, mm.
pub fn polyline_length(pts: &[[f64; 2]], closed: bool) -> f64 {
    let open: f64 = pts.windows(2).map(|w| dist(w[0], w[1])).sum();
    match (closed, pts.first(), pts.last()) {
        (true, Some(a), Some(b)) => open + dist(*a, *b),
        _ => open,
    }
}

/// Resamples a polyline at equal arc-length steps no longer than `spacing_mm` (both ends of an
/// open polyline are kept; a closed one is resampled around the loop).
pub fn resample(pts: &[[f64; 2]], closed: bool, spacing_mm: f64) -> Vec<[f64; 2]> {
    let mut path: Vec<[f64; 2]> = pts.to_vec();
    if closed {
        if let Some(&p0) = pts.first() {
            path.push(p0);
        }
    }
    let total = polyline_length(&path, false);
    if path.len() < 2 || total <= 0.0 || spacing_mm.is_nan() || spacing_mm <= 0.0 {
        return pts.to_vec();
    }
    let n = (total / spacing_mm).ceil().max(1.0) as usize;
    let step = total / n as f64;
    let count = if closed { n } else { n + 1 };
    let mut out = Vec::with_capacity(count);
    let (mut seg, mut seg_start) = (0usize, 0.0f64);
    for i in 0..count {
        let s = (i as f64 * step).min(total);
        while seg + 2 < path.len() && seg_start + dist(path[seg], path[seg + 1]) < s {
            seg_start += dist(path[seg], path[seg + 1]);
            seg += 1;
        }
        let (a, b) = (path[seg], path[seg + 1]);
        let d = dist(a, b);
        let f = if d > 0.0 {
            ((s - seg_start) / d).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resample_keeps_ends_and_spacing() {
        let pts = [[0.0, 0.0], [1.0, 0.0], [1.0, 2.05]];
        let r = resample(&pts, false, 0.5);
        assert_eq!(r[0], [0.0, 0.0]);
        let last = r[r.len() - 1];
        assert!((last[0] - 1.0).abs() < 1e-12 && (last[1] - 2.05).abs() < 1e-12);
        for w in r.windows(2) {
            assert!(dist(w[0], w[1]) <= 0.5 + 1e-12);
        }
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let c = resample(&square, true, 0.3);
        assert_eq!(c.len(), 14);
        assert!(dist(c[13], c[0]) <= 0.3);
    }
}
