//! `fcc-wire-fault`: a fault-injecting serial relay for robustness tests. It opens the MCU's
//! device (e.g. the pty `fcc-sitl --link-pty` serves), creates a new pseudo-terminal for the
//! Linux side (the bridge opens it like the UART), and forwards bytes both ways while flipping
//! bits at a given bit-error rate and dropping / duplicating bytes.
//!
//! ```text
//! fcc-wire-fault --mcu /tmp/fcc-sitl.tty --link /tmp/fcc-noisy.tty --ber 1e-4 --drop 1e-4 --dup 1e-4
//! ```
//! On SIGINT/SIGTERM it prints one line of counters (`wire-fault: …`) and exits 0.
//!
//! `--baud N` makes it a UART of N baud (8N1) as well: each direction forwards at most N/10
//! bytes/s. It reads a side only as fast as the line carries, so what a writer sends faster
//! queues in the pty (as in a UART driver's transmit buffer); the bytes waiting there (the
//! backlog, `FIONREAD`) and the bytes forwarded are written once a second to `--stats FILE` as
//! JSON lines with CLOCK_MONOTONIC times:
//! `{"mono_ns":…,"up_bytes":…,"down_bytes":…,"up_backlog_max":…,"down_backlog_max":…}`
//! (`up` = Linux → MCU; bytes since the previous line, backlog its largest since then).

use clap::Parser;
use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
use nix::pty::openpty;
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
use std::fs::{File, OpenOptions};
use std::io::{Read, Write};

use std::os::fd::{AsFd, AsRawFd};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

#[derive(Parser, Debug)]
#[command(
    name = "fcc-wire-fault",
    about = "Fault-injecting serial relay (bit flips, drops, duplicates)"
)]
struct Args {
    /// The MCU side: a serial device or pty path.
    #[arg(long)]
    mcu: PathBuf,
    /// Make this symlink to the new Linux-side pty.
    #[arg(long)]
    link: Option<PathBuf>,
    /// Bit-error rate applied to every bit in both directions.
    #[arg(long, default_value_t = 1e-4, allow_negative_numbers = true)]
    ber: f64,
    /// Probability that a byte is dropped.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    drop: f64,
    /// Probability that a byte is sent twice.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    dup: f64,
    /// Seed of the fault generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Limit each direction to this baud rate (8N1: baud/10 bytes/s); 0 = no limit.
    #[arg(long, default_value_t = 0)]
    baud: u32,
    /// JSON lines of bytes forwarded and backlog per second (see the module docs).
    #[arg(long)]
    stats: Option<PathBuf>,
}

/// One direction's line: a token bucket of `rate` bytes/s holding at most `burst` bytes.
struct Line {
    rate: f64,
    burst: f64,
    tokens: f64,
    last: std::time::Instant,
}

impl Line {
    fn new(baud: u32) -> Line {
        let rate = baud as f64 / 10.0;
        // Enough for the ~1 ms granularity of poll(2); ≈ 2.8 ms of line time at 921600 baud.
        let burst = (rate / 100.0).max(64.0);
        Line {
            rate,
            burst,
            tokens: burst,
            last: std::time::Instant::now(),
        }
    }
    /// Bytes the line can take now (`usize::MAX` when unlimited).
    fn allowance(&mut self) -> usize {
        if self.rate <= 0.0 {
            return usize::MAX;
        }
        let now = std::time::Instant::now();
        self.tokens = (self.tokens + (now - self.last).as_secs_f64() * self.rate).min(self.burst);
        self.last = now;
        self.tokens.floor() as usize
    }
    fn take(&mut self, n: usize) {
        if self.rate > 0.0 {
            self.tokens -= n as f64;
        }
    }
    /// Milliseconds until one byte fits.
    fn wait_ms(&self) -> u16 {
        if self.rate <= 0.0 || self.tokens >= 1.0 {
            0
        } else {
            (((1.0 - self.tokens) / self.rate * 1000.0).ceil() as u16).max(1)
        }
    }
}

/// Bytes waiting to be read on `fd` (FIONREAD): a pty's transmit backlog.
fn backlog(fd: i32) -> usize {
    let mut n: nix::libc::c_int = 0;
    // SAFETY: FIONREAD writes one int.
    if unsafe { nix::libc::ioctl(fd, nix::libc::FIONREAD, &mut n) } < 0 {
        return 0;
    }
    n.max(0) as usize
}

fn mono_ns() -> i64 {
    let mut t = nix::libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: one valid timespec.
    unsafe { nix::libc::clock_gettime(nix::libc::CLOCK_MONOTONIC, &mut t) };
    t.tv_sec as i64 * 1_000_000_000 + t.tv_nsec as i64
}

/// splitmix64: a seeded uniform source for the faults.
struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[derive(Default)]
struct Counters {
    bytes: u64,
    bit_flips: u64,
    dropped: u64,
    duplicated: u64,
    overflow: u64,
}

/// Write what fits without blocking; count the rest.
fn send(to: &mut File, bytes: &[u8], c: &mut Counters) {
    let n = to.write(bytes).unwrap_or(0);
    c.overflow += (bytes.len() - n) as u64;
}

fn corrupt(rng: &mut Rng, a: &Args, input: &[u8], out: &mut Vec<u8>, c: &mut Counters) {
    for &b in input {
        c.bytes += 1;
        if a.drop > 0.0 && rng.unit() < a.drop {
            c.dropped += 1;
            continue;
        }
        let mut b = b;
        if a.ber > 0.0 {
            for bit in 0..8 {
                if rng.unit() < a.ber {
                    b ^= 1 << bit;
                    c.bit_flips += 1;
                }
            }
        }
        out.push(b);
        if a.dup > 0.0 && rng.unit() < a.dup {
            out.push(b);
            c.duplicated += 1;
        }
    }
}

fn main() -> ExitCode {
    let a = match fcc_mission::cli::parse::<Args, _, _>("fcc-wire-fault", std::env::args_os()) {
        Ok(a) => a,
        Err(code) => return ExitCode::from(code),
    };
    for (name, p) in [("--ber", a.ber), ("--drop", a.drop), ("--dup", a.dup)] {
        if !(0.0..=1.0).contains(&p) {
            eprintln!("fcc-wire-fault: {name}: must be a probability in [0, 1], got {p}");
            return ExitCode::from(2);
        }
    }
    let mut mcu: File = match OpenOptions::new().read(true).write(true).open(&a.mcu) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("fcc-wire-fault: {}: {e}", a.mcu.display());
            return ExitCode::from(2);
        }
    };
    let raw = |fd: std::os::fd::BorrowedFd| -> nix::Result<()> {
        let mut t = tcgetattr(fd)?;
        cfmakeraw(&mut t);
        tcsetattr(fd, SetArg::TCSANOW, &t)
    };
    if let Err(e) = raw(mcu.as_fd()) {
        eprintln!(
            "fcc-wire-fault: {}: cannot set raw mode: {e}",
            a.mcu.display()
        );
        return ExitCode::from(2);
    }
    let pty = match openpty(None, None) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("fcc-wire-fault: cannot open a pseudo-terminal: {e}");
            return ExitCode::from(1);
        }
    };
    let _ = raw(pty.slave.as_fd());
    let slave =
        std::fs::read_link(format!("/proc/self/fd/{}", pty.slave.as_raw_fd())).unwrap_or_default();
    if let Some(l) = &a.link {
        let _ = std::fs::remove_file(l);
        if let Err(e) = std::os::unix::fs::symlink(&slave, l) {
            eprintln!("fcc-wire-fault: {}: {e}", l.display());
            return ExitCode::from(1);
        }
    }
    println!("fcc-wire-fault: linux side on {}", slave.display());
    let _ = std::io::stdout().flush();
    let mut linux = File::from(pty.master);
    // Never block on a side nobody reads: what does not fit is dropped (counted as overflow).
    for fd in [mcu.as_raw_fd(), linux.as_raw_fd()] {
        use nix::fcntl::{fcntl, FcntlArg, OFlag};
        if let Ok(fl) = fcntl(fd, FcntlArg::F_GETFL) {
            let _ = fcntl(
                fd,
                FcntlArg::F_SETFL(OFlag::from_bits_truncate(fl) | OFlag::O_NONBLOCK),
            );
        }
    }
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register(sig, stop.clone());
    }
    let mut stats = match &a.stats {
        Some(p) => match File::create(p) {
            Ok(f) => Some(f),
            Err(e) => {
                eprintln!("fcc-wire-fault: {}: {e}", p.display());
                return ExitCode::from(2);
            }
        },
        None => None,
    };
    let mut rng = Rng(a.seed);
    let (mut up, mut down) = (Counters::default(), Counters::default());
    let (mut up_line, mut down_line) = (Line::new(a.baud), Line::new(a.baud));
    // Per stats period: bytes forwarded, largest backlog (up = Linux → MCU).
    let (mut up_b, mut down_b, mut up_q, mut down_q) = (0u64, 0u64, 0usize, 0usize);
    let mut next_stats = mono_ns() + 1_000_000_000;
    let mut buf = [0u8; 4096];
    let mut out = Vec::with_capacity(8192);
    while !stop.load(Ordering::Relaxed) {
        let (down_ok, up_ok) = (down_line.allowance(), up_line.allowance());
        let flags = |ok: usize| {
            if ok > 0 {
                PollFlags::POLLIN
            } else {
                PollFlags::empty()
            }
        };
        let mut fds = [
            PollFd::new(mcu.as_fd(), flags(down_ok)),
            PollFd::new(linux.as_fd(), flags(up_ok)),
        ];
        let mut timeout = 100u16;
        for w in [down_line.wait_ms(), up_line.wait_ms()] {
            if w > 0 {
                timeout = timeout.min(w);
            }
        }
        if a.baud > 0 {
            up_q = up_q.max(backlog(linux.as_raw_fd()));
            down_q = down_q.max(backlog(mcu.as_raw_fd()));
        }
        if let Some(f) = stats.as_mut() {
            let now = mono_ns();
            if now >= next_stats {
                let _ = writeln!(
                    f,
                    "{{\"mono_ns\":{now},\"up_bytes\":{up_b},\"down_bytes\":{down_b},\"up_backlog_max\":{up_q},\"down_backlog_max\":{down_q}}}"
                );
                let _ = f.flush();
                (up_b, down_b, up_q, down_q) = (0, 0, 0, 0);
                next_stats = now + 1_000_000_000;
            }
        }
        if poll(&mut fds, PollTimeout::from(timeout)).is_err() {
            continue;
        }
        let ready = |f: &PollFd| f.revents().is_some_and(|r| r.contains(PollFlags::POLLIN));
        let (from_mcu, from_linux) = (ready(&fds[0]), ready(&fds[1]));
        if from_mcu {
            let n = down_ok.min(buf.len());
            if let Ok(n) = mcu.read(&mut buf[..n]) {
                down_line.take(n);
                down_b += n as u64;
                out.clear();
                corrupt(&mut rng, &a, &buf[..n], &mut out, &mut down);
                send(&mut linux, &out, &mut down);
            }
        }
        if from_linux {
            let n = up_ok.min(buf.len());
            if let Ok(n) = linux.read(&mut buf[..n]) {
                up_line.take(n);
                up_b += n as u64;
                out.clear();
                corrupt(&mut rng, &a, &buf[..n], &mut out, &mut up);
                send(&mut mcu, &out, &mut up);
            }
        }
    }
    if let Some(l) = &a.link {
        let _ = std::fs::remove_file(l);
    }
    println!(
        "wire-fault: mcu→linux {} bytes, {} bit flips, {} dropped, {} duplicated, {} overflow | linux→mcu {} bytes, {} bit flips, {} dropped, {} duplicated, {} overflow",
        down.bytes, down.bit_flips, down.dropped, down.duplicated, down.overflow, up.bytes, up.bit_flips, up.dropped, up.duplicated, up.overflow
    );
    ExitCode::SUCCESS
}
