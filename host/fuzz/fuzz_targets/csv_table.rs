//! Arbitrary text through every CSV reader built on the shared table reader (pose files, jig
//! files, fused samples): errors are fine, panics are not, and accepted values are in range.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rigctl::io::pose_csv::{parse_poses, PoseSpec};
use rigctl::io::table::Table;
use std::path::Path;
use std::sync::OnceLock;

fn spec() -> &'static PoseSpec {
    static SPEC: OnceLock<PoseSpec> = OnceLock::new();
    SPEC.get_or_init(|| {
        let model = rigctl::model::katana450(0.0).expect("preset");
        PoseSpec::for_model(&model, false)
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(table) = Table::parse(text, "fuzz.csv") {
        for row in &table.rows {
            for col in 0..table.header.len() {
                if let Ok(Some(v)) = table.optional_number(row, col) {
                    assert!(v.is_finite() && v.abs() <= 1e12);
                }
            }
        }
    }
    if let Ok(poses) = parse_poses(text, "fuzz.csv", spec()) {
        for p in &poses.poses {
            assert!(p.q.iter().all(|q| q.is_finite()));
        }
    }
    let path = Path::new("fuzz.csv");
    let _ = rigctl::fusion::potcal::parse_jig_csv(text, path);
    let _ = rigctl::fusion::fuse::parse_fused(text, path, 5);
});
