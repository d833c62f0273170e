//! The inclinometers: the board core's tilt scheduler says which of the sensors found at boot
//! to read and when (round robin, reads spread evenly); every reading becomes one
//! `TiltReading` frame. A failed read counts as `Status.sensor_errors` and sends nothing.
//! The sensors themselves are the board's (`board::TiltSensors`: SCL3300s on SPI1 on the
//! STM32, a known table on the emulated board).

use embassy_futures::select::select;
use embassy_time::{Instant, Timer};

use crate::board::TiltSensors;
use crate::shared::{self, now_us};

/// Reads the inclinometer the board core's scheduler asks for, when it asks.
#[embassy_executor::task]
pub async fn tilt_task(mut sensors: TiltSensors) -> ! {
    loop {
        match shared::with(|s| s.board.next_deadline_us()) {
            Some(deadline_us) => {
                let deadline = Instant::from_micros(deadline_us);
                select(Timer::at(deadline), shared::schedule_changed()).await;
            }
            None => shared::schedule_changed().await,
        }
        let read = shared::with(|s| {
            let now = now_us();
            // Keep the core's other deadlines moving too, so the wait above never spins.
            s.pot.drain(&mut s.board, now);
            s.board.poll(now);
            let slot = s.board.tilt_due(now)?;
            match sensors.read(slot, now) {
                Ok(reading) => s.board.on_tilt_reading(reading),
                Err(_) => s.board.on_sensor_error(),
            }
            Some(slot)
        });
        if read.is_some() {
            shared::tx_ready();
        }
    }
}
