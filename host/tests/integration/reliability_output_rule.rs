//! One output rule for every writer (docs/reliability.md, "One output rule"): the cases of
//! issue 48, items 1 and 2 (here), and a seeded property test over random layouts of symbolic
//! links, hard links and folder aliases between the inputs and outputs of the subcommands that
//! write a folder (`simulate`, `export`, `diagnose --plots`) or one file (`report --html`,
//! `calibrate --out`, `diagnose --json`, `model2urdf`, `plan --out`, `urdf2model`, `potcal`,
//! `compensate`, `trace`, `fuse`; `simulate --session` writes a folder too): no input's bytes
//! ever change (`link_layouts`; `RELIABILITY_SEED=N` draws other layouts).

mod link_layouts;

use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};

use super::common::spawn::{rigctl, text};

/// `rigctl ARGS` in `cwd`: (exit code, stderr).
fn run(cwd: &Path, args: &[&str]) -> (Option<i32>, String) {
    let o = rigctl().current_dir(cwd).args(args).output().unwrap();
    (o.status.code(), text(&o.stderr))
}

/// A workspace: RUN/ (a simulated run: cal.csv, val.csv, truth.toml, truth.json), M.toml (a
/// model), M.urdf (it as a URDF), a pencil session (REC its recording, SCAN.png its sheet's scan,
/// T.csv the trace of it, JS.csv its joint log, PL.toml the sheet's placement, POT.toml the
/// potentiometer's calibration), J.csv (potentiometer jig points), P.csv (a path of three
/// reachable points) and ALIAS -> RUN.
fn workspace(dir: &Path) {
    let (code, err) = run(
        dir,
        &["simulate", "--seed", "5", "--val", "20", "--out", "RUN"],
    );
    assert_eq!(code, Some(0), "{err}");
    let (code, err) = run(dir, &["simulate", "--session", "line", "--out", "S"]);
    assert_eq!(code, Some(0), "{err}");
    std::fs::rename(dir.join("S/pot.rec"), dir.join("REC")).unwrap();
    std::fs::rename(dir.join("S/scan.png"), dir.join("SCAN.png")).unwrap();
    std::fs::rename(dir.join("S/joints.csv"), dir.join("JS.csv")).unwrap();
    std::fs::rename(dir.join("S/placement.toml"), dir.join("PL.toml")).unwrap();
    let (code, err) = run(
        dir,
        &["potcal", "--points", "S/potjig.csv", "--out", "POT.toml"],
    );
    assert_eq!(code, Some(0), "{err}");
    std::fs::remove_dir_all(dir.join("S")).unwrap();
    let (code, err) = run(dir, &["trace", "SCAN.png", "--out", "T.csv"]);
    assert_eq!(code, Some(0), "{err}");
    std::fs::copy(dir.join("RUN/truth.toml"), dir.join("M.toml")).unwrap();
    let (code, err) = run(dir, &["model2urdf", "--model", "M.toml", "--out", "M.urdf"]);
    assert_eq!(code, Some(0), "{err}");
    std::fs::write(
        dir.join("J.csv"),
        "raw,travel_mm\n100,0\n2000,10\n4000,20\n",
    )
    .unwrap();
    // three measured points of the run: reachable by the model
    let cal = std::fs::read_to_string(dir.join("RUN/cal.csv")).unwrap();
    let head: Vec<&str> = cal.lines().next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (x, y, z) = (col("x"), col("y"), col("z"));
    let mut path = String::from("x,y,z\n");
    for line in cal.lines().skip(1).take(3) {
        let f: Vec<&str> = line.split(',').collect();
        path += &format!("{},{},{}\n", f[x], f[y], f[z]);
    }
    std::fs::write(dir.join("P.csv"), path).unwrap();
    symlink("RUN", dir.join("ALIAS")).unwrap();
}

/// The input files of the workspace.
const INPUTS: [&str; 14] = [
    "RUN/cal.csv",
    "RUN/val.csv",
    "RUN/truth.toml",
    "RUN/truth.json",
    "M.toml",
    "REC",
    "M.urdf",
    "SCAN.png",
    "J.csv",
    "P.csv",
    "T.csv",
    "JS.csv",
    "PL.toml",
    "POT.toml",
];

/// Every input file of the workspace and its bytes.
fn inputs(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    INPUTS
        .iter()
        .map(|n| (dir.join(n), std::fs::read(dir.join(n)).unwrap()))
        .collect()
}

fn assert_inputs_intact(before: &[(PathBuf, Vec<u8>)], what: &str) {
    for (p, bytes) in before {
        let now = std::fs::read(p).unwrap_or_default();
        assert!(&now == bytes, "{what}: {} changed", p.display());
        assert!(
            !std::fs::symlink_metadata(p)
                .unwrap()
                .file_type()
                .is_symlink(),
            "{what}: {} became a link",
            p.display()
        );
    }
}

/// No temporary file (`.NAME.tmp-PID`) anywhere in the workspace.
fn assert_no_temp(dir: &Path, what: &str) {
    for e in walk(dir) {
        let n = e.file_name().unwrap().to_string_lossy().into_owned();
        assert!(!n.contains(".tmp-"), "{what}: left {}", e.display());
    }
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if e.file_type().is_ok_and(|t| t.is_dir()) {
            out.extend(walk(&p));
        }
        out.push(p);
    }
    out
}

#[test]
fn report_html_onto_a_file_of_its_run_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let w = tmp.path();
    workspace(w);
    let (code, err) = run(
        w,
        &[
            "diagnose",
            "--poses",
            "RUN/cal.csv",
            "--validate",
            "RUN/val.csv",
            "--json",
            "RUN/diagnose.json",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    let before = inputs(w);
    let json = std::fs::read(w.join("RUN/diagnose.json")).unwrap();
    symlink("diagnose.json", w.join("RUN/page.html")).unwrap();
    std::fs::hard_link(w.join("RUN/cal.csv"), w.join("hard.html")).unwrap();
    for html in [
        "RUN/cal.csv",
        "RUN/page.html",    // a link to diagnose.json
        "ALIAS/truth.toml", // through an alias of the run folder
        "RUN/./truth.toml",
        "hard.html", // a hard link to cal.csv elsewhere
    ] {
        for run_dir in ["RUN", "ALIAS"] {
            let (code, err) = run(w, &["report", run_dir, "--html", html]);
            assert_eq!(code, Some(2), "report {run_dir} --html {html}: {err}");
            assert!(err.contains("refusing"), "{err}");
        }
    }
    assert_inputs_intact(&before, "report");
    assert_eq!(std::fs::read(w.join("RUN/diagnose.json")).unwrap(), json);
    // a new name inside the run folder, and a name outside it, are written
    for html in ["RUN/report.html", "page2.html"] {
        let (code, err) = run(w, &["report", "RUN", "--html", html]);
        assert_eq!(code, Some(0), "{html}: {err}");
        assert!(std::fs::read_to_string(w.join(html))
            .unwrap()
            .contains("<html"));
    }
    // the page of an earlier report is replaced; a page-like file that is not one, or a report
    // page with a second hard link, is not
    let (code, err) = run(w, &["report", "RUN", "--html", "RUN/report.html"]);
    assert_eq!(code, Some(0), "a second report over its own page: {err}");
    std::fs::write(
        w.join("RUN/notes.html"),
        "<!DOCTYPE html>\n<html>mine</html>\n",
    )
    .unwrap();
    std::fs::hard_link(w.join("page2.html"), w.join("RUN/linked.html")).unwrap();
    for html in ["RUN/notes.html", "RUN/linked.html"] {
        let (code, err) = run(w, &["report", "RUN", "--html", html]);
        assert_eq!(code, Some(2), "{html}: {err}");
    }
    assert!(std::fs::read_to_string(w.join("RUN/notes.html"))
        .unwrap()
        .contains("mine"));
    assert_no_temp(w, "report");
}

#[test]
fn planted_links_in_output_folders_are_refused_or_replaced_never_followed() {
    let tmp = tempfile::tempdir().unwrap();
    let w = tmp.path();
    workspace(w);
    let before = inputs(w);
    // the issue's three cases: each refused before the work
    std::fs::create_dir(w.join("plots")).unwrap();
    symlink("../RUN/cal.csv", w.join("plots/01_link_length_d4.svg")).unwrap();
    let (code, err) = run(
        w,
        &[
            "diagnose",
            "--poses",
            "RUN/cal.csv",
            "--validate",
            "RUN/val.csv",
            "--plots",
            "plots",
        ],
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("is a link to the input"), "{err}");
    std::fs::create_dir(w.join("csv")).unwrap();
    symlink("../REC", w.join("csv/status.csv")).unwrap();
    let (code, err) = run(w, &["export", "REC", "--csv", "csv"]);
    assert_eq!(code, Some(2), "{err}");
    std::fs::create_dir(w.join("sim")).unwrap();
    symlink("../M.toml", w.join("sim/truth.toml")).unwrap();
    let (code, err) = run(w, &["simulate", "--model", "M.toml", "--out", "sim"]);
    assert_eq!(code, Some(2), "{err}");
    // hard links are refused the same way
    std::fs::hard_link(w.join("M.toml"), w.join("sim/cal.csv")).unwrap();
    std::fs::remove_file(w.join("sim/truth.toml")).unwrap();
    let (code, err) = run(w, &["simulate", "--model", "M.toml", "--out", "sim"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("hard link"), "{err}");
    assert_inputs_intact(&before, "planted links");
    // a link to a file that is not an input is replaced by the new file, its target untouched
    std::fs::write(w.join("bystander.txt"), "keep me\n").unwrap();
    std::fs::remove_file(w.join("csv/status.csv")).unwrap();
    symlink("../bystander.txt", w.join("csv/status.csv")).unwrap();
    let (code, err) = run(w, &["export", "REC", "--csv", "csv"]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(
        std::fs::read_to_string(w.join("bystander.txt")).unwrap(),
        "keep me\n"
    );
    let status = std::fs::symlink_metadata(w.join("csv/status.csv")).unwrap();
    assert!(status.is_file(), "the planted link was followed");
    assert_no_temp(w, "planted links");
}

#[test]
fn report_reads_symlinked_run_files() {
    let tmp = tempfile::tempdir().unwrap();
    let w = tmp.path();
    workspace(w);
    std::fs::create_dir(w.join("LINKED")).unwrap();
    for f in ["cal.csv", "val.csv", "truth.toml", "truth.json"] {
        symlink(format!("../RUN/{f}"), w.join("LINKED").join(f)).unwrap();
    }
    symlink("../RUN/nothing.json", w.join("LINKED/dangling.json")).unwrap();
    let (code, err) = run(w, &["report", "LINKED", "--html", "linked.html"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("nothing to report"), "{err}");
    assert!(
        err.contains("dangling.json: a symbolic link to nothing readable"),
        "{err}"
    );
}

#[test]
fn hidden_characters_in_file_names_are_escaped_in_messages() {
    let tmp = tempfile::tempdir().unwrap();
    let w = tmp.path();
    for name in [
        "a\nrigctl: all good.csv",
        "b\u{1b}[2J\u{1b}[31m.csv",
        "c\u{202e}vsc.csv",
        "d\r\u{7}.csv",
    ] {
        for args in [
            vec!["calibrate", "--poses", name],
            vec!["simulate", "--model", name, "--out", "o"],
            vec!["export", name, "--csv", "o"],
        ] {
            let (code, err) = run(w, &args);
            assert_eq!(code, Some(2), "{args:?}: {err}");
            let body = err.strip_suffix('\n').unwrap_or(&err);
            assert!(!body.contains('\n'), "{args:?}: a raw newline in {err:?}");
            assert!(
                !body.chars().any(|c| c.is_control() || c == '\u{202e}'),
                "{args:?}: a raw control character in {err:?}"
            );
            assert!(
                body.contains("\\u{") || body.contains("\\n") || body.contains("\\r"),
                "{err:?}"
            );
        }
    }
}
