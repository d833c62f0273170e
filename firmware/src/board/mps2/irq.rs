//! The MPS2 AN386's interrupt vectors (QEMU `hw/arm/mps2.c`, ARM AN386: 32 external
//! interrupts) and the numbers the NVIC takes. Only the handlers this firmware uses are
//! named; every other vector is `DefaultHandler` (cortex-m-rt: a hang, reported as a panic
//! below).

use cortex_m::interrupt::InterruptNumber;

/// The interrupts this firmware enables.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u16)]
pub enum Interrupt {
    /// CMSDK UART0 receive (the host link).
    Uart0Rx = 0,
    /// CMSDK UART0 transmit.
    Uart0Tx = 1,
    /// CMSDK TIMER0: the free-running board clock wrapped.
    Timer0 = 8,
    /// CMSDK TIMER1: the time driver's alarm.
    Timer1 = 9,
}

// SAFETY: the numbers are the AN386's interrupt lines (below its 32).
unsafe impl InterruptNumber for Interrupt {
    fn number(self) -> u16 {
        self as u16
    }
}

extern "C" {
    fn DefaultHandler();
}

/// A vector table entry.
type Handler = unsafe extern "C" fn();

/// Vectors `0..32`: UART0 at 0/1, TIMER0 at 8, TIMER1 at 9, the rest unused.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
pub static __INTERRUPTS: [Handler; 32] = {
    let mut v: [Handler; 32] = [DefaultHandler; 32];
    v[Interrupt::Uart0Rx as usize] = super::uart::on_rx_interrupt;
    v[Interrupt::Uart0Tx as usize] = super::uart::on_tx_interrupt;
    v[Interrupt::Timer0 as usize] = super::time_driver::on_wrap_interrupt;
    v[Interrupt::Timer1 as usize] = super::time_driver::on_alarm_interrupt;
    v
};

/// Enables `irq` in the NVIC.
pub fn unmask(irq: Interrupt) {
    // SAFETY: the handlers above are installed and take only their own driver's state,
    // behind critical sections or atomics.
    unsafe { cortex_m::peripheral::NVIC::unmask(irq) };
}
