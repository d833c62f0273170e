//! End-to-end tests across the crates: one test binary, a module per area (`cargo test -p rig-tests --test e2e <area>`).

/// `record(key, value)` for `docs/results.md` (the integration tests' helper, shared).
#[allow(dead_code)]
#[path = "../../../host/tests/integration/common/record.rs"]
mod record;

mod diagnose_cli;
mod emulated_board;
mod record_pty;
mod reliability_signals;
mod report_browser;
mod session_e2e;
mod simulate_cli;
