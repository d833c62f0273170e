//! The emulated board's session: `firmware/emulated/run.sh` (QEMU) started, its console
//! collected, stopped or waited for; the board's link between two recordings (silent, but
//! answering `Ping`); the stack high-water marks it logs.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rig_protocol::{encode_host, DeviceMsg, HostMsg, HOST_FRAME_MAX};
use rigctl::daq::link::{open_port, FrameReader, LinkEvent};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ is inside the repository")
        .to_path_buf()
}

/// True if QEMU can run; without it the test is skipped locally and fails in CI.
pub(super) fn qemu_or_skip() -> bool {
    let found = Command::new("qemu-system-arm")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        let msg =
            "emulated_board: qemu-system-arm is not installed (apt-get install qemu-system-arm)";
        assert!(!rigctl::in_ci(), "{msg}; with CI=true it is required");
        eprintln!("SKIPPED {msg}");
    }
    found
}

/// `run.sh` running, with its stdout (the firmware's semihosting console) collected.
pub(super) struct Emulator {
    child: Child,
    pub(super) link: PathBuf,
    console: Arc<Mutex<String>>,
    reader: Option<std::thread::JoinHandle<()>>,
}

impl Emulator {
    /// Starts `run.sh DURATION LINK SWITCHES` and waits for the link (the first run also builds
    /// the firmware).
    pub(super) fn start(dir: &Path, name: &str, duration_s: u64, switches: &[&str]) -> Self {
        let link = dir.join(name);
        let mut child = Command::new("bash")
            .arg(repo_root().join("firmware/emulated/run.sh"))
            .arg(duration_s.to_string())
            .arg(&link)
            .args(switches)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("spawn run.sh");
        let mut stdout = child.stdout.take().expect("piped stdout");
        let console = Arc::new(Mutex::new(String::new()));
        let sink = Arc::clone(&console);
        let reader = std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = stdout.read(&mut buf) {
                if n == 0 {
                    break;
                }
                let text = String::from_utf8_lossy(&buf[..n]);
                eprint!("{text}");
                sink.lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push_str(&text);
            }
        });
        let deadline = Instant::now() + Duration::from_secs(600);
        while std::fs::symlink_metadata(&link).is_err() {
            if let Some(status) = child.try_wait().expect("poll run.sh") {
                panic!("run.sh ended before linking {}: {status}", link.display());
            }
            assert!(
                Instant::now() < deadline,
                "run.sh did not link {}",
                link.display()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
        Self {
            child,
            link,
            console,
            reader: Some(reader),
        }
    }

    /// The console output so far.
    fn console(&self) -> String {
        self.console
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    /// Waits (at most `limit`) for run.sh to end; returns its status and the whole console.
    pub(super) fn wait(mut self, limit: Duration) -> (ExitStatus, String) {
        let deadline = Instant::now() + limit;
        let status = loop {
            if let Some(status) = self.child.try_wait().expect("poll run.sh") {
                break status;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                panic!("run.sh did not end within {limit:?}");
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        if let Some(reader) = self.reader.take() {
            let _ = reader.join();
        }
        (status, self.console())
    }

    /// Ends run.sh (and with it QEMU) with SIGTERM.
    pub(super) fn stop(self) -> String {
        self.terminate();
        self.wait(Duration::from_secs(20)).1
    }

    /// SIGTERM to run.sh, which stops QEMU and removes the link.
    fn terminate(&self) {
        let _ = Command::new("kill")
            .arg("-TERM")
            .arg(self.child.id().to_string())
            .status();
    }
}

impl Drop for Emulator {
    /// A failed assertion leaves no QEMU behind.
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            self.terminate();
            let _ = self.child.wait();
        }
    }
}

/// Between runs the board sends no data (it obeyed `Stop`) but answers a `Ping`.
pub(super) fn idle_but_alive(link: &Path) {
    let mut port = open_port(link, Duration::from_millis(50)).expect("open the board's link");
    let mut frame = [0u8; HOST_FRAME_MAX];
    let ping = encode_host(&HostMsg::Ping { nonce: 0x5EED }, &mut frame).expect("encode Ping");
    let mut reader = FrameReader::new();
    let mut buf = [0u8; 1024];
    let mut pong = false;
    let mut data_frames = 0u32;
    // QEMU notices a reopened pty within about a second; ping until it answers.
    let deadline = Instant::now() + Duration::from_secs(5);
    let mut next_ping = Instant::now();
    let quiet_until = Instant::now() + Duration::from_millis(1500);
    while Instant::now() < deadline && !(pong && Instant::now() >= quiet_until) {
        if !pong && Instant::now() >= next_ping {
            port.write_all(ping).expect("write Ping");
            next_ping = Instant::now() + Duration::from_millis(300);
        }
        let n = match port.read(&mut buf) {
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                0
            }
            Err(e) => panic!("read from the board: {e}"),
        };
        reader.push_slice(&buf[..n], |event| match event {
            LinkEvent::Frame {
                msg: DeviceMsg::Pong { nonce: 0x5EED },
                ..
            } => pong = true,
            LinkEvent::Frame {
                msg: DeviceMsg::Pot(_) | DeviceMsg::Tilt(_) | DeviceMsg::Status(_),
                ..
            } => data_frames += 1,
            _ => {}
        });
    }
    assert!(pong, "the stopped board answers Ping");
    assert_eq!(data_frames, 0, "the stopped board sends no data");
}

/// The high-water marks the board logged (`stack high-water mark: USED of SIZE bytes`).
pub(super) fn stack_marks(console: &str) -> Vec<(u64, u64)> {
    console
        .lines()
        .filter_map(|line| {
            let rest = line.split("stack high-water mark: ").nth(1)?;
            let mut words = rest.split_whitespace();
            let used = words.next()?.parse().ok()?;
            let size = words.nth(1)?.parse().ok()?;
            Some((used, size))
        })
        .collect()
}
