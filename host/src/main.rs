//! `rigctl`: thin entry point. Parses the command line, runs one subcommand and turns its error
//! into an exit code (FORMATS.md: 0 success, 1 failure of the run, 2 bad input or usage; a
//! closed stdout ends quietly with 141, an interruption with 130 after removing temporary
//! files).

mod cli;

use clap::Parser;
use std::process::ExitCode;

use cli::out::{errln, BROKEN_PIPE_EXIT};

fn main() -> ExitCode {
    let argv = match cli::project::merge_args(
        std::env::args_os().collect(),
        std::path::Path::new(cli::project::DEFAULT_FILE),
    ) {
        Ok(a) => a,
        Err(e) => {
            errln!("rigctl: {e}");
            return ExitCode::from(e.exit_code());
        }
    };
    let args = match cli::Cli::try_parse_from(argv) {
        Ok(args) => args,
        Err(e) => {
            if e.use_stderr() {
                let _ = e.print();
                return ExitCode::from(2);
            }
            // --help / --version on stdout.
            return match e.print() {
                Ok(()) => ExitCode::SUCCESS,
                Err(io) if io.kind() == std::io::ErrorKind::BrokenPipe => {
                    ExitCode::from(BROKEN_PIPE_EXIT)
                }
                Err(io) => {
                    errln!("rigctl: cannot write to stdout: {io}");
                    ExitCode::from(1)
                }
            };
        }
    };
    if let Err(e) = rigctl::io::interrupt::install() {
        errln!("rigctl: interruptions will not clean up ({e})");
    }
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            rigctl::io::interrupt::remove_live_temps();
            if e.quiet_exit.is_none() {
                errln!("rigctl: {e}");
            }
            ExitCode::from(e.exit_code())
        }
    }
}
