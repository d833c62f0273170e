//! Joint logs from ROS 2 bags written by a producer rigctl did not write (rosbags, PyPI, in the
//! venv of `common::python_env`; no ROS install): a simulated session's joint log as a rosbag2
//! directory with extra joints, other topics, messages in other name orders and messages that
//! lack the model's joints; `fuse` and `fk` from the bag equal those from the CSV; a truncated
//! bag reads what is intact and says what was lost; 10^6 messages stream in bounded memory.

use crate::common;
use crate::common::record::record;
use crate::common::spawn::{self, output};

use crate::common::spawn::{output_ok as ok, path_arg as s};
use std::path::Path;
use std::process::Command;

fn write_bag(py: &Path, args: &[&str]) {
    let out = Command::new(py)
        .arg(common::py_script("write_bag.py"))
        .args(args)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "write_bag.py {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Rows of numbers of a CSV (comment and header lines compared as text, returned apart).
fn numbers(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut head = Vec::new();
    let mut rows = Vec::new();
    for l in text.lines() {
        match l
            .split(',')
            .map(|c| c.trim().parse::<f64>())
            .collect::<Result<Vec<f64>, _>>()
        {
            Ok(r) if !l.starts_with('#') => rows.push(r),
            _ => head.push(l.to_string()),
        }
    }
    (head, rows)
}

/// Largest difference between two CSV texts of the same shape (headers equal).
fn max_diff(a: &str, b: &str) -> f64 {
    let (ha, ra) = numbers(a);
    let (hb, rb) = numbers(b);
    assert_eq!(ha, hb, "header lines");
    assert_eq!(ra.len(), rb.len(), "row counts");
    assert!(!ra.is_empty());
    let mut worst = 0.0f64;
    for (x, y) in ra.iter().zip(&rb) {
        assert_eq!(x.len(), y.len());
        for (u, v) in x.iter().zip(y) {
            worst = worst.max((u - v).abs());
        }
    }
    worst
}

const KATANA_NAMES: &str = "katana_motor1_pan_joint,katana_motor2_lift_joint,katana_motor3_lift_joint,katana_motor4_lift_joint,katana_motor5_wrist_roll_joint";

#[test]
fn fuse_and_fk_from_a_rosbags_bag_equal_the_csv() {
    let Some(py) = common::python_env("fuse_and_fk_from_a_rosbags_bag_equal_the_csv") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sim = d.join("s");
    ok(&["simulate", "--session", "circle", "--out", s(&sim)]);
    let trace = sim.join("trace.csv");
    ok(&["trace", s(&sim.join("scan.png")), "--out", s(&trace)]);
    let pot = sim.join("pot.toml");
    ok(&[
        "potcal",
        "--points",
        s(&sim.join("potjig.csv")),
        "--out",
        s(&pot),
    ]);
    let joints_csv = sim.join("joints.csv");
    let bag = d.join("session_bag");
    write_bag(
        &py,
        &[
            "csv",
            s(&joints_csv),
            s(&bag),
            "--names",
            KATANA_NAMES,
            "--extra",
            "katana_r_finger_joint,katana_l_finger_joint",
            "--other-topic",
            "--shuffle",
            "--partial-every",
            "25",
        ],
    );
    let (rec, placement) = (sim.join("pot.rec"), sim.join("placement.toml"));
    let fuse = |joints: &Path, out: &Path, extra: &[&str]| {
        let mut args = vec![
            "fuse",
            "--joints",
            s(joints),
            "--recording",
            s(&rec),
            "--trace",
            s(&trace),
            "--placement",
            s(&placement),
            "--pot",
            s(&pot),
            "--out",
            s(out),
        ];
        args.extend_from_slice(extra);
        ok(&args)
    };
    let from_csv = d.join("fused_csv.csv");
    let from_bag = d.join("fused_bag.csv");
    let a = fuse(&joints_csv, &from_csv, &[]);
    let b = fuse(&bag, &from_bag, &["--joint-names", KATANA_NAMES]);
    assert_eq!(a.stdout, b.stdout, "the same fusion report");
    let fused_a = std::fs::read_to_string(&from_csv).unwrap();
    let fused_b = std::fs::read_to_string(&from_bag).unwrap();
    let worst = max_diff(&fused_a, &fused_b);
    let n_rows = numbers(&fused_a).1.len();
    eprintln!("fuse: {n_rows} fused samples, bag vs CSV max difference {worst:.3e}");
    record("fuse_bag_vs_csv_worst", worst);
    assert!(worst <= 1e-6, "fused samples differ by {worst}");
    // The messages of the gripper controller (only the finger joints) are skipped and counted.
    let n_joint_rows = numbers(&std::fs::read_to_string(&joints_csv).unwrap())
        .1
        .len();
    let partial = n_joint_rows.div_ceil(25);
    let err = String::from_utf8_lossy(&b.stderr);
    assert!(
        err.contains(&format!(
            "skipped {partial} of {} messages that lack a needed joint",
            n_joint_rows + partial
        )),
        "{err}"
    );

    // fk: the same positions.
    let fk_csv = ok(&["fk", "--joints", s(&joints_csv)]);
    let fk_bag = ok(&["fk", "--joints", s(&bag), "--joint-names", KATANA_NAMES]);
    let worst_fk = max_diff(
        &String::from_utf8_lossy(&fk_csv.stdout),
        &String::from_utf8_lossy(&fk_bag.stdout),
    );
    eprintln!("fk: bag vs CSV max difference {worst_fk:.3e}");
    record("fk_bag_vs_csv_worst", worst_fk);
    assert!(worst_fk <= 1e-6, "fk differs by {worst_fk}");

    // zstd-compressed chunks (rosbag2's storage compression) read the same.
    let zbag = d.join("zstd_bag");
    write_bag(
        &py,
        &[
            "csv",
            s(&joints_csv),
            s(&zbag),
            "--names",
            KATANA_NAMES,
            "--extra",
            "katana_r_finger_joint,katana_l_finger_joint",
            "--other-topic",
            "--shuffle",
            "--partial-every",
            "25",
            "--zstd",
        ],
    );
    let fk_zstd = ok(&["fk", "--joints", s(&zbag), "--joint-names", KATANA_NAMES]);
    assert_eq!(fk_zstd.stdout, fk_bag.stdout);

    // The bare .mcap file reads the same.
    let mcap = bag.join("session_bag.mcap");
    let fk_mcap = ok(&["fk", "--joints", s(&mcap), "--joint-names", KATANA_NAMES]);
    assert_eq!(fk_mcap.stdout, fk_bag.stdout);

    // Wrong names, topic or options are bad input (exit 2) naming what is wrong.
    let no_names = output(&["fk", "--joints", s(&bag)]);
    assert_eq!(no_names.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&no_names.stderr).contains("--joint-names"));
    let wrong = output(&["fk", "--joints", s(&bag), "--joint-names", "a,b,c,d,e"]);
    assert_eq!(wrong.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&wrong.stderr).contains("joint `a`"));
    let topic = output(&[
        "fk",
        "--joints",
        s(&bag),
        "--joint-names",
        KATANA_NAMES,
        "--joint-topic",
        "/rosout_text",
    ]);
    assert_eq!(topic.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&topic.stderr).contains("std_msgs/msg/String"));
    let csv_opt = output(&[
        "fk",
        "--joints",
        s(&joints_csv),
        "--joint-names",
        KATANA_NAMES,
    ]);
    assert_eq!(csv_opt.status.code(), Some(2));
}

const UR5_NAMES: &str =
    "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint";

#[test]
fn truncated_bag_reads_what_is_intact_and_says_what_was_lost() {
    let Some(py) = common::python_env("truncated_bag_reads_what_is_intact_and_says_what_was_lost")
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bag = d.join("bag");
    let n = 20_000;
    write_bag(
        &py,
        &[
            "synthetic",
            s(&bag),
            "--count",
            &n.to_string(),
            "--names",
            UR5_NAMES,
            "--extra",
            "gripper_joint",
        ],
    );
    let fk = |joints: &Path| {
        output(&[
            "fk",
            "--robot",
            "ur5",
            "--joints",
            s(joints),
            "--joint-names",
            UR5_NAMES,
        ])
    };
    let full = fk(&bag);
    assert!(full.status.success());
    assert!(
        full.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&full.stderr)
    );
    let full_rows: Vec<&[u8]> = full.stdout.split(|b| *b == b'\n').collect();
    assert_eq!(full_rows.len(), n + 2, "header, rows and the final newline");

    // Cut the bag's file at 60 %: what is intact is read, the loss is counted from the metadata.
    let cut = d.join("cut");
    std::fs::create_dir(&cut).unwrap();
    std::fs::copy(bag.join("metadata.yaml"), cut.join("metadata.yaml")).unwrap();
    let bytes = std::fs::read(bag.join("bag.mcap")).unwrap();
    std::fs::write(cut.join("bag.mcap"), &bytes[..bytes.len() * 6 / 10]).unwrap();
    let part = fk(&cut);
    assert!(
        part.status.success(),
        "{}",
        String::from_utf8_lossy(&part.stderr)
    );
    let rows: Vec<&[u8]> = part.stdout.split(|b| *b == b'\n').collect();
    let read = rows.len() - 2;
    assert!(read > n / 3 && read < n * 6 / 10, "{read} messages read");
    assert_eq!(
        rows[..rows.len() - 1],
        full_rows[..rows.len() - 1],
        "the intact part is exact"
    );
    let err = String::from_utf8_lossy(&part.stderr);
    eprintln!("truncated bag: {read} of {n} rows; stderr: {err}");
    assert!(err.contains("damaged or cut short"), "{err}");
    assert!(
        err.contains(&format!(
            "{} of the {n} messages the metadata counts lost",
            n - read
        )),
        "{err}"
    );
    // The bare file: the count of what followed is unknown, and said so.
    let bare = fk(&cut.join("bag.mcap"));
    assert!(bare.status.success());
    assert_eq!(bare.stdout, part.stdout);
    assert!(String::from_utf8_lossy(&bare.stderr).contains("how many followed is unknown"));
    // Nothing usable: bad input.
    std::fs::write(cut.join("bag.mcap"), &bytes[..200]).unwrap();
    let none = fk(&cut);
    assert_eq!(none.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&none.stderr).contains("no usable"));
    std::fs::write(d.join("text.mcap"), "not a bag\n").unwrap();
    let text = fk(&d.join("text.mcap"));
    assert_eq!(text.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&text.stderr).contains("not an MCAP file"));
}

#[test]
fn a_million_messages_stream_in_bounded_memory() {
    let Some(py) = common::python_env("a_million_messages_stream_in_bounded_memory") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bag = d.join("long");
    let n = 1_000_000usize;
    write_bag(
        &py,
        &[
            "synthetic",
            s(&bag),
            "--count",
            &n.to_string(),
            "--names",
            UR5_NAMES,
            "--extra",
            "finger_1,finger_2,finger_3,finger_4",
        ],
    );
    let bag_bytes = std::fs::metadata(bag.join("long.mcap")).unwrap().len();
    // The peak RSS and wall time of rigctl alone: a Python parent that runs it and reads its
    // rusage.
    let out = d.join("fk.csv");
    let probe = "import resource, subprocess, sys, time\n\
         with open(sys.argv[1], 'wb') as f:\n\
         \x20   t0 = time.monotonic()\n\
         \x20   r = subprocess.run(sys.argv[2:], stdout=f, stderr=subprocess.PIPE)\n\
         \x20   wall_s = time.monotonic() - t0\n\
         sys.stderr.write(r.stderr.decode())\n\
         print(r.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, wall_s)\n";
    let run = Command::new("python3")
        .args(["-c", probe, s(&out)])
        .arg(spawn::bin())
        .args([
            "fk",
            "--robot",
            "ur5",
            "--joints",
            s(&bag),
            "--joint-names",
            UR5_NAMES,
        ])
        .output()
        .expect("python3 runs");
    let text = String::from_utf8_lossy(&run.stdout);
    let mut it = text.split_whitespace();
    let code: i32 = it.next().and_then(|v| v.parse().ok()).expect("exit code");
    let rss_kb: u64 = it.next().and_then(|v| v.parse().ok()).expect("max rss");
    let wall_s: f64 = it.next().and_then(|v| v.parse().ok()).expect("wall time");
    assert_eq!(code, 0, "{}", String::from_utf8_lossy(&run.stderr));
    let rows = std::fs::read(&out)
        .unwrap()
        .iter()
        .filter(|b| **b == b'\n')
        .count();
    assert_eq!(rows, n + 1, "a row per message");
    eprintln!(
        "{n} messages, bag {:.1} MB: rigctl fk peak RSS {:.1} MB, {wall_s:.2} s",
        bag_bytes as f64 / 1e6,
        rss_kb as f64 / 1e3
    );
    record("million_messages_fk_peak_rss_mb", rss_kb as f64 / 1e3);
    record("million_messages_fk_wall_s", wall_s);
    assert!(
        rss_kb < 64 * 1024,
        "peak RSS {rss_kb} kB for a {bag_bytes}-byte bag: not streamed"
    );
}
