//! Messages about a user's files that say what is wrong in the file's own terms (issue 50):
//! a joint value quoted in the file's unit with the other unit suggested, unknown URDF links
//! listed nearest first, a German spreadsheet export read with `--sep ';' --decimal ','` or
//! named when not declared, UTF-16 text read (with a byte-order mark) or named (without), and
//! another robot's joint count said as such.

use std::path::Path;

use super::common::spawn::{rig, Run};
use super::hostile_inputs::URDF;

fn refused(r: &Run, what: &str) -> String {
    assert_eq!(r.code, Some(2), "{what}: {}", r.show());
    r.stderr.clone()
}

fn ok(r: &Run, what: &str) -> String {
    assert_eq!(r.code, Some(0), "{what}: {}", r.show());
    r.stdout.clone()
}

/// Katana joint rows (deg): well inside the limits.
const ROWS_DEG: [[f64; 5]; 3] = [
    [-63.5, 40.25, 10.0, -20.5, 30.0],
    [12.0, 60.0, -50.0, 45.0, -90.0],
    [100.0, 0.5, 80.0, 0.0, 120.0],
];

fn joints_csv(sep: &str, decimal: char) -> String {
    let mut s = ["q1", "q2", "q3", "q4", "q5"].join(sep) + "\n";
    for r in ROWS_DEG {
        let cells: Vec<String> = r
            .iter()
            .map(|v| format!("{v:.2}").replace('.', &decimal.to_string()))
            .collect();
        s += &(cells.join(sep) + "\n");
    }
    s
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn a_joint_out_of_limits_is_quoted_in_the_files_unit() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "deg.csv", joints_csv(",", '.'));
    // a file in degrees declared as radians
    let err = refused(
        &rig!(30; "fk", "--joints", f, "--units", "mm,rad"),
        "deg as rad",
    );
    assert!(
        err.contains("column `q1`: joint value -63.5 outside the limits [-2.958"),
        "{err}"
    );
    assert!(
        err.contains("] rad; read as deg it is within them"),
        "{err}"
    );
    assert!(err.contains("--units mm,deg"), "{err}");
    // not the converted value (-63.5 rad = -3638.28 deg)
    assert!(!err.contains("3638"), "{err}");
    // a value out of limits in either unit gets no suggestion
    let f = write(dir.path(), "far.csv", "q1,q2,q3,q4,q5\n400,1,1,1,1\n");
    let err = refused(&rig!(30; "fk", "--joints", f), "400 deg");
    assert!(
        err.contains("joint value 400 outside the limits [-169.5, 169.5] deg"),
        "{err}"
    );
    assert!(!err.contains("read as"), "{err}");
}

#[test]
fn an_unknown_urdf_link_lists_the_links_nearest_first() {
    let dir = tempfile::tempdir().unwrap();
    let u = write(dir.path(), "u.urdf", URDF);
    let out = dir.path().join("m.toml");
    let err = refused(
        &rig!(30; "urdf2model", "--urdf", u, "--tip", "link2", "--out", out),
        "typo'd tip",
    );
    assert!(
        err.contains("no link `link2`; its links, nearest first: `l2`, `l1`, `base`"),
        "{err}"
    );
    let err = refused(
        &rig!(30; "urdf2model", "--urdf", u, "--base-link", "base_link", "--tip", "l2", "--out", out),
        "base_link",
    );
    assert!(
        err.contains("no link `base_link`; its links, nearest first: `base`,"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn a_german_spreadsheet_export_is_read_with_sep_and_decimal_or_named() {
    let dir = tempfile::tempdir().unwrap();
    let plain = write(dir.path(), "plain.csv", joints_csv(",", '.'));
    let german = write(dir.path(), "german.csv", joints_csv(";", ','));
    let want = ok(&rig!(30; "fk", "--joints", plain), "plain");
    let err = refused(&rig!(30; "fk", "--joints", german), "undeclared");
    assert!(
        err.contains(
            "the file looks like `;`-separated with decimal commas: use --sep ';' --decimal ','"
        ),
        "{err}"
    );
    assert!(err.contains("german.csv:1"), "{err}");
    let got = ok(
        &rig!(30; "fk", "--joints", german, "--sep", ";", "--decimal", ","),
        "declared",
    );
    assert_eq!(got, want);
    // --sep ';' alone on decimal commas names the missing flag
    let err = refused(
        &rig!(30; "fk", "--joints", german, "--sep", ";"),
        "sep only",
    );
    assert!(err.contains("--decimal ','"), "{err}");
    // a `;`-separated instrument log for `poses`
    let p = write(
        dir.path(),
        "p.csv",
        "t;x;y;z\n0,0;1,5;2,5;3,5\n0,1;1,5;2,5;3,5\n",
    );
    let j = write(
        dir.path(),
        "j.csv",
        "t,q1,q2,q3,q4,q5\n0,1,2,3,4,5\n0.1,1,2,3,4,5\n0.2,1,2,3,4,5\n",
    );
    let err = refused(
        &rig!(30; "poses", "--joints", j, "--points", p, "--out", dir.path().join("o.csv")),
        "poses",
    );
    assert!(err.contains("--sep ';' --decimal ','"), "{err}");
}

#[test]
fn utf16_is_read_with_a_byte_order_mark_and_named_without() {
    let dir = tempfile::tempdir().unwrap();
    let text = joints_csv(",", '.');
    let plain = write(dir.path(), "plain.csv", &text);
    let want = ok(&rig!(30; "fk", "--joints", plain), "plain");
    let mut le = vec![0xFF, 0xFE];
    le.extend(text.encode_utf16().flat_map(u16::to_le_bytes));
    let f = write(dir.path(), "utf16.csv", &le);
    assert_eq!(
        ok(&rig!(30; "fk", "--joints", f), "UTF-16 LE with BOM"),
        want
    );
    let f = write(dir.path(), "nobom.csv", &le[2..]);
    let err = refused(&rig!(30; "fk", "--joints", f), "UTF-16 without BOM");
    assert!(err.contains("UTF-16"), "{err}");
}

#[test]
fn another_robots_file_is_said_to_have_fewer_joints() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "katana.csv", joints_csv(",", '.'));
    let err = refused(&rig!(30; "fk", "--robot", "ur5", "--joints", f), "5 vs 6");
    assert!(
        err.contains("5 joints in the file (q1..q5), 6 in the model (not in the file: q6)"),
        "{err}"
    );
    assert!(!err.contains("column `q6` is missing"), "{err}");
}
