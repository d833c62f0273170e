//! Sub-pixel centreline of pencil strokes by tracking: from a seed on the stroke, step along the
//! local tangent and put each centre at the darkness-weighted centroid of the pixels in a short
//! window across the stroke (along the local normal; not a skeleton). Ends are found where the
//! stroke's mass per unit length falls to half, then pulled back by half the stroke width (a
//! round pencil tip leaves a round cap). Work is confined to windows around the stroke. Edges of
//! light (a hard shadow's, a scan's page edge) are cut out of the pieces (`illumination.rs`).

use crate::trace::ink::InkModel;
use crate::trace::paper::PaperMap;
use crate::trace::plane::dist;
use crate::trace::raster::CoarseMap;
use image::RgbImage;
use indicatif::ProgressBar;
use own_track::{Retrace, Verdict};

mod illumination;
mod own_track;
mod params;
mod section;

pub use params::CentrelineParams;

pub(crate) use illumination::{cut_light_steps, is_page_edge};
pub(crate) use section::Occluders;

/// The owner of blocks around a seed too faint to begin a piece: not seeded again, but free
/// to walk.
const TRIED: u32 = u32::MAX;

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
    /// The stage's tuned numbers (faint graphite, own track).
    pub centreline: CentrelineParams,
}

/// Window geometry and reference mass of one piece.
#[derive(Clone, Copy)]
struct Geom {
    half_w: f64,
    width_px: f64,
    mass0: f64,
    /// [`Tracker::clock`] when the piece began.
    clock0: u32,
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
        marked_at: vec![0; seeds.len()],
        marked_dir: vec![[0.0; 2]; seeds.len()],
        clock: 0,
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
        tracker.mark(seed, 2.0 * map.k as f64, owner, [0.0; 2]);
        pieces.push(piece.ok());
    }
    progress.set_position(seeds.len() as u64);
    pieces.into_iter().flatten().collect()
}

pub(in crate::trace) struct Tracker<'a> {
    img: &'a RgbImage,
    ink: &'a InkModel,
    paper: &'a PaperMap,
    occluders: &'a Occluders,
    map: &'a CoarseMap,
    visited: Vec<u32>,
    /// When each block was first marked, on [`Self::clock`].
    marked_at: Vec<u32>,
    /// The heading of the walk when it marked each block (zero where no walk did).
    marked_dir: Vec<[f32; 2]>,
    /// Counts the marks made (one per centre walked).
    clock: u32,
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
            clock0: self.clock,
        };
        let mut fwd = vec![start];
        self.mark(start, half_w + self.map.k as f64, id, t0);
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
            clock0,
        } = geom;
        let step = self.p.step_px;
        let half_len = 0.5 * step;
        let mut t = t;
        let mut ema = mass0;
        let mut last_mass = mass0;
        let start = pts[0];
        let mut retrace = Retrace::new(self.retrace_patience(half_w), &self.p.centreline);
        let max_steps = 4 * (self.img.width() as usize + self.img.height() as usize) * 4;
        for _ in 0..max_steps {
            let Some(&c) = pts.last() else {
                return End::Stopped;
            };
            let pred = [c[0] + step * t[0], c[1] + step * t[1]];
            if !self.free_at(pred, id) {
                return End::Stopped;
            }
            let own = self.own_track_cos(pred, t, id, start, half_w);
            let marks = self.clock.wrapping_sub(clock0) as usize;
            let v = retrace.step(own, pts.len(), marks, self.clock);
            if let Verdict::StopAt { keep, since } = v {
                pts.truncate(keep.max(1));
                if let Some(since) = since {
                    self.unmark_since(id, since);
                }
                return End::Stopped;
            }
            let found = self.centre_at(pred, t, half_len, half_w);
            let mass = found.as_ref().map_or(0.0, |(_, s)| s.mass);
            let (run, single);
            let steps: &[([f64; 2], f64)] = if mass < 0.5 * ema {
                // In faint graphite, gone fainter or broken up by the paper's tooth, not a
                // skip: where the stroke goes on (back within `back_within_steps` steps, or
                // `faint_run_steps` steps holding half its level on average), walk through to there.
                run = (ema < self.p.centreline.faint_mass * self.p.min_mass)
                    .then(|| {
                        let level = ema.clamp(
                            self.p.centreline.faint_floor * self.p.min_mass,
                            self.p.min_mass,
                        );
                        self.faint_run(pts, t, half_w, id, level)
                    })
                    .flatten();
                let Some(run) = &run else {
                    // Half-mass crossing between the last centre and this step, then back by
                    // half the stroke width.
                    let frac =
                        ((last_mass - 0.5 * ema) / (last_mass - mass).max(1e-12)).clamp(0.0, 1.0);
                    return End::Faded {
                        trim_px: 0.5 * width_px - frac * step,
                    };
                };
                run
            } else {
                let Some((p, _)) = found else {
                    return End::Stopped;
                };
                single = [(p, mass)];
                &single
            };
            for &(p, m) in steps {
                if may_close && pts.len() > 12 && dist(p, start) < 1.5 * step {
                    return End::Closed;
                }
                t = heading(pts, p, t);
                ema = 0.9 * ema + 0.1 * m;
                last_mass = m;
                self.mark(p, half_w + self.map.k as f64, id, t);
                pts.push(p);
            }
        }
        End::Stopped
    }

    /// The centres on from the last of `pts` (heading `t`), each with its window's mass, up to
    /// where the stroke goes on: back at half of `level` within `CentrelineParams::back_within_steps` more steps
    /// (after a hole, for two steps running), or `CentrelineParams::faint_run_steps` steps holding half of `level` on
    /// average. At most one window holds under `CentrelineParams::faint_share` of `level` (a grain hole: its
    /// centre is the step's prediction); every step is inside the area and not on another
    /// piece.
    fn faint_run(
        &self,
        pts: &[[f64; 2]],
        t: [f64; 2],
        half_w: f64,
        id: u32,
        level: f64,
    ) -> Option<Vec<([f64; 2], f64)>> {
        let step = self.p.step_px;
        let mut trail = pts[pts.len().saturating_sub(4)..].to_vec();
        let (mut t, mut holes, mut sum) = (t, 0, 0.0);
        let mut run: Vec<([f64; 2], f64)> = Vec::with_capacity(self.p.centreline.faint_run_steps);
        for j in 1..=self.p.centreline.faint_run_steps {
            let c = *trail.last()?;
            let pred = [c[0] + step * t[0], c[1] + step * t[1]];
            if !self.free_at(pred, id) {
                return None;
            }
            let found = self.centre_at(pred, t, 0.5 * step, half_w);
            let m = found.as_ref().map_or(0.0, |(_, s)| s.mass);
            let p = match found {
                Some((p, _)) if m >= self.p.centreline.faint_share * level => p,
                _ => {
                    holes += 1;
                    if holes > 1 {
                        return None;
                    }
                    pred
                }
            };
            sum += m;
            t = heading(&trail, p, t);
            trail.push(p);
            let back = m >= 0.5 * level
                && (2..=self.p.centreline.back_within_steps + 1).contains(&j)
                && (holes == 0 || run.last().is_some_and(|r| r.1 >= 0.5 * level));
            run.push((p, m));
            if back {
                return Some(run);
            }
        }
        (sum >= 0.5 * level * self.p.centreline.faint_run_steps as f64).then_some(run)
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
    fn mark(&mut self, p: [f64; 2], radius_px: f64, id: u32, t: [f64; 2]) {
        self.clock = self.clock.wrapping_add(1);
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
                    let b = by * self.map.w + bx;
                    let v = &mut self.visited[b];
                    if *v == 0 || *v == TRIED {
                        *v = id;
                        self.marked_at[b] = self.clock;
                        self.marked_dir[b] = [t[0] as f32, t[1] as f32];
                    }
                }
            }
        }
    }
}

/// The heading on to `p` from the last points of `pts`: the chord from four steps back (`t`
/// where that is no chord).
fn heading(pts: &[[f64; 2]], p: [f64; 2], t: [f64; 2]) -> [f64; 2] {
    let Some(&back) = pts.get(pts.len().saturating_sub(4)) else {
        return t;
    };
    let d = dist(p, back);
    if d > 1e-9 {
        [(p[0] - back[0]) / d, (p[1] - back[1]) / d]
    } else {
        t
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
