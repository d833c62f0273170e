//! Hard shadows on a traced sheet (issue 49, parts 3 and 5): a phone's or a hand's shadow
//! across the sheet, a sharp-edged region of lowered brightness, and a scanner's page-edge
//! shadow inside the trace area. The shadows here are put on the finished image by this file's
//! own generator, which shares nothing with the project's renderer (`synth::shade`): it works
//! on the 8-bit values as written (not on reflectance before a tone curve), in image pixels
//! (not sheet mm), with a logistic edge profile (not a smoothstep), and on the project's own
//! simulated session scan (`rigctl simulate --session circle`). The tracer must either trace
//! through the shadow (exit 0 within 0.05 mm RMS of the clean trace, covering it) or refuse
//! naming the shadow: never exit 0 with the path linked into a shadow's edge, never the page
//! edge's shadow as "another drawn line".

use super::common::spawn::{rigctl, text};
use image::RgbImage;
use std::path::{Path, PathBuf};

/// A shadow by this file's generator: pixels on the positive side of the line through `at_px`
/// with normal `normal` (image pixels) are multiplied by `factor`, with a logistic edge of
/// scale `edge_px` (10-90 % over about 4.4 `edge_px`).
struct Shade {
    at_px: [f64; 2],
    normal: [f64; 2],
    factor: f64,
    edge_px: f64,
}

impl Shade {
    fn gain(&self, x: f64, y: f64) -> f64 {
        let n = self.normal[0].hypot(self.normal[1]);
        let d = ((x - self.at_px[0]) * self.normal[0] + (y - self.at_px[1]) * self.normal[1]) / n;
        let inside = 1.0 / (1.0 + (-d / self.edge_px).exp());
        1.0 - (1.0 - self.factor) * inside
    }

    fn apply(&self, img: &mut RgbImage) {
        for (x, y, p) in img.enumerate_pixels_mut() {
            let g = self.gain(x as f64 + 0.5, y as f64 + 0.5);
            for c in p.0.iter_mut() {
                *c = (f64::from(*c) * g).round().clamp(0.0, 255.0) as u8;
            }
        }
    }
}

/// A scanner's lid beyond the page's edge at column `edge_x` (everything right of it: nothing
/// printed there), at `lid` of the paper's level, with the page edge's shadow on the lid: a dip
/// to `dip` of the paper's level, `band_px` wide (a half-cosine profile).
fn lid_beyond(img: &mut RgbImage, edge_x: u32, lid: f64, dip: f64, band_px: f64) {
    // The paper's level: the brightest tenth of the column left of the edge.
    let mut col: Vec<u8> = (0..img.height())
        .map(|y| img.get_pixel(edge_x.saturating_sub(20), y)[1])
        .collect();
    col.sort_unstable();
    let paper = f64::from(col[col.len() * 9 / 10]);
    for (x, _, p) in img.enumerate_pixels_mut() {
        if x < edge_x {
            continue;
        }
        let d = f64::from(x - edge_x);
        let level = if d < band_px {
            let s = (std::f64::consts::PI * d / band_px).sin();
            lid - (lid - dip) * s
        } else {
            lid
        };
        let v = (paper * level).round().clamp(0.0, 255.0) as u8;
        p.0 = [v, v, v];
    }
}

fn read_trace(path: &Path) -> Option<Vec<[f64; 2]>> {
    let csv = std::fs::read_to_string(path).ok()?;
    csv.lines()
        .skip(1)
        .map(|l| {
            let (x, y) = l.split_once(',')?;
            Some([x.parse().ok()?, y.parse().ok()?])
        })
        .collect()
}

/// Distance from `p` to the polyline `q`.
fn to_polyline(p: [f64; 2], q: &[[f64; 2]]) -> f64 {
    q.windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let l2 = d[0] * d[0] + d[1] * d[1];
            let t = if l2 > 0.0 {
                (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p[0] - a[0] - t * d[0]).hypot(p[1] - a[1] - t * d[1])
        })
        .fold(f64::INFINITY, f64::min)
}

/// RMS distance of `a` from `b`, and the share of `b`'s points within 0.1 mm of `a`.
fn compare(a: &[[f64; 2]], b: &[[f64; 2]]) -> (f64, f64) {
    let rms = (a.iter().map(|p| to_polyline(*p, b).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
    let covered = b.iter().filter(|p| to_polyline(**p, a) <= 0.1).count() as f64 / b.len() as f64;
    (rms, covered)
}

/// The circle session's scan (`rigctl simulate --session circle --seed 7`), written to `dir`.
fn session_scan(dir: &Path) -> PathBuf {
    let o = rigctl()
        .args(["simulate", "--session", "circle", "--seed", "7", "--out"])
        .arg(dir)
        .output()
        .expect("run");
    assert!(o.status.success(), "simulate: {}", text(&o.stderr));
    dir.join("scan.png")
}

struct Traced {
    code: Option<i32>,
    stderr: String,
    pts: Option<Vec<[f64; 2]>>,
}

fn trace(scan: &Path, out: &Path) -> Traced {
    let o = rigctl()
        .arg("trace")
        .arg(scan)
        .arg("--out")
        .arg(out)
        .output()
        .expect("run");
    Traced {
        code: o.status.code(),
        stderr: text(&o.stderr),
        pts: read_trace(out),
    }
}

/// Exit 0 within 0.05 mm RMS of the clean trace covering 95 % of it, or exit 1/2 naming the
/// shadow (and nothing written); never exit 0 off the clean trace, never "another drawn line"
/// for the shadow.
fn judge(name: &str, t: &Traced, clean: &[[f64; 2]]) {
    match t.code {
        Some(0) => {
            let pts = t.pts.as_ref().expect("a trace written on exit 0");
            let (rms, covered) = compare(pts, clean);
            eprintln!(
                "{name}: exit 0, {rms:.4} mm RMS from the clean trace, covering {covered:.4}"
            );
            assert!(
                rms <= 0.05 && covered >= 0.95,
                "{name}: exit 0 off the clean trace"
            );
        }
        Some(1 | 2) => {
            eprintln!("{name}: exit {:?}: {}", t.code, t.stderr.trim());
            assert!(
                t.stderr.contains("shadow"),
                "{name}: refused without naming the shadow: {}",
                t.stderr
            );
            assert!(
                !t.stderr.contains("another drawn line"),
                "{name}: {}",
                t.stderr
            );
        }
        c => panic!("{name}: exit {c:?}: {}", t.stderr),
    }
}

#[test]
fn a_hard_shadow_across_a_third_of_the_session_scan() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scan = session_scan(dir.path());
    let clean = trace(&scan, &dir.path().join("clean.csv"));
    assert_eq!(clean.code, Some(0), "clean scan: {}", clean.stderr);
    let clean = clean.pts.expect("clean trace");
    let img = image::open(&scan).expect("png").to_rgb8();
    let (w, h) = (f64::from(img.width()), f64::from(img.height()));
    // A third of the sheet in shadow at x0.55 with an edge of a few pixels: a slanted edge across
    // the drawing, the shadow to its right (a phone held over the sheet), one across the bottom
    // third (a hand from below), and edges nearly along the circle (100 mm about the sheet's
    // centre), where an edge is most easily taken for the stroke: a vertical edge through the
    // circle's right end and 1 and 3 mm inside it, a horizontal one at its top.
    let px_per_mm = 600.0 / 25.4;
    let (cx, cy) = (0.5 * w, 0.5 * h);
    let r = 100.0 * px_per_mm;
    let mut shades: Vec<(String, Shade)> = vec![
        (
            "phone shadow, right third".into(),
            Shade {
                at_px: [0.64 * w, 0.5 * h],
                normal: [1.0, -0.12],
                factor: 0.55,
                edge_px: 1.0,
            },
        ),
        (
            "hand shadow, bottom third".into(),
            Shade {
                at_px: [0.5 * w, 0.62 * h],
                normal: [0.18, 1.0],
                factor: 0.55,
                edge_px: 2.0,
            },
        ),
    ];
    for inside_mm in [0.0, 1.0, 3.0] {
        shades.push((
            format!("edge along the circle's right end, {inside_mm} mm inside"),
            Shade {
                at_px: [cx + r - inside_mm * px_per_mm, cy],
                normal: [1.0, 0.0],
                factor: 0.55,
                edge_px: 1.5,
            },
        ));
        shades.push((
            format!("edge along the circle's top, {inside_mm} mm inside"),
            Shade {
                at_px: [cx, cy - r + inside_mm * px_per_mm],
                normal: [0.0, -1.0],
                factor: 0.55,
                edge_px: 1.0,
            },
        ));
    }
    for (k, (name, shade)) in shades.iter().enumerate() {
        let mut shaded = img.clone();
        shade.apply(&mut shaded);
        let path = dir.path().join(format!("shade{k}.png"));
        shaded.save(&path).expect("png");
        let t = trace(&path, &dir.path().join(format!("shade{k}.csv")));
        judge(name, &t, &clean);
    }
}

#[test]
fn a_page_edge_shadow_in_the_trace_area_is_not_a_drawn_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scan = session_scan(dir.path());
    let clean = trace(&scan, &dir.path().join("clean.csv"));
    assert_eq!(clean.code, Some(0), "clean scan: {}", clean.stderr);
    let clean = clean.pts.expect("clean trace");
    let img = image::open(&scan).expect("png").to_rgb8();
    // The page's edge 3 mm right of the drawing's right end (the rightmost dark grey pixel: the
    // circle reaches further right than anything printed), inside the trace area (105 mm from
    // the centre): the print shifted sideways on the page. 600 dpi.
    let px_per_mm = 600.0 / 25.4;
    let rightmost = img
        .enumerate_pixels()
        .filter(|(_, _, p)| {
            let [r, g, b] = p.0;
            g < 150 && r.abs_diff(g) < 25 && b.abs_diff(g) < 25
        })
        .map(|(x, _, _)| x)
        .max()
        .expect("a drawing");
    let edge_x = rightmost + (3.0 * px_per_mm) as u32;
    let from_centre_mm = (f64::from(edge_x) - 0.5 * f64::from(img.width())) / px_per_mm;
    eprintln!("page edge {from_centre_mm:.1} mm right of the scan's centre");
    assert!(from_centre_mm < 105.0, "{from_centre_mm} mm");
    for (k, (lid, dip, band_mm)) in [
        (0.97, 0.45, 1.5),
        (0.85, 0.3, 3.0),
        (1.0, 0.5, 0.6),
        (0.9, 0.4, 1.0),
    ]
    .iter()
    .enumerate()
    {
        let mut edged = img.clone();
        lid_beyond(&mut edged, edge_x, *lid, *dip, band_mm * px_per_mm);
        let path = dir.path().join(format!("edge{k}.png"));
        edged.save(&path).expect("png");
        let t = trace(&path, &dir.path().join(format!("edge{k}.csv")));
        judge(&format!("page edge {k}"), &t, &clean);
    }
}

/// The project's renderer's shadows (`synth::HardShadow`, `synth::PageEdge`), on the reflectance
/// before the tone curve, in sheet mm: a circle of 100.2 mm radius at 300 and 600 dpi, in its
/// truth.
#[test]
fn the_project_renderer_shadows_are_traced_through() {
    use rigctl::sheet::ReferencePath;
    use rigctl::trace::synth::{render_scan, HardShadow, PageEdge, RenderSpec};
    let n = 6_284;
    let truth: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [100.2 * a.cos(), 100.2 * a.sin()]
        })
        .collect();
    let dir = tempfile::tempdir().expect("tempdir");
    let shadow = |through_mm: [f64; 2], dir_deg: f64, edge_mm: f64| HardShadow {
        through_mm,
        dir_deg,
        factor: 0.55,
        edge_mm,
    };
    let cases: Vec<(&str, Vec<HardShadow>, Option<PageEdge>)> = vec![
        (
            "a third, slanted",
            vec![shadow([35.0, 0.0], 80.0, 0.1)],
            None,
        ),
        (
            "along the circle's end",
            vec![shadow([99.5, 0.0], 90.0, 0.2)],
            None,
        ),
        (
            "a hand from below",
            vec![shadow([0.0, -40.0], 175.0, 0.3)],
            None,
        ),
        (
            "page edge 3 mm past the drawing",
            Vec::new(),
            Some(PageEdge {
                x_mm: 103.2,
                lid_level: 0.9,
                shadow_mm: 1.0,
                shadow_level: 0.4,
            }),
        ),
    ];
    for dpi in [300.0, 600.0] {
        for (k, (name, hard_shadows, page_edge)) in cases.iter().enumerate() {
            let spec = RenderSpec {
                dpi,
                pencil_mm: truth.clone(),
                pencil_closed: true,
                reference: Some(ReferencePath::Circle),
                rotation_deg: 0.7,
                seed: 40 + k as u64,
                hard_shadows: hard_shadows.clone(),
                page_edge: *page_edge,
                ..RenderSpec::default()
            };
            let path = dir.path().join(format!("r{k}.png"));
            render_scan(&spec).save(&path).expect("png");
            let t = trace(&path, &dir.path().join(format!("r{k}_{dpi}.csv")));
            judge(&format!("project renderer {dpi} dpi, {name}"), &t, &truth);
        }
    }
}
