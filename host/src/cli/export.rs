//! `rigctl export FILE --csv DIR`: `pot.csv`, `tilt.csv` and `status.csv` from a recording
//! (columns in `rigctl::daq::export`).

use std::path::PathBuf;

use rigctl::daq::export::export_csv;

use super::out::errln;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Recording written by `rigctl record`.
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Directory for pot.csv, tilt.csv and status.csv (created if missing).
    #[arg(long, value_name = "DIR")]
    pub csv: PathBuf,
    /// Refuse a damaged recording (exit 2) instead of skipping its damaged records.
    #[arg(long)]
    pub strict: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("FILE", Some(&args.file))
        .output_dir("--csv", Some(&args.csv), |n| {
            matches!(n, "pot.csv" | "tilt.csv" | "status.csv")
        })
        .check()?;
    let summary = export_csv(&args.file, &args.csv, args.strict)?;
    for d in &summary.damaged {
        errln!("rigctl export: {}: skipped {d}", args.file.display());
    }
    if summary.truncated_tail_bytes > 0 {
        errln!(
            "rigctl export: {}: ignored an incomplete last record ({} bytes; the run was cut short)",
            args.file.display(),
            summary.truncated_tail_bytes
        );
    }
    errln!(
        "rigctl export: {}: pot.csv {} rows, tilt.csv {} rows, status.csv {} rows ({} samples dropped)",
        args.csv.display(),
        summary.pot_rows,
        summary.tilt_rows,
        summary.status_rows,
        summary.tally.dropped()
    );
    if let Some(why) = &summary.out_of_range {
        return Err(CliError::failure(format!(
            "{}: {why}",
            rigctl::io::shown::shown(&args.file)
        )));
    }
    Ok(())
}
