//! The simulated board's UART: a pseudo-terminal whose slave side (`/dev/pts/N`, optionally
//! behind a fixed symlink) the bridge opens exactly like a real serial port.
//!
//! The simulator keeps the master side, non-blocking: bytes the Linux side wrote are read each
//! tick; telemetry that does not fit in the pty's buffer (nobody reading) is dropped and counted,
//! as bytes are lost on a real UART with no listener. The slave is set to raw mode at once, so
//! nothing written before the bridge opens it is cooked or echoed.

use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::pty::openpty;
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
use std::fs::File;
use std::io::{self, Read, Write};
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};

pub struct PtyLink {
    master: File,
    /// Kept open so the master never sees a hang-up while no client is connected.
    _slave: OwnedFd,
    slave_path: PathBuf,
    symlink: Option<PathBuf>,
    /// Bytes of telemetry dropped because the pty buffer was full.
    pub tx_dropped_bytes: u64,
}

impl PtyLink {
    /// Open a pty pair; if `symlink` is given, (re)create it pointing at the slave.
    pub fn open(symlink: Option<&Path>) -> io::Result<Self> {
        let pty = openpty(None, None).map_err(io::Error::from)?;
        let mut tio = tcgetattr(pty.slave.as_fd()).map_err(io::Error::from)?;
        cfmakeraw(&mut tio);
        tcsetattr(pty.slave.as_fd(), SetArg::TCSANOW, &tio).map_err(io::Error::from)?;
        let flags = fcntl(
            std::os::fd::AsRawFd::as_raw_fd(&pty.master),
            FcntlArg::F_GETFL,
        )
        .map_err(io::Error::from)?;
        fcntl(
            std::os::fd::AsRawFd::as_raw_fd(&pty.master),
            FcntlArg::F_SETFL(OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK),
        )
        .map_err(io::Error::from)?;
        let slave_path = std::fs::read_link(format!(
            "/proc/self/fd/{}",
            std::os::fd::AsRawFd::as_raw_fd(&pty.slave)
        ))?;
        let symlink = match symlink {
            Some(l) => {
                let _ = std::fs::remove_file(l);
                std::os::unix::fs::symlink(&slave_path, l)?;
                Some(l.to_path_buf())
            }
            None => None,
        };
        Ok(Self {
            master: File::from(pty.master),
            _slave: pty.slave,
            slave_path,
            symlink,
            tx_dropped_bytes: 0,
        })
    }

    /// The device a client opens (`/dev/pts/N`).
    pub fn slave_path(&self) -> &Path {
        &self.slave_path
    }

    /// The fixed symlink, if one was made.
    pub fn symlink(&self) -> Option<&Path> {
        self.symlink.as_deref()
    }

    /// Read whatever the client wrote (non-blocking); 0 when nothing is pending.
    pub fn read_available(&mut self, buf: &mut [u8]) -> usize {
        match self.master.read(buf) {
            Ok(n) => n,
            Err(_) => 0, // WouldBlock, or EIO while no client has the slave open
        }
    }

    /// Write without blocking; what does not fit is dropped and counted.
    pub fn write_or_drop(&mut self, bytes: &[u8]) -> usize {
        let n = match self.master.write(bytes) {
            Ok(n) => n,
            Err(_) => 0,
        };
        self.tx_dropped_bytes += (bytes.len() - n) as u64;
        n
    }
}

impl Drop for PtyLink {
    fn drop(&mut self) {
        if let Some(l) = &self.symlink {
            let _ = std::fs::remove_file(l);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_cross_the_pty_raw_both_ways() {
        let mut link = PtyLink::open(None).unwrap();
        let mut client = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(link.slave_path())
            .unwrap();
        // Every byte value, including the ones a cooked tty would interpret (CR, ^C, ^D, 0).
        let all: Vec<u8> = (0..=255u8).collect();
        client.write_all(&all).unwrap();
        let mut got = Vec::new();
        let mut buf = [0u8; 512];
        for _ in 0..100 {
            let n = link.read_available(&mut buf);
            got.extend_from_slice(&buf[..n]);
            if got.len() >= all.len() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        assert_eq!(got, all);
        assert_eq!(link.write_or_drop(&all), all.len());
        let mut back = vec![0u8; all.len()];
        client.read_exact(&mut back).unwrap();
        assert_eq!(back, all);
    }

    #[test]
    fn a_full_buffer_drops_instead_of_blocking() {
        let mut link = PtyLink::open(None).unwrap();
        let chunk = [0x55u8; 4096];
        let mut written = 0;
        for _ in 0..1000 {
            written += link.write_or_drop(&chunk);
        }
        assert!(written < 1000 * chunk.len());
        assert_eq!(link.tx_dropped_bytes as usize + written, 1000 * chunk.len());
    }
}
