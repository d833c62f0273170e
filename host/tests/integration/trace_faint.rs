//! `trace` on faint graphite drawn pixel by pixel (no renderer of the project's): a pencil line
//! whose pressure drops along it, broken up by the paper's tooth, with a skip. Read with a plain
//! scale (`--no-fiducials`), so only the tracker and the linking are under test.

use indicatif::ProgressBar;
use rigctl::trace::{trace_image, Mapping, TraceOptions};

/// Pixels per mm (300 dpi).
const PX_PER_MM: f64 = 300.0 / 25.4;
const PAPER: f64 = 236.0;

/// A deterministic uniform number in [0, 1) (xorshift).
struct Grain(u64);

impl Grain {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The line's centre at `x` px: a gentle wave across the image.
fn centre_y(x: f64) -> f64 {
    300.0 + 40.0 * (x / 150.0).sin()
}

/// Draws the line from x = 100 to 1100 px, 0.35 mm wide, with darkness `dark(x)` times the
/// tooth's factor per pixel (`tooth`: 0 smooth .. 1 from nothing to twice), nothing where
/// `dark(x)` is 0, on paper with a little noise.
fn draw(dark: impl Fn(f64) -> f64, tooth: f64, seed: u64) -> image::RgbImage {
    let (w, h) = (1200u32, 600u32);
    let mut g = Grain(seed);
    let mut img = image::RgbImage::new(w, h);
    let half_w_px = 0.5 * 0.35 * PX_PER_MM;
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let noise = 3.0 * (g.next() - 0.5);
            let mut d = 0.0;
            if (100.0..1100.0).contains(&fx) {
                // Distance across the line (its slope is at most 0.27, so vertical is close).
                let slope = 40.0 / 150.0 * (fx / 150.0).cos();
                let across = (fy - centre_y(fx)).abs() / slope.hypot(1.0);
                let cover = (half_w_px + 0.5 - across).clamp(0.0, 1.0);
                d = dark(fx) * cover * (1.0 + tooth * (2.0 * g.next() - 1.0));
            }
            let v = (PAPER * (1.0 - d.clamp(0.0, 1.0)) + noise).clamp(0.0, 255.0) as u8;
            img.put_pixel(x, y, image::Rgb([v, v, v]));
        }
    }
    img
}

fn trace(img: &image::RgbImage) -> rigctl::trace::Trace {
    let opts = TraceOptions {
        mapping: Mapping::Scale {
            mm_per_px: 1.0 / PX_PER_MM,
        },
        ..TraceOptions::default()
    };
    trace_image(img, &opts, &ProgressBar::hidden()).expect("a trace")
}

/// Length of the drawn line, mm.
fn line_length_mm() -> f64 {
    let n = 10_000;
    (0..n)
        .map(|i| {
            let (a, b) = (
                100.0 + 1000.0 * i as f64 / n as f64,
                100.0 + 1000.0 * (i + 1) as f64 / n as f64,
            );
            (b - a).hypot(centre_y(b) - centre_y(a))
        })
        .sum::<f64>()
        / PX_PER_MM
}

/// Dark graphite (0.4) either end; between them a faint stretch (0.2) that drops for 20 mm to
/// a fainter one (0.12: too faint to begin a piece, its windows under half the faint one's
/// running mass) with a hole a window long every 5 mm, and a 2 mm skip in the faint stretch.
/// Read a window at a time, the walk ended at the drop (or at the first hole) and the fainter
/// stretch was a gap over `--max-gap-mm` (not whole). Two millimetres at a time it holds half
/// of what begins a piece, with one hole at most, so the walk goes on through it; the skip
/// leaves windows empty in a row, still ends it, and is bridged and listed.
#[test]
fn a_faint_line_dropping_to_fainter_graphite_is_followed_through_it() {
    let skip = (400.0, 400.0 + 2.0 * PX_PER_MM);
    let dark = |x: f64| {
        if (skip.0..skip.1).contains(&x) {
            0.0
        } else if !(350.0..850.0).contains(&x) {
            0.4
        } else if (480.0..480.0 + 20.0 * PX_PER_MM).contains(&x) {
            // Holes a window long every 5 mm.
            if (x - 480.0) % 60.0 >= 55.0 {
                0.0
            } else {
                0.12
            }
        } else {
            0.2
        }
    };
    let tr = trace(&draw(dark, 0.3, 1));
    let len = tr.main_stroke().expect("a stroke").length_mm();
    let truth = line_length_mm();
    assert!(
        tr.is_whole(),
        "not whole: {:?}",
        tr.linking.missing().collect::<Vec<_>>()
    );
    assert!(
        (len - truth).abs() < 0.01 * truth,
        "{len:.2} mm written of {truth:.2}"
    );
    let skips: Vec<f64> = tr
        .linking
        .gaps
        .iter()
        .filter(|g| g.length_mm > 1.5)
        .map(|g| g.length_mm)
        .collect();
    assert!(
        skips.len() == 1 && (skips[0] - 2.0).abs() < 0.6,
        "the 2 mm skip bridged and listed: {skips:?}"
    );
}
