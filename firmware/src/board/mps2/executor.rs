//! The emulated board's executor loop: embassy's raw executor, as on the STM32, sleeping with
//! WFI instead of WFE. (QEMU implements WFE as a yield, so embassy's cortex-m thread executor
//! would keep one host core busy while the board idles; WFI halts QEMU's CPU until an
//! interrupt.)

use core::sync::atomic::{AtomicBool, Ordering};

use embassy_executor::{raw, Spawner};
use static_cell::StaticCell;

/// Set when a task was woken; the loop polls again instead of sleeping.
static PENDED: AtomicBool = AtomicBool::new(false);

static EXECUTOR: StaticCell<raw::Executor> = StaticCell::new();

/// Called by embassy when a task is woken (from thread mode or an interrupt).
#[export_name = "__pender"]
fn pender(_context: *mut ()) {
    PENDED.store(true, Ordering::Release);
}

/// Runs `init` with a spawner, then polls the tasks forever, sleeping while none is woken.
pub fn run_executor(init: impl FnOnce(Spawner)) -> ! {
    let executor: &'static raw::Executor = EXECUTOR.init(raw::Executor::new(core::ptr::null_mut()));
    init(executor.spawner());
    loop {
        // SAFETY: `poll` is called from this one thread-mode loop only.
        unsafe { executor.poll() };
        // A wake between the check and WFI leaves its interrupt pending, and WFI returns at
        // once on a pending interrupt even with interrupts masked.
        cortex_m::interrupt::free(|_| {
            if !PENDED.swap(false, Ordering::AcqRel) {
                cortex_m::asm::wfi();
            }
        });
    }
}
