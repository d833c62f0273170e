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
