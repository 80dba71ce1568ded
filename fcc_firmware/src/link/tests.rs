extern crate std;

use super::*;
use crate::commands::Mode;
use crate::params::Params;
use crate::sensors::{
    BaroSample, BatterySample, GpsFix, ImuSample, MagSample, RangeSample, SensorInputs,
};
use fcc_msgs::{
    Command, Frame, HelloRequest, TimeSyncPing, VelocitySetpoint, YawSetpoint, MAX_FRAME_LEN,
    PROTOCOL_VERSION, SCHEMA_HASH,
};
use std::collections::BTreeMap;
use std::vec::Vec;

const TICK_US: u64 = crate::scheduler::TICK_US;

/// The Linux side: encodes with its own sequence numbers.
struct Linux {
    enc: Encoder,
    dec: FrameDecoder,
}

impl Linux {
    fn new() -> Self {
        Self {
            enc: Encoder::new(),
            dec: FrameDecoder::new(),
        }
    }
    fn frame(&mut self, m: Message) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = self.enc.encode(&m, 42, &mut buf).unwrap();
        buf[..n].to_vec()
    }
    fn receive(&mut self, bytes: &[u8]) -> Vec<Frame> {
        self.dec
            .push_slice(bytes)
            .map(|r| r.expect("MCU frames decode"))
            .collect()
    }
}

/// Synthetic sensors at board rates: IMU 500 Hz, mag 100, baro 50, GPS 5, laser 20, sonar 10,
/// battery 10 — vehicle level and still at a fixed GPS position.
fn sensors(tick: u64) -> SensorInputs {
    let t_us = tick * TICK_US;
    let every = |n: u64| tick.is_multiple_of(n);
    SensorInputs {
        imu: Some(ImuSample {
            t_us,
            gyro_frd_radps: [0.0; 3],
            accel_frd_mps2: [0.0, 0.0, -9.80665],
        }),
        mag: every(5).then_some(MagSample {
            t_us,
            mag_frd_ut: [21.0, 0.0, 43.0],
        }),
        baro: every(10).then_some(BaroSample {
            t_us,
            pressure_pa: 101_325.0,
            temperature_c: 20.0,
        }),
        gps: every(100).then_some(GpsFix {
            t_us,
            lat_deg: 47.3977,
            lon_deg: 8.5456,
            alt_m: 488.0,
            vel_ned_mps: [0.0; 3],
            h_acc_m: 1.0,
            num_sats: 12,
            fix_ok: true,
        }),
        laser: every(25).then_some(RangeSample { t_us, range_m: 0.2 }),
        sonar: every(50).then_some(RangeSample {
            t_us,
            range_m: 0.25,
        }),
        battery: every(50).then_some(BatterySample {
            t_us,
            voltage_v: 24.0,
            current_a: 1.0,
        }),
    }
}

fn ack_results(frames: &[Frame]) -> Vec<CommandAck> {
    frames
        .iter()
        .filter_map(|f| match f.message {
            Message::CommandAck(a) => Some(a),
            _ => None,
        })
        .collect()
}

fn tx(link: &mut LinkEndpoint, now_us: u64, core: &FlightCore, s: &SensorInputs) -> Vec<u8> {
    let mut out = [0u8; 1024];
    let n = link.poll_tx(now_us, core, s, &mut out);
    out[..n].to_vec()
}

#[test]
fn setpoint_while_disarmed_reaches_core_and_is_counted_as_rejected() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let mut linux = Linux::new();
    let sp = VelocitySetpoint {
        vel_ned_mps: [1.0, 0.0, 0.0],
        yaw: YawSetpoint::Keep,
        ttl_ms: 500,
    };
    let bytes = linux.frame(Message::VelocitySetpoint(sp));
    // Byte by byte, as a UART interrupt would deliver it.
    for b in &bytes {
        link.on_bytes(1_000, core::slice::from_ref(b), &mut core);
    }
    assert_eq!(link.stats().setpoint_rejects, 1);
    assert_eq!(link.stats().last_reject, CommandResult::Disarmed);
    assert_eq!(link.rx_counters().rx_frames, 1);
    assert_eq!(core.mode(), Mode::Disarmed);
    // Non-finite values are refused before the arming check.
    let bad = VelocitySetpoint {
        vel_ned_mps: [f32::NAN, 0.0, 0.0],
        ..sp
    };
    link.on_bytes(
        2_000,
        &linux.frame(Message::VelocitySetpoint(bad)),
        &mut core,
    );
    assert_eq!(link.stats().setpoint_rejects, 2);
    assert_eq!(link.stats().last_reject, CommandResult::InvalidSetpoint);
    // A time-to-live outside the safe range (issue 14: 65535 ms flew 169 m on one setpoint) is
    // refused as invalid too, before the arming check; the range ends are fine (Disarmed).
    for (ttl_ms, want) in [
        (65535, CommandResult::InvalidSetpoint),
        (
            fcc_msgs::SETPOINT_TTL_MS_MAX + 1,
            CommandResult::InvalidSetpoint,
        ),
        (
            fcc_msgs::SETPOINT_TTL_MS_MIN - 1,
            CommandResult::InvalidSetpoint,
        ),
        (0, CommandResult::InvalidSetpoint),
        (fcc_msgs::SETPOINT_TTL_MS_MIN, CommandResult::Disarmed),
        (fcc_msgs::SETPOINT_TTL_MS_MAX, CommandResult::Disarmed),
    ] {
        let sp2 = VelocitySetpoint { ttl_ms, ..sp };
        link.on_bytes(
            2_000,
            &linux.frame(Message::VelocitySetpoint(sp2)),
            &mut core,
        );
        assert_eq!(link.stats().last_reject, want, "ttl_ms {ttl_ms}");
    }
    assert_eq!(link.stats().setpoint_rejects, 8);
    link.on_bytes(
        2_000,
        &linux.frame(Message::VelocitySetpoint(bad)),
        &mut core,
    );
    // The rejects show up in Status.
    let frames = linux.receive(&tx(&mut link, 3_000, &core, &SensorInputs::default()));
    let status = frames.iter().find_map(|f| match f.message {
        Message::Status(s) => Some(s),
        _ => None,
    });
    let status = status.expect("status is due at start");
    assert_eq!(
        (status.setpoint_rejects, status.last_reject),
        (9, CommandResult::InvalidSetpoint)
    );
    assert_eq!(status.link_rx.rx_frames, 9);
    assert_eq!(status.mode, Mode::Disarmed);
}

/// A heading or yaw rate that is not finite, or a rate over the absurd limit, is refused as an
/// invalid setpoint before the arming check; any finite heading and the limit itself pass it.
#[test]
fn yaw_setpoints_are_validated_before_the_arming_check() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let mut linux = Linux::new();
    let max = fcc_msgs::SETPOINT_YAW_RATE_ABS_MAX_RADPS;
    let heading = |y| YawSetpoint::Heading { yaw_ned_rad: y };
    let rate = |r| YawSetpoint::Rate {
        yaw_rate_ned_radps: r,
    };
    for (yaw, want) in [
        (heading(f32::NAN), CommandResult::InvalidSetpoint),
        (heading(f32::NEG_INFINITY), CommandResult::InvalidSetpoint),
        (rate(f32::NAN), CommandResult::InvalidSetpoint),
        (rate(f32::INFINITY), CommandResult::InvalidSetpoint),
        (rate(max * 1.001), CommandResult::InvalidSetpoint),
        (rate(-max * 1.001), CommandResult::InvalidSetpoint),
        (rate(max), CommandResult::Disarmed),
        (rate(-0.3), CommandResult::Disarmed),
        (heading(100.0), CommandResult::Disarmed),
        (YawSetpoint::Keep, CommandResult::Disarmed),
    ] {
        let sp = VelocitySetpoint {
            vel_ned_mps: [0.0; 3],
            yaw,
            ttl_ms: 300,
        };
        link.on_bytes(
            1_000,
            &linux.frame(Message::VelocitySetpoint(sp)),
            &mut core,
        );
        assert_eq!(link.stats().last_reject, want, "{yaw:?}");
    }
    assert_eq!(link.stats().setpoint_rejects, 10);
}

#[test]
fn arm_before_calibration_is_acked_with_the_reason() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let mut linux = Linux::new();
    let bytes = linux.frame(Message::Command(Command {
        command: CommandKind::Arm,
        confirm: 0,
    }));
    link.on_bytes(0, &bytes, &mut core);
    let hold = linux.frame(Message::Command(Command {
        command: CommandKind::Hold,
        confirm: 0,
    }));
    link.on_bytes(0, &hold, &mut core);
    assert_eq!(link.stats().command_rejects, 2);
    let acks = ack_results(&linux.receive(&tx(&mut link, 0, &core, &SensorInputs::default())));
    assert_eq!(
        acks,
        [
            CommandAck {
                command: CommandKind::Arm,
                result: CommandResult::NotCalibrated
            },
            CommandAck {
                command: CommandKind::Hold,
                result: CommandResult::Disarmed
            },
        ]
    );
}

/// Calibrate on synthetic sensors, then arm and fly a setpoint entirely through link frames.
#[test]
fn arm_and_setpoint_through_the_link() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let mut linux = Linux::new();
    let arm = linux.frame(Message::Command(Command {
        command: CommandKind::Arm,
        confirm: 0,
    }));
    let mut armed_at = None;
    let mut results = Vec::new();
    for tick in 0..3_000u64 {
        let now = tick * TICK_US;
        let s = sensors(tick);
        core.step(now, &s);
        if tick % 250 == 0 && armed_at.is_none() {
            link.on_bytes(now, &arm, &mut core);
        }
        let frames = linux.receive(&tx(&mut link, now, &core, &s));
        for a in ack_results(&frames) {
            results.push(a.result);
            if a.result == CommandResult::Accepted {
                armed_at = Some(tick);
            }
        }
        if armed_at.is_some() {
            break;
        }
    }
    assert!(armed_at.is_some(), "never armed: {results:?}");
    assert!(
        results.contains(&CommandResult::NotCalibrated),
        "{results:?}"
    );
    assert!(core.armed());
    let sp = VelocitySetpoint {
        vel_ned_mps: [0.0, 0.0, -0.5],
        yaw: YawSetpoint::Heading { yaw_ned_rad: 0.3 },
        ttl_ms: 300,
    };
    let t = armed_at.unwrap() * TICK_US + TICK_US;
    link.on_bytes(t, &linux.frame(Message::VelocitySetpoint(sp)), &mut core);
    assert_eq!(link.stats().setpoints_applied, 1);
    assert_eq!(core.mode(), Mode::Velocity);
    let nav = linux.receive(&tx(&mut link, t + 20_000, &core, &sensors(0)));
    let nav = nav.iter().find_map(|f| match f.message {
        Message::NavState(n) => Some(n),
        _ => None,
    });
    let nav = nav.expect("nav state due within 20 ms");
    assert!(nav.home_set && nav.calibrated);
    // The home rides in about one NavState a second: 3 s of them carry it 3 or 4 times, the
    // first within the first second.
    let mut homes = Vec::new();
    let mut navs = 0;
    for k in 1..=150u64 {
        let at = t + 20_000 + k * 20_000;
        for f in linux.receive(&tx(&mut link, at, &core, &sensors(0))) {
            if let Message::NavState(n) = f.message {
                navs += 1;
                if let Some(h) = n.home {
                    homes.push((at - t, h));
                }
            }
        }
    }
    assert!(navs >= 100, "{navs} nav states");
    assert!((3..=4).contains(&homes.len()), "{homes:?}");
    assert!(homes[0].0 <= 1_020_000, "{homes:?}");
    assert!((homes[0].1.lat_deg - 47.3977).abs() < 1e-9, "{homes:?}");
}

#[test]
fn ping_is_answered_with_pong() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::new(StreamRates::OFF);
    let mut linux = Linux::new();
    link.on_bytes(
        5_000,
        &linux.frame(Message::TimeSyncPing(TimeSyncPing {
            linux_time_ns: 123_456_789,
        })),
        &mut core,
    );
    let frames = linux.receive(&tx(&mut link, 7_000, &core, &SensorInputs::default()));
    let pong = frames.iter().find_map(|f| match f.message {
        Message::TimeSyncPong(p) => Some((p, f.header.t_us)),
        _ => None,
    });
    let (pong, t) = pong.expect("pong");
    assert_eq!(
        pong,
        TimeSyncPong {
            linux_time_ns: 123_456_789,
            mcu_rx_time_us: 5_000,
            mcu_tx_time_us: 7_000
        }
    );
    assert_eq!(t, 7_000);
    // Answered once.
    assert!(tx(&mut link, 9_000, &core, &SensorInputs::default()).is_empty());
}

#[test]
fn hello_at_start_and_on_request_and_incompatible_peer_is_refused() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::new(StreamRates::OFF);
    let mut linux = Linux::new();
    let hellos = |frames: Vec<Frame>| {
        frames
            .into_iter()
            .filter_map(|f| match f.message {
                Message::Hello(h) => Some(h),
                _ => None,
            })
            .collect::<Vec<_>>()
    };
    let h = hellos(linux.receive(&tx(&mut link, 0, &core, &SensorInputs::default())));
    assert_eq!(h.len(), 1);
    assert_eq!(
        (h[0].protocol_version, h[0].schema_hash),
        (PROTOCOL_VERSION, SCHEMA_HASH)
    );
    assert_eq!(h[0].check(), Ok(()));
    assert_eq!(h[0].firmware_version, FIRMWARE_VERSION);
    link.on_bytes(
        1,
        &linux.frame(Message::HelloRequest(HelloRequest::ours())),
        &mut core,
    );
    assert_eq!(link.peer(), PeerState::Compatible);
    assert_eq!(
        hellos(linux.receive(&tx(&mut link, 2, &core, &SensorInputs::default()))).len(),
        1
    );
    // A peer built from another schema: its commands are refused, readably.
    let other = HelloRequest {
        protocol_version: PROTOCOL_VERSION,
        schema_hash: SCHEMA_HASH ^ 0xFF,
    };
    link.on_bytes(3, &linux.frame(Message::HelloRequest(other)), &mut core);
    assert!(matches!(
        link.peer(),
        PeerState::Incompatible(HandshakeError::SchemaMismatch { .. })
    ));
    link.on_bytes(
        4,
        &linux.frame(Message::Command(Command {
            command: CommandKind::Disarm,
            confirm: 0,
        })),
        &mut core,
    );
    let acks = ack_results(&linux.receive(&tx(&mut link, 5, &core, &SensorInputs::default())));
    assert_eq!(
        acks,
        [CommandAck {
            command: CommandKind::Disarm,
            result: CommandResult::Incompatible
        }]
    );
}

#[test]
fn garbage_and_mcu_messages_from_linux_are_counted() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let mut linux = Linux::new();
    let mut bytes = std::vec![0x13u8, 0x37, 0xFF, 0x00];
    let mut good = linux.frame(Message::Command(Command {
        command: CommandKind::Land,
        confirm: 0,
    }));
    let n = good.len();
    good[n / 2] ^= 0x04;
    bytes.extend_from_slice(&good);
    bytes.extend(linux.frame(Message::ImuRaw(Default::default())));
    link.on_bytes(0, &bytes, &mut core);
    let c = link.rx_counters();
    assert_eq!(c.resyncs, 2, "{c:?}");
    assert_eq!(c.rx_frames, 1);
    assert_eq!(link.stats().unexpected, 1);
    assert_eq!(
        link.stats().command_rejects,
        0,
        "the corrupted command never reached the core"
    );
}

/// One second of 500 Hz ticks: each stream at its configured rate, frames well-formed.
#[test]
fn telemetry_rates_over_one_second() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let mut linux = Linux::new();
    let mut count: BTreeMap<&'static str, u32> = BTreeMap::new();
    let mut laser = 0;
    let mut sonar = 0;
    let mut total = 0usize;
    let mut max_tick = 0usize;
    let mut last_imu_t = None;
    for tick in 0..500u64 {
        let now = tick * TICK_US;
        let s = sensors(tick);
        core.step(now, &s);
        link.record_loop_time_us(100 + (tick % 7) as u32);
        let bytes = tx(&mut link, now, &core, &s);
        total += bytes.len();
        max_tick = max_tick.max(bytes.len());
        for f in linux.receive(&bytes) {
            *count.entry(f.message.name()).or_default() += 1;
            match f.message {
                Message::RangeRaw(r) if r.sensor == RangeSensor::Laser => laser += 1,
                Message::RangeRaw(_) => sonar += 1,
                Message::ImuRaw(_) => {
                    assert!(
                        last_imu_t.is_none_or(|t| f.header.t_us > t),
                        "no IMU sample twice"
                    );
                    last_imu_t = Some(f.header.t_us);
                }
                Message::Status(st) if st.loop_time_max_us > 0 => {
                    assert!(st.loop_time_max_us <= 106 && st.loop_time_avg_us >= 100);
                }
                _ => {}
            }
        }
    }
    std::println!("1 s of telemetry: {count:?}, laser {laser}, sonar {sonar}; {total} B/s, max {max_tick} B in one tick");
    let r = StreamRates::DEFAULT;
    let expect = [
        ("ImuRaw", r.imu_raw_hz),
        ("NavState", r.nav_state_hz),
        ("AltitudeFusion", r.altitude_hz),
        ("MagRaw", r.mag_raw_hz),
        ("BaroRaw", r.baro_raw_hz),
        ("GpsRaw", 5), // the GPS delivers 5 Hz: never more than the sensor
        ("Battery", r.battery_hz.min(10)),
        ("Status", r.status_hz),
    ];
    for (name, hz) in expect {
        let got = count.get(name).copied().unwrap_or(0) as i64;
        assert!(
            (got - hz as i64).abs() <= 1,
            "{name}: {got} frames in 1 s, expected {hz}"
        );
    }
    assert!(
        (laser as i64 - r.laser_raw_hz as i64).abs() <= 1,
        "laser {laser}"
    );
    assert!(
        (sonar as i64 - r.sonar_raw_hz as i64).abs() <= 1,
        "sonar {sonar}"
    );
    assert_eq!(count.get("Hello"), Some(&1));
    assert_eq!(link.stats().tx_dropped, 0);
    assert!(
        max_tick <= 184,
        "one tick carries at most 184 B at 921600 baud: {max_tick}"
    );
    assert!(total as f64 <= 0.6 * fcc_msgs::BAUD_921600_BYTES_PER_S as f64);
}

#[test]
fn small_buffer_is_never_overrun_and_drops_are_counted() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let mut linux = Linux::new();
    let mut frames = 0;
    for tick in 0..500u64 {
        let s = sensors(tick);
        core.step(tick * TICK_US, &s);
        let mut out = [0u8; 40];
        let n = link.poll_tx(tick * TICK_US, &core, &s, &mut out);
        assert!(n <= 40);
        frames += linux.receive(&out[..n]).len();
    }
    // NavState (59 B without the home, 80 B with) never fits 40 B: all of its frames are
    // dropped and counted.
    assert!(link.stats().tx_dropped >= 100, "{:?}", link.stats());
    assert!(frames > 200);
    assert_eq!(linux.dec.counters().rx_frames as usize, frames);
}

#[test]
fn quaternion_from_euler() {
    let q = quat_from_euler(0.0, 0.0, 0.0);
    assert_eq!(q, [1.0, 0.0, 0.0, 0.0]);
    let q = quat_from_euler(0.0, 0.0, core::f32::consts::FRAC_PI_2);
    assert!((q[0] - q[3]).abs() < 1e-6 && (q[0] - core::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6);
    let q = quat_from_euler(0.3, -0.2, 2.0);
    let n: f32 = q.iter().map(|x| x * x).sum();
    assert!((n - 1.0).abs() < 1e-5);
}

#[test]
fn param_set_is_applied_refused_with_a_reason_and_acknowledged() {
    use fcc_msgs::{param_id, ParamSet};
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let mut linux = Linux::new();
    let tilt0 = core.params().limits.max_tilt_deg;
    let sets = [
        (param_id::MAX_TILT_DEG, 30.0),        // accepted
        (param_id::MAX_TILT_DEG, 80.0),        // out of range (validate: 5..=60)
        (param_id::VEL_P_PER_S, f32::NAN),     // a read
        (param_id::CROSS_TRACK_K_PER_S, -1.0), // out of range (set_param's own range)
    ];
    for (id, value) in sets {
        link.on_bytes(
            1_000,
            &linux.frame(Message::ParamSet(ParamSet { id, value })),
            &mut core,
        );
    }
    link.on_bytes(
        1_000,
        &linux.frame(Message::ParamSet(ParamSet {
            id: 999,
            value: 1.0,
        })),
        &mut core,
    );
    assert_ne!(tilt0, 30.0);
    assert_eq!(core.params().limits.max_tilt_deg, 30.0);
    let acks: Vec<ParamAck> = linux
        .receive(&tx(&mut link, 2_000, &core, &SensorInputs::default()))
        .iter()
        .filter_map(|f| match f.message {
            Message::ParamAck(a) => Some(a),
            _ => None,
        })
        .collect();
    // Queue of 4: the oldest (the accepted set) was dropped for the unknown id's ack.
    let r: Vec<(u16, ParamResult)> = acks.iter().map(|a| (a.id, a.result)).collect();
    assert_eq!(
        r,
        [
            (param_id::MAX_TILT_DEG, ParamResult::OutOfRange),
            (param_id::VEL_P_PER_S, ParamResult::NotFinite),
            (param_id::CROSS_TRACK_K_PER_S, ParamResult::OutOfRange),
            (999, ParamResult::UnknownId),
        ]
    );
    assert_eq!(
        acks[0].value, 30.0,
        "a refused set reports the value in use"
    );
    assert_eq!(acks[1].value, Params::default().control.vel_p_per_s);
    assert_eq!(
        core.params().control.cross_track_k_per_s,
        Params::default().control.cross_track_k_per_s
    );
}

/// A frame with the given sequence number (the Linux side's encoder at any point).
fn frame_seq(m: Message, seq: u16) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = fcc_msgs::encode(&m, seq, 42, &mut buf).unwrap();
    buf[..n].to_vec()
}

fn ping() -> Message {
    Message::TimeSyncPing(TimeSyncPing { linux_time_ns: 1 })
}

/// A restarted bridge handshakes again with its sequence counting from 0: the jump is one
/// sequence reset, not ~21,000 lost frames; real gaps before and after are still counted.
#[test]
fn second_handshake_with_a_fresh_sequence_counts_no_loss() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let hello = || Message::HelloRequest(HelloRequest::ours());
    // First bridge: its session began long ago (seq 44530), one real gap of 2 frames.
    let mut bytes = frame_seq(hello(), 44_530);
    for seq in [44_531, 44_532, 44_533, 44_536] {
        bytes.extend(frame_seq(ping(), seq));
    }
    link.on_bytes(0, &bytes, &mut core);
    let c = link.rx_counters();
    assert_eq!((c.seq_gaps, c.frames_lost, c.seq_resets), (1, 2, 0));

    // It is killed; a new bridge flushes, handshakes from seq 0 and pings (one real loss: 3).
    let mut bytes = std::vec![0u8];
    bytes.extend(frame_seq(hello(), 0));
    for seq in [1, 2, 4] {
        bytes.extend(frame_seq(ping(), seq));
    }
    // Byte by byte, as the UART interrupt delivers them.
    for b in &bytes {
        link.on_bytes(1_000, core::slice::from_ref(b), &mut core);
    }
    let c = link.rx_counters();
    assert_eq!(c.rx_frames, 9);
    assert_eq!(
        (c.seq_gaps, c.frames_lost, c.seq_resets),
        (2, 3, 1),
        "the new session's jump (44536 -> 0, 20999 frames by the numbers) is not loss: {c:?}"
    );
    assert_eq!(link.peer(), PeerState::Compatible);

    // Status carries the same figures.
    let mut linux = Linux::new();
    let frames = linux.receive(&tx(&mut link, 2_000, &core, &SensorInputs::default()));
    let status = frames
        .iter()
        .find_map(|f| match f.message {
            Message::Status(s) => Some(s),
            _ => None,
        })
        .expect("status is due at start");
    assert_eq!(status.link_rx, c);

    // A repeated HelloRequest within the session (seq continues) changes nothing.
    link.on_bytes(3_000, &frame_seq(hello(), 5), &mut core);
    let c2 = link.rx_counters();
    assert_eq!(
        (c2.seq_gaps, c2.frames_lost, c2.seq_resets),
        (2, 3, 1),
        "{c2:?}"
    );
}

/// A jump onto a new session that the decoder already counts as a reset (≥ 32768 back) stays
/// one reset.
#[test]
fn handshake_after_a_backward_jump_is_one_reset() {
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::default();
    let hello = || Message::HelloRequest(HelloRequest::ours());
    let mut bytes = frame_seq(hello(), 0);
    bytes.extend(frame_seq(ping(), 1));
    bytes.extend(frame_seq(ping(), 2));
    bytes.extend(frame_seq(hello(), 0));
    bytes.extend(frame_seq(ping(), 1));
    link.on_bytes(0, &bytes, &mut core);
    let c = link.rx_counters();
    assert_eq!(
        (c.seq_gaps, c.frames_lost, c.seq_resets),
        (0, 0, 1),
        "{c:?}"
    );
}

/// IMU frames in `ticks` 500 Hz ticks from `tick0` on.
fn imu_frames(
    link: &mut LinkEndpoint,
    core: &mut FlightCore,
    linux: &mut Linux,
    tick0: u64,
    ticks: u64,
) -> usize {
    let mut n = 0;
    for tick in tick0..tick0 + ticks {
        let s = sensors(tick);
        core.step(tick * TICK_US, &s);
        let bytes = tx(link, tick * TICK_US, core, &s);
        n += linux
            .receive(&bytes)
            .iter()
            .filter(|f| matches!(f.message, Message::ImuRaw(_)))
            .count();
    }
    n
}

/// `rates.imu_hz` set over the link changes the IMU stream from the next tick on; a set whose
/// worst case would not fit 921600 baud is refused and changes nothing.
#[test]
fn rate_parameters_reschedule_the_streams() {
    use fcc_msgs::{param_id, ParamSet};
    let mut core = FlightCore::new(Params::default());
    let mut link = LinkEndpoint::new(core.params().stream_rates());
    let mut linux = Linux::new();
    let before = imu_frames(&mut link, &mut core, &mut linux, 0, 500);
    let set =
        |link: &mut LinkEndpoint, core: &mut FlightCore, linux: &mut Linux, id: u16, value: f32| {
            link.on_bytes(
                0,
                &linux.frame(Message::ParamSet(ParamSet { id, value })),
                core,
            );
            let acks: Vec<ParamAck> = linux
                .receive(&tx(link, 1_000_000, core, &SensorInputs::default()))
                .iter()
                .filter_map(|f| match f.message {
                    Message::ParamAck(a) => Some(a),
                    _ => None,
                })
                .collect();
            acks[0]
        };
    let ack = set(
        &mut link,
        &mut core,
        &mut linux,
        param_id::RATES_IMU_HZ,
        50.0,
    );
    assert_eq!((ack.result, ack.value), (ParamResult::Accepted, 50.0));
    assert_eq!(link.rates().imu_raw_hz, 50);
    let after = imu_frames(&mut link, &mut core, &mut linux, 501, 500);
    // Every stream at its table maximum: far beyond 92 160 B/s.
    let mut over = None;
    for s in Stream::ALL {
        let max_hz = fcc_msgs::params::by_id(s.param_id()).unwrap().max;
        let a = set(&mut link, &mut core, &mut linux, s.param_id(), max_hz);
        over = over.or((a.result != ParamResult::Accepted).then_some((s, a)));
    }
    let (s, a) = over.expect("some set exceeds the UART");
    assert_eq!(a.result, ParamResult::OutOfRange, "{s:?}");
    let r = link.rates();
    assert!(
        r.worst_case_bytes_per_s() <= fcc_msgs::BAUD_921600_BYTES_PER_S,
        "{r:?}"
    );
    assert_eq!(*r, core.params().stream_rates());
    std::println!("IMU frames/s: {before} at the default rate, {after} after rates.imu_hz 50; {s:?} refused at {r:?}");
    assert!((before as i64 - 200).abs() <= 1, "{before}");
    assert!((after as i64 - 50).abs() <= 1, "{after}");
}
