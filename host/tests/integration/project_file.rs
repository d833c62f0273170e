//! The project file (docs/project.md): a command with a project file gives what the long command
//! line gives (calibrate, diagnose, plan), a flag on the command line wins, a bad file is exit 2
//! naming the file, line and key, `init` writes a file that loads back and refuses to overwrite
//! it, and the report of an own robot's run names its model and suggests commands that run.

use std::path::Path;
use std::process::Output;

use crate::common::spawn::{bin_dir, rigctl, text};

/// `rigctl args` run in `dir`.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    rigctl()
        .args(args)
        .current_dir(dir)
        .output()
        .expect("rigctl runs")
}

fn ok(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}: exit {:?}\n{}",
        out.status.code(),
        text(&out.stderr)
    );
}

/// A simulated UR5 run in `root/sim`, and the folders `proj` (with `project`) and `long`.
fn setup(root: &Path, project: &str) {
    ok(
        &run_in(
            root,
            &["simulate", "--robot", "ur5", "--out", "sim", "--val", "30"],
        ),
        "simulate",
    );
    for d in ["proj", "long"] {
        std::fs::create_dir(root.join(d)).unwrap();
    }
    std::fs::write(root.join("proj/rigctl.toml"), project).unwrap();
}

const UR5_PROJECT: &str = "[robot]\npreset = \"ur5\"\n[robot.set]\ntool_dz = 31.0\n\
    [instrument]\nsigma_mm = 0.01\n[frames]\nbase = true\n\
    [data]\nposes = \"../sim/cal.csv\"\nvalidate = \"../sim/val.csv\"\n\
    [plan]\ntable_z_mm = -50.0\nkeep_out = [[300.0, -100.0, -50.0, 500.0, 100.0, 100.0]]\n\
    limit_margin_deg = 3.0\n";

#[test]
fn a_project_file_gives_what_the_long_command_line_gives() {
    let root = tempfile::tempdir().unwrap();
    let root = root.path();
    setup(root, UR5_PROJECT);
    let (proj, long) = (root.join("proj"), root.join("long"));
    let model = ["--robot", "ur5", "--set", "tool_dz=31"];
    let data = ["--poses", "../sim/cal.csv", "--validate", "../sim/val.csv"];
    let cases: Vec<(&str, Vec<&str>, Vec<&str>, &str)> = vec![
        (
            "calibrate",
            vec!["calibrate", "--json", "out.json", "--out", "model.toml"],
            [&model[..], &data[..], &["--base"]].concat(),
            "out.json",
        ),
        (
            "diagnose",
            vec!["diagnose", "--json", "out.json"],
            [&model[..], &data[..], &["--instrument-mm", "0.01"]].concat(),
            "out.json",
        ),
        (
            "plan",
            vec![
                "plan",
                "--n",
                "8",
                "--candidates",
                "300",
                "--out",
                "plan.csv",
            ],
            [
                &model[..],
                &[
                    "--base",
                    "--noise-mm",
                    "0.01",
                    "--table-z-mm",
                    "-50",
                    "--keep-out",
                    "300,-100,-50,500,100,100",
                    "--limit-margin-deg",
                    "3",
                ],
            ]
            .concat(),
            "plan.csv",
        ),
    ];
    for (name, short, extra, file) in cases {
        let a = run_in(&proj, &short);
        ok(&a, &format!("{name} with the project file"));
        assert!(
            text(&a.stderr).contains("project file rigctl.toml read"),
            "{name}: {}",
            text(&a.stderr)
        );
        let b = run_in(&long, &[&short[..], &extra[..]].concat());
        ok(&b, &format!("{name} with the long command line"));
        assert!(!text(&b.stderr).contains("project file"), "{name}");
        assert_eq!(text(&a.stdout), text(&b.stdout), "{name}: stdout differs");
        let (fa, fb) = (
            std::fs::read(proj.join(file)).unwrap(),
            std::fs::read(long.join(file)).unwrap(),
        );
        assert!(fa == fb, "{name}: {file} differs");
        assert!(!fa.is_empty(), "{name}: {file} empty");
    }
}

#[test]
fn flags_on_the_command_line_win_over_the_project_file() {
    let root = tempfile::tempdir().unwrap();
    let root = root.path();
    // a wrong tool length and a missing held-out file in the project
    let project = UR5_PROJECT
        .replace("tool_dz = 31.0", "tool_dz = 80.0")
        .replace("../sim/val.csv", "nowhere.csv");
    setup(root, &project);
    let (proj, long) = (root.join("proj"), root.join("long"));
    let bad = run_in(&proj, &["calibrate", "--json", "out.json"]);
    assert_eq!(bad.status.code(), Some(2), "{}", text(&bad.stderr));
    assert!(text(&bad.stderr).contains("nowhere.csv"));
    let a = run_in(
        &proj,
        &[
            "calibrate",
            "--set",
            "tool_dz=31",
            "--validate",
            "../sim/val.csv",
            "--json",
            "out.json",
        ],
    );
    ok(&a, "calibrate with flags over the project");
    let b = run_in(
        &long,
        &[
            "calibrate",
            "--robot",
            "ur5",
            "--set",
            "tool_dz=31",
            "--base",
            "--poses",
            "../sim/cal.csv",
            "--validate",
            "../sim/val.csv",
            "--json",
            "out.json",
        ],
    );
    ok(&b, "calibrate, long");
    assert_eq!(text(&a.stdout), text(&b.stdout));
    // a robot on the command line replaces the file's model (its --set too)
    let c = run_in(
        &proj,
        &["fk", "--robot", "katana450", "--joints", "../sim/val.csv"],
    );
    let d = run_in(&long, &["fk", "--joints", "../sim/val.csv"]);
    // the Katana has 5 joints, the UR5's file 6: the same answer either way
    assert_eq!(c.status.code(), d.status.code(), "{}", text(&c.stderr));
}

#[test]
fn a_bad_project_file_is_exit_2_naming_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "[robot]\npreset = \"ur5\"\n\n[units]\njoint = \"rad\"\n",
            "rigctl.toml:5:",
            "`joint`",
        ),
        (
            "[instrument]\nsigma_mm = \"0.01\"\n",
            "rigctl.toml:2:",
            "`sigma_mm`",
        ),
        (
            "[plan]\ntable_z_mm = 0.0\nkeep_out = [1.0]\n",
            "rigctl.toml:3:",
            "`keep_out`",
        ),
        ("[robots]\npreset = \"ur5\"\n", "rigctl.toml:1:", "`robots`"),
    ];
    for (body, at, key) in cases {
        std::fs::write(dir.path().join("rigctl.toml"), body).unwrap();
        let out = run_in(dir.path(), &["plan", "--n", "5", "--out", "p.csv"]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{body}: {err}");
        assert!(err.contains(at) && err.contains(key), "{body}: {err}");
        assert!(!dir.path().join("p.csv").exists());
    }
    // the same through --project, from elsewhere; a missing --project file
    let other = tempfile::tempdir().unwrap();
    let file = dir.path().join("rigctl.toml");
    let out = run_in(
        other.path(),
        &["calibrate", "--project", file.to_str().unwrap()],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains(&format!("{}:1:", file.display())));
    let out = run_in(other.path(), &["calibrate", "--project", "none.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("none.toml"));
}

/// TIAGo's URDF of the shared data, if present.
fn tiago_urdf(test: &str) -> Option<std::path::PathBuf> {
    crate::common::shared_file(
        test,
        "data/real/thanhndv212__figaroh-examples/examples/tiago/urdf/tiago_48_schunk.urdf",
    )
}

/// `init` from TIAGo's URDF into `dir`.
fn init_tiago(dir: &Path, urdf: &Path) -> Output {
    run_in(
        dir,
        &[
            "init",
            "--urdf",
            urdf.to_str().unwrap(),
            "--base-link",
            "base_footprint",
            "--tip",
            "wrist_ft_tool_link",
        ],
    )
}

#[test]
fn init_writes_a_project_that_loads_back_and_is_not_overwritten() {
    let Some(urdf) = tiago_urdf("init_writes_a_project_that_loads_back") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(&init_tiago(d, &urdf), "init");
    let written = std::fs::read_to_string(d.join("rigctl.toml")).unwrap();
    for joint in ["torso_lift_joint: prismatic", "arm_7_joint: revolute"] {
        assert!(written.contains(joint), "{written}");
    }
    // loads back: the commands work on the chain it names, with its data files
    let sim = run_in(d, &["simulate", "--out", "run", "--val", "20"]);
    ok(&sim, "simulate from the project");
    assert!(text(&sim.stderr).contains("project file rigctl.toml read (--model"));
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("run/truth.json")).unwrap()).unwrap();
    assert_eq!(truth["robot"], "tiago", "{truth}");
    ok(
        &run_in(d, &["calibrate", "--method", "standard"]),
        "calibrate",
    );
    // not overwritten without --force
    std::fs::write(d.join("rigctl.toml"), "# mine\n").unwrap();
    let again = init_tiago(d, &urdf);
    assert_eq!(again.status.code(), Some(2), "{}", text(&again.stderr));
    assert_eq!(
        std::fs::read_to_string(d.join("rigctl.toml")).unwrap(),
        "# mine\n"
    );
    let forced = run_in(d, &["init", "--robot", "ur5", "--force"]);
    ok(&forced, "init --force");
    let text_ur5 = std::fs::read_to_string(d.join("rigctl.toml")).unwrap();
    assert!(text_ur5.contains("preset = \"ur5\""));
    // the preset is read now
    let fk = run_in(d, &["fk", "--joints", "run/val.csv"]);
    assert!(
        text(&fk.stderr).contains("read (--robot"),
        "{}",
        text(&fk.stderr)
    );
}

/// The commands (`rigctl ...` in backticks, HTML-escaped) under "What to do next" of a page.
fn suggested_commands(html: &str) -> Vec<String> {
    let Some(start) = html.find("What to do next") else {
        return Vec::new();
    };
    let part = &html[start..];
    let part = &part[..part.find("</ul>").unwrap_or(part.len())];
    part.split("<code>")
        .skip(1)
        .filter_map(|c| c.split("</code>").next())
        .map(|c| {
            c.replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&#39;", "'")
                .replace("&amp;", "&")
        })
        .filter(|c| c.starts_with("rigctl "))
        .collect()
}

#[test]
#[cfg(unix)]
fn an_own_robots_report_names_its_model_and_its_suggested_commands_run() {
    let Some(urdf) = tiago_urdf("an_own_robots_report_suggested_commands_run") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(&init_tiago(d, &urdf), "init");
    ok(
        &run_in(d, &["simulate", "--out", "run", "--val", "30"]),
        "simulate",
    );
    ok(
        &run_in(
            d,
            &[
                "calibrate",
                "--json",
                "run/calibrate.json",
                "--out",
                "run/calibrated.toml",
            ],
        ),
        "calibrate",
    );
    // a diagnosis that says which poses to measure: with the instrument claimed too good
    ok(
        &run_in(
            d,
            &[
                "diagnose",
                "--json",
                "run/diagnose.json",
                "--instrument-mm",
                "0.001",
            ],
        ),
        "diagnose",
    );
    ok(
        &run_in(d, &["report", "run", "--html", "report.html"]),
        "report",
    );
    let page = std::fs::read_to_string(d.join("report.html")).unwrap();
    assert!(
        !page.contains("unknown robot"),
        "the report names an unknown robot"
    );
    assert!(!page.contains("pose files not evaluated"));
    let commands = suggested_commands(&page);
    assert!(!commands.is_empty(), "no command suggested");
    let path = format!(
        "{}:{}",
        bin_dir().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for c in &commands {
        assert!(
            !c.contains("--robot") && !c.contains("--model"),
            "{c}: the project names the model"
        );
        let out = std::process::Command::new("bash")
            .args(["-euo", "pipefail", "-c", c])
            .current_dir(d)
            .env("PATH", &path)
            .output()
            .expect("bash runs");
        ok(&out, &format!("suggested `{c}`"));
    }
    // without the project file the commands name the model file
    std::fs::rename(d.join("rigctl.toml"), d.join("kept.toml")).unwrap();
    ok(
        &run_in(
            d,
            &[
                "report",
                "run",
                "--html",
                "report2.html",
                "--model",
                "tiago_48_schunk.model.toml",
            ],
        ),
        "report with --model",
    );
    let page = std::fs::read_to_string(d.join("report2.html")).unwrap();
    assert!(!page.contains("unknown robot"));
    for c in suggested_commands(&page) {
        assert!(c.contains("--model tiago_48_schunk.model.toml"), "{c}");
    }
}

/// `path` (a pose CSV in mm and deg, header `q1..,x,y,z,..`) in metres and radians.
fn to_m_rad(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut out = header.join(",") + "\n";
    for l in lines {
        let cells: Vec<String> = l
            .split(',')
            .zip(&header)
            .map(
                |(c, h)| match (h.starts_with('q'), ["x", "y", "z"].contains(h)) {
                    (true, _) => format!("{:.12}", c.parse::<f64>().unwrap().to_radians()),
                    (_, true) => format!("{:.12}", c.parse::<f64>().unwrap() / 1000.0),
                    _ => c.to_string(),
                },
            )
            .collect();
        out.push_str(&(cells.join(",") + "\n"));
    }
    out
}

/// The report's table of position errors per set.
fn error_table(page: &str) -> &str {
    let start = page
        .find("<h3>Calibration poses, ")
        .expect("the pose-set table");
    &page[start..start + page[start..].find("</table>").unwrap()]
}

#[test]
fn report_reads_the_run_in_the_projects_units() {
    let root = tempfile::tempdir().unwrap();
    let root = root.path();
    setup(
        root,
        "[robot]\npreset = \"ur5\"\n[units]\njoints = \"rad\"\npoints = \"m\"\n",
    );
    let proj = root.join("proj");
    std::fs::create_dir(proj.join("run")).unwrap();
    for f in ["cal.csv", "val.csv"] {
        std::fs::write(
            proj.join("run").join(f),
            to_m_rad(&root.join("sim").join(f)),
        )
        .unwrap();
    }
    for f in ["truth.toml", "truth.json"] {
        std::fs::copy(root.join("sim").join(f), proj.join("run").join(f)).unwrap();
    }
    ok(
        &run_in(&proj, &["report", "run", "--html", "si.html"]),
        "report, m and rad",
    );
    ok(
        &run_in(
            &root.join("long"),
            &["report", "../sim", "--html", "mm.html", "--robot", "ur5"],
        ),
        "report, mm and deg",
    );
    let si = std::fs::read_to_string(proj.join("si.html")).unwrap();
    let mm = std::fs::read_to_string(root.join("long/mm.html")).unwrap();
    assert!(!si.contains("not evaluated"));
    assert_eq!(error_table(&si), error_table(&mm));
}
