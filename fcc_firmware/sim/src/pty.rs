//! The simulated board's UART: a pseudo-terminal whose slave side (`/dev/pts/N`, optionally
//! behind a fixed symlink) the bridge opens exactly like a real serial port.
//!
//! The simulator keeps the master side, non-blocking: bytes the Linux side wrote are read each
//! tick. Telemetry goes through a transmit ring of [`TX_RING_BYTES`] (an MCU's UART DMA ring)
//! into the pty; a frame that does not fit in the ring (nobody reading, or a reader slower than
//! the MCU writes) is dropped whole and counted, as a UART driver with a full ring does: the wire
//! never carries a cut frame, so the bridge sees lost frames (sequence gaps), not CRC errors.
//! The slave is set to raw mode at once, so nothing written before the bridge opens it is cooked
//! or echoed.

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
    /// Frames queued for the pty (whole frames, at most [`TX_RING_BYTES`]).
    ring: Vec<u8>,
    /// Bytes of telemetry dropped (whole frames) because the ring was full.
    pub tx_dropped_bytes: u64,
    /// Frames dropped because the ring was full.
    pub tx_dropped_frames: u64,
}

/// The transmit ring: bytes of whole frames waiting for the pty (a 4 KiB DMA ring).
pub const TX_RING_BYTES: usize = 4096;

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
            ring: Vec::with_capacity(TX_RING_BYTES),
            tx_dropped_bytes: 0,
            tx_dropped_frames: 0,
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

    /// Queue whole frames (each ending in 0x00) in the transmit ring and hand the pty what it
    /// takes, without blocking; a frame that does not fit in the ring is dropped whole and
    /// counted. Returns the bytes the pty took.
    pub fn send_frames(&mut self, bytes: &[u8]) -> usize {
        let mut taken = self.flush_ring();
        for f in bytes.split_inclusive(|b| *b == 0) {
            if self.ring.len() + f.len() <= TX_RING_BYTES {
                self.ring.extend_from_slice(f);
            } else {
                self.tx_dropped_bytes += f.len() as u64;
                self.tx_dropped_frames += 1;
            }
        }
        taken += self.flush_ring();
        taken
    }

    /// Move what the pty takes from the ring (0 while it is full or nobody has it open).
    fn flush_ring(&mut self) -> usize {
        if self.ring.is_empty() {
            return 0;
        }
        match self.master.write(&self.ring) {
            Ok(n) => {
                self.ring.drain(..n);
                n
            }
            Err(_) => 0,
        }
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
        assert_eq!(link.send_frames(&all), all.len());
        let mut back = vec![0u8; all.len()];
        client.read_exact(&mut back).unwrap();
        assert_eq!(back, all);
    }

    #[test]
    fn a_full_buffer_drops_whole_frames_instead_of_blocking() {
        let mut link = PtyLink::open(None).unwrap();
        let mut frame = [0x55u8; 100];
        frame[99] = 0;
        let frames: Vec<u8> = frame
            .iter()
            .copied()
            .cycle()
            .take(40 * frame.len())
            .collect();
        let mut taken = 0;
        for _ in 0..1000 {
            taken += link.send_frames(&frames);
        }
        let sent = 1000 * frames.len();
        assert!(link.tx_dropped_frames > 0);
        assert_eq!(
            link.tx_dropped_bytes,
            link.tx_dropped_frames * frame.len() as u64
        );
        // Every byte was taken by the pty, waits in the ring, or belongs to a dropped frame.
        assert_eq!(
            taken + link.ring.len() + link.tx_dropped_bytes as usize,
            sent
        );
        // Only whole frames entered the ring (the pty takes them in order, the last one perhaps
        // in part, its rest still in the ring).
        assert_eq!((taken + link.ring.len()) % frame.len(), 0);
    }
}
