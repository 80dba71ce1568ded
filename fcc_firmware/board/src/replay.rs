//! A compact binary recording of what the flight core saw and did, tick by tick, so the same
//! sequence can be replayed on the MCU (or an emulated Cortex-M4F) and the outputs compared
//! with the host build's.
//!
//! Format (little-endian), written by the `record` host tool:
//! - header: `b"FCCR"`, `u32` version (1), `u32` tick count;
//! - per tick: `u64` now_us, `u8` flags (bit 0 imu, 1 mag, 2 baro, 3 gps, 4 laser, 5 sonar,
//!   6 battery, 7 events), then the present samples in that order, then (bit 7) a `u8` event
//!   count and the events (operator commands and velocity setpoints applied before the step).
//!
//! The expected outputs are a second stream: header `b"FCCO"`, `u32` version, `u32` tick count,
//! then per tick 8 × `f32` motor commands.
//!
//! Decoding never panics: every read is bounds-checked and a short or corrupt buffer ends the
//! replay with `None`.

use fcc_firmware::commands::{Command, VelocitySetpoint, YawSetpoint};
use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::scheduler::FlightComputer;
use fcc_firmware::sensors::*;

pub const INPUT_MAGIC: &[u8; 4] = b"FCCR";
pub const OUTPUT_MAGIC: &[u8; 4] = b"FCCO";
pub const VERSION: u32 = 1;

/// Something the Linux computer told the core before a tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    Command(Command),
    Setpoint(VelocitySetpoint),
}

/// At most this many events per tick are carried (more are dropped by the reader).
pub const MAX_EVENTS: usize = 4;

/// The link's transmit room per replayed tick (what the board's tick offers at most).
pub const TX_BYTES: usize = 512;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TickRecord {
    pub now_us: u64,
    pub inputs: SensorInputs,
    pub events: [Option<Event>; MAX_EVENTS],
}

/// Bounds-checked little-endian reader.
pub struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub fn new(buf: &'a [u8]) -> Self {
        Self { buf, pos: 0 }
    }
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let end = self.pos.checked_add(N)?;
        let s = self.buf.get(self.pos..end)?;
        self.pos = end;
        s.try_into().ok()
    }
    fn u8(&mut self) -> Option<u8> {
        Some(self.take::<1>()?[0])
    }
    fn u16(&mut self) -> Option<u16> {
        Some(u16::from_le_bytes(self.take()?))
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take()?))
    }
    fn f32(&mut self) -> Option<f32> {
        Some(f32::from_le_bytes(self.take()?))
    }
    fn f64(&mut self) -> Option<f64> {
        Some(f64::from_le_bytes(self.take()?))
    }
    fn f32x3(&mut self) -> Option<[f32; 3]> {
        Some([self.f32()?, self.f32()?, self.f32()?])
    }
}

/// Iterates the ticks of an input recording.
pub struct InputStream<'a> {
    r: Reader<'a>,
    remaining: u32,
}

impl<'a> InputStream<'a> {
    /// `None` if the header is missing or of another version.
    pub fn new(buf: &'a [u8]) -> Option<Self> {
        let mut r = Reader::new(buf);
        if &r.take::<4>()? != INPUT_MAGIC || r.u32()? != VERSION {
            return None;
        }
        let remaining = r.u32()?;
        Some(Self { r, remaining })
    }
    pub fn len(&self) -> u32 {
        self.remaining
    }
    pub fn is_empty(&self) -> bool {
        self.remaining == 0
    }
    fn read_tick(&mut self) -> Option<TickRecord> {
        let r = &mut self.r;
        let now_us = r.u64()?;
        let flags = r.u8()?;
        let mut inp = SensorInputs::default();
        if flags & 1 != 0 {
            inp.imu = Some(ImuSample {
                t_us: r.u64()?,
                gyro_frd_radps: r.f32x3()?,
                accel_frd_mps2: r.f32x3()?,
            });
        }
        if flags & 2 != 0 {
            inp.mag = Some(MagSample {
                t_us: r.u64()?,
                mag_frd_ut: r.f32x3()?,
            });
        }
        if flags & 4 != 0 {
            inp.baro = Some(BaroSample {
                t_us: r.u64()?,
                pressure_pa: r.f32()?,
                temperature_c: r.f32()?,
            });
        }
        if flags & 8 != 0 {
            inp.gps = Some(GpsFix {
                t_us: r.u64()?,
                lat_deg: r.f64()?,
                lon_deg: r.f64()?,
                alt_m: r.f32()?,
                vel_ned_mps: r.f32x3()?,
                h_acc_m: r.f32()?,
                num_sats: r.u8()?,
                fix_ok: r.u8()? != 0,
            });
        }
        if flags & 16 != 0 {
            inp.laser = Some(RangeSample {
                t_us: r.u64()?,
                range_m: r.f32()?,
            });
        }
        if flags & 32 != 0 {
            inp.sonar = Some(RangeSample {
                t_us: r.u64()?,
                range_m: r.f32()?,
            });
        }
        if flags & 64 != 0 {
            inp.battery = Some(BatterySample {
                t_us: r.u64()?,
                voltage_v: r.f32()?,
                current_a: r.f32()?,
            });
        }
        let mut events = [None; MAX_EVENTS];
        if flags & 128 != 0 {
            let n = r.u8()?;
            for i in 0..n as usize {
                let ev = match r.u8()? {
                    0 => Event::Command(Command::Arm),
                    1 => Event::Command(Command::Disarm),
                    2 => Event::Command(Command::Hold),
                    3 => Event::Command(Command::Land),
                    4 => Event::Command(Command::Velocity),
                    6 => Event::Command(Command::Kill { confirm: r.u32()? }),
                    5 => {
                        let vel_ned_mps = r.f32x3()?;
                        let yaw_case = r.u8()?;
                        let v = r.f32()?;
                        let ttl_ms = r.u16()?;
                        let yaw = match yaw_case {
                            0 => YawSetpoint::Keep,
                            1 => YawSetpoint::Heading { yaw_ned_rad: v },
                            2 => YawSetpoint::Rate {
                                yaw_rate_ned_radps: v,
                            },
                            _ => return None,
                        };
                        Event::Setpoint(VelocitySetpoint {
                            vel_ned_mps,
                            yaw,
                            ttl_ms,
                        })
                    }
                    _ => return None,
                };
                if let Some(slot) = events.get_mut(i) {
                    *slot = Some(ev);
                }
            }
        }
        Some(TickRecord {
            now_us,
            inputs: inp,
            events,
        })
    }
}

impl Iterator for InputStream<'_> {
    type Item = TickRecord;
    fn next(&mut self) -> Option<TickRecord> {
        if self.remaining == 0 {
            return None;
        }
        self.remaining -= 1;
        let t = self.read_tick();
        if t.is_none() {
            self.remaining = 0;
        }
        t
    }
}

/// Iterates the expected motor outputs.
pub struct OutputStream<'a> {
    r: Reader<'a>,
    remaining: u32,
}

impl<'a> OutputStream<'a> {
    pub fn new(buf: &'a [u8]) -> Option<Self> {
        let mut r = Reader::new(buf);
        if &r.take::<4>()? != OUTPUT_MAGIC || r.u32()? != VERSION {
            return None;
        }
        let remaining = r.u32()?;
        Some(Self { r, remaining })
    }
    pub fn len(&self) -> u32 {
        self.remaining
    }
    pub fn is_empty(&self) -> bool {
        self.remaining == 0
    }
}

impl Iterator for OutputStream<'_> {
    type Item = [f32; MOTOR_COUNT];
    fn next(&mut self) -> Option<[f32; MOTOR_COUNT]> {
        if self.remaining == 0 {
            return None;
        }
        self.remaining -= 1;
        let mut m = [0.0; MOTOR_COUNT];
        for v in &mut m {
            *v = self.r.f32()?;
        }
        Some(m)
    }
}

/// Apply a tick's events to the core (results ignored, as the recording kept whatever the core
/// answered: a refused command is refused again).
pub fn apply_events(core: &mut fcc_firmware::flight::FlightCore, rec: &TickRecord) {
    for ev in rec.events.iter().flatten() {
        let _ = match *ev {
            Event::Command(c) => core.command(rec.now_us, c),
            Event::Setpoint(sp) => core.setpoint(rec.now_us, sp),
        };
    }
}

/// A board that hands out the recorded samples: the flight computer's tick runs unchanged on it.
pub struct ReplayBoard {
    pub next: SensorInputs,
}

impl SensorBoard for ReplayBoard {
    fn poll(&mut self, _now_us: u64) -> SensorInputs {
        core::mem::take(&mut self.next)
    }
}

/// Latches the last motor command (what the ESC outputs would get).
pub use fcc_firmware::sensors::MotorLatch;

/// Replays a whole recording on a fresh flight computer (its tick, as the QEMU image runs it:
/// no received bytes, telemetry at the default rates), calling `each(tick_index, motors)` after
/// every tick. Returns the number of ticks.
pub fn replay<F: FnMut(u32, &[f32; MOTOR_COUNT])>(
    params: fcc_firmware::params::Params,
    input: &[u8],
    mut each: F,
) -> Option<u32> {
    let stream = InputStream::new(input)?;
    let mut fc = FlightComputer::new(params);
    let mut board = ReplayBoard {
        next: SensorInputs::default(),
    };
    let mut motors = MotorLatch::default();
    let mut tx = [0u8; TX_BYTES];
    let mut n = 0;
    for rec in stream {
        apply_events(&mut fc.core, &rec);
        board.next = rec.inputs;
        fc.tick(rec.now_us, &[], &mut board, &mut motors, &mut tx);
        each(n, &motors.0);
        n += 1;
    }
    Some(n)
}

/// Encoder (host side).
#[cfg(feature = "std")]
pub mod encode {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    pub struct InputWriter {
        pub buf: Vec<u8>,
        pub ticks: u32,
    }

    impl Default for InputWriter {
        fn default() -> Self {
            Self::new()
        }
    }

    impl InputWriter {
        pub fn new() -> Self {
            let mut buf = Vec::new();
            buf.extend_from_slice(INPUT_MAGIC);
            buf.extend_from_slice(&VERSION.to_le_bytes());
            buf.extend_from_slice(&0u32.to_le_bytes());
            Self { buf, ticks: 0 }
        }
        fn f32s(&mut self, v: &[f32]) {
            for x in v {
                self.buf.extend_from_slice(&x.to_le_bytes());
            }
        }
        pub fn tick(&mut self, now_us: u64, inp: &SensorInputs, events: &[Event]) {
            assert!(events.len() <= MAX_EVENTS, "too many events in one tick");
            let b = &mut self.buf;
            b.extend_from_slice(&now_us.to_le_bytes());
            let flags = inp.imu.is_some() as u8
                | (inp.mag.is_some() as u8) << 1
                | (inp.baro.is_some() as u8) << 2
                | (inp.gps.is_some() as u8) << 3
                | (inp.laser.is_some() as u8) << 4
                | (inp.sonar.is_some() as u8) << 5
                | (inp.battery.is_some() as u8) << 6
                | (!events.is_empty() as u8) << 7;
            b.push(flags);
            if let Some(s) = inp.imu {
                self.buf.extend_from_slice(&s.t_us.to_le_bytes());
                self.f32s(&s.gyro_frd_radps);
                self.f32s(&s.accel_frd_mps2);
            }
            if let Some(s) = inp.mag {
                self.buf.extend_from_slice(&s.t_us.to_le_bytes());
                self.f32s(&s.mag_frd_ut);
            }
            if let Some(s) = inp.baro {
                self.buf.extend_from_slice(&s.t_us.to_le_bytes());
                self.f32s(&[s.pressure_pa, s.temperature_c]);
            }
            if let Some(s) = inp.gps {
                self.buf.extend_from_slice(&s.t_us.to_le_bytes());
                self.buf.extend_from_slice(&s.lat_deg.to_le_bytes());
                self.buf.extend_from_slice(&s.lon_deg.to_le_bytes());
                self.f32s(&[s.alt_m]);
                self.f32s(&s.vel_ned_mps);
                self.f32s(&[s.h_acc_m]);
                self.buf.push(s.num_sats);
                self.buf.push(s.fix_ok as u8);
            }
            for s in [inp.laser, inp.sonar].into_iter().flatten() {
                self.buf.extend_from_slice(&s.t_us.to_le_bytes());
                self.f32s(&[s.range_m]);
            }
            if let Some(s) = inp.battery {
                self.buf.extend_from_slice(&s.t_us.to_le_bytes());
                self.f32s(&[s.voltage_v, s.current_a]);
            }
            if !events.is_empty() {
                self.buf.push(events.len() as u8);
                for e in events {
                    match e {
                        Event::Command(Command::Kill { confirm }) => {
                            self.buf.push(6);
                            self.buf.extend_from_slice(&confirm.to_le_bytes());
                        }
                        Event::Command(c) => self.buf.push(match c {
                            Command::Arm => 0,
                            Command::Disarm => 1,
                            Command::Hold => 2,
                            Command::Land => 3,
                            Command::Velocity => 4,
                            Command::Kill { .. } => 6,
                        }),
                        Event::Setpoint(sp) => {
                            self.buf.push(5);
                            self.f32s(&sp.vel_ned_mps);
                            let (yaw_case, v) = match sp.yaw {
                                YawSetpoint::Keep => (0, 0.0),
                                YawSetpoint::Heading { yaw_ned_rad } => (1, yaw_ned_rad),
                                YawSetpoint::Rate { yaw_rate_ned_radps } => {
                                    (2, yaw_rate_ned_radps)
                                }
                            };
                            self.buf.push(yaw_case);
                            self.f32s(&[v]);
                            self.buf.extend_from_slice(&sp.ttl_ms.to_le_bytes());
                        }
                    }
                }
            }
            self.ticks += 1;
        }
        pub fn finish(mut self) -> Vec<u8> {
            self.buf[8..12].copy_from_slice(&self.ticks.to_le_bytes());
            self.buf
        }
    }

    pub fn outputs(rows: &[[f32; MOTOR_COUNT]]) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(OUTPUT_MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&(rows.len() as u32).to_le_bytes());
        for r in rows {
            for x in r {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        b
    }
}
