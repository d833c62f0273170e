//! The board's portable logic: everything the firmware does that is not hardware, so that the
//! firmware (`firmware/`) and the host's virtual board (`rigctl board-sim`) run the same code
//! and the host's tests cover it.
//!
//! - [`Board`]: the core. Drive it with board timestamps (microseconds since boot):
//!   [`Board::boot`] once, [`Board::receive`] with bytes from the host (or
//!   [`Board::handle_command`] with decoded commands), [`Board::on_pot_sample`] for each ADC
//!   sample, [`Board::tilt_due`] to learn which inclinometer to read now and
//!   [`Board::on_tilt_reading`] / [`Board::on_sensor_error`] with the result,
//!   [`Board::on_overrun`] when the sampler fell behind, [`Board::poll`] periodically (or at
//!   [`Board::next_deadline_us`]); send what [`Board::tx_peek`] / [`Board::tx_pop_into`] give.
//!   Commands return an [`Action`] telling the firmware to start or stop its sampling timers.
//! - [`known_signal`]: what the emulated board's sensors return (checked by the host's test).
//! - Parts, usable alone: [`PotBatcher`], [`TiltScheduler`], [`FrameQueue`], [`RunConfig`].

mod board;
#[cfg(test)]
mod board_tests;
mod command;
pub mod known_signal;
mod pot;
mod queue;
mod tilt;

pub use board::{
    Action, Board, BoardInfo, CONTROL_RESERVE, POT_MAX_LATENCY_US, STATUS_PERIOD_US, TX_QUEUE_BYTES,
};
pub use command::{RunConfig, POT_RATE_HZ, TILT_RATE_HZ};
pub use pot::PotBatcher;
pub use queue::FrameQueue;
pub use tilt::TiltScheduler;
