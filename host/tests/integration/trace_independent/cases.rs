//! Drawn paths for the independent tests: what a robot's pencil leaves on a sheet laid by hand
//! (offset 2-40 mm and turned 0-30 deg from the printed reference, other radii, free curves,
//! 3-8 skips of 1-6 mm), the clutter around it, and the measures of a trace against the truth.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{PI, TAU};

use super::render2::Printed;

/// The drawn path and what lies around it, in sheet mm.
#[derive(Debug, Clone)]
pub struct Case {
    pub shape: &'static str,
    pub printed: Printed,
    /// Dense centreline (0.025 mm steps) of the drawn path, skips included.
    pub truth: Vec<[f64; 2]>,
    pub closed: bool,
    pub skips: Vec<[f64; 2]>,
    pub width_mm: f64,
    pub darkness: f64,
    /// A second, shorter pencil stroke across the path (dense centreline).
    pub crossing: Option<Vec<[f64; 2]>>,
    /// Short pencil flicks away from the path.
    pub strays: Vec<Vec<[f64; 2]>>,
    pub dust: Vec<[f64; 4]>,
    pub fibres: Vec<[f64; 4]>,
    /// A second drawn run on the same sheet (dense centreline, closed), drawn as the path is,
    /// without skips.
    pub second_run: Option<(Vec<[f64; 2]>, bool)>,
}

pub fn densify(f: impl Fn(f64) -> [f64; 2], closed: bool) -> Vec<[f64; 2]> {
    // Sample finely, then keep points 0.025 mm apart.
    let n = 200_000;
    let m = if closed { n } else { n + 1 };
    let raw: Vec<[f64; 2]> = (0..m).map(|i| f(i as f64 / n as f64)).collect();
    let mut out = vec![raw[0]];
    let mut acc = 0.0;
    for w in raw.windows(2) {
        acc += (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        if acc >= 0.025 {
            out.push(w[1]);
            acc = 0.0;
        }
    }
    if !closed && out.last() != raw.last() {
        if let Some(&l) = raw.last() {
            out.push(l);
        }
    }
    out
}

pub fn length(pts: &[[f64; 2]]) -> f64 {
    pts.windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// Inside the trace area, clear of the corner discs and the orientation dot.
pub fn placeable(pts: &[[f64; 2]]) -> bool {
    let keep_out = [
        ([-90.0, -90.0], 9.0),
        ([90.0, -90.0], 9.0),
        ([-90.0, 90.0], 9.0),
        ([90.0, 90.0], 9.0),
        ([-90.0, 75.0], 6.0),
    ];
    pts.iter().all(|p| {
        p[0].abs() <= 97.0
            && p[1].abs() <= 97.0
            && keep_out
                .iter()
                .all(|(c, r)| (p[0] - c[0]).hypot(p[1] - c[1]) > *r)
    })
}

fn path(rng: &mut ChaCha8Rng, shape: usize) -> (&'static str, Printed, Vec<[f64; 2]>, bool) {
    loop {
        let off = rng.gen_range(2.0..40.0);
        let dir = rng.gen_range(0.0..TAU);
        let o = [off * dir.cos(), off * dir.sin()];
        let ph: f64 = rng.gen_range(0.0..TAU);
        let (name, printed, pts, closed) = match shape {
            0 => {
                let r = rng.gen_range(35.0..(96.0 - off).max(36.0));
                let wob = rng.gen_range(0.0..0.5);
                let f = move |t: f64| {
                    let a = t * TAU;
                    let rr = r + wob * (3.0 * a + ph).sin();
                    [o[0] + rr * a.cos(), o[1] + rr * a.sin()]
                };
                ("circle", Printed::Circle, densify(f, true), true)
            }
            1 => {
                let turn = rng.gen_range(0.0f64..30.0).to_radians()
                    * if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
                let half = rng.gen_range(40.0..90.0);
                let bow = rng.gen_range(-0.6..0.6);
                let (s, c) = turn.sin_cos();
                let f = move |t: f64| {
                    let u = (2.0 * t - 1.0) * half;
                    let v = bow * (1.0 - (2.0 * t - 1.0).powi(2));
                    [o[0] + c * u - s * v, o[1] + s * u + c * v]
                };
                ("line", Printed::Line, densify(f, false), false)
            }
            2 => {
                // A wiggly open curve: a ramp with two to four waves, turned anywhere.
                let half = rng.gen_range(40.0..85.0);
                let turn = rng.gen_range(0.0..TAU);
                let waves: Vec<(f64, f64, f64)> = (0..rng.gen_range(2..=4))
                    .map(|k| {
                        let freq = rng.gen_range(0.5..2.0) + k as f64 * 0.3;
                        (
                            rng.gen_range(3.0..12.0) / freq,
                            freq,
                            rng.gen_range(0.0..TAU),
                        )
                    })
                    .collect();
                let (s, c) = turn.sin_cos();
                let f = move |t: f64| {
                    let u = (2.0 * t - 1.0) * half;
                    let v: f64 = waves
                        .iter()
                        .map(|(a, fr, p)| a * (fr * PI * (2.0 * t - 1.0) + p).sin())
                        .sum();
                    [o[0] + c * u - s * v, o[1] + s * u + c * v]
                };
                let printed = if rng.gen_bool(0.5) {
                    Printed::Line
                } else {
                    Printed::Circle
                };
                ("free open", printed, densify(f, false), false)
            }
            _ => {
                // A closed blob, star-shaped about its centre.
                let r = rng.gen_range(30.0..(90.0 - off).max(31.0));
                let (a2, a3) = (rng.gen_range(0.0..0.18), rng.gen_range(0.0..0.08));
                let ph3: f64 = rng.gen_range(0.0..TAU);
                let f = move |t: f64| {
                    let a = t * TAU;
                    let rr = r * (1.0 + a2 * (2.0 * a + ph).sin() + a3 * (3.0 * a + ph3).sin());
                    [o[0] + rr * a.cos(), o[1] + rr * a.sin()]
                };
                ("free closed", Printed::Circle, densify(f, true), true)
            }
        };
        if placeable(&pts) {
            return (name, printed, pts, closed);
        }
    }
}

/// 3-8 skips of 1-6 mm, apart from each other and (open paths) from the ends.
fn skips(rng: &mut ChaCha8Rng, total: f64, closed: bool) -> Vec<[f64; 2]> {
    let n = rng.gen_range(3..=8);
    let margin = if closed { 0.0 } else { 8.0 };
    let mut out: Vec<[f64; 2]> = Vec::new();
    let mut tries = 0;
    while out.len() < n && tries < 1000 {
        tries += 1;
        let len = rng.gen_range(1.0..6.0);
        let s0 = rng.gen_range(margin..(total - margin - len));
        if out.iter().all(|k| s0 + len + 6.0 < k[0] || s0 > k[1] + 6.0) {
            out.push([s0, s0 + len]);
        }
    }
    out.sort_by(|a, b| a[0].total_cmp(&b[0]));
    out
}

fn at_arc(pts: &[[f64; 2]], s: f64) -> ([f64; 2], [f64; 2]) {
    let mut acc = 0.0;
    for w in pts.windows(2) {
        let l = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        if acc + l >= s && l > 0.0 {
            return (w[0], [(w[1][0] - w[0][0]) / l, (w[1][1] - w[0][1]) / l]);
        }
        acc += l;
    }
    (pts[pts.len() - 1], [1.0, 0.0])
}

pub fn segment(a: [f64; 2], b: [f64; 2]) -> Vec<[f64; 2]> {
    let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / 0.025).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        })
        .collect()
}

/// The case of `seed`: the shape cycles with the seed; `faint` for scans of light graphite;
/// `crossing` adds a second pencil stroke across the path.
pub fn case(seed: u64, faint: bool, crossing: bool) -> Case {
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x5EED);
    let (shape, printed, truth, closed) = path(&mut rng, (seed % 4) as usize);
    let total = length(&truth);
    let skips = skips(&mut rng, total, closed);
    let width_mm = rng.gen_range(0.3..0.65);
    let darkness = if faint {
        rng.gen_range(0.22..0.34)
    } else {
        rng.gen_range(0.32..0.55)
    };
    let near_path = |p: [f64; 2], d: f64| {
        truth
            .iter()
            .step_by(20)
            .any(|q| (p[0] - q[0]).hypot(p[1] - q[1]) < d)
    };
    let crossing = crossing.then(|| {
        // Across the path at least 25 mm from an open path's ends, 35-90 deg to it.
        let s = rng.gen_range(25.0..total - 25.0);
        let (p, t) = at_arc(&truth, s);
        let ang =
            rng.gen_range(35.0f64..90.0).to_radians() * if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
        let (sn, cs) = ang.sin_cos();
        let d = [cs * t[0] - sn * t[1], sn * t[0] + cs * t[1]];
        let (l0, l1) = (rng.gen_range(8.0..20.0), rng.gen_range(8.0..20.0));
        segment(
            [p[0] - l0 * d[0], p[1] - l0 * d[1]],
            [p[0] + l1 * d[0], p[1] + l1 * d[1]],
        )
    });
    let mut strays = Vec::new();
    while strays.len() < rng.gen_range(1..=2) {
        let p = [rng.gen_range(-85.0..85.0), rng.gen_range(-85.0..85.0)];
        if near_path(p, 15.0) {
            continue;
        }
        let a: f64 = rng.gen_range(0.0..TAU);
        let l = rng.gen_range(1.5..4.0);
        strays.push(segment(p, [p[0] + l * a.cos(), p[1] + l * a.sin()]));
    }
    let mut dust: Vec<[f64; 4]> = (0..rng.gen_range(20..60))
        .map(|_| {
            [
                rng.gen_range(-95.0..95.0),
                rng.gen_range(-95.0..95.0),
                rng.gen_range(0.04..0.18),
                rng.gen_range(0.5..0.9),
            ]
        })
        .collect();
    for _ in 0..3 {
        let (p, _) = at_arc(&truth, rng.gen_range(0.0..total));
        dust.push([
            p[0] + rng.gen_range(-0.3..0.3),
            p[1] + rng.gen_range(-0.3..0.3),
            rng.gen_range(0.05..0.15),
            rng.gen_range(0.6..0.9),
        ]);
    }
    let fibres: Vec<[f64; 4]> = (0..rng.gen_range(2..5))
        .map(|_| {
            let p = [rng.gen_range(-90.0..90.0), rng.gen_range(-90.0..90.0)];
            let a: f64 = rng.gen_range(0.0..TAU);
            let l = rng.gen_range(2.0..6.0);
            [p[0], p[1], p[0] + l * a.cos(), p[1] + l * a.sin()]
        })
        .collect();
    Case {
        shape,
        printed,
        truth,
        closed,
        skips,
        width_mm,
        darkness,
        crossing,
        strays,
        dust,
        fibres,
        second_run: None,
    }
}

/// Segments of a polyline indexed on a grid of `cell` mm.
pub struct SegIndex<'a> {
    pts: &'a [[f64; 2]],
    cell: f64,
    map: std::collections::HashMap<(i32, i32), Vec<u32>>,
}

impl<'a> SegIndex<'a> {
    pub fn new(pts: &'a [[f64; 2]], closed: bool) -> Self {
        let cell = 1.0;
        let mut map: std::collections::HashMap<(i32, i32), Vec<u32>> = Default::default();
        let n = if closed {
            pts.len()
        } else {
            pts.len().saturating_sub(1)
        };
        for i in 0..n {
            let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
            let (x0, x1) = (a[0].min(b[0]), a[0].max(b[0]));
            let (y0, y1) = (a[1].min(b[1]), a[1].max(b[1]));
            for gx in (x0 / cell).floor() as i32..=(x1 / cell).floor() as i32 {
                for gy in (y0 / cell).floor() as i32..=(y1 / cell).floor() as i32 {
                    map.entry((gx, gy)).or_default().push(i as u32);
                }
            }
        }
        Self { pts, cell, map }
    }

    /// Distance from `p` to the polyline, searched out to `reach` mm (infinity beyond).
    pub fn dist(&self, p: [f64; 2], reach: f64) -> f64 {
        let n = (reach / self.cell).ceil() as i32;
        let (cx, cy) = (
            (p[0] / self.cell).floor() as i32,
            (p[1] / self.cell).floor() as i32,
        );
        let mut best = f64::INFINITY;
        for gx in cx - n..=cx + n {
            for gy in cy - n..=cy + n {
                for &i in self.map.get(&(gx, gy)).into_iter().flatten() {
                    let i = i as usize;
                    let (a, b) = (self.pts[i], self.pts[(i + 1) % self.pts.len()]);
                    best = best.min(seg_dist(p, a, b));
                }
            }
        }
        best
    }
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

/// Coverage (share of the true centreline within 0.1 mm of the trace) and RMS distance of the
/// trace's points to the truth (a trace point farther than 20 mm counts as 20 mm).
pub fn measure(
    truth: &[[f64; 2]],
    closed: bool,
    trace: &[[f64; 2]],
    trace_closed: bool,
) -> (f64, f64) {
    if trace.len() < 2 {
        return (0.0, f64::INFINITY);
    }
    let ti = SegIndex::new(trace, trace_closed);
    let covered = truth.iter().filter(|p| ti.dist(**p, 0.1) <= 0.1).count();
    let tr = SegIndex::new(truth, closed);
    let ss: f64 = trace
        .iter()
        .map(|p| {
            let d = tr.dist(*p, 2.0);
            if d.is_finite() {
                d * d
            } else {
                400.0
            }
        })
        .sum();
    (
        covered as f64 / truth.len() as f64,
        (ss / trace.len() as f64).sqrt(),
    )
}
