//! Unit tests of `potcal.rs`.

use super::*;
use crate::error::Classify;

#[test]
fn two_point_jig_is_exact_and_has_no_residual() {
    let c = PotCalibration::fit(
        &[
            JigPoint {
                raw: 1000.0,
                travel_mm: 2.0,
            },
            JigPoint {
                raw: 3000.0,
                travel_mm: -3.0,
            },
        ],
        1,
    )
    .unwrap();
    // line through the two points: slope -5/2000 mm per count
    assert!((c.travel_mm(2000.0) - (-0.5)).abs() < 1e-12);
    assert!((c.mm_per_count() - (-0.0025)).abs() < 1e-15);
    assert!(c.rms_residual_mm.is_none());
    let back = PotCalibration::from_toml_str(&c.to_toml_string(), Path::new("p.toml")).unwrap();
    assert!((back.travel_mm(1234.0) - c.travel_mm(1234.0)).abs() < 1e-12);
}

#[test]
fn multi_point_residuals_and_nonlinearity_check() {
    // travel = -(raw - 2000)/400 + 1e-7 (raw - 2000)^2: ~0.1 mm of bow over +-1000 counts
    let pts: Vec<JigPoint> = (0..7)
        .map(|k| {
            let raw = 1000.0 + 1000.0 * k as f64 / 3.0;
            let d = raw - 2000.0;
            JigPoint {
                raw,
                travel_mm: -d / 400.0 + 1e-7 * d * d,
            }
        })
        .collect();
    let lin = PotCalibration::fit(&pts, 1).unwrap();
    assert!(lin.rms_residual_mm.unwrap() > 0.01);
    assert!(PotCalibration::nonlinearity(&pts).is_some());
    let quad = PotCalibration::fit(&pts, 2).unwrap();
    assert!(quad.max_residual_mm.unwrap() < 1e-9);
    assert!((quad.travel_mm(2500.0) - (-1.25 + 0.025)).abs() < 1e-9);
    // a straight pot passes the check
    let straight: Vec<JigPoint> = pts
        .iter()
        .map(|p| JigPoint {
            travel_mm: -(p.raw - 2000.0) / 400.0,
            ..*p
        })
        .collect();
    assert!(PotCalibration::nonlinearity(&straight).is_none());
}

#[test]
fn too_few_or_non_monotonic_points_are_refused() {
    let one = [JigPoint {
        raw: 1.0,
        travel_mm: 1.0,
    }; 3];
    assert!(PotCalibration::fit(&one, 1).is_err());
    let zigzag = [
        JigPoint {
            raw: 0.0,
            travel_mm: 0.0,
        },
        JigPoint {
            raw: 1.0,
            travel_mm: 1.0,
        },
        JigPoint {
            raw: 2.0,
            travel_mm: 0.0,
        },
    ];
    assert!(PotCalibration::fit(&zigzag, 2).is_err());
}

#[test]
fn jig_file_forms() {
    let p = Path::new("jig.csv");
    let JigFile::Points(pts) =
        parse_jig_csv("# gauges\nraw,travel_mm\n1000,2\n3000,-3\n", p).unwrap()
    else {
        panic!("points expected")
    };
    assert_eq!(pts.len(), 2);
    let JigFile::Windows(w) = parse_jig_csv("start_s,end_s,travel_mm\n0.5,1.5,1.0\n", p).unwrap()
    else {
        panic!("windows expected")
    };
    assert_eq!(w[0].end_s, 1.5);
    let err = parse_jig_csv("raw,travel_mm\n1000,abc\n", p)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("jig.csv:2") && err.contains("travel_mm"),
        "{err}"
    );
    // every problem is bad input naming the file, the line and the column
    let cases = [
        (
            "# c\nraw,travel_mm\n1000,\n",
            "jig.csv:3: travel_mm: missing value",
        ),
        (
            "raw,travel_mm\n1000,1\nx,2\n",
            "jig.csv:3: raw: not a number (`x`)",
        ),
        (
            "raw,travel\n1000,1\n",
            "jig.csv:1: travel_mm: column missing",
        ),
        (
            "start_s,travel_mm\n1,1\n",
            "jig.csv:1: raw: the header needs `raw`",
        ),
        (
            "start_s,end_s,travel_mm\n1,1,1\n",
            "jig.csv:2: end_s: must be after start_s",
        ),
        (
            "raw,travel_mm\n1,2,3\n",
            "jig.csv:2: row: 3 fields, the header has 2",
        ),
        ("raw,travel_mm\n", "jig.csv:1: rows: no jig rows"),
        (
            "raw,travel_mm,raw\n1,2,3\n",
            "jig.csv:1: raw: column appears twice in the header",
        ),
    ];
    for (text, want) in cases {
        let e = parse_jig_csv(text, p).unwrap_err();
        assert_eq!(e.kind(), crate::error::ErrorKind::BadInput);
        assert!(e.to_string().starts_with(want), "`{e}` vs `{want}`");
    }
    let samples: Vec<PotSample> = (0..3000u64)
        .map(|k| PotSample {
            t_us: 5_000_000 + 1000 * k,
            raw: if k < 1500 { 1000 } else { 3000 },
        })
        .collect();
    let wins = [
        JigWindow {
            start_s: 0.1,
            end_s: 1.0,
            travel_mm: 2.0,
        },
        JigWindow {
            start_s: 2.0,
            end_s: 2.9,
            travel_mm: -3.0,
        },
    ];
    let pts = points_from_windows(&samples, &wins).unwrap();
    assert_eq!((pts[0].raw, pts[1].raw), (1000.0, 3000.0));
}
