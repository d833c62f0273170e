//! Real photographs of plotter drawings (BrachioGraph docs, shared/data/real): they carry no
//! fiducials, so `trace` must say so; with a plain scale the strokes are still extracted, one per
//! drawn line, and the trace of one of them is never reported as the whole drawing.

use crate::common;

use indicatif::ProgressBar;
use rigctl::trace::{load_scan, trace_image, Mapping, TraceError, TraceOptions};

fn photos() -> Option<Vec<std::path::PathBuf>> {
    let dir = common::shared_file(
        "BrachioGraph photos",
        "data/real/evildmp__BrachioGraph/docs/images",
    )?;
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("jpg")))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no photos in {}", dir.display());
    Some(files)
}

#[test]
fn photos_without_fiducials_are_refused_clearly() {
    let Some(files) = photos() else { return };
    for f in files {
        let img = load_scan(&f).expect("decode jpeg");
        let err = trace_image(&img, &TraceOptions::default(), &ProgressBar::hidden())
            .expect_err("no fiducials");
        assert!(
            matches!(err, TraceError::NoFiducials { .. }),
            "{}: {err}",
            f.display()
        );
        assert!(err.to_string().contains("--no-fiducials"));
    }
}

#[test]
fn photos_with_a_plain_scale_yield_strokes() {
    let Some(files) = photos() else { return };
    let opts = TraceOptions {
        mapping: Mapping::Scale { mm_per_px: 0.2 },
        ..TraceOptions::default()
    };
    for f in files {
        let img = load_scan(&f).expect("decode jpeg");
        let tr = trace_image(&img, &opts, &ProgressBar::hidden()).expect("strokes");
        let total: f64 = tr.strokes.iter().map(|s| s.length_mm()).sum();
        eprintln!(
            "{}: {}x{} px, {} strokes, {total:.0} mm in all, longest {:.0} mm",
            f.display(),
            img.width(),
            img.height(),
            tr.strokes.len(),
            tr.main_stroke().expect("a stroke").length_mm()
        );
        assert!(total > 10.0, "{}: {total} mm", f.display());
        // Several drawn lines (and the grid of earlier ones): one written path cannot be the
        // whole drawing, so the trace is never reported whole (no exit 0 on a part).
        assert!(
            !tr.is_whole() && tr.linking.left_out.iter().any(|o| o.could_be_path()),
            "{}: reported whole",
            f.display()
        );
        for s in &tr.strokes {
            assert!(s
                .points_mm
                .iter()
                .all(|p| p[0].is_finite() && p[1].is_finite()));
        }
    }
}
