//! `rigctl sheet` and `rigctl trace` end to end: files, CSV contract, exit codes.

use rigctl::sheet::ReferencePath;
use rigctl::trace::synth::{render_scan, RenderSpec};
use std::path::Path;
use std::process::Output;

use super::common::spawn::rigctl;

/// `rigctl trace SCAN --out OUT`.
pub(crate) fn trace_to(scan: &Path, out: &Path) -> Output {
    rigctl()
        .arg("trace")
        .arg(scan)
        .arg("--out")
        .arg(out)
        .output()
        .expect("run")
}

fn circle_scan(dir: &std::path::Path, mirrored: bool) -> std::path::PathBuf {
    let n = 6_284;
    let pencil: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [100.2 * a.cos(), 100.2 * a.sin()]
        })
        .collect();
    let spec = RenderSpec {
        dpi: 300.0,
        pencil_mm: pencil,
        pencil_closed: true,
        reference: Some(ReferencePath::Circle),
        rotation_deg: 1.0,
        mirrored,
        ..RenderSpec::default()
    };
    let path = dir.join(if mirrored { "mirrored.png" } else { "scan.png" });
    render_scan(&spec).save(&path).expect("save png");
    path
}

#[test]
fn sheet_writes_an_a4_svg() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("sheet.svg");
    let st = rigctl()
        .args(["sheet", "--out"])
        .arg(&out)
        .args(["--path", "circle", "--path", "line"])
        .status()
        .expect("run");
    assert!(st.success());
    let svg = std::fs::read_to_string(&out).expect("svg");
    assert!(
        svg.contains(r#"viewBox="0 0 210 297""#)
            && svg.contains("<line ")
            && svg.contains("expected 180.0 mm")
    );
}

#[test]
fn trace_writes_csv_along_the_circle() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scan = circle_scan(dir.path(), false);
    let out = dir.path().join("trace.csv");
    let o = trace_to(&scan, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(&out).expect("csv");
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("x,y"));
    let pts: Vec<[f64; 2]> = lines
        .map(|l| {
            let (x, y) = l.split_once(',').expect("two columns");
            [x.parse().expect("x"), y.parse().expect("y")]
        })
        .collect();
    assert!(pts.len() > 1250, "{} points", pts.len());
    for w in pts.windows(2) {
        assert!((w[0][0] - w[1][0]).hypot(w[0][1] - w[1][1]) <= 0.5 + 1e-3);
    }
    for p in &pts {
        assert!((p[0].hypot(p[1]) - 100.2).abs() < 0.08, "{p:?}");
    }
}

#[test]
fn trace_exit_codes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mirrored = circle_scan(dir.path(), true);
    let out = dir.path().join("t.csv");
    let o = trace_to(&mirrored, &out);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("mirrored"));
    assert!(!out.exists());
    let o = trace_to(&dir.path().join("missing.png"), &out);
    assert_eq!(o.status.code(), Some(2));
    let o = rigctl()
        .arg("trace")
        .arg(&mirrored)
        .arg("--out")
        .arg(&out)
        .arg("--no-fiducials")
        .output()
        .expect("run");
    assert_eq!(
        o.status.code(),
        Some(2),
        "--no-fiducials without --mm-per-px is a usage error"
    );
}

#[test]
fn a_damaged_scan_png_is_exit_2_naming_the_file_and_nothing_is_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let good = dir.path().join("good.png");
    image::RgbImage::from_fn(640, 480, |x, y| {
        image::Rgb([(x % 251) as u8, (y % 241) as u8, ((x ^ y) % 256) as u8])
    })
    .save(&good)
    .expect("save");
    let bytes = std::fs::read(&good).expect("read");
    let mut flipped = bytes.clone();
    flipped[bytes.len() / 2] ^= 0x40; // inside the image data: its chunk's CRC no longer holds
    let cases = [
        ("cut.png", bytes[..bytes.len() / 2].to_vec(), "ends inside"),
        ("flipped.png", flipped, "Png"),
    ];
    for (name, data, says) in cases {
        let scan = dir.path().join(name);
        std::fs::write(&scan, data).expect("write");
        let out = dir.path().join(format!("{name}.csv"));
        let o = trace_to(&scan, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(name) && err.contains(says), "{name}: {err}");
        assert!(!out.exists(), "{name}: nothing written");
    }
}
