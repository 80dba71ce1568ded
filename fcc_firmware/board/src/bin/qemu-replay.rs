//! QEMU test image (machine `mps2-an386`, Cortex-M4 with FPU): replays a recorded flight
//! (`data/inputs.bin`, made by the host `record` tool from the SITL) through the flight
//! computer's tick the board runs (`fcc_firmware::scheduler::FlightComputer::tick`: link in →
//! `FlightCore::step` → link out), prints every tick's motor commands over semihosting (f32 bit
//! patterns, hex) for the host to compare, and measures each tick with SysTick.
//!
//! Instruction counting: run QEMU with `-icount shift=0` (virtual clock advances 1 ns per
//! executed instruction). SysTick runs from the mps2's CPU clock on that virtual clock; the image
//! calibrates SysTick ticks → instructions with a loop of known length, so the per-step figures
//! are in instructions. Output lines:
//!   `M <tick> <8 × hex f32>` per tick, then `CAL`, `STEP`, `LINK`, `SELF`, `DONE` summary lines.
//! `STEP` is the step inside the tick: from the core polling the board to the motor commands
//! written (SysTick read in the replay board's `poll` and the ESC latch's `write`). `LINK` is
//! the rest of the tick after the step, the link's transmit side (telemetry frames at the
//! default stream rates into at most 512 bytes; the recording has no received bytes, so
//! `on_bytes` is not exercised). `TICK` is the whole tick.
#![no_std]
#![no_main]

use core::fmt::Write;
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hio};
use fcc_board::replay::{apply_events, InputStream, MotorLatch, OutputStream, ReplayBoard, TX_BYTES};
use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::params::Params;
use fcc_firmware::scheduler::FlightComputer;
use fcc_firmware::sensors::{MotorOutputs, SensorBoard, SensorInputs};

static INPUTS: &[u8] = include_bytes!("../../data/inputs.bin");
static EXPECTED: &[u8] = include_bytes!("../../data/expected.bin");

/// Semihosting output batched into 2 KB writes (each write is one trap into QEMU).
struct Out {
    host: Option<hio::HostStream>,
    buf: [u8; 2048],
    len: usize,
}

impl Out {
    fn flush(&mut self) {
        if let Some(h) = self.host.as_mut() {
            let _ = h.write_all(&self.buf[..self.len]);
        }
        self.len = 0;
    }
}

impl Write for Out {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for &b in s.as_bytes() {
            if self.len == self.buf.len() {
                self.flush();
            }
            self.buf[self.len] = b;
            self.len += 1;
        }
        Ok(())
    }
}

const SYST_MASK: u32 = 0x00FF_FFFF;

fn elapsed(start: u32, end: u32) -> u32 {
    // SysTick counts down.
    start.wrapping_sub(end) & SYST_MASK
}

/// The recorded samples, with SysTick read when the core polls them (its step starts).
struct TimedBoard {
    replay: ReplayBoard,
    polled_at: u32,
}

impl SensorBoard for TimedBoard {
    fn poll(&mut self, now_us: u64) -> SensorInputs {
        self.polled_at = SYST::get_current();
        self.replay.poll(now_us)
    }
}

/// The ESC latch, with SysTick read when the step has written the motor commands.
struct TimedEscs {
    latch: MotorLatch,
    written_at: u32,
}

impl MotorOutputs for TimedEscs {
    fn write(&mut self, now_us: u64, cmd: &[f32; MOTOR_COUNT]) {
        self.latch.write(now_us, cmd);
        self.written_at = SYST::get_current();
    }
}

/// `n` iterations of a 2-instruction loop (`subs`, `bne`): 2n instructions.
#[inline(never)]
fn known_loop(n: u32) {
    if n == 0 {
        return;
    }
    unsafe {
        core::arch::asm!("2:", "subs {0}, #1", "bne 2b", inout(reg) n => _, options(nomem, nostack));
    }
}

#[entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap();
    let mut out = Out { host: hio::hstdout().ok(), buf: [0; 2048], len: 0 };
    let syst: &mut SYST = &mut cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYST_MASK);
    syst.clear_current();
    syst.enable_counter();

    // Calibrate: SysTick ticks for 2,000,000 instructions.
    const CAL_INSNS: u32 = 2_000_000;
    let t0 = SYST::get_current();
    known_loop(CAL_INSNS / 2);
    let cal_ticks = elapsed(t0, SYST::get_current()).max(1);
    let insn_per_tick = CAL_INSNS as f32 / cal_ticks as f32;
    let _ = writeln!(out, "CAL {} insns in {} systick ticks: {:.3} insns/tick", CAL_INSNS, cal_ticks, insn_per_tick);

    let Some(stream) = InputStream::new(INPUTS) else {
        let _ = writeln!(out, "ERROR bad input recording");
        out.flush();
        debug::exit(debug::EXIT_FAILURE);
        loop {}
    };
    let mut expected = OutputStream::new(EXPECTED);
    // The board's flight computer: telemetry at the default stream rates into at most 512 bytes
    // per tick (the link reads the core and does not change it).
    let mut fc = FlightComputer::new(Params::default());
    let mut board = TimedBoard { replay: ReplayBoard { next: SensorInputs::default() }, polled_at: 0 };
    let mut motors = TimedEscs { latch: MotorLatch::default(), written_at: 0 };
    let mut tx = [0u8; TX_BYTES];
    let (mut link_sum, mut link_max, mut link_bytes) = (0u64, 0u32, 0u64);
    let (mut tick_sum, mut tick_max) = (0u64, 0u32);
    let (mut n, mut sum, mut min, mut max, mut max_at) = (0u32, 0u64, u32::MAX, 0u32, 0u32);
    let (mut armed_n, mut armed_sum, mut armed_max) = (0u32, 0u64, 0u32);
    let mut max_diff = 0.0f32;
    let mut compared = 0u32;
    for rec in stream {
        apply_events(&mut fc.core, &rec);
        board.replay.next = rec.inputs;
        let a = SYST::get_current();
        let nb = fc.tick(rec.now_us, &[], &mut board, &mut motors, &mut tx);
        let c = SYST::get_current();
        let t = elapsed(board.polled_at, motors.written_at);
        let tl = elapsed(motors.written_at, c);
        let tt = elapsed(a, c);
        link_sum += tl as u64;
        link_max = link_max.max(tl);
        link_bytes += nb as u64;
        tick_sum += tt as u64;
        tick_max = tick_max.max(tt);
        sum += t as u64;
        if t < min {
            min = t;
        }
        if t > max {
            max = t;
            max_at = n;
        }
        if fc.core.armed() {
            armed_n += 1;
            armed_sum += t as u64;
            armed_max = armed_max.max(t);
        }
        let _ = write!(out, "M {}", n);
        for v in motors.latch.0 {
            let _ = write!(out, " {:08x}", v.to_bits());
        }
        let _ = writeln!(out);
        if let Some(e) = expected.as_mut().and_then(|e| e.next()) {
            for (x, y) in e.iter().zip(motors.latch.0.iter()) {
                let d = libm::fabsf(x - y);
                if !(d <= max_diff) {
                    max_diff = if d.is_nan() { f32::INFINITY } else { d };
                }
            }
            compared += 1;
        }
        n += 1;
    }
    let k = insn_per_tick;
    let mean = if n > 0 { sum as f32 / n as f32 } else { 0.0 };
    let armed_mean = if armed_n > 0 { armed_sum as f32 / armed_n as f32 } else { 0.0 };
    let _ = writeln!(
        out,
        "STEP all {} ticks: mean {:.0} min {:.0} max {:.0} (tick {}) insns; armed {} ticks: mean {:.0} max {:.0} insns",
        n,
        mean * k,
        min as f32 * k,
        max as f32 * k,
        max_at,
        armed_n,
        armed_mean * k,
        armed_max as f32 * k
    );
    let _ = writeln!(
        out,
        "LINK all {} ticks: poll_tx mean {:.0} max {:.0} insns, {:.1} bytes/tick; whole tick max {:.0} insns",
        n,
        if n > 0 { link_sum as f32 / n as f32 * k } else { 0.0 },
        link_max as f32 * k,
        if n > 0 { link_bytes as f32 / n as f32 } else { 0.0 },
        tick_max as f32 * k
    );
    let _ = writeln!(
        out,
        "TICK all {} ticks: FlightComputer::tick mean {:.0} max {:.0} insns",
        n,
        if n > 0 { tick_sum as f32 / n as f32 * k } else { 0.0 },
        tick_max as f32 * k
    );
    let _ = writeln!(out, "SELF compared {} ticks with the embedded host outputs: max abs diff {:e}", compared, max_diff);
    let _ = writeln!(out, "DONE {}", n);
    out.flush();
    debug::exit(if n > 0 { debug::EXIT_SUCCESS } else { debug::EXIT_FAILURE });
    loop {}
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    if let Ok(mut h) = hio::hstdout() {
        let _ = writeln!(h, "PANIC {}", info);
    }
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}
