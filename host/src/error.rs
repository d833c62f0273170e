//! Error classification. Library errors are typed (each module has its own `thiserror` enum);
//! they say whether the *input* was bad or the *run* failed, and only the binary turns that into
//! an exit code (FORMATS.md: 1 failure of the run, 2 bad input or usage).

/// What kind of failure an error is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The user's input (a file, a value, an argument) is wrong: exit code 2.
    BadInput,
    /// The run itself failed (device lost, solver failed, I/O): exit code 1.
    Failure,
}

/// Implemented by every library error type.
pub trait Classify {
    fn kind(&self) -> ErrorKind;
}
