//! `trace` on an A4 scan at 600 dpi (4961 x 7016 px, a 100 mm-radius pencil circle, rotated
//! 2 degrees) and on a 12 MP phone photo (JPEG, 30 degrees tilt, k1 = -0.08, shading): decoding
//! and tracing measured separately, and the whole read-and-trace as the CLI does it
//! (`load_prepared` + `trace_prepared`: a PNG's rows are decoded by the `png` crate on one
//! thread while the RGB image and its maps are built on another; against it, the `image`
//! crate's decoding followed by the maps on all cores).
//!
//! The bench also leaves the scan and its truth in `target/tmp/trace_bench/` (`scan600.png`,
//! `truth.csv` = the pencil centreline, closed, x,y mm in sheet coordinates) for the OpenCV
//! baseline `bench/trace_opencv.py`.

use criterion::{criterion_group, criterion_main, Criterion};
use indicatif::ProgressBar;
use rigctl::trace::synth::{jpeg_bytes, render_photo, render_scan, PhotoSpec, RenderSpec};
use rigctl::trace::{
    load_prepared, load_scan, trace_image, trace_prepared, PrepareParams, Prepared, TraceOptions,
};
use std::io::Write;
use std::path::Path;
use std::path::PathBuf;
use std::time::Duration;

fn bench_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("trace_bench")
}

fn truth() -> Vec<[f64; 2]> {
    let n = 12_566;
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            let r = 100.0 + 0.3 * (3.0 * a).sin() + 0.15 * (5.0 * a + 0.4).cos();
            [r * a.cos(), r * a.sin()]
        })
        .collect()
}

/// Reads and traces a file as `rigctl trace` does.
fn read_and_trace(path: &Path, opts: &TraceOptions) -> Option<usize> {
    let (img, prepared) = load_prepared(path).ok()?;
    trace_prepared(&img, &prepared, opts, &ProgressBar::hidden())
        .ok()
        .map(|t| t.strokes.len())
}

fn trace_a4_600dpi(c: &mut Criterion) {
    let spec = RenderSpec {
        dpi: 600.0,
        pencil_mm: truth(),
        pencil_closed: true,
        rotation_deg: 2.0,
        shift_mm: [1.5, -2.0],
        seed: 600,
        ..RenderSpec::default()
    };
    let img = render_scan(&spec);
    let dir = bench_dir();
    let png = dir.join("scan600.png");
    let written = std::fs::create_dir_all(&dir).is_ok() && img.save(&png).is_ok() && {
        let mut csv = String::from("x,y\n");
        for p in &spec.pencil_mm {
            csv.push_str(&format!("{:.5},{:.5}\n", p[0], p[1]));
        }
        std::fs::File::create(dir.join("truth.csv"))
            .and_then(|mut f| f.write_all(csv.as_bytes()))
            .is_ok()
    };
    if !written {
        eprintln!("could not write {}", dir.display());
        return;
    }
    let mut g = c.benchmark_group("trace");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("decode_png_a4_600dpi", |b| {
        b.iter(|| load_scan(&png).map(|i| i.width()))
    });
    // The CLI's reader: the rows decoded on one thread, the RGB image and the maps on another.
    g.bench_function("read_png_with_maps_a4_600dpi", |b| {
        b.iter(|| load_prepared(&png).map(|(i, _)| i.width()))
    });
    // The same in turn: the whole image decoded, then its maps.
    g.bench_function("decode_png_then_maps_a4_600dpi", |b| {
        b.iter(|| load_scan(&png).map(|i| Prepared::build(&i).fits(&i, &PrepareParams::default())))
    });
    let opts = TraceOptions::default();
    g.bench_function("trace_a4_600dpi", |b| {
        b.iter(|| trace_image(&img, &opts, &ProgressBar::hidden()).map(|t| t.strokes.len()))
    });
    g.bench_function("read_and_trace_png_a4_600dpi", |b| {
        b.iter(|| read_and_trace(&png, &opts))
    });
    g.finish();
}

fn trace_photo_12mp(c: &mut Criterion) {
    let sheet = RenderSpec {
        pencil_mm: truth(),
        pencil_closed: true,
        ring: true,
        seed: 12,
        ..RenderSpec::default()
    };
    let photo = PhotoSpec {
        tilt_deg: 30.0,
        k1: -0.08,
        jpeg_quality: None,
        ..PhotoSpec::default()
    };
    let img = render_photo(&sheet, &photo);
    let dir = bench_dir();
    let jpg = dir.join("photo12mp.jpg");
    let written = std::fs::create_dir_all(&dir).is_ok()
        && jpeg_bytes(&img, 92).is_some_and(|b| std::fs::write(&jpg, b).is_ok());
    if !written {
        eprintln!("could not write {}", jpg.display());
        return;
    }
    let Ok(decoded) = load_scan(&jpg) else {
        eprintln!("could not decode {}", jpg.display());
        return;
    };
    let mut g = c.benchmark_group("trace");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("decode_jpeg_12mp", |b| {
        b.iter(|| load_scan(&jpg).map(|i| i.width()))
    });
    let opts = TraceOptions::default();
    g.bench_function("trace_photo_12mp", |b| {
        b.iter(|| trace_image(&decoded, &opts, &ProgressBar::hidden()).map(|t| t.strokes.len()))
    });
    g.bench_function("read_and_trace_jpeg_12mp", |b| {
        b.iter(|| read_and_trace(&jpg, &opts))
    });
    g.finish();
}

criterion_group!(benches, trace_a4_600dpi, trace_photo_12mp);
criterion_main!(benches);
