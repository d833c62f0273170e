//! DAQ board firmware of the calibration rig: potentiometer (ADC), up to three SCL3300
//! inclinometers (SPI) and a framed link to the host over USART1 and USB CDC-ACM.
//!
//! This crate is the hardware glue. Everything that can be tested on a PC (framing, batching,
//! the command state machine, counters) lives in `rig-protocol` and is shared with the host's
//! virtual board. See `firmware/README.md` for the tasks and how to build and flash.
#![no_std]
#![no_main]

mod adc_task;
mod board;
mod clock;
mod link_usart;
mod link_usb;
mod shared;
mod tilt_task;

use defmt::{info, unwrap};
use embassy_executor::Spawner;
use embassy_stm32::gpio::{Level, Output, Speed};
use embassy_stm32::peripherals::{DMA2_CH0, DMA2_CH2, DMA2_CH7, USART1, USB_OTG_FS};
use embassy_stm32::{bind_interrupts, dma, usart, usb};
use rig_protocol::device::{Board as BoardCore, BoardInfo};
use {defmt_rtt as _, panic_probe as _};

use crate::adc_task::PotSampler;
use crate::board::Board;
use crate::shared::Shared;

bind_interrupts!(
    /// Every interrupt the drivers need.
    pub struct Irqs {
        USART1 => usart::InterruptHandler<USART1>;
        OTG_FS => usb::InterruptHandler<USB_OTG_FS>;
        DMA2_STREAM0 => dma::InterruptHandler<DMA2_CH0>;
        DMA2_STREAM2 => dma::InterruptHandler<DMA2_CH2>;
        DMA2_STREAM7 => dma::InterruptHandler<DMA2_CH7>;
    }
);

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

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let board = Board::new(embassy_stm32::init(clock::config()));
    info!("rig firmware {}", env!("CARGO_PKG_VERSION"));

    // The SCL3300 needs a few ms after power-up before it takes SPI commands.
    embassy_time::Timer::after_millis(SENSOR_POWER_UP_MS).await;
    let tilt_sensors = tilt_task::probe(board.tilt);
    let info = BoardInfo {
        firmware_version: firmware_version(),
        board_id: embassy_stm32::uid::uid(),
        tilt_sensors: tilt_sensors.count(),
    };
    shared::init(Shared {
        board: BoardCore::new(info),
        pot: PotSampler::new(board.pot),
        status_led: Output::new(board.status_led, Level::High, Speed::Low),
    });
    let (usart_tx, usart_rx) = link_usart::open(board.link);
    let (usb_device, usb_tx, usb_rx) = link_usb::open(board.usb);

    spawner.spawn(unwrap!(link_usart::usart_tx_task(usart_tx)));
    spawner.spawn(unwrap!(link_usart::usart_rx_task(usart_rx)));
    spawner.spawn(unwrap!(link_usb::usb_device_task(usb_device)));
    spawner.spawn(unwrap!(link_usb::usb_tx_task(usb_tx)));
    spawner.spawn(unwrap!(link_usb::usb_rx_task(usb_rx)));
    spawner.spawn(unwrap!(adc_task::adc_task()));
    spawner.spawn(unwrap!(tilt_task::tilt_task(tilt_sensors)));
}
