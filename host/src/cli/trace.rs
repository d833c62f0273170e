//! `rigctl trace`: the pencil centreline of a scanned or photographed sheet as CSV `x,y`
//! (sheet mm). Exit 0 only when the written trace is the whole drawn path; 1 when part of it is
//! missing (nothing is written then but the overlay); 2 for unusable input. With `--paths DIR`
//! every path of graphite is written as a file of its own with a JSON summary that groups the
//! paths running alongside each other as the passes of one drawn line; exit 0 only when every
//! drawn line is whole.

use super::out::errln;
use super::CliError;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rigctl::sheet::ReferencePath;
use rigctl::trace::overlay::{render_drawing_overlay, render_overlay, write_overlay};
use rigctl::trace::{
    load_prepared_with, trace_paths, trace_prepared, write_csv, LeftOut, LeftOutKind, Mapping,
    PathChoice, Trace, TraceOptions, TraceParams,
};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scan (>= 300 dpi) or phone photo (PNG or JPEG).
    pub scan: PathBuf,
    /// Measured centre-to-centre spacing of the corner fiducials, mm.
    #[arg(long, default_value_t = 180.0)]
    pub fiducial_spacing_mm: f64,
    /// Output CSV `x,y` (mm).
    #[arg(long, required_unless_present = "paths", conflicts_with = "paths")]
    pub out: Option<PathBuf>,
    /// Write every drawn line as a path of its own into this directory: `path-001.csv`, ...
    /// (CSV `x,y`, mm, longest first) and `paths.json` (the drawn lines, each with the paths
    /// drawn along it as its passes, its ends and whether it is drawn end to end; each path's
    /// length, ends, gaps and whether it is whole; the strays).
    #[arg(long, value_name = "DIR")]
    pub paths: Option<PathBuf>,
    /// The image has no fiducials: map pixels by --mm-per-px about the image centre.
    #[arg(long, requires = "mm_per_px")]
    pub no_fiducials: bool,
    /// Scale for --no-fiducials, mm per pixel.
    #[arg(long, requires = "no_fiducials")]
    pub mm_per_px: Option<f64>,
    /// The printed path the pencil was meant to follow, a hint between chains of graphite of
    /// similar length (auto: whichever the pencil runs along; free: no hint).
    #[arg(long, value_enum, default_value = "auto")]
    pub path: PathArg,
    /// Pencil skips up to this long (between ends that continue each other) are bridged; longer
    /// gaps fail, mm.
    #[arg(long, default_value_t = 10.0)]
    pub max_gap_mm: f64,
    /// Also write the overlay (trace and fitted marks drawn on the input) as PNG.
    #[arg(long)]
    pub overlay: Option<PathBuf>,
    /// The stages' numbers from this TOML file over the tuned values: a table per stage
    /// (`[link]`, `[lines]`, `[centreline]`, `[camera]`, `[fiducials]`, `[prepare]`), a key per
    /// number (docs/trace.md "Stages and their numbers").
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathArg {
    Auto,
    Circle,
    Line,
    Free,
}

/// The files `trace --paths DIR` writes (and removes, when stale) in its folder.
fn writes_in_paths_dir(name: &str) -> bool {
    let numbered = |prefix: &str| {
        name.strip_prefix(prefix)
            .and_then(|r| r.strip_suffix(".csv"))
            .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
    };
    name == rigctl::trace::SUMMARY_FILE || numbered("path-") || numbered("line-")
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("SCAN", Some(&args.scan))
        .input("--params", args.params.as_deref())
        .output("--out", args.out.as_deref())
        .output("--overlay", args.overlay.as_deref())
        .output_dir("--paths", args.paths.as_deref(), writes_in_paths_dir)
        .check()?;
    let mapping = match (args.no_fiducials, args.mm_per_px) {
        (true, Some(mm_per_px)) => Mapping::Scale { mm_per_px },
        (true, None) => return Err(CliError::bad_input("--no-fiducials needs --mm-per-px")),
        (false, _) => Mapping::Fiducials {
            spacing_mm: args.fiducial_spacing_mm,
        },
    };
    if !(args.max_gap_mm.is_finite() && args.max_gap_mm >= 0.0) {
        return Err(CliError::bad_input(format!(
            "invalid --max-gap-mm {}: expected a length >= 0 mm",
            args.max_gap_mm
        )));
    }
    let params = match &args.params {
        Some(path) => TraceParams::read_toml(path)
            .map_err(|e| CliError::bad_input(format!("invalid --params {e}")))?,
        None => TraceParams::default(),
    };
    let opts = TraceOptions {
        params,
        mapping,
        max_gap_mm: args.max_gap_mm,
        path: match args.path {
            PathArg::Auto => PathChoice::Auto,
            PathArg::Circle => PathChoice::Known(ReferencePath::Circle),
            PathArg::Line => PathChoice::Known(ReferencePath::Line),
            PathArg::Free => PathChoice::Free,
        },
        ..TraceOptions::default()
    };
    if jpeg_truncated(&args.scan) {
        errln!(
            "rigctl trace: {}: warning: the JPEG has no end-of-image marker (truncated): only its first part is decoded, the rest is blank",
            args.scan.display()
        );
    }
    // A PNG's whole-image maps are built while it is decoded.
    let (img, prepared) = load_prepared_with(&args.scan, &opts.params.prepare)?;
    let progress = if u64::from(img.width()) * u64::from(img.height()) > 4_000_000 {
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("tracing {bar:40} {percent:>3}%")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    if let Some(dir) = &args.paths {
        let drawing = trace_paths(&img, &prepared, &opts, &progress);
        drop(prepared);
        progress.finish_and_clear();
        let drawing = drawing.map_err(|e| CliError::from(e).in_file(&args.scan))?;
        if let Some(path) = &args.overlay {
            write_overlay(
                path,
                &render_drawing_overlay(&img, &drawing, args.fiducial_spacing_mm),
            )?;
        }
        return super::trace_paths::finish(dir, &drawing);
    }
    let trace = trace_prepared(&img, &prepared, &opts, &progress);
    drop(prepared);
    progress.finish_and_clear();
    let trace = trace.map_err(|e| CliError::from(e).in_file(&args.scan))?;
    if let Some(path) = &args.overlay {
        write_overlay(
            path,
            &render_overlay(&img, &trace, args.fiducial_spacing_mm),
        )?;
    }
    report(&trace);
    if !trace.is_whole() {
        return Err(CliError::failure(missing_message(&trace)));
    }
    let main = trace
        .main_stroke()
        .ok_or_else(|| CliError::bad_input("no pencil trace found").in_file(&args.scan))?;
    if let Some(out) = &args.out {
        write_csv(out, &main.points_mm)?;
    }
    Ok(())
}

/// Warns when the image is coarser than the tracer is made for.
pub(super) fn warn_resolution(px_per_mm: f64) {
    if px_per_mm < 300.0 / 25.4 * 0.97 {
        errln!(
            "rigctl trace: warning: {:.0} dpi on the sheet, below the 300 dpi the tracer is made for; expect a coarser trace",
            px_per_mm * 25.4
        );
    }
}

fn report(trace: &Trace) {
    let Some(main) = trace.main_stroke() else {
        return;
    };
    warn_resolution(trace.px_per_mm);
    let camera = match (&trace.camera_fit, &trace.camera) {
        (Some(q), Some(c)) => format!(
            ", camera check {:.3} mm RMS ({:.3} max) on {} of {} marks, k1 {:.4} k2 {:.4}",
            q.rms_mm, q.max_mm, q.used, q.found, c.k1, c.k2
        ),
        _ => trace
            .dot_residual_mm
            .map(|r| format!(", fiducial check {r:.3} mm"))
            .unwrap_or_default(),
    };
    errln!(
        "rigctl trace: {} points, {:.1} mm{}{} ({:.1} px/mm{camera})",
        main.points_mm.len(),
        main.length_mm(),
        if main.closed { ", closed" } else { "" },
        if main.bridged_mm > 0.0 {
            format!(", {:.2} mm of skips bridged", main.bridged_mm)
        } else {
            String::new()
        },
        trace.px_per_mm,
    );
    if trace.tone.source != rigctl::trace::ToneSource::Assumed {
        errln!("rigctl trace: the image was {}", trace.tone.describe());
    }
    let l = &trace.linking;
    for g in l.gaps.iter().filter(|g| g.bridged) {
        errln!(
            "rigctl trace: gap bridged: {:.2} mm from ({:.2}, {:.2}) to ({:.2}, {:.2}) mm",
            g.length_mm,
            g.from_mm[0],
            g.from_mm[1],
            g.to_mm[0],
            g.to_mm[1]
        );
    }
    if let Some(g) = trace.grey_print {
        errln!(
            "rigctl trace: the printed {} is as dark as the pencil (no red ink: a greyscale scan, or the path printed in grey or black): {:.0} of its {:.0} mm seen and left out, with any pencil within {} mm of it (a crossing is bridged; pencil running along it is missing); scan in colour with the path printed in red to trace pencil on it",
            if g.path == ReferencePath::Circle { "circle" } else { "line" },
            g.seen_mm,
            g.printed_mm,
            rigctl::trace::grey_print::STRIP_MM,
        );
    }
    if let Some((path, mean)) = l.hint {
        errln!(
            "rigctl trace: {} piece(s) linked; the path lies {mean:.1} mm from the printed {} on average",
            l.pieces,
            if path == ReferencePath::Circle { "circle" } else { "line" },
        );
    }
    let specks: Vec<&LeftOut> = l
        .left_out
        .iter()
        .filter(|o| o.kind == LeftOutKind::Speck)
        .collect();
    if !specks.is_empty() {
        errln!(
            "rigctl trace: left out {} speck(s) (dust, fibres, flicks; {:.1} mm in all)",
            specks.len(),
            specks.iter().map(|o| o.length_mm).sum::<f64>()
        );
    }
    for o in l.left_out.iter().filter(|o| o.kind != LeftOutKind::Speck) {
        errln!(
            "rigctl trace: left out {}: {}",
            match o.kind {
                LeftOutKind::Mark => "a mark apart from the path",
                LeftOutKind::Continues => "a mark that may continue the path",
                _ => "a drawn line of its own",
            },
            describe(o)
        );
    }
}

pub(super) fn describe(o: &LeftOut) -> String {
    format!(
        "{:.1} mm from ({:.1}, {:.1}) to ({:.1}, {:.1}) mm",
        o.length_mm, o.from_mm[0], o.from_mm[1], o.to_mm[0], o.to_mm[1]
    )
}

fn missing_message(trace: &Trace) -> String {
    let l = &trace.linking;
    let mut parts: Vec<String> = Vec::new();
    let crossing_marks: Vec<usize> = l.crossings.iter().map(|c| c.other).collect();
    parts.extend(l
        .gaps
        .iter()
        .enumerate()
        .filter(|(i, g)| !g.bridged && !l.gaps_to_crossing.contains(i))
        .map(|(_, g)| {
            format!(
                "a gap of {:.1} mm from ({:.1}, {:.1}) to ({:.1}, {:.1}) mm (longer than --max-gap-mm)",
                g.length_mm, g.from_mm[0], g.from_mm[1], g.to_mm[0], g.to_mm[1]
            )
        }));
    for (_, o) in l
        .left_out
        .iter()
        .enumerate()
        .filter(|(i, o)| o.could_be_path() && !crossing_marks.contains(i))
    {
        parts.push(format!(
            "{} {}",
            if o.kind == LeftOutKind::Continues {
                "a mark that may continue it,"
            } else {
                "another drawn line,"
            },
            describe(o)
        ));
    }
    for p in &trace.ends_at_print_mm {
        parts.push(format!(
            "whatever goes on from its end at ({:.1}, {:.1}) mm under the printed path (as dark as the pencil)",
            p[0], p[1]
        ));
    }
    match crossing_message(l) {
        Some(cross) if parts.is_empty() => format!("{cross}; nothing written"),
        Some(cross) => format!(
            "{cross}; the path also misses {}; nothing written",
            parts.join("; ")
        ),
        None => format!(
            "the pencil trace is not the whole drawn path: missing {}; nothing written",
            parts.join("; ")
        ),
    }
}

/// "two drawn paths cross at (x, y) and (x, y) mm (the other ...)" when another run crosses
/// or meets the path.
fn crossing_message(l: &rigctl::trace::Linking) -> Option<String> {
    if l.crossings.is_empty() {
        return None;
    }
    // Two parts of the other run (cut where it met the path) meet it at the same place.
    let mut places: Vec<[f64; 2]> = Vec::new();
    for c in &l.crossings {
        if places
            .iter()
            .all(|p| (p[0] - c.at_mm[0]).hypot(p[1] - c.at_mm[1]) > 3.0)
        {
            places.push(c.at_mm);
        }
    }
    let at: Vec<String> = places
        .iter()
        .map(|p| format!("({:.1}, {:.1})", p[0], p[1]))
        .collect();
    let mut others: Vec<usize> = l.crossings.iter().map(|c| c.other).collect();
    others.sort_unstable();
    others.dedup();
    let seen: Vec<String> = others
        .iter()
        .filter_map(|&i| l.left_out.get(i))
        .map(describe)
        .collect();
    Some(format!(
        "two drawn paths cross at {} mm: the sheet holds a second drawing (the other path, seen as {}), so the trace is not the one drawn path; `--paths DIR` writes each",
        at.join(", "),
        seen.join(" and ")
    ))
}

/// Whether `path` is a JPEG (starts with SOI) whose scan data is not followed by an end-of-image
/// marker: a file cut short, which the decoder fills with blank blocks without an error.
fn jpeg_truncated(path: &std::path::Path) -> bool {
    // a PNG or anything else: reading stops after its first block
    let Ok(bytes) = rigctl::io::read::read_capped_magic(path, 1 << 30, &[0xFF, 0xD8]) else {
        return false; // the decoder reports an unreadable file
    };
    if !bytes.starts_with(&[0xFF, 0xD8]) {
        return false;
    }
    let Some(sos) = bytes.windows(2).position(|w| w == [0xFF, 0xDA]) else {
        return true;
    };
    !bytes[sos..].windows(2).any(|w| w == [0xFF, 0xD9])
}
