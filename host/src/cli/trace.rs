//! `rigctl trace`: the pencil centreline of a scanned sheet as CSV `x,y` (sheet mm).

use super::out::errln;
use super::CliError;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rigctl::trace::{load_scan, trace_image, write_csv, Mapping, TraceOptions};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scan (PNG or JPEG), at least 300 dpi.
    pub scan: PathBuf,
    /// Measured centre-to-centre spacing of the corner fiducials, mm.
    #[arg(long, default_value_t = 180.0)]
    pub fiducial_spacing_mm: f64,
    /// Output CSV `x,y` (mm).
    #[arg(long)]
    pub out: PathBuf,
    /// The image has no fiducials: map pixels by --mm-per-px about the image centre.
    #[arg(long, requires = "mm_per_px")]
    pub no_fiducials: bool,
    /// Scale for --no-fiducials, mm per pixel.
    #[arg(long, requires = "no_fiducials")]
    pub mm_per_px: Option<f64>,
    /// Join stroke pieces whose ends are at most this far apart, mm.
    #[arg(long, default_value_t = 2.0)]
    pub max_gap_mm: f64,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::check_outputs([Some(args.out.as_path())])?;
    let mapping = match (args.no_fiducials, args.mm_per_px) {
        (true, Some(mm_per_px)) => Mapping::Scale { mm_per_px },
        (true, None) => return Err(CliError::bad_input("--no-fiducials needs --mm-per-px")),
        (false, _) => Mapping::Fiducials {
            spacing_mm: args.fiducial_spacing_mm,
        },
    };
    let opts = TraceOptions {
        mapping,
        max_gap_mm: args.max_gap_mm,
        ..TraceOptions::default()
    };
    let img = load_scan(&args.scan)?;
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
    let trace = trace_image(&img, &opts, &progress);
    progress.finish_and_clear();
    let trace = trace.map_err(|e| CliError::from(e).in_file(&args.scan))?;
    let main = trace
        .main_stroke()
        .ok_or_else(|| CliError::bad_input("no pencil trace found").in_file(&args.scan))?;
    write_csv(&args.out, &main.points_mm)?;
    errln!(
        "rigctl trace: {} points, {:.1} mm{}{} ({:.1} px/mm{})",
        main.points_mm.len(),
        main.length_mm(),
        if main.closed { ", closed" } else { "" },
        if main.bridged_mm > 0.0 {
            format!(", {:.2} mm of gaps bridged", main.bridged_mm)
        } else {
            String::new()
        },
        trace.px_per_mm,
        trace
            .dot_residual_mm
            .map(|r| format!(", fiducial check {r:.3} mm"))
            .unwrap_or_default(),
    );
    if trace.strokes.len() > 1 {
        let rest: f64 = trace.strokes[1..].iter().map(|s| s.length_mm()).sum();
        errln!(
            "rigctl trace: warning: {} other stroke(s), {rest:.1} mm in all, not written (only the longest is)",
            trace.strokes.len() - 1
        );
    }
    Ok(())
}
