//! Host link over USART1 (PA9 TX, PA10 RX) at 921600 baud 8N1, both directions by DMA.
//!
//! - [`usart_rx_task`]: the receive DMA runs circularly into a ring buffer; the bytes go to
//!   the board core, whose streaming decoder finds the commands (corrupt frames count as
//!   `Status.rx_errors` there).
//! - [`usart_tx_task`]: while USART1 is the active link, writes the core's queued bytes, up to
//!   [`TX_CHUNK`] per DMA transfer (frames may span transfers: the wire is a byte stream).

use defmt::warn;
use embassy_stm32::mode::Async;
use embassy_stm32::usart::{self, RingBufferedUartRx, Uart, UartTx};
use static_cell::ConstStaticCell;

use crate::board::LinkPins;
use crate::shared::{self, LinkId};
use crate::Irqs;

/// Baud rate of the host link. 96 MHz / 921600 = 104.17: 0.16 % error at 16x oversampling.
pub const LINK_BAUD: u32 = 921_600;

/// Receive ring buffer: 256 bytes = 2.8 ms of line time at full rate; commands are tiny.
const RX_RING_LEN: usize = 256;

/// Bytes per transmit DMA transfer: 2.8 ms of line time.
const TX_CHUNK: usize = 256;

static RX_RING: ConstStaticCell<[u8; RX_RING_LEN]> = ConstStaticCell::new([0; RX_RING_LEN]);

/// Opens USART1 with DMA in both directions and splits it into the two halves.
pub fn open(pins: LinkPins) -> (UartTx<'static, Async>, RingBufferedUartRx<'static>) {
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
    (tx, rx.into_ring_buffered(RX_RING.take()))
}

/// Hands the bytes arriving on USART1 to the board core.
#[embassy_executor::task]
pub async fn usart_rx_task(mut rx: RingBufferedUartRx<'static>) -> ! {
    let mut chunk = [0u8; 32];
    loop {
        match rx.read(&mut chunk).await {
            Ok(n) => shared::receive(LinkId::Usart, &chunk[..n]),
            // The driver restarts reception on the next read. The frame in flight fails its
            // CRC in the core's decoder and counts as an rx error there.
            Err(e) => warn!("usart rx: {}", e),
        }
    }
}

/// Writes the board core's queued frames while USART1 is the active link.
#[embassy_executor::task]
pub async fn usart_tx_task(mut tx: UartTx<'static, Async>) -> ! {
    let mut buf = [0u8; TX_CHUNK];
    loop {
        let n = shared::pop_tx(LinkId::Usart, &mut buf);
        if n == 0 {
            shared::wait_tx(LinkId::Usart).await;
            continue;
        }
        if let Err(e) = tx.write(&buf[..n]).await {
            warn!("usart tx: {}", e);
        }
    }
}
