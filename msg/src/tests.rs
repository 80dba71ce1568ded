//! Codec tests: round trips, chunking, garbage, corruption, truncation, limits, budget.

extern crate std;
use crate::frame::CRC32C;
use crate::*;
use proptest::prelude::*;
use std::vec;
use std::vec::Vec;

/// One representative value of every message, in id order.
pub(crate) fn samples() -> Vec<Message> {
    let counters = LinkCounters {
        rx_bytes: 123_456,
        rx_frames: 4_321,
        crc_errors: 3,
        framing_errors: 1,
        overruns: 0,
        resyncs: 4,
        decode_errors: 0,
        unknown_ids: 0,
        version_errors: 0,
        seq_gaps: 2,
        frames_lost: 5,
        seq_resets: 0,
    };
    vec![
        Message::Hello(Hello::ours([0, 1, 0])),
        Message::ImuRaw(ImuRaw {
            gyro_frd_radps: on_grid([0.01, -0.02, 0.003], fixed::gyro::LSB),
            accel_frd_mps2: on_grid([0.1, -0.2, -9.81], fixed::accel::LSB),
        }),
        Message::MagRaw(MagRaw {
            mag_frd_ut: on_grid([21.0, -3.5, 43.2], fixed::mag::LSB),
        }),
        Message::BaroRaw(BaroRaw {
            pressure_pa: 101_325.0,
            temperature_c: 21.5,
        }),
        Message::GpsRaw(GpsRaw {
            lat_deg: 47.397_742_123,
            lon_deg: 8.545_594_456,
            alt_m: 488.2,
            vel_ned_mps: [1.0, -0.5, 0.1],
            h_acc_m: 1.2,
            num_sats: 14,
            fix_ok: true,
        }),
        Message::RangeRaw(RangeRaw {
            sensor: RangeSensor::Sonar,
            range_m: 2.31,
        }),
        Message::Battery(Battery {
            voltage_v: 22.4,
            current_a: 31.0,
        }),
        Message::NavState(NavState {
            q_body_to_ned: on_grid([0.999, 0.01, -0.02, 0.03], fixed::unit::LSB),
            rate_frd_radps: on_grid([0.1, 0.2, -0.3], fixed::gyro::LSB),
            pos_ned_m: [10.0, -5.0, -20.0],
            vel_ned_mps: on_grid([2.0, 0.5, -0.1], fixed::vel::LSB),
            accel_ned_mps2: on_grid([0.1, 0.0, 0.05], fixed::accel_est::LSB),
            accel_obs_ne_mps2: on_grid([0.08, -0.01], fixed::accel_est::LSB),
            home: Some(HomePosition {
                lat_deg: 47.397_742,
                lon_deg: 8.545_594,
                alt_m: 488.0,
            }),
            gps_ok: true,
            home_set: true,
            calibrated: true,
        }),
        Message::AltitudeFusion(AltitudeFusion {
            baro_alt_m: 19.8,
            alt_m: 20.0,
            vel_down_mps: -0.1,
            ground_height_m: 19.5,
            ground_var_m2: 0.04,
            laser_m: 19.6,
            sonar_m: f32::NAN,
            source: AltitudeSource::Laser,
        }),
        Message::Status(Status {
            mode: FlightMode::Velocity,
            armed: true,
            landed: false,
            failsafe: FailsafeCause::None,
            sensors: SensorHealth {
                gps_ok: true,
                mag_disturbed: true,
                mag_rejects: 17,
                laser_ok: false,
                sonar_ok: true,
                mag_disturbed_ds: 25,
                nav_faults: 2,
            },
            loop_time_max_us: 310,
            loop_time_avg_us: 180,
            link_rx: counters,
            tx_frames: 1_000_000,
            tx_dropped: 0,
            setpoint_rejects: 2,
            command_rejects: 1,
            last_reject: CommandResult::Disarmed,
        }),
        Message::TimeSyncPong(TimeSyncPong {
            linux_time_ns: 1_700_000_000_123_456_789,
            mcu_rx_time_us: 12_345_678,
            mcu_tx_time_us: 12_345_900,
        }),
        Message::CommandAck(CommandAck {
            command: CommandKind::Arm,
            result: CommandResult::NoHome,
        }),
        Message::ParamAck(ParamAck {
            id: param_id::MAX_TILT_DEG,
            value: 25.0,
            result: ParamResult::OutOfRange,
        }),
        Message::HelloRequest(HelloRequest::ours()),
        Message::VelocitySetpoint(VelocitySetpoint {
            vel_ned_mps: [1.5, -0.5, -1.0],
            yaw: YawSetpoint::Heading { yaw_ned_rad: 1.57 },
            ttl_ms: 500,
        }),
        Message::Command(Command {
            command: CommandKind::Land,
            confirm: 0,
        }),
        Message::TimeSyncPing(TimeSyncPing {
            linux_time_ns: 1_700_000_000_000_000_000,
        }),
        Message::ParamSet(ParamSet {
            id: param_id::VEL_P_PER_S,
            value: 1.5,
        }),
    ]
}

/// `v` rounded to the fixed-point grid of `lsb` (what crosses the link unchanged).
pub(crate) fn on_grid<const N: usize>(v: [f32; N], lsb: f32) -> [f32; N] {
    v.map(|x| fixed::from_count(fixed::to_count(x, lsb), lsb))
}

pub(crate) fn enc(msg: &Message, seq: u16, t_us: u64) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode(msg, seq, t_us, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// A frame built by hand (to forge versions, ids and payloads the encoder would never write).
fn raw_frame(version: u8, msg_id: u8, seq: u16, t_us: u64, payload: &[u8]) -> Vec<u8> {
    let mut raw = vec![version, msg_id];
    raw.extend_from_slice(&seq.to_le_bytes());
    raw.extend_from_slice(&t_us.to_le_bytes()[..header_len(msg_id) - 4]);
    raw.extend_from_slice(payload);
    let crc = CRC32C.checksum(&raw);
    raw.extend_from_slice(&crc.to_le_bytes());
    let mut out = vec![0u8; cobs::max_encoding_length(raw.len()) + 1];
    let n = cobs::encode(&raw, &mut out);
    out.truncate(n);
    out.push(0);
    out
}

/// Same value, NaN-aware (compares the Debug text, where NaN prints as NaN).
fn same(a: &Message, b: &Message) -> bool {
    std::format!("{a:?}") == std::format!("{b:?}")
}

fn decode_all(dec: &mut FrameDecoder, bytes: &[u8]) -> Vec<Result<Frame, DecodeError>> {
    dec.push_slice(bytes).collect()
}

fn stream_of_samples() -> (Vec<u8>, Vec<Message>) {
    let msgs = samples();
    let mut bytes = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        bytes.extend(enc(m, i as u16, 1_000 * i as u64));
    }
    (bytes, msgs)
}

#[test]
fn round_trip_every_message() {
    let msgs = samples();
    assert_eq!(msgs.len(), ALL_IDS.len(), "a sample per message");
    for (i, m) in msgs.iter().enumerate() {
        assert_eq!(m.id(), ALL_IDS[i]);
        let bytes = enc(m, 40_000 + i as u16, u64::MAX - i as u64);
        assert_eq!(*bytes.last().unwrap(), 0);
        assert!(
            !bytes[..bytes.len() - 1].contains(&0),
            "COBS leaves no 0 inside a frame"
        );
        assert!(
            bytes.len() <= max_frame_len(m.id()),
            "{}: {} > max",
            m.name(),
            bytes.len()
        );
        let mut dec = FrameDecoder::new();
        let out = decode_all(&mut dec, &bytes);
        assert_eq!(out.len(), 1);
        let f = out[0].unwrap();
        assert!(
            same(&f.message, m),
            "{}: {:?} != {:?}",
            m.name(),
            f.message,
            m
        );
        assert_eq!(
            f.header,
            Header {
                version: PROTOCOL_VERSION,
                msg_id: m.id(),
                seq: 40_000 + i as u16,
                // A fresh decoder extends a short header's low 32 bits with none (its first
                // frame): the long headers carry the whole.
                t_us: if long_header(m.id()) {
                    u64::MAX - i as u64
                } else {
                    u64::from((u64::MAX - i as u64) as u32)
                }
            }
        );
        assert_eq!(dec.counters().rx_frames, 1);
    }
}

#[test]
fn print_encoded_sizes() {
    for m in samples() {
        let n = enc(&m, 1, 1_000_000).len();
        std::println!(
            "{:>16} id 0x{:02x}: {n:>3} B typical, {:>3} B max on the wire",
            m.name(),
            m.id(),
            max_frame_len(m.id())
        );
    }
    std::println!("MAX_FRAME_LEN {MAX_FRAME_LEN} B");
}

#[test]
fn every_chunk_size_1_to_64() {
    let (bytes, msgs) = stream_of_samples();
    for chunk in 1..=64 {
        let mut dec = FrameDecoder::new();
        let mut got = Vec::new();
        for c in bytes.chunks(chunk) {
            for r in dec.push_slice(c) {
                got.push(r.unwrap_or_else(|e| panic!("chunk {chunk}: {e}")).message);
            }
        }
        assert_eq!(got.len(), msgs.len(), "chunk {chunk}");
        assert!(
            got.iter().zip(&msgs).all(|(a, b)| same(a, b)),
            "chunk {chunk}"
        );
        let c = dec.counters();
        assert_eq!(
            (c.rx_frames as usize, c.resyncs, c.seq_gaps),
            (msgs.len(), 0, 0)
        );
        assert_eq!(c.rx_bytes as usize, bytes.len());
    }
}

#[test]
fn byte_push_matches_slice_push() {
    let (bytes, msgs) = stream_of_samples();
    let mut dec = FrameDecoder::new();
    let got: Vec<Message> = bytes
        .iter()
        .filter_map(|&b| dec.push(b))
        .map(|r| r.unwrap().message)
        .collect();
    assert!(got.iter().zip(&msgs).all(|(a, b)| same(a, b)) && got.len() == msgs.len());
}

#[test]
fn garbage_prefixes_resync() {
    let (bytes, msgs) = stream_of_samples();
    let garbages: Vec<Vec<u8>> = vec![
        vec![0x55],
        vec![0xFF; 7],
        vec![1, 2, 3, 0, 4, 5, 6],     // garbage containing a delimiter
        (0..=255u8).collect(),         // every byte value
        vec![0xAA; MAX_FRAME_LEN * 3], // long enough to overrun
        bytes[5..bytes.len() / 2].to_vec(), // the back half of real frames
    ];
    for g in &garbages {
        let mut stream = g.clone();
        stream.extend_from_slice(&bytes);
        let mut dec = FrameDecoder::new();
        let out = decode_all(&mut dec, &stream);
        let ok: Vec<Message> = out
            .iter()
            .filter_map(|r| r.ok())
            .map(|f| f.message)
            .collect();
        // The garbage eats at most the first frame it runs into (no delimiter before it); the
        // last garbage case holds whole real frames of its own, which decode too.
        assert!(
            ok.len() >= msgs.len() - 1,
            "lost frames after {} B of garbage",
            g.len()
        );
        let n = msgs.len() - 1;
        assert!(ok[ok.len() - n..]
            .iter()
            .zip(&msgs[1..])
            .all(|(a, b)| same(a, b)));
        let c = dec.counters();
        assert!(c.resyncs >= 1, "garbage must be counted: {c:?}");
    }
    // With a leading 0x00 the sender flushes the receiver: nothing real is lost.
    let mut stream = vec![0x42; 10];
    stream.push(0);
    stream.extend_from_slice(&bytes);
    let mut dec = FrameDecoder::new();
    let ok = decode_all(&mut dec, &stream)
        .iter()
        .filter(|r| r.is_ok())
        .count();
    assert_eq!(ok, msgs.len());
}

#[test]
fn overrun_is_counted_once_and_recovers() {
    let mut dec = FrameDecoder::new();
    let mut stream = vec![0x11; MAX_FRAME_LEN * 4];
    stream.push(0);
    let good = enc(&samples()[1], 0, 0);
    stream.extend_from_slice(&good);
    let out = decode_all(&mut dec, &stream);
    assert_eq!(out.len(), 2);
    assert_eq!(out[0], Err(DecodeError::Overrun));
    assert!(out[1].is_ok());
    assert_eq!((dec.counters().overruns, dec.counters().resyncs), (1, 1));
}

#[test]
fn single_bit_flips_are_never_accepted_and_decoder_resyncs() {
    for m in samples() {
        let frame = enc(&m, 7, 99);
        let next = enc(
            &Message::Command(Command {
                command: CommandKind::Hold,
                confirm: 0,
            }),
            8,
            100,
        );
        let after = enc(
            &Message::TimeSyncPing(TimeSyncPing { linux_time_ns: 5 }),
            9,
            101,
        );
        for byte in 0..frame.len() {
            for bit in 0..8 {
                let mut bad = frame.clone();
                bad[byte] ^= 1 << bit;
                let mut stream = bad.clone();
                stream.extend_from_slice(&next);
                stream.extend_from_slice(&after);
                let mut dec = FrameDecoder::new();
                let out = decode_all(&mut dec, &stream);
                let ok: Vec<Frame> = out.iter().filter_map(|r| r.ok()).collect();
                assert!(
                    ok.iter().all(|f| f.header.seq != 7),
                    "{}: flip of bit {bit} in byte {byte} accepted",
                    m.name()
                );
                // The frame after the next one always survives; the next one too unless the
                // flip removed the delimiter that separates it from the corrupted frame.
                assert_eq!(
                    ok.last().map(|f| f.header.seq),
                    Some(9),
                    "{} byte {byte} bit {bit}",
                    m.name()
                );
                if byte != frame.len() - 1 {
                    assert_eq!(ok.len(), 2, "{} byte {byte} bit {bit}", m.name());
                }
                assert!(out.iter().any(|r| r.is_err()), "the corruption is reported");
            }
        }
    }
}

#[test]
fn truncated_frames_are_rejected() {
    for m in samples() {
        let frame = enc(&m, 3, 3);
        for cut in 1..frame.len() - 1 {
            let mut t = frame[..cut].to_vec();
            t.push(0);
            let mut dec = FrameDecoder::new();
            let out = decode_all(&mut dec, &t);
            assert_eq!(out.len(), 1, "{} cut {cut}", m.name());
            assert!(out[0].is_err(), "{} cut at {cut} accepted", m.name());
            let c = dec.counters();
            assert_eq!(c.framing_errors + c.crc_errors, 1);
        }
    }
}

#[test]
fn trailing_bytes_and_short_payloads_are_counted() {
    let cmd = [0u8, 0u8]; // Command { Arm, confirm: 0 }
    let mut long = cmd.to_vec();
    long.push(0x00);
    let mut dec = FrameDecoder::new();
    let out = decode_all(
        &mut dec,
        &raw_frame(PROTOCOL_VERSION, id::COMMAND, 0, 0, &long),
    );
    assert_eq!(
        out,
        vec![Err(DecodeError::TrailingBytes {
            msg_id: id::COMMAND,
            extra: 1
        })]
    );
    let out = decode_all(
        &mut dec,
        &raw_frame(PROTOCOL_VERSION, id::IMU_RAW, 1, 0, &[0u8; 11]),
    );
    assert_eq!(
        out,
        vec![Err(DecodeError::Payload {
            msg_id: id::IMU_RAW
        })]
    );
    // bool must be 0 or 1, enum index in range.
    let out = decode_all(
        &mut dec,
        &raw_frame(PROTOCOL_VERSION, id::COMMAND, 2, 0, &[9]),
    );
    assert_eq!(
        out,
        vec![Err(DecodeError::Payload {
            msg_id: id::COMMAND
        })]
    );
    // A setpoint's yaw case index past `Rate` (2): 12 bytes of velocity, case 3, a rate, ttl.
    let mut sp = vec![0u8; 12];
    sp.push(3);
    sp.extend_from_slice(&0.5f32.to_le_bytes());
    sp.push(100);
    let out = decode_all(
        &mut dec,
        &raw_frame(PROTOCOL_VERSION, id::VELOCITY_SETPOINT, 3, 0, &sp),
    );
    assert_eq!(
        out,
        vec![Err(DecodeError::Payload {
            msg_id: id::VELOCITY_SETPOINT
        })]
    );
    assert_eq!(dec.counters().decode_errors, 4);
    assert_eq!(dec.counters().seq_gaps, 0);
}

#[test]
fn unknown_id_is_counted() {
    let mut dec = FrameDecoder::new();
    let out = decode_all(
        &mut dec,
        &raw_frame(PROTOCOL_VERSION, 0x7E, 0, 0, &[1, 2, 3]),
    );
    assert_eq!(out, vec![Err(DecodeError::UnknownId { msg_id: 0x7E })]);
    assert_eq!(dec.counters().unknown_ids, 1);
    assert!(std::format!("{}", out[0].unwrap_err()).contains("0x7e"));
}

#[test]
fn version_and_schema_mismatch_are_readable() {
    let mut dec = FrameDecoder::new();
    // A data frame of another version is refused, not misdecoded.
    let imu = [0u8; 24];
    let out = decode_all(
        &mut dec,
        &raw_frame(PROTOCOL_VERSION + 1, id::IMU_RAW, 0, 0, &imu),
    );
    assert_eq!(
        out,
        vec![Err(DecodeError::VersionMismatch {
            ours: PROTOCOL_VERSION,
            theirs: PROTOCOL_VERSION + 1
        })]
    );
    assert_eq!(dec.counters().version_errors, 1);
    // The frozen Hello decodes across versions and the check names both versions.
    let hello = Hello {
        protocol_version: PROTOCOL_VERSION + 1,
        schema_hash: SCHEMA_HASH,
        firmware_version: [1, 2, 3],
    };
    let mut payload = [0u8; 16];
    let p = postcard::to_slice(&hello, &mut payload).unwrap();
    let out = decode_all(
        &mut dec,
        &raw_frame(PROTOCOL_VERSION + 1, id::HELLO, 1, 0, p),
    );
    let Ok(Frame {
        message: Message::Hello(h),
        ..
    }) = out[0]
    else {
        panic!("{out:?}")
    };
    let e = h.check().unwrap_err();
    assert_eq!(
        e,
        HandshakeError::VersionMismatch {
            ours: PROTOCOL_VERSION,
            theirs: PROTOCOL_VERSION + 1
        }
    );
    let text = std::format!("{e}");
    assert!(
        text.contains("version mismatch")
            && text.contains(&std::format!("v{}", PROTOCOL_VERSION + 1)),
        "{text}"
    );
    // Same version, other schema.
    let h = Hello {
        schema_hash: SCHEMA_HASH ^ 1,
        ..Hello::ours([0, 1, 0])
    };
    let e = h.check().unwrap_err();
    assert_eq!(
        e,
        HandshakeError::SchemaMismatch {
            ours: SCHEMA_HASH,
            theirs: SCHEMA_HASH ^ 1
        }
    );
    assert!(std::format!("{e}").contains("schema mismatch"));
    assert_eq!(Hello::ours([0, 1, 0]).check(), Ok(()));
    assert_eq!(HelloRequest::ours().check(), Ok(()));
}

#[test]
fn sequence_gaps_and_restarts() {
    let mut dec = FrameDecoder::new();
    let m = Message::Command(Command {
        command: CommandKind::Hold,
        confirm: 0,
    });
    for seq in [65_533u16, 65_534, 65_535, 0, 1, 5, 6, 2] {
        assert!(decode_all(&mut dec, &enc(&m, seq, 0))[0].is_ok());
    }
    let c = dec.counters();
    assert_eq!(
        (c.seq_gaps, c.frames_lost, c.seq_resets),
        (1, 3, 1),
        "{c:?}"
    );
}

#[test]
fn max_length_checks() {
    // Every message's worst case fits MAX_FRAME_LEN, and the largest one needs all of it.
    let largest = ALL_IDS.iter().map(|&i| max_frame_len(i)).max().unwrap();
    assert_eq!(largest, MAX_FRAME_LEN);
    // The encoder refuses a short buffer (and writes nothing past it).
    let m = samples()[9]; // Status
    let mut small = [0u8; 10];
    assert!(matches!(
        encode(&m, 0, 0, &mut small),
        Err(EncodeError::BufferTooSmall { available: 10, .. })
    ));
    let mut exact = vec![0u8; max_frame_len(m.id())];
    assert!(encode(&m, 0, 0, &mut exact).is_ok());
    // A worst-case-size payload (all varints at max) still round-trips.
    let max_counters = LinkCounters {
        rx_bytes: u32::MAX,
        rx_frames: u32::MAX,
        crc_errors: u32::MAX,
        framing_errors: u32::MAX,
        overruns: u32::MAX,
        resyncs: u32::MAX,
        decode_errors: u32::MAX,
        unknown_ids: u32::MAX,
        version_errors: u32::MAX,
        seq_gaps: u32::MAX,
        frames_lost: u32::MAX,
        seq_resets: u32::MAX,
    };
    let st = Message::Status(Status {
        mode: FlightMode::Land,
        failsafe: FailsafeCause::GpsLost,
        sensors: SensorHealth {
            gps_ok: true,
            mag_disturbed: true,
            mag_rejects: u32::MAX,
            laser_ok: true,
            sonar_ok: true,
            mag_disturbed_ds: u16::MAX,
            nav_faults: u8::MAX,
        },
        loop_time_max_us: u32::MAX,
        loop_time_avg_us: u32::MAX,
        link_rx: max_counters,
        tx_frames: u32::MAX,
        tx_dropped: u32::MAX,
        setpoint_rejects: u32::MAX,
        command_rejects: u32::MAX,
        last_reject: CommandResult::Incompatible,
        armed: true,
        landed: true,
    });
    let b = enc(&st, 0, u64::MAX);
    assert!(b.len() <= MAX_FRAME_LEN);
    assert_eq!(
        decode_all(&mut FrameDecoder::new(), &b)[0].unwrap().message,
        st
    );
    // A frame one byte longer than the decoder's buffer is an overrun.
    let mut dec = FrameDecoder::new();
    let mut long = vec![0x01u8; MAX_FRAME_LEN + 1];
    long.push(0);
    let out = decode_all(&mut dec, &long);
    assert_eq!(out, vec![Err(DecodeError::Overrun)]);
}

#[test]
fn encoder_numbers_frames() {
    let mut e = Encoder::new();
    let mut dec = FrameDecoder::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    for i in 0..3u16 {
        let n = e
            .encode(
                &Message::Command(Command {
                    command: CommandKind::Arm,
                    confirm: 0,
                }),
                5,
                &mut buf,
            )
            .unwrap();
        assert_eq!(decode_all(&mut dec, &buf[..n])[0].unwrap().header.seq, i);
    }
    assert!(e.encode(&samples()[9], 0, &mut buf[..5]).is_err());
    assert_eq!(
        e.next_seq(),
        3,
        "a failed encode does not use a sequence number"
    );
}

/// Link budget at the default rates: ≤ 60 % of 921600 baud.
#[test]
fn default_rates_fit_budget() {
    let rates = StreamRates::DEFAULT;
    let typical_len = |msg_id: u8| {
        let m = samples().into_iter().find(|m| m.id() == msg_id).unwrap();
        enc(&m, 0x1234, 123_456_789).len() as u32
    };
    let mut typical = 0u32;
    for (msg_id, hz) in rates.streams() {
        typical += hz as u32 * typical_len(msg_id);
    }
    let worst = rates.worst_case_bytes_per_s();
    let budget = BAUD_921600_BYTES_PER_S;
    std::println!(
        "default rates: {typical} B/s typical ({:.1} %), {worst} B/s worst case ({:.1} %) of {budget} B/s (921600 baud)",
        100.0 * typical as f64 / budget as f64,
        100.0 * worst as f64 / budget as f64
    );
    assert!(typical <= worst);
    assert!(
        worst as f64 <= 0.6 * budget as f64,
        "{worst} B/s exceeds 60 % of {budget}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Arbitrary bytes never panic, and a valid frame after them still decodes.
    #[test]
    fn random_bytes_never_panic(junk in proptest::collection::vec(any::<u8>(), 0..600), chunk in 1usize..80) {
        let mut dec = FrameDecoder::new();
        for c in junk.chunks(chunk) {
            for _ in dec.push_slice(c) {}
        }
        let good = enc(&Message::TimeSyncPing(TimeSyncPing { linux_time_ns: 77 }), 1, 2);
        let mut stream = vec![0u8];
        stream.extend_from_slice(&good);
        let out = decode_all(&mut dec, &stream);
        let expected = Message::TimeSyncPing(TimeSyncPing { linux_time_ns: 77 });
        let last_ok = matches!(out.last(), Some(Ok(f)) if f.message == expected);
        prop_assert!(last_ok, "valid frame after junk lost: {:?}", out.last());
    }

    /// Random values of a setpoint round-trip bit-exactly (NaN included), in each yaw case.
    #[test]
    fn setpoint_round_trip(v in any::<[u32; 3]>(), yaw in any::<u32>(), case in 0u8..3, ttl in any::<u16>(), seq in any::<u16>(), t in any::<u64>()) {
        let y = f32::from_bits(yaw);
        let yaw_sp = match case {
            0 => YawSetpoint::Keep,
            1 => YawSetpoint::Heading { yaw_ned_rad: y },
            _ => YawSetpoint::Rate { yaw_rate_ned_radps: y },
        };
        let m = Message::VelocitySetpoint(VelocitySetpoint {
            vel_ned_mps: v.map(f32::from_bits), yaw: yaw_sp, ttl_ms: ttl,
        });
        let out = decode_all(&mut FrameDecoder::new(), &enc(&m, seq, t));
        let Ok(Frame { header, message: Message::VelocitySetpoint(sp) }) = out[0] else { panic!() };
        prop_assert_eq!(sp.vel_ned_mps.map(f32::to_bits), v);
        let back = match sp.yaw {
            YawSetpoint::Keep => (0, None),
            YawSetpoint::Heading { yaw_ned_rad } => (1, Some(yaw_ned_rad.to_bits())),
            YawSetpoint::Rate { yaw_rate_ned_radps } => (2, Some(yaw_rate_ned_radps.to_bits())),
        };
        prop_assert_eq!(back, (case, (case != 0).then_some(yaw)));
        // A setpoint's header is short: the low 32 bits of the time (a fresh decoder).
        prop_assert_eq!((sp.ttl_ms, header.seq, header.t_us), (ttl, seq, u64::from(t as u32)));
    }
}

/// The `cobs` crate's in-place decoding: the decoded bytes, or `None` where it errs.
fn cobs_reference(mut buf: Vec<u8>) -> Option<Vec<u8>> {
    let n = cobs::decode_in_place(&mut buf).ok()?;
    buf.truncate(n);
    Some(buf)
}

/// Ours, the same way.
fn cobs_ours(mut buf: Vec<u8>) -> Option<Vec<u8>> {
    let n = crate::frame::cobs_decode_in_place(&mut buf)?;
    Some(buf[1..1 + n].to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    /// The block-hopping COBS decoder agrees with the `cobs` crate: on valid encodings of
    /// 0..700 bytes (sparse zeros, so 0xFF blocks and the shift after them occur) and on
    /// arbitrary zero-free bytes (what the delimiter split hands it).
    #[test]
    fn cobs_decoding_matches_the_cobs_crate(
        data in proptest::collection::vec(prop_oneof![4 => 1u8..=255, 1 => Just(0u8)], 0..700),
        junk in proptest::collection::vec(1u8..=255, 1..300),
    ) {
        let mut enc = vec![0u8; cobs::max_encoding_length(data.len())];
        let n = cobs::try_encode(&data, &mut enc).unwrap();
        enc.truncate(n);
        prop_assert_eq!(cobs_ours(enc.clone()), Some(data));
        prop_assert_eq!(cobs_ours(enc.clone()), cobs_reference(enc));
        prop_assert_eq!(cobs_ours(junk.clone()), cobs_reference(junk));
    }
}

/// Long runs without a zero: 0xFF blocks at the start, the middle and the end.
#[test]
fn cobs_decoding_handles_full_blocks() {
    for len in [253, 254, 255, 508, 509, 600] {
        for zero_at in [None, Some(0), Some(100), Some(len - 1)] {
            let mut data: Vec<u8> = (0..len).map(|i| (i % 255 + 1) as u8).collect();
            if let Some(z) = zero_at {
                data[z] = 0;
            }
            let mut enc = vec![0u8; cobs::max_encoding_length(data.len())];
            let n = cobs::try_encode(&data, &mut enc).unwrap();
            enc.truncate(n);
            assert_eq!(
                cobs_ours(enc.clone()),
                Some(data),
                "len {len} zero at {zero_at:?}"
            );
            assert_eq!(cobs_ours(enc.clone()), cobs_reference(enc));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// The run-at-a-time `push_slice` and the byte-at-a-time `push` agree on every item (frame
    /// or error, in order) and every counter, on streams of valid frames, random bytes, bit
    /// flips and long runs without a delimiter (overruns), in any chunking.
    #[test]
    fn slice_decoding_matches_byte_decoding(
        parts in proptest::collection::vec((0usize..16, proptest::collection::vec(any::<u8>(), 0..40), any::<u16>(), 0u8..4), 1..12),
        chunk in 1usize..200,
    ) {
        let sample = samples();
        let mut stream = Vec::new();
        for (i, (which, junk, flip, kind)) in parts.iter().enumerate() {
            let mut f = enc(&sample[which % sample.len()], i as u16, 1_000 * i as u64);
            match kind {
                0 => {}
                1 => {
                    let at = usize::from(*flip) % f.len();
                    f[at] ^= 1 << (flip % 8);
                }
                2 => stream.extend_from_slice(junk),
                _ => stream.extend(core::iter::repeat_n(0x55u8, MAX_FRAME_LEN + usize::from(*flip % 50))),
            }
            stream.extend_from_slice(&f);
        }
        let mut by_byte = FrameDecoder::new();
        let items_b: Vec<_> = stream.iter().filter_map(|&b| by_byte.push(b)).collect();
        let mut by_run = FrameDecoder::new();
        let mut items_r = Vec::new();
        for c in stream.chunks(chunk) {
            items_r.extend(by_run.push_slice(c));
        }
        // Compared as text: the samples carry NaN (not equal to itself).
        prop_assert_eq!(std::format!("{items_r:?}"), std::format!("{items_b:?}"));
        prop_assert_eq!(by_run.counters(), by_byte.counters());
    }
}

/// Short headers' times are extended from the frame before: across the 32-bit wrap
/// (71.6 min), after a gap of half the range less a second, and from the start; a long
/// header sets the time whole; a sequence restart (reboot) forgets it.
#[test]
fn short_header_times_are_extended_from_the_frames_before() {
    let imu = Message::ImuRaw(ImuRaw::default());
    let status = samples()
        .into_iter()
        .find(|m| m.id() == id::STATUS)
        .unwrap();
    let mut dec = FrameDecoder::new();
    let mut seq = 0u16;
    let mut times = |dec: &mut FrameDecoder, m: &Message, t: u64| {
        seq = seq.wrapping_add(1);
        let out = decode_all(dec, &enc(m, seq, t));
        out[0].unwrap().header.t_us
    };
    // From the start: the low bits are the time.
    assert_eq!(times(&mut dec, &imu, 5_000), 5_000);
    // A long header 3 h in, then short ones across two wraps of the low 32 bits.
    let t0 = 3 * 3_600_000_000u64;
    assert_eq!(times(&mut dec, &status, t0), t0);
    let mut t = t0;
    while t < t0 + 2 * (1u64 << 32) {
        assert_eq!(times(&mut dec, &imu, t), t);
        t += 300_000_000; // 5 min between frames
    }
    // A gap just under half the range is still right.
    let last = t - 300_000_000;
    let gap = (1u64 << 31) - 1_000_000;
    assert_eq!(times(&mut dec, &imu, last + gap), last + gap);
    // The sender restarts (its sequence and clock): the time starts again from the low bits.
    let out = decode_all(&mut dec, &enc(&imu, 40_000, 1_234));
    assert_eq!(out[0].unwrap().header.t_us, 1_234);
    assert_eq!(extend_time(None, 7), 7);
    assert_eq!(extend_time(Some(10), u32::MAX), u64::from(u32::MAX));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    /// The fixed-layout decoders of the busiest payloads give postcard's values and errors on
    /// any bytes: valid encodings (with and without the home, NaN counts, odd flags) and
    /// arbitrary ones of any length.
    #[test]
    fn fast_decoding_equals_postcard(
        bytes in proptest::collection::vec(any::<u8>(), 0..80),
        tag in 0u8..3,
        flags in any::<u8>(),
    ) {
        for id in [id::IMU_RAW, id::MAG_RAW, id::NAV_STATE] {
            let fast = Message::deserialize_payload(id, &bytes);
            let slow = Message::deserialize_payload_postcard(id, &bytes);
            prop_assert_eq!(std::format!("{fast:?}"), std::format!("{slow:?}"));
        }
        // A NavState-shaped payload: 42 fixed bytes, the home's tag (0, 1 or invalid), the
        // home, the flags.
        let mut nav = bytes.clone();
        nav.resize(42, 0x80);
        nav.push(tag);
        if tag == 1 {
            nav.extend_from_slice(&bytes.iter().copied().cycle().take(20).collect::<Vec<u8>>());
            nav.resize(63, 0);
        }
        nav.push(flags);
        let fast = Message::deserialize_payload(id::NAV_STATE, &nav);
        let slow = Message::deserialize_payload_postcard(id::NAV_STATE, &nav);
        prop_assert_eq!(std::format!("{fast:?}"), std::format!("{slow:?}"));
    }
}

/// The NavState flags byte: bits 0–2, any other bit makes the payload invalid.
#[test]
fn nav_state_flags_share_one_byte() {
    let nav = NavState {
        gps_ok: true,
        home_set: false,
        calibrated: true,
        ..Default::default()
    };
    let bytes = enc(&Message::NavState(nav), 1, 2);
    let mut dec = FrameDecoder::new();
    let Ok(f) = decode_all(&mut dec, &bytes)[0] else {
        panic!()
    };
    assert_eq!(f.message, Message::NavState(nav));
    let mut payload = std::vec![0u8; 42];
    payload.push(0); // no home
    payload.push(0b101);
    assert_eq!(
        Message::deserialize_payload(id::NAV_STATE, &payload),
        Ok(Message::NavState(NavState {
            gps_ok: true,
            calibrated: true,
            ..Default::default()
        }))
    );
    *payload.last_mut().unwrap() = 0b1000;
    assert_eq!(
        Message::deserialize_payload(id::NAV_STATE, &payload),
        Err(crate::messages::PayloadError::Invalid)
    );
}
