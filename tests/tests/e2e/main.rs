//! End-to-end tests across the crates: one test binary, a module per area (`cargo test -p rig-tests --test e2e <area>`).

/// `record(key, value)` for `docs/results.md` (the integration tests' helper, shared).
#[allow(dead_code)]
#[path = "../../../host/tests/integration/common/record.rs"]
mod record;

/// The rule that every test runs the CLI through one helper (the integration tests', shared).
#[path = "../../../host/tests/integration/common/spawn_rule.rs"]
mod spawn_rule;

/// Every test here runs the CLI through `rig_tests::rigctl` (so that the binary under test, see
/// `rig_tests::rigctl_path`, is the one every test runs): no file under `tests/e2e` names the
/// binary's path or makes its own `Command` of it.
#[test]
fn every_spawn_of_the_cli_goes_through_the_helper() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/e2e");
    let found = spawn_rule::offences(&root, &[]);
    assert!(
        found.is_empty(),
        "run the CLI through rig_tests::rigctl():\n{}",
        found.join("\n")
    );
}

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
