//! Docs that cannot go stale: every ```sh block of README.md and docs/*.md runs as written.
//!
//! The blocks of one page run in order in one fresh directory (a walkthrough's later steps use
//! the files of the earlier ones), with `rigctl` the binary under test first on the PATH,
//! `../shared` the shared documents and data beside the checkout (as in a real checkout), and
//! `host/`, `scripts/` of the repository reachable as relative paths. Synopses with
//! placeholders are fenced ```text. A block that cannot run here is preceded by
//! `<!-- doc-test: skip: REASON -->` (the reason is required; the skipped blocks are listed).

use std::path::{Path, PathBuf};
use std::process::Command;

/// One fenced block: the page, its first line number, its text, and the skip reason if any.
struct Block {
    page: PathBuf,
    line: usize,
    text: String,
    skip: Option<String>,
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("repository root")
        .to_path_buf()
}

fn pages() -> Vec<PathBuf> {
    let root = repo();
    let mut out = vec![root.join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .expect("docs/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    docs.sort();
    out.extend(docs);
    out
}

/// The ```sh blocks of `page` (also indented ones, inside list items).
fn sh_blocks(page: &Path) -> Vec<Block> {
    let text = std::fs::read_to_string(page).expect("read page");
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let t = lines[k].trim_start();
        if t == "```sh" {
            let indent = lines[k].len() - t.len();
            let start = k + 1;
            let mut end = start;
            while end < lines.len() && lines[end].trim_start() != "```" {
                end += 1;
            }
            let body: Vec<String> = lines[start..end.min(lines.len())]
                .iter()
                .map(|l| {
                    l.get(indent.min(l.len() - l.trim_start().len())..)
                        .unwrap_or(l)
                        .to_string()
                })
                .collect();
            let skip = lines[..k]
                .iter()
                .rev()
                .find(|l| !l.trim().is_empty())
                .and_then(|l| {
                    l.trim()
                        .strip_prefix("<!-- doc-test: skip:")
                        .and_then(|r| r.strip_suffix("-->"))
                        .map(|r| r.trim().to_string())
                });
            out.push(Block {
                page: page.to_path_buf(),
                line: k + 1,
                text: body.join("\n"),
                skip,
            });
            k = end + 1;
        } else {
            k += 1;
        }
    }
    out
}

#[cfg(unix)]
fn link(target: &Path, at: &Path) {
    std::os::unix::fs::symlink(target, at).expect("symlink");
}

#[test]
#[cfg(unix)]
fn every_sh_block_of_the_docs_runs_as_written() {
    let Some(shared) = crate::common::shared_file("every_sh_block_of_the_docs_runs_as_written", "")
    else {
        return;
    };
    let bin_dir = crate::common::spawn::bin_dir();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut ran = 0;
    let mut skipped = Vec::new();
    let mut failures = Vec::new();
    for page in pages() {
        let blocks = sh_blocks(&page);
        if blocks.is_empty() {
            continue;
        }
        let root = tempfile::tempdir().expect("temp dir");
        let work = root.path().join("work");
        std::fs::create_dir(&work).expect("work dir");
        link(&shared, &root.path().join("shared"));
        for dir in ["host", "scripts"] {
            link(&repo().join(dir), &work.join(dir));
        }
        for b in blocks {
            let at = format!("{}:{}", b.page.display(), b.line);
            if let Some(reason) = &b.skip {
                assert!(!reason.is_empty(), "{at}: a skipped block needs a reason");
                skipped.push(format!("{at} ({reason})"));
                continue;
            }
            let out = Command::new("bash")
                .args(["-euo", "pipefail", "-c", &b.text])
                .current_dir(&work)
                .env("PATH", &path)
                .output()
                .expect("run bash");
            ran += 1;
            if !out.status.success() {
                failures.push(format!(
                    "{at}: exit {:?}\n{}\n--- stderr:\n{}",
                    out.status.code(),
                    b.text,
                    String::from_utf8_lossy(&out.stderr)
                        .lines()
                        .rev()
                        .take(15)
                        .collect::<Vec<_>>()
                        .into_iter()
                        .rev()
                        .collect::<Vec<_>>()
                        .join("\n")
                ));
            }
        }
    }
    eprintln!("doc blocks run: {ran}; skipped: {skipped:#?}");
    assert!(
        ran >= 10,
        "only {ran} blocks found: is the extraction broken?"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
