//! The flight-control image for the TI TM4C1294 (Cortex-M4F, 120 MHz, 1 MB flash, 256 KB RAM).
//!
//! - Clock tree to 120 MHz from the 25 MHz crystal (`tm4c129x-hal` sysctl).
//! - The 500 Hz SysTick exception (240,000 core cycles) runs, in this order: the link's received
//!   bytes into `fcc_firmware::link::LinkEndpoint::on_bytes` (setpoints, commands, parameters,
//!   time sync), the unchanged `fcc_firmware::scheduler::tick` → `FlightCore::step`, then
//!   `LinkEndpoint::poll_tx` (telemetry, acknowledgements) into the UART's transmit ring; the
//!   step's duration (DWT cycle counter) goes into the link's `Status` loop-time figures.
//! - The link to the Linux computer: UART0 (PA0 = U0RX, PA1 = U0TX; the LaunchPad's ICDI
//!   virtual COM port), 921600 baud 8N1 (divisor 8 + 9/64 at 120 MHz: 921,305 baud, −0.03 %).
//!   The UART0 interrupt, at a higher priority than SysTick, moves bytes between the 16-byte
//!   hardware FIFOs and two static lock-free rings (one producer, one consumer each; no heap):
//!   RX 2 KB (22 ms of line time), TX 2 KB. Nothing blocks: a full RX ring drops bytes (the
//!   link's CRC/sequence numbers count the loss), and `poll_tx` is only given the TX ring's free
//!   space, so telemetry that does not fit is dropped and counted by the endpoint.
//! - The eight ESC outputs: PWM0 generators 0–3 (`fcc_board::drivers::pwm::tm4c::Pwm0Esc`,
//!   400 Hz, 1000–2000 µs) on M0PWM0..7 = PF0–PF3, PG0, PG1, PK4, PK5 (alternate function 6).
//!
//! Not wired in this image: the sensor buses. `fcc_board::drivers` has the MPU-9250/AK8963 and
//! MS5611 (SPI `SpiDevice`), u-blox UBX, ILM-150-R laser, MB7076 sonar and S.BUS drivers, but
//! `tm4c129x-hal` 0.9 has no SPI (SSI) driver, so they need an SSI `SpiDevice` adapter and one
//! more interrupt-fed UART ring per serial sensor (as UART0's here). Until then
//! [`Tm4cSensors::poll`] returns the samples an interrupt handler deposited in `PENDING` (none),
//! so the core stays disarmed: it refuses to arm without an IMU.
#![no_std]
#![no_main]

use core::cell::{Cell, UnsafeCell};
use core::sync::atomic::{AtomicU32, AtomicUsize, Ordering};
use cortex_m::interrupt::Mutex;
use cortex_m::peripheral::{scb::SystemHandler, syst::SystClkSource, DWT, NVIC};
use cortex_m_rt::{entry, exception};
use fcc_board::drivers::pwm::{tm4c::Pwm0Esc, EscOutputs, PwmConfig};
use fcc_firmware::flight::FlightCore;
use fcc_firmware::link::LinkEndpoint;
use fcc_firmware::params::Params;
use fcc_firmware::scheduler::{self, TICK_US};
use fcc_firmware::sensors::{SensorBoard, SensorInputs};
use tm4c129x_hal::{
    self as hal,
    gpio::{AF1, AF6},
    interrupt,
    prelude::*,
    serial::{NewlineMode, Serial},
    tm4c129x::{Interrupt, UART0},
};

/// Core clock after PLL setup.
const SYSCLK_HZ: u32 = 120_000_000;
/// SysTick reload for the 500 Hz control tick.
const TICK_RELOAD: u32 = SYSCLK_HZ / 1_000_000 * TICK_US as u32 - 1;
/// The link's line rate (921600 baud 8N1 = 92,160 B/s = 184 B per 2 ms tick).
const LINK_BAUD: u32 = 921_600;
/// NVIC priorities (upper 3 bits on the TM4C129x): the UART must preempt the control tick, whose
/// step can take longer than the 174 µs a 16-byte FIFO lasts at 921600 baud.
const PRIO_UART: u8 = 0x20;
const PRIO_SYSTICK: u8 = 0x80;

/// A single-producer single-consumer byte ring in static memory. `N` is a power of two; the
/// indices run freely and wrap (`head − tail` = bytes stored).
struct ByteRing<const N: usize> {
    buf: UnsafeCell<[u8; N]>,
    /// Written only by the producer.
    head: AtomicUsize,
    /// Written only by the consumer.
    tail: AtomicUsize,
}

// SAFETY: each slot is written by the producer before `head` is released past it and read by the
// consumer before `tail` is released past it; the two sides never touch the same slot at once.
unsafe impl<const N: usize> Sync for ByteRing<N> {}

impl<const N: usize> ByteRing<N> {
    const fn new() -> Self {
        assert!(N.is_power_of_two());
        Self {
            buf: UnsafeCell::new([0; N]),
            head: AtomicUsize::new(0),
            tail: AtomicUsize::new(0),
        }
    }

    /// Free space (producer side).
    fn free(&self) -> usize {
        N - self
            .head
            .load(Ordering::Relaxed)
            .wrapping_sub(self.tail.load(Ordering::Acquire))
    }

    /// Producer: store `b`, or return false when full.
    fn push(&self, b: u8) -> bool {
        let head = self.head.load(Ordering::Relaxed);
        if head.wrapping_sub(self.tail.load(Ordering::Acquire)) >= N {
            return false;
        }
        // SAFETY: slot `head` is not readable by the consumer until `head` is released below.
        unsafe { (*self.buf.get())[head % N] = b };
        self.head.store(head.wrapping_add(1), Ordering::Release);
        true
    }

    /// Producer: store as much of `bytes` as fits; returns how many.
    fn push_slice(&self, bytes: &[u8]) -> usize {
        let n = bytes.len().min(self.free());
        let head = self.head.load(Ordering::Relaxed);
        for (i, &b) in bytes[..n].iter().enumerate() {
            // SAFETY: as in `push`; these n slots are free.
            unsafe { (*self.buf.get())[head.wrapping_add(i) % N] = b };
        }
        self.head.store(head.wrapping_add(n), Ordering::Release);
        n
    }

    /// Consumer: take the oldest byte.
    fn pop(&self) -> Option<u8> {
        let tail = self.tail.load(Ordering::Relaxed);
        if self.head.load(Ordering::Acquire) == tail {
            return None;
        }
        // SAFETY: the producer released slot `tail` and does not reuse it before `tail` moves.
        let b = unsafe { (*self.buf.get())[tail % N] };
        self.tail.store(tail.wrapping_add(1), Ordering::Release);
        Some(b)
    }

    /// Consumer: move up to `out.len()` bytes out; returns how many.
    fn pop_into(&self, out: &mut [u8]) -> usize {
        let tail = self.tail.load(Ordering::Relaxed);
        let n = self
            .head
            .load(Ordering::Acquire)
            .wrapping_sub(tail)
            .min(out.len());
        for (i, o) in out[..n].iter_mut().enumerate() {
            // SAFETY: as in `pop`.
            *o = unsafe { (*self.buf.get())[tail.wrapping_add(i) % N] };
        }
        self.tail.store(tail.wrapping_add(n), Ordering::Release);
        n
    }
}

/// UART0 interrupt → SysTick.
static LINK_RX: ByteRing<2048> = ByteRing::new();
/// SysTick → UART0 interrupt.
static LINK_TX: ByteRing<2048> = ByteRing::new();
/// Received bytes dropped: RX ring full, or a framing/parity/break/overrun error on the line.
static LINK_RX_DROPPED: AtomicU32 = AtomicU32::new(0);
static LINK_RX_LINE_ERRORS: AtomicU32 = AtomicU32::new(0);

/// UART0: drain the RX FIFO into `LINK_RX`, refill the TX FIFO from `LINK_TX`.
#[interrupt]
fn UART0() {
    // SAFETY: after set-up this handler is the only user of UART0's data, flag and interrupt
    // registers, except SysTick setting IM.TXIM (a read-modify-write of IM done with this
    // interrupt masked, see `kick_tx`).
    let u = unsafe { &*UART0::ptr() };
    // Receive interrupt, receive timeout (bytes waiting below the FIFO level), transmit.
    u.icr.write(|w| w.rxic().set_bit().rtic().set_bit().txic().set_bit().oeic().set_bit());
    while u.fr.read().rxfe().bit_is_clear() {
        let dr = u.dr.read().bits();
        // DR bits 8..11: framing, parity, break, overrun error for this byte.
        if dr & 0xF00 != 0 {
            LINK_RX_LINE_ERRORS.fetch_add(1, Ordering::Relaxed);
            if dr & 0x700 != 0 {
                continue; // the byte itself is bad; an overrun flags a loss before a good byte
            }
        }
        if !LINK_RX.push(dr as u8) {
            LINK_RX_DROPPED.fetch_add(1, Ordering::Relaxed);
        }
    }
    while u.fr.read().txff().bit_is_clear() {
        match LINK_TX.pop() {
            // SAFETY: any 8-bit value is a valid DR data field.
            Some(b) => u.dr.write(|w| unsafe { w.bits(b as u32) }),
            None => {
                // Nothing left: stop transmit interrupts until SysTick queues more.
                u.im.modify(|_, w| w.txim().clear_bit());
                break;
            }
        }
    }
}

/// SysTick side: frames were queued in `LINK_TX`; enable the transmit interrupt and run the
/// handler once so it primes the FIFO (it fires again whenever the FIFO drains to 4 bytes).
fn kick_tx() {
    cortex_m::interrupt::free(|_| {
        // SAFETY: IM is shared with the UART0 handler, which cannot run inside this section.
        let u = unsafe { &*UART0::ptr() };
        u.im.modify(|_, w| w.txim().set_bit());
    });
    NVIC::pend(Interrupt::UART0);
}

/// The sensor drivers' interrupt handlers (not attached yet, see the module docs) deposit their
/// newest samples here; the tick takes them. Read volatile so the image keeps the whole
/// per-step path.
static mut PENDING: SensorInputs = SensorInputs {
    imu: None,
    mag: None,
    baro: None,
    gps: None,
    laser: None,
    sonar: None,
    battery: None,
};

struct Tm4cSensors;

impl SensorBoard for Tm4cSensors {
    fn poll(&mut self, _now_us: u64) -> SensorInputs {
        // Only called from SysTick, the only user of PENDING.
        unsafe {
            let p = core::ptr::addr_of_mut!(PENDING);
            let s = core::ptr::read_volatile(p);
            core::ptr::write_volatile(p, SensorInputs::default());
            s
        }
    }
}

struct Board {
    core: FlightCore,
    link: LinkEndpoint,
    sensors: Tm4cSensors,
    escs: EscOutputs<Pwm0Esc>,
    now_us: u64,
}

/// Handed from `main` to the first SysTick, which keeps it.
static BOARD: Mutex<Cell<Option<Board>>> = Mutex::new(Cell::new(None));

#[entry]
fn main() -> ! {
    let p = hal::Peripherals::take().unwrap();
    let mut cp = hal::CorePeripherals::take().unwrap();
    let mut sc = p.SYSCTL.constrain();
    sc.clock_setup.oscillator = hal::sysctl::Oscillator::Main(
        hal::sysctl::CrystalFrequency::_25mhz,
        hal::sysctl::SystemClock::UsePll(hal::sysctl::PllOutputFrequency::_120mhz),
    );
    let clocks = sc.clock_setup.freeze();

    // ESCs first, so they see the stop pulse from power-up on.
    let mut portf = p.GPIO_PORTF_AHB.split(&sc.power_control);
    let mut portg = p.GPIO_PORTG_AHB.split(&sc.power_control);
    let mut portk = p.GPIO_PORTK.split(&sc.power_control);
    let _esc_pins = (
        portf.pf0.into_af_push_pull::<AF6>(&mut portf.control),
        portf.pf1.into_af_push_pull::<AF6>(&mut portf.control),
        portf.pf2.into_af_push_pull::<AF6>(&mut portf.control),
        portf.pf3.into_af_push_pull::<AF6>(&mut portf.control),
        portg.pg0.into_af_push_pull::<AF6>(&mut portg.control),
        portg.pg1.into_af_push_pull::<AF6>(&mut portg.control),
        portk.pk4.into_af_push_pull::<AF6>(&mut portk.control),
        portk.pk5.into_af_push_pull::<AF6>(&mut portk.control),
    );
    let esc_cfg = PwmConfig::default();
    let pwm = match Pwm0Esc::new(p.PWM0, &sc.power_control, SYSCLK_HZ, esc_cfg) {
        Some(pwm) => pwm,
        // 400 Hz at 120 MHz always fits the 16-bit counter; never fly without outputs.
        None => cortex_m::peripheral::SCB::sys_reset(),
    };
    let mut escs = EscOutputs::new(pwm, esc_cfg);
    escs.stop();

    // The link UART: 921600 8N1, FIFOs on, interrupts at RX ≥ 8 bytes, RX timeout, TX ≤ 4 bytes.
    let mut porta = p.GPIO_PORTA_AHB.split(&sc.power_control);
    let u0_tx = porta.pa1.into_af_push_pull::<AF1>(&mut porta.control);
    let u0_rx = porta.pa0.into_af_push_pull::<AF1>(&mut porta.control);
    let uart = Serial::uart0(
        p.UART0,
        u0_tx,
        u0_rx,
        (),
        (),
        LINK_BAUD.bps(),
        NewlineMode::Binary,
        &clocks,
        &sc.power_control,
    );
    // The interrupt handler owns the registers from here on (through UART0::ptr()); keep the
    // configured pins and peripheral alive without using the blocking HAL calls.
    let _uart = uart.split();
    {
        // SAFETY: UART0 is configured and its interrupt is not yet unmasked in the NVIC.
        let u = unsafe { &*UART0::ptr() };
        u.ifls.write(|w| w.rx().rx4_8().tx().tx2_8());
        u.icr.write(|w| unsafe { w.bits(0x7FF) });
        u.im.write(|w| w.rxim().set_bit().rtim().set_bit().oeim().set_bit());
    }

    cortex_m::interrupt::free(|cs| {
        BOARD.borrow(cs).set(Some(Board {
            core: FlightCore::new(Params::default()),
            link: LinkEndpoint::default(),
            sensors: Tm4cSensors,
            escs,
            now_us: 0,
        }));
    });

    // Step timing for the link's loop-time report.
    cp.DCB.enable_trace();
    cp.DWT.enable_cycle_counter();

    // SAFETY: priorities are set before either interrupt can fire.
    unsafe {
        cp.SCB.set_priority(SystemHandler::SysTick, PRIO_SYSTICK);
        cp.NVIC.set_priority(Interrupt::UART0, PRIO_UART);
        NVIC::unmask(Interrupt::UART0);
    }

    let syst = &mut cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(TICK_RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
    loop {
        cortex_m::asm::wfi();
    }
}

/// The 500 Hz control tick. It runs with interrupts enabled (the UART0 handler preempts it);
/// the board state lives in this handler's own `static mut`, taken once from `BOARD`.
#[exception]
fn SysTick() {
    static mut STATE: Option<Board> = None;
    if STATE.is_none() {
        *STATE = cortex_m::interrupt::free(|cs| BOARD.borrow(cs).take());
    }
    let Some(b) = STATE.as_mut() else { return };
    let t0 = DWT::cycle_count();
    b.now_us += TICK_US;

    // 1. Link in: everything the UART received since the last tick.
    let mut rx = [0u8; 256];
    loop {
        let n = LINK_RX.pop_into(&mut rx);
        if n == 0 {
            break;
        }
        b.link.on_bytes(b.now_us, &rx[..n], &mut b.core);
    }

    // 2. Sensors → core → ESCs.
    let inputs = scheduler::tick(&mut b.core, &mut b.sensors, &mut b.escs, b.now_us);

    // 3. Link out: at most what the transmit ring can take now (the endpoint drops and counts
    //    telemetry that does not fit; replies wait for the next tick).
    let mut tx = [0u8; 512];
    let room = LINK_TX.free().min(tx.len());
    let n = b.link.poll_tx(b.now_us, &b.core, &inputs, &mut tx[..room]);
    if let Some(bytes) = tx.get(..n).filter(|b| !b.is_empty()) {
        LINK_TX.push_slice(bytes);
        kick_tx();
    }

    let cycles = DWT::cycle_count().wrapping_sub(t0);
    b.link.record_loop_time_us(cycles / (SYSCLK_HZ / 1_000_000));
}

/// Any panic stops the motors (ESC pulses → 1000 µs via reset) by resetting the MCU.
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    cortex_m::peripheral::SCB::sys_reset()
}
