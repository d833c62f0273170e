//! stdout and stderr for every subcommand: never a panic on a closed or full stream.
//!
//! - stdout closed by its reader (`rigctl ... | head -1`, EPIPE): the command ends quietly with
//!   exit status 141 (as a Unix tool killed by SIGPIPE), removing any temporary output file.
//! - stdout on a full disk (`> /dev/full`) or any other write error: exit 1 with a message on
//!   stderr.
//! - stderr errors are ignored (there is nowhere left to report them).

use std::fmt;
use std::io::Write;

use super::CliError;

/// The command-line arguments with a hidden character (`rigctl::io::shown::is_hidden`).
fn hostile_args() -> &'static [String] {
    static ARGS: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    ARGS.get_or_init(|| {
        std::env::args_os()
            .map(|a| a.to_string_lossy().into_owned())
            .filter(|a| a.chars().any(rigctl::io::shown::is_hidden))
            .collect()
    })
}

/// Exit status when stdout's reader has gone (128 + SIGPIPE).
pub const BROKEN_PIPE_EXIT: u8 = 141;

/// Writes `args` to stdout and flushes.
pub fn stdout_fmt(args: fmt::Arguments<'_>) -> Result<(), CliError> {
    let mut out = std::io::stdout().lock();
    out.write_fmt(args)
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// Writes bytes to stdout and flushes.
pub fn stdout_bytes(bytes: &[u8]) -> Result<(), CliError> {
    let mut out = std::io::stdout().lock();
    out.write_all(bytes)
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// The error for a failed write to stdout.
pub fn stdout_error(e: std::io::Error) -> CliError {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        CliError::quiet(BROKEN_PIPE_EXIT)
    } else {
        CliError::failure(format!("cannot write to stdout: {e}"))
    }
}

/// Writes `args` to stderr, ignoring errors.
/// Control characters other than newline and tab, and the bidirectional overrides, are
/// escaped (`rigctl::io::shown`): a file name cannot drive the terminal.
/// A command-line argument holding a hidden character (a file name with a newline) is shown
/// escaped wherever it appears in a message, newline included.
pub fn stderr_fmt(args: fmt::Arguments<'_>) {
    let mut text = args.to_string();
    for arg in hostile_args() {
        if text.contains(arg.as_str()) {
            text = text.replace(arg.as_str(), &rigctl::io::shown::escape(arg));
        }
    }
    let text = rigctl::io::shown::escape_keep_lines(&text);
    let mut err = std::io::stderr().lock();
    let _ = err.write_all(text.as_bytes());
    let _ = err.flush();
}

/// `println!` that returns a [`CliError`] instead of panicking (use with `?`).
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::out::stdout_fmt(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` that returns a [`CliError`] instead of panicking (use with `?`).
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cli::out::stdout_fmt(format_args!($($arg)*))
    };
}

/// `eprintln!` that ignores a closed or full stderr.
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::cli::out::stderr_fmt(format_args!("{}\n", format_args!($($arg)*)))
    };
}

pub(crate) use {errln, out, outln};
