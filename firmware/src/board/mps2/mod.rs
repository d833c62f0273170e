//! The emulated board: QEMU's `mps2-an386` (ARM MPS2 with the AN386 FPGA image, a
//! Cortex-M4F at 25 MHz), which runs the same tasks as the STM32 board with these drivers:
//! - embassy-time on the CMSDK timers TIMER0 (free-running) and TIMER1 (alarm)
//!   (`time_driver.rs`);
//! - [`SerialRx`] / [`SerialTx`]: CMSDK UART0, interrupt driven (`uart.rs`), which QEMU
//!   connects to a pseudo-terminal;
//! - [`PotAdc`]: a ring of conversions of the known ramp (`pot.rs`);
//! - [`TiltSensors`]: three inclinometers answering from the known table (`tilt.rs`);
//! - [`StatusLed`]: FPGAIO LED0; logs, panics and hard faults over semihosting
//!   (`semihosting.rs`), which also carries the test switches.
//!
//! `firmware/emulated/run.sh` builds and starts it.

mod executor;
mod irq;
mod pot;
mod semihosting;
mod tilt;
mod time_driver;
mod uart;

use core::ptr::write_volatile;

use embassy_executor::Spawner;

pub use executor::run_executor;
pub use pot::{PotAdc, POT_RING_LEN};
pub use semihosting::log_line;
pub use tilt::{probe as probe_tilt, TiltBus, TiltSensors};
pub use uart::{SerialRx, SerialTx};

/// What the board is, for the boot log.
pub const BOARD_NAME: &str = "emulated MPS2 AN386 (QEMU)";

/// The board id sent in `Hello`.
const BOARD_ID: [u8; 12] = *b"QEMU-AN386\0\0";

/// FPGAIO LED register (bit 0: LED0).
const FPGAIO_LED: usize = 0x4002_8000;

/// FPGAIO LED0: on while sampling.
pub struct StatusLed(());

impl StatusLed {
    pub fn on(&mut self) {
        set_led(true);
    }

    pub fn off(&mut self) {
        set_led(false);
    }
}

fn set_led(on: bool) {
    // SAFETY: the AN386's FPGAIO LED register; nothing else uses it.
    unsafe { write_volatile(FPGAIO_LED as *mut u32, u32::from(on)) };
}

/// The drivers, opened; `main` hands them to the shared tasks.
pub struct Hardware {
    pub pot: PotAdc,
    pub tilt: TiltBus,
    pub serial_tx: SerialTx,
    pub serial_rx: SerialRx,
    pub status_led: StatusLed,
    pub board_id: [u8; 12],
    /// The test switches, acted on by [`spawn_board_tasks`].
    pub board_tasks: semihosting::Switches,
}

/// Timers, UART, and the switches from the semihosting command line.
pub fn init() -> Hardware {
    time_driver::init();
    let (serial_tx, serial_rx) = uart::open();
    set_led(false);
    Hardware {
        pot: PotAdc::new(),
        tilt: TiltBus,
        serial_tx,
        serial_rx,
        status_led: StatusLed(()),
        board_id: BOARD_ID,
        board_tasks: semihosting::switches(),
    }
}

/// Starts what only this board runs: the forced panic or stack overflow, if asked for.
pub fn spawn_board_tasks(spawner: Spawner, switches: semihosting::Switches) {
    if let Some(ms) = switches.panic_after_ms {
        crate::spawn(spawner, forced_panic_task(ms));
    }
    if let Some(ms) = switches.overflow_after_ms {
        crate::spawn(spawner, forced_overflow_task(ms));
    }
}

/// Panics `ms` after boot, from a task like any other (`panic-after-ms=N`).
#[embassy_executor::task]
async fn forced_panic_task(ms: u32) {
    embassy_time::Timer::at(embassy_time::Instant::from_millis(u64::from(ms))).await;
    panic!("forced panic after {} ms (panic-after-ms switch)", ms);
}

/// Recurses without end `ms` after boot (`overflow-after-ms=N`): the stack runs off the bottom
/// of RAM (flip-link put it there) and the core faults; `run.sh` reports it.
#[embassy_executor::task]
async fn forced_overflow_task(ms: u32) {
    embassy_time::Timer::at(embassy_time::Instant::from_millis(u64::from(ms))).await;
    crate::log::info!(
        "forced stack overflow after {} ms (overflow-after-ms switch)",
        ms
    );
    let depth = recurse(0);
    panic!(
        "the recursion returned at depth {}: no stack overflow",
        depth
    );
}

/// One 256-byte frame per call, kept live across the next call (`black_box`: neither the
/// frame nor the recursion can be optimised away or turned into a loop).
#[inline(never)]
fn recurse(depth: u32) -> u32 {
    let mut frame = [0u8; 256];
    core::hint::black_box(&mut frame);
    if core::hint::black_box(depth) == u32::MAX {
        return depth;
    }
    let deepest = recurse(depth + 1);
    core::hint::black_box(&frame);
    deepest
}
