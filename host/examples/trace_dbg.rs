#![allow(dead_code, unused_imports)]
#[path = "../tests/integration/trace_independent/cases.rs"]
mod cases;
#[path = "../tests/integration/trace_independent/render2.rs"]
mod render2;
use cases::{case, measure, Case, SegIndex};
use indicatif::ProgressBar;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use render2::{photo_view, scan_view, Printed, Scene};
use rigctl::sheet::ReferencePath;
use rigctl::trace::{render_photo, render_scan, trace_image, PhotoSpec, RenderSpec, TraceOptions};
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Photo,
    Scan300,
    Scan600,
}

/// One traced image: coverage, RMS (mm), whether the tracer would exit 0, and its message.
struct Outcome {
    coverage: f64,
    rms: f64,
    exit0: bool,
    note: String,
}

fn printed(p: Printed) -> ReferencePath {
    match p {
        Printed::Circle => ReferencePath::Circle,
        Printed::Line => ReferencePath::Line,
    }
}

/// The camera and light of a photo or scan of `seed`, drawn independently of the path.
struct Shot {
    ppm: f64,
    tilt: f64,
    azimuth: f64,
    roll: f64,
    k1: f64,
    rot_deg: f64,
    jpeg: u8,
}

fn shot(kind: Kind, seed: u64) -> Shot {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5407_0000);
    Shot {
        ppm: match kind {
            Kind::Photo => rng.gen_range(200.0..300.0) / 25.4,
            Kind::Scan300 => 300.0 / 25.4,
            Kind::Scan600 => 600.0 / 25.4,
        },
        tilt: rng.gen_range(0.0f64..40.0).to_radians(),
        azimuth: rng.gen_range(0.0..std::f64::consts::TAU),
        roll: rng.gen_range(0.0..std::f64::consts::TAU),
        k1: rng.gen_range(-0.08..0.08),
        rot_deg: rng.gen_range(-4.0..4.0),
        jpeg: rng.gen_range(85..96),
    }
}

fn render_independent(c: &Case, kind: Kind, seed: u64) -> image::RgbImage {
    let s = shot(kind, seed);
    let mut marks = vec![render2::Mark {
        pts: c.truth.clone(),
        width_mm: c.width_mm,
        darkness: c.darkness,
        skips: c.skips.clone(),
    }];
    for extra in c.crossing.iter().chain(&c.strays) {
        marks.push(render2::Mark {
            pts: extra.clone(),
            width_mm: c.width_mm,
            darkness: c.darkness,
            skips: Vec::new(),
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x11_6417);
    let (view, light, noise, jpeg) = match kind {
        Kind::Photo => (
            photo_view(
                s.ppm,
                s.tilt,
                s.azimuth,
                s.roll,
                s.k1,
                [rng.gen_range(-8.0..8.0), rng.gen_range(-8.0..8.0)],
            ),
            [
                rng.gen_range(0.75..0.95),
                rng.gen_range(-0.25..0.25),
                rng.gen_range(-0.25..0.25),
                rng.gen_range(0.0..0.3),
            ],
            rng.gen_range(2.0..5.0),
            Some(s.jpeg),
        ),
        _ => (
            scan_view(s.ppm * 25.4, s.rot_deg),
            [
                rng.gen_range(0.9..1.0),
                rng.gen_range(-0.04..0.04),
                rng.gen_range(-0.04..0.04),
                0.0,
            ],
            rng.gen_range(1.0..3.0),
            None,
        ),
    };
    render2::render(&Scene {
        printed: c.printed,
        marks,
        dust: c.dust.clone(),
        fibres: c.fibres.clone(),
        view,
        light,
        noise,
        jpeg,
        seed,
    })
}

fn render_project(c: &Case, kind: Kind, seed: u64) -> image::RgbImage {
    let s = shot(kind, seed);
    let spec = RenderSpec {
        dpi: if kind == Kind::Photo {
            450.0
        } else {
            s.ppm * 25.4
        },
        pencil_mm: c.truth.clone(),
        pencil_closed: c.closed,
        pencil_width_mm: c.width_mm,
        pencil_darkness: c.darkness,
        reference: Some(printed(c.printed)),
        ring: true,
        rotation_deg: s.rot_deg,
        skips_mm: c.skips.clone(),
        dust_mm: c.dust.iter().map(|d| [d[0], d[1], d[2]]).collect(),
        fibres_mm: c.fibres.clone(),
        seed,
        ..RenderSpec::default()
    };
    match kind {
        Kind::Photo => {
            let dist = 400.0;
            let half = (s.ppm * 100.0 * 1.45) as u32;
            render_photo(
                &spec,
                &PhotoSpec {
                    width_px: 2 * half + 80,
                    height_px: 2 * half + 80,
                    focal_px: s.ppm * dist,
                    distance_mm: dist,
                    tilt_deg: s.tilt.to_degrees(),
                    tilt_azimuth_deg: s.azimuth.to_degrees(),
                    roll_deg: s.roll.to_degrees(),
                    k1: s.k1,
                    texture_dpi: 450.0,
                    jpeg_quality: Some(s.jpeg),
                    seed,
                    ..PhotoSpec::default()
                },
            )
        }
        _ => render_scan(&spec),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = match args[1].as_str() {
        "photo" => Kind::Photo,
        "s300" => Kind::Scan300,
        _ => Kind::Scan600,
    };
    let indep = args[2] == "2";
    let seeds: Vec<u64> = args[3].split(',').map(|s| s.parse().unwrap()).collect();
    let cross_every = if indep && kind != Kind::Photo { 3 } else { 0 };
    let verbose = args.len() > 4;
    for seed in seeds {
        let crossing = cross_every > 0 && seed % cross_every == 0;
        let c = case(seed, kind != Kind::Photo, crossing);
        let img = if indep {
            render_independent(&c, kind, seed)
        } else {
            render_project(&c, kind, seed)
        };
        let t0 = std::time::Instant::now();
        let t = match trace_image(&img, &TraceOptions::default(), &ProgressBar::hidden()) {
            Ok(t) => t,
            Err(e) => {
                println!("seed {seed}: {e}");
                continue;
            }
        };
        let dt = t0.elapsed().as_secs_f64();
        let main = t.main_stroke().unwrap();
        let (cov, rms) = measure(&c.truth, c.closed, &main.points_mm, main.closed);
        println!(
            "seed {seed} {} skips {:?} cov {cov:.4} rms {rms:.4} whole {} pieces {} ({dt:.2}s)",
            c.shape,
            c.skips
                .iter()
                .map(|k| format!("{:.1}-{:.1}", k[0], k[1]))
                .collect::<Vec<_>>(),
            t.is_whole(),
            t.linking.pieces
        );
        let tr = SegIndex::new(&c.truth, c.closed);
        let d: Vec<f64> = main.points_mm.iter().map(|p| tr.dist(*p, 2.0)).collect();
        // sum of squares near gaps vs elsewhere
        let near_gap = |p: [f64; 2]| {
            t.linking.gaps.iter().any(|g| {
                let (a, b) = (g.from_mm, g.to_mm);
                let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                let r = 0.5 * ((a[0] - b[0]).hypot(a[1] - b[1])) + 2.0;
                (p[0] - mid[0]).hypot(p[1] - mid[1]) <= r
            })
        };
        let (mut ss_g, mut n_g, mut ss_o, mut n_o) = (0.0, 0, 0.0, 0);
        for (p, dd) in main.points_mm.iter().zip(&d) {
            if near_gap(*p) {
                ss_g += dd * dd;
                n_g += 1
            } else {
                ss_o += dd * dd;
                n_o += 1
            }
        }
        let n = d.len() as f64;
        println!("  ss share near gaps {:.3} (n {n_g}), rms without gaps {:.4}, rms-contribution gaps {:.4}", ss_g/(ss_g+ss_o), (ss_o/n_o as f64).sqrt(), (ss_g/n).sqrt());
        for g in &t.linking.gaps {
            let (a, b) = (g.from_mm, g.to_mm);
            let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            let r = 0.5 * ((a[0] - b[0]).hypot(a[1] - b[1])) + 2.0;
            let ds: Vec<f64> = main
                .points_mm
                .iter()
                .zip(&d)
                .filter(|(p, _)| (p[0] - mid[0]).hypot(p[1] - mid[1]) <= r)
                .map(|(_, dd)| *dd)
                .collect();
            let mx = ds.iter().copied().fold(0.0, f64::max);
            let ssg: f64 = ds.iter().map(|x| x * x).sum();
            println!(
                "  gap {:.2} mm at ({:.1},{:.1}) bridged {} max err {mx:.3} ss {:.4}",
                g.length_mm, a[0], a[1], g.bridged, ssg
            );
        }
        if verbose {
            let worst = t
                .linking
                .gaps
                .iter()
                .max_by(|a, b| {
                    let e = |g: &rigctl::trace::Gap| {
                        let m = [
                            (g.from_mm[0] + g.to_mm[0]) / 2.0,
                            (g.from_mm[1] + g.to_mm[1]) / 2.0,
                        ];
                        main.points_mm
                            .iter()
                            .zip(&d)
                            .filter(|(p, _)| (p[0] - m[0]).hypot(p[1] - m[1]) < 3.0)
                            .map(|(_, x)| *x)
                            .fold(0.0, f64::max)
                    };
                    e(a).total_cmp(&e(b))
                })
                .unwrap();
            let m = [
                (worst.from_mm[0] + worst.to_mm[0]) / 2.0,
                (worst.from_mm[1] + worst.to_mm[1]) / 2.0,
            ];
            println!("  worst gap {:?} -> {:?}", worst.from_mm, worst.to_mm);
            // signed error: nearest truth point and tangent
            for p in main.points_mm.iter() {
                let r = (p[0] - m[0]).hypot(p[1] - m[1]);
                if r > 16.0 {
                    continue;
                }
                let (mut bi, mut bd) = (0, f64::INFINITY);
                for (i, q) in c.truth.iter().enumerate() {
                    let dd = (p[0] - q[0]).hypot(p[1] - q[1]);
                    if dd < bd {
                        bd = dd;
                        bi = i;
                    }
                }
                let j = (bi + 1).min(c.truth.len() - 1);
                let i0 = if j == bi { bi - 1 } else { bi };
                let tt = [
                    c.truth[j][0] - c.truth[i0][0],
                    c.truth[j][1] - c.truth[i0][1],
                ];
                let tn = tt[0].hypot(tt[1]);
                let q = c.truth[bi];
                let s = (tt[0] * (p[1] - q[1]) - tt[1] * (p[0] - q[0])) / tn;
                println!(
                    "    {:8.3} {:8.3}  arc {:7.2}  err {:+.4}",
                    p[0],
                    p[1],
                    bi as f64 * 0.025,
                    s
                );
            }
        }
    }
}
