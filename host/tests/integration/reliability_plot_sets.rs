//! `diagnose --plots` as one set (docs/reliability.md, "Sets of files as one commit"): a second
//! run removes the plots of the first that it lacks (a file of the user's stays), and a plot that
//! cannot be written (a full disk) leaves every output of the run as it was: the plots, the JSON.
//! The interruption trials of the same set are in `reliability_interrupt`.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::common::spawn::{bin_dir, rigctl, text};

/// Two runs to diagnose, `[(poses, validate); 2]` under `dir`: the first adds one effect (one
/// plot), the second two, one of them the first's effect under another number. 30 poses each:
/// a run of a fraction of a second in the debug build.
pub(crate) fn diagnose_inputs(dir: &Path) -> [(String, String); 2] {
    let run = |s: &str, effects: &[&str]| {
        let out = dir.join(format!("s{s}"));
        let mut args = vec!["simulate", "--seed", s, "--val", "10"];
        for e in effects {
            args.extend(["--effect", e]);
        }
        let o = rigctl()
            .args(&args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
        let cal = std::fs::read_to_string(out.join("cal.csv")).unwrap();
        let head: Vec<&str> = cal.lines().take(31).collect();
        std::fs::write(out.join("cal30.csv"), head.join("\n") + "\n").unwrap();
        let s = |f: &str| out.join(f).display().to_string();
        (s("cal30.csv"), s("val.csv"))
    };
    [
        run("1", &["encoder_harmonic:j3:h1=0.04,20"]),
        run(
            "2",
            &["encoder_harmonic:j3:h1=0.05,60", "joint_scale:j2=0.003"],
        ),
    ]
}

/// `diagnose --poses P --validate V --json JSON --plots PLOTS`: exit code and stderr.
fn diagnose(input: &(String, String), json: &Path, plots: &Path) -> (Option<i32>, String) {
    let o = rigctl()
        .args(["diagnose", "--poses", &input.0, "--validate", &input.1])
        .arg("--json")
        .arg(json)
        .arg("--plots")
        .arg(plots)
        .output()
        .unwrap();
    (o.status.code(), text(&o.stderr))
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The files of `dir` and their bytes, sorted by name.
fn contents(dir: &Path) -> Vec<(String, Vec<u8>)> {
    names(dir)
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(dir.join(&n)).unwrap_or_default();
            (n, bytes)
        })
        .collect()
}

#[test]
fn a_second_diagnose_plots_removes_the_first_runs_plots() {
    let tmp = tempfile::tempdir().unwrap();
    let inputs = diagnose_inputs(tmp.path());
    let (plots, json) = (tmp.path().join("plots"), tmp.path().join("d.json"));
    let (code, err) = diagnose(&inputs[0], &json, &plots);
    assert_eq!(code, Some(0), "{err}");
    let first = names(&plots);
    assert_eq!(first.len(), 1, "{first:?}");
    // a plot of a still earlier run, a probe plot, and two files of the user's
    for (n, body) in [
        ("99_old.svg", "<svg/>"),
        ("probe_old.svg", "<svg/>"),
        ("mine.svg", "<svg>mine</svg>"),
        ("notes.txt", "mine\n"),
    ] {
        std::fs::write(plots.join(n), body).unwrap();
    }
    let (code, err) = diagnose(&inputs[1], &json, &plots);
    assert_eq!(code, Some(0), "{err}");
    // the second run's plots alone, as it writes them into an empty folder
    let fresh = tmp.path().join("fresh");
    let (code, err) = diagnose(&inputs[1], &tmp.path().join("fresh.json"), &fresh);
    assert_eq!(code, Some(0), "{err}");
    let mut expected = names(&fresh);
    assert_eq!(expected.len(), 2, "{expected:?}");
    assert!(!expected.contains(&first[0]), "{expected:?} {first:?}");
    expected.extend(["mine.svg".to_string(), "notes.txt".to_string()]);
    expected.sort();
    assert_eq!(names(&plots), expected);
}

/// Runs `script` (sh) in a private mount namespace as root of a user namespace (`unshare -rm`),
/// with `rigctl` on `PATH`; `None` when the system allows no such namespace.
fn in_namespace(script: &str, args: &[&Path]) -> Option<std::process::Output> {
    let probe = Command::new("unshare").args(["-rm", "true"]).output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!("SKIPPED: no user and mount namespace (unshare -rm) for a small tmpfs");
        return None;
    }
    let path = format!(
        "{}:{}",
        bin_dir().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    Some(
        Command::new("unshare")
            .args(["-rm", "sh", "-c", script, "sh"])
            .args(args)
            .env("PATH", path)
            .output()
            .unwrap(),
    )
}

#[test]
fn a_full_disk_while_writing_the_plots_leaves_every_output_as_it_was() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let inputs = diagnose_inputs(t);
    // the old outputs, and the sizes of the new ones
    let old = t.join("old");
    std::fs::create_dir(&old).unwrap();
    let (code, err) = diagnose(&inputs[0], &old.join("d.json"), &old.join("plots"));
    assert_eq!(code, Some(0), "{err}");
    let new = t.join("new");
    std::fs::create_dir(&new).unwrap();
    let (code, err) = diagnose(&inputs[1], &new.join("d.json"), &new.join("plots"));
    assert_eq!(code, Some(0), "{err}");
    let json_bytes = std::fs::metadata(new.join("d.json")).unwrap().len();
    let plot_bytes: u64 = contents(&new.join("plots"))
        .iter()
        .map(|(_, b)| b.len() as u64)
        .sum();
    // room for the new JSON (in 4 KiB pages) and 8 KiB more, not for the plots
    let free = json_bytes.div_ceil(4096) * 4096 + 8192;
    assert!(
        plot_bytes > free + 8192,
        "plots {plot_bytes} B, free {free} B"
    );

    // a 1 MiB tmpfs holding the old outputs, filled to `free` bytes left; then the new run;
    // then what the tmpfs holds, copied out (the mount ends with the namespace)
    let script = r#"
        set -e
        mnt=$1; after=$2; poses=$4; validate=$5
        mount -t tmpfs -o size=1m tmpfs "$mnt"
        cp -r "$3/." "$mnt/"
        avail=$(df --output=avail -B1 "$mnt" | tail -n 1)
        head -c $((avail - $6)) /dev/zero > "$mnt/filler"
        set +e
        rigctl diagnose --poses "$poses" --validate "$validate" \
            --json "$mnt/d.json" --plots "$mnt/plots" 2> "$after.err"
        echo $? > "$after.code"
        rm -f "$mnt/filler"
        cp -r "$mnt/." "$after/"
    "#;
    let (mnt, after) = (t.join("mnt"), t.join("after"));
    std::fs::create_dir(&mnt).unwrap();
    std::fs::create_dir(&after).unwrap();
    let poses = PathBuf::from(&inputs[1].0);
    let validate = PathBuf::from(&inputs[1].1);
    let free_arg = PathBuf::from(free.to_string());
    let Some(o) = in_namespace(script, &[&mnt, &after, &old, &poses, &validate, &free_arg]) else {
        return;
    };
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = std::fs::read_to_string(t.join("after.err")).unwrap();
    let code = std::fs::read_to_string(t.join("after.code")).unwrap();
    assert_eq!(code.trim(), "1", "{err}");
    assert!(err.contains("No space left"), "{err}");
    // the JSON and the plots of the old run, file for file; no temporary file
    assert!(
        std::fs::read(after.join("d.json")).unwrap() == std::fs::read(old.join("d.json")).unwrap(),
        "the JSON was replaced while the plots failed"
    );
    assert!(
        contents(&after.join("plots")) == contents(&old.join("plots")),
        "the plots changed: {:?} (the old run's: {:?})",
        names(&after.join("plots")),
        names(&old.join("plots"))
    );
    assert_eq!(names(&after), ["d.json", "plots"]);
}
