//! The plot functions write real PNG / SVG files of the requested size.

use rigctl::plot::{self, ErrorHistogram, LineChart, PlotError, PoseErrorBars, Scatter, Series};

fn labels() -> [String; 2] {
    ["before".into(), "after".into()]
}

fn bars() -> PoseErrorBars {
    PoseErrorBars {
        title: "poses".into(),
        before_mm: (0..30)
            .map(|k| 0.5 + (k as f64 * 0.37).sin().abs())
            .collect(),
        after_mm: (0..30)
            .map(|k| 0.05 + 0.02 * (k as f64).cos().abs())
            .collect(),
        labels: labels(),
    }
}

fn charts_to(dir: &std::path::Path, ext: &str) -> Vec<std::path::PathBuf> {
    let x: Vec<f64> = (0..50).map(|k| k as f64 / 49.0).collect();
    let sin = |f: f64| x.iter().map(|s| (f * s).sin()).collect::<Vec<_>>();
    let b = bars();
    let files = [
        ("bars", 0),
        ("hist", 1),
        ("path", 2),
        ("moments", 3),
        ("influence", 4),
        ("scatter", 5),
    ];
    let mut out = Vec::new();
    for (name, k) in files {
        let p = dir.join(format!("{name}.{ext}"));
        match k {
            0 => plot::write(&p, &b).unwrap(),
            1 => plot::write(
                &p,
                &ErrorHistogram {
                    title: "hist".into(),
                    before_mm: b.before_mm.clone(),
                    after_mm: b.after_mm.clone(),
                    bins: 12,
                    labels: labels(),
                },
            )
            .unwrap(),
            2 => plot::write(
                &p,
                &LineChart::path_error(x.clone(), sin(3.0), sin(1.0), ["a", "b"]),
            )
            .unwrap(),
            3 => plot::write(
                &p,
                &LineChart::moments_tilts(
                    x.clone(),
                    vec![Series::new("j2", sin(2.0)), Series::new("j3", sin(4.0))],
                    vec![Series::new("j2", sin(5.0))],
                ),
            )
            .unwrap(),
            4 => plot::write(
                &p,
                &LineChart::influence(vec![Series::new("dth2", sin(7.0))]),
            )
            .unwrap(),
            _ => plot::write(
                &p,
                &Scatter {
                    title: "residual".into(),
                    x_label: "q2 (deg)".into(),
                    y_label: "mm".into(),
                    x: x.clone(),
                    before: sin(2.0),
                    after: sin(0.5),
                    labels: labels(),
                },
            )
            .unwrap(),
        }
        out.push(p);
    }
    out
}

#[test]
fn png_files_decode_to_the_chart_size_and_are_not_blank() {
    let dir = tempfile::tempdir().unwrap();
    for p in charts_to(dir.path(), "png") {
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", p.display());
        let img = image::load_from_memory(&bytes).unwrap().to_rgb8();
        assert!(
            img.width() == 900 && img.height() >= 380,
            "{}: {}x{}",
            p.display(),
            img.width(),
            img.height()
        );
        let non_white = img.pixels().filter(|px| px.0 != [255, 255, 255]).count();
        let frac = non_white as f64 / (img.width() * img.height()) as f64;
        assert!(
            frac > 0.005 && frac < 0.9,
            "{}: {frac} of pixels drawn",
            p.display()
        );
    }
}

#[test]
fn png_text_is_drawn_with_the_embedded_font() {
    // The same chart with and without a long title: the title's glyphs change the pixels in the
    // caption band, which only happens if text is rasterised.
    let dir = tempfile::tempdir().unwrap();
    let mut a = bars();
    a.title = String::new();
    let mut b = bars();
    b.title = "WWWWWWWWWWWWWWWWWWWWWWWW".into();
    let pa = dir.path().join("a.png");
    let pb = dir.path().join("b.png");
    plot::write(&pa, &a).unwrap();
    plot::write(&pb, &b).unwrap();
    let ia = image::open(&pa).unwrap().to_rgb8();
    let ib = image::open(&pb).unwrap().to_rgb8();
    let dark = |img: &image::RgbImage| {
        (0..30)
            .flat_map(|y| (0..img.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0[0] < 128)
            .count()
    };
    assert!(
        dark(&ib) > dark(&ia) + 200,
        "title pixels: {} vs {}",
        dark(&ib),
        dark(&ia)
    );
}

#[test]
fn svg_files_have_an_svg_root_of_the_chart_size() {
    let dir = tempfile::tempdir().unwrap();
    for p in charts_to(dir.path(), "svg") {
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.len() > 1000, "{}", p.display());
        let root = text.find("<svg").expect("svg root");
        assert!(text[root..].contains("width=\"900\""), "{}", p.display());
        assert!(text.trim_end().ends_with("</svg>"), "{}", p.display());
        assert!(text.contains("<text"), "{}: labels", p.display());
    }
}

#[test]
fn bad_data_and_unknown_formats_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let err = plot::write(&dir.path().join("x.jpg"), &bars()).unwrap_err();
    assert!(matches!(err, PlotError::Format { .. }), "{err}");
    let mut b = bars();
    b.after_mm.pop();
    let err = plot::write(&dir.path().join("x.svg"), &b).unwrap_err();
    assert!(matches!(err, PlotError::Data { .. }), "{err}");
    let nan = LineChart::path_error(
        vec![0.0, 1.0],
        vec![f64::NAN; 2],
        vec![f64::NAN; 2],
        ["a", "b"],
    );
    assert!(plot::write(&dir.path().join("n.png"), &nan).is_err());
    assert!(!dir.path().join("x.svg").exists() && !dir.path().join("n.png").exists());
}

#[test]
fn histogram_counts_by_hand() {
    // bins of width 1 over 0..4; 4.0 goes into the last bin; NaN and negatives are not counted
    let c = ErrorHistogram::counts(&[0.1, 0.9, 1.0, 2.5, 4.0, f64::NAN, -1.0], 4, 4.0);
    assert_eq!(c, vec![2, 1, 1, 1]);
}
