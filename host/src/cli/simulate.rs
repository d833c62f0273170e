//! `rigctl simulate` (being written).

use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::failure("rigctl simulate: not implemented yet"))
}
