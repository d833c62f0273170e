//! The board: everything that differs between the STM32 DAQ board and the emulated MPS2
//! AN386 (QEMU). Both export the same names, which the shared tasks use:
//!
//! | name | what |
//! |---|---|
//! | `init() -> Hardware` | clocks, pins, drivers; `Hardware` holds them and the board id |
//! | `PotAdc`, `POT_RING_LEN` | the potentiometer's timer-paced ADC ring (`start`, `stop`, `read_latest`) |
//! | `probe_tilt(..) -> TiltSensors` | the inclinometers found at boot (`count`, `read`) |
//! | `SerialRx`, `SerialTx` | the serial host link (`read`, `write`; errors name themselves with `as_str`) |
//! | `StatusLed` | `on` while sampling, `off` otherwise |
//! | `spawn_board_tasks` | what only this board runs (STM32: USB; emulated: its test switches) |

#[cfg(all(feature = "stm32", feature = "mps2-an386"))]
compile_error!(
    "choose one board: an STM32 chip feature or `mps2-an386` (with --no-default-features)"
);
#[cfg(not(any(feature = "stm32", feature = "mps2-an386")))]
compile_error!(
    "choose a board feature: stm32f411 (default), stm32f401, stm32f446, stm32f405 or mps2-an386"
);

#[cfg(feature = "mps2-an386")]
mod mps2;
#[cfg(feature = "stm32")]
mod stm32;

#[cfg(feature = "mps2-an386")]
pub use mps2::*;
#[cfg(feature = "stm32")]
pub use stm32::*;
