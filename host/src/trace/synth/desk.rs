//! Parts of a simulated scan beyond the printed sheet: the desk or lid around the page with the
//! page edge's shadow, and the arc length along the pencil used for skips and faint graphite.

use super::draw::{mul, Placement};
use crate::sheet::{PAGE_HEIGHT_MM, PAGE_WIDTH_MM};
use image::{Rgb, RgbImage};

/// Arc length at the start of every segment of a polyline, mm.
pub(super) fn cumulative_arc(pts: &[[f64; 2]]) -> Vec<f64> {
    let mut out = Vec::with_capacity(pts.len());
    let mut s = 0.0;
    for i in 0..pts.len() {
        out.push(s);
        let j = (i + 1) % pts.len();
        s += (pts[j][0] - pts[i][0]).hypot(pts[j][1] - pts[i][1]);
    }
    out
}

/// Replaces everything outside the page by a desk at `level` with a soft 1 mm shadow along the
/// page's edge; the page's centre at `page_centre_mm` (sheet mm: the print off-centre on the
/// page). `lid_shadow` `[width_mm, depth]`: the shadow the page's edge casts on the lid beyond
/// it, a band `width_mm` wide taking `depth` of the lid's light.
pub(super) fn desk(
    img: &mut RgbImage,
    place: &Placement,
    level: f64,
    page_centre_mm: [f64; 2],
    lid_shadow: Option<[f64; 2]>,
) {
    let (w, h) = (img.width(), img.height());
    let px_mm = 1.0 / place.ppmm();
    for y in 0..h {
        for x in 0..w {
            let s = place.sheet([x as f64 + 0.5, y as f64 + 0.5]);
            let s = [s[0] - page_centre_mm[0], s[1] - page_centre_mm[1]];
            let out_x = (s[0].abs() - PAGE_WIDTH_MM / 2.0).max(0.0);
            let out_y = (s[1].abs() - PAGE_HEIGHT_MM / 2.0).max(0.0);
            let inside_edge = (PAGE_WIDTH_MM / 2.0 - s[0].abs())
                .min(PAGE_HEIGHT_MM / 2.0 - s[1].abs())
                .max(0.0);
            if out_x > 0.0 || out_y > 0.0 {
                let d = out_x.hypot(out_y);
                let shade = lid_shadow.map_or(0.0, |[width, depth]| {
                    depth * (0.5 - (d - width) / px_mm).clamp(0.0, 1.0)
                });
                let v = (255.0 * level * (1.0 - shade)).round().clamp(0.0, 255.0) as u8;
                img.put_pixel(x, y, Rgb([v, v, v]));
            } else if inside_edge < 1.5 {
                let f = 0.55 + 0.45 * inside_edge / 1.5;
                let Rgb(mut p) = *img.get_pixel(x, y);
                for c in p.iter_mut() {
                    *c = mul(*c, f);
                }
                img.put_pixel(x, y, Rgb(p));
            }
        }
    }
}
