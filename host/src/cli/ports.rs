//! `rigctl ports`: the serial ports the OS knows, one per line (`PATH<TAB>DESCRIPTION`).

use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: Args) -> Result<(), CliError> {
    let ports = rigctl::daq::link::list_ports()?;
    if ports.is_empty() {
        eprintln!("rigctl ports: no serial ports found (is the board plugged in?)");
    }
    for port in ports {
        println!("{}\t{}", port.path, port.description);
    }
    Ok(())
}
