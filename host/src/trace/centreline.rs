//! Sub-pixel centreline of pencil strokes by tracking: from a seed on the stroke, step along the
//! local tangent and put each centre at the darkness-weighted centroid of the pixels in a short
//! window across the stroke (along the local normal; not a skeleton). Ends are found where the
//! stroke's mass per unit length falls to half, then pulled back by half the stroke width (a
//! round pencil tip leaves a round cap). Work is confined to windows around the stroke.

use super::ink::InkModel;
use super::paper::PaperMap;
use super::plane::dist;
use super::raster::CoarseMap;
use image::RgbImage;
use indicatif::ProgressBar;

mod section;

pub(crate) use section::Occluders;

/// The owner of blocks around a seed too faint to begin a piece: not seeded again, but free
/// to walk.
const TRIED: u32 = u32::MAX;

/// In faint graphite (a running mass under [`FAINT_MASS`] times [`TrackParams::min_mass`]), a
/// window under half the running mass but holding at least [`FAINT_SHARE`] of it ends the piece
/// only if the stroke is not back within [`LOOK_AHEAD`] more steps: the paper's tooth breaks
/// faint graphite up, a skip leaves none.
const FAINT_MASS: f64 = 2.0;
const FAINT_SHARE: f64 = 0.2;
const LOOK_AHEAD: usize = 2;

/// Why a seed began no piece.
enum Unbegun {
    /// Less darkness-weighted width than [`TrackParams::min_mass`].
    TooFaint,
    /// Wider than pencil, no direction, or nothing to walk.
    Other,
}

/// One tracked piece of stroke, pixel coordinates.
#[derive(Debug, Clone)]
pub(crate) struct Piece {
    pub pts_px: Vec<[f64; 2]>,
    pub closed: bool,
}

/// Tracking settings, pixels.
pub(crate) struct TrackParams {
    pub px_per_mm: f64,
    /// Distance between centres, pixels.
    pub step_px: f64,
    /// Strokes wider than this (pixels) are not pencil.
    pub max_width_px: f64,
    /// Smallest accepted mass per unit length (weight x pixels).
    pub min_mass: f64,
}

/// Window geometry and reference mass of one piece.
#[derive(Clone, Copy)]
struct Geom {
    half_w: f64,
    width_px: f64,
    mass0: f64,
}

enum End {
    Faded { trim_px: f64 },
    Closed,
    Stopped,
}

/// Tracks every stroke whose coarse blocks are set in `seeds` (a mask over `map`), keeping the
/// centre of every window inside `roi`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn track_all(
    img: &RgbImage,
    ink: &InkModel,
    paper: &PaperMap,
    occluders: &Occluders,
    map: &CoarseMap,
    seeds: &[bool],
    roi: &dyn Fn([f64; 2]) -> bool,
    params: &TrackParams,
    progress: &ProgressBar,
) -> Vec<Piece> {
    let mut tracker = Tracker {
        img,
        ink,
        paper,
        occluders,
        map,
        visited: vec![0; seeds.len()],
        roi,
        p: params,
    };
    let mut pieces = Vec::new();
    progress.set_length(seeds.len() as u64);
    let chunk = (seeds.len() / 100).max(1);
    for (i, &s) in seeds.iter().enumerate() {
        if i % chunk == 0 {
            progress.set_position(i as u64);
        }
        if !s || tracker.visited[i] != 0 {
            continue;
        }
        let id = pieces.len() as u32 + 1;
        let seed = map.block_centre_px(i % map.w, i / map.w);
        let piece = tracker.track_from(seed, id, seeds);
        // Whatever happened, the seed's surroundings are done as seeds. Where the graphite was
        // too faint to begin a piece, a walk from a darker stretch may still pass; anything
        // else that began nothing (a blob wider than pencil) stays fenced off.
        let owner = match piece {
            Err(Unbegun::TooFaint) => TRIED,
            _ => id,
        };
        tracker.mark(seed, 2.0 * map.k as f64, owner);
        pieces.push(piece.ok());
    }
    progress.set_position(seeds.len() as u64);
    pieces.into_iter().flatten().collect()
}

pub(super) struct Tracker<'a> {
    img: &'a RgbImage,
    ink: &'a InkModel,
    paper: &'a PaperMap,
    occluders: &'a Occluders,
    map: &'a CoarseMap,
    visited: Vec<u32>,
    roi: &'a dyn Fn([f64; 2]) -> bool,
    p: &'a TrackParams,
}

impl Tracker<'_> {
    fn track_from(&mut self, seed: [f64; 2], id: u32, seeds: &[bool]) -> Result<Piece, Unbegun> {
        let t0 = self.seed_tangent(seed, seeds).ok_or(Unbegun::Other)?;
        let wide = 1.0 * self.p.px_per_mm;
        let half_len = 0.5 * self.p.step_px;
        let (start, s0) = self
            .centre_at(seed, t0, half_len, wide)
            .ok_or(Unbegun::Other)?;
        let width_px = (12.0 * s0.var).sqrt();
        if width_px > self.p.max_width_px {
            return Err(Unbegun::Other);
        }
        if s0.mass < self.p.min_mass {
            return Err(Unbegun::TooFaint);
        }
        let half_w = (0.9 * width_px + 2.0).max(0.25 * self.p.px_per_mm);
        // Re-centre with the narrow window.
        let (start, s0) = self
            .centre_at(start, t0, half_len, half_w)
            .ok_or(Unbegun::Other)?;
        let geom = Geom {
            half_w,
            width_px,
            mass0: s0.mass,
        };
        let mut fwd = vec![start];
        self.mark(start, half_w + self.map.k as f64, id);
        let end_f = self.walk(&mut fwd, t0, geom, id, true);
        let closed = matches!(end_f, End::Closed);
        let mut pts = if closed {
            fwd
        } else {
            let mut back = vec![start];
            let end_b = self.walk(&mut back, [-t0[0], -t0[1]], geom, id, false);
            // Join first, then trim: the seed itself may lie in an end cap.
            back.reverse();
            back.pop();
            back.extend(fwd);
            if let End::Faded { trim_px } = end_f {
                trim_end(&mut back, trim_px);
            }
            if let End::Faded { trim_px } = end_b {
                back.reverse();
                trim_end(&mut back, trim_px);
                back.reverse();
            }
            back
        };
        pts.dedup();
        if pts.len() < 2 {
            return Err(Unbegun::Other);
        }
        Ok(Piece {
            pts_px: pts,
            closed,
        })
    }

    /// Principal direction of the seed mask blocks within 1.5 mm of `p`.
    fn seed_tangent(&self, p: [f64; 2], seeds: &[bool]) -> Option<[f64; 2]> {
        let k = self.map.k as f64;
        let r_blocks = (1.5 * self.p.px_per_mm / k).ceil() as i64;
        let (bx, by) = ((p[0] / k) as i64, (p[1] / k) as i64);
        let (mut n, mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for y in (by - r_blocks).max(0)..=(by + r_blocks).min(self.map.h as i64 - 1) {
            for x in (bx - r_blocks).max(0)..=(bx + r_blocks).min(self.map.w as i64 - 1) {
                if !seeds[y as usize * self.map.w + x as usize] {
                    continue;
                }
                let (fx, fy) = (x as f64, y as f64);
                n += 1.0;
                sx += fx;
                sy += fy;
                sxx += fx * fx;
                sxy += fx * fy;
                syy += fy * fy;
            }
        }
        if n < 2.0 {
            return None;
        }
        let (cxx, cxy, cyy) = (
            sxx / n - (sx / n).powi(2),
            sxy / n - sx * sy / (n * n),
            syy / n - (sy / n).powi(2),
        );
        let angle = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        Some([angle.cos(), angle.sin()])
    }

    /// Follows the stroke from the last point of `pts` in direction `t`.
    fn walk(
        &mut self,
        pts: &mut Vec<[f64; 2]>,
        t: [f64; 2],
        geom: Geom,
        id: u32,
        may_close: bool,
    ) -> End {
        let Geom {
            half_w,
            width_px,
            mass0,
        } = geom;
        let step = self.p.step_px;
        let half_len = 0.5 * step;
        let mut t = t;
        let mut ema = mass0;
        let mut last_mass = mass0;
        let start = pts[0];
        let max_steps = 4 * (self.img.width() as usize + self.img.height() as usize) * 4;
        for _ in 0..max_steps {
            let Some(&c) = pts.last() else {
                return End::Stopped;
            };
            let pred = [c[0] + step * t[0], c[1] + step * t[1]];
            if !self.free_at(pred, id) {
                return End::Stopped;
            }
            let mut found = self.centre_at(pred, t, half_len, half_w);
            let mut mass = found.as_ref().map_or(0.0, |(_, s)| s.mass);
            if mass < 0.5 * ema && mass >= FAINT_SHARE * ema && ema < FAINT_MASS * self.p.min_mass {
                // Faint graphite broken up by the paper's tooth, not a skip: where the stroke is
                // back within LOOK_AHEAD steps, every window on the way holding graphite, walk on
                // from there.
                if let Some(f) = self.ahead(c, t, geom, id, ema) {
                    mass = f.1.mass;
                    found = Some(f);
                }
            }
            if mass < 0.5 * ema {
                // Half-mass crossing between the last centre and this step, then back by
                // half the stroke width.
                let frac =
                    ((last_mass - 0.5 * ema) / (last_mass - mass).max(1e-12)).clamp(0.0, 1.0);
                return End::Faded {
                    trim_px: 0.5 * width_px - frac * step,
                };
            }
            let Some((p, _)) = found else {
                return End::Stopped;
            };
            if may_close && pts.len() > 12 && dist(p, start) < 1.5 * step {
                return End::Closed;
            }
            let back = pts[pts.len().saturating_sub(4)];
            let d = dist(p, back);
            if d > 1e-9 {
                t = [(p[0] - back[0]) / d, (p[1] - back[1]) / d];
            }
            ema = 0.9 * ema + 0.1 * mass;
            last_mass = mass;
            self.mark(p, half_w + self.map.k as f64, id);
            pts.push(p);
        }
        End::Stopped
    }

    /// The first centre 2..=[`LOOK_AHEAD`] + 1 steps on from `c` along `t` whose window holds at
    /// least half of `ema`, every window before it at least [`FAINT_SHARE`] of it, inside the
    /// area and not on another piece.
    fn ahead(
        &self,
        c: [f64; 2],
        t: [f64; 2],
        geom: Geom,
        id: u32,
        ema: f64,
    ) -> Option<([f64; 2], section::Section)> {
        let step = self.p.step_px;
        for j in 2..=LOOK_AHEAD + 1 {
            let pred = [c[0] + j as f64 * step * t[0], c[1] + j as f64 * step * t[1]];
            if !self.free_at(pred, id) {
                return None;
            }
            let f = self.centre_at(pred, t, 0.5 * step, geom.half_w)?;
            let m = f.1.mass;
            if m >= 0.5 * ema {
                return Some(f);
            }
            if m < FAINT_SHARE * ema {
                return None;
            }
        }
        None
    }

    /// Whether piece `id` may walk onto `p`: inside the area and not on another piece.
    fn free_at(&self, p: [f64; 2], id: u32) -> bool {
        let owner = self.visited_at(p);
        (self.roi)(p) && (owner == 0 || owner == id)
    }

    /// The piece owning the block at `p`; 0 where none does (a seed too faint to begin a piece
    /// owns nothing).
    fn visited_at(&self, p: [f64; 2]) -> u32 {
        let k = self.map.k as f64;
        if p[0] < 0.0 || p[1] < 0.0 {
            return 0;
        }
        let (bx, by) = ((p[0] / k) as usize, (p[1] / k) as usize);
        if bx >= self.map.w || by >= self.map.h {
            return 0;
        }
        match self.visited[by * self.map.w + bx] {
            TRIED => 0,
            owner => owner,
        }
    }

    /// Marks the blocks within `radius_px` of `p` as belonging to piece `id`.
    fn mark(&mut self, p: [f64; 2], radius_px: f64, id: u32) {
        let k = self.map.k as f64;
        let bx0 = ((p[0] - radius_px) / k).floor().max(0.0) as usize;
        let by0 = ((p[1] - radius_px) / k).floor().max(0.0) as usize;
        let bx1 =
            (((p[0] + radius_px) / k).floor().max(0.0) as usize).min(self.map.w.saturating_sub(1));
        let by1 =
            (((p[1] + radius_px) / k).floor().max(0.0) as usize).min(self.map.h.saturating_sub(1));
        for by in by0..=by1 {
            for bx in bx0..=bx1 {
                let c = self.map.block_centre_px(bx, by);
                if dist(c, p) <= radius_px + 0.71 * k {
                    let v = &mut self.visited[by * self.map.w + bx];
                    if *v == 0 || *v == TRIED {
                        *v = id;
                    }
                }
            }
        }
    }
}

/// Shortens the polyline `pts` by `trim` (pixels) at its end (never below one point).
fn trim_end(pts: &mut Vec<[f64; 2]>, trim: f64) {
    let mut left = trim;
    while left > 0.0 && pts.len() >= 2 {
        let (a, b) = (pts[pts.len() - 2], pts[pts.len() - 1]);
        let d = dist(a, b);
        if d <= left {
            pts.pop();
            left -= d;
        } else {
            let f = (d - left) / d;
            let last = pts.len() - 1;
            pts[last] = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            left = 0.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trim_end_shortens_by_length() {
        let mut p = vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        trim_end(&mut p, 1.5);
        assert_eq!(p, vec![[0.0, 0.0], [0.5, 0.0]]);
        let mut q = vec![[0.0, 0.0], [1.0, 0.0]];
        trim_end(&mut q, -0.3);
        assert_eq!(q.len(), 2);
    }
}
