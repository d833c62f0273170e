//! Host link over USB full speed (PA11 D-, PA12 D+) as a CDC-ACM serial port.
//!
//! STM32 only (the emulated board has no USB). The same byte stream as on USART1 travels in 64-byte bulk packets. Three tasks:
//! - [`usb_device_task`] runs the USB stack (enumeration, control requests);
//! - [`usb_rx_task`] hands OUT packets to the board core, like the USART receiver;
//! - [`usb_tx_task`] sends the core's queued bytes while USB is the active link, ending each
//!   burst with a short (or zero-length) packet so the host sees it at once.
//!
//! The board is bus-powered, so VBUS sensing is off (it would need PA9, the USART's TX pin).

use defmt::{info, warn};
use embassy_stm32::peripherals::USB_OTG_FS;
use embassy_stm32::usb::Driver;
use embassy_usb::class::cdc_acm::{CdcAcmClass, Receiver, Sender, State};
use embassy_usb::driver::EndpointError;
use embassy_usb::{Builder, UsbDevice};
use static_cell::{ConstStaticCell, StaticCell};

use super::pins::UsbPins;
use super::Irqs;
use crate::shared::{self, LinkId};

/// The USB driver of this board.
pub type UsbDriver = Driver<'static, USB_OTG_FS>;

/// pid.codes test VID/PID: fine on a lab bench, replace before shipping boards to others.
const USB_VID: u16 = 0x1209;
const USB_PID: u16 = 0x0001;
/// Full-speed bulk packet size.
const PACKET_LEN: usize = 64;

static EP_OUT_BUF: ConstStaticCell<[u8; 256]> = ConstStaticCell::new([0; 256]);
static CONFIG_DESC: ConstStaticCell<[u8; 256]> = ConstStaticCell::new([0; 256]);
static BOS_DESC: ConstStaticCell<[u8; 256]> = ConstStaticCell::new([0; 256]);
static CONTROL_BUF: ConstStaticCell<[u8; 64]> = ConstStaticCell::new([0; 64]);
static CDC_STATE: StaticCell<State<'static>> = StaticCell::new();

/// Builds the CDC-ACM device and splits the class into its two directions.
pub fn open(
    pins: UsbPins,
) -> (
    UsbDevice<'static, UsbDriver>,
    Sender<'static, UsbDriver>,
    Receiver<'static, UsbDriver>,
) {
    let mut driver_config = embassy_stm32::usb::Config::default();
    driver_config.vbus_detection = false;
    let driver = Driver::new_fs(
        pins.usb_otg,
        Irqs,
        pins.usb_dp,
        pins.usb_dm,
        EP_OUT_BUF.take(),
        driver_config,
    );

    let mut config = embassy_usb::Config::new(USB_VID, USB_PID);
    config.manufacturer = Some("calibration-rig");
    config.product = Some("rig DAQ board");
    config.serial_number = Some(embassy_stm32::uid::uid_hex());
    config.max_power = 100;

    let mut builder = Builder::new(
        driver,
        config,
        CONFIG_DESC.take(),
        BOS_DESC.take(),
        &mut [], // no Microsoft OS descriptors
        CONTROL_BUF.take(),
    );
    let class = CdcAcmClass::new(
        &mut builder,
        CDC_STATE.init(State::new()),
        PACKET_LEN as u16,
    );
    let (tx, rx) = class.split();
    (builder.build(), tx, rx)
}

/// Runs the USB stack.
#[embassy_executor::task]
pub async fn usb_device_task(mut device: UsbDevice<'static, UsbDriver>) -> ! {
    device.run().await
}

/// Hands the bytes arriving over USB to the board core.
#[embassy_executor::task]
pub async fn usb_rx_task(mut rx: Receiver<'static, UsbDriver>) -> ! {
    let mut packet = [0u8; PACKET_LEN];
    loop {
        rx.wait_connection().await;
        info!("usb: host connected");
        loop {
            match rx.read_packet(&mut packet).await {
                Ok(n) => shared::receive(LinkId::Usb, &packet[..n]),
                Err(EndpointError::BufferOverflow) => warn!("usb rx: packet too long"),
                Err(EndpointError::Disabled) => break,
            }
        }
        info!("usb: host disconnected");
    }
}

/// Writes the board core's queued frames while USB is the active link.
#[embassy_executor::task]
pub async fn usb_tx_task(mut tx: Sender<'static, UsbDriver>) -> ! {
    let mut packet = [0u8; PACKET_LEN];
    loop {
        tx.wait_connection().await;
        loop {
            let n = shared::pop_tx(LinkId::Usb, &mut packet);
            if n == 0 {
                shared::wait_tx(LinkId::Usb).await;
                continue;
            }
            if write(&mut tx, &packet[..n]).await.is_err() {
                break; // disconnected: these bytes are lost, wait for the host again
            }
        }
    }
}

/// Sends one packet; a full packet is followed by a zero-length one when nothing else is
/// queued, so the host's driver hands the data over at once.
async fn write(tx: &mut Sender<'static, UsbDriver>, packet: &[u8]) -> Result<(), EndpointError> {
    tx.write_packet(packet).await?;
    if packet.len() == PACKET_LEN && shared::with(|s| s.board.tx_len()) == 0 {
        tx.write_packet(&[]).await?;
    }
    Ok(())
}
