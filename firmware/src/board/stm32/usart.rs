//! The serial host link on the STM32: USART1 (PA9 TX, PA10 RX) at 921600 baud 8N1, both
//! directions by DMA (receive into a circular ring). The tasks are `crate::link`'s.

use embassy_stm32::mode::Async;
use embassy_stm32::usart::{self, RingBufferedUartRx, Uart, UartTx};
use static_cell::ConstStaticCell;

use super::pins::LinkPins;
use super::Irqs;

/// Baud rate of the host link. 96 MHz / 921600 = 104.17: 0.16 % error at 16x oversampling.
pub const LINK_BAUD: u32 = 921_600;

/// Receive ring buffer: 256 bytes = 2.8 ms of line time at full rate; commands are tiny.
const RX_RING_LEN: usize = 256;

static RX_RING: ConstStaticCell<[u8; RX_RING_LEN]> = ConstStaticCell::new([0; RX_RING_LEN]);

/// A USART error, named for the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SerialError(usart::Error);

impl SerialError {
    /// What went wrong, for the log.
    pub fn as_str(&self) -> &'static str {
        match self.0 {
            usart::Error::Framing => "framing error",
            usart::Error::Noise => "noise",
            usart::Error::Overrun => "overrun",
            usart::Error::Parity => "parity error",
            usart::Error::BufferTooLong => "buffer too long",
            _ => "USART error",
        }
    }
}

/// Receiving half of the serial link.
pub struct SerialRx(RingBufferedUartRx<'static>);

impl SerialRx {
    /// Waits for bytes; returns how many were put into `buf`.
    pub async fn read(&mut self, buf: &mut [u8]) -> Result<usize, SerialError> {
        self.0.read(buf).await.map_err(SerialError)
    }
}

/// Sending half of the serial link.
pub struct SerialTx(UartTx<'static, Async>);

impl SerialTx {
    /// Writes all of `bytes`.
    pub async fn write(&mut self, bytes: &[u8]) -> Result<(), SerialError> {
        self.0.write(bytes).await.map_err(SerialError)
    }
}

/// Opens USART1 with DMA in both directions and splits it into the two halves.
pub fn open(pins: LinkPins) -> (SerialTx, SerialRx) {
    let mut config = usart::Config::default();
    config.baudrate = LINK_BAUD;
    // Without an adapter plugged in, a floating RX pin would feed noise to the decoder.
    config.rx_pull = embassy_stm32::gpio::Pull::Up;
    let uart = defmt::unwrap!(Uart::new(
        pins.link_uart,
        pins.link_rx,
        pins.link_tx,
        pins.link_tx_dma,
        pins.link_rx_dma,
        Irqs,
        config,
    ));
    let (tx, rx) = uart.split();
    (
        SerialTx(tx),
        SerialRx(rx.into_ring_buffered(RX_RING.take())),
    )
}
