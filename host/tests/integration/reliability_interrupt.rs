//! The interruption harness (docs/reliability.md, "Sets of files as one commit"): each writer
//! of a set of files (`simulate --out`, `export --csv`, `diagnose --plots`) is interrupted
//! (SIGINT or SIGTERM) at seeded random moments of its run, over a folder holding the set of an
//! earlier run: half of the trials at a uniform moment of the run, half 0-2 ms after the first
//! temporary file of the new set appears (the writes and the commit). After each trial no
//! temporary file is left and the folder holds the old set or the new one, file for file,
//! never a mix.
//! `RELIABILITY_SEED=N` draws other moments; `RELIABILITY_TRIALS=N` sets the trials per writer.

use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::common::spawn::{rigctl, text};

/// The files of a folder (no temporary ones) and their bytes, sorted by name.
fn set(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| {
            let n = e.file_name().to_string_lossy().into_owned();
            (n, std::fs::read(e.path()).unwrap_or_default())
        })
        .collect();
    v.sort();
    v
}

/// Whether a temporary file of a set is in `dir` (not the probe of the checks before the work).
fn writing(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|entries| {
        entries.flatten().any(|e| {
            let n = e.file_name().to_string_lossy().into_owned();
            n.contains(".tmp-") && !n.starts_with(".rigctl-probe")
        })
    })
}

/// Runs `args` + `--out`-like folder `dir` to the end; the folder's set.
fn reference(args: &[&str], dir: &Path) -> Vec<(String, Vec<u8>)> {
    let o = rigctl().args(args).arg(dir).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    set(dir)
}

fn copy_set(from: &[(String, Vec<u8>)], to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for (n, b) in from {
        std::fs::write(to.join(n), b).unwrap();
    }
}

/// Interrupts `new_args DIR` over the old set, `trials` times at random moments.
fn harness(name: &str, old_args: &[&str], new_args: &[&str], trials: usize, seed: u64) {
    let tmp = tempfile::tempdir().unwrap();
    let old = reference(old_args, &tmp.path().join("old"));
    let t0 = Instant::now();
    let new = reference(new_args, &tmp.path().join("new"));
    let full = t0.elapsed();
    assert_ne!(old, new, "{name}: the two runs must differ");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // old, new, finished before the signal; trials signalled while the set was being written
    let mut outcomes = [0usize; 4];
    for trial in 0..trials {
        let dir = tmp.path().join(format!("t{trial}"));
        copy_set(&old, &dir);
        let mut child = rigctl()
            .args(new_args)
            .arg(&dir)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let started = Instant::now();
        let targeted = rng.gen_bool(0.5);
        if targeted {
            // at the writes: a temporary file of the set has appeared, then 0-2 ms more
            while child.try_wait().unwrap().is_none()
                && !writing(&dir)
                && started.elapsed() < full * 3 + Duration::from_secs(5)
            {
                std::thread::sleep(Duration::from_micros(50));
            }
            if child.try_wait().unwrap().is_none() {
                outcomes[3] += 1;
            }
            std::thread::sleep(Duration::from_micros(rng.gen_range(0..2000)));
        } else {
            std::thread::sleep(full.mul_f64(rng.gen_range(0.0..1.2)));
        }
        let at = started.elapsed();
        let sig = if rng.gen_bool(0.5) {
            Signal::SIGINT
        } else {
            Signal::SIGTERM
        };
        let _ = kill(Pid::from_raw(child.id() as i32), sig);
        let status = child.wait_with_output().unwrap().status;
        let code = status.code();
        let what = format!(
            "{name} trial {trial} (seed {seed}, {sig} after {at:?}{})",
            if targeted { ", at the writes" } else { "" }
        );
        // killed by the signal itself: it came before the handler was installed (nothing
        // written yet)
        let before_handler = code.is_none() && status.signal() == Some(sig as i32);
        assert!(
            matches!(code, Some(0) | Some(130)) || before_handler,
            "{what}: {status:?}"
        );
        let now = set(&dir);
        for (n, _) in &now {
            assert!(!n.contains(".tmp-"), "{what}: {n} left behind");
        }
        if now == old {
            outcomes[0] += 1;
        } else if now == new {
            outcomes[1 + usize::from(code == Some(0))] += 1;
        } else {
            let names: Vec<&String> = now.iter().map(|(n, _)| n).collect();
            panic!("{what}: a mixed set {names:?}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
    eprintln!(
        "{name}: {trials} trials: old set {}, new set {} (+{} finished); {} signalled after the writes of \
         the set began",
        outcomes[0], outcomes[1], outcomes[2], outcomes[3]
    );
}

fn seed_and_trials() -> (u64, usize) {
    let seed = std::env::var("RELIABILITY_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(48);
    let trials = std::env::var("RELIABILITY_TRIALS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    (seed, trials)
}

#[test]
fn interrupted_simulate_leaves_the_old_set_or_the_new_one() {
    let (seed, trials) = seed_and_trials();
    harness(
        "simulate",
        &["simulate", "--seed", "1", "--val", "20", "--out"],
        &["simulate", "--seed", "2", "--val", "20", "--out"],
        trials,
        seed,
    );
}

#[test]
fn interrupted_export_leaves_the_old_set_or_the_new_one() {
    let (seed, trials) = seed_and_trials();
    let tmp = tempfile::tempdir().unwrap();
    for (s, path) in [("1", "line"), ("2", "circle")] {
        let o = rigctl()
            .args(["simulate", "--session", path, "--seed", s, "--out"])
            .arg(tmp.path().join(format!("s{s}")))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    }
    let rec = |s: &str| {
        tmp.path()
            .join(format!("s{s}/pot.rec"))
            .display()
            .to_string()
    };
    let (r1, r2) = (rec("1"), rec("2"));
    harness(
        "export",
        &["export", &r1, "--csv"],
        &["export", &r2, "--csv"],
        trials,
        seed.wrapping_add(1),
    );
}

#[test]
fn interrupted_diagnose_plots_leave_the_old_set_or_the_new_one() {
    let (seed, trials) = seed_and_trials();
    let tmp = tempfile::tempdir().unwrap();
    let [(p1, v1), (p2, v2)] = super::reliability_plot_sets::diagnose_inputs(tmp.path());
    harness(
        "diagnose --plots",
        &["diagnose", "--poses", &p1, "--validate", &v1, "--plots"],
        &["diagnose", "--poses", &p2, "--validate", &v2, "--plots"],
        trials,
        seed.wrapping_add(2),
    );
}

#[test]
fn a_second_simulate_removes_the_files_of_an_earlier_kind_of_run() {
    // a session's files, then a plain run into the same folder: only the plain set remains
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let o = rigctl()
        .args(["simulate", "--session", "line", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    std::fs::write(dir.join("notes.txt"), "mine\n").unwrap();
    let o = rigctl()
        .args(["simulate", "--val", "10", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let names: Vec<String> = set(&dir).into_iter().map(|(n, _)| n).collect();
    assert_eq!(
        names,
        [
            "cal.csv",
            "notes.txt",
            "truth.json",
            "truth.toml",
            "val.csv"
        ],
        "the session's files are stale; a file of the user's stays"
    );
}

#[test]
fn signals_during_the_output_checks_leave_no_probe_file() {
    // the probe files of the checks before the work (`check_output`, the folder probe) are
    // registered before they exist: a signal at any moment of a short run leaves none
    let tmp = tempfile::tempdir().unwrap();
    let (seed, _) = seed_and_trials();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let o = rigctl()
        .args(["simulate", "--val", "5", "--out"])
        .arg(tmp.path().join("run"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let cal = tmp.path().join("run/cal.csv");
    for trial in 0..40 {
        let out = tmp.path().join(format!("o{trial}"));
        std::fs::create_dir(&out).unwrap();
        let child = rigctl()
            .args(["calibrate", "--poses"])
            .arg(&cal)
            .arg("--json")
            .arg(out.join("c.json"))
            .arg("--out")
            .arg(out.join("m.toml"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_micros(rng.gen_range(0..30_000)));
        let _ = kill(Pid::from_raw(child.id() as i32), Signal::SIGINT);
        let _ = child.wait_with_output().unwrap();
        for (n, _) in set(&out) {
            assert!(!n.contains(".tmp-"), "trial {trial}: {n} left behind");
        }
    }
}
