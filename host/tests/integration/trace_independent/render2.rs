//! A second sheet renderer, written apart from `rigctl::trace::synth`, so that the tracer is
//! measured on images it was not developed with.
//!
//! Model: every output pixel is mapped back to sheet mm (a scanner's rotation + shift, or a
//! pinhole camera with radial distortion `k1` in focal-length units, inverted by fixed-point
//! iteration) and the sheet is *evaluated* there: near ink a pixel is the mean of n x n
//! sub-samples. The pencil is a chain of stamped tip discs (every 0.03 mm, each disc its own
//! radius and pressure, a dome profile) laid on a paper tooth that takes graphite only on its
//! crests; the light is a smooth shading field (and, in photos, a vignette and a soft shadow
//! edge); noise is a hashed triangular distribution; photos are blurred by a 3-tap binomial
//! kernel and JPEG-compressed. Layout: sheet v2 (FORMATS.md): four 6 mm discs at (+-90, +-90),
//! the 3 mm dot at (-90, 75), 43 ring dots of 1.5 mm every 15 mm, the red reference path.

use image::RgbImage;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A pencil mark: a dense centreline (<= 0.03 mm steps).
#[derive(Debug, Clone)]
pub struct Mark {
    pub pts: Vec<[f64; 2]>,
    /// Tip width, mm, and mean darkness (fraction absorbed).
    pub width_mm: f64,
    pub darkness: f64,
    /// Arc-length intervals left unwritten (pencil skips), mm.
    pub skips: Vec<[f64; 2]>,
}

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

/// The printed reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Printed {
    Circle,
    Line,
}

/// The whole scene of one image.
#[derive(Debug, Clone)]
pub struct Scene {
    pub printed: Printed,
    pub marks: Vec<Mark>,
    /// Dust `[x, y, radius, darkness]`.
    pub dust: Vec<[f64; 4]>,
    /// Fibres `[x0, y0, x1, y1]`, 0.06 mm wide, grey.
    pub fibres: Vec<[f64; 4]>,
    pub view: View,
    /// Shading: paper level at the centre and its linear change per 100 mm (x, y), vignette.
    pub light: [f64; 4],
    /// Noise amplitude, 8-bit levels; blur and JPEG quality for photos.
    pub noise: f64,
    pub jpeg: Option<u8>,
    pub seed: u64,
    /// The device's tone curve, reflectance (0..1) to the value written (0..1), applied to the
    /// exposed, blurred and noisy values before they are rounded; `None`: linear.
    pub tone: Option<fn(f64) -> f64>,
    /// A photographed sheet that sags or curls (`None`: flat).
    pub sag: Option<Sag>,
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
fn on_paper(scene: &Scene, q: [f64; 2]) -> Option<[f64; 2]> {
    let p0 = scene.view.to_mm(q)?;
    match (&scene.sag, &scene.view) {
        (Some(sag), View::Photo { c, .. }) => Some(sag.paper_point(*c, p0)),
        _ => Some(p0),
    }
}

fn hash(a: u64) -> u64 {
    let mut z = a.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn unit(a: u64) -> f64 {
    (hash(a) >> 11) as f64 / (1u64 << 53) as f64
}

/// Value noise on a lattice of `cell` mm, bilinear, in [0, 1].
fn value_noise(p: [f64; 2], cell: f64, seed: u64) -> f64 {
    let (x, y) = (p[0] / cell, p[1] / cell);
    let (xi, yi) = (x.floor(), y.floor());
    let (fx, fy) = (x - xi, y - yi);
    let at = |i: f64, j: f64| {
        unit(seed ^ ((i as i64 as u64).wrapping_mul(0x1000_0000_01B3)) ^ (j as i64 as u64) << 21)
    };
    let (a, b, c, d) = (
        at(xi, yi),
        at(xi + 1.0, yi),
        at(xi, yi + 1.0),
        at(xi + 1.0, yi + 1.0),
    );
    let (sx, sy) = (fx * fx * (3.0 - 2.0 * fx), fy * fy * (3.0 - 2.0 * fy));
    (a * (1.0 - sx) + b * sx) * (1.0 - sy) + (c * (1.0 - sx) + d * sx) * sy
}

struct Stamp {
    c: [f64; 2],
    r: f64,
    a: f64,
}

/// Stamps indexed on a grid of 0.25 mm cells over +-120 mm (compressed rows).
struct StampGrid {
    stamps: Vec<Stamp>,
    start: Vec<u32>,
    list: Vec<u32>,
    max_r: f64,
}

const SG_CELL: f64 = 0.25;
const SG_N: usize = 960;

fn sg_cell(p: [f64; 2]) -> Option<(usize, usize)> {
    let (i, j) = ((p[0] + 120.0) / SG_CELL, (p[1] + 120.0) / SG_CELL);
    (i >= 0.0 && j >= 0.0 && (i as usize) < SG_N && (j as usize) < SG_N)
        .then_some((i as usize, j as usize))
}

impl StampGrid {
    fn new(stamps: Vec<Stamp>) -> Self {
        let mut count = vec![0u32; SG_N * SG_N + 1];
        let mut max_r: f64 = 0.0;
        let cells: Vec<Option<usize>> = stamps
            .iter()
            .map(|s| {
                max_r = max_r.max(s.r);
                sg_cell(s.c).map(|(i, j)| j * SG_N + i)
            })
            .collect();
        for c in cells.iter().flatten() {
            count[c + 1] += 1;
        }
        for k in 1..count.len() {
            count[k] += count[k - 1];
        }
        let mut fill = count.clone();
        let mut list = vec![0u32; stamps.len()];
        for (k, c) in cells.iter().enumerate() {
            if let Some(c) = c {
                list[fill[*c] as usize] = k as u32;
                fill[*c] += 1;
            }
        }
        Self {
            stamps,
            start: count,
            list,
            max_r,
        }
    }

    /// Darkness of the graphite at `p` (max over the discs, dome profile).
    fn at(&self, p: [f64; 2]) -> f64 {
        let Some((ci, cj)) = sg_cell(p) else {
            return 0.0;
        };
        let n = (self.max_r / SG_CELL).ceil() as usize;
        let mut best: f64 = 0.0;
        for j in cj.saturating_sub(n)..=(cj + n).min(SG_N - 1) {
            for i in ci.saturating_sub(n)..=(ci + n).min(SG_N - 1) {
                let c = j * SG_N + i;
                for &k in &self.list[self.start[c] as usize..self.start[c + 1] as usize] {
                    let s = &self.stamps[k as usize];
                    let d2 = (p[0] - s.c[0]).powi(2) + (p[1] - s.c[1]).powi(2);
                    if d2 < s.r * s.r {
                        best = best.max(s.a * (1.0 - d2 / (s.r * s.r)).sqrt());
                    }
                }
            }
        }
        best
    }
}

fn arc_lengths(pts: &[[f64; 2]]) -> Vec<f64> {
    let mut s = vec![0.0];
    for w in pts.windows(2) {
        let l = s[s.len() - 1] + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        s.push(l);
    }
    s
}

fn stamps_of(mark: &Mark, seed: u64) -> Vec<Stamp> {
    let s = arc_lengths(&mark.pts);
    let mut out = Vec::new();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Slow pressure: three random sines over the arc length.
    let waves: Vec<(f64, f64, f64)> = (0..3)
        .map(|_| {
            (
                rng.gen_range(0.04..0.12),
                rng.gen_range(5.0..60.0),
                rng.gen_range(0.0..std::f64::consts::TAU),
            )
        })
        .collect();
    let mut next = 0.0;
    for (i, p) in mark.pts.iter().enumerate() {
        if s[i] < next {
            continue;
        }
        next = s[i] + 0.03;
        if mark.skips.iter().any(|k| s[i] >= k[0] && s[i] <= k[1]) {
            continue;
        }
        let pressure: f64 = 1.0
            + waves
                .iter()
                .map(|(a, l, ph)| a * (s[i] / l * std::f64::consts::TAU + ph).sin())
                .sum::<f64>();
        out.push(Stamp {
            c: *p,
            r: 0.5 * mark.width_mm * (1.0 + 0.06 * (rng.gen::<f64>() - 0.5)),
            a: (mark.darkness * pressure * (0.9 + 0.2 * rng.gen::<f64>())).min(0.95),
        });
    }
    out
}

const RING: [f64; 11] = [
    -75.0, -60.0, -45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0, 60.0, 75.0,
];

/// Black print: coverage (0..1) of the discs at `p`, with a soft edge `aa` mm wide.
fn black_at(p: [f64; 2], aa: f64) -> f64 {
    let disc =
        |c: [f64; 2], r: f64| (0.5 - ((p[0] - c[0]).hypot(p[1] - c[1]) - r) / aa).clamp(0.0, 1.0);
    let mut v: f64 = 0.0;
    for c in [[-90.0, -90.0], [90.0, -90.0], [-90.0, 90.0], [90.0, 90.0]] {
        v = v.max(disc(c, 3.0));
    }
    v = v.max(disc([-90.0, 75.0], 1.5));
    for t in RING {
        for c in [[t, 90.0], [t, -90.0], [90.0, t], [-90.0, t]] {
            if c == [-90.0, 75.0] {
                continue;
            }
            v = v.max(disc(c, 0.75));
        }
    }
    v
}

fn red_at(printed: Printed, p: [f64; 2], aa: f64) -> f64 {
    let half = 0.14;
    let d = match printed {
        Printed::Circle => (p[0].hypot(p[1]) - 100.0).abs(),
        Printed::Line => {
            let beyond = (p[0].abs() - 100.0).max(0.0);
            beyond.hypot(p[1])
        }
    };
    (0.5 - (d - half) / aa).clamp(0.0, 1.0)
}

fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
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
    let ppm = dpi / 25.4;
    let rot = rot_deg.to_radians();
    let half = 96.0 * (rot.cos().abs() + rot.sin().abs());
    let n = (2.0 * half * ppm).ceil() as u32;
    View::Scan {
        px_per_mm: ppm,
        rot,
        size: [n, n],
    }
}

/// Renders the scene.
pub fn render(scene: &Scene) -> RgbImage {
    let grids: Vec<StampGrid> = scene
        .marks
        .iter()
        .enumerate()
        .map(|(i, m)| {
            StampGrid::new(stamps_of(
                m,
                scene.seed.wrapping_mul(31).wrapping_add(i as u64),
            ))
        })
        .collect();
    // Where ink may be: cells of 1 mm within reach of a stamp, dust, fibre, red or black print.
    let cell = 1.0;
    let n_cells = 240usize; // -120 .. 120 mm
    let idx = |p: [f64; 2]| -> Option<usize> {
        let (i, j) = ((p[0] + 120.0) / cell, (p[1] + 120.0) / cell);
        (i >= 0.0 && j >= 0.0 && (i as usize) < n_cells && (j as usize) < n_cells)
            .then(|| j as usize * n_cells + i as usize)
    };
    // Bits per cell: graphite, black print, red print, dust or fibre.
    const GRAPHITE: u8 = 1;
    const BLACK: u8 = 2;
    const RED: u8 = 4;
    const SPECK: u8 = 8;
    let mut near = vec![0u8; n_cells * n_cells];
    let mut specks: std::collections::HashMap<usize, Vec<usize>> = Default::default();
    let mut flag = |p: [f64; 2], reach: f64, bit: u8, speck: Option<usize>| {
        let r = (reach / cell).ceil() as i64 + 1;
        for dj in -r..=r {
            for di in -r..=r {
                if let Some(k) = idx([p[0] + di as f64 * cell, p[1] + dj as f64 * cell]) {
                    near[k] |= bit;
                    if let Some(d) = speck {
                        let v = specks.entry(k).or_default();
                        if !v.contains(&d) {
                            v.push(d);
                        }
                    }
                }
            }
        }
    };
    for g in &grids {
        for s in g.stamps.iter().step_by(10) {
            flag(s.c, s.r + 0.5, GRAPHITE, None);
        }
    }
    let n_dust = scene.dust.len();
    for (i, d) in scene.dust.iter().enumerate() {
        flag([d[0], d[1]], d[2] + 0.3, SPECK, Some(i));
    }
    for (i, f) in scene.fibres.iter().enumerate() {
        for k in 0..=20 {
            let t = k as f64 / 20.0;
            flag(
                [f[0] + t * (f[2] - f[0]), f[1] + t * (f[3] - f[1])],
                0.5,
                SPECK,
                Some(n_dust + i),
            );
        }
    }
    for i in 0..2000 {
        let t = i as f64 / 2000.0;
        let p = match scene.printed {
            Printed::Circle => {
                let a = t * std::f64::consts::TAU;
                [100.0 * a.cos(), 100.0 * a.sin()]
            }
            Printed::Line => [-100.0 + 200.0 * t, 0.0],
        };
        flag(p, 0.5, RED, None);
    }
    for c in [[-90.0, -90.0], [90.0, -90.0], [-90.0, 90.0], [90.0, 90.0]] {
        flag(c, 3.6, BLACK, None);
    }
    flag([-90.0, 75.0], 2.0, BLACK, None);
    for t in RING {
        for c in [[t, 90.0], [t, -90.0], [90.0, t], [-90.0, t]] {
            flag(c, 1.2, BLACK, None);
        }
    }

    let [w, h] = scene.view.size();
    let photo = matches!(scene.view, View::Photo { .. });
    let sub = 2;
    let seed = scene.seed;
    let mut buf = vec![0f32; 3 * w as usize * h as usize];
    // Reflectance of the sheet at `p` (mm) for a pixel `aa` mm across.
    let sheet = |p: [f64; 2], aa: f64| -> [f64; 3] {
        let on_page = p[0].abs() <= 105.0 && p[1].abs() <= 140.0;
        if !on_page {
            return [0.28, 0.26, 0.24];
        }
        let mut rgb = [0.93, 0.92, 0.885];
        let Some(cell) = idx(p) else {
            return rgb;
        };
        let bits = near[cell];
        if bits == 0 {
            return rgb;
        }
        let mut g: f64 = 0.0;
        if bits & GRAPHITE != 0 {
            for grid in &grids {
                g = g.max(grid.at(p));
            }
            if g > 0.0 {
                // Paper tooth: graphite on the crests.
                let tooth = 0.65 + 0.35 * value_noise(p, 0.07, seed ^ 0xA5);
                g *= tooth;
            }
        }
        if bits & SPECK != 0 {
            for &i in specks.get(&cell).into_iter().flatten() {
                if let Some(d) = scene.dust.get(i) {
                    let dd = (p[0] - d[0]).hypot(p[1] - d[1]);
                    let cov = (0.5 - (dd - d[2]) / aa).clamp(0.0, 1.0);
                    g = g.max(cov * d[3]);
                } else if let Some(f) = scene.fibres.get(i - n_dust) {
                    let dd = seg_dist(p, [f[0], f[1]], [f[2], f[3]]);
                    g = g.max((0.5 - (dd - 0.03) / aa).clamp(0.0, 1.0) * 0.3);
                }
            }
        }
        let red = if bits & RED != 0 {
            red_at(scene.printed, p, aa)
        } else {
            0.0
        };
        let black = if bits & BLACK != 0 {
            black_at(p, aa)
        } else {
            0.0
        };
        let tint = [1.0 - 0.08 * red, 1.0 - 0.78 * red, 1.0 - 0.74 * red];
        for k in 0..3 {
            rgb[k] *= tint[k] * (1.0 - g) * (1.0 - 0.93 * black);
        }
        rgb
    };
    for y in 0..h {
        for x in 0..w {
            let centre = [x as f64 + 0.5, y as f64 + 0.5];
            let Some(pm) = on_paper(scene, centre) else {
                continue;
            };
            let inked = idx(pm).is_some_and(|k| near[k] != 0);
            let rgb = if inked {
                // Pixel size in mm from the neighbouring pixel.
                let aa = scene
                    .view
                    .to_mm([centre[0] + 1.0, centre[1]])
                    .map_or(0.1, |q| (q[0] - pm[0]).hypot(q[1] - pm[1]))
                    / sub as f64;
                let mut acc = [0.0; 3];
                for j in 0..sub {
                    for i in 0..sub {
                        let q = [
                            x as f64 + (i as f64 + 0.5) / sub as f64,
                            y as f64 + (j as f64 + 0.5) / sub as f64,
                        ];
                        if let Some(pq) = on_paper(scene, q) {
                            let v = sheet(pq, aa);
                            for k in 0..3 {
                                acc[k] += v[k];
                            }
                        }
                    }
                }
                acc.map(|a| a / (sub * sub) as f64)
            } else {
                sheet(pm, 0.1)
            };
            // Light: linear field in sheet mm, a vignette in the image, a soft shadow edge.
            let [l0, gx, gy, vig] = scene.light;
            let mut light = l0 * (1.0 + gx * pm[0] / 100.0 + gy * pm[1] / 100.0);
            if photo {
                let (cx, cy) = (0.5 * w as f64, 0.5 * h as f64);
                let r2 = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)) / (cx * cx + cy * cy);
                light *= 1.0 - vig * r2;
                let edge = (pm[0] * 0.6 + pm[1] * 0.8 - 40.0) / 25.0;
                light *= 1.0 - 0.22 / (1.0 + (-edge).exp());
            }
            let o = 3 * (y as usize * w as usize + x as usize);
            for k in 0..3 {
                let tri = unit(seed ^ (o as u64 + k as u64).wrapping_mul(0x9E37))
                    + unit(
                        (seed.wrapping_add(77)) ^ (o as u64 + k as u64).wrapping_mul(0x5851_F42D),
                    )
                    - 1.0;
                buf[o + k] = (255.0 * light * rgb[k] + scene.noise * tri) as f32;
            }
        }
    }
    if photo {
        blur(&mut buf, w as usize, h as usize);
    }
    if let Some(curve) = scene.tone {
        for v in buf.iter_mut() {
            *v = (255.0 * curve((f64::from(*v) / 255.0).clamp(0.0, 1.0))) as f32;
        }
    }
    let img = RgbImage::from_fn(w, h, |x, y| {
        let o = 3 * (y as usize * w as usize + x as usize);
        image::Rgb([0, 1, 2].map(|k| buf[o + k].round().clamp(0.0, 255.0) as u8))
    });
    match scene.jpeg {
        Some(q) => jpeg_roundtrip(&img, q).unwrap_or(img),
        None => img,
    }
}

fn blur(buf: &mut [f32], w: usize, h: usize) {
    let mut tmp = buf.to_vec();
    for y in 0..h {
        for x in 1..w.saturating_sub(1) {
            for k in 0..3 {
                let o = 3 * (y * w + x) + k;
                tmp[o] = 0.25 * buf[o - 3] + 0.5 * buf[o] + 0.25 * buf[o + 3];
            }
        }
    }
    for y in 1..h.saturating_sub(1) {
        for x in 0..w {
            for k in 0..3 {
                let o = 3 * (y * w + x) + k;
                buf[o] = 0.25 * tmp[o - 3 * w] + 0.5 * tmp[o] + 0.25 * tmp[o + 3 * w];
            }
        }
    }
}

fn jpeg_roundtrip(img: &RgbImage, quality: u8) -> Option<RgbImage> {
    let mut bytes = Vec::new();
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, quality);
    img.write_with_encoder(enc).ok()?;
    image::load_from_memory(&bytes).ok().map(|d| d.to_rgb8())
}
