//! Pseudo-terminal plumbing for the virtual board: the board-sim holds the master side, the host
//! opens the slave side like any serial port (through a symlink at a path of the user's choice).
//!
//! The slave is put in raw mode (no echo, no line editing, no CR/LF translation) so that bytes
//! pass through unchanged in both directions. The master is non-blocking: a full slave input
//! buffer (host not reading) shows as a short write, which is how the board-sim sees a busy link.
//!
//! Hang-up detection: the master reports `POLLHUP` only once *every* slave descriptor is closed,
//! so the board-sim keeps its own slave descriptor until the host has opened the port (its first
//! command arrived) and then [`Pty::release_slave`]s it; from then on the host closing the port
//! (or dying) is visible as [`MasterEvent::HungUp`].

use nix::errno::Errno;
use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsFd, AsRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// What can go wrong with the pseudo-terminal.
#[derive(Debug, thiserror::Error)]
pub enum PtyError {
    #[error("cannot create a pseudo-terminal: {0}")]
    Open(Errno),
    #[error("cannot configure the pseudo-terminal {path}: {source}")]
    Configure { path: PathBuf, source: Errno },
    #[error("{path} exists and is not a symbolic link; refusing to replace it")]
    LinkOccupied { path: PathBuf },
    #[error("cannot link {path} to the pseudo-terminal: {source}")]
    Link {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("pseudo-terminal I/O failed: {0}")]
    Io(#[source] std::io::Error),
}

impl crate::error::Classify for PtyError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::LinkOccupied { .. } => crate::error::ErrorKind::BadInput,
            _ => crate::error::ErrorKind::Failure,
        }
    }
}

/// What [`Pty::wait`] saw on the master.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MasterEvent {
    /// Nothing before the timeout.
    Idle,
    /// Bytes from the host are waiting.
    Readable,
    /// Every slave descriptor is closed (the host closed the port after [`Pty::release_slave`]).
    HungUp,
}

/// A pseudo-terminal pair; the master side is ours.
#[derive(Debug)]
pub struct Pty {
    master: File,
    slave: Option<OwnedFd>,
    slave_path: PathBuf,
}

impl Pty {
    /// Opens a new pair: slave in raw mode, master non-blocking.
    pub fn open() -> Result<Self, PtyError> {
        let pair = nix::pty::openpty(None, None).map_err(PtyError::Open)?;
        let slave_path = nix::unistd::ttyname(pair.slave.as_fd()).map_err(PtyError::Open)?;
        let configure = |source| PtyError::Configure {
            path: slave_path.clone(),
            source,
        };
        let mut termios = tcgetattr(pair.slave.as_fd()).map_err(configure)?;
        cfmakeraw(&mut termios);
        tcsetattr(pair.slave.as_fd(), SetArg::TCSANOW, &termios).map_err(configure)?;
        let flags = fcntl(pair.master.as_raw_fd(), FcntlArg::F_GETFL).map_err(configure)?;
        let flags = OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK;
        fcntl(pair.master.as_raw_fd(), FcntlArg::F_SETFL(flags)).map_err(configure)?;
        Ok(Self {
            master: File::from(pair.master),
            slave: Some(pair.slave),
            slave_path,
        })
    }

    /// The slave device (`/dev/pts/N`) a host opens.
    pub fn slave_path(&self) -> &Path {
        &self.slave_path
    }

    /// Closes our own slave descriptor, so that the host closing the port becomes visible as
    /// [`MasterEvent::HungUp`]. Call it once the host has opened the port.
    pub fn release_slave(&mut self) {
        self.slave = None;
    }

    /// Waits up to `timeout` for bytes from the host or a hang-up.
    pub fn wait(&self, timeout: Duration) -> Result<MasterEvent, PtyError> {
        let ms = u16::try_from(timeout.as_millis()).unwrap_or(u16::MAX);
        let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::POLLIN)];
        match poll(&mut fds, PollTimeout::from(ms)) {
            Ok(0) | Err(Errno::EINTR) => return Ok(MasterEvent::Idle),
            Ok(_) => {}
            Err(e) => return Err(PtyError::Io(e.into())),
        }
        let revents = fds[0].revents().unwrap_or(PollFlags::empty());
        if revents.contains(PollFlags::POLLIN) {
            Ok(MasterEvent::Readable)
        } else if revents.intersects(PollFlags::POLLHUP | PollFlags::POLLERR) {
            Ok(MasterEvent::HungUp)
        } else {
            Ok(MasterEvent::Idle)
        }
    }

    /// Reads what the host sent, without blocking: `Ok(None)` on a hang-up, `Ok(Some(0))` when
    /// nothing is waiting.
    pub fn read(&mut self, buf: &mut [u8]) -> Result<Option<usize>, PtyError> {
        match self.master.read(buf) {
            Ok(n) => Ok(Some(n)),
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => Ok(Some(0)),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => Ok(Some(0)),
            // Linux reports a closed slave side as EIO on the master.
            Err(e) if e.raw_os_error() == Some(Errno::EIO as i32) => Ok(None),
            Err(e) => Err(PtyError::Io(e)),
        }
    }

    /// Writes what the link takes now, without blocking; returns the number of bytes taken
    /// (0 when the host's input buffer is full).
    pub fn write(&mut self, bytes: &[u8]) -> Result<usize, PtyError> {
        match self.master.write(bytes) {
            Ok(n) => Ok(n),
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::Interrupted
                ) =>
            {
                Ok(0)
            }
            Err(e) => Err(PtyError::Io(e)),
        }
    }
}

/// A symbolic link to the pseudo-terminal's slave, removed when dropped.
#[derive(Debug)]
pub struct PtyLink {
    path: PathBuf,
}

impl PtyLink {
    /// Links `path` to `target`. An existing symbolic link at `path` (left by a killed
    /// board-sim) is replaced; any other file is left alone and refused.
    pub fn create(path: &Path, target: &Path) -> Result<Self, PtyError> {
        if let Ok(meta) = std::fs::symlink_metadata(path) {
            if !meta.file_type().is_symlink() {
                return Err(PtyError::LinkOccupied {
                    path: path.to_path_buf(),
                });
            }
            std::fs::remove_file(path).map_err(|source| PtyError::Link {
                path: path.to_path_buf(),
                source,
            })?;
        }
        std::os::unix::fs::symlink(target, path).map_err(|source| PtyError::Link {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(Self {
            path: path.to_path_buf(),
        })
    }

    /// Where the link is.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for PtyLink {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};
    use std::os::unix::fs::OpenOptionsExt;

    /// Opens the slave like a serial port would (never as our controlling terminal).
    fn open_slave(path: &Path) -> File {
        std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(nix::libc::O_NOCTTY)
            .open(path)
            .unwrap()
    }

    #[test]
    fn bytes_pass_unchanged_both_ways() {
        let mut pty = Pty::open().unwrap();
        let mut slave = open_slave(pty.slave_path());
        // Every byte value, including CR, LF, ^C, ^D and 0x00, survives raw mode.
        let all: Vec<u8> = (0..=255u8).collect();
        assert_eq!(pty.write(&all).unwrap(), 256);
        let mut got = vec![0u8; 256];
        slave.read_exact(&mut got).unwrap();
        assert_eq!(got, all);

        slave.write_all(&all).unwrap();
        let mut back = Vec::new();
        while back.len() < 256 {
            assert_eq!(
                pty.wait(Duration::from_secs(2)).unwrap(),
                MasterEvent::Readable
            );
            let mut buf = [0u8; 512];
            let n = pty.read(&mut buf).unwrap().unwrap();
            back.extend_from_slice(&buf[..n]);
        }
        assert_eq!(back, all);
    }

    #[test]
    fn host_closing_is_a_hang_up_after_release() {
        let mut pty = Pty::open().unwrap();
        let slave = open_slave(pty.slave_path());
        pty.release_slave();
        assert_eq!(
            pty.wait(Duration::from_millis(10)).unwrap(),
            MasterEvent::Idle
        );
        drop(slave);
        assert_eq!(
            pty.wait(Duration::from_secs(2)).unwrap(),
            MasterEvent::HungUp
        );
        assert_eq!(pty.read(&mut [0u8; 8]).unwrap(), None);
    }

    #[test]
    fn link_replaces_stale_symlink_but_not_files_and_is_removed_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let link_path = dir.path().join("board");
        std::os::unix::fs::symlink("/nonexistent", &link_path).unwrap();
        let link = PtyLink::create(&link_path, Path::new("/dev/null")).unwrap();
        assert_eq!(
            std::fs::read_link(&link_path).unwrap(),
            Path::new("/dev/null")
        );
        drop(link);
        assert!(std::fs::symlink_metadata(&link_path).is_err());

        let file_path = dir.path().join("file");
        std::fs::write(&file_path, b"x").unwrap();
        assert!(matches!(
            PtyLink::create(&file_path, Path::new("/dev/null")),
            Err(PtyError::LinkOccupied { .. })
        ));
        assert_eq!(std::fs::read(&file_path).unwrap(), b"x");
    }
}
