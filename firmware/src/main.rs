//! DAQ board firmware of the calibration rig: potentiometer (ADC), up to three SCL3300
//! inclinometers (SPI) and a framed link to the host over a serial link (and USB CDC-ACM).
//!
//! This crate is the glue between the hardware and `rig-protocol`'s board core, which does
//! everything that can be tested on a PC (framing, batching, the command state machine,
//! counters). The tasks (`pot`, `tilt`, `link`, `shared`) are the same for every board; only
//! the drivers in `board/` differ: `board/stm32` for the DAQ board, `board/mps2` for the
//! emulated Cortex-M4 that QEMU runs in CI. See `firmware/README.md`.
#![no_std]
#![no_main]

mod board;
mod link;
mod log;
mod pot;
mod shared;
mod stack;
mod tilt;

use embassy_executor::{SpawnError, SpawnToken, Spawner};
use rig_protocol::device::{Board as BoardCore, BoardInfo};

use crate::log::info;
use crate::pot::PotSampler;
use crate::shared::Shared;

/// Wait after reset before the inclinometers are probed (a generous margin over their
/// power-on start-up time).
const SENSOR_POWER_UP_MS: u64 = 25;

/// This firmware's version, from Cargo.toml, as sent in `Hello`.
fn firmware_version() -> [u8; 3] {
    let part = |s: &str| s.parse::<u8>().unwrap_or(u8::MAX);
    [
        part(env!("CARGO_PKG_VERSION_MAJOR")),
        part(env!("CARGO_PKG_VERSION_MINOR")),
        part(env!("CARGO_PKG_VERSION_PATCH")),
    ]
}

/// Spawns a task; the task pools hold one of each, so a failure is a programming error.
pub fn spawn<S>(spawner: Spawner, token: Result<SpawnToken<S>, SpawnError>) {
    match token {
        Ok(token) => spawner.spawn(token),
        Err(_) => panic!("task spawned twice"),
    }
}

/// Boot, the same on every board: drivers, sensors, the shared state, then the tasks.
async fn boot(spawner: Spawner) {
    let hw = board::init();
    info!(
        "rig firmware {} on {}",
        env!("CARGO_PKG_VERSION"),
        board::BOARD_NAME
    );

    // The SCL3300 needs a few ms after power-up before it takes SPI commands.
    embassy_time::Timer::after_millis(SENSOR_POWER_UP_MS).await;
    let tilt_sensors = board::probe_tilt(hw.tilt);
    let info = BoardInfo {
        firmware_version: firmware_version(),
        board_id: hw.board_id,
        tilt_sensors: tilt_sensors.count(),
    };
    shared::init(Shared {
        board: BoardCore::new(info),
        pot: PotSampler::new(hw.pot),
        status_led: hw.status_led,
    });

    spawn(spawner, link::serial_tx_task(hw.serial_tx));
    spawn(spawner, link::serial_rx_task(hw.serial_rx));
    spawn(spawner, pot::adc_task());
    spawn(spawner, tilt::tilt_task(tilt_sensors));
    board::spawn_board_tasks(spawner, hw.board_tasks);
}

#[cfg(feature = "stm32")]
#[embassy_executor::main]
async fn main(spawner: Spawner) {
    boot(spawner).await;
}

#[cfg(feature = "mps2-an386")]
#[cortex_m_rt::entry]
fn main() -> ! {
    board::run_executor(|spawner| spawn(spawner, boot_task(spawner)))
}

/// [`boot`] as the emulated board's first task.
#[cfg(feature = "mps2-an386")]
#[embassy_executor::task]
async fn boot_task(spawner: Spawner) {
    boot(spawner).await;
}
