//! The serial host link on the emulated board: CMSDK APB UART0 (0x4000_4000; QEMU connects it
//! to `-serial`), interrupt driven.
//!
//! - Receive: the RX interrupt moves each byte into a [`RX_RING_LEN`]-byte ring and wakes the
//!   reader. A full ring leaves the byte in the UART (QEMU then stops reading the pty, so the
//!   host is held back instead of losing bytes) until the reader has made room and takes it.
//! - Transmit: a byte is written whenever the UART's one-byte buffer is free; when it is full,
//!   the writer waits for the TX interrupt (QEMU holds the buffer full while the pty is full).
//!   Each byte costs QEMU a write to the pty, so the writer yields to the other tasks every
//!   [`TX_BURST`] bytes (the STM32's DMA does not hold the CPU either).

use core::cell::UnsafeCell;
use core::future::poll_fn;
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{AtomicUsize, Ordering};
use core::task::Poll;

use embassy_sync::waitqueue::AtomicWaker;

use super::irq::{self, Interrupt};

const UART0: usize = 0x4000_4000;
const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTSTATUS: usize = 0x0C; // write: INTCLEAR
const BAUDDIV: usize = 0x10;

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_TX_INTEN: u32 = 1 << 2;
const CTRL_RX_INTEN: u32 = 1 << 3;
const INT_TX: u32 = 1 << 0;
const INT_RX: u32 = 1 << 1;

/// PCLK / baud rate. QEMU does not pace the line, but it needs a divider of at least 16.
const BAUD_DIVIDER: u32 = 25_000_000 / 921_600;

/// Bytes written before the writer lets the other tasks run.
const TX_BURST: usize = 16;

/// Receive ring, bytes (a power of two).
const RX_RING_LEN: usize = 256;

fn reg(offset: usize) -> *mut u32 {
    (UART0 + offset) as *mut u32
}

fn read(offset: usize) -> u32 {
    // SAFETY: a CMSDK UART0 register of the AN386.
    unsafe { read_volatile(reg(offset)) }
}

fn write(offset: usize, value: u32) {
    // SAFETY: as in `read`; only this driver touches UART0.
    unsafe { write_volatile(reg(offset), value) }
}

/// Sets or clears bits of CTRL (also changed by the interrupt handlers: in a critical section).
fn ctrl(set: u32, clear: u32) {
    cortex_m::interrupt::free(|_| write(CTRL, (read(CTRL) | set) & !clear));
}

/// Single-producer (RX interrupt), single-consumer (reader task) byte ring.
struct RxRing {
    buf: UnsafeCell<[u8; RX_RING_LEN]>,
    /// Bytes ever written / read (wrapping); `head - tail` are waiting.
    head: AtomicUsize,
    tail: AtomicUsize,
}

// SAFETY: the producer writes only the slot at `head` before publishing it, the consumer reads
// only slots below `head` before releasing them through `tail`.
unsafe impl Sync for RxRing {}

impl RxRing {
    /// Appends `byte`; the caller has checked that the ring is not full.
    fn push(&self, byte: u8) {
        let head = self.head.load(Ordering::Relaxed);
        // SAFETY: slot `head` is not readable by the consumer until `head` is published.
        unsafe { (*self.buf.get())[head % RX_RING_LEN] = byte };
        self.head.store(head.wrapping_add(1), Ordering::Release);
    }

    fn pop_into(&self, out: &mut [u8]) -> usize {
        let tail = self.tail.load(Ordering::Relaxed);
        let head = self.head.load(Ordering::Acquire);
        let n = head.wrapping_sub(tail).min(out.len());
        for (i, slot) in out[..n].iter_mut().enumerate() {
            // SAFETY: slots `tail..head` were published by the producer.
            *slot = unsafe { (*self.buf.get())[tail.wrapping_add(i) % RX_RING_LEN] };
        }
        self.tail.store(tail.wrapping_add(n), Ordering::Release);
        n
    }

    fn is_full(&self) -> bool {
        let tail = self.tail.load(Ordering::Acquire);
        self.head.load(Ordering::Relaxed).wrapping_sub(tail) == RX_RING_LEN
    }
}

static RX: RxRing = RxRing {
    buf: UnsafeCell::new([0; RX_RING_LEN]),
    head: AtomicUsize::new(0),
    tail: AtomicUsize::new(0),
};
static RX_WAKER: AtomicWaker = AtomicWaker::new();
static TX_WAKER: AtomicWaker = AtomicWaker::new();

/// The UART cannot fail in QEMU (no framing or parity errors on a pty); the type keeps the
/// serial link's interface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SerialError {}

impl SerialError {
    /// What went wrong, for the log.
    pub fn as_str(&self) -> &'static str {
        match *self {}
    }
}

/// Receiving half of the serial link.
pub struct SerialRx(());

/// Sending half of the serial link.
pub struct SerialTx(());

/// Enables UART0 in both directions and its interrupts.
pub fn open() -> (SerialTx, SerialRx) {
    write(CTRL, 0);
    write(BAUDDIV, BAUD_DIVIDER);
    write(INTSTATUS, INT_TX | INT_RX);
    write(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INTEN);
    irq::unmask(Interrupt::Uart0Rx);
    irq::unmask(Interrupt::Uart0Tx);
    (SerialTx(()), SerialRx(()))
}

impl SerialRx {
    /// Waits for bytes; returns how many were put into `buf` (at least one).
    pub async fn read(&mut self, buf: &mut [u8]) -> Result<usize, SerialError> {
        poll_fn(|cx| {
            RX_WAKER.register(cx.waker());
            let mut n = RX.pop_into(buf);
            if n == 0 {
                // A byte left in the UART while the ring was full raises no new interrupt.
                cortex_m::interrupt::free(|_| take_received());
                n = RX.pop_into(buf);
            }
            if n > 0 {
                Poll::Ready(Ok(n))
            } else {
                Poll::Pending
            }
        })
        .await
    }
}

impl SerialTx {
    /// Writes all of `bytes`.
    pub async fn write(&mut self, bytes: &[u8]) -> Result<(), SerialError> {
        for (i, &byte) in bytes.iter().enumerate() {
            if i > 0 && i % TX_BURST == 0 {
                embassy_futures::yield_now().await;
            }
            poll_fn(|cx| {
                if read(STATE) & STATE_TX_FULL == 0 {
                    write(DATA, u32::from(byte));
                    return Poll::Ready(());
                }
                TX_WAKER.register(cx.waker());
                ctrl(CTRL_TX_INTEN, 0);
                // The buffer may have emptied before the interrupt was enabled.
                if read(STATE) & STATE_TX_FULL == 0 {
                    ctrl(0, CTRL_TX_INTEN);
                    write(DATA, u32::from(byte));
                    return Poll::Ready(());
                }
                Poll::Pending
            })
            .await;
        }
        Ok(())
    }
}

/// Moves the byte the UART holds into the ring, if there is room. Runs in the RX interrupt or
/// in a critical section (so the ring has one producer at a time).
fn take_received() {
    while read(STATE) & STATE_RX_FULL != 0 && !RX.is_full() {
        RX.push(read(DATA) as u8);
    }
}

/// UART0 RX interrupt: moves the received byte into the ring.
pub extern "C" fn on_rx_interrupt() {
    write(INTSTATUS, INT_RX);
    take_received();
    RX_WAKER.wake();
}

/// UART0 TX interrupt: the transmit buffer is free again.
pub extern "C" fn on_tx_interrupt() {
    write(INTSTATUS, INT_TX);
    ctrl(0, CTRL_TX_INTEN);
    TX_WAKER.wake();
}
