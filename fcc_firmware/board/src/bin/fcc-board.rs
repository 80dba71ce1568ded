//! The flight-control image for the TI TM4C1294 (Cortex-M4F, 120 MHz, 1 MB flash, 256 KB RAM).
//!
//! What is real here: clock tree to 120 MHz from the 25 MHz crystal (`tm4c129x-hal` sysctl), the
//! 500 Hz SysTick exception (240,000 core cycles) driving the unchanged
//! `fcc_firmware::scheduler::tick` → `FlightCore::step`, the flight core itself, and the
//! vector table / reset / memory layout (cortex-m-rt, memory.x).
//!
//! What is STUBBED (marked `STUB` below) and must be filled in before flying:
//! - `Tm4cSensors`: the SPI/UART drivers (MPU-9250, MS5611, GPS, laser, sonar) are not wired to
//!   the SSI/UART peripherals yet; `poll` returns no samples, so the core stays disarmed.
//! - `EscPwm`: `tm4c129x-hal` 0.9 has no PWM module; the eight ESC outputs (PWM0 M0PWM0..7) are
//!   latched in memory but not yet written to the PWM generator registers.
//! - The link UART (921600 baud) and SBUS input are not wired.
#![no_std]
#![no_main]

use core::cell::RefCell;
use cortex_m::interrupt::Mutex;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception};
use fcc_firmware::flight::FlightCore;
use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::params::Params;
use fcc_firmware::scheduler::{self, TICK_US};
use fcc_firmware::sensors::{MotorOutputs, SensorBoard, SensorInputs};
use tm4c129x_hal::{self as hal, prelude::*};

/// Core clock after PLL setup.
const SYSCLK_HZ: u32 = 120_000_000;
/// SysTick reload for the 500 Hz control tick.
const TICK_RELOAD: u32 = SYSCLK_HZ / 1_000_000 * TICK_US as u32 - 1;

/// STUB: the sensor drivers' interrupt handlers (not yet attached to SSI0/SSI2 and UART2/3/6)
/// will deposit their newest samples here; the tick takes them. Read volatile so the image
/// contains the whole per-step path (an empty stub would let the optimiser drop most of it).
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
        // Only called inside the SysTick critical section.
        unsafe {
            let p = core::ptr::addr_of_mut!(PENDING);
            let s = core::ptr::read_volatile(p);
            core::ptr::write_volatile(p, SensorInputs::default());
            s
        }
    }
}

/// STUB: ESC commands latched; PWM0 generator writes to come (50–400 Hz, 1000–2000 µs pulses).
struct EscPwm {
    pulse_us: [u16; MOTOR_COUNT],
}

/// STUB: where the PWM0 compare registers will be written; volatile so the output is kept.
static mut ESC_PULSE_US: [u16; MOTOR_COUNT] = [1000; MOTOR_COUNT];

impl MotorOutputs for EscPwm {
    fn write(&mut self, _now_us: u64, cmd: &[f32; MOTOR_COUNT]) {
        for (p, c) in self.pulse_us.iter_mut().zip(cmd) {
            // NaN-safe clamp to 0..1, then 1000..2000 µs.
            let c = if *c > 0.0 { c.min(1.0) } else { 0.0 };
            *p = 1000 + (c * 1000.0) as u16;
        }
        unsafe { core::ptr::write_volatile(core::ptr::addr_of_mut!(ESC_PULSE_US), self.pulse_us) };
    }
}

struct Board {
    core: FlightCore,
    sensors: Tm4cSensors,
    escs: EscPwm,
    now_us: u64,
}

static BOARD: Mutex<RefCell<Option<Board>>> = Mutex::new(RefCell::new(None));

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
    let _ = clocks.sysclk;

    cortex_m::interrupt::free(|cs| {
        BOARD.borrow(cs).replace(Some(Board {
            core: FlightCore::new(Params::default()),
            sensors: Tm4cSensors,
            escs: EscPwm { pulse_us: [1000; MOTOR_COUNT] },
            now_us: 0,
        }));
    });

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

/// The 500 Hz control tick.
#[exception]
fn SysTick() {
    cortex_m::interrupt::free(|cs| {
        if let Some(b) = BOARD.borrow(cs).borrow_mut().as_mut() {
            b.now_us += TICK_US;
            scheduler::tick(&mut b.core, &mut b.sensors, &mut b.escs, b.now_us);
        }
    });
}

/// Any panic stops the motors (ESC pulses → 1000 µs via reset) by resetting the MCU.
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    cortex_m::peripheral::SCB::sys_reset()
}
