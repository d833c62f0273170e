//! `rigctl trace --paths DIR`: every drawn line (its centreline) and every path written to a
//! file of its own, the drawn lines (the band of ink a line's passes leave) reported on
//! stderr; a failure (exit 1) naming each drawn line that is not whole.

use super::out::errln;
use super::trace::{describe, warn_resolution};
use super::CliError;
use rigctl::trace::{line_file_name, path_file_name, write_drawing, Drawing};
use std::path::Path;

/// Writes `drawing` into `dir` and reports it; `Err` (a run failure) when a path is not whole.
pub fn finish(dir: &Path, drawing: &Drawing) -> Result<(), CliError> {
    let summary = write_drawing(dir, drawing)?;
    warn_resolution(drawing.px_per_mm);
    for (i, p) in drawing.paths.iter().enumerate() {
        let pts = &p.stroke.points_mm;
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        let bridged = p.gaps.iter().filter(|g| g.bridged).count();
        errln!(
            "rigctl trace: {}: {:.1} mm{}, from ({:.1}, {:.1}) to ({:.1}, {:.1}) mm, {bridged} gap(s) bridged ({:.2} mm){}",
            path_file_name(i),
            p.stroke.length_mm(),
            if p.stroke.closed { ", closed" } else { "" },
            a[0],
            a[1],
            b[0],
            b[1],
            p.stroke.bridged_mm + 0.0,
            if p.is_whole() { "" } else { ", NOT whole" },
        );
    }
    if !drawing.strays.is_empty() {
        errln!(
            "rigctl trace: left out {} stray mark(s) shorter than a path ({:.1} mm in all), listed in {}",
            drawing.strays.len(),
            drawing.strays.iter().map(|o| o.length_mm).sum::<f64>(),
            summary.display()
        );
    }
    for (i, l) in drawing.lines.iter().enumerate() {
        if l.passes.len() > 1 || !l.is_whole() {
            errln!(
                "rigctl trace: line {} ({}): {:.1} mm{}, from ({:.1}, {:.1}) to ({:.1}, {:.1}) mm, {} pass(es): {}{}",
                i + 1,
                line_file_name(i),
                l.length_mm,
                if l.closed { ", closed" } else { "" },
                l.from_mm[0],
                l.from_mm[1],
                l.to_mm[0],
                l.to_mm[1],
                l.passes.len(),
                pass_list(&l.passes),
                if l.is_whole() { "" } else { ", NOT whole" },
            );
        }
    }
    errln!(
        "rigctl trace: {} drawn line(s) ({} whole) from {} path(s)",
        drawing.lines.len(),
        drawing.lines.iter().filter(|l| l.is_whole()).count(),
        drawing.paths.len()
    );
    if drawing.is_whole() {
        return Ok(());
    }
    let parts: Vec<String> = drawing
        .lines
        .iter()
        .enumerate()
        .filter(|(_, l)| !l.is_whole())
        .map(|(i, l)| {
            let mut why: Vec<String> = l
                .gaps
                .iter()
                .filter(|g| !g.bridged)
                .map(|g| {
                    format!(
                        "a gap of {:.1} mm from ({:.1}, {:.1}) to ({:.1}, {:.1}) mm (longer than --max-gap-mm)",
                        g.length_mm, g.from_mm[0], g.from_mm[1], g.to_mm[0], g.to_mm[1]
                    )
                })
                .collect();
            why.extend(
                l.continued_by
                    .iter()
                    .map(|o| format!("a mark that may continue it, {}", describe(o))),
            );
            format!(
                "line {} ({}) [{}] ({})",
                i + 1,
                line_file_name(i),
                pass_list(&l.passes),
                why.join("; ")
            )
        })
        .collect();
    Err(CliError::failure(format!(
        "{} of {} drawn lines are not whole: {}; all paths written to {}, see {}",
        parts.len(),
        drawing.lines.len(),
        parts.join(" | "),
        dir.display(),
        summary.display()
    )))
}

/// The file names of the paths `passes`, comma-separated.
fn pass_list(passes: &[usize]) -> String {
    passes
        .iter()
        .map(|&p| path_file_name(p))
        .collect::<Vec<_>>()
        .join(", ")
}
