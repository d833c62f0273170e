//! `rigctl board-sim --link PATH [--duration-s S] [--pot-hz 1000] [--tilt-hz 100] [--sensors 3]
//! [--corrupt-ppm N] [--seed N] [--speed F]`: a virtual DAQ board on a pseudo-terminal linked at
//! PATH (behaviour in `rigctl::daq::board_sim`). Prints what it sent on stdout when it ends.

use std::path::PathBuf;
use std::time::Duration;

use rigctl::daq::board_sim::{serve, SimConfig};
use rigctl::daq::pty::{Pty, PtyLink};

use super::out::{errln, outln};
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Where to link the pseudo-terminal (pass it to `rigctl record --port`).
    #[arg(long, value_name = "PATH")]
    pub link: PathBuf,
    /// Stop the run this many seconds (board time) after Start (default: run until Stop).
    #[arg(long, value_name = "S", value_parser = parse_positive)]
    pub duration_s: Option<f64>,
    /// Highest potentiometer rate the virtual hardware accepts, Hz.
    #[arg(long, value_name = "HZ", default_value_t = 1000)]
    pub pot_hz: u32,
    /// Highest inclinometer rate the virtual hardware accepts, Hz.
    #[arg(long, value_name = "HZ", default_value_t = 100)]
    pub tilt_hz: u32,
    /// Number of inclinometers.
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u8).range(0..=16))]
    pub sensors: u8,
    /// Bytes per million replaced on the way out (delimiters are kept).
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=1_000_000))]
    pub corrupt_ppm: u32,
    /// Seed of the synthetic signals and of the corruption.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,
    /// Board time per wall time: 1 is real time, 10 runs ten times faster.
    #[arg(long, value_name = "F", default_value_t = 1.0, value_parser = parse_positive)]
    pub speed: f64,
}

fn parse_positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v < 1e9 => Ok(v),
        _ => Err(format!("`{s}` is not a positive number")),
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    let cfg = SimConfig {
        pot_hz_max: args.pot_hz,
        tilt_hz_max: args.tilt_hz,
        sensors: args.sensors,
        corrupt_ppm: args.corrupt_ppm,
        seed: args.seed,
        duration: args.duration_s.map(Duration::from_secs_f64),
        speed: args.speed,
    };
    // Ctrl-C and SIGTERM end the run cleanly: the link is removed.
    let stop = rigctl::io::interrupt::cooperative_stop();
    let mut pty = Pty::open()?;
    let link = PtyLink::create(&args.link, pty.slave_path())?;
    errln!(
        "rigctl board-sim: serving on {} -> {} (waiting for the host)",
        link.path().display(),
        pty.slave_path().display()
    );
    let (report, end) = serve(&mut pty, &cfg, &stop)?;
    drop(link);
    errln!("rigctl board-sim: ended ({end:?})");
    outln!("{report}")?;
    Ok(())
}
