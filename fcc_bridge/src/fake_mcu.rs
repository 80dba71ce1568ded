//! A scripted fake MCU on a pseudo-terminal, for tests without the simulator.
//!
//! It speaks the real link protocol (`fcc_msgs`): sends `Hello` at start and on `HelloRequest`,
//! answers `TimeSyncPing`, streams telemetry with fixed, known values ([`Script`]) at roughly
//! the default rates, and logs every `VelocitySetpoint` and `Command` it receives as one JSON
//! line (`{"t_us":…,"mono_us":…,"msg":"VelocitySetpoint","vel_ned_mps":[…],"yaw":…,"ttl_ms":…}`,
//! `yaw` being `"Keep"`, `{"Heading":{"yaw_ned_rad":…}}` or `{"Rate":{"yaw_rate_ned_radps":…}}`
//! as serde writes the link's `YawSetpoint`; `t_us` from
//! the fake's start, `mono_us` the same instant on CLOCK_MONOTONIC, comparable with another
//! process's monotonic clock, e.g. Python's `time.monotonic_ns()`).

use fcc_msgs as link;
use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsRawFd, OwnedFd};
use std::time::{Duration, Instant};

/// The fixed state the fake MCU reports (NED/FRD, like the firmware).
#[derive(Clone, Copy, Debug)]
pub struct Script {
    pub roll_rad: f32,
    pub pitch_rad: f32,
    pub yaw_rad: f32,
    pub pos_ned_m: [f32; 3],
    pub vel_ned_mps: [f32; 3],
    pub gyro_frd_radps: [f32; 3],
    pub accel_frd_mps2: [f32; 3],
    pub mag_frd_ut: [f32; 3],
    pub pressure_pa: f32,
    pub lat_deg: f64,
    pub lon_deg: f64,
    pub gps_alt_m: f32,
    /// The laser alternates between this and the no-return sentinel 99 999.
    pub laser_m: f32,
    pub sonar_m: f32,
    pub voltage_v: f32,
    pub current_a: f32,
}

impl Default for Script {
    fn default() -> Self {
        Script {
            roll_rad: 0.0,
            // Nose down 10°, heading 30° (east of north).
            pitch_rad: -10f32.to_radians(),
            yaw_rad: 30f32.to_radians(),
            pos_ned_m: [10.0, 5.0, -3.0],
            // North 2 m/s, climbing 0.5 m/s.
            vel_ned_mps: [2.0, 0.0, -0.5],
            gyro_frd_radps: [0.1, 0.2, 0.3],
            accel_frd_mps2: [0.5, -0.2, -9.81],
            mag_frd_ut: [20.0, 5.0, 40.0],
            pressure_pa: 101_000.0,
            lat_deg: 47.397742,
            lon_deg: 8.545594,
            gps_alt_m: 488.0,
            laser_m: 3.2,
            sonar_m: 2.5,
            voltage_v: 15.8,
            current_a: 12.0,
        }
    }
}

/// Options of a fake MCU run.
#[derive(Clone, Debug)]
pub struct FakeOptions {
    pub script: Script,
    /// Announced schema hash (a wrong one tests the bridge's mismatch error).
    pub schema_hash: u32,
    pub protocol_version: u8,
    /// Stop after this long (None = forever).
    pub duration: Option<Duration>,
    /// JSON-lines log of received setpoints/commands.
    pub log: Option<String>,
    /// Also write garbage bytes every second (resync test).
    pub garbage: bool,
    /// Telemetry rates (Hz). The IMU stream sets the loop's tick (at least 200 Hz); the other
    /// streams go out on the ticks where their own schedule falls due. Laser and sonar share
    /// `laser_raw_hz`. Default: [`FakeOptions::SCRIPT_RATES`].
    pub rates: link::StreamRates,
    /// Put the IMU frame counter (0, 1, 2, …) in gyro x instead of the script's value, so a
    /// peer can count lost messages (exact in f32 up to 2²⁴ frames).
    pub imu_counter: bool,
}

impl FakeOptions {
    /// The fake's historical rates (what tests/dds/peer.py expects): IMU 200, nav 50,
    /// mag/baro/altitude 20, GPS/ranges/status 10, battery 5 Hz.
    pub const SCRIPT_RATES: link::StreamRates = link::StreamRates {
        imu_raw_hz: 200,
        mag_raw_hz: 20,
        baro_raw_hz: 20,
        gps_raw_hz: 10,
        laser_raw_hz: 10,
        sonar_raw_hz: 10,
        battery_hz: 5,
        nav_state_hz: 50,
        altitude_hz: 20,
        status_hz: 10,
    };
}

impl Default for FakeOptions {
    fn default() -> Self {
        FakeOptions {
            script: Script::default(),
            schema_hash: link::SCHEMA_HASH,
            protocol_version: link::PROTOCOL_VERSION,
            duration: None,
            log: None,
            garbage: false,
            rates: FakeOptions::SCRIPT_RATES,
            imu_counter: false,
        }
    }
}

/// An open pty pair: the master (the fake MCU's end) and the slave's path (the bridge's).
pub struct Pty {
    pub master: File,
    /// Kept open so the master never sees EIO while the bridge reopens the slave.
    pub _slave: OwnedFd,
    pub path: String,
}

/// Open a pty pair with the slave in raw mode (no echo, no line discipline).
pub fn open_pty() -> std::io::Result<Pty> {
    use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
    let r = nix::pty::openpty(None, None).map_err(std::io::Error::from)?;
    let mut t = tcgetattr(&r.slave).map_err(std::io::Error::from)?;
    cfmakeraw(&mut t);
    tcsetattr(&r.slave, SetArg::TCSANOW, &t).map_err(std::io::Error::from)?;
    let path = nix::unistd::ttyname(&r.slave)
        .map_err(std::io::Error::from)?
        .to_string_lossy()
        .into_owned();
    let fl = nix::fcntl::fcntl(r.master.as_raw_fd(), nix::fcntl::FcntlArg::F_GETFL)
        .map_err(std::io::Error::from)?;
    let fl = nix::fcntl::OFlag::from_bits_truncate(fl) | nix::fcntl::OFlag::O_NONBLOCK;
    nix::fcntl::fcntl(r.master.as_raw_fd(), nix::fcntl::FcntlArg::F_SETFL(fl))
        .map_err(std::io::Error::from)?;
    Ok(Pty {
        master: File::from(r.master),
        _slave: r.slave,
        path,
    })
}

/// `--imu-counter`: the IMU frame counter travels in gyro x as this many distinct counts.
pub const IMU_COUNTER_MOD: u64 = 32_767;

/// Frames sent by [`run_stats`].
#[derive(Clone, Copy, Debug, Default)]
pub struct FakeStats {
    /// All frames (counted by their 0 delimiters).
    pub frames: u64,
    /// `ImuRaw` frames.
    pub imu_frames: u64,
    /// Loop ticks that started more than one tick period late (the writer fell behind).
    pub late_ticks: u64,
}

/// Run the fake MCU on `pty` until the duration ends. Returns the number of frames sent.
pub fn run(pty: Pty, o: &FakeOptions) -> std::io::Result<u64> {
    run_stats(pty, o).map(|s| s.frames)
}

/// Like [`run`], with the counts of IMU frames and late ticks.
pub fn run_stats(mut pty: Pty, o: &FakeOptions) -> std::io::Result<FakeStats> {
    let tick_hz = u64::from(o.rates.imu_raw_hz.max(200));
    let tick_us = (1_000_000 / tick_hz).max(1);
    let mut stats = FakeStats::default();
    let start = Instant::now();
    let mut mcu = FakeMcu::new(o, start)?;
    mcu.push(&mcu.hello.clone(), mcu.now_us());
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    /// Stops the reader thread however `run_stats` returns.
    struct StopOnDrop(std::sync::Arc<std::sync::atomic::AtomicBool>);
    impl Drop for StopOnDrop {
        fn drop(&mut self) {
            self.0.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    }
    let _stop_guard = StopOnDrop(stop.clone());
    let (reader, rx_ch) = spawn_reader(&pty.master, start, stop.clone())?;
    let mut tick: u64 = 0;
    loop {
        if let Some(d) = o.duration {
            if start.elapsed() >= d {
                break;
            }
        }
        // Receive: everything the reader thread has read since the last tick.
        while let Ok(item) = rx_ch.try_recv() {
            let (bytes, t_rx) = item?;
            let frames: Vec<_> = mcu.dec.push_slice(&bytes).filter_map(Result::ok).collect();
            for f in frames {
                // Receive time: when the reader thread got the bytes (a UART RX interrupt's
                // timestamp), not when this loop got round to them.
                mcu.on_message(f.message, t_rx)?;
            }
        }
        // Telemetry on a tick of 1/tick_hz (200 Hz unless the IMU goes faster).
        let t = mcu.now_us();
        if t > tick * tick_us + tick_us {
            stats.late_ticks += 1;
        }
        mcu.telemetry(tick, tick_hz, t, &mut stats);
        if o.garbage && tick % tick_hz == tick_hz / 2 {
            mcu.out.extend_from_slice(&[0x13, 0x37, 0xff, 0x42, 0x00]);
        }
        mcu.sent += mcu.out.iter().filter(|b| **b == 0).count() as u64;
        write_all_retry(&mut pty.master, &mcu.out)?;
        mcu.out.clear();
        tick += 1;
        let next = start + Duration::from_micros(tick * tick_us);
        if let Some(d) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
    }
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = reader.join();
    stats.frames = mcu.sent;
    Ok(stats)
}

/// What the reader thread hands over: bytes and the fake's µs when they were read.
type RxItem = std::io::Result<(Vec<u8>, u64)>;

/// A reader thread that timestamps input as it arrives (poll + read), like a UART RX interrupt,
/// so a TimeSyncPing's receive time does not include the wait for the next telemetry tick
/// (which would bias the bridge's time sync by up to half a tick). It ends when `stop` is set.
fn spawn_reader(
    master: &File,
    start: Instant,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> std::io::Result<(
    std::thread::JoinHandle<()>,
    std::sync::mpsc::Receiver<RxItem>,
)> {
    let (tx_ch, rx_ch) = std::sync::mpsc::channel::<RxItem>();
    let mut f = master.try_clone()?;
    let reader = std::thread::spawn(move || {
        let mut buf = [0u8; 1024];
        while !stop.load(std::sync::atomic::Ordering::Relaxed) {
            let mut pfd = nix::libc::pollfd {
                fd: f.as_raw_fd(),
                events: nix::libc::POLLIN,
                revents: 0,
            };
            // SAFETY: one valid pollfd, 50 ms timeout.
            let r = unsafe { nix::libc::poll(&mut pfd, 1, 50) };
            if r <= 0 {
                continue;
            }
            loop {
                match f.read(&mut buf) {
                    Ok(0) => break,
                    Ok(n) => {
                        let t = start.elapsed().as_micros() as u64;
                        if tx_ch.send(Ok((buf[..n].to_vec(), t))).is_err() {
                            return;
                        }
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Err(e) => {
                        let _ = tx_ch.send(Err(e));
                        return;
                    }
                }
            }
        }
    });
    Ok((reader, rx_ch))
}

/// CLOCK_MONOTONIC now in µs (Instant is CLOCK_MONOTONIC on Linux), for the log's mono_us.
fn monotonic_us() -> u64 {
    let mut t = nix::libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: one valid timespec.
    unsafe { nix::libc::clock_gettime(nix::libc::CLOCK_MONOTONIC, &mut t) };
    t.tv_sec as u64 * 1_000_000 + t.tv_nsec as u64 / 1000
}

/// The fake MCU's state between ticks: its link codec, what it has queued to send, its log,
/// its mode and parameters.
struct FakeMcu<'a> {
    o: &'a FakeOptions,
    /// Telemetry rates now: `o.rates`, then as the `rates.*` parameters set them.
    rates: link::StreamRates,
    start: Instant,
    /// CLOCK_MONOTONIC at `start`.
    mono_start_us: u64,
    enc: link::Encoder,
    dec: link::FrameDecoder,
    /// Bytes to write at the end of this tick.
    out: Vec<u8>,
    /// Frames written so far.
    sent: u64,
    log: Option<File>,
    hello: link::Message,
    armed: bool,
    mode: link::FlightMode,
    params: Vec<(u16, f32)>,
    laser_toggle: bool,
}

impl<'a> FakeMcu<'a> {
    fn new(o: &'a FakeOptions, start: Instant) -> std::io::Result<Self> {
        Ok(FakeMcu {
            o,
            start,
            mono_start_us: monotonic_us(),
            enc: link::Encoder::new(),
            dec: link::FrameDecoder::new(),
            out: Vec::new(),
            sent: 0,
            log: match &o.log {
                Some(p) => Some(File::create(p)?),
                None => None,
            },
            hello: link::Message::Hello(link::Hello {
                protocol_version: o.protocol_version,
                schema_hash: o.schema_hash,
                firmware_version: [0, 1, 0],
            }),
            armed: false,
            mode: link::FlightMode::Disarmed,
            // The `rates.*` parameters report the rates it actually sends.
            params: crate::mcu_params::MCU_PARAMS
                .iter()
                .map(|p| match link::Stream::by_param_id(p.id) {
                    Some(st) => (p.id, f32::from(o.rates.hz(st))),
                    None => (p.id, p.default),
                })
                .collect(),
            laser_toggle: false,
            rates: o.rates,
        })
    }

    fn now_us(&self) -> u64 {
        self.start.elapsed().as_micros() as u64
    }

    /// Queue one frame.
    fn push(&mut self, m: &link::Message, t_us: u64) {
        let mut b = [0u8; link::MAX_FRAME_LEN];
        let n = self.enc.encode(m, t_us, &mut b).expect("encode");
        self.out.extend_from_slice(&b[..n]);
    }

    /// One JSON line into the log, if there is one.
    fn log_line(&mut self, line: std::fmt::Arguments) -> std::io::Result<()> {
        if let Some(l) = self.log.as_mut() {
            writeln!(l, "{line}")?;
            l.flush()?;
        }
        Ok(())
    }

    /// A message from the bridge, received at `t` µs.
    fn on_message(&mut self, m: link::Message, t: u64) -> std::io::Result<()> {
        match m {
            link::Message::HelloRequest(_) => self.push(&self.hello.clone(), t),
            link::Message::TimeSyncPing(p) => {
                let pong = link::Message::TimeSyncPong(link::TimeSyncPong {
                    linux_time_ns: p.linux_time_ns,
                    mcu_rx_time_us: t,
                    mcu_tx_time_us: self.now_us(),
                });
                self.push(&pong, t)
            }
            link::Message::VelocitySetpoint(sp) => {
                let mono = self.mono_start_us + t;
                self.log_line(format_args!(
                    "{{\"t_us\":{t},\"mono_us\":{},\"msg\":\"VelocitySetpoint\",\"vel_ned_mps\":[{},{},{}],\"yaw\":{},\"ttl_ms\":{}}}",
                    mono, sp.vel_ned_mps[0], sp.vel_ned_mps[1], sp.vel_ned_mps[2], YawJson(sp.yaw), sp.ttl_ms
                ))?;
            }
            link::Message::Command(c) => self.on_command(c, t)?,
            link::Message::ParamSet(ps) => self.on_param_set(ps, t)?,
            _ => {}
        }
        Ok(())
    }

    /// A command: the mode follows it, the ack accepts it, the log records it.
    fn on_command(&mut self, c: link::Command, t: u64) -> std::io::Result<()> {
        match c.command {
            link::CommandKind::Arm => {
                self.armed = true;
                self.mode = link::FlightMode::Hold;
            }
            link::CommandKind::Disarm | link::CommandKind::Kill => {
                self.armed = false;
                self.mode = link::FlightMode::Disarmed;
            }
            link::CommandKind::Hold => self.mode = link::FlightMode::Hold,
            link::CommandKind::Land => self.mode = link::FlightMode::Land,
            link::CommandKind::Velocity => self.mode = link::FlightMode::Velocity,
        }
        self.push(
            &link::Message::CommandAck(link::CommandAck {
                command: c.command,
                result: link::CommandResult::Accepted,
            }),
            t,
        );
        let mono = self.mono_start_us + t;
        self.log_line(format_args!(
            "{{\"t_us\":{t},\"mono_us\":{},\"msg\":\"Command\",\"command\":\"{:?}\"}}",
            mono, c.command
        ))
    }

    /// A parameter set: checked against the bridge's table of MCU parameters, acked with the
    /// value now in use, logged.
    fn on_param_set(&mut self, ps: link::ParamSet, t: u64) -> std::io::Result<()> {
        let def = crate::mcu_params::by_id(ps.id);
        let slot = self.params.iter_mut().find(|(i, _)| *i == ps.id);
        let (result, value) = match (def, slot) {
            (Some(d), Some(slot)) => {
                let r = if !ps.value.is_finite() {
                    link::ParamResult::NotFinite
                } else if d.check(ps.value as f64).is_err() {
                    link::ParamResult::OutOfRange
                } else {
                    slot.1 = ps.value;
                    if let Some(st) = link::Stream::by_param_id(ps.id) {
                        // Its loop ticks at the start-up IMU rate: no stream goes faster.
                        self.rates.set_hz(st, ps.value as u16);
                    }
                    link::ParamResult::Accepted
                };
                (r, slot.1)
            }
            _ => (link::ParamResult::UnknownId, f32::NAN),
        };
        self.push(
            &link::Message::ParamAck(link::ParamAck {
                id: ps.id,
                value,
                result,
            }),
            t,
        );
        self.log_line(format_args!(
            "{{\"t_us\":{t},\"msg\":\"ParamSet\",\"id\":{},\"name\":\"{}\",\"value\":{},\"result\":\"{:?}\",\"now\":{}}}",
            ps.id,
            def.map_or("?", |d| d.name),
            if ps.value.is_finite() { ps.value.to_string() } else { "null".into() },
            result,
            if value.is_finite() { value.to_string() } else { "null".into() },
        ))
    }

    /// The telemetry due on tick `tick` of `tick_hz`, stamped `t`: a stream of rate hz is due
    /// on the ticks where floor(tick·hz / tick_hz) steps (tick 0 included), which for hz
    /// dividing tick_hz is `tick % (tick_hz / hz) == 0`.
    fn telemetry(&mut self, tick: u64, tick_hz: u64, t: u64, stats: &mut FakeStats) {
        let every = |hz: u16| {
            let hz = u64::from(hz);
            hz > 0 && (tick == 0 || (tick * hz) / tick_hz != ((tick - 1) * hz) / tick_hz)
        };
        let (rates, s) = (self.rates, self.o.script);
        if every(rates.imu_raw_hz) {
            let mut gyro = s.gyro_frd_radps;
            if self.o.imu_counter {
                // The counter in gyro counts (the link carries gyro x as an i16 count of
                // `fixed::gyro::LSB`), modulo 32767: the peer unwraps it.
                gyro[0] = (stats.imu_frames % IMU_COUNTER_MOD) as f32 * link::fixed::gyro::LSB;
            }
            self.push(
                &link::Message::ImuRaw(link::ImuRaw {
                    gyro_frd_radps: gyro,
                    accel_frd_mps2: s.accel_frd_mps2,
                }),
                t,
            );
            stats.imu_frames += 1;
        }
        if every(rates.nav_state_hz) {
            self.push(&link::Message::NavState(script_nav_state(&s)), t);
        }
        if every(rates.mag_raw_hz) {
            self.push(
                &link::Message::MagRaw(link::MagRaw {
                    mag_frd_ut: s.mag_frd_ut,
                }),
                t,
            );
        }
        if every(rates.baro_raw_hz) {
            self.push(
                &link::Message::BaroRaw(link::BaroRaw {
                    pressure_pa: s.pressure_pa,
                    temperature_c: 21.0,
                }),
                t,
            );
        }
        if every(rates.altitude_hz) {
            self.push(
                &link::Message::AltitudeFusion(link::AltitudeFusion {
                    baro_alt_m: -s.pos_ned_m[2] + 0.1,
                    alt_m: -s.pos_ned_m[2],
                    vel_down_mps: s.vel_ned_mps[2],
                    ground_height_m: s.laser_m,
                    ground_var_m2: 0.0025,
                    laser_m: s.laser_m,
                    sonar_m: s.sonar_m,
                    source: link::AltitudeSource::Laser,
                }),
                t,
            );
        }
        if every(rates.gps_raw_hz) {
            self.push(
                &link::Message::GpsRaw(link::GpsRaw {
                    lat_deg: s.lat_deg,
                    lon_deg: s.lon_deg,
                    alt_m: s.gps_alt_m,
                    vel_ned_mps: s.vel_ned_mps,
                    h_acc_m: 1.0,
                    num_sats: 12,
                    fix_ok: true,
                }),
                t,
            );
        }
        if every(rates.laser_raw_hz) {
            self.ranges(t);
        }
        if every(rates.status_hz) {
            let status = self.status();
            self.push(&status, t);
        }
        if every(rates.battery_hz) {
            self.push(
                &link::Message::Battery(link::Battery {
                    voltage_v: s.voltage_v,
                    current_a: s.current_a,
                }),
                t,
            );
        }
    }

    /// Laser (every other reading out of range) and sonar readings.
    fn ranges(&mut self, t: u64) {
        let s = self.o.script;
        self.laser_toggle = !self.laser_toggle;
        let laser = if self.laser_toggle {
            s.laser_m
        } else {
            99_999.0
        };
        self.push(
            &link::Message::RangeRaw(link::RangeRaw {
                sensor: link::RangeSensor::Laser,
                range_m: laser,
            }),
            t,
        );
        self.push(
            &link::Message::RangeRaw(link::RangeRaw {
                sensor: link::RangeSensor::Sonar,
                range_m: s.sonar_m,
            }),
            t,
        );
    }

    /// The status frame: mode, arming, link counters, a healthy vehicle.
    fn status(&self) -> link::Message {
        link::Message::Status(link::Status {
            mode: self.mode,
            armed: self.armed,
            landed: !self.armed,
            loop_time_max_us: 180,
            loop_time_avg_us: 95,
            link_rx: *self.dec.counters(),
            tx_frames: self.sent as u32,
            // A healthy vehicle: fix, undisturbed compass, both rangefinders reading.
            sensors: link::SensorHealth {
                gps_ok: true,
                mag_disturbed: false,
                mag_rejects: 0,
                laser_ok: true,
                sonar_ok: true,
                mag_disturbed_ds: 0,
                nav_faults: 0,
            },
            ..Default::default()
        })
    }
}

/// The script's navigation state.
fn script_nav_state(s: &Script) -> link::NavState {
    link::NavState {
        q_body_to_ned: fcc_nav::attitude::quat_from_euler(s.roll_rad, s.pitch_rad, s.yaw_rad),
        rate_frd_radps: s.gyro_frd_radps,
        pos_ned_m: s.pos_ned_m,
        vel_ned_mps: s.vel_ned_mps,
        accel_ned_mps2: [0.0; 3],
        // A fixed observer estimate (north 0.5, east −0.25 m/s²): peers check the ENU map.
        accel_obs_ne_mps2: [0.5, -0.25],
        home: Some(link::HomePosition {
            lat_deg: s.lat_deg,
            lon_deg: s.lon_deg,
            alt_m: s.gps_alt_m,
        }),
        gps_ok: true,
        home_set: true,
        calibrated: true,
    }
}

/// Write to the non-blocking master, waiting while the pty buffer is full.
fn write_all_retry(f: &mut File, mut buf: &[u8]) -> std::io::Result<()> {
    let deadline = Instant::now() + Duration::from_millis(200);
    while !buf.is_empty() {
        match f.write(buf) {
            Ok(n) => buf = &buf[n..],
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                if Instant::now() > deadline {
                    // Nobody reads: drop the rest, as a UART would.
                    return Ok(());
                }
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// A setpoint's yaw case as JSON (serde's externally tagged form of `YawSetpoint`).
struct YawJson(link::YawSetpoint);

impl std::fmt::Display for YawJson {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            link::YawSetpoint::Keep => write!(f, "\"Keep\""),
            link::YawSetpoint::Heading { yaw_ned_rad } => {
                write!(f, "{{\"Heading\":{{\"yaw_ned_rad\":{yaw_ned_rad}}}}}")
            }
            link::YawSetpoint::Rate { yaw_rate_ned_radps } => {
                write!(
                    f,
                    "{{\"Rate\":{{\"yaw_rate_ned_radps\":{yaw_rate_ned_radps}}}}}"
                )
            }
        }
    }
}
