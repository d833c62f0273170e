//! `rigctl`: thin entry point. Parses the command line, runs one subcommand and turns its error
//! into an exit code (FORMATS.md: 0 success, 1 failure of the run, 2 bad input or usage).

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = match cli::Cli::try_parse() {
        Ok(args) => args,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rigctl: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
