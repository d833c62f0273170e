//! `rigctl ports`: the serial ports the OS knows, one per line (`PATH<TAB>DESCRIPTION`).

use super::out::{errln, outln};
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: Args) -> Result<(), CliError> {
    let ports = rigctl::daq::link::list_ports()?;
    if ports.is_empty() {
        errln!("rigctl ports: no serial ports found (is the board plugged in?)");
    }
    for port in ports {
        outln!("{}\t{}", port.path, port.description)?;
    }
    Ok(())
}
