//! `rigctl board_sim` (being written).

use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::failure("rigctl board_sim: not implemented yet"))
}
