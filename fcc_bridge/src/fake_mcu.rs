//! A scripted fake MCU on a pseudo-terminal, for tests without the simulator.
//!
//! It speaks the real link protocol (`fcc_msgs`): sends `Hello` at start and on `HelloRequest`,
//! answers `TimeSyncPing`, streams telemetry with fixed, known values ([`Script`]) at roughly
//! the default rates, and logs every `VelocitySetpoint` and `Command` it receives as one JSON
//! line (`{"t_us":…,"mono_us":…,"msg":"VelocitySetpoint","vel_ned_mps":[…],…}`; `t_us` from
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

fn quat_from_euler(roll: f32, pitch: f32, yaw: f32) -> [f32; 4] {
    let (sr, cr) = (0.5 * roll).sin_cos();
    let (sp, cp) = (0.5 * pitch).sin_cos();
    let (sy, cy) = (0.5 * yaw).sin_cos();
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

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
    let rates = o.rates;
    let tick_hz = u64::from(rates.imu_raw_hz.max(200));
    let tick_us = (1_000_000 / tick_hz).max(1);
    let mut stats = FakeStats::default();
    let s = o.script;
    let start = Instant::now();
    // CLOCK_MONOTONIC at `start` (Instant is CLOCK_MONOTONIC on Linux), for the log's mono_us.
    let mono_start_us = {
        let mut t = nix::libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: one valid timespec.
        unsafe { nix::libc::clock_gettime(nix::libc::CLOCK_MONOTONIC, &mut t) };
        t.tv_sec as u64 * 1_000_000 + t.tv_nsec as u64 / 1000
    };
    let now_us = || start.elapsed().as_micros() as u64;
    let mut enc = link::Encoder::new();
    let mut dec = link::FrameDecoder::new();
    let mut log = match &o.log {
        Some(p) => Some(File::create(p)?),
        None => None,
    };
    let hello = link::Message::Hello(link::Hello {
        protocol_version: o.protocol_version,
        schema_hash: o.schema_hash,
        firmware_version: [0, 1, 0],
    });
    let mut sent = 0u64;
    let mut out: Vec<u8> = Vec::new();
    let push = |m: &link::Message, t_us: u64, enc: &mut link::Encoder, out: &mut Vec<u8>| {
        let mut b = [0u8; link::MAX_FRAME_LEN];
        let n = enc.encode(m, t_us, &mut b).expect("encode");
        out.extend_from_slice(&b[..n]);
    };
    push(&hello, now_us(), &mut enc, &mut out);
    let mut tick: u64 = 0;
    let mut armed = false;
    let mut mode = link::FlightMode::Disarmed;
    // A reader thread timestamps input as it arrives (poll + read), like a UART RX interrupt,
    // so a TimeSyncPing's receive time does not include the wait for the next telemetry tick
    // (which would bias the bridge's time sync by up to half a tick).
    let (tx_ch, rx_ch) = std::sync::mpsc::channel::<std::io::Result<(Vec<u8>, u64)>>();
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    /// Stops the reader thread however `run_stats` returns.
    struct StopOnDrop(std::sync::Arc<std::sync::atomic::AtomicBool>);
    impl Drop for StopOnDrop {
        fn drop(&mut self) {
            self.0.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    }
    let _stop_guard = StopOnDrop(stop.clone());
    let reader = {
        let mut f = pty.master.try_clone()?;
        let stop = stop.clone();
        std::thread::spawn(move || {
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
        })
    };
    let mut laser_toggle = false;
    let mut params: Vec<(u16, f32)> = crate::mcu_params::MCU_PARAMS
        .iter()
        .map(|p| (p.id, p.default))
        .collect();
    loop {
        if let Some(d) = o.duration {
            if start.elapsed() >= d {
                break;
            }
        }
        // Receive: everything the reader thread has read since the last tick.
        while let Ok(item) = rx_ch.try_recv() {
            {
                let (bytes, t_rx) = item?;
                let frames: Vec<_> = dec.push_slice(&bytes).filter_map(Result::ok).collect();
                for f in frames {
                    // Receive time: when the reader thread got the bytes (a UART RX
                    // interrupt's timestamp), not when this loop got round to them.
                    let t = t_rx;
                    match f.message {
                        link::Message::HelloRequest(_) => push(&hello, t, &mut enc, &mut out),
                        link::Message::TimeSyncPing(p) => push(
                            &link::Message::TimeSyncPong(link::TimeSyncPong {
                                linux_time_ns: p.linux_time_ns,
                                mcu_rx_time_us: t,
                                mcu_tx_time_us: now_us(),
                            }),
                            t,
                            &mut enc,
                            &mut out,
                        ),
                        link::Message::VelocitySetpoint(sp) => {
                            if let Some(l) = log.as_mut() {
                                writeln!(
                                        l,
                                        "{{\"t_us\":{t},\"mono_us\":{},\"msg\":\"VelocitySetpoint\",\"vel_ned_mps\":[{},{},{}],\"has_yaw\":{},\"yaw_rad\":{},\"ttl_ms\":{}}}",
                                        mono_start_us + t, sp.vel_ned_mps[0], sp.vel_ned_mps[1], sp.vel_ned_mps[2], sp.has_yaw, sp.yaw_rad, sp.ttl_ms
                                    )?;
                                l.flush()?;
                            }
                        }
                        link::Message::Command(c) => {
                            match c.command {
                                link::CommandKind::Arm => {
                                    armed = true;
                                    mode = link::FlightMode::Hold;
                                }
                                link::CommandKind::Disarm | link::CommandKind::Kill => {
                                    armed = false;
                                    mode = link::FlightMode::Disarmed;
                                }
                                link::CommandKind::Hold => mode = link::FlightMode::Hold,
                                link::CommandKind::Land => mode = link::FlightMode::Land,
                                link::CommandKind::Velocity => mode = link::FlightMode::Velocity,
                            }
                            push(
                                &link::Message::CommandAck(link::CommandAck {
                                    command: c.command,
                                    result: link::CommandResult::Accepted,
                                }),
                                t,
                                &mut enc,
                                &mut out,
                            );
                            if let Some(l) = log.as_mut() {
                                writeln!(
                                    l,
                                    "{{\"t_us\":{t},\"mono_us\":{},\"msg\":\"Command\",\"command\":\"{:?}\"}}",
                                    mono_start_us + t,
                                    c.command
                                )?;
                                l.flush()?;
                            }
                        }
                        link::Message::ParamSet(ps) => {
                            let def = crate::mcu_params::by_id(ps.id);
                            let slot = params.iter_mut().find(|(i, _)| *i == ps.id);
                            let (result, value) = match (def, slot) {
                                (Some(d), Some(slot)) => {
                                    let r = if !ps.value.is_finite() {
                                        link::ParamResult::NotFinite
                                    } else if d.check(ps.value as f64).is_err() {
                                        link::ParamResult::OutOfRange
                                    } else {
                                        slot.1 = ps.value;
                                        link::ParamResult::Accepted
                                    };
                                    (r, slot.1)
                                }
                                _ => (link::ParamResult::UnknownId, f32::NAN),
                            };
                            push(
                                &link::Message::ParamAck(link::ParamAck {
                                    id: ps.id,
                                    value,
                                    result,
                                }),
                                t,
                                &mut enc,
                                &mut out,
                            );
                            if let Some(l) = log.as_mut() {
                                writeln!(
                                        l,
                                        "{{\"t_us\":{t},\"msg\":\"ParamSet\",\"id\":{},\"name\":\"{}\",\"value\":{},\"result\":\"{:?}\",\"now\":{}}}",
                                        ps.id,
                                        def.map_or("?", |d| d.name),
                                        if ps.value.is_finite() { ps.value.to_string() } else { "null".into() },
                                        result,
                                        if value.is_finite() { value.to_string() } else { "null".into() },
                                    )?;
                                l.flush()?;
                            }
                        }
                        _ => {}
                    }
                }
            }
        }
        // Telemetry on a tick of 1/tick_hz (200 Hz unless the IMU goes faster); a stream of
        // rate hz is due on the ticks where floor(tick·hz / tick_hz) steps (tick 0 included),
        // which for hz dividing tick_hz is `tick % (tick_hz / hz) == 0`.
        let t = now_us();
        if t > tick * tick_us + tick_us {
            stats.late_ticks += 1;
        }
        let every = |hz: u16| {
            let hz = u64::from(hz);
            hz > 0 && (tick == 0 || (tick * hz) / tick_hz != ((tick - 1) * hz) / tick_hz)
        };
        let m = |v| v;
        if every(rates.imu_raw_hz) {
            let mut gyro = s.gyro_frd_radps;
            if o.imu_counter {
                gyro[0] = stats.imu_frames as f32;
            }
            push(
                &link::Message::ImuRaw(link::ImuRaw {
                    gyro_frd_radps: gyro,
                    accel_frd_mps2: s.accel_frd_mps2,
                }),
                t,
                &mut enc,
                &mut out,
            );
            stats.imu_frames += 1;
        }
        if every(rates.nav_state_hz) {
            let nav = link::NavState {
                q_body_to_ned: quat_from_euler(s.roll_rad, s.pitch_rad, s.yaw_rad),
                rate_frd_radps: s.gyro_frd_radps,
                pos_ned_m: s.pos_ned_m,
                vel_ned_mps: s.vel_ned_mps,
                accel_ned_mps2: [0.0; 3],
                // A fixed observer estimate (north 0.5, east −0.25 m/s²): peers check the ENU map.
                accel_obs_ne_mps2: [0.5, -0.25],
                home_lat_deg: s.lat_deg,
                home_lon_deg: s.lon_deg,
                home_alt_m: s.gps_alt_m,
                gps_ok: true,
                home_set: true,
                calibrated: true,
            };
            push(&link::Message::NavState(m(nav)), t, &mut enc, &mut out);
        }
        if every(rates.mag_raw_hz) {
            push(
                &link::Message::MagRaw(link::MagRaw {
                    mag_frd_ut: s.mag_frd_ut,
                }),
                t,
                &mut enc,
                &mut out,
            );
        }
        if every(rates.baro_raw_hz) {
            push(
                &link::Message::BaroRaw(link::BaroRaw {
                    pressure_pa: s.pressure_pa,
                    temperature_c: 21.0,
                }),
                t,
                &mut enc,
                &mut out,
            );
        }
        if every(rates.altitude_hz) {
            push(
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
                &mut enc,
                &mut out,
            );
        }
        if every(rates.gps_raw_hz) {
            push(
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
                &mut enc,
                &mut out,
            );
        }
        if every(rates.laser_raw_hz) {
            laser_toggle = !laser_toggle;
            let laser = if laser_toggle { s.laser_m } else { 99_999.0 };
            push(
                &link::Message::RangeRaw(link::RangeRaw {
                    sensor: link::RangeSensor::Laser,
                    range_m: laser,
                }),
                t,
                &mut enc,
                &mut out,
            );
            push(
                &link::Message::RangeRaw(link::RangeRaw {
                    sensor: link::RangeSensor::Sonar,
                    range_m: s.sonar_m,
                }),
                t,
                &mut enc,
                &mut out,
            );
        }
        if every(rates.status_hz) {
            push(
                &link::Message::Status(link::Status {
                    mode,
                    armed,
                    landed: !armed,
                    loop_time_max_us: 180,
                    loop_time_avg_us: 95,
                    link_rx: *dec.counters(),
                    tx_frames: sent as u32,
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
                }),
                t,
                &mut enc,
                &mut out,
            );
        }
        if every(rates.battery_hz) {
            push(
                &link::Message::Battery(link::Battery {
                    voltage_v: s.voltage_v,
                    current_a: s.current_a,
                }),
                t,
                &mut enc,
                &mut out,
            );
        }
        if o.garbage && tick % tick_hz == tick_hz / 2 {
            out.extend_from_slice(&[0x13, 0x37, 0xff, 0x42, 0x00]);
        }
        sent += out.iter().filter(|b| **b == 0).count() as u64;
        write_all_retry(&mut pty.master, &out)?;
        out.clear();
        tick += 1;
        let next = start + Duration::from_micros(tick * tick_us);
        if let Some(d) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
    }
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = reader.join();
    stats.frames = sent;
    Ok(stats)
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
