//! End-to-end tests across the crates: one test binary, a module per area (`cargo test -p rig-tests --test e2e <area>`).

/// `record(key, value)` for `docs/results.md` (the integration tests' helper, shared).
#[allow(dead_code)]
#[path = "../../../host/tests/integration/common/record.rs"]
mod record;

/// Tests that run in real time (the virtual boards of `record_pty`, at up to ten times real
/// time; the emulated board in QEMU) or load both cores (a headless browser) take this lock,
/// one at a time: a board starved of CPU by another such test wakes late and overflows its
/// queues or skips its slots, which is not what the tests check.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Takes [`ONE_AT_A_TIME`] (a test that panicked while holding it leaves it usable).
pub(crate) fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

mod diagnose_cli;
mod emulated_board;
mod record_pty;
mod reliability_signals;
mod report_browser;
mod session_e2e;
mod simulate_cli;
