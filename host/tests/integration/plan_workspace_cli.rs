//! `rigctl plan --box X0,Y0,Z0,X1,Y1,Z1` and `--visible-from X,Y,Z` in the comma form the
//! README documents (negative coordinates included): every planned tool point inside the box;
//! a wrong count is exit 2 naming the option, nothing written.

use super::common::spawn::rigctl;

fn plan(dir: &std::path::Path, extra: &[&str]) -> (std::process::Output, std::path::PathBuf) {
    let out = dir.join("p.csv");
    let o = rigctl()
        .args([
            "plan",
            "--robot",
            "katana450",
            "--n",
            "10",
            "--candidates",
            "1500",
        ])
        .arg("--out")
        .arg(&out)
        .args(extra)
        .output()
        .expect("rigctl runs");
    (o, out)
}

#[test]
fn box_and_line_of_sight_in_the_documented_form() {
    let dir = tempfile::tempdir().unwrap();
    let (o, out) = plan(dir.path(), &["--box", "-400,-400,50,400,400,500"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 10);
    for r in &rows {
        let p = &r[5..8];
        assert!(
            (-400.0..=400.0).contains(&p[0])
                && (-400.0..=400.0).contains(&p[1])
                && (50.0..=500.0).contains(&p[2]),
            "{p:?} outside the box"
        );
    }
    std::fs::remove_file(&out).unwrap();
    let (o, _) = plan(
        dir.path(),
        &["--visible-from", "0,-1500,800", "--cone-deg", "80"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_file(&out).unwrap();
    let (o, out) = plan(dir.path(), &["--box", "1,2,3"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--box"));
    assert!(!out.exists(), "nothing written");
}
