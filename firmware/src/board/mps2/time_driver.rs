//! embassy-time's driver on the AN386's two CMSDK APB timers (25 MHz PCLK in QEMU):
//! - TIMER0 runs free from 0xFFFF_FFFF down, wrapping every 171.8 s; its interrupt counts the
//!   wraps, which extend it to 64 bits (board time in 25 MHz ticks, divided down to
//!   embassy-time's 1 MHz tick);
//! - TIMER1 is the alarm: loaded with the ticks until the earliest deadline of the timer
//!   queue, its interrupt runs the queue's expired wakers and loads the next deadline.

use core::cell::RefCell;
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{AtomicU32, Ordering};
use core::task::Waker;

use cortex_m::interrupt::{CriticalSection, Mutex};
use embassy_time_driver::Driver;
use embassy_time_queue_utils::Queue;

use super::irq::{self, Interrupt};

/// CMSDK APB timer registers.
const TIMER0: usize = 0x4000_0000;
const TIMER1: usize = 0x4000_1000;
const CTRL: usize = 0x00;
const VALUE: usize = 0x04;
const RELOAD: usize = 0x08;
const INTSTATUS: usize = 0x0C; // write: INTCLEAR
const CTRL_ENABLE: u32 = 1 << 0;
const CTRL_INTEN: u32 = 1 << 3;

/// Timer clock (the AN386's PCLK) per embassy-time tick (1 MHz).
const TICKS_PER_US: u64 = 25;
const _: () = assert!(embassy_time_driver::TICK_HZ == 1_000_000);

fn reg(timer: usize, offset: usize) -> *mut u32 {
    (timer + offset) as *mut u32
}

fn read(timer: usize, offset: usize) -> u32 {
    // SAFETY: an AN386 CMSDK timer register (QEMU maps them at these addresses).
    unsafe { read_volatile(reg(timer, offset)) }
}

fn write(timer: usize, offset: usize, value: u32) {
    // SAFETY: as in `read`; only this driver touches TIMER0 and TIMER1.
    unsafe { write_volatile(reg(timer, offset), value) }
}

struct CmsdkTimeDriver {
    /// TIMER0 wraps handled by its interrupt.
    wraps: AtomicU32,
    queue: Mutex<RefCell<Queue>>,
}

embassy_time_driver::time_driver_impl!(static DRIVER: CmsdkTimeDriver = CmsdkTimeDriver {
    wraps: AtomicU32::new(0),
    queue: Mutex::new(RefCell::new(Queue::new())),
});

/// Starts both timers (TIMER1 idle) and enables their interrupts.
pub fn init() {
    write(TIMER0, CTRL, 0);
    write(TIMER0, RELOAD, u32::MAX);
    write(TIMER0, VALUE, u32::MAX);
    write(TIMER0, INTSTATUS, 1);
    write(TIMER0, CTRL, CTRL_ENABLE | CTRL_INTEN);
    write(TIMER1, CTRL, 0);
    write(TIMER1, INTSTATUS, 1);
    irq::unmask(Interrupt::Timer0);
    irq::unmask(Interrupt::Timer1);
}

impl CmsdkTimeDriver {
    /// Timer ticks since `init`, 64 bits.
    fn ticks(&self) -> u64 {
        cortex_m::interrupt::free(|_| {
            let wraps = self.wraps.load(Ordering::Relaxed);
            let before = read(TIMER0, VALUE);
            let wrapped = read(TIMER0, INTSTATUS) & 1 != 0;
            let after = read(TIMER0, VALUE);
            // A wrap whose interrupt has not run yet (it cannot run inside this critical
            // section) happened before `after` was read.
            let (wraps, value) = if wrapped {
                (wraps + 1, after)
            } else {
                (wraps, before)
            };
            (u64::from(wraps) << 32) | u64::from(u32::MAX - value)
        })
    }

    /// Loads TIMER1 to fire at `at` (1 MHz ticks). `false` if `at` has already passed.
    fn set_alarm(&self, at: u64) -> bool {
        write(TIMER1, CTRL, 0);
        write(TIMER1, INTSTATUS, 1);
        if at == u64::MAX {
            return true;
        }
        let now = self.now();
        if at <= now {
            return false;
        }
        // Longer waits fire early and are loaded again by the interrupt.
        let ticks = (at - now)
            .saturating_mul(TICKS_PER_US)
            .min(u64::from(u32::MAX)) as u32;
        write(TIMER1, RELOAD, ticks);
        write(TIMER1, VALUE, ticks);
        write(TIMER1, CTRL, CTRL_ENABLE | CTRL_INTEN);
        true
    }

    /// Runs the expired wakers and loads the alarm for the next deadline.
    fn run_queue(&self, cs: &CriticalSection) {
        let mut queue = self.queue.borrow(cs).borrow_mut();
        let mut next = queue.next_expiration(self.now());
        while !self.set_alarm(next) {
            next = queue.next_expiration(self.now());
        }
    }
}

impl Driver for CmsdkTimeDriver {
    fn now(&self) -> u64 {
        self.ticks() / TICKS_PER_US
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        cortex_m::interrupt::free(|cs| {
            let changed = self.queue.borrow(cs).borrow_mut().schedule_wake(at, waker);
            if changed {
                self.run_queue(cs);
            }
        })
    }
}

/// TIMER0 interrupt: one more wrap of the free-running counter.
pub extern "C" fn on_wrap_interrupt() {
    cortex_m::interrupt::free(|_| {
        write(TIMER0, INTSTATUS, 1);
        DRIVER.wraps.fetch_add(1, Ordering::Relaxed);
    });
}

/// TIMER1 interrupt: the alarm fired.
pub extern "C" fn on_alarm_interrupt() {
    cortex_m::interrupt::free(|cs| {
        write(TIMER1, CTRL, 0);
        write(TIMER1, INTSTATUS, 1);
        DRIVER.run_queue(cs);
    });
}
