//! How the second renderer's pixels see the sheet: a flatbed scan (rotation and shift) or a
//! pinhole camera with radial distortion, the sheet flat or sagging, and the views the tests use
//! (a scan at a dpi, a tilted camera, a photo cropped off its centre).

use super::scene::Scene;

/// How pixels see the sheet.
#[derive(Debug, Clone)]
pub enum View {
    /// Flatbed: `px_per_mm`, rotation (rad) and the image size, the sheet origin at the centre.
    Scan {
        px_per_mm: f64,
        rot: f64,
        size: [u32; 2],
    },
    /// Pinhole camera: position `c` (mm, sheet z = 0 plane, z up), rows of the world -> camera
    /// rotation, focal length and principal point (px), radial `k1` in units of the focal
    /// length.
    Photo {
        c: [f64; 3],
        r: [[f64; 3]; 3],
        f: f64,
        pp: [f64; 2],
        k1: f64,
        size: [u32; 2],
    },
}

/// A sheet not lying flat, as a height over the desk that varies across one direction only (so
/// the paper unrolls exactly): `Roll` lifts both edges along a cosine, `Curl` one edge along a
/// cubic from the middle third on.
#[derive(Debug, Clone, Copy)]
pub struct Sag {
    pub height_mm: f64,
    /// Direction across which the height varies, rad from the sheet's +x.
    pub across_rad: f64,
    /// Half extent across, mm: the height is `height_mm` there.
    pub half_mm: f64,
    pub curl: bool,
}

impl Sag {
    fn z(&self, u: f64) -> f64 {
        let w = self.half_mm;
        if self.curl {
            let u0 = w / 3.0;
            self.height_mm * ((u - u0).max(0.0) / (w - u0)).powi(3)
        } else {
            self.height_mm * (1.0 - (std::f64::consts::FRAC_PI_2 * u / w).cos())
        }
    }

    /// The paper point (unrolled) under the camera's ray through the desk point `p0`, the
    /// camera at `c`: the ray walked to where its height meets the surface's, then the distance
    /// across replaced by the arc length (trapezoids of 0.25 mm) from the middle.
    fn paper_point(&self, c: [f64; 3], p0: [f64; 2]) -> [f64; 2] {
        let (sn, cs) = self.across_rad.sin_cos();
        let mut h = 0.0;
        let mut p = p0;
        for _ in 0..10 {
            let t = 1.0 - h / c[2];
            p = [c[0] + t * (p0[0] - c[0]), c[1] + t * (p0[1] - c[1])];
            h = self.z(p[0] * cs + p[1] * sn);
        }
        let u = p[0] * cs + p[1] * sn;
        let v = -p[0] * sn + p[1] * cs;
        let n = ((u.abs() / 0.25).ceil() as usize).max(1);
        let du = u / n as f64;
        let mut arc = 0.0;
        for i in 0..n {
            let (a, b) = (i as f64 * du, (i + 1) as f64 * du);
            arc += (b - a).hypot(self.z(b) - self.z(a)) * du.signum();
        }
        [arc * cs - v * sn, arc * sn + v * cs]
    }
}

/// Pixel -> paper mm on `scene`'s sheet, flat or sagging.
pub(super) fn on_paper(scene: &Scene, q: [f64; 2]) -> Option<[f64; 2]> {
    let p0 = scene.view.to_mm(q)?;
    match (&scene.sag, &scene.view) {
        (Some(sag), View::Photo { c, .. }) => Some(sag.paper_point(*c, p0)),
        _ => Some(p0),
    }
}

impl View {
    pub fn size(&self) -> [u32; 2] {
        match self {
            View::Scan { size, .. } | View::Photo { size, .. } => *size,
        }
    }

    /// Pixel (x right, y down; centres at +0.5) -> sheet mm; `None` off the sheet plane.
    pub fn to_mm(&self, q: [f64; 2]) -> Option<[f64; 2]> {
        match self {
            View::Scan {
                px_per_mm,
                rot,
                size,
            } => {
                let (dx, dy) = (
                    (q[0] - 0.5 * size[0] as f64) / px_per_mm,
                    -(q[1] - 0.5 * size[1] as f64) / px_per_mm,
                );
                let (s, c) = rot.sin_cos();
                Some([c * dx + s * dy, -s * dx + c * dy])
            }
            View::Photo {
                c, r, f, pp, k1, ..
            } => {
                let d = [q[0] - pp[0], q[1] - pp[1]];
                let mut u = d;
                for _ in 0..6 {
                    let rr = (u[0] * u[0] + u[1] * u[1]) / (f * f);
                    let g = 1.0 + k1 * rr;
                    u = [d[0] / g, d[1] / g];
                }
                let v = [u[0] / f, u[1] / f, 1.0];
                // Camera -> world: transpose.
                let w = [
                    r[0][0] * v[0] + r[1][0] * v[1] + r[2][0] * v[2],
                    r[0][1] * v[0] + r[1][1] * v[1] + r[2][1] * v[2],
                    r[0][2] * v[0] + r[1][2] * v[1] + r[2][2] * v[2],
                ];
                if w[2] >= -1e-9 {
                    return None;
                }
                let t = -c[2] / w[2];
                Some([c[0] + t * w[0], c[1] + t * w[1]])
            }
        }
    }

    /// Sheet mm -> pixel (for sizing and checks).
    pub fn to_px(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        match self {
            View::Scan {
                px_per_mm,
                rot,
                size,
            } => {
                let (s, c) = rot.sin_cos();
                let (dx, dy) = (c * p[0] - s * p[1], s * p[0] + c * p[1]);
                Some([
                    0.5 * size[0] as f64 + dx * px_per_mm,
                    0.5 * size[1] as f64 - dy * px_per_mm,
                ])
            }
            View::Photo {
                c, r, f, pp, k1, ..
            } => {
                let d = [p[0] - c[0], p[1] - c[1], -c[2]];
                let x: Vec<f64> = r
                    .iter()
                    .map(|row| row[0] * d[0] + row[1] * d[1] + row[2] * d[2])
                    .collect();
                if x[2] <= 1e-6 {
                    return None;
                }
                let u = [f * x[0] / x[2], f * x[1] / x[2]];
                let g = 1.0 + k1 * (u[0] * u[0] + u[1] * u[1]) / (f * f);
                Some([pp[0] + g * u[0], pp[1] + g * u[1]])
            }
        }
    }
}

/// `view` as cropped off its centre: the principal point `off_px` from the image centre (the
/// image grown so the sheet still fits). A photo trimmed from one side, or a camera whose lens
/// axis is not at the sensor's centre.
pub fn off_centre(view: View, off_px: [f64; 2]) -> View {
    match view {
        View::Photo {
            c,
            r,
            f,
            pp,
            k1,
            size,
        } => {
            let grow = [
                (2.0 * off_px[0].abs()).ceil(),
                (2.0 * off_px[1].abs()).ceil(),
            ];
            let size = [size[0] + grow[0] as u32, size[1] + grow[1] as u32];
            View::Photo {
                c,
                r,
                f,
                pp: [
                    pp[0] + 0.5 * grow[0] + off_px[0],
                    pp[1] + 0.5 * grow[1] + off_px[1],
                ],
                k1,
                size,
            }
        }
        scan => scan,
    }
}

/// A camera at `tilt` (rad) from the sheet normal towards `azimuth`, `dist` mm from `target`,
/// rolled by `roll`; image sized to hold the fiducial square with a margin.
pub fn photo_view(
    px_per_mm: f64,
    tilt: f64,
    azimuth: f64,
    roll: f64,
    k1: f64,
    target: [f64; 2],
) -> View {
    let dist = 420.0;
    let c = [
        target[0] + dist * tilt.sin() * azimuth.cos(),
        target[1] + dist * tilt.sin() * azimuth.sin(),
        dist * tilt.cos(),
    ];
    let z = {
        let v = [target[0] - c[0], target[1] - c[1], -c[2]];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let x0 = [roll.cos(), -roll.sin(), 0.0];
    let dot = x0[0] * z[0] + x0[1] * z[1] + x0[2] * z[2];
    let x = {
        let v = [x0[0] - dot * z[0], x0[1] - dot * z[1], x0[2] - dot * z[2]];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let y = [
        z[1] * x[2] - z[2] * x[1],
        z[2] * x[0] - z[0] * x[2],
        z[0] * x[1] - z[1] * x[0],
    ];
    let f = px_per_mm * dist;
    let mut view = View::Photo {
        c,
        r: [x, y, z],
        f,
        pp: [0.0, 0.0],
        k1,
        size: [0, 0],
    };
    // Size: the projected square of +-100 mm, symmetric about the principal point.
    let mut ext: [f64; 2] = [0.0, 0.0];
    for i in 0..=40 {
        let t = -100.0 + 5.0 * i as f64;
        for p in [[t, -100.0], [t, 100.0], [-100.0, t], [100.0, t]] {
            if let Some(q) = view.to_px(p) {
                ext[0] = ext[0].max(q[0].abs());
                ext[1] = ext[1].max(q[1].abs());
            }
        }
    }
    let size = [
        (2.0 * ext[0] + 60.0).ceil() as u32,
        (2.0 * ext[1] + 60.0).ceil() as u32,
    ];
    if let View::Photo { pp, size: s, .. } = &mut view {
        *pp = [0.5 * size[0] as f64, 0.5 * size[1] as f64];
        *s = size;
    }
    view
}

/// A flatbed scan of the fiducial square with a 3 mm margin, rotated by `rot_deg`.
pub fn scan_view(dpi: f64, rot_deg: f64) -> View {
    scan_view_wide(dpi, rot_deg, 96.0)
}

/// [`scan_view`] reaching `half_mm` from the sheet's centre (96 mm: the fiducial square and a
/// 3 mm margin).
pub fn scan_view_wide(dpi: f64, rot_deg: f64, half_mm: f64) -> View {
    let ppm = dpi / 25.4;
    let rot = rot_deg.to_radians();
    let half = half_mm * (rot.cos().abs() + rot.sin().abs());
    let n = (2.0 * half * ppm).ceil() as u32;
    View::Scan {
        px_per_mm: ppm,
        rot,
        size: [n, n],
    }
}
