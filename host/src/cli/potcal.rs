//! `rigctl potcal --points JIG.csv [--recording REC] [--degree 1] --out POT.toml`: calibrates the
//! pencil's potentiometer (counts -> travel mm) from a gauge-block jig (see
//! `rigctl::fusion::potcal` for the file formats).

use std::path::PathBuf;

use rigctl::fusion::pot::read_pot_samples;
use rigctl::fusion::potcal::{points_from_windows, read_jig_csv, JigFile, PotCalibration};

use super::out::{errln, outln};
use super::{note_damage, note_out_of_range, out_of_range_failure, CliError};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Jig points: CSV `raw,travel_mm`, or `start_s,end_s,travel_mm` windows of --recording.
    #[arg(long, value_name = "JIG.csv")]
    pub points: PathBuf,
    /// The board recording the windows refer to (seconds after its first pot sample).
    #[arg(long, value_name = "REC")]
    pub recording: Option<PathBuf>,
    /// Polynomial degree (1 = linear; up to 3).
    #[arg(long, default_value_t = 1)]
    pub degree: usize,
    /// Output calibration (TOML).
    #[arg(long, value_name = "POT.toml")]
    pub out: PathBuf,
    /// Refuse a damaged recording (exit 2) instead of skipping its damaged records.
    #[arg(long)]
    pub strict: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--points", Some(&args.points))
        .input("--recording", args.recording.as_deref())
        .output("--out", Some(&args.out))
        .check()?;
    let mut out_of_range = false;
    let points = match read_jig_csv(&args.points)? {
        JigFile::Points(_) if args.recording.is_some() => {
            return Err(CliError::bad_input(format!(
                "{}: the jig gives raw counts; --recording is only for a jig of time windows (start_s,end_s)",
                args.points.display()
            )))
        }
        JigFile::Points(p) => p,
        JigFile::Windows(w) => {
            let rec = args.recording.as_deref().ok_or_else(|| {
                CliError::bad_input(format!(
                    "{}: the jig gives time windows (start_s,end_s); pass the recording with --recording",
                    args.points.display()
                ))
            })?;
            let read = read_pot_samples(rec, args.strict, &mut note_damage)?;
            note_out_of_range(rec, read.out_of_range.as_deref());
            out_of_range = read.out_of_range.is_some();
            points_from_windows(&read.samples, &w).map_err(|e| CliError::from(e).in_file(rec))?
        }
    };
    let cal = PotCalibration::fit(&points, args.degree)?;
    cal.write(&args.out)?;
    outln!(
        "potcal: {} points, degree {}, {:.6} mm/count at the centre, counts {:.1}..{:.1}",
        cal.points,
        cal.coefficients.len() - 1,
        cal.mm_per_count(),
        cal.raw_min,
        cal.raw_max
    )?;
    match (cal.rms_residual_mm, cal.max_residual_mm) {
        (Some(rms), Some(max)) => outln!("residuals: rms {rms:.4} mm, max {max:.4} mm")?,
        _ => outln!(
            "residuals: none (exact fit through {} points; add points to check)",
            cal.points
        )?,
    }
    if let Some(w) = PotCalibration::nonlinearity(&points).filter(|_| args.degree == 1) {
        errln!("rigctl potcal: warning: {w}");
    }
    match args.recording.as_deref() {
        Some(rec) if out_of_range => Err(out_of_range_failure(rec, &args.out)),
        _ => Ok(()),
    }
}
