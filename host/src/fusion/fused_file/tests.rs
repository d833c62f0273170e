//! Unit tests of `fuse.rs`.

use super::*;
use crate::error::Classify;

#[test]
fn fused_file_round_trip_and_errors() {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let s = FusedSample {
        t_s: 1.25,
        q_deg: vec![1.0, 2.0, 3.0, 4.0, 5.0],
        nominal_mm: Vector3::new(0.1, -300.0, 139.3),
        dev_u_mm: -0.123,
        u: Vector3::new(1.0, 0.0, 0.0),
        dev_n_mm: 0.456,
        n: Vector3::new(0.0, h, h),
    };
    let text = fused_csv(std::slice::from_ref(&s));
    assert!(text.starts_with("# rigctl-fused/1"));
    let back = parse_fused(&text, Path::new("f.csv"), 5).unwrap();
    assert_eq!(back, vec![s.clone()]);
    let e = (s.measured_error_mm() - Vector3::new(-0.123, 0.456 * h, 0.456 * h)).norm();
    assert!(e < 1e-12);
    let bad = text.replace(",-0.123,", ",nan,");
    let msg = parse_fused(&bad, Path::new("f.csv"), 5)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("f.csv:3") && msg.contains("dev_u"), "{msg}");
    // every problem is bad input naming the file, the line and the column
    let cases = [
        (
            text.replace("dev_u,", "dev_v,"),
            "f.csv:2: dev_u: column missing",
        ),
        (
            text.replace(",-0.123,", ",,"),
            "f.csv:3: dev_u: missing value",
        ),
        (
            text.replace(",-0.123,", ","),
            "f.csv:3: row: 16 fields, the header has 17",
        ),
        (
            text.replace(",1,0,0,", ",1,0,0.5,"),
            "f.csv:3: u_x: direction of length",
        ),
        (
            format!("# c\n{}\n", fused_header(5)),
            "f.csv:2: rows: no sample rows",
        ),
        ("# only\n".into(), "f.csv:1: header: no header row"),
    ];
    for (bad, want) in cases {
        let e = parse_fused(&bad, Path::new("f.csv"), 5).unwrap_err();
        assert_eq!(e.kind(), crate::error::ErrorKind::BadInput);
        assert!(e.to_string().starts_with(want), "`{e}` vs `{want}`");
    }
}
