//! The serial host link, the same on both boards (STM32: USART1 by DMA; emulated board: the
//! CMSDK UART0, interrupt driven):
//! - [`serial_rx_task`] hands the received bytes to the board core, whose streaming decoder
//!   finds the commands (corrupt frames count as `Status.rx_errors` there);
//! - [`serial_tx_task`] writes the core's queued bytes while this is the active link, up to
//!   [`TX_CHUNK`] per write (frames may span writes: the wire is a byte stream).

use crate::board::{SerialRx, SerialTx};
use crate::log::warning;
use crate::shared::{self, LinkId};

/// Bytes per write.
const TX_CHUNK: usize = 256;

/// Hands the bytes arriving on the serial link to the board core.
#[embassy_executor::task]
pub async fn serial_rx_task(mut rx: SerialRx) -> ! {
    let mut chunk = [0u8; 32];
    loop {
        match rx.read(&mut chunk).await {
            Ok(n) => shared::receive(LinkId::Serial, &chunk[..n]),
            // The driver restarts reception on the next read. The frame in flight fails its
            // CRC in the core's decoder and counts as an rx error there.
            Err(e) => warning!("serial rx: {}", e.as_str()),
        }
    }
}

/// Writes the board core's queued frames while the serial link is the active link.
#[embassy_executor::task]
pub async fn serial_tx_task(mut tx: SerialTx) -> ! {
    let mut buf = [0u8; TX_CHUNK];
    loop {
        let n = shared::pop_tx(LinkId::Serial, &mut buf);
        if n == 0 {
            shared::wait_tx(LinkId::Serial).await;
            continue;
        }
        if let Err(e) = tx.write(&buf[..n]).await {
            warning!("serial tx: {}", e.as_str());
        }
    }
}
