//! ESC outputs: normalised motor commands → pulse widths, and the TM4C129x PWM0 generators.
//!
//! The flight core's mixer gives one command per motor in [0, 1] (`fcc_firmware`
//! `MotorOutputs::write`, `MOTOR_COUNT` = 8, 0 = stopped, 1 = full throttle). Standard
//! "PWM" ESCs take a 1000 µs (stop) … 2000 µs (full) pulse; at 400 Hz the period is 2500 µs.
//! [`pulse_us`] is the pure mapping (NaN and out-of-range commands are clamped, NaN → stop);
//! [`PwmOutputs`] is what a timer peripheral implements; [`EscOutputs`] joins them into the
//! core's `MotorOutputs`.
//!
//! The register-level TM4C129x implementation, [`tm4c::Pwm0Esc`] (feature `tm4c`), uses the
//! `tm4c129x` PAC (re-exported by `tm4c129x-hal`, which has no PWM driver in 0.9). Source:
//! TI **TM4C1294NCPDT datasheet** (SPMS433), chapter "Pulse Width Modulator (PWM)":
//! its "Initialization and Configuration" section: enable the clock in RCGCPWM, PWMCC.USEPWM and
//! PWMDIV, per generator PWMnCTL = 0 / count-down, PWMnGENA = 0x8C (drive high on LOAD, low on
//! CMPA counting down), PWMnGENB = 0x80C (same with CMPB), PWMnLOAD = period − 1, PWMnCMPA/B,
//! start the generator, PWMENABLE), 16-bit counters; compare updates locally synchronised
//! (PWMnCTL.CMPAUPD/CMPBUPD = 0) so a new width takes effect at the next period, never
//! mid-pulse.
//! Pins (TM4C1294NCPDT pin table, alternate function 6): M0PWM0 PF0, M0PWM1 PF1, M0PWM2 PF2,
//! M0PWM3 PF3, M0PWM4 PG0, M0PWM5 PG1, M0PWM6 PK4, M0PWM7 PK5 — the board binary configures the
//! pins (GPIO AFSEL/PCTL/DEN, e.g. `tm4c129x-hal` gpio `into_af_push_pull::<AF6>`); this driver
//! only owns the PWM0 block.

use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::sensors::MotorOutputs;

/// Pulse mapping and rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PwmConfig {
    /// Pulse at command 0 (stop / arming), µs.
    pub min_us: u16,
    /// Pulse at command 1, µs.
    pub max_us: u16,
    /// Frame rate, Hz (400: the period 2500 µs must exceed `max_us`).
    pub freq_hz: u32,
}

impl Default for PwmConfig {
    fn default() -> Self {
        Self {
            min_us: 1000,
            max_us: 2000,
            freq_hz: 400,
        }
    }
}

/// Command in [0, 1] → pulse width, µs. Clamped; NaN → `min_us` (stop).
pub fn pulse_us(cmd: f32, cfg: &PwmConfig) -> u16 {
    let c = if cmd > 0.0 { cmd.min(1.0) } else { 0.0 }; // NaN fails `> 0` → 0
    let span = cfg.max_us.saturating_sub(cfg.min_us) as f32;
    cfg.min_us.saturating_add((c * span + 0.5) as u16)
}

/// All motors.
pub fn motor_pulses(cmds: &[f32; MOTOR_COUNT], cfg: &PwmConfig) -> [u16; MOTOR_COUNT] {
    cmds.map(|c| pulse_us(c, cfg))
}

/// A PWM peripheral with `MOTOR_COUNT` channels (0-based). Channels beyond its count are ignored.
pub trait PwmOutputs {
    fn set_duty_us(&mut self, ch: usize, us: u16);
}

/// The core's `MotorOutputs` on any [`PwmOutputs`]: motor `i` → channel `i`.
pub struct EscOutputs<P> {
    pub pwm: P,
    pub cfg: PwmConfig,
    /// Last pulses written (telemetry / tests).
    pub last_us: [u16; MOTOR_COUNT],
}

impl<P: PwmOutputs> EscOutputs<P> {
    pub fn new(pwm: P, cfg: PwmConfig) -> Self {
        Self {
            pwm,
            cfg,
            last_us: [cfg.min_us; MOTOR_COUNT],
        }
    }

    /// All outputs to the stop pulse (call at boot so the ESCs arm, and on disarm).
    pub fn stop(&mut self) {
        self.write_pulses(&[self.cfg.min_us; MOTOR_COUNT]);
    }

    pub fn write_pulses(&mut self, us: &[u16; MOTOR_COUNT]) {
        for (ch, &u) in us.iter().enumerate() {
            self.pwm.set_duty_us(ch, u);
        }
        self.last_us = *us;
    }
}

impl<P: PwmOutputs> MotorOutputs for EscOutputs<P> {
    fn write(&mut self, _now_us: u64, cmd: &[f32; MOTOR_COUNT]) {
        let us = motor_pulses(cmd, &self.cfg);
        self.write_pulses(&us);
    }
}

/// PWM0 timing for a system clock and frame rate: the smallest PWM clock divider (2…64) that
/// keeps the period within the 16-bit counter, for the finest pulse resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PwmTiming {
    /// PWMCC.PWMDIV field: 0 = /2 … 5 = /64.
    pub div_code: u8,
    pub pwm_clk_hz: u32,
    /// PWMnLOAD (period − 1, counts).
    pub load: u16,
}

impl PwmTiming {
    pub fn new(sysclk_hz: u32, freq_hz: u32) -> Option<PwmTiming> {
        if freq_hz == 0 {
            return None;
        }
        (0u8..=5).find_map(|code| {
            let clk = sysclk_hz >> (code + 1);
            let period = clk / freq_hz;
            if (2..=65_536).contains(&period) {
                Some(PwmTiming {
                    div_code: code,
                    pwm_clk_hz: clk,
                    load: (period - 1) as u16,
                })
            } else {
                None
            }
        })
    }

    /// Counts for a pulse of `us`, clamped to [1, load − 1] (a compare at 0 or LOAD would
    /// give no edge).
    pub fn pulse_counts(&self, us: u16) -> u16 {
        let c = (us as u64 * self.pwm_clk_hz as u64 + 500_000) / 1_000_000;
        c.clamp(1, self.load.saturating_sub(1).max(1) as u64) as u16
    }

    /// Compare value in count-down mode: the output is high from LOAD down to CMP, so
    /// CMP = LOAD − pulse counts.
    pub fn compare(&self, us: u16) -> u16 {
        self.load.saturating_sub(self.pulse_counts(us))
    }
}

/// TM4C129x PWM0, register level (feature `tm4c`).
#[cfg(feature = "tm4c")]
pub mod tm4c {
    use super::{PwmConfig, PwmOutputs, PwmTiming};
    use tm4c129x_hal::sysctl::{self, Domain, PowerControl, PowerState, RunMode};
    use tm4c129x_hal::tm4c129x::PWM0;

    /// PWMnGENA: ACTLOAD = 3 (drive high), ACTCMPAD = 2 (drive low) → 0x8C.
    const GENA: u32 = 0x0000_008C;
    /// PWMnGENB: ACTLOAD = 3, ACTCMPBD = 2 → 0x80C.
    const GENB: u32 = 0x0000_080C;
    /// PWMnCTL: ENABLE (bit 0), count-down (MODE = 0), LOADUPD/CMPAUPD/CMPBUPD = 0
    /// ("locally synchronised": a new LOAD/CMPA/CMPB takes effect the next time the counter
    /// reaches 0; 1 would wait for a global update request through PWMCTL).
    const CTL_RUN: u32 = 0x0000_0001;
    /// PWMCC.USEPWM (bit 8).
    const CC_USEPWM: u32 = 0x0000_0100;

    /// The eight ESC outputs M0PWM0..7 on PWM0 generators 0–3.
    pub struct Pwm0Esc {
        pwm: PWM0,
        timing: PwmTiming,
    }

    impl Pwm0Esc {
        /// Power and reset PWM0, set the divider and period for `cfg.freq_hz`, start all four
        /// generators with every output at `cfg.min_us`, enable the outputs. `None` if the
        /// rate cannot be reached with a 16-bit counter.
        pub fn new(pwm: PWM0, pc: &PowerControl, sysclk_hz: u32, cfg: PwmConfig) -> Option<Self> {
            let timing = PwmTiming::new(sysclk_hz, cfg.freq_hz)?;
            sysctl::control_power(pc, Domain::Pwm0, RunMode::Run, PowerState::On);
            sysctl::reset(pc, Domain::Pwm0);
            let cmp = timing.compare(cfg.min_us) as u32;
            let load = timing.load as u32;
            // SAFETY: raw register values per the datasheet's bit fields (see the module docs);
            // this driver owns PWM0.
            unsafe {
                pwm.cc.write(|w| w.bits(CC_USEPWM | timing.div_code as u32));
                macro_rules! gen {
                    ($ctl:ident, $gena:ident, $genb:ident, $load:ident, $cmpa:ident, $cmpb:ident) => {
                        pwm.$ctl.write(|w| w.bits(0));
                        pwm.$gena.write(|w| w.bits(GENA));
                        pwm.$genb.write(|w| w.bits(GENB));
                        pwm.$load.write(|w| w.bits(load));
                        pwm.$cmpa.write(|w| w.bits(cmp));
                        pwm.$cmpb.write(|w| w.bits(cmp));
                        pwm.$ctl.write(|w| w.bits(CTL_RUN));
                    };
                }
                gen!(_0_ctl, _0_gena, _0_genb, _0_load, _0_cmpa, _0_cmpb);
                gen!(_1_ctl, _1_gena, _1_genb, _1_load, _1_cmpa, _1_cmpb);
                gen!(_2_ctl, _2_gena, _2_genb, _2_load, _2_cmpa, _2_cmpb);
                gen!(_3_ctl, _3_gena, _3_genb, _3_load, _3_cmpa, _3_cmpb);
                pwm.enable.write(|w| w.bits(0xFF));
            }
            Some(Self { pwm, timing })
        }

        pub fn timing(&self) -> PwmTiming {
            self.timing
        }

        /// Give the peripheral back (outputs left running).
        pub fn free(self) -> PWM0 {
            self.pwm
        }
    }

    impl PwmOutputs for Pwm0Esc {
        fn set_duty_us(&mut self, ch: usize, us: u16) {
            let v = self.timing.compare(us) as u32;
            let p = &self.pwm;
            // SAFETY: any 16-bit compare value is valid; `compare` keeps it below LOAD.
            unsafe {
                match ch {
                    0 => p._0_cmpa.write(|w| w.bits(v)),
                    1 => p._0_cmpb.write(|w| w.bits(v)),
                    2 => p._1_cmpa.write(|w| w.bits(v)),
                    3 => p._1_cmpb.write(|w| w.bits(v)),
                    4 => p._2_cmpa.write(|w| w.bits(v)),
                    5 => p._2_cmpb.write(|w| w.bits(v)),
                    6 => p._3_cmpa.write(|w| w.bits(v)),
                    7 => p._3_cmpb.write(|w| w.bits(v)),
                    _ => {}
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pulse_mapping() {
        let c = PwmConfig::default();
        assert_eq!(pulse_us(0.0, &c), 1000);
        assert_eq!(pulse_us(1.0, &c), 2000);
        assert_eq!(pulse_us(0.5, &c), 1500);
        assert_eq!(pulse_us(0.1234, &c), 1123);
        assert_eq!(pulse_us(-3.0, &c), 1000);
        assert_eq!(pulse_us(7.0, &c), 2000);
        assert_eq!(pulse_us(f32::NAN, &c), 1000);
        assert_eq!(pulse_us(f32::INFINITY, &c), 2000);
        assert_eq!(pulse_us(f32::NEG_INFINITY, &c), 1000);
        let mut x = -0.5f32;
        let mut prev = 0;
        while x < 1.5 {
            let p = pulse_us(x, &c);
            assert!(p >= prev && (1000..=2000).contains(&p));
            prev = p;
            x += 0.001;
        }
    }

    struct Rec([u16; 10]);
    impl PwmOutputs for Rec {
        fn set_duty_us(&mut self, ch: usize, us: u16) {
            if let Some(s) = self.0.get_mut(ch) {
                *s = us;
            }
        }
    }

    #[test]
    fn esc_outputs_are_the_core_motor_outputs() {
        let mut e = EscOutputs::new(Rec([0; 10]), PwmConfig::default());
        e.stop();
        assert_eq!(&e.pwm.0[..8], &[1000; 8]);
        let cmd = [0.0, 0.25, 0.5, 0.75, 1.0, f32::NAN, -1.0, 2.0];
        MotorOutputs::write(&mut e, 0, &cmd);
        assert_eq!(
            &e.pwm.0[..8],
            &[1000, 1250, 1500, 1750, 2000, 1000, 1000, 2000]
        );
        assert_eq!(e.last_us, [1000, 1250, 1500, 1750, 2000, 1000, 1000, 2000]);
        assert_eq!(&e.pwm.0[8..], &[0, 0]);
    }

    #[test]
    fn tm4c_timing_at_120mhz() {
        // 400 Hz: /2 → 150000 counts and /4 → 75000 exceed 16 bits; /8 → 15 MHz, 37500 counts.
        let t = PwmTiming::new(120_000_000, 400).unwrap();
        assert_eq!(
            t,
            PwmTiming {
                div_code: 2,
                pwm_clk_hz: 15_000_000,
                load: 37_499
            }
        );
        assert_eq!(t.pulse_counts(1000), 15_000);
        assert_eq!(t.pulse_counts(2000), 30_000);
        assert_eq!(t.compare(1500), 37_499 - 22_500);
        assert_eq!(t.pulse_counts(u16::MAX), 37_498); // clamped below LOAD
                                                      // 50 Hz (servo-style ESCs): /64 → 1.875 MHz, 37500 counts.
        let t = PwmTiming::new(120_000_000, 50).unwrap();
        assert_eq!((t.div_code, t.load), (5, 37_499));
        // Impossible rates.
        assert_eq!(PwmTiming::new(120_000_000, 0), None);
        assert_eq!(PwmTiming::new(120_000_000, 10), None);
        assert_eq!(PwmTiming::new(0, 400), None);
    }
}
