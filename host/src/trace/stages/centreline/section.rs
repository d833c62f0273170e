//! The cross-section of a stroke in a short window: the darkness-weighted centroid, mass and
//! spread of the pixels across the stroke, and the windows that cannot be read (the printed
//! ring dots). However dark, graphite is graphite: inside the trace area the only black print
//! is the ring dots (occluders) and the corner discs and orientation dot (outside the area
//! read), so a soft pencil or one pressed hard is followed like a light one.

use super::Tracker;
use crate::trace::plane::dist;

/// Printed marks (ring dots) in pixel coordinates that the pencil may cross: windows touching
/// them are occluded, the stroke is bridged across them.
#[derive(Debug, Clone, Default)]
pub(crate) struct Occluders {
    /// `(centre, radius)`, pixels.
    pub discs: Vec<([f64; 2], f64)>,
}

impl Occluders {
    fn touches(&self, c: [f64; 2], reach: f64) -> bool {
        self.discs.iter().any(|(p, r)| dist(*p, c) < r + reach)
    }
}

pub(super) struct Section {
    pub offset: f64,
    /// Summed weight per pixel of window length.
    pub mass: f64,
    pub var: f64,
}

impl Tracker<'_> {
    /// Moves `p` across the stroke onto the weighted centroid (up to three iterations).
    pub(super) fn centre_at(
        &self,
        p: [f64; 2],
        t: [f64; 2],
        half_len: f64,
        half_w: f64,
    ) -> Option<([f64; 2], Section)> {
        let n = [-t[1], t[0]];
        let mut p = p;
        let mut last = None;
        for _ in 0..3 {
            let s = self.section(p, t, half_len, half_w)?;
            p = [p[0] + s.offset * n[0], p[1] + s.offset * n[1]];
            let done = s.offset.abs() < 0.01;
            last = Some(s);
            if done {
                break;
            }
        }
        last.map(|s| (p, s))
    }

    /// Weighted statistics of the offsets along the normal inside the window
    /// `|along| <= half_len, |across| <= half_w` centred at `c`.
    fn section(&self, c: [f64; 2], t: [f64; 2], half_len: f64, half_w: f64) -> Option<Section> {
        let n = [-t[1], t[0]];
        let ex = t[0].abs() * half_len + n[0].abs() * half_w;
        let ey = t[1].abs() * half_len + n[1].abs() * half_w;
        if self.occluders.touches(c, half_len.hypot(half_w)) {
            return None;
        }
        let paper = self.paper.at(c[0], c[1]);
        let (w, h) = (self.img.width() as i64, self.img.height() as i64);
        let x0 = ((c[0] - ex - 0.5).floor() as i64).clamp(0, w);
        let x1 = ((c[0] + ex + 0.5).ceil() as i64).clamp(0, w);
        let y0 = ((c[1] - ey - 0.5).floor() as i64).clamp(0, h);
        let y1 = ((c[1] + ey + 0.5).ceil() as i64).clamp(0, h);
        let raw = self.img.as_raw();
        let (mut sw, mut sb, mut sbb) = (0.0f64, 0.0f64, 0.0f64);
        for y in y0..y1 {
            let dy = y as f64 + 0.5 - c[1];
            let row = &raw[(3 * y * w) as usize..(3 * (y + 1) * w) as usize];
            for x in x0..x1 {
                let dx = x as f64 + 0.5 - c[0];
                let along = dx * t[0] + dy * t[1];
                let across = dx * n[0] + dy * n[1];
                if along.abs() > half_len || across.abs() > half_w {
                    continue;
                }
                let i = 3 * x as usize;
                let dark = self.ink.darkness_on(&row[i..i + 3], paper);
                let wgt = (dark - self.ink.floor).max(0.0) as f64;
                sw += wgt;
                sb += wgt * across;
                sbb += wgt * across * across;
            }
        }
        if sw <= 0.0 {
            return None;
        }
        let offset = sb / sw;
        Some(Section {
            offset,
            mass: sw / (2.0 * half_len),
            var: (sbb / sw - offset * offset).max(0.0),
        })
    }
}
