//! The flight-control image for the TI TM4C1294 (Cortex-M4F, 120 MHz, 1 MB flash, 256 KB RAM).
//!
//! - Clock tree to 120 MHz from the 25 MHz crystal (`tm4c129x-hal` sysctl).
//! - The 500 Hz SysTick exception (240,000 core cycles) hands the S.BUS frames to the core, then
//!   runs the flight computer's tick (`fcc_firmware::scheduler::FlightComputer::tick`, the same
//!   one the simulator and the QEMU replay run): the link's received bytes (setpoints,
//!   commands, parameters, time sync) → `FlightCore::step` → telemetry and acknowledgements into
//!   the UART's transmit ring; the handler's duration (DWT cycle counter) goes into the link's
//!   `Status` loop-time figures.
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
//! - The sensors, through `fcc_board::drivers`, polled by [`Tm4cSensors::poll`] in the tick:
//!   MPU-9250 + AK8963 on SSI2 (PD3 clock, PD1 MOSI, PD0 MISO, PD2 chip select as GPIO; SPI
//!   mode 3, 1 MHz while configuring, then 10 MHz for the sensor-register bursts), MS5611 on SSI3
//!   (PQ0 clock, PQ2 MOSI, PQ3 MISO, PQ1 chip select; mode 3, 10 MHz), u-blox GPS on UART2 (PA6
//!   RX, PA7 TX; configured at its 9600-baud default for NAV-PVT at 5 Hz, then switched to 38400),
//!   ILM-150-R laser on UART3 (PJ0 RX, 9600) and MB7076 sonar on UART6 (PP0 RX, 9600), both
//!   through an external inverter (inverted-TTL outputs). `tm4c129x-hal` 0.9 has no SPI driver:
//!   [`SsiSpi`] is a small blocking register-level `embedded_hal::spi::SpiDevice`. At 9600 and
//!   38400 baud a 16-byte RX FIFO lasts 16.7 / 4.2 ms, longer than the 2 ms tick, so those UARTs
//!   are drained by polling in the tick (no interrupts).
//!   A sensor whose initialisation fails is left out (its samples stay `None`: without the IMU
//!   the core refuses to arm). Not wired: the battery monitor (no ADC driver).
//! - The R/C receiver: S.BUS on UART7 (PC4 = U7RX, AF1), 100000 baud 8E2 (IBRD 75, exact at
//!   120 MHz). S.BUS is an inverted signal (idle low) and the TM4C's UART has no RX inversion,
//!   so the usual practice applies: an external inverter (one 74HC14 gate or an NPN stage, as
//!   on F1/F4 flight controllers) between the receiver and PC4. A 25-byte frame arrives in a
//!   3 ms burst, more than the 16-byte FIFO holds over one 2 ms tick, so the UART7 interrupt
//!   (same priority as the link's) moves bytes into a 64-byte ring; the tick decodes them
//!   (`fcc_board::drivers::sbus`), maps channels 1–4 (AETR: roll, pitch, throttle, yaw; ±100 %
//!   → ±1) and the override switch on channel 5 to a `fcc_firmware::pilot::PilotInput`, and
//!   hands it to `FlightCore::pilot`. A frame flagged failsafe by the receiver turns the
//!   override off; frames flagged frame-lost are not passed on (a run of them longer than the
//!   core's 0.5 s receiver timeout turns it off too).
#![no_std]
#![no_main]

use core::cell::{Cell, UnsafeCell};
use core::sync::atomic::{AtomicU32, AtomicUsize, Ordering};
use cortex_m::interrupt::Mutex;
use cortex_m::peripheral::{scb::SystemHandler, syst::SystClkSource, DWT, NVIC};
use cortex_m_rt::{entry, exception};
use embedded_hal::delay::DelayNs;
use fcc_board::drivers::gps_ubx::{
    config as ubx_config, UbxMessage, UbxParser, CLASS_NAV, ID_NAV_PVT,
};
use fcc_board::drivers::laser::LaserParser;
use fcc_board::drivers::mpu9250::{Mpu9250, Mpu9250Config};
use fcc_board::drivers::ms5611::{Ms5611, Osr};
use fcc_board::drivers::pwm::{tm4c::Pwm0Esc, EscOutputs, PwmConfig};
use fcc_board::drivers::sbus::{self, SbusDecoder, SbusFrame};
use fcc_board::drivers::sonar::{SonarConfig, SonarParser};
use fcc_firmware::params::Params;
use fcc_firmware::pilot::PilotInput;
use fcc_firmware::scheduler::{FlightComputer, TICK_US};
use fcc_firmware::sensors::{SensorBoard, SensorInputs};
use tm4c129x_hal::{
    self as hal,
    gpio::{AF1, AF14, AF6},
    interrupt,
    prelude::*,
    serial::{NewlineMode, Serial},
    tm4c129x::{
        Interrupt, GPIO_PORTD_AHB, GPIO_PORTJ_AHB, GPIO_PORTP, GPIO_PORTQ, SSI2, SSI3, UART0,
        UART2, UART3, UART6, UART7,
    },
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
/// S.BUS line rate (8E2, inverted by the external inverter).
const SBUS_BAUD: u32 = 100_000;
/// S.BUS channels (1-based), AETR order (FrSky/OpenTX default): roll (aileron), pitch
/// (elevator, +100 % = stick pushed forward), throttle, yaw (rudder), and the override switch.
const SBUS_CH_ROLL: usize = 1;
const SBUS_CH_PITCH: usize = 2;
const SBUS_CH_THROTTLE: usize = 3;
const SBUS_CH_YAW: usize = 4;
const SBUS_CH_OVERRIDE: usize = 5;
/// Override on above this raw value (a 2- or 3-position switch: only the top position).
const SBUS_OVERRIDE_ON_RAW: u16 = 1500;

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
const LINK_RX_BYTES: usize = 2048;
static LINK_RX: ByteRing<LINK_RX_BYTES> = ByteRing::new();
/// SysTick → UART0 interrupt.
static LINK_TX: ByteRing<2048> = ByteRing::new();
/// Received bytes dropped: RX ring full, or a framing/parity/break/overrun error on the line.
static LINK_RX_DROPPED: AtomicU32 = AtomicU32::new(0);
static LINK_RX_LINE_ERRORS: AtomicU32 = AtomicU32::new(0);

/// UART7 interrupt (S.BUS) → SysTick.
static SBUS_RX: ByteRing<64> = ByteRing::new();
static SBUS_RX_DROPPED: AtomicU32 = AtomicU32::new(0);

/// UART7: drain the S.BUS bytes into `SBUS_RX` (bytes with a framing, parity or break error are
/// dropped; the decoder resynchronises on the next header).
#[interrupt]
fn UART7() {
    // SAFETY: after set-up this handler is the only user of UART7's data and flag registers.
    let u = unsafe { &*UART7::ptr() };
    u.icr
        .write(|w| w.rxic().set_bit().rtic().set_bit().oeic().set_bit());
    while u.fr.read().rxfe().bit_is_clear() {
        let dr = u.dr.read().bits();
        if dr & 0x700 != 0 {
            continue;
        }
        if !SBUS_RX.push(dr as u8) {
            SBUS_RX_DROPPED.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// An S.BUS frame as the flight core's pilot input.
fn pilot_input(f: &SbusFrame, now_us: u64) -> PilotInput {
    let ch = |n: usize| f.channel(n).map_or(0.0, sbus::to_unit);
    PilotInput {
        override_on: sbus::pilot_override(Some(f), SBUS_CH_OVERRIDE, SBUS_OVERRIDE_ON_RAW),
        failsafe: f.failsafe,
        sticks: [
            ch(SBUS_CH_ROLL),
            ch(SBUS_CH_PITCH),
            ch(SBUS_CH_THROTTLE),
            ch(SBUS_CH_YAW),
        ],
        t_us: now_us,
    }
}

/// UART0: drain the RX FIFO into `LINK_RX`, refill the TX FIFO from `LINK_TX`.
#[interrupt]
fn UART0() {
    // SAFETY: after set-up this handler is the only user of UART0's data, flag and interrupt
    // registers, except SysTick setting IM.TXIM (a read-modify-write of IM done with this
    // interrupt masked, see `kick_tx`).
    let u = unsafe { &*UART0::ptr() };
    // Receive interrupt, receive timeout (bytes waiting below the FIFO level), transmit.
    u.icr.write(|w| {
        w.rxic()
            .set_bit()
            .rtic()
            .set_bit()
            .txic()
            .set_bit()
            .oeic()
            .set_bit()
    });
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

/// SSI (SPI) clock = SysClk / (CPSDVSR · (1 + SCR)) with CPSDVSR = 2.
const fn ssi_scr(hz: u32) -> u32 {
    // hz = 0 would divide by zero (a panic path): treat it as the slowest clock.
    let scr = SYSCLK_HZ / 2 / if hz == 0 { 1 } else { hz };
    if scr == 0 {
        0
    } else {
        scr - 1
    }
}

/// Alternate function 15 (the TM4C129x's SSI0–SSI2 pins); `tm4c-hal` 0.4 names only 1–9, 14.
struct AF15;
impl hal::gpio::AlternateFunctionChoice for AF15 {
    fn number() -> u32 {
        15
    }
}

/// A blocking, register-level SPI master on one SSI module (TM4C1294NCPDT datasheet, SSI
/// chapter: SSICR0 = SCR·2⁸ | SPH·2⁷ | SPO·2⁶ | FRF 0 (Freescale SPI) | DSS 7 (8 bits); SSICR1.SSE
/// enables, MS = 0 master; SSICPSR even prescaler; SSISR TNF/RNE/BSY), with a GPIO chip select
/// held low for a whole `transaction`.
struct SsiSpi {
    ssi: &'static hal::tm4c129x::ssi0::RegisterBlock,
    /// Bit-band target: the GPIO port's DATA register and the chip-select pin number.
    cs_data: *const u32,
    cs_pin: u8,
    /// SPI mode bits of SSICR0 (SPO, SPH).
    mode: u32,
    hz: u32,
    /// Where the owner can ask for another clock rate between transactions (the MPU-9250 runs
    /// its configuration at 1 MHz and its sensor-register bursts at up to 20 MHz).
    hz_request: Option<&'static AtomicU32>,
}

// SAFETY: one core; an `SsiSpi` is built in `main` and then moved, once, to the SysTick handler,
// its only user (it holds raw pointers to its own SSI module's and chip-select port's registers).
unsafe impl Send for SsiSpi {}

impl SsiSpi {
    /// `ssi` must be powered and its pins configured; `cs` must be a GPIO output.
    fn new(
        ssi: &'static hal::tm4c129x::ssi0::RegisterBlock,
        cs_data: *const u32,
        cs_pin: u8,
        hz: u32,
        hz_request: Option<&'static AtomicU32>,
    ) -> Self {
        let mut s = Self {
            ssi,
            cs_data,
            cs_pin,
            mode: 0xC0, // SPO = 1, SPH = 1: SPI mode 3
            hz,
            hz_request,
        };
        s.cs(true);
        // SAFETY: raw SSI register values per the datasheet; this struct owns the module.
        unsafe {
            s.ssi.cr1.write(|w| w.bits(0)); // disabled, master
            s.ssi.cc.write(|w| w.bits(0)); // system clock
            s.ssi.cpsr.write(|w| w.bits(2));
        }
        s.set_hz(hz);
        s
    }

    fn set_hz(&mut self, hz: u32) {
        self.hz = hz;
        // SAFETY: as in `new` (SSE off while changing the format).
        unsafe {
            self.ssi.cr1.write(|w| w.bits(0));
            self.ssi
                .cr0
                .write(|w| w.bits((ssi_scr(hz) << 8) | self.mode | 0x7));
            self.ssi.cr1.write(|w| w.bits(0x2)); // SSE
        }
    }

    fn cs(&mut self, high: bool) {
        // SAFETY: bit-band write of one GPIO DATA bit (the pin is an output owned by this SPI).
        unsafe { hal::bb::change_bit(self.cs_data, self.cs_pin, high) };
    }

    fn xfer(&mut self, out: u8) -> u8 {
        while self.ssi.sr.read().bits() & 0x2 == 0 {} // TNF
                                                      // SAFETY: 8-bit frame into the TX FIFO.
        unsafe { self.ssi.dr.write(|w| w.bits(out as u32)) };
        while self.ssi.sr.read().bits() & 0x4 == 0 {} // RNE
        self.ssi.dr.read().bits() as u8
    }
}

impl embedded_hal::spi::ErrorType for SsiSpi {
    type Error = core::convert::Infallible;
}

impl embedded_hal::spi::SpiDevice for SsiSpi {
    fn transaction(
        &mut self,
        operations: &mut [embedded_hal::spi::Operation<'_, u8>],
    ) -> Result<(), Self::Error> {
        use embedded_hal::spi::Operation;
        if let Some(want) = self.hz_request.map(|r| r.load(Ordering::Relaxed)) {
            if want != self.hz {
                self.set_hz(want);
            }
        }
        while self.ssi.sr.read().bits() & 0x4 != 0 {
            let _ = self.ssi.dr.read(); // stale RX bytes
        }
        self.cs(false);
        for op in operations.iter_mut() {
            match op {
                Operation::Read(buf) => buf.iter_mut().for_each(|b| *b = self.xfer(0)),
                Operation::Write(buf) => buf.iter().for_each(|&b| {
                    self.xfer(b);
                }),
                Operation::Transfer(read, write) => {
                    for i in 0..read.len().max(write.len()) {
                        let r = self.xfer(write.get(i).copied().unwrap_or(0));
                        if let Some(slot) = read.get_mut(i) {
                            *slot = r;
                        }
                    }
                }
                Operation::TransferInPlace(buf) => buf.iter_mut().for_each(|b| *b = self.xfer(*b)),
                Operation::DelayNs(ns) => CycleDelay.delay_ns(*ns),
            }
        }
        while self.ssi.sr.read().bits() & 0x10 != 0 {} // BSY
        self.cs(true);
        Ok(())
    }
}

/// Busy-wait delays from the core clock (drivers' power-up and reset waits, at start-up only).
struct CycleDelay;

impl embedded_hal::delay::DelayNs for CycleDelay {
    fn delay_ns(&mut self, ns: u32) {
        let cycles = (ns as u64 * (SYSCLK_HZ / 1_000_000) as u64).div_ceil(1000);
        cortex_m::asm::delay(cycles.min(u32::MAX as u64) as u32);
    }
}

/// Hand every byte waiting in a sensor UART's RX FIFO to `sink` (bytes with a framing, parity
/// or break error are dropped; the parsers resynchronise). At most 64 per call.
fn drain_uart(u: &hal::tm4c129x::uart0::RegisterBlock, mut sink: impl FnMut(u8)) {
    for _ in 0..64 {
        if u.fr.read().rxfe().bit_is_set() {
            break;
        }
        let dr = u.dr.read().bits();
        if dr & 0x700 == 0 {
            sink(dr as u8);
        }
    }
}

/// The board's sensors behind the core's `SensorBoard` trait.
struct Tm4cSensors {
    imu: Option<Mpu9250<SsiSpi>>,
    baro: Option<Ms5611<SsiSpi>>,
    gps: UbxParser,
    laser: LaserParser,
    sonar: SonarParser,
    /// SPI reads that failed (cannot happen with `SsiSpi`) or returned a stuck bus.
    bus_errors: u32,
}

impl SensorBoard for Tm4cSensors {
    fn poll(&mut self, now_us: u64) -> SensorInputs {
        let mut s = SensorInputs::default();
        if let Some(imu) = self.imu.as_mut() {
            match imu.read(now_us) {
                Ok(Some(r)) => {
                    s.imu = Some(r.imu);
                    s.mag = r.mag;
                }
                _ => self.bus_errors = self.bus_errors.wrapping_add(1),
            }
        }
        if let Some(baro) = self.baro.as_mut() {
            match baro.poll(now_us) {
                Ok(b) => s.baro = b,
                Err(_) => self.bus_errors = self.bus_errors.wrapping_add(1),
            }
        }
        // SAFETY: after set-up the tick is the only user of these UARTs' data registers.
        let (u2, u3, u6) = unsafe { (&*UART2::ptr(), &*UART3::ptr(), &*UART6::ptr()) };
        let gps = &mut self.gps;
        drain_uart(u2, |b| {
            if let Some(UbxMessage::NavPvt(p)) = gps.push(b) {
                s.gps = Some(p.to_gps_fix(now_us));
            }
        });
        let laser = &mut self.laser;
        drain_uart(u3, |b| {
            if let Some(r) = laser.push(b) {
                s.laser = Some(r.to_range_sample(now_us));
            }
        });
        let sonar = &mut self.sonar;
        drain_uart(u6, |b| {
            if let Some(r) = sonar.push(b) {
                s.sonar = Some(r.to_range_sample(now_us));
            }
        });
        s
    }
}

struct Board {
    fc: FlightComputer,
    sensors: Tm4cSensors,
    escs: EscOutputs<Pwm0Esc>,
    sbus: SbusDecoder,
    now_us: u64,
}

/// Handed from `main` to the first SysTick, which keeps it.
static BOARD: Mutex<Cell<Option<Board>>> = Mutex::new(Cell::new(None));

/// MPU-9250 SPI clock: 1 MHz until its configuration is done, then 10 MHz (sensor registers
/// allow 20 MHz, PS §7.5).
static IMU_SPI_HZ: AtomicU32 = AtomicU32::new(1_000_000);

/// The SPI sensors: SSI2 (MPU-9250) on PD0–PD3, SSI3 (MS5611) on PQ0–PQ3, their power, and
/// each driver's start-up (`None` when it fails; the IMU then runs its bus at 10 MHz).
fn spi_sensors(
    ssi2: SSI2,
    ssi3: SSI3,
    portd: GPIO_PORTD_AHB,
    portq: GPIO_PORTQ,
    pc: &hal::sysctl::PowerControl,
    delay: &mut CycleDelay,
) -> (Option<Mpu9250<SsiSpi>>, Option<Ms5611<SsiSpi>>) {
    use hal::sysctl::{self, Domain, PowerState, RunMode};
    // SPI: SSI2 (IMU) on PD0–PD3 (AF15), SSI3 (barometer) on PQ0–PQ3 (AF14); chip selects GPIO.
    let mut pd = portd.split(pc);
    let _imu_pins = (
        pd.pd3.into_af_push_pull::<AF15>(&mut pd.control),
        pd.pd1.into_af_push_pull::<AF15>(&mut pd.control),
        pd.pd0.into_af_push_pull::<AF15>(&mut pd.control),
        pd.pd2.into_push_pull_output(),
    );
    let mut pq = portq.split(pc);
    let _baro_pins = (
        pq.pq0.into_af_push_pull::<AF14>(&mut pq.control),
        pq.pq2.into_af_push_pull::<AF14>(&mut pq.control),
        pq.pq3.into_af_push_pull::<AF14>(&mut pq.control),
        pq.pq1.into_push_pull_output(),
    );
    for d in [Domain::Ssi2, Domain::Ssi3] {
        sysctl::control_power(pc, d, RunMode::Run, PowerState::On);
        sysctl::reset(pc, d);
    }
    // The SSI modules are used through their register blocks from here on.
    let _ = (ssi2, ssi3);
    // SAFETY: the register blocks exist for the program's life; SsiSpi owns each module.
    let (ssi2_regs, ssi3_regs) = unsafe { (&*SSI2::ptr(), &*SSI3::ptr()) };
    let (pd_data, pq_data) = unsafe {
        (
            core::ptr::addr_of!((*GPIO_PORTD_AHB::ptr()).data) as *const u32,
            core::ptr::addr_of!((*GPIO_PORTQ::ptr()).data) as *const u32,
        )
    };

    let imu_spi = SsiSpi::new(ssi2_regs, pd_data, 2, 1_000_000, Some(&IMU_SPI_HZ));
    let mut imu = Mpu9250::new(imu_spi, Mpu9250Config::default());
    let imu = match imu.init(delay) {
        Ok(()) => {
            IMU_SPI_HZ.store(10_000_000, Ordering::Relaxed);
            Some(imu)
        }
        Err(_) => None,
    };
    let baro_spi = SsiSpi::new(ssi3_regs, pq_data, 1, 10_000_000, None);
    let mut baro = Ms5611::new(baro_spi, Osr::Osr4096);
    let baro = baro.init(delay).ok().map(|_| baro);
    (imu, baro)
}

/// Pins, SSI modules and UARTs of the sensors; each driver's start-up sequence. A sensor whose
/// start-up fails is left out (`None`), see the module docs.
#[allow(clippy::too_many_arguments)]
fn setup_sensors<P>(
    ssi2: SSI2,
    ssi3: SSI3,
    uart2: UART2,
    uart3: UART3,
    uart6: UART6,
    portd: GPIO_PORTD_AHB,
    portq: GPIO_PORTQ,
    portj: GPIO_PORTJ_AHB,
    portp: GPIO_PORTP,
    gps_pins: (
        P,
        hal::gpio::gpioa::PA6<hal::gpio::AlternateFunction<AF1, hal::gpio::PushPull>>,
    ),
    clocks: &hal::sysctl::Clocks,
    pc: &hal::sysctl::PowerControl,
) -> Tm4cSensors
where
    P: hal::serial::TxPin<UART2>,
{
    let mut delay = CycleDelay;

    let (imu, baro) = spi_sensors(ssi2, ssi3, portd, portq, pc, &mut delay);

    // GPS on UART2: NAV-PVT every 200 ms, then the receiver's port to 38400 baud (sent at the
    // u-blox default of 9600; a receiver already at 38400 ignores it and is simply read there).
    let mut gps_uart = Serial::uart2(
        uart2,
        gps_pins.0,
        gps_pins.1,
        (),
        (),
        9_600.bps(),
        NewlineMode::Binary,
        clocks,
        pc,
    );
    let mut frame = [0u8; 32];
    for build in [
        |f: &mut [u8]| ubx_config::cfg_msg(CLASS_NAV, ID_NAV_PVT, 1, f),
        |f: &mut [u8]| ubx_config::cfg_rate(200, f),
        |f: &mut [u8]| ubx_config::cfg_prt_uart1(38_400, f),
    ] {
        if let Some(bytes) = build(&mut frame).and_then(|n| frame.get(..n)) {
            gps_uart.write_all(bytes);
        }
        delay.delay_ms(50); // the frame leaves the FIFO (≤ 28 bytes at 9600 baud: 29 ms)
    }
    delay.delay_ms(100);
    gps_uart.change_baud_rate(38_400.bps(), clocks);

    // Laser on UART3 (PJ0) and sonar on UART6 (PP0), receive only, 9600 8N1.
    let mut pj = portj.split(pc);
    let laser_rx = pj.pj0.into_af_push_pull::<AF1>(&mut pj.control);
    let _laser_uart = Serial::uart3(
        uart3,
        (),
        laser_rx,
        (),
        (),
        9_600.bps(),
        NewlineMode::Binary,
        clocks,
        pc,
    );
    let mut pp = portp.split(pc);
    let sonar_rx = pp.pp0.into_af_push_pull::<AF1>(&mut pp.control);
    let _sonar_uart = Serial::uart6(
        uart6,
        (),
        sonar_rx,
        (),
        (),
        9_600.bps(),
        NewlineMode::Binary,
        clocks,
        pc,
    );

    Tm4cSensors {
        imu,
        baro,
        gps: UbxParser::new(),
        laser: LaserParser::new(),
        sonar: SonarParser::new(SonarConfig::MB7076),
        bus_errors: 0,
    }
}

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
    let porta_sensor_pins = (
        porta.pa7.into_af_push_pull::<AF1>(&mut porta.control), // U2TX
        porta.pa6.into_af_push_pull::<AF1>(&mut porta.control), // U2RX
    );
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
    link_uart_interrupts();

    // The S.BUS receiver: UART7 RX on PC4, 100000 baud 8E2 (the HAL configures 8N1; parity
    // and two stop bits are set in LCRH with the UART disabled, as the datasheet requires).
    let mut portc = p.GPIO_PORTC_AHB.split(&sc.power_control);
    let sbus_rx = portc.pc4.into_af_push_pull::<AF1>(&mut portc.control);
    let _sbus_uart = Serial::uart7(
        p.UART7,
        (),
        sbus_rx,
        (),
        (),
        SBUS_BAUD.bps(),
        NewlineMode::Binary,
        &clocks,
        &sc.power_control,
    );
    sbus_uart_8e2();

    let sensors = setup_sensors(
        p.SSI2,
        p.SSI3,
        p.UART2,
        p.UART3,
        p.UART6,
        p.GPIO_PORTD_AHB,
        p.GPIO_PORTQ,
        p.GPIO_PORTJ_AHB,
        p.GPIO_PORTP,
        porta_sensor_pins,
        &clocks,
        &sc.power_control,
    );

    cortex_m::interrupt::free(|cs| {
        BOARD.borrow(cs).set(Some(Board {
            fc: FlightComputer::new(Params::default()),
            sensors,
            escs,
            sbus: SbusDecoder::new(),
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
        cp.NVIC.set_priority(Interrupt::UART7, PRIO_UART);
        NVIC::unmask(Interrupt::UART0);
        NVIC::unmask(Interrupt::UART7);
    }

    start_tick(&mut cp.SYST);
    loop {
        cortex_m::asm::wfi();
    }
}

/// The link UART's FIFO levels and interrupts (RX ≥ 8 bytes, RX timeout, overrun; TX ≤ 4
/// bytes is enabled by `kick_tx`), after the HAL configured it.
fn link_uart_interrupts() {
    // SAFETY: UART0 is configured and its interrupt is not yet unmasked in the NVIC.
    let u = unsafe { &*UART0::ptr() };
    u.ifls.write(|w| w.rx().rx4_8().tx().tx2_8());
    u.icr.write(|w| unsafe { w.bits(0x7FF) });
    u.im.write(|w| w.rxim().set_bit().rtim().set_bit().oeim().set_bit());
}

/// UART7 to 8E2 for S.BUS (the HAL configures 8N1; parity and two stop bits are set in LCRH
/// with the UART disabled, as the datasheet requires), its FIFO level and RX interrupts.
fn sbus_uart_8e2() {
    // SAFETY: UART7 is configured and its interrupt is not yet unmasked in the NVIC.
    let u = unsafe { &*UART7::ptr() };
    u.ctl.modify(|_, w| w.uarten().clear_bit());
    u.lcrh.write(|w| {
        w.wlen()
            ._8()
            .fen()
            .set_bit()
            .pen()
            .set_bit()
            .eps()
            .set_bit()
            .stp2()
            .set_bit()
    });
    u.ctl.modify(|_, w| w.uarten().set_bit());
    u.ifls.write(|w| w.rx().rx4_8());
    u.icr.write(|w| unsafe { w.bits(0x7FF) });
    u.im.write(|w| w.rxim().set_bit().rtim().set_bit().oeim().set_bit());
}

/// SysTick from the core clock at the 500 Hz control rate, its exception on.
fn start_tick(syst: &mut cortex_m::peripheral::SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(TICK_RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
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

    // 1. Pilot: the S.BUS frames received since the last tick (frame-lost frames repeat old
    //    channels and are not passed on; the core times the receiver out after 0.5 s). They
    //    take effect in the tick's step.
    while let Some(byte) = SBUS_RX.pop() {
        if let Some(f) = b.sbus.push(byte) {
            if f.failsafe || !f.frame_lost {
                b.fc.core.pilot(b.now_us, &pilot_input(&f, b.now_us));
            }
        }
    }

    // 2. The tick: everything the UART received since the last tick (the whole ring) in;
    //    sensors → core → ESCs; out at most what the transmit ring can take now (the endpoint
    //    drops and counts telemetry that does not fit; replies wait for the next tick).
    let mut rx = [0u8; LINK_RX_BYTES];
    let n_rx = LINK_RX.pop_into(&mut rx);
    let mut tx = [0u8; 512];
    let room = LINK_TX.free().min(tx.len());
    let n = b.fc.tick(
        b.now_us,
        rx.get(..n_rx).unwrap_or_default(),
        &mut b.sensors,
        &mut b.escs,
        tx.get_mut(..room).unwrap_or_default(),
    );
    if let Some(bytes) = tx.get(..n).filter(|b| !b.is_empty()) {
        LINK_TX.push_slice(bytes);
        kick_tx();
    }

    let cycles = DWT::cycle_count().wrapping_sub(t0);
    b.fc.link.record_loop_time_us(cycles / (SYSCLK_HZ / 1_000_000));
}

/// Any panic stops the motors (ESC pulses → 1000 µs via reset) by resetting the MCU.
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    cortex_m::peripheral::SCB::sys_reset()
}
