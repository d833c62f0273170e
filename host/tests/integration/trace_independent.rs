//! `trace` on images it was not shaped to: drawn paths offset 2-40 mm and turned 0-30 deg from the
//! printed reference, other radii and free curves (open and closed), 3-8 skips of 1-6 mm, dust,
//! fibres, stray flicks and a second pencil stroke across the path; rendered by the project's
//! renderer and by an independent one (`trace_independent/render2.rs`: another stroke, skip,
//! dust, shading and camera model; also photos cropped off their centre). Measured by coverage (share of the true centreline within
//! 0.1 mm of the trace) and RMS; the exit rule: exit 0 only with the whole drawn path written,
//! so never exit 0 below 0.95 coverage, and an incomplete path exits 1 naming where.

#[path = "trace_independent/bends.rs"]
mod bends;
#[path = "trace_independent/cases.rs"]
mod cases;
#[path = "trace_independent/drawing.rs"]
mod drawing;
#[path = "trace_independent/render2.rs"]
mod render2;
#[path = "trace_independent/reported.rs"]
mod reported;
#[path = "trace_independent/tone_curves.rs"]
mod tone_curves;
#[path = "trace_independent/two_runs.rs"]
mod two_runs;

use crate::trace_cli::trace_to;
use cases::{case, measure, Case};
use indicatif::ProgressBar;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use render2::{photo_view, scan_view, Printed, Scene};
use rigctl::sheet::ReferencePath;
use rigctl::trace::synth::{render_photo, render_scan, Bend, DeviceTone, PhotoSpec, RenderSpec};
use rigctl::trace::{trace_image, TraceOptions};

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
    /// The principal point this far from the image centre, px (a photo cropped off its centre).
    centre_off_px: f64,
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
        centre_off_px: 0.0,
    }
}

fn render_independent(c: &Case, kind: Kind, seed: u64) -> image::RgbImage {
    render_independent_shot(c, kind, &shot(kind, seed), seed)
}

/// [`render_independent`] with the camera and light of `s`.
fn render_independent_shot(c: &Case, kind: Kind, s: &Shot, seed: u64) -> image::RgbImage {
    render_independent_toned(c, kind, s, seed, None)
}

/// [`render_independent_shot`] written through the tone curve `tone` (`None`: linear).
fn render_independent_toned(
    c: &Case,
    kind: Kind,
    s: &Shot,
    seed: u64,
    tone: Option<fn(f64) -> f64>,
) -> image::RgbImage {
    render_independent_with(c, kind, s, seed, tone, None)
}

/// [`render_independent_toned`] with a photo's sheet sagging by `sag`.
fn render_independent_with(
    c: &Case,
    kind: Kind,
    s: &Shot,
    seed: u64,
    tone: Option<fn(f64) -> f64>,
    sag: Option<render2::Sag>,
) -> image::RgbImage {
    let mut marks = vec![render2::Mark {
        pts: c.truth.clone(),
        width_mm: c.width_mm,
        darkness: c.darkness,
        skips: c.skips.clone(),
    }];
    if let Some((pts, closed)) = &c.second_run {
        let mut pts = pts.clone();
        if *closed {
            pts.push(pts[0]);
        }
        marks.push(render2::Mark {
            pts,
            width_mm: c.width_mm,
            darkness: c.darkness,
            skips: Vec::new(),
        });
    }
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
            {
                let view = photo_view(
                    s.ppm,
                    s.tilt,
                    s.azimuth,
                    s.roll,
                    s.k1,
                    [rng.gen_range(-8.0..8.0), rng.gen_range(-8.0..8.0)],
                );
                let a = seed as f64 * 2.399_963; // a direction per seed, outside `rng`'s stream
                render2::off_centre(view, [s.centre_off_px * a.cos(), s.centre_off_px * a.sin()])
            },
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
        tone,
        sag,
    })
}

fn render_project(c: &Case, kind: Kind, seed: u64) -> image::RgbImage {
    render_project_toned(c, kind, seed, DeviceTone::Linear)
}

/// [`render_project`] written through the device's tone curve `tone`.
fn render_project_toned(c: &Case, kind: Kind, seed: u64, tone: DeviceTone) -> image::RgbImage {
    render_project_with(c, kind, seed, tone, None)
}

/// [`render_project_toned`] with a photo's sheet bent by `bend`.
fn render_project_with(
    c: &Case,
    kind: Kind,
    seed: u64,
    tone: DeviceTone,
    bend: Option<Bend>,
) -> image::RgbImage {
    let s = shot(kind, seed);
    let spec = RenderSpec {
        dpi: if kind == Kind::Photo {
            450.0
        } else {
            s.ppm * 25.4
        },
        pencil_mm: c.truth.clone(),
        pencil_closed: c.closed,
        more_pencil_mm: c.second_run.iter().cloned().collect(),
        pencil_width_mm: c.width_mm,
        pencil_darkness: c.darkness,
        reference: Some(printed(c.printed)),
        ring: true,
        rotation_deg: s.rot_deg,
        skips_mm: c.skips.clone(),
        dust_mm: c.dust.iter().map(|d| [d[0], d[1], d[2]]).collect(),
        fibres_mm: c.fibres.clone(),
        seed,
        device_tone: tone,
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
                    bend,
                    ..PhotoSpec::default()
                },
            )
        }
        _ => render_scan(&spec),
    }
}

fn trace_outcome(img: &image::RgbImage, c: &Case) -> Outcome {
    match trace_image(img, &TraceOptions::default(), &ProgressBar::hidden()) {
        Err(e) => Outcome {
            coverage: 0.0,
            rms: f64::INFINITY,
            exit0: false,
            note: format!("error: {e}"),
        },
        Ok(t) => {
            let Some(main) = t.main_stroke() else {
                return Outcome {
                    coverage: 0.0,
                    rms: f64::INFINITY,
                    exit0: false,
                    note: "no stroke".into(),
                };
            };
            let (coverage, rms) = measure(&c.truth, c.closed, &main.points_mm, main.closed);
            let flat = t.flatness.map_or(String::new(), |f| {
                format!(
                    "; marks' pattern {:.4} mm (F {:.1}, scatter {:.4})",
                    f.pattern_mm, f.f_stat, f.scatter_mm
                )
            });
            Outcome {
                coverage,
                rms,
                exit0: t.is_whole(),
                note: format!(
                    "{:.1} mm{}{}",
                    main.length_mm(),
                    if main.closed { " closed" } else { "" },
                    if t.is_whole() {
                        String::new()
                    } else {
                        let why: Vec<String> = t
                            .linking
                            .missing()
                            .map(|g| format!("gap {:.1} mm at {:.1?}", g.length_mm, g.from_mm))
                            .chain(t.linking.left_out.iter().filter(|o| o.could_be_path()).map(
                                |o| {
                                    format!(
                                        "{:?} {:.1} mm {:.1?}..{:.1?}",
                                        o.kind, o.length_mm, o.from_mm, o.to_mm
                                    )
                                },
                            ))
                            .chain(
                                t.ends_at_print_mm
                                    .iter()
                                    .map(|p| format!("end at the grey print {p:.1?}")),
                            )
                            .collect();
                        format!("; {}", why.join("; "))
                    },
                ) + &flat,
            }
        }
    }
}

/// Which renderer draws a set.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Renderer {
    /// The project's own (`rigctl::trace::synth`).
    Project,
    /// `render2`; its photos' principal point 0.5-1 times `centre_off_px` from the image centre
    /// (a photo cropped off its centre), in a direction and at a distance set by the seed.
    Independent { centre_off_px: f64 },
    /// `render2`'s image turned to grey (luminance): a greyscale scan, the red print as dark as
    /// the pencil.
    IndependentGrey,
}

const INDEPENDENT: Renderer = Renderer::Independent { centre_off_px: 0.0 };

/// Runs `seeds` of one renderer and image kind; prints a row per seed and the summary; returns
/// the outcomes.
fn run_set(
    name: &str,
    kind: Kind,
    renderer: Renderer,
    seeds: std::ops::Range<u64>,
    crossing_every: u64,
) -> Vec<Outcome> {
    let mut out = Vec::new();
    for seed in seeds {
        let independent = renderer != Renderer::Project;
        let crossing = independent && crossing_every > 0 && seed % crossing_every == 0;
        let c = case(seed, kind != Kind::Photo, crossing);
        let img = match renderer {
            Renderer::Independent { centre_off_px } => {
                let share = 0.5 + 0.5 * (seed as f64 * 0.618_034).fract();
                let s = Shot {
                    centre_off_px: share * centre_off_px,
                    ..shot(kind, seed)
                };
                render_independent_shot(&c, kind, &s, seed)
            }
            Renderer::IndependentGrey => grey(render_independent(&c, kind, seed)),
            Renderer::Project => render_project(&c, kind, seed),
        };
        if let Some(dir) = std::env::var_os("TRACE_INDEPENDENT_DUMP") {
            let f =
                std::path::Path::new(&dir).join(format!("{}_{seed}.png", name.replace(' ', "_")));
            img.save(&f).expect("dump");
            let rows: String = c
                .truth
                .iter()
                .step_by(4)
                .map(|p| format!("{},{}\n", p[0], p[1]))
                .collect();
            std::fs::write(f.with_extension("truth.csv"), rows).expect("dump truth");
        }
        let o = trace_outcome(&img, &c);
        eprintln!(
            "{name} seed {seed:>3} {:<11}{} {} skips: coverage {:.4}, rms {:.4} mm, exit {} ({})",
            c.shape,
            if crossing { " +cross" } else { "" },
            c.skips.len(),
            o.coverage,
            o.rms,
            if o.exit0 { 0 } else { 1 },
            o.note
        );
        out.push(o);
    }
    let cov: Vec<f64> = out.iter().map(|o| o.coverage).collect();
    let rms: Vec<f64> = out.iter().filter(|o| o.exit0).map(|o| o.rms).collect();
    eprintln!(
        "{name}: {} seeds, exit 0 on {}, coverage {:.4}..{:.4}, rms (exit 0) {:.4}..{:.4} mm, exit 0 below 0.95 coverage: {}",
        out.len(),
        rms.len(),
        cov.iter().copied().fold(f64::INFINITY, f64::min),
        cov.iter().copied().fold(0.0, f64::max),
        rms.iter().copied().fold(f64::INFINITY, f64::min),
        rms.iter().copied().fold(0.0, f64::max),
        out.iter().filter(|o| o.exit0 && o.coverage < 0.95).count()
    );
    out
}

/// `img` in grey: each pixel's luminance (ITU-R BT.601) in all three channels.
fn grey(mut img: image::RgbImage) -> image::RgbImage {
    for p in img.pixels_mut() {
        let [r, g, b] = p.0.map(f64::from);
        let l = (0.299 * r + 0.587 * g + 0.114 * b)
            .round()
            .clamp(0.0, 255.0) as u8;
        p.0 = [l; 3];
    }
    img
}

/// The bars, on every seed: never exit 0 below 0.95 coverage; exit 0 with coverage >= 0.95 and
/// RMS within `rms_bar`.
fn check(name: &str, outs: &[Outcome], rms_bar: f64) {
    let partial_exit0 = outs.iter().filter(|o| o.exit0 && o.coverage < 0.95).count();
    assert_eq!(partial_exit0, 0, "{name}: exit 0 below 0.95 coverage");
    for (i, o) in outs.iter().enumerate() {
        assert!(
            o.exit0 && o.coverage >= 0.95 && o.rms <= rms_bar,
            "{name} #{i}: coverage {:.4}, rms {:.4} (bar {rms_bar}), exit0 {} ({})",
            o.coverage,
            o.rms,
            o.exit0,
            o.note
        );
    }
}

const SEEDS: std::ops::Range<u64> = 1..21;

/// The seeds: 1..21, or `TRACE_INDEPENDENT_SEEDS=a..b` for a closer look.
fn seeds() -> std::ops::Range<u64> {
    std::env::var("TRACE_INDEPENDENT_SEEDS")
        .ok()
        .and_then(|v| {
            let (a, b) = v.split_once("..")?;
            Some(a.parse().ok()?..b.parse().ok()?)
        })
        .unwrap_or(SEEDS)
}

#[test]
fn independent_photos() {
    let outs = run_set("render2 photo", Kind::Photo, INDEPENDENT, seeds(), 0);
    check("render2 photo", &outs, 0.03);
}

/// Photos cropped off their centre: the lens's axis 500-1000 px from the image centre (the lens
/// distortion is about the axis, not the image centre). Taken about the image centre, the marks
/// still fitted (0.01-0.02 mm) while the inside of the ring was bent by 0.05-0.17 mm: exit 0
/// at coverage down to 0.15.
#[test]
fn independent_photos_cropped_off_centre() {
    let s = seeds();
    let renderer = Renderer::Independent {
        centre_off_px: 1000.0,
    };
    let outs = run_set(
        "render2 photo cropped",
        Kind::Photo,
        renderer,
        s.start..s.end.min(s.start + 10),
        0,
    );
    check("render2 photo cropped", &outs, 0.03);
}

#[test]
fn independent_scans_600dpi() {
    let outs = run_set("render2 scan 600", Kind::Scan600, INDEPENDENT, seeds(), 3);
    check("render2 scan 600", &outs, 0.015);
}

#[test]
fn independent_scans_300dpi() {
    let outs = run_set("render2 scan 300", Kind::Scan300, INDEPENDENT, seeds(), 3);
    check("render2 scan 300", &outs, 0.02);
}

/// A greyscale scan: render2's 300 dpi scans in grey, the printed path as dark as the pencil.
/// The print is found by its geometry and left out with the pencil near it; before, every one
/// exited 1 naming the pencil as "another drawn line" (the print was the longest). Where the
/// pencil runs along the print, or ends within 3 mm of it, it cannot be told from the print:
/// exit 1 is right there. Never exit 0 below 0.95 coverage; every whole trace within the bars.
#[test]
fn independent_scans_300dpi_greyscale() {
    let outs = run_set(
        "render2 scan 300 grey",
        Kind::Scan300,
        Renderer::IndependentGrey,
        seeds(),
        3,
    );
    let partial_exit0 = outs.iter().filter(|o| o.exit0 && o.coverage < 0.95).count();
    assert_eq!(partial_exit0, 0, "exit 0 below 0.95 coverage");
    for (i, o) in outs.iter().filter(|o| o.exit0).enumerate() {
        assert!(
            o.rms <= 0.02,
            "whole #{i}: coverage {:.4}, rms {:.4} ({})",
            o.coverage,
            o.rms,
            o.note
        );
    }
    let whole = outs.iter().filter(|o| o.exit0).count();
    assert!(2 * whole >= outs.len(), "{whole} of {} whole", outs.len());
}

#[test]
fn project_renderer_photos() {
    let outs = run_set("render photo", Kind::Photo, Renderer::Project, seeds(), 0);
    check("render photo", &outs, 0.03);
}

#[test]
fn project_renderer_scans_600dpi() {
    let outs = run_set(
        "render scan 600",
        Kind::Scan600,
        Renderer::Project,
        seeds(),
        0,
    );
    check("render scan 600", &outs, 0.015);
}

#[test]
fn project_renderer_scans_300dpi() {
    let outs = run_set(
        "render scan 300",
        Kind::Scan300,
        Renderer::Project,
        seeds(),
        0,
    );
    check("render scan 300", &outs, 0.02);
}

/// A pencil circle of 90.4 mm about the sheet's centre runs over four ring dots, (+-90, 0) and
/// (0, +-90), 0.4 mm off their centres: where the graphite merges with a dot the mark search
/// finds no disc, yet the dot's ink must not pull the centreline into it (render2's scans and
/// photo).
#[test]
fn pencil_across_ring_dots() {
    let dots = [[90.0, 0.0], [0.0, 90.0], [-90.0, 0.0], [0.0, -90.0]];
    let truth = cases::densify(
        |u| {
            let a = std::f64::consts::TAU * u;
            [90.4 * a.cos(), 90.4 * a.sin()]
        },
        true,
    );
    let c = Case {
        shape: "circle across ring dots",
        printed: Printed::Circle,
        truth,
        closed: true,
        skips: Vec::new(),
        width_mm: 0.5,
        darkness: 0.8,
        crossing: None,
        strays: Vec::new(),
        dust: Vec::new(),
        fibres: Vec::new(),
        second_run: None,
    };
    for (kind, seed, rms_bar) in [
        (Kind::Scan600, 71, 0.015),
        (Kind::Scan300, 72, 0.02),
        (Kind::Photo, 73, 0.03),
    ] {
        let img = render_independent(&c, kind, seed);
        let t =
            trace_image(&img, &TraceOptions::default(), &ProgressBar::hidden()).expect("traced");
        let main = t.main_stroke().expect("a stroke");
        let (coverage, rms) = measure(&c.truth, c.closed, &main.points_mm, main.closed);
        let tr = cases::SegIndex::new(&c.truth, true);
        let at_dots = dots.map(|d| {
            main.points_mm
                .iter()
                .filter(|p| (p[0] - d[0]).hypot(p[1] - d[1]) < 2.0)
                .map(|p| tr.dist(*p, 5.0))
                .fold(0.0, f64::max)
        });
        let found = t.camera_fit.map_or(0, |f| f.found);
        eprintln!(
            "{kind:?}: coverage {coverage:.4}, rms {rms:.4} mm, worst beside the dots {at_dots:.3?} mm, {found} of 48 marks found"
        );
        assert!(
            t.is_whole() && coverage >= 0.95,
            "{kind:?}: {:?}",
            t.linking.missing().collect::<Vec<_>>()
        );
        assert!(rms <= rms_bar, "{kind:?}: rms {rms} mm");
        for d in at_dots {
            assert!(d < 0.1, "{kind:?}: {d} mm off the pencil beside a ring dot");
        }
    }
}

/// The arc-length position `s` on the truth.
fn truth_at(c: &Case, s: f64) -> [f64; 2] {
    let mut acc = 0.0;
    for w in c.truth.windows(2) {
        acc += (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        if acc >= s {
            return w[1];
        }
    }
    c.truth[c.truth.len() - 1]
}

/// A path that cannot be completed: one skip of 20-30 mm (beyond --max-gap-mm 10) besides the
/// short ones. Never exit 0; the missing gap is named where it is; bridging it on purpose
/// (a larger --max-gap-mm) gives the whole path.
#[test]
fn long_skip_is_never_exit_0_and_is_named() {
    for seed in 101..109u64 {
        let mut c = case(seed, true, false);
        let total = cases::length(&c.truth);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let len = rng.gen_range(20.0..30.0);
        let s0 = 0.5 * total - 0.5 * len;
        c.skips.retain(|k| k[1] < s0 - 6.0 || k[0] > s0 + len + 6.0);
        c.skips.push([s0, s0 + len]);
        let img = render_independent(&c, Kind::Scan300, seed);
        let t =
            trace_image(&img, &TraceOptions::default(), &ProgressBar::hidden()).expect("traced");
        let main = t.main_stroke().expect("a path");
        let (coverage, _) = measure(&c.truth, c.closed, &main.points_mm, main.closed);
        let missing: Vec<_> = t.linking.missing().collect();
        eprintln!(
            "seed {seed} {} skip {len:.1} mm: coverage of the longest chain {coverage:.3}, whole {}, missing {missing:?}",
            c.shape,
            t.is_whole()
        );
        assert!(!t.is_whole(), "seed {seed}: exit 0 with a {len:.1} mm skip");
        // Named: a missing gap from one side of the skip to the other, or the mark beyond it
        // (a part of the path that may continue it) starting at the skip's far side.
        let (a, b) = (truth_at(&c, s0), truth_at(&c, s0 + len));
        let near = |q: [f64; 2], p: [f64; 2]| (q[0] - p[0]).hypot(q[1] - p[1]) < 1.5;
        let gap_named = missing.iter().any(|g| {
            (near(g.from_mm, a) && near(g.to_mm, b)) || (near(g.from_mm, b) && near(g.to_mm, a))
        });
        let mark_named = t
            .linking
            .left_out
            .iter()
            .filter(|o| o.could_be_path())
            .any(|o| {
                [o.from_mm, o.to_mm]
                    .iter()
                    .any(|q| near(*q, a) || near(*q, b))
            });
        assert!(
            gap_named || mark_named,
            "seed {seed}: the missing stretch {a:?}..{b:?} is not named: {missing:?}, {:?}",
            t.linking.left_out
        );
        // On purpose: a larger --max-gap-mm bridges it where the path is smooth at the gap's
        // scale (circle, line); a wiggly curve may still not be extrapolated across 20-30 mm,
        // but whenever the trace is then reported whole it covers the path.
        let wide = TraceOptions {
            max_gap_mm: 35.0,
            ..TraceOptions::default()
        };
        let t = trace_image(&img, &wide, &ProgressBar::hidden()).expect("traced");
        let main = t.main_stroke().expect("a path");
        let (coverage, rms) = measure(&c.truth, c.closed, &main.points_mm, main.closed);
        eprintln!(
            "  --max-gap-mm 35: whole {}, coverage {coverage:.3}, rms {rms:.3} mm",
            t.is_whole()
        );
        if c.shape == "circle" || c.shape == "line" {
            assert!(t.is_whole(), "seed {seed}: not whole with --max-gap-mm 35");
        }
        if t.is_whole() {
            assert!(coverage >= 0.9, "seed {seed}: coverage {coverage} bridged");
            assert!(rms < 0.5, "seed {seed}: rms {rms} bridged");
        }
    }
}

/// Through the CLI: the gaps bridged are listed on exit 0; exit 1 naming the gap, and no CSV.
#[test]
fn cli_exit_codes_and_messages() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut c = case(7, true, false);
    let scan = dir.path().join("whole.png");
    render_independent(&c, Kind::Scan300, 7)
        .save(&scan)
        .expect("png");
    let out = dir.path().join("whole.csv");
    let o = trace_to(&scan, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    // Every skip is listed (besides any ring dot or speck of dust the pencil crossed).
    assert!(
        err.matches("gap bridged:").count() >= c.skips.len(),
        "{err}"
    );
    assert!(out.exists());
    let total = cases::length(&c.truth);
    c.skips = vec![[0.5 * total, 0.5 * total + 25.0]];
    let scan = dir.path().join("gap.png");
    render_independent(&c, Kind::Scan300, 7)
        .save(&scan)
        .expect("png");
    let out = dir.path().join("gap.csv");
    let o = trace_to(&scan, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("not the whole drawn path") && err.contains("gap of"),
        "{err}"
    );
    assert!(!out.exists());
}

/// A greyscale scan through the CLI: whole (seed 5, a line crossing the print) is exit 0 with
/// the grey print named; a line running along the print (seed 17) is exit 1 naming the end at
/// the print, nothing written.
#[test]
fn cli_greyscale_scans_name_the_grey_print() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (seed, code) in [(5, 0), (17, 1)] {
        let c = case(seed, true, false);
        let scan = dir.path().join(format!("grey{seed}.png"));
        grey(render_independent(&c, Kind::Scan300, seed))
            .save(&scan)
            .expect("png");
        let out = dir.path().join(format!("grey{seed}.csv"));
        let o = trace_to(&scan, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "seed {seed}: {err}");
        assert!(
            err.contains("the printed line is as dark as the pencil"),
            "seed {seed}: {err}"
        );
        assert_eq!(out.exists(), code == 0, "seed {seed}");
        if code == 1 {
            assert!(err.contains("under the printed path"), "{err}");
        }
    }
}

/// The overlay of a greyscale scan whose path ends at the print (render2 seed 17) marks that end
/// with a red cross, 3 mm across: more red than the same trace without the end listed.
#[test]
fn overlay_marks_an_end_at_the_grey_print() {
    let c = case(17, true, false);
    let img = grey(render_independent(&c, Kind::Scan300, 17));
    let t = trace_image(&img, &TraceOptions::default(), &ProgressBar::hidden()).expect("trace");
    assert_eq!(t.ends_at_print_mm.len(), 1, "{:?}", t.ends_at_print_mm);
    let red = |t: &rigctl::trace::Trace| {
        rigctl::trace::overlay::render_overlay(&img, t, 180.0)
            .pixels()
            .filter(|p| p.0[0] > 200 && p.0[1] < 60 && p.0[2] < 60)
            .count()
    };
    let without = rigctl::trace::Trace {
        ends_at_print_mm: Vec::new(),
        ..t.clone()
    };
    // Two strokes of 4.2 mm at 11.8 px/mm, 3 px wide: about 300 pixels.
    let more = red(&t) as f64 - red(&without) as f64;
    assert!(more > 150.0, "{more} more red pixels");
}
