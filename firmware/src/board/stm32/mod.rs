//! The STM32 board glue (WeAct Black Pill and the other chip features): clocks, pins, and the
//! drivers behind the shared tasks' board interface:
//! - [`PotAdc`]: TIM3-paced ADC1 into a DMA ring (`pot.rs`);
//! - [`TiltSensors`]: SCL3300s on SPI1 (`tilt.rs`);
//! - [`SerialRx`] / [`SerialTx`]: USART1 by DMA (`usart.rs`);
//! - USB CDC-ACM, a second host link with its own tasks (`usb.rs`);
//! - [`StatusLed`]: PC13; logs over defmt-rtt, panics through panic-probe.

mod clock;
mod pins;
mod pot;
mod tilt;
mod usart;
mod usb;

use embassy_executor::Spawner;
use embassy_stm32::gpio::{Level, Output, Speed};
use embassy_stm32::peripherals::{DMA2_CH0, DMA2_CH2, DMA2_CH7, USART1, USB_OTG_FS};
use embassy_stm32::{bind_interrupts, dma, usart as hal_usart, usb as hal_usb};
use {defmt_rtt as _, panic_probe as _};

pub use pot::{PotAdc, POT_RING_LEN};
pub use tilt::{probe as probe_tilt, TiltSensors};
pub use usart::{SerialRx, SerialTx};

bind_interrupts!(
    /// Every interrupt the drivers need.
    pub struct Irqs {
        USART1 => hal_usart::InterruptHandler<USART1>;
        OTG_FS => hal_usb::InterruptHandler<USB_OTG_FS>;
        DMA2_STREAM0 => dma::InterruptHandler<DMA2_CH0>;
        DMA2_STREAM2 => dma::InterruptHandler<DMA2_CH2>;
        DMA2_STREAM7 => dma::InterruptHandler<DMA2_CH7>;
    }
);

/// What the board is, for the boot log.
pub const BOARD_NAME: &str = "STM32F4 DAQ board";

/// The on-board LED (PC13, active low): on while sampling.
pub struct StatusLed(Output<'static>);

impl StatusLed {
    pub fn on(&mut self) {
        self.0.set_low();
    }

    pub fn off(&mut self) {
        self.0.set_high();
    }
}

/// The drivers, opened; `main` hands them to the shared tasks.
pub struct Hardware {
    pub pot: PotAdc,
    pub tilt: pins::TiltPins,
    pub serial_tx: SerialTx,
    pub serial_rx: SerialRx,
    pub status_led: StatusLed,
    pub board_id: [u8; 12],
    /// The USB link, started by [`spawn_board_tasks`].
    pub board_tasks: pins::UsbPins,
}

/// Clocks, pins and drivers.
pub fn init() -> Hardware {
    let board = pins::Board::new(embassy_stm32::init(clock::config()));
    let (serial_tx, serial_rx) = usart::open(board.link);
    Hardware {
        pot: PotAdc::new(board.pot),
        tilt: board.tilt,
        serial_tx,
        serial_rx,
        status_led: StatusLed(Output::new(board.status_led, Level::High, Speed::Low)),
        board_id: embassy_stm32::uid::uid(),
        board_tasks: board.usb,
    }
}

/// Starts what only this board has: the USB CDC-ACM link.
pub fn spawn_board_tasks(spawner: Spawner, usb_pins: pins::UsbPins) {
    let (usb_device, usb_tx, usb_rx) = usb::open(usb_pins);
    crate::spawn(spawner, usb::usb_device_task(usb_device));
    crate::spawn(spawner, usb::usb_tx_task(usb_tx));
    crate::spawn(spawner, usb::usb_rx_task(usb_rx));
}
