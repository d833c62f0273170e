//! The emulated board's console: log lines, panics and hard faults go to QEMU's semihosting
//! (`-semihosting-config enable=on,target=native`), which prints them on QEMU's stdout; a panic
//! or fault then ends QEMU with exit status 1. The command line (`arg=` of the same option)
//! carries the test switches.

use core::fmt::Arguments;
use core::panic::PanicInfo;

use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln, nr};

use crate::shared::now_us;

/// Writes one log line: `[seconds.micros] LEVEL message`.
pub fn log_line(level: &str, args: Arguments) {
    let t = now_us();
    hprintln!(
        "[{:>4}.{:06}] {:<4} {}",
        t / 1_000_000,
        t % 1_000_000,
        level,
        args
    );
}

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    hprintln!("PANIC {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    hprintln!("PANIC hard fault at pc {:#010x}", frame.pc());
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    panic!("unexpected interrupt {}", irqn);
}

/// The semihosting command line, or an empty string.
fn command_line(buf: &mut [u8; 128]) -> &str {
    // SYS_GET_CMDLINE takes a block {buffer, length} and returns the length written.
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: `block` points at `buf`, which outlives the call; the host writes at most
    // `buf.len()` bytes.
    let status =
        unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if status != 0 {
        return "";
    }
    // The length written is in the block, and the string is NUL-terminated (QEMU 7.2 leaves
    // the length as it was): take the shorter.
    let len = block[1].min(buf.len());
    let len = buf[..len].iter().position(|&b| b == 0).unwrap_or(len);
    core::str::from_utf8(&buf[..len]).unwrap_or("")
}

/// Test switches given on the semihosting command line (`run.sh` passes them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Switches {
    /// `panic-after-ms=N`: panic N ms after boot, to show that a panic is reported.
    pub panic_after_ms: Option<u32>,
    /// `overflow-after-ms=N`: recurse without end N ms after boot, to show that a stack
    /// overflow is reported.
    pub overflow_after_ms: Option<u32>,
}

/// Reads the switches from the command line; unknown words are logged and ignored.
pub fn switches() -> Switches {
    let mut buf = [0u8; 128];
    let mut switches = Switches::default();
    // The first word is the program name.
    for word in command_line(&mut buf).split_ascii_whitespace().skip(1) {
        match word.split_once('=') {
            Some(("panic-after-ms", ms)) if ms.parse::<u32>().is_ok() => {
                switches.panic_after_ms = ms.parse().ok();
            }
            Some(("overflow-after-ms", ms)) if ms.parse::<u32>().is_ok() => {
                switches.overflow_after_ms = ms.parse().ok();
            }
            _ => crate::log::warning!("unknown switch {:?}", word),
        }
    }
    switches
}
