//! Ink past a drawn line's end that nothing written covers (`rigctl trace --paths`): where the
//! tracker left a stretch of a line untraced (passes broken into dashes, a zigzag too fine for
//! the resolution), the written points end early and the line would look whole. So the image
//! itself is read ahead of every open line end: pixels darker than the paper by
//! [`INK_DARKNESS`] in every channel (grey, as graphite and pen ink are), within [`PROBE_HALF_MM`] across the end's direction and `max(2 x
//! --max-gap-mm, 15 mm)` ahead, farther than [`TRACED_MM`] from every written point and outside
//! the band of a line running across (the line it ends on); a run of them [`RUN_MM`] long that
//! starts within `--max-gap-mm` of the end means the line may go on: it is not whole.

use super::link::{LeftOut, LeftOutKind};
use super::paper::PaperMap;
use super::paths::Drawing;
use image::RgbImage;
use std::collections::HashMap;

/// Darkness (1 - the lightest of the channels relative to the paper's) of a pixel that is ink.
const INK_DARKNESS: f32 = 0.15;
/// Reach across the end's direction, mm.
const PROBE_HALF_MM: f64 = 2.0;
/// A written point within this covers the ink, mm.
const TRACED_MM: f64 = 1.2;
/// Untraced ink this long along the end's direction may continue the line, mm.
const RUN_MM: f64 = 2.0;
/// The band of a line across reaches this far from its centreline, mm.
const ACROSS_BAND_MM: f64 = 4.0;
const STEP_MM: f64 = 0.25;

/// A point and a direction (zero: none), sheet mm.
type Directed = ([f64; 2], [f64; 2]);

/// Points on a grid of 1 mm cells, each with a direction.
struct Points {
    cells: HashMap<(i64, i64), Vec<Directed>>,
}

impl Points {
    fn new() -> Self {
        Self {
            cells: HashMap::new(),
        }
    }

    fn add(&mut self, p: [f64; 2], dir: [f64; 2]) {
        self.cells
            .entry((p[0].floor() as i64, p[1].floor() as i64))
            .or_default()
            .push((p, dir));
    }

    fn any_within(&self, q: [f64; 2], r: f64, keep: impl Fn([f64; 2]) -> bool) -> bool {
        let k = r.ceil() as i64;
        let (cx, cy) = (q[0].floor() as i64, q[1].floor() as i64);
        (-k..=k).any(|dx| {
            (-k..=k).any(|dy| {
                self.cells.get(&(cx + dx, cy + dy)).is_some_and(|v| {
                    v.iter()
                        .any(|(p, d)| (p[0] - q[0]).hypot(p[1] - q[1]) <= r && keep(*d))
                })
            })
        })
    }
}

/// Marks every open line of `drawing` with untraced ink past one of its ends as not whole
/// (the ink listed as a mark that may continue it). `to_px` maps sheet mm to image pixels.
pub(super) fn mark_untraced_ink(
    drawing: &mut Drawing,
    img: &RgbImage,
    paper: &PaperMap,
    to_px: &dyn Fn([f64; 2]) -> [f64; 2],
    max_gap_mm: f64,
) {
    let mut written = Points::new();
    for p in &drawing.paths {
        for q in &p.stroke.points_mm {
            written.add(*q, [0.0, 0.0]);
        }
    }
    for s in &drawing.stray_points {
        for q in s {
            written.add(*q, [0.0, 0.0]);
        }
    }
    // The lines' centrelines with their directions, to tell a line across.
    let mut centres: Vec<Points> = Vec::new();
    for l in &drawing.lines {
        let mut pts = Points::new();
        let c = &l.points_mm;
        for i in 0..c.len() {
            let (a, b) = (c[i.saturating_sub(8)], c[(i + 8).min(c.len() - 1)]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let n = d[0].hypot(d[1]);
            if n > 1e-9 {
                pts.add(c[i], [d[0] / n, d[1] / n]);
            }
        }
        centres.push(pts);
    }
    let (w, h) = (img.width() as f64, img.height() as f64);
    let dark = |q: [f64; 2]| -> bool {
        let p = to_px(q);
        if !(p[0] >= 0.0 && p[1] >= 0.0 && p[0] < w && p[1] < h) {
            return false;
        }
        // Grey: dark in every channel (a red or yellow object is not ink).
        let px = img.get_pixel(p[0] as u32, p[1] as u32);
        let level = paper.at(p[0], p[1]);
        let lightest = (0..3)
            .map(|c| f32::from(px[c]) / level[c].max(1.0))
            .fold(0.0f32, f32::max);
        1.0 - lightest >= INK_DARKNESS
    };
    let reach = (2.0 * max_gap_mm).max(15.0);
    let cos_across = 45f64.to_radians().cos();
    let mut found: Vec<(usize, LeftOut)> = Vec::new();
    for (li, l) in drawing.lines.iter().enumerate() {
        if l.closed || l.points_mm.len() < 2 {
            continue;
        }
        for (e, t) in [(l.from_mm, l.out_dir[0]), (l.to_mm, l.out_dir[1])] {
            let n = [-t[1], t[0]];
            let across_line = |q: [f64; 2]| {
                centres.iter().enumerate().any(|(k, c)| {
                    k != li
                        && c.any_within(q, ACROSS_BAND_MM, |d| {
                            (d[0] * t[0] + d[1] * t[1]).abs() < cos_across
                        })
                })
            };
            // The steps ahead with untraced ink somewhere across, then their first run of
            // RUN_MM that starts within max_gap_mm.
            let steps = (reach / STEP_MM) as usize;
            let half = (PROBE_HALF_MM / STEP_MM) as i64;
            let hits: Vec<(f64, [f64; 2])> = (2..=steps)
                .filter_map(|k| {
                    let s = k as f64 * STEP_MM;
                    (-half..=half)
                        .map(|j| j as f64 * STEP_MM)
                        .map(|c| [e[0] + s * t[0] + c * n[0], e[1] + s * t[1] + c * n[1]])
                        .find(|q| {
                            dark(*q)
                                && !written.any_within(*q, TRACED_MM, |_| true)
                                && !across_line(*q)
                        })
                        .map(|q| (s, q))
                })
                .collect();
            let mut hit = None;
            let mut i = 0;
            while i < hits.len() && hits[i].0 <= max_gap_mm + STEP_MM {
                let mut j = i;
                while j + 1 < hits.len() && hits[j + 1].0 - hits[j].0 <= 2.0 * STEP_MM {
                    j += 1;
                }
                if hits[j].0 - hits[i].0 >= RUN_MM {
                    hit = Some((hits[i].0, hits[j].0, hits[i].1, hits[j].1));
                    break;
                }
                i = j + 1;
            }
            if let Some((s0, s1, a, b)) = hit {
                found.push((
                    li,
                    LeftOut {
                        from_mm: a,
                        to_mm: b,
                        length_mm: s1 - s0,
                        kind: LeftOutKind::Continues,
                    },
                ));
            }
        }
    }
    for (li, m) in found {
        drawing.lines[li].continued_by.push(m);
    }
}
