//! Arbitrary text through the CSV readers built on the shared table reader: errors are fine,
//! panics are not, and accepted values are in range. The first byte chooses the reader (`0`
//! the bare table with its range checks, `1` pose files, `2` jig files, `3` fused samples; the
//! byte modulo 4), the rest is the file: one parse per input instead of four, and the corpus
//! specialises per reader (the seeds in `seeds/csv_table` start with that digit).
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
    let Some((&reader, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let path = Path::new("fuzz.csv");
    match reader % 4 {
        0 => {
            if let Ok(table) = Table::parse(text, "fuzz.csv") {
                for row in &table.rows {
                    for col in 0..table.header.len() {
                        if let Ok(Some(v)) = table.optional_number(row, col) {
                            assert!(v.is_finite() && v.abs() <= 1e12);
                        }
                    }
                }
            }
        }
        1 => {
            if let Ok(poses) = parse_poses(text, "fuzz.csv", spec()) {
                for p in &poses.poses {
                    assert!(p.q.iter().all(|q| q.is_finite()));
                }
            }
        }
        2 => {
            let _ = rigctl::fusion::potcal::parse_jig_csv(text, path);
        }
        _ => {
            let _ = rigctl::fusion::fused_file::parse_fused(text, path, 5);
        }
    }
});
