//! A scripted fake MCU on a pseudo-terminal, for tests without the simulator.
//!
//! It speaks the real link protocol (`fcc_msgs`): sends `Hello` at start and on `HelloRequest`,
//! answers `TimeSyncPing`, streams telemetry with fixed, known values ([`Script`]) at roughly
//! the default rates, and logs every `VelocitySetpoint` and `Command` it receives as one JSON
//! line (`{"t_us":…,"msg":"VelocitySetpoint","vel_ned_mps":[…],…}`).

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

/// Run the fake MCU on `pty` until the duration ends. Returns the number of frames sent.
pub fn run(mut pty: Pty, o: &FakeOptions) -> std::io::Result<u64> {
    let s = o.script;
    let start = Instant::now();
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
    let mut rx = [0u8; 1024];
    let mut laser_toggle = false;
    loop {
        if let Some(d) = o.duration {
            if start.elapsed() >= d {
                break;
            }
        }
        // Receive.
        loop {
            match pty.master.read(&mut rx) {
                Ok(0) => break,
                Ok(n) => {
                    let frames: Vec<_> = dec.push_slice(&rx[..n]).filter_map(Result::ok).collect();
                    for f in frames {
                        let t = now_us();
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
                                        "{{\"t_us\":{t},\"msg\":\"VelocitySetpoint\",\"vel_ned_mps\":[{},{},{}],\"has_yaw\":{},\"yaw_rad\":{},\"ttl_ms\":{}}}",
                                        sp.vel_ned_mps[0], sp.vel_ned_mps[1], sp.vel_ned_mps[2], sp.has_yaw, sp.yaw_rad, sp.ttl_ms
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
                                    link::CommandKind::Disarm => {
                                        armed = false;
                                        mode = link::FlightMode::Disarmed;
                                    }
                                    link::CommandKind::Hold => mode = link::FlightMode::Hold,
                                    link::CommandKind::Land => mode = link::FlightMode::Land,
                                    link::CommandKind::Velocity => {
                                        mode = link::FlightMode::Velocity
                                    }
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
                                        "{{\"t_us\":{t},\"msg\":\"Command\",\"command\":\"{:?}\"}}",
                                        c.command
                                    )?;
                                    l.flush()?;
                                }
                            }
                            _ => {}
                        }
                    }
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            }
        }
        // Telemetry on a 5 ms tick (200 Hz).
        let t = now_us();
        let every = |hz: u64| tick % (200 / hz) == 0;
        let m = |v| v;
        push(
            &link::Message::ImuRaw(link::ImuRaw {
                gyro_frd_radps: s.gyro_frd_radps,
                accel_frd_mps2: s.accel_frd_mps2,
            }),
            t,
            &mut enc,
            &mut out,
        );
        if every(50) {
            let nav = link::NavState {
                q_body_to_ned: quat_from_euler(s.roll_rad, s.pitch_rad, s.yaw_rad),
                rate_frd_radps: s.gyro_frd_radps,
                pos_ned_m: s.pos_ned_m,
                vel_ned_mps: s.vel_ned_mps,
                accel_ned_mps2: [0.0; 3],
                home_lat_deg: s.lat_deg,
                home_lon_deg: s.lon_deg,
                home_alt_m: s.gps_alt_m,
                gps_ok: true,
                home_set: true,
                calibrated: true,
            };
            push(&link::Message::NavState(m(nav)), t, &mut enc, &mut out);
        }
        if every(20) {
            push(
                &link::Message::MagRaw(link::MagRaw {
                    mag_frd_ut: s.mag_frd_ut,
                }),
                t,
                &mut enc,
                &mut out,
            );
            push(
                &link::Message::BaroRaw(link::BaroRaw {
                    pressure_pa: s.pressure_pa,
                    temperature_c: 21.0,
                }),
                t,
                &mut enc,
                &mut out,
            );
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
        if every(10) {
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
            push(
                &link::Message::Status(link::Status {
                    mode,
                    armed,
                    landed: !armed,
                    loop_time_max_us: 180,
                    loop_time_avg_us: 95,
                    link_rx: *dec.counters(),
                    tx_frames: sent as u32,
                    ..Default::default()
                }),
                t,
                &mut enc,
                &mut out,
            );
        }
        if every(5) {
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
        if o.garbage && tick % 200 == 100 {
            out.extend_from_slice(&[0x13, 0x37, 0xff, 0x42, 0x00]);
        }
        sent += out.iter().filter(|b| **b == 0).count() as u64;
        write_all_retry(&mut pty.master, &out)?;
        out.clear();
        tick += 1;
        let next = start + Duration::from_micros(tick * 5_000);
        if let Some(d) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
    }
    Ok(sent)
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
