//! `trace` on images it was not shaped to: drawn paths offset 2-40 mm and turned 0-30 deg from the
//! printed reference, other radii and free curves (open and closed), 3-8 skips of 1-6 mm, dust,
//! fibres, stray flicks and a second pencil stroke across the path; rendered by the project's
//! renderer and by an independent one (`trace_independent/render2.rs`: another stroke, skip,
//! dust, shading and camera model; also photos cropped off their centre). Measured by coverage
//! (share of the true centreline within 0.1 mm of the trace) and RMS; the exit rule: exit 0 only
//! with the whole drawn path written, so never exit 0 below 0.95 coverage, and an incomplete
//! path exits 1 naming where (`exit_rule`).
//!
//! Here: the sets of 20 seeds per renderer and image kind (`renderers` draws them) and a pencil
//! line across ring dots. In the submodules: the exit rule (`exit_rule`), several drawn lines
//! (`drawing`), sheets not lying flat (`bends`), device tone curves (`tone_curves`), two runs
//! on one sheet (`two_runs`), hard shadows and page edges (`shadows`), six sheets as a new user
//! would draw them (`reported`).

#[path = "trace_independent/bends.rs"]
mod bends;
#[path = "trace_independent/cases.rs"]
mod cases;
#[path = "trace_independent/drawing.rs"]
mod drawing;
#[path = "trace_independent/exit_rule.rs"]
mod exit_rule;
#[path = "trace_independent/render2.rs"]
mod render2;
#[path = "trace_independent/renderers.rs"]
mod renderers;
#[path = "trace_independent/reported.rs"]
mod reported;
#[path = "trace_independent/shadows.rs"]
mod shadows;
#[path = "trace_independent/tone_curves.rs"]
mod tone_curves;
#[path = "trace_independent/two_runs.rs"]
mod two_runs;

use crate::trace_cli::trace_to;
use cases::{case, measure, Case};
use indicatif::ProgressBar;
use render2::Printed;
use renderers::{
    render_independent, render_independent_shot, render_independent_toned, render_independent_with,
    render_project, render_project_toned, render_project_with, shot, Kind, Shot,
};
use rigctl::trace::{trace_image, TraceOptions};

/// One traced image: coverage, RMS (mm), whether the tracer would exit 0, and its message.
struct Outcome {
    coverage: f64,
    rms: f64,
    exit0: bool,
    note: String,
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
