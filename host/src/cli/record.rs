//! `rigctl record --port PORT --out FILE [--duration S] [--pot-hz 1000] [--tilt-hz 100]`:
//! records the board's frames (format in `rigctl::daq::recording`), with a live line on stderr,
//! and prints `frames N, samples N, dropped N, crc_errors N` on stdout at the end (also when the
//! device is lost, before the error; exit 1 then).

use std::ops::RangeInclusive;
use std::path::PathBuf;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rig_protocol::device::{POT_RATE_HZ, TILT_RATE_HZ};
use rigctl::daq::session::{record, RecordConfig, Timing};
use rigctl::daq::tally::Tally;

use super::out::outln;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Serial port of the board (see `rigctl ports`), or a board-sim link.
    #[arg(long, value_name = "PORT")]
    pub port: PathBuf,
    /// Recording file to create.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Stop after this many seconds (default: at Ctrl-C).
    #[arg(long, value_name = "S", value_parser = parse_seconds)]
    pub duration: Option<f64>,
    /// Potentiometer sample rate, Hz (100..=10000).
    #[arg(long, value_name = "HZ", default_value_t = 1000, value_parser = parse_pot_hz)]
    pub pot_hz: u32,
    /// Read rate of each inclinometer, Hz (1..=1000).
    #[arg(long, value_name = "HZ", default_value_t = 100, value_parser = parse_tilt_hz)]
    pub tilt_hz: u32,
    /// Replace FILE if it exists.
    #[arg(long)]
    pub overwrite: bool,
}

/// A rate within what the protocol's `Start` accepts.
fn parse_rate(s: &str, range: RangeInclusive<u32>) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(v) if range.contains(&v) => Ok(v),
        _ => Err(format!(
            "`{s}` is not a rate in {}..={} Hz",
            range.start(),
            range.end()
        )),
    }
}

fn parse_pot_hz(s: &str) -> Result<u32, String> {
    parse_rate(s, POT_RATE_HZ)
}

fn parse_tilt_hz(s: &str) -> Result<u32, String> {
    parse_rate(s, TILT_RATE_HZ)
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v < 1e9 => Ok(v),
        _ => Err(format!("`{s}` is not a positive number of seconds")),
    }
}

/// The live line: rates over the last interval and the counters.
struct Live {
    bar: ProgressBar,
    last: Option<(Duration, u64, u64)>,
}

impl Live {
    fn new() -> Self {
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template("{spinner} {msg}") {
            bar.set_style(style);
        }
        Self { bar, last: None }
    }

    fn update(&mut self, tally: &Tally, elapsed: Duration) {
        let (frame_rate, sample_rate) = match self.last {
            Some((t, frames, samples)) if elapsed > t => {
                let dt = (elapsed - t).as_secs_f64();
                (
                    (tally.frames - frames) as f64 / dt,
                    (tally.samples - samples) as f64 / dt,
                )
            }
            _ => (0.0, 0.0),
        };
        self.last = Some((elapsed, tally.frames, tally.samples));
        self.bar.set_message(format!(
            "{:.1} s | {frame_rate:.0} frames/s | {sample_rate:.0} samples/s | dropped {} | crc errors {}",
            elapsed.as_secs_f64(),
            tally.dropped(),
            tally.crc_errors
        ));
        self.bar.tick();
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--port", Some(&args.port))
        .output("--out", Some(&args.out))
        .check()?;
    // Ctrl-C and SIGTERM stop the recording cleanly: summary, exit 0.
    let stop = rigctl::io::interrupt::cooperative_stop();
    let cfg = RecordConfig {
        port: args.port,
        out: args.out,
        duration: args.duration.map(Duration::from_secs_f64),
        pot_rate_hz: args.pot_hz,
        tilt_rate_hz: args.tilt_hz,
        overwrite: args.overwrite,
        timing: Timing::default(),
    };
    let mut live = Live::new();
    let result = record(&cfg, &stop, &mut |tally, elapsed| {
        live.update(tally, elapsed)
    });
    live.bar.finish_and_clear();
    match result {
        Ok(tally) => {
            outln!("{}", tally.summary_line())?;
            Ok(())
        }
        Err(e) => {
            if let Some(tally) = e.tally() {
                // The run's error matters more than a failed summary.
                let _ = outln!("{}", tally.summary_line());
            }
            Err(e.into())
        }
    }
}
