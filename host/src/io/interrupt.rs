//! SIGINT / SIGTERM for the whole process (installed once by the binary).
//!
//! By default an interrupted command removes the temporary files of the outputs it was writing
//! (registered by [`crate::io::atomic`]) and exits with 130. Commands that must end cleanly on
//! a signal (`record` prints its summary and keeps the recording, `board-sim` removes its link)
//! ask for [`cooperative_stop`]: the signal then only raises the returned flag.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

/// Exit status after SIGINT/SIGTERM (128 + SIGINT, as shells report it).
pub const INTERRUPTED_EXIT: i32 = 130;

static LIVE_TEMPS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Held while a set of files is renamed into place ([`commit_guard`]).
static COMMIT: Mutex<()> = Mutex::new(());

/// Held by [`crate::io::file_set::FileSet::commit`] while it renames its files: an
/// interruption waits for the commit to end, so a folder never holds half of a set.
pub fn commit_guard() -> std::sync::MutexGuard<'static, ()> {
    COMMIT
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}
static COOPERATIVE: AtomicBool = AtomicBool::new(false);
static STOP: OnceLock<Arc<AtomicBool>> = OnceLock::new();

fn stop_flag() -> &'static Arc<AtomicBool> {
    STOP.get_or_init(|| Arc::new(AtomicBool::new(false)))
}

/// Records a temporary file about to be created, to be removed if the process is interrupted.
/// Call it *before* creating the file: a signal between the two then removes nothing that
/// exists yet, and one after it removes the file.
pub fn register_temp(path: &Path) {
    if let Ok(mut live) = LIVE_TEMPS.lock() {
        live.push(path.to_path_buf());
    }
}

/// The temporary file was renamed or removed.
pub fn unregister_temp(path: &Path) {
    if let Ok(mut live) = LIVE_TEMPS.lock() {
        live.retain(|p| p != path);
    }
}

/// Removes every registered temporary file (on interruption or a fatal output error).
pub fn remove_live_temps() {
    if let Ok(mut live) = LIVE_TEMPS.lock() {
        for p in live.drain(..) {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// Removes every registered temporary file and exits with [`INTERRUPTED_EXIT`] while still
/// holding the registry: the rest of the process, still running until the exit completes,
/// cannot register (and so cannot create, see [`register_temp`]) another temporary file.
fn remove_live_temps_and_exit() -> ! {
    // a set of files being renamed into place is finished first (it never deadlocks: the
    // commit takes this lock, then the registry's, in the same order as here)
    let _commit = commit_guard();
    let guard = LIVE_TEMPS.lock();
    if let Ok(mut live) = guard {
        for p in live.drain(..) {
            let _ = std::fs::remove_file(p);
        }
        std::process::exit(INTERRUPTED_EXIT);
    }
    std::process::exit(INTERRUPTED_EXIT)
}

/// Installs the SIGINT/SIGTERM/SIGHUP handler. Returns an error message when another handler
/// is already installed.
pub fn install() -> Result<(), String> {
    let stop = Arc::clone(stop_flag());
    ctrlc::set_handler(move || {
        if COOPERATIVE.load(Ordering::SeqCst) {
            stop.store(true, Ordering::SeqCst);
        } else {
            remove_live_temps_and_exit();
        }
    })
    .map_err(|e| e.to_string())
}

/// Switches the process to cooperative mode and returns the flag that SIGINT/SIGTERM raise.
pub fn cooperative_stop() -> Arc<AtomicBool> {
    COOPERATIVE.store(true, Ordering::SeqCst);
    Arc::clone(stop_flag())
}
