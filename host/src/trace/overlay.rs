//! The overlay image: the input (reduced to at most 2400 px on its long side) with the fitted
//! printed marks (blue rings where the camera model puts them, magenta crosses where they were
//! measured), the written trace (green) and the missing stretches of the drawn path (red), so
//! that a person can check a trace at a glance. Without fiducials (a plain scale) there are no
//! marks; the trace is drawn through the same scale. For every drawn line of a drawing
//! ([`render_drawing_overlay`]): the passes of whole lines green, of lines not whole orange,
//! the missing stretches red.

use super::mapping::SheetToPx;
use super::{CameraModel, Drawing, Fiducials, Trace, TraceError};
use crate::io::atomic::{write_atomic, AtomicWriteError};
use crate::sheet::{
    fiducial_centres_mm, orientation_dot_mm, ring_dots_mm, FIDUCIAL_DIAMETER_MM,
    ORIENTATION_DOT_DIAMETER_MM, RING_DOT_DIAMETER_MM,
};
use image::{Rgb, RgbImage};
use std::path::Path;

const GREEN: Rgb<u8> = Rgb([0, 170, 0]);
const ORANGE: Rgb<u8> = Rgb([255, 140, 0]);
const BLUE: Rgb<u8> = Rgb([20, 60, 255]);
const MAGENTA: Rgb<u8> = Rgb([220, 0, 220]);
const RED: Rgb<u8> = Rgb([255, 0, 0]);

/// Sheet mm to overlay pixels: to image pixels, then reduced by `step`.
struct ToPx {
    image: SheetToPx,
    scale: f64,
}

impl ToPx {
    fn px(&self, p: [f64; 2]) -> [f64; 2] {
        let q = self.image.px(p);
        [q[0] * self.scale, q[1] * self.scale]
    }

    fn polyline(&self, pts: &[[f64; 2]], closed: bool) -> Vec<[f64; 2]> {
        let mut out: Vec<[f64; 2]> = pts.iter().map(|p| self.px(*p)).collect();
        if closed {
            if let Some(&first) = out.first() {
                out.push(first);
            }
        }
        out
    }
}

/// The reduced image and its mapping; the printed marks drawn (fiducial mapping only).
/// How the sheet of a [`Trace`] or a [`Drawing`] maps onto its image: what an overlay's base
/// is drawn from.
struct Frame<'a> {
    camera: Option<&'a CameraModel>,
    fiducials: Option<&'a Fiducials>,
    px_per_mm: f64,
}

/// [`Frame`] of each result that carries the three fields.
macro_rules! frame_of {
    ($($result:ty),*) => {$(
        impl<'a> From<&'a $result> for Frame<'a> {
            fn from(x: &'a $result) -> Self {
                Frame {
                    camera: x.camera.as_ref(),
                    fiducials: x.fiducials.as_ref(),
                    px_per_mm: x.px_per_mm,
                }
            }
        }
    )*};
}
frame_of!(Trace, Drawing);

fn base(img: &RgbImage, frame: Frame<'_>, spacing_mm: f64) -> (RgbImage, ToPx) {
    let Frame {
        camera,
        fiducials,
        px_per_mm,
    } = frame;
    let long = img.width().max(img.height()) as usize;
    let step = long.div_ceil(2400).max(1);
    let mut out = downsample(img, step);
    let to = ToPx {
        image: SheetToPx {
            camera: camera.copied(),
            px_per_mm,
            size_px: [img.width() as f64, img.height() as f64],
        },
        scale: 1.0 / step as f64,
    };
    if camera.is_some() {
        let mut marks: Vec<([f64; 2], f64)> = fiducial_centres_mm(spacing_mm)
            .iter()
            .map(|c| (*c, FIDUCIAL_DIAMETER_MM))
            .collect();
        marks.push((orientation_dot_mm(spacing_mm), ORIENTATION_DOT_DIAMETER_MM));
        marks.extend(
            ring_dots_mm(spacing_mm)
                .into_iter()
                .map(|c| (c, RING_DOT_DIAMETER_MM)),
        );
        for (c, d) in marks {
            let r_mm = 0.5 * d + 1.0;
            let ring: Vec<[f64; 2]> = (0..=48)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / 48.0;
                    to.px([c[0] + r_mm * a.cos(), c[1] + r_mm * a.sin()])
                })
                .collect();
            polyline(&mut out, &ring, BLUE, 1);
        }
    }
    if let Some(f) = fiducials {
        let measured = f
            .corners
            .iter()
            .chain(std::iter::once(&f.dot))
            .chain(f.ring.iter().map(|(d, _)| d));
        for d in measured {
            let c = [d.centre_px[0] * to.scale, d.centre_px[1] * to.scale];
            polyline(
                &mut out,
                &[[c[0] - 4.0, c[1]], [c[0] + 4.0, c[1]]],
                MAGENTA,
                0,
            );
            polyline(
                &mut out,
                &[[c[0], c[1] - 4.0], [c[0], c[1] + 4.0]],
                MAGENTA,
                0,
            );
        }
    }
    (out, to)
}

/// Draws the overlay of `trace` on `img` (the traced image). `spacing_mm` is the fiducial
/// spacing used.
pub fn render_overlay(img: &RgbImage, trace: &Trace, spacing_mm: f64) -> RgbImage {
    let (mut out, to) = base(img, trace.into(), spacing_mm);
    for s in &trace.strokes {
        polyline(&mut out, &to.polyline(&s.points_mm, s.closed), GREEN, 1);
    }
    for g in trace.linking.missing() {
        polyline(&mut out, &[to.px(g.from_mm), to.px(g.to_mm)], RED, 3);
    }
    // A red cross, 3 mm across, on each end of the path that meets a grey print.
    for p in &trace.ends_at_print_mm {
        for d in [[1.5, 1.5], [1.5, -1.5]] {
            let (a, b) = ([p[0] - d[0], p[1] - d[1]], [p[0] + d[0], p[1] + d[1]]);
            polyline(&mut out, &[to.px(a), to.px(b)], RED, 3);
        }
    }
    out
}

/// Draws the overlay of every drawn line of `drawing` on `img`: each path green when every line
/// it runs along is whole, orange otherwise; each missing stretch red.
pub fn render_drawing_overlay(img: &RgbImage, drawing: &Drawing, spacing_mm: f64) -> RgbImage {
    let (mut out, to) = base(img, drawing.into(), spacing_mm);
    let mut whole = vec![true; drawing.paths.len()];
    for l in &drawing.lines {
        for &p in &l.passes {
            whole[p] &= l.is_whole();
        }
    }
    for (p, ok) in drawing.paths.iter().zip(&whole) {
        let colour = if *ok { GREEN } else { ORANGE };
        polyline(
            &mut out,
            &to.polyline(&p.stroke.points_mm, p.stroke.closed),
            colour,
            1,
        );
    }
    for l in &drawing.lines {
        for g in l.gaps.iter().filter(|g| !g.bridged) {
            polyline(&mut out, &[to.px(g.from_mm), to.px(g.to_mm)], RED, 3);
        }
    }
    out
}

/// Writes the overlay as PNG, atomically.
pub fn write_overlay(path: &Path, overlay: &RgbImage) -> Result<(), TraceError> {
    let mut buf = Vec::new();
    let enc = image::codecs::png::PngEncoder::new(&mut buf);
    overlay
        .write_with_encoder(enc)
        .map_err(|e| TraceError::Write {
            path: path.to_path_buf(),
            source: std::io::Error::other(e.to_string()),
        })?;
    write_atomic(path, |w| {
        w.write_all(&buf).map_err(|source| {
            TraceError::Atomic(AtomicWriteError::Io {
                path: path.to_path_buf(),
                source,
            })
        })
    })
}

/// Box-filter reduction by an integer factor.
fn downsample(img: &RgbImage, step: usize) -> RgbImage {
    if step <= 1 {
        return img.clone();
    }
    let (w, h) = (img.width() as usize / step, img.height() as usize / step);
    let mut out = RgbImage::new(w.max(1) as u32, h.max(1) as u32);
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0u32; 3];
            for yy in y * step..(y + 1) * step {
                for xx in x * step..(x + 1) * step {
                    let p = img.get_pixel(xx as u32, yy as u32);
                    for c in 0..3 {
                        acc[c] += p[c] as u32;
                    }
                }
            }
            let n = (step * step) as u32;
            out.put_pixel(x as u32, y as u32, Rgb(acc.map(|v| (v / n) as u8)));
        }
    }
    out
}

/// Draws a polyline with square pens of half width `half` pixels.
fn polyline(img: &mut RgbImage, pts: &[[f64; 2]], colour: Rgb<u8>, half: i64) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    for seg in pts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let n = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as usize).clamp(1, 100_000);
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let x = (a[0] + t * (b[0] - a[0])).round() as i64;
            let y = (a[1] + t * (b[1] - a[1])).round() as i64;
            for yy in y - half..=y + half {
                for xx in x - half..=x + half {
                    if xx >= 0 && yy >= 0 && xx < w && yy < h {
                        img.put_pixel(xx as u32, yy as u32, colour);
                    }
                }
            }
        }
    }
}
