//! End to end on the emulated board: the firmware's tasks built for the MPS2 AN386
//! (`firmware`, feature `mps2-an386`) run in QEMU (`firmware/emulated/run.sh`), `rigctl record`
//! records them over QEMU's pseudo-terminal, `rigctl export` turns the recording into CSV, and
//! every exported value is checked against the emulated sensors' known signal
//! (`rig_protocol::device::known_signal`).
//!
//! One QEMU session serves two recordings with different rates (the board obeys `Start`'s
//! rates, and `Stop`: it is silent but alive between the runs); a second session is forced to
//! panic, which must be reported on QEMU's output and end it with a failure status, and a
//! third to overflow its stack (unbounded recursion), which must lock the core up with the
//! stack pointer below RAM (flip-link's layout) and be reported by `run.sh` (exit 1).
//!
//! Timing: QEMU's clock follows the host's (no `-icount`), so board time is real time but the
//! guest runs only when the host schedules QEMU. Potentiometer timestamps are computed from
//! the trigger period and must be exact. Inclinometer timestamps are taken when the read
//! starts: late by the wake-up latency of the emulated board (measured: median about 0.1 ms,
//! 99th percentile about 2 ms on a loaded 2-core machine). The board's scheduler reads the most
//! recent slot that has passed, so every reading is within one slot interval (1 / (rate x 3))
//! after its slot, and a wake-up later than that skips a slot, which the board counts in
//! `Status.overruns`. The test allows [`TILT_SKIPPED_MAX`] of the slots to be skipped and
//! requires each skipped slot to be counted by the board; none may be lost on the link. It
//! runs apart from the binary's other real-time and CPU-heavy tests (`one_at_a_time`).
//!
//! Without `qemu-system-arm` the test is skipped with a message, except with `CI=true`, where
//! it fails (`.ci/run` installs QEMU).
//!
//! Here: the test and its bounds; in `emulator`: the QEMU session and the board's link between
//! runs; in `recording`: one recording and everything it is checked for.

mod emulator;
mod recording;

use std::time::{Duration, Instant};

use emulator::{idle_but_alive, qemu_or_skip, stack_marks, Emulator};
use recording::record_and_check;

/// Seconds of the long recording (1 kHz pot, 3 x 100 Hz tilt).
const LONG_RUN_S: u64 = 25;
/// Seconds of the second recording, at other rates.
const SHORT_RUN_S: u64 = 5;
/// Fraction of inclinometer slots that may be skipped because QEMU woke late (each one
/// counted in `Status.overruns`).
const TILT_SKIPPED_MAX: f64 = 0.01;
/// Board clock against the host clock (Status uptime vs host receive time), relative.
const CLOCK_RATE_TOLERANCE: f64 = 0.02;
/// Samples against the host's recording duration, relative (the host's duration runs from its
/// `Start` to its `Stop`; the board's from the `Start` it received to the `Stop`).
const SAMPLE_COUNT_TOLERANCE: f64 = 0.03;

#[test]
fn emulated_board_records_known_signals_and_reports_panics_and_overflows() {
    if !qemu_or_skip() {
        return;
    }
    // Real time: nothing else real-time or CPU-heavy in this binary runs beside it.
    let _alone = crate::one_at_a_time();
    let started = Instant::now();
    let dir = tempfile::tempdir().expect("temp dir");
    // run.sh builds the firmware first; the QEMU session covers both recordings.
    let emulator = Emulator::start(dir.path(), "board", LONG_RUN_S + SHORT_RUN_S + 60, &[]);

    let long = record_and_check(&emulator.link, dir.path(), "long", LONG_RUN_S, 1000, 100);
    idle_but_alive(&emulator.link);
    let short = record_and_check(&emulator.link, dir.path(), "short", SHORT_RUN_S, 500, 50);
    let console = emulator.stop();

    assert!(console.contains("INFO rig firmware"), "boot log: {console}");
    assert!(
        console.contains("start: RunConfig { pot_rate_hz: 1000")
            && console.contains("start: RunConfig { pot_rate_hz: 500"),
        "the board logged both starts: {console}"
    );
    let marks = stack_marks(&console);
    assert_eq!(marks.len(), 2, "a stack report at each Stop: {console}");
    for &(used, size) in &marks {
        assert!(used > 0 && used < size, "stack {used} of {size} bytes");
    }
    let (used, size) = marks[marks.len() - 1];

    // A panic on the board is reported on the console and ends QEMU with a failure.
    let panicking = Emulator::start(dir.path(), "panicking", 60, &["panic-after-ms=1500"]);
    let (status, panic_console) = panicking.wait(Duration::from_secs(60));
    assert!(!status.success(), "run.sh exits non-zero after a panic");
    assert!(
        panic_console.contains("PANIC panicked at")
            && panic_console.contains("forced panic after 1500 ms"),
        "panic message on the console: {panic_console}"
    );

    // A stack overflow (unbounded recursion) runs off the bottom of RAM, where flip-link put
    // the stack: the core cannot even stack the HardFault's frame, locks up, and run.sh says
    // so, naming the stack pointer below RAM, and fails.
    let overflowing = Emulator::start(dir.path(), "overflowing", 60, &["overflow-after-ms=1500"]);
    let (status, overflow_console) = overflowing.wait(Duration::from_secs(60));
    assert_eq!(
        status.code(),
        Some(1),
        "run.sh exits 1 after a stack overflow"
    );
    assert!(
        overflow_console.contains("forced stack overflow after 1500 ms"),
        "the overflow was started: {overflow_console}"
    );
    let report = overflow_console
        .lines()
        .find(|l| l.starts_with("run.sh: FAULT stack overflow"))
        .unwrap_or_else(|| panic!("stack overflow reported: {overflow_console}"));
    let sp = report
        .split("stack pointer at 0x")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|h| u32::from_str_radix(h, 16).ok())
        .unwrap_or_else(|| panic!("stack pointer in the report: {report}"));
    assert!(
        sp < 0x2000_0000,
        "stack pointer {sp:#x} below RAM: {report}"
    );
    assert!(
        !overflow_console.contains("PANIC"),
        "no panic, a fault: {overflow_console}"
    );

    for (name, run) in [("1 kHz / 100 Hz", &long), ("500 Hz / 50 Hz", &short)] {
        println!(
            "emulated board, {name}: frames {}, lost 0, pot samples {}, tilt readings {}, \
             tilt slots skipped {} (allowed {:.0} %), tilt read lateness p50/p99/max {:?} us, \
             board clock {:.4} x host",
            run.frames,
            run.pot_samples,
            run.tilt_readings,
            run.tilt_skipped,
            TILT_SKIPPED_MAX * 100.0,
            run.tilt_late_us,
            run.clock_rate
        );
    }
    println!("emulated board: stack high-water mark {used} of {size} bytes (painted stack)");
    println!(
        "emulated board: test took {:.1} s",
        started.elapsed().as_secs_f64()
    );
}
