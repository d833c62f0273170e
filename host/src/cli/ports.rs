//! `rigctl ports` (being written).

use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::failure("rigctl ports: not implemented yet"))
}
