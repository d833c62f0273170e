//! The scene of one image of the second renderer: the pencil marks, dust and fibres, light and
//! noise, and the printed sheet v2 layout (black discs and ring dots, the red reference path) as
//! coverage at a point in sheet mm.

use super::view::{Sag, View};

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
    /// A hand's hard shadow across a photographed sheet (`None`: none).
    pub hand: Option<Hand>,
    /// The page: its edges in sheet mm and what lies beyond them.
    pub page: Page,
}

/// The page in sheet mm and what a scanner sees beyond it: the lid at `lid` (reflectance) and
/// the shadow the page's edge throws on it, falling off as `exp(-d / shadow_mm)` from
/// `shadow_depth` at the edge.
#[derive(Debug, Clone, Copy)]
pub struct Page {
    /// The page's x extent and y extent, mm.
    pub x_mm: [f64; 2],
    pub y_mm: [f64; 2],
    pub lid: [f64; 3],
    pub shadow_mm: f64,
    pub shadow_depth: f64,
}

impl Default for Page {
    /// A4 about the print, a dark desk beyond, no shadow.
    fn default() -> Self {
        Self {
            x_mm: [-105.0, 105.0],
            y_mm: [-140.0, 140.0],
            lid: [0.28, 0.26, 0.24],
            shadow_mm: 0.0,
            shadow_depth: 0.0,
        }
    }
}

impl Page {
    /// Distance outside the page, mm (0 on it).
    pub fn outside_mm(&self, p: [f64; 2]) -> f64 {
        let dx = (self.x_mm[0] - p[0]).max(p[0] - self.x_mm[1]).max(0.0);
        let dy = (self.y_mm[0] - p[1]).max(p[1] - self.y_mm[1]).max(0.0);
        dx.hypot(dy)
    }
}

/// A hand over the sheet, lit by a small lamp: its shadow is a palm (an ellipse) and fingers
/// (capsules) fanning from it, with curved edges, `depth` of the light taken inside and a
/// linear penumbra `blur_mm` wide.
#[derive(Debug, Clone)]
pub struct Hand {
    /// Palm centre, sheet mm, and its half axes (mm) and direction (rad).
    pub palm: [f64; 2],
    pub palm_half: [f64; 2],
    pub dir: f64,
    /// Fingers: segments `[x0, y0, x1, y1]` and their radius, mm.
    pub fingers: Vec<([f64; 4], f64)>,
    pub depth: f64,
    pub blur_mm: f64,
}

impl Hand {
    /// A hand whose palm lies `reach_mm` from the sheet's centre in direction `at` (rad), the
    /// fingers pointing to the centre, spread by `spread` (rad between fingers).
    pub fn reaching(at: f64, reach_mm: f64, spread: f64, depth: f64, blur_mm: f64) -> Self {
        let palm = [reach_mm * at.cos(), reach_mm * at.sin()];
        let inward = at + std::f64::consts::PI;
        let fingers = (0..4)
            .map(|i| {
                let a = inward + (i as f64 - 1.5) * spread;
                let base = [palm[0] + 32.0 * a.cos(), palm[1] + 32.0 * a.sin()];
                let len = [55.0, 65.0, 62.0, 50.0][i];
                let tip = [base[0] + len * a.cos(), base[1] + len * a.sin()];
                ([base[0], base[1], tip[0], tip[1]], 8.5)
            })
            .collect();
        Self {
            palm,
            palm_half: [45.0, 38.0],
            dir: inward,
            fingers,
            depth,
            blur_mm,
        }
    }

    /// Signed distance (mm, negative inside) to the hand's outline, approximate for the palm.
    fn signed_mm(&self, p: [f64; 2]) -> f64 {
        let (s, c) = self.dir.sin_cos();
        let d = [p[0] - self.palm[0], p[1] - self.palm[1]];
        let l = [c * d[0] + s * d[1], -s * d[0] + c * d[1]];
        let k = (l[0] / self.palm_half[0]).hypot(l[1] / self.palm_half[1]);
        let mut sd = (k - 1.0) * self.palm_half[0].min(self.palm_half[1]);
        for (f, r) in &self.fingers {
            let (ax, ay, bx, by) = (f[0], f[1], f[2], f[3]);
            let (vx, vy) = (bx - ax, by - ay);
            let t = (((p[0] - ax) * vx + (p[1] - ay) * vy) / (vx * vx + vy * vy)).clamp(0.0, 1.0);
            let dd = (p[0] - ax - t * vx).hypot(p[1] - ay - t * vy) - r;
            sd = sd.min(dd);
        }
        sd
    }

    /// Light factor at sheet point `p`.
    pub fn light_at(&self, p: [f64; 2]) -> f64 {
        let sd = self.signed_mm(p);
        let inside = if self.blur_mm <= 1e-9 {
            if sd < 0.0 {
                1.0
            } else {
                0.0
            }
        } else {
            (0.5 - sd / self.blur_mm).clamp(0.0, 1.0)
        };
        1.0 - self.depth * inside
    }
}

pub(super) const RING: [f64; 11] = [
    -75.0, -60.0, -45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0, 60.0, 75.0,
];

/// Black print: coverage (0..1) of the discs at `p`, with a soft edge `aa` mm wide.
pub(super) fn black_at(p: [f64; 2], aa: f64) -> f64 {
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

pub(super) fn red_at(printed: Printed, p: [f64; 2], aa: f64) -> f64 {
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
