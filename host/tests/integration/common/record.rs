//! Measured values for `docs/results.md`: a test records the number it asserts on with
//! [`record`]; `scripts/results.py` renders `docs/results.md.in` from the recorded files.

use std::fs::OpenOptions;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Environment variable naming the folder the values are written to.
pub const RESULTS_DIR_ENV: &str = "RIG_RESULTS_DIR";

/// Serialises the read-merge-write of the test threads of this process; the file lock below
/// serialises processes.
static WRITERS: Mutex<()> = Mutex::new(());

/// Records `value` under `key` in `$RIG_RESULTS_DIR/<module>.json`, `<module>` being the file
/// name (without `.rs`) of the calling test module; does nothing when `RIG_RESULTS_DIR` is unset.
/// Keys of other tests of the same module are kept (the file is a merged JSON object).
///
/// # Panics
/// When the folder or the file cannot be written or the file holds something other than a JSON
/// object: a recording run must not lose a value silently.
#[track_caller]
pub fn record(key: &str, value: impl Into<serde_json::Value>) {
    store(key, value.into(), Store::Replace);
}

/// Like [`record`], but appends `value` to the list under `key`: one list filled by several
/// tests of the module (in the order they ran, so only its smallest and largest elements are
/// for `docs/results.md`).
#[track_caller]
pub fn record_push(key: &str, value: impl Into<serde_json::Value>) {
    store(key, value.into(), Store::Append);
}

/// Whether a value replaces the one under its key or is appended to the list there.
#[derive(Clone, Copy, PartialEq)]
enum Store {
    Replace,
    Append,
}

#[track_caller]
fn store(key: &str, value: serde_json::Value, how: Store) {
    let Some(dir) = std::env::var_os(RESULTS_DIR_ENV) else {
        return;
    };
    let module = module_of(Path::new(std::panic::Location::caller().file()));
    if let Err(e) = merge(&PathBuf::from(dir), &module, key, value, how) {
        panic!("{RESULTS_DIR_ENV}: cannot record {module}.{key}: {e}");
    }
}

/// `calib_ur5` for `host/tests/integration/calib_ur5.rs`; the folder's name for a `mod.rs`.
fn module_of(file: &Path) -> String {
    let stem = file
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("unknown");
    match stem {
        "mod" => file
            .parent()
            .and_then(|p| p.file_name())
            .and_then(|s| s.to_str())
            .unwrap_or("unknown")
            .to_string(),
        _ => stem.to_string(),
    }
}

fn merge(
    dir: &Path,
    module: &str,
    key: &str,
    value: serde_json::Value,
    how: Store,
) -> io::Result<()> {
    let _threads = WRITERS.lock().unwrap_or_else(|p| p.into_inner());
    std::fs::create_dir_all(dir)?;
    let lock = OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(dir.join(format!("{module}.json.lock")))?;
    lock.lock()?;
    let path = dir.join(format!("{module}.json"));
    let mut values = match std::fs::read_to_string(&path) {
        Ok(text) => match serde_json::from_str::<serde_json::Value>(&text) {
            Ok(serde_json::Value::Object(map)) => map,
            _ => {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!("{} is not a JSON object", path.display()),
                ))
            }
        },
        Err(e) if e.kind() == io::ErrorKind::NotFound => serde_json::Map::new(),
        Err(e) => return Err(e),
    };
    match values.get_mut(key) {
        Some(serde_json::Value::Array(list)) if how == Store::Append => list.push(value),
        _ if how == Store::Append => {
            values.insert(key.to_string(), serde_json::Value::Array(vec![value]));
        }
        _ => {
            values.insert(key.to_string(), value);
        }
    }
    let text = serde_json::to_string_pretty(&serde_json::Value::Object(values))?;
    let tmp = dir.join(format!("{module}.json.{}.tmp", std::process::id()));
    std::fs::write(&tmp, text + "\n")?;
    std::fs::rename(&tmp, &path)?;
    lock.unlock()
}
