//! Pose CSV reading (FORMATS.md): what is accepted, and every bad-input rule with the file,
//! line and column it must name.

use crate::common;

use rigctl::error::{Classify, ErrorKind};
use rigctl::io::pose_csv::{parse_poses, read_poses, PoseCsvError, PoseSpec};
use rigctl::io::table::TableError;
use rigctl::model::katana450;

fn spec(require_xyz: bool) -> PoseSpec {
    PoseSpec::for_model(&katana450(200.0).unwrap(), require_xyz)
}

#[test]
fn reads_columns_comments_and_extras() {
    let text = "\u{feff}# a comment\n\
                id,t,q1,q2,q3,q4,q5,note,x,y,z\n\
                \n\
                p1, 0.5,1,2,3,4,5,first,10,20,30\r\n\
                # another comment\n\
                p2,1.5,-1,-2,-3,-4,-5,,11,21,31\n";
    let f = parse_poses(text, "mem.csv", &spec(true)).unwrap();
    assert_eq!(f.poses.len(), 2);
    assert_eq!(f.extra_columns, ["note"]);
    let p = &f.poses[0];
    assert_eq!((p.line, p.id.as_deref(), p.t_s), (4, Some("p1"), Some(0.5)));
    assert_eq!(p.q, [1.0, 2.0, 3.0, 4.0, 5.0]);
    assert_eq!(p.xyz_mm, Some([10.0, 20.0, 30.0]));
    assert_eq!(f.poses[1].line, 6);
    assert_eq!(f.extra(0, "note"), Some("first"));
    assert_eq!(f.extra(1, "note"), Some(""));
    // x,y,z are optional for FK input.
    let f = parse_poses("q5,q4,q3,q2,q1\n5,4,3,2,1\n", "mem.csv", &spec(false)).unwrap();
    assert_eq!(f.poses[0].q, [1.0, 2.0, 3.0, 4.0, 5.0]);
    assert_eq!(f.poses[0].xyz_mm, None);
    assert_eq!(f.positions_mm(), None);
}

/// FORMATS.md: other columns are kept and ignored, also when their names look like numbered
/// points (`x1`, `z2`); with plain `x,y,z` those are the measurement. Without plain `x,y,z`
/// the numbered points are the measurement (README "Pose files: extensions").
#[test]
fn plain_xyz_wins_over_columns_named_like_numbered_points() {
    let text = "q1,q2,q3,q4,q5,z2,x,y,z,x1
1,2,3,4,5,junk,10,20,30,
";
    let f = parse_poses(text, "mem.csv", &spec(true)).unwrap();
    assert_eq!(f.poses[0].xyz_mm, Some([10.0, 20.0, 30.0]));
    assert_eq!(f.poses[0].markers_mm, [[10.0, 20.0, 30.0]]);
    assert_eq!(f.n_markers(), 1);
    assert_eq!(f.extra_columns, ["z2", "x1"]);
    assert_eq!(f.extra(0, "z2"), Some("junk"));
    // The same without the plain point: two numbered points.
    let text = "q1,q2,q3,q4,q5,x1,y1,z1,x2,y2,z2
1,2,3,4,5,1,2,3,4,5,6
";
    let f = parse_poses(text, "mem.csv", &spec(true)).unwrap();
    assert_eq!(f.poses[0].markers_mm, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(f.poses[0].xyz_mm, Some([1.0, 2.0, 3.0]));
    assert!(f.extra_columns.is_empty());
    // Incomplete groups without a complete plain x,y,z stay bad input naming the column.
    for (text, column) in [
        (
            "q1,q2,q3,q4,q5,x1,y1,x2,y2,z2
0,0,0,0,0,1,2,3,4,5
",
            "`z1`",
        ),
        (
            "q1,q2,q3,q4,q5,x,y,x1,y1,z1
0,0,0,0,0,1,2,3,4,5
",
            "`x`",
        ),
        (
            "q1,q2,q3,q4,q5,x0,y0,z0
0,0,0,0,0,1,2,3
",
            "`x1`",
        ),
    ] {
        let msg = parse_poses(text, "p.csv", &spec(false))
            .unwrap_err()
            .to_string();
        assert!(msg.starts_with("p.csv:1: "), "{msg}");
        assert!(msg.contains(column), "`{msg}` should name {column}");
    }
}

/// Each rule: text, expected line, a fragment the message must contain.
#[test]
fn every_bad_input_rule_names_file_line_and_column() {
    let h = "q1,q2,q3,q4,q5,x,y,z\n";
    let ok = "0,0,0,0,0,1,2,3\n";
    let cases: Vec<(String, bool, usize, &str)> = vec![
        (
            format!("{h}{ok}0,0,,0,0,1,2,3\n"),
            true,
            3,
            "column `q3`: missing value",
        ),
        (
            format!("{h}{ok}0,0,abc,0,0,1,2,3\n"),
            true,
            3,
            "column `q3`: not a number",
        ),
        (
            format!("{h}{ok}0,0,0,0,0,NaN,2,3\n"),
            true,
            3,
            "column `x`: NaN",
        ),
        (
            format!("{h}{ok}0,0,0,0,0,1,inf,3\n"),
            true,
            3,
            "column `y`: infinite",
        ),
        (
            format!("{h}{ok}{ok}0,0,0,0,0,1,2\n"),
            true,
            4,
            "7 fields, the header has 8",
        ),
        (format!("{h}0,0,0,0,0,1,2,3,4\n"), true, 2, "9 fields"),
        (
            format!("{h}{ok}0,103,0,0,0,1,2,3\n"),
            true,
            3,
            "column `q2`: joint value 103 outside the limits [-30, 102]",
        ),
        (format!("{h}-170,0,0,0,0,1,2,3\n"), true, 2, "column `q1`"),
        (
            "# c\nq1,q2,q3,q4,x,y,z\n0,0,0,0,1,2,3\n".to_string(),
            true,
            2,
            // issue 50: another robot's file is said to be one, not "column `q5` is missing"
            "4 joints in the file (q1..q4), 5 in the model",
        ),
        (
            "q1,q2,q3,q4,q5\n0,0,0,0,0\n".to_string(),
            true,
            1,
            "column `x` is missing",
        ),
        (
            "q1,q2,q3,q4,q5,x,y\n0,0,0,0,0,1,2\n".to_string(),
            false,
            1,
            "column `z` is missing",
        ),
        (
            "q1,q2,q3,q4,q5,q1\n0,0,0,0,0,0\n".to_string(),
            false,
            1,
            "column `q1` appears twice",
        ),
        (
            "q1,q2,q3,q4,q5,t\n0,0,0,0,0,soon\n".to_string(),
            false,
            2,
            "column `t`: not a number",
        ),
    ];
    for (text, require_xyz, line, fragment) in cases {
        let err = parse_poses(&text, "poses.csv", &spec(require_xyz)).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::BadInput);
        let msg = err.to_string();
        assert!(
            msg.starts_with(&format!("poses.csv:{line}: ")),
            "`{msg}` should name poses.csv line {line}"
        );
        assert!(
            msg.contains(fragment),
            "`{msg}` should contain `{fragment}`"
        );
    }
}

#[test]
fn empty_files_and_missing_files() {
    for text in ["", "# only a comment\n"] {
        assert!(matches!(
            parse_poses(text, "e.csv", &spec(false)),
            Err(PoseCsvError::Table(TableError::NoHeader { .. }))
        ));
    }
    assert!(matches!(
        parse_poses("q1,q2,q3,q4,q5\n", "e.csv", &spec(false)),
        Err(PoseCsvError::NoPoses { .. })
    ));
    let err = read_poses(std::path::Path::new("/nonexistent/p.csv"), &spec(false)).unwrap_err();
    assert!(err.to_string().contains("/nonexistent/p.csv"));
    assert_eq!(err.kind(), ErrorKind::BadInput);
}

#[test]
fn reads_the_shared_ur5_pose_files() {
    let Some(shared) = common::shared_file(
        "reads_the_shared_ur5_pose_files",
        "data/real/ur5_laser_tracker",
    ) else {
        return;
    };
    let model = rigctl::model::ur5().unwrap();
    let f = read_poses(&shared.join("grid.csv"), &PoseSpec::for_model(&model, true)).unwrap();
    assert_eq!(f.poses.len(), 1000);
    assert!(f.poses.iter().all(|p| p.id.is_some() && p.xyz_mm.is_some()));
}
