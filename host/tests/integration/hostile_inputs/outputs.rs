//! Hostile outputs (docs/reliability.md, items 1, 7 and 9): an output that is an input is
//! refused (exit 2) and the input kept, every output checked before the work, unusable output
//! paths are bad input, concurrent runs into one folder leave the files of one run.

use std::process::Stdio;

use super::{refused_and_kept, simulated, URDF};
use crate::common::spawn::{rig, rigctl};

// ---------------------------------------------------------------------------------------------
// 1. An output that is an input is refused (exit 2), the input kept; all outputs checked first.

#[test]
fn item1_output_equal_to_an_input_is_refused_and_the_input_kept() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(dir.path());
    let cal = sim.join("cal.csv");
    let val = sim.join("val.csv");
    let cal_bytes = std::fs::read(&cal).unwrap();
    let val_bytes = std::fs::read(&val).unwrap();
    let scan = dir.path().join("S.png");
    std::fs::write(&scan, b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let scan_bytes = std::fs::read(&scan).unwrap();
    let jig = dir.path().join("jig.csv");
    std::fs::write(&jig, "raw,travel_mm\n1000,0\n2000,5\n3000,10\n").unwrap();
    let jig_bytes = std::fs::read(&jig).unwrap();
    let urdf = dir.path().join("u.urdf");
    std::fs::write(&urdf, URDF).unwrap();
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink(&cal, &link).unwrap();

    let r = rig!(60; "trace", scan, "--out", scan);
    refused_and_kept(&r, &scan, &scan_bytes, "trace --out SCAN");
    let r = rig!(60; "trace", scan, "--out", dir.path().join("t.csv"), "--overlay", scan);
    refused_and_kept(&r, &scan, &scan_bytes, "trace --overlay SCAN");
    let r = rig!(60; "calibrate", "--poses", cal, "--json", cal);
    refused_and_kept(&r, &cal, &cal_bytes, "calibrate --json CAL");
    let r = rig!(60; "calibrate", "--poses", cal, "--validate", val, "--out", val);
    refused_and_kept(&r, &val, &val_bytes, "calibrate --out VAL");
    let r = rig!(60; "calibrate", "--poses", cal, "--out", link);
    refused_and_kept(&r, &cal, &cal_bytes, "calibrate --out LINK-TO-CAL");
    let r = rig!(60; "diagnose", "--poses", cal, "--validate", val, "--json", val);
    refused_and_kept(&r, &val, &val_bytes, "diagnose --json VAL");
    let r = rig!(60; "diagnose", "--poses", cal, "--validate", val, "--out", cal);
    refused_and_kept(&r, &cal, &cal_bytes, "diagnose --out CAL");
    let r = rig!(60; "plan", "--n", "8", "--candidates", "200", "--poses", cal, "--out", cal);
    refused_and_kept(&r, &cal, &cal_bytes, "plan --out CAL");
    let r = rig!(60; "plan", "--n", "8", "--candidates-from", cal, "--out",
        dir.path().join("p.csv"), "--json", cal);
    refused_and_kept(&r, &cal, &cal_bytes, "plan --json CAL");
    let r = rig!(60; "potcal", "--points", jig, "--out", jig);
    refused_and_kept(&r, &jig, &jig_bytes, "potcal --out JIG");
    let r = rig!(60; "urdf2model", "--urdf", urdf, "--tip", "l2", "--out", urdf);
    refused_and_kept(&r, &urdf, URDF.as_bytes(), "urdf2model --out URDF");
    // the same new file as two outputs
    let both = dir.path().join("both.json");
    let r = rig!(60; "calibrate", "--poses", cal, "--json", both, "--out", both);
    assert_eq!(r.code, Some(2), "{}", r.show());
    assert!(!both.exists());
}

#[test]
fn item1_every_output_is_checked_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(dir.path());
    let keep = dir.path().join("keep.json");
    std::fs::write(&keep, "old").unwrap();
    let file = dir.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    let r = rig!(120; "diagnose", "--poses", sim.join("cal.csv"), "--validate",
        sim.join("val.csv"), "--json", keep, "--plots", file);
    refused_and_kept(&r, &keep, b"old", "diagnose --plots FILE");
    // plots into the directory of the inputs would overwrite nothing; an input named as an
    // output directory's file would be
    let r = rig!(60; "simulate", "--model", sim.join("truth.toml"), "--out", sim);
    refused_and_kept(
        &r,
        &sim.join("truth.toml"),
        &std::fs::read(sim.join("truth.toml")).unwrap(),
        "simulate --model DIR/truth.toml --out DIR",
    );
}

// 9. An output that is a directory or under a missing parent is bad input.
#[test]
fn item9_unusable_output_paths_are_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(dir.path());
    let cal = sim.join("cal.csv");
    let r = rig!(60; "calibrate", "--poses", cal, "--json", dir.path());
    assert_eq!(r.code, Some(2), "{}", r.show());
    let r = rig!(60; "calibrate", "--poses", cal, "--json", dir.path().join("no/such/x.json"));
    assert_eq!(r.code, Some(2), "{}", r.show());
    assert!(r.stderr.contains("does not exist"), "{}", r.show());
}

// ---------------------------------------------------------------------------------------------
// 7. Concurrent runs into one directory leave the files of one run.

#[test]
fn item7_concurrent_simulate_runs_leave_one_consistent_set() {
    let dir = tempfile::tempdir().unwrap();
    // a mix needs the runs to interleave: 16 at once, three rounds
    for round in 0..3 {
        let out = dir.path().join(format!("shared{round}"));
        let children: Vec<_> = (1..=16)
            .map(|seed| {
                rigctl()
                    .args(["simulate", "--seed", &seed.to_string(), "--out"])
                    .arg(&out)
                    .stdout(Stdio::null())
                    .stderr(Stdio::null())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for mut c in children {
            assert!(c.wait().unwrap().success());
        }
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap())
                .unwrap();
        let seed = truth["seed"].as_u64().expect("truth.json has the seed");
        let single = dir.path().join(format!("single{round}"));
        let r = rig!(120; "simulate", "--seed", seed.to_string(), "--out", single);
        assert_eq!(r.code, Some(0), "{}", r.show());
        for f in ["cal.csv", "val.csv", "truth.toml", "truth.json"] {
            assert_eq!(
                std::fs::read(out.join(f)).unwrap(),
                std::fs::read(single.join(f)).unwrap(),
                "round {round}: {f} is not from seed {seed}"
            );
        }
    }
}
