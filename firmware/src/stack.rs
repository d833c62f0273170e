//! Stack use, measured on the target: cortex-m-rt paints the whole stack region with
//! `STACK_PAINT_VALUE` at reset (feature `paint-stack`); the deepest word that no longer holds
//! the paint is the high-water mark of every call chain that ran since (interrupt handlers
//! included: they run on the same main stack).

use core::ptr::{addr_of, read_volatile};

use cortex_m_rt::STACK_PAINT_VALUE;

extern "C" {
    /// Top of the stack (initial stack pointer), from cortex-m-rt's linker script.
    static _stack_start: u32;
    /// Lowest address of the stack region (end of `.bss` / `.uninit`).
    static _stack_end: u32;
}

/// The stack region and its high-water mark, bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StackUse {
    /// Bytes that were ever written (from the top down to the deepest unpainted word).
    pub used: usize,
    /// Size of the stack region.
    pub size: usize,
}

/// Scans the painted region from its low end up to the first word that lost the paint.
pub fn high_water() -> StackUse {
    let top = addr_of!(_stack_start) as usize;
    let bottom = addr_of!(_stack_end) as usize;
    let mut addr = bottom;
    while addr < top {
        // SAFETY: `bottom..top` is the RAM of the stack region (linker symbols), word aligned
        // (cortex-m-rt asserts it); reading it races with nothing: the stack below the current
        // stack pointer is not in use.
        if unsafe { read_volatile(addr as *const u32) } != STACK_PAINT_VALUE {
            break;
        }
        addr += 4;
    }
    StackUse {
        used: top - addr,
        size: top - bottom,
    }
}

/// Logs the high-water mark (at every `Stop` and on the emulated board's request).
pub fn report() {
    let s = high_water();
    crate::log::info!(
        "stack high-water mark: {} of {} bytes (painted stack)",
        s.used,
        s.size
    );
}
