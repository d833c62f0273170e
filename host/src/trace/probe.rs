//! Ink past a drawn line's end that nothing written covers (`rigctl trace --paths`): where the
//! tracker left a stretch of a line untraced (passes broken into dashes, a zigzag too fine for
//! the resolution), the written points end early and the line would look whole. So the image
//! itself is read ahead of every open line end: pixels darker than the paper by
//! `probe_ink_darkness` in every channel (grey, as graphite and pen ink are), within
//! `probe_half_mm` across the end's direction and `max(2 x --max-gap-mm, 15 mm)` ahead,
//! farther than `probe_traced_mm` from every written point and outside the band of a line
//! running across (the line it ends on); `probe_run_mm` of them along the way, with no hole
//! longer than `probe_hole_mm` between them (a line drawn in loops crosses the probe again and
//! again), the first within `--max-gap-mm` of the end, mean the line may go on: it is not
//! whole. The numbers are [`LinesParams`]' `probe_*`.

use super::mapping::SheetToPx;
use super::paper::PaperMap;
use super::paths::Drawing;
use super::plane::{unit, Grid};
use super::stages::link::{LeftOut, LeftOutKind};
use super::stages::LinesParams;
use image::RgbImage;

/// Grid cell for the written points and the lines' centrelines, mm: how they are bucketed
/// for neighbour queries (what a query finds does not depend on it, only the order and the
/// speed), not a tuned number.
const CELL_MM: f64 = 1.0;

/// Marks every open line of `drawing` with untraced ink past one of its ends as not whole
/// (the ink listed as a mark that may continue it). `to_px` maps sheet mm to image pixels.
pub(super) fn mark_untraced_ink(
    drawing: &mut Drawing,
    img: &RgbImage,
    paper: &PaperMap,
    to_px: &SheetToPx,
    max_gap_mm: f64,
    lp: &LinesParams,
) {
    let step_mm = lp.probe_step_mm;
    let mut written = Grid::new(CELL_MM);
    for p in &drawing.paths {
        for q in &p.stroke.points_mm {
            written.insert(*q, ());
        }
    }
    for s in &drawing.stray_points {
        for q in s {
            written.insert(*q, ());
        }
    }
    // The lines' centrelines with their directions, to tell a line across.
    let mut centres: Vec<Grid<[f64; 2]>> = Vec::new();
    for l in &drawing.lines {
        let mut pts = Grid::new(CELL_MM);
        let c = &l.points_mm;
        for i in 0..c.len() {
            let (a, b) = (c[i.saturating_sub(8)], c[(i + 8).min(c.len() - 1)]);
            if let Some(d) = unit([b[0] - a[0], b[1] - a[1]]) {
                pts.insert(c[i], d);
            }
        }
        centres.push(pts);
    }
    let (w, h) = (img.width() as f64, img.height() as f64);
    let dark = |q: [f64; 2]| -> bool {
        let p = to_px.px(q);
        if !(p[0] >= 0.0 && p[1] >= 0.0 && p[0] < w && p[1] < h) {
            return false;
        }
        // Grey: dark in every channel (a red or yellow object is not ink).
        let px = img.get_pixel(p[0] as u32, p[1] as u32);
        let level = paper.at(p[0], p[1]);
        let lightest = (0..3)
            .map(|c| f32::from(px[c]) / level[c].max(1.0))
            .fold(0.0f32, f32::max);
        1.0 - lightest >= lp.probe_ink_darkness
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
                        && c.within(q, lp.probe_across_band_mm)
                            .any(|(_, d)| (d[0] * t[0] + d[1] * t[1]).abs() < cos_across)
                })
            };
            // The steps ahead with untraced ink somewhere across.
            let steps = (reach / step_mm) as usize;
            let half = (lp.probe_half_mm / step_mm) as i64;
            let hits: Vec<(f64, [f64; 2])> = (2..=steps)
                .filter_map(|k| {
                    let s = k as f64 * step_mm;
                    (-half..=half)
                        .map(|j| j as f64 * step_mm)
                        .map(|c| [e[0] + s * t[0] + c * n[0], e[1] + s * t[1] + c * n[1]])
                        .find(|q| {
                            dark(*q)
                                && written.within(*q, lp.probe_traced_mm).next().is_none()
                                && !across_line(*q)
                        })
                        .map(|q| (s, q))
                })
                .collect();
            // Runs of hits with holes up to `probe_hole_mm` (a line drawn in loops or a zigzag crosses
            // the probe again and again) holding `probe_run_mm` of hits, the first within max_gap_mm.
            let mut hit = None;
            let mut i = 0;
            while i < hits.len() && hits[i].0 <= max_gap_mm + step_mm {
                let (mut j, mut inked) = (i, step_mm);
                while j + 1 < hits.len() && hits[j + 1].0 - hits[j].0 <= lp.probe_hole_mm + step_mm
                {
                    j += 1;
                    inked += step_mm;
                }
                if inked > lp.probe_run_mm {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::paper::BlockMap;
    use crate::trace::paths::open_path;
    use crate::trace::stages::lines::DrawnLine;
    use image::Rgb;

    /// A line written from (-20, 0) to (0, 0) mm and inked there, with `ahead(x, y)` inked
    /// too, on a 60 x 40 mm image at 5 px/mm; whether the probe says the line goes on.
    fn goes_on(ahead: impl Fn(f64, f64) -> bool) -> bool {
        let to_px = SheetToPx {
            camera: None,
            px_per_mm: 5.0,
            size_px: [300.0, 200.0],
        };
        let img = RgbImage::from_fn(300, 200, |x, y| {
            let (xm, ym) = (
                (f64::from(x) + 0.5 - 150.0) / 5.0,
                (100.0 - f64::from(y) - 0.5) / 5.0,
            );
            let line = (-20.0..=0.0).contains(&xm) && ym.abs() <= 0.3;
            if line || ahead(xm, ym) {
                Rgb([40, 40, 40])
            } else {
                Rgb([235, 232, 228])
            }
        });
        let paper = PaperMap::build(&img, PaperMap::block_size_for(&img));
        let pts: Vec<[f64; 2]> = (0..=80)
            .map(|k| [-20.0 + 0.25 * f64::from(k), 0.0])
            .collect();
        let line = DrawnLine {
            passes: vec![0],
            points_mm: pts.clone(),
            closed: false,
            from_mm: [-20.0, 0.0],
            to_mm: [0.0, 0.0],
            length_mm: 20.0,
            covered_mm: 20.0,
            gaps: Vec::new(),
            continued_by: Vec::new(),
            out_dir: [[-1.0, 0.0], [1.0, 0.0]],
        };
        let mut drawing = Drawing {
            paths: vec![open_path(pts)],
            lines: vec![line],
            strays: Vec::new(),
            stray_points: Vec::new(),
            px_per_mm: 5.0,
            camera: None,
            fiducials: None,
        };
        mark_untraced_ink(
            &mut drawing,
            &img,
            &paper,
            &to_px,
            10.0,
            &LinesParams::default(),
        );
        !drawing.lines[0].continued_by.is_empty()
    }

    /// Bars 0.6 mm wide across the line's way, the first 1 mm past its end, `pitch` mm apart.
    fn bars(pitch: f64, count: usize) -> impl Fn(f64, f64) -> bool {
        move |x, y| {
            let u = x - 1.0;
            u >= 0.0 && u < pitch * count as f64 && u % pitch <= 0.6 && y.abs() <= 2.5
        }
    }

    #[test]
    fn ink_crossing_the_probe_again_and_again_means_the_line_goes_on() {
        // Nothing ahead, or one mark across (the line it ends on): whole.
        assert!(!goes_on(|_, _| false));
        assert!(!goes_on(bars(2.5, 1)));
        // A line drawn on in loops: bars 2.5 mm apart, none 2 mm long along the way.
        assert!(goes_on(bars(2.5, 4)));
        // ... but not marks farther apart than a hole (dust).
        assert!(!goes_on(bars(5.0, 3)));
        // Ink running on straight: goes on.
        assert!(goes_on(|x, y| (1.0..4.0).contains(&x) && y.abs() <= 0.3));
    }
}
