//! Scans and photos as devices write them: through a tone curve (sRGB, a plain gamma of 1/2.2,
//! a phone's S-curve), with nothing in the image saying so. The project's renderer applies its
//! curves to its finished 8-bit image (`synth::DeviceTone`); the independent renderer applies its
//! own, written here apart from the tracer and from `synth`, to its exposed, blurred and noisy
//! values before they are rounded. Each set cycles photos, 300 dpi and 600 dpi scans over its
//! seeds. The rule: exit 0 only within coverage >= 0.95 and RMS <= 0.05 mm (never a wrong trace
//! passed); the bars of the medium (photos 0.03 mm, 600 dpi 0.015, 300 dpi 0.02) are counted.
//! The tracer is told nothing: it measures the curve from the print's black.

use super::{
    case, render_independent_toned, render_project_toned, shot, trace_outcome, Kind, Outcome,
};
use rigctl::trace::synth::DeviceTone;
use rigctl::trace::{tone, trace_image, ToneCurve, ToneSource, TraceOptions};

/// sRGB's transfer, written out from its definition (IEC 61966-2-1) with a threshold on the
/// linear side, as an encoder writes it.
fn srgb(l: f64) -> f64 {
    if l < 0.003_130_8 {
        l * 12.92
    } else {
        1.055 * l.powf(0.416_666_666_666_666_7) - 0.055
    }
}

fn gamma_22(l: f64) -> f64 {
    l.powf(1.0 / 2.2)
}

/// A phone's look: a gamma of 1/2.0 on a black lifted to 2 % and a soft shoulder that rolls the
/// highlights off.
fn phone(l: f64) -> f64 {
    let e = 0.02 + 0.98 * l.sqrt();
    e - 0.08 * (e - 0.6).max(0.0).powi(2)
}

/// Which renderer draws a set, and through which curve.
#[derive(Clone, Copy)]
enum Toned {
    Project(DeviceTone),
    Independent(fn(f64) -> f64),
}

const MEDIA: [Kind; 3] = [Kind::Photo, Kind::Scan300, Kind::Scan600];

fn bar(kind: Kind) -> f64 {
    match kind {
        Kind::Photo => 0.03,
        Kind::Scan300 => 0.02,
        Kind::Scan600 => 0.015,
    }
}

/// The counts of one set: images, exit 0 within the medium's bars, exit 1/2 (each named),
/// exit 0 outside the medium's bars but within 0.95 / 0.05 mm, and exit 0 below 0.95 coverage
/// or above 0.05 mm RMS (a wrong trace passed).
#[derive(Debug, Default, PartialEq)]
struct Counts {
    n: usize,
    within: usize,
    refused: usize,
    over_medium_bar: usize,
    wrong: usize,
}

fn run(name: &str, toned: Toned, seeds: std::ops::Range<u64>) -> Counts {
    let mut k = Counts::default();
    for seed in seeds {
        let kind = MEDIA[(seed % 3) as usize];
        let c = case(seed, kind != Kind::Photo, seed % 4 == 0);
        let img = match toned {
            Toned::Project(t) => render_project_toned(&c, kind, seed, t),
            Toned::Independent(f) => {
                render_independent_toned(&c, kind, &shot(kind, seed), seed, Some(f))
            }
        };
        if let Some(dir) = std::env::var_os("TRACE_TONE_DUMP") {
            let f = std::path::Path::new(&dir)
                .join(format!("{}_{seed}.png", name.replace([' ', '/'], "_")));
            img.save(&f).expect("dump");
            let rows: String = c
                .truth
                .iter()
                .map(|p| format!("{},{}\n", p[0], p[1]))
                .collect();
            std::fs::write(f.with_extension("truth.csv"), rows).expect("dump truth");
        }
        let o: Outcome = trace_outcome(&img, &c);
        k.n += 1;
        let verdict = if !o.exit0 {
            assert!(
                !o.note.is_empty(),
                "{name} seed {seed}: a refusal names its cause"
            );
            k.refused += 1;
            "refused"
        } else if o.coverage < 0.95 || o.rms > 0.05 {
            k.wrong += 1;
            "WRONG"
        } else if o.rms > bar(kind) {
            k.over_medium_bar += 1;
            "over the medium's bar"
        } else {
            k.within += 1;
            "within"
        };
        eprintln!(
            "{name} seed {seed:>3} {kind:?} {}: coverage {:.4}, rms {:.4} mm, {verdict} ({})",
            c.shape, o.coverage, o.rms, o.note
        );
    }
    eprintln!("{name}: {k:?}");
    k
}

/// No wrong trace passed, and the curve does not stop the tracer: at least 90 % of the images
/// within their medium's bars.
fn check(name: &str, k: &Counts) {
    assert_eq!(k.wrong, 0, "{name}: exit 0 on a wrong trace: {k:?}");
    assert!(10 * k.within >= 9 * k.n, "{name}: {k:?}");
}

const SEEDS: std::ops::Range<u64> = 1..22;

/// The seeds: 1..22, or `TRACE_TONE_SEEDS=a..b` for a closer look.
fn seeds() -> std::ops::Range<u64> {
    std::env::var("TRACE_TONE_SEEDS")
        .ok()
        .and_then(|v| {
            let (a, b) = v.split_once("..")?;
            Some(a.parse().ok()?..b.parse().ok()?)
        })
        .unwrap_or(SEEDS)
}

#[test]
fn project_renderer_through_srgb() {
    let k = run("project sRGB", Toned::Project(DeviceTone::Srgb), seeds());
    check("project sRGB", &k);
}

#[test]
fn project_renderer_through_gamma_1_over_2_2() {
    let k = run(
        "project gamma 1/2.2",
        Toned::Project(DeviceTone::Gamma(2.2)),
        seeds(),
    );
    check("project gamma 1/2.2", &k);
}

#[test]
fn project_renderer_through_a_phone_s_curve() {
    let k = run(
        "project phone S-curve",
        Toned::Project(DeviceTone::PhoneS { share: 0.3 }),
        seeds(),
    );
    check("project phone S-curve", &k);
}

#[test]
fn independent_renderer_through_srgb() {
    let k = run("independent sRGB", Toned::Independent(srgb), seeds());
    check("independent sRGB", &k);
}

#[test]
fn independent_renderer_through_gamma_1_over_2_2() {
    let k = run(
        "independent gamma 1/2.2",
        Toned::Independent(gamma_22),
        seeds(),
    );
    check("independent gamma 1/2.2", &k);
}

#[test]
fn independent_renderer_through_a_phone_curve() {
    let k = run(
        "independent phone curve",
        Toned::Independent(phone),
        seeds(),
    );
    check("independent phone curve", &k);
}

/// The curve is measured, not assumed: a linear render is left linear, a gamma render gets
/// about its gamma back.
#[test]
fn the_tone_curve_is_measured_from_the_print() {
    let c = case(3, true, false);
    for (t, want) in [
        (DeviceTone::Linear, None),
        (DeviceTone::Gamma(2.2), Some(2.2)),
        (DeviceTone::Gamma(1.8), Some(1.8)),
    ] {
        let img = render_project_toned(&c, Kind::Scan300, 3, t);
        let tr = trace_image(
            &img,
            &TraceOptions::default(),
            &indicatif::ProgressBar::hidden(),
        )
        .expect("traced");
        match want {
            None => assert_eq!(tr.tone.source, ToneSource::Assumed, "{t:?}"),
            Some(g) => {
                let ToneCurve::Gamma(got) = tr.tone.curve else {
                    panic!("{t:?}: {:?}", tr.tone)
                };
                // The print's black is 0.07 of the paper in the render, taken as 0.06.
                let expect = tone::PRINT_BLACK.ln() / 0.07f64.ln() * g;
                assert!(
                    (got / expect - 1.0).abs() < 0.12,
                    "{t:?}: gamma {got}, {expect} expected"
                );
            }
        }
    }
}

/// A CLI case: name, the device's curve, whether the file says sRGB, what the report says.
type CliCase = (&'static str, fn(f64) -> f64, bool, &'static str);

/// Writes `img` as a PNG with an `sRGB` chunk.
fn save_srgb_png(img: &image::RgbImage, path: &std::path::Path) {
    let file = std::fs::File::create(path).expect("create");
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), img.width(), img.height());
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut w = enc.write_header().expect("header");
    w.write_image_data(img.as_raw()).expect("data");
}

/// The case: `rigctl simulate --session circle --seed 7`'s scan, as a scanner would
/// write it (sRGB, or a gamma of 1/2.2), once saying so in an `sRGB` chunk and once not: traced
/// whole by the CLI (exit 0), the curve reported, the trace on the session's true path.
#[test]
fn simulated_scan_through_device_curves_is_traced_by_the_cli() {
    use super::super::common::spawn::{rigctl, text};
    let dir = tempfile::tempdir().expect("tempdir");
    let sim = dir.path().join("sim");
    let st = rigctl()
        .args(["simulate", "--session", "circle", "--seed", "7", "--out"])
        .arg(&sim)
        .output()
        .expect("run simulate");
    assert!(st.status.success(), "{}", text(&st.stderr));
    let scan = image::open(sim.join("scan.png")).expect("scan").to_rgb8();
    let linear_out = dir.path().join("linear.csv");
    let st = super::trace_to(&sim.join("scan.png"), &linear_out);
    assert!(st.status.success(), "linear: {}", text(&st.stderr));
    let read = |p: &std::path::Path| -> Vec<[f64; 2]> {
        std::fs::read_to_string(p)
            .expect("csv")
            .lines()
            .skip(1)
            .filter_map(|l| {
                let (x, y) = l.split_once(',')?;
                Some([x.parse().ok()?, y.parse().ok()?])
            })
            .collect()
    };
    let linear = read(&linear_out);
    let cases: [CliCase; 3] = [
        ("srgb-tagged", srgb, true, "sRGB chunk"),
        ("srgb-untagged", srgb, false, "measured"),
        ("gamma", gamma_22, false, "measured"),
    ];
    for (name, curve, tagged, says) in cases {
        let mut img = scan.clone();
        for v in img.iter_mut() {
            *v = (255.0 * curve(f64::from(*v) / 255.0))
                .round()
                .clamp(0.0, 255.0) as u8;
        }
        let path = dir.path().join(format!("{name}.png"));
        if tagged {
            save_srgb_png(&img, &path);
        } else {
            img.save(&path).expect("save");
        }
        let out = dir.path().join(format!("{name}.csv"));
        let st = super::trace_to(&path, &out);
        let err = text(&st.stderr);
        assert!(st.status.success(), "{name}: {err}");
        assert!(
            err.contains("linearised") && err.contains(says),
            "{name}: {err}"
        );
        // The same path as the linear scan's trace (a closed polyline) within a few
        // thousandths of a mm RMS.
        let got = read(&out);
        let near = |p: &[f64; 2]| {
            (0..linear.len())
                .map(|i| {
                    let (a, b) = (linear[i], linear[(i + 1) % linear.len()]);
                    let d = [b[0] - a[0], b[1] - a[1]];
                    let v = [p[0] - a[0], p[1] - a[1]];
                    let t = ((v[0] * d[0] + v[1] * d[1]) / (d[0] * d[0] + d[1] * d[1]).max(1e-12))
                        .clamp(0.0, 1.0);
                    (v[0] - t * d[0]).hypot(v[1] - t * d[1])
                })
                .fold(f64::INFINITY, f64::min)
        };
        let d: Vec<f64> = got.iter().map(near).collect();
        let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt();
        let worst = d.iter().copied().fold(0.0, f64::max);
        eprintln!("{name}: {rms:.4} mm RMS, {worst:.4} max from the linear scan's trace; {err}");
        assert!(
            !d.is_empty() && rms < 0.005 && worst < 0.06,
            "{name}: {rms} mm RMS, {worst} max from the linear scan's trace"
        );
    }
}
