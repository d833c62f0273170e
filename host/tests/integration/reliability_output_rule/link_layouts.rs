//! The seeded property test of the output rule: random layouts of symbolic links, hard links and
//! folder aliases between the inputs and the outputs of every writer (14 of them, 8 layouts
//! each); no input's bytes ever change. `RELIABILITY_SEED=N` draws other layouts.

use std::os::unix::fs::symlink;
use std::path::PathBuf;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{assert_inputs_intact, assert_no_temp, inputs, run, workspace, INPUTS};

/// The writers of the property test: [`command`] gives each one's command line.
const WRITERS: usize = 14;

/// One writer's command line in a workspace, with its output folder (or file) `out`:
/// `simulate --out`, `export --csv`, `diagnose --plots` write folders, the others one file.
/// (`diagnose` fits the 20 held-out poses and checks on the 119 others: a fraction of a second.)
fn command(writer: usize, out: &str) -> Vec<String> {
    let v = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let diagnose = |flag: &str| {
        v(&[
            "diagnose",
            "--poses",
            "RUN/val.csv",
            "--validate",
            "RUN/cal.csv",
            flag,
            out,
        ])
    };
    match writer {
        0 => v(&["simulate", "--model", "M.toml", "--val", "10", "--out", out]),
        1 => v(&["export", "REC", "--csv", out]),
        2 => v(&["report", "RUN", "--html", out]),
        3 => v(&[
            "calibrate",
            "--poses",
            "RUN/cal.csv",
            "--validate",
            "RUN/val.csv",
            "--out",
            out,
        ]),
        4 => diagnose("--plots"),
        5 => diagnose("--json"),
        6 => v(&["model2urdf", "--model", "M.toml", "--out", out]),
        7 => v(&[
            "plan",
            "--model",
            "M.toml",
            "--n",
            "6",
            "--candidates",
            "300",
            "--out",
            out,
        ]),
        8 => v(&[
            "urdf2model",
            "--urdf",
            "M.urdf",
            "--tip",
            "tool0",
            "--out",
            out,
        ]),
        9 => v(&["potcal", "--points", "J.csv", "--out", out]),
        10 => v(&[
            "compensate",
            "--model",
            "M.toml",
            "--path",
            "P.csv",
            "--out",
            out,
        ]),
        11 => v(&["trace", "SCAN.png", "--out", out]),
        13 => v(&["simulate", "--session", "line", "--out", out]),
        _ => v(&[
            "fuse",
            "--joints",
            "JS.csv",
            "--recording",
            "REC",
            "--trace",
            "T.csv",
            "--placement",
            "PL.toml",
            "--pot",
            "POT.toml",
            "--out",
            out,
        ]),
    }
}

/// The name of a writer's one output file; `None` for a writer of a folder.
fn single_output(writer: usize) -> Option<&'static str> {
    match writer {
        2 => Some("page.html"),
        3 => Some("model.toml"),
        5 => Some("d.json"),
        6 => Some("m.urdf"),
        7 => Some("plan.csv"),
        8 => Some("m2.toml"),
        9 => Some("pot.toml"),
        10 => Some("joints.csv"),
        11 => Some("trace.csv"),
        12 => Some("fused.csv"),
        _ => None,
    }
}

/// The names writer `writer` writes into its folder.
fn names(writer: usize) -> &'static [&'static str] {
    match writer {
        0 => &["cal.csv", "val.csv", "truth.toml", "truth.json"],
        // the set replaces an earlier simulate's set: its files this one lacks go
        13 => &[
            "cal.csv",
            "val.csv",
            "truth.json",
            "joints.csv",
            "placement.toml",
            "pot.rec",
            "potjig.csv",
            "scan.png",
            "session.json",
            "truth.toml",
            "truth_path.csv",
        ],
        4 => &[
            "01_encoder_harmonic_j3_h1.svg",
            "02_link_length_d4.svg",
            "probe_t.svg",
        ],
        _ => &["pot.csv", "tilt.csv", "status.csv"],
    }
}

/// A path to an input, spelled at random: direct, through ALIAS, or through `..` / `.`.
fn input_spelling(rng: &mut ChaCha8Rng, from_sub: bool) -> String {
    let up = if from_sub { "../" } else { "" };
    let files = ["cal.csv", "val.csv", "truth.toml", "truth.json"];
    match rng.gen_range(0..6) {
        0 => format!("{up}M.toml"),
        1 => format!("{up}REC"),
        5 => format!(
            "{up}{}",
            ["M.urdf", "SCAN.png", "J.csv", "P.csv", "T.csv", "JS.csv", "PL.toml", "POT.toml"]
                [rng.gen_range(0..8)]
        ),
        2 => format!("{up}ALIAS/{}", files[rng.gen_range(0..4)]),
        3 => format!("{up}RUN/./{}", files[rng.gen_range(0..4)]),
        _ => format!("{up}RUN/{}", files[rng.gen_range(0..4)]),
    }
}

#[test]
fn no_layout_of_links_changes_an_input() {
    let seed: u64 = std::env::var("RELIABILITY_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(48);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let base = tempfile::tempdir().unwrap();
    workspace(base.path());
    let mut codes = [0usize; 3];
    for trial in 0..8 * WRITERS {
        let tmp = tempfile::tempdir().unwrap();
        let w = tmp.path();
        let cp = |rel: &str| {
            std::fs::copy(base.path().join(rel), w.join(rel)).unwrap();
        };
        std::fs::create_dir(w.join("RUN")).unwrap();
        for f in INPUTS {
            cp(f);
        }
        symlink("RUN", w.join("ALIAS")).unwrap();
        let before = inputs(w);
        let writer = trial % WRITERS;
        let out = if let Some(name) = single_output(writer) {
            // one output file: one path, planted as a link / hard link / alias spelling
            match rng.gen_range(0..5) {
                0 => {
                    let target = input_spelling(&mut rng, false);
                    symlink(&target, w.join(name)).unwrap();
                    name.to_string()
                }
                1 => {
                    let target = input_spelling(&mut rng, false);
                    std::fs::hard_link(w.join(&target), w.join(name)).unwrap();
                    name.to_string()
                }
                2 => {
                    // a link inside the run folder to a file of the run
                    let target = ["cal.csv", "truth.toml", "val.csv"][rng.gen_range(0..3)];
                    symlink(target, w.join("RUN").join(name)).unwrap();
                    format!("ALIAS/{name}")
                }
                3 => input_spelling(&mut rng, false),
                _ => format!("RUN/{name}"),
            }
        } else {
            // an output folder: new, a plain folder, or an alias of the run folder, with
            // links and hard links to inputs planted under the names the command writes
            let dir = match rng.gen_range(0..3) {
                0 => "OUT".to_string(),
                1 => {
                    std::fs::create_dir(w.join("OUT")).unwrap();
                    "OUT".to_string()
                }
                _ => "ALIAS".to_string(),
            };
            if w.join(&dir).is_dir() {
                for _ in 0..rng.gen_range(1..4) {
                    let name = names(writer)[rng.gen_range(0..names(writer).len())];
                    let at = w.join(&dir).join(name);
                    if std::fs::symlink_metadata(&at).is_ok() {
                        continue;
                    }
                    let target = input_spelling(&mut rng, true);
                    if rng.gen_bool(0.5) {
                        symlink(&target, &at).unwrap();
                    } else {
                        let resolved = w.join(&dir).join(&target);
                        let _ = std::fs::hard_link(resolved, &at);
                    }
                }
            }
            dir
        };
        // what the command may legitimately replace: the files it writes (links followed for
        // a single output, as documented; the folder's entries by name); its own inputs never
        let canon = std::fs::canonicalize(w.join(&out));
        let may_write: Vec<PathBuf> = if single_output(writer).is_some() {
            canon.into_iter().collect()
        } else {
            canon
                .map(|d| names(writer).iter().map(|n| d.join(n)).collect())
                .unwrap_or_default()
        };
        let own: &[&str] = match writer {
            0 | 6 | 7 => &["M.toml"],
            1 => &["REC"],
            8 => &["M.urdf"],
            9 => &["J.csv"],
            10 => &["M.toml", "P.csv"],
            11 => &["SCAN.png"],
            12 => &["JS.csv", "REC", "T.csv", "PL.toml", "POT.toml"],
            13 => &[],
            2 => &[
                "RUN/cal.csv",
                "RUN/val.csv",
                "RUN/truth.toml",
                "RUN/truth.json",
            ],
            _ => &["RUN/cal.csv", "RUN/val.csv"],
        };
        let guarded: Vec<(PathBuf, Vec<u8>)> = before
            .iter()
            .filter(|(p, _)| {
                own.iter().any(|o| w.join(o) == *p)
                    || !std::fs::canonicalize(p).is_ok_and(|c| may_write.contains(&c))
            })
            .cloned()
            .collect();
        let args = command(writer, &out);
        let args_ref: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, err) = run(w, &args_ref);
        let what = format!("trial {trial} (seed {seed}): rigctl {}", args.join(" "));
        assert!(matches!(code, Some(0..=2)), "{what}: exit {code:?}: {err}");
        codes[code.unwrap() as usize] += 1;
        assert_inputs_intact(&guarded, &what);
        assert_no_temp(w, &what);
    }
    // both outcomes occur: the layouts are not all refused, nor all harmless
    assert!(codes[0] > 0 && codes[2] > 0, "exit codes {codes:?}");
}
