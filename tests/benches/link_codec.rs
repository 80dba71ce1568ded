//! Row 1 of BENCHMARKS.md (issue 9): link efficiency and codec speed of our frames (`fcc_msgs`)
//! against MAVLink v2 (the `mavlink` crate, common dialect). Run by `scripts/bench.sh`; alone:
//! `cargo bench -p fcc_tests --bench link_codec`.
//!
//! The telemetry is the MCU's real link output: `fcc_firmware::link::LinkEndpoint::poll_tx` at
//! `StreamRates::DEFAULT` on every tick of the simulated square flight (captured as in
//! `common/mod.rs`). Its frames are decoded, and the same content is mapped to the closest
//! MAVLink common messages (see `MAPPING`), which the `mavlink` crate encodes. Then, on the same
//! message sequence in the same run:
//! - bytes/s of each stream over the flight;
//! - encode: `fcc_msgs::encode` vs `mavlink::write_v2_msg`, both into one preallocated buffer;
//! - decode: `fcc_msgs::FrameDecoder::push_slice` vs `mavlink::MavlinkReader::read_message`
//!   (MAVLink 2, CRC checked, typed `MavMessage`), both over the whole byte stream.

mod common;

use common::{best_of_interleaved, capture, note, row, thousands, verdict};
use fcc_msgs::{
    encode, AltitudeFusion, Battery, FlightMode, FrameDecoder, HomePosition, Message, NavState,
    RangeSensor, Status, MAX_FRAME_LEN,
};
use mavlink::dialects::common as mav;
use mavlink::{MavHeader, MavlinkReader, MavlinkVersion};

const MAPPING: &str = "IMU_RAW 200 Hz + MAG_RAW 50 Hz → HIGHRES_IMU 200 Hz (gyro, accel, newest mag; fields_updated marks a new mag); BARO_RAW 50 Hz → SCALED_PRESSURE; GPS_RAW 10 Hz → GPS_RAW_INT (ground speed + course instead of our 3-D velocity, eph = our h_acc); RANGE_RAW laser + sonar 10 + 10 Hz → DISTANCE_SENSOR ×2; NAV_STATE 100 Hz → ATTITUDE_QUATERNION + LOCAL_POSITION_NED 100 Hz each, home → HOME_POSITION 1 Hz (our gravity-compensated NED acceleration has no MAVLink counterpart outside LOCAL_POSITION_NED_COV and is dropped); ALTITUDE_FUSION 50 Hz → ALTITUDE 50 Hz (vertical speed, variance, source, raw ranges dropped); STATUS 10 Hz → HEARTBEAT + SYS_STATUS 10 Hz (mode, armed, landed state, loop load, link error counters); BATTERY 5 Hz → folded into SYS_STATUS (voltage, current). Where MAVLink carries less, it is left with less: the byte ratio favours MAVLink. MAVLink v2 without signing, trailing-zero payload truncation as the crate does it.";

/// Map our decoded telemetry (in arrival order) to MAVLink messages carrying the same content.
fn to_mavlink(frames: &[(u64, Message)]) -> Vec<mav::MavMessage> {
    let mut out = Vec::new();
    let mut mag = [0.0f32; 3];
    let mut mag_new = false;
    let mut battery = Battery::default();
    let mut last_home_s: Option<u64> = None;
    let mut last_nav: Option<NavState> = None;
    // NavState carries the home about once a second; the last one stands.
    let mut home: Option<HomePosition> = None;
    for (t_us, m) in frames {
        let t_us = *t_us;
        let ms = (t_us / 1000) as u32;
        match m {
            Message::MagRaw(x) => {
                // µT → gauss
                mag = x.mag_frd_ut.map(|v| v * 0.01);
                mag_new = true;
            }
            Message::ImuRaw(x) => {
                use mav::HighresImuUpdatedFlags as F;
                let mut flags = F::HIGHRES_IMU_UPDATED_XACC
                    | F::HIGHRES_IMU_UPDATED_YACC
                    | F::HIGHRES_IMU_UPDATED_ZACC
                    | F::HIGHRES_IMU_UPDATED_XGYRO
                    | F::HIGHRES_IMU_UPDATED_YGYRO
                    | F::HIGHRES_IMU_UPDATED_ZGYRO;
                if mag_new {
                    flags |= F::HIGHRES_IMU_UPDATED_XMAG
                        | F::HIGHRES_IMU_UPDATED_YMAG
                        | F::HIGHRES_IMU_UPDATED_ZMAG;
                    mag_new = false;
                }
                out.push(mav::MavMessage::HIGHRES_IMU(mav::HIGHRES_IMU_DATA {
                    time_usec: t_us,
                    xacc: x.accel_frd_mps2[0],
                    yacc: x.accel_frd_mps2[1],
                    zacc: x.accel_frd_mps2[2],
                    xgyro: x.gyro_frd_radps[0],
                    ygyro: x.gyro_frd_radps[1],
                    zgyro: x.gyro_frd_radps[2],
                    xmag: mag[0],
                    ymag: mag[1],
                    zmag: mag[2],
                    fields_updated: flags,
                    ..mav::HIGHRES_IMU_DATA::DEFAULT
                }));
            }
            Message::BaroRaw(x) => out.push(mav::MavMessage::SCALED_PRESSURE(
                mav::SCALED_PRESSURE_DATA {
                    time_boot_ms: ms,
                    press_abs: x.pressure_pa * 0.01,
                    press_diff: 0.0,
                    temperature: (x.temperature_c * 100.0) as i16,
                },
            )),
            Message::GpsRaw(x) => {
                let v = x.vel_ned_mps;
                let speed = (v[0] * v[0] + v[1] * v[1]).sqrt();
                let cog = (v[1].atan2(v[0]).to_degrees() + 360.0) % 360.0;
                out.push(mav::MavMessage::GPS_RAW_INT(mav::GPS_RAW_INT_DATA {
                    time_usec: t_us,
                    lat: (x.lat_deg * 1e7).round() as i32,
                    lon: (x.lon_deg * 1e7).round() as i32,
                    alt: (x.alt_m * 1000.0) as i32,
                    eph: (x.h_acc_m * 100.0) as u16,
                    epv: u16::MAX,
                    vel: (speed * 100.0) as u16,
                    cog: (cog * 100.0) as u16,
                    fix_type: if x.fix_ok {
                        mav::GpsFixType::GPS_FIX_TYPE_3D_FIX
                    } else {
                        mav::GpsFixType::GPS_FIX_TYPE_NO_FIX
                    },
                    satellites_visible: x.num_sats,
                }));
            }
            Message::RangeRaw(x) => {
                let (kind, id, min_cm, max_cm) = match x.sensor {
                    RangeSensor::Laser => (
                        mav::MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
                        0,
                        20,
                        15_000,
                    ),
                    RangeSensor::Sonar => (
                        mav::MavDistanceSensor::MAV_DISTANCE_SENSOR_ULTRASOUND,
                        1,
                        20,
                        765,
                    ),
                };
                // MAVLink: "no return" is max_distance + 1.
                let cm = if x.range_m * 100.0 > max_cm as f32 {
                    max_cm + 1
                } else {
                    (x.range_m * 100.0).round() as u16
                };
                out.push(mav::MavMessage::DISTANCE_SENSOR(
                    mav::DISTANCE_SENSOR_DATA {
                        time_boot_ms: ms,
                        min_distance: min_cm,
                        max_distance: max_cm,
                        current_distance: cm,
                        mavtype: kind,
                        id,
                        orientation: mav::MavSensorOrientation::MAV_SENSOR_ROTATION_PITCH_270,
                        covariance: u8::MAX,
                    },
                ));
            }
            Message::Battery(x) => battery = *x,
            Message::NavState(x) => {
                last_nav = Some(*x);
                home = x.home.or(home);
                out.push(mav::MavMessage::ATTITUDE_QUATERNION(
                    mav::ATTITUDE_QUATERNION_DATA {
                        time_boot_ms: ms,
                        q1: x.q_body_to_ned[0],
                        q2: x.q_body_to_ned[1],
                        q3: x.q_body_to_ned[2],
                        q4: x.q_body_to_ned[3],
                        rollspeed: x.rate_frd_radps[0],
                        pitchspeed: x.rate_frd_radps[1],
                        yawspeed: x.rate_frd_radps[2],
                    },
                ));
                out.push(mav::MavMessage::LOCAL_POSITION_NED(
                    mav::LOCAL_POSITION_NED_DATA {
                        time_boot_ms: ms,
                        x: x.pos_ned_m[0],
                        y: x.pos_ned_m[1],
                        z: x.pos_ned_m[2],
                        vx: x.vel_ned_mps[0],
                        vy: x.vel_ned_mps[1],
                        vz: x.vel_ned_mps[2],
                    },
                ));
                let s = t_us / 1_000_000;
                if let Some(h) = home.filter(|_| x.home_set && last_home_s != Some(s)) {
                    last_home_s = Some(s);
                    out.push(mav::MavMessage::HOME_POSITION(mav::HOME_POSITION_DATA {
                        latitude: (h.lat_deg * 1e7).round() as i32,
                        longitude: (h.lon_deg * 1e7).round() as i32,
                        altitude: (h.alt_m * 1000.0) as i32,
                        q: [1.0, 0.0, 0.0, 0.0],
                        ..mav::HOME_POSITION_DATA::DEFAULT
                    }));
                }
            }
            Message::AltitudeFusion(AltitudeFusion {
                baro_alt_m,
                alt_m,
                ground_height_m,
                ..
            }) => {
                let home_alt = home.map_or(0.0, |h| h.alt_m);
                out.push(mav::MavMessage::ALTITUDE(mav::ALTITUDE_DATA {
                    time_usec: t_us,
                    altitude_monotonic: *baro_alt_m,
                    altitude_amsl: home_alt + alt_m,
                    altitude_local: *alt_m,
                    altitude_relative: *alt_m,
                    altitude_terrain: f32::NAN,
                    bottom_clearance: if ground_height_m.is_finite() {
                        *ground_height_m
                    } else {
                        -1.0
                    },
                }));
            }
            Message::Status(x) => {
                out.extend(status_to_mavlink(x, &battery, last_nav.as_ref()));
            }
            // Hello (once at start-up) and replies to requests: no counterpart needed here.
            _ => {}
        }
    }
    out
}

fn status_to_mavlink(
    x: &Status,
    battery: &Battery,
    nav: Option<&NavState>,
) -> [mav::MavMessage; 2] {
    use mav::MavModeFlag as M;
    use mav::MavSysStatusSensor as S;
    let mut base = M::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | M::MAV_MODE_FLAG_STABILIZE_ENABLED;
    if x.armed {
        base |= M::MAV_MODE_FLAG_SAFETY_ARMED;
    }
    if matches!(x.mode, FlightMode::Velocity) {
        base |= M::MAV_MODE_FLAG_GUIDED_ENABLED;
    }
    let hb = mav::MavMessage::HEARTBEAT(mav::HEARTBEAT_DATA {
        // custom_mode: mode | failsafe << 8 | landed << 16
        custom_mode: x.mode as u32 | (x.failsafe as u32) << 8 | (x.landed as u32) << 16,
        mavtype: mav::MavType::MAV_TYPE_OCTOROTOR,
        autopilot: mav::MavAutopilot::MAV_AUTOPILOT_GENERIC,
        base_mode: base,
        system_status: if x.armed {
            mav::MavState::MAV_STATE_ACTIVE
        } else {
            mav::MavState::MAV_STATE_STANDBY
        },
        mavlink_version: 3,
    });
    let present = S::MAV_SYS_STATUS_SENSOR_3D_GYRO
        | S::MAV_SYS_STATUS_SENSOR_3D_ACCEL
        | S::MAV_SYS_STATUS_SENSOR_3D_MAG
        | S::MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
        | S::MAV_SYS_STATUS_SENSOR_GPS
        | S::MAV_SYS_STATUS_SENSOR_LASER_POSITION;
    let mut health = present;
    if let Some(n) = nav {
        if !n.gps_ok {
            health.remove(S::MAV_SYS_STATUS_SENSOR_GPS);
        }
        if !n.calibrated {
            health.remove(S::MAV_SYS_STATUS_SENSOR_3D_GYRO);
        }
    }
    let l = &x.link_rx;
    let c16 = |v: u32| v.min(u16::MAX as u32) as u16;
    let ss = mav::MavMessage::SYS_STATUS(mav::SYS_STATUS_DATA {
        onboard_control_sensors_present: present,
        onboard_control_sensors_enabled: present,
        onboard_control_sensors_health: health,
        // ‰ of the 2 ms period
        load: c16(x.loop_time_avg_us / 2),
        voltage_battery: (battery.voltage_v * 1000.0) as u16,
        current_battery: (battery.current_a * 100.0) as i16,
        drop_rate_comm: c16(l.frames_lost),
        errors_comm: c16(l.crc_errors + l.framing_errors),
        errors_count1: c16(l.overruns),
        errors_count2: c16(l.decode_errors + l.unknown_ids),
        errors_count3: c16(x.tx_dropped),
        errors_count4: c16(x.setpoint_rejects + x.command_rejects),
        battery_remaining: -1,
    });
    [hb, ss]
}

fn main() {
    let cap = capture("square", true);
    assert_eq!(cap.telemetry_dropped, 0, "the link endpoint dropped frames");
    let ours_bytes = &cap.telemetry;
    let secs = cap.sim_s;

    // Decode our stream (also checks it).
    let mut dec = FrameDecoder::new();
    let frames: Vec<(u64, u16, Message)> = dec
        .push_slice(ours_bytes)
        .map(|r| {
            let f = r.expect("our own stream decodes");
            (f.header.t_us, f.header.seq, f.message)
        })
        .collect();
    let ours_msgs: Vec<(u64, Message)> = frames.iter().map(|(t, _, m)| (*t, *m)).collect();
    let mav_msgs = to_mavlink(&ours_msgs);
    let hdr = |i: usize| MavHeader {
        system_id: 1,
        component_id: 1,
        sequence: i as u8,
    };

    // The MAVLink stream.
    let mut mav_bytes = Vec::with_capacity(mav_msgs.len() * 80);
    for (i, m) in mav_msgs.iter().enumerate() {
        mavlink::write_v2_msg(&mut mav_bytes, hdr(i), m).expect("mavlink encode");
    }
    let ours_bps = ours_bytes.len() as f64 / secs;
    let mav_bps = mav_bytes.len() as f64 / secs;
    let byte_ratio = ours_bps / mav_bps;

    // Re-encoding our frames reproduces the link's bytes exactly (same encoder).
    let mut ours_buf = vec![0u8; ours_bytes.len() + MAX_FRAME_LEN];
    let mut n = 0;
    for (t, seq, m) in &frames {
        n += encode(m, *seq, *t, &mut ours_buf[n..]).unwrap();
    }
    assert_eq!(
        &ours_buf[..n],
        &ours_bytes[..],
        "re-encoding differs from the link output"
    );

    // Encode throughput.
    let reps = 15;
    let mut mav_buf = vec![0u8; mav_bytes.len() + 300];
    let (ours_enc, mav_enc) = best_of_interleaved(
        reps,
        || {
            let mut n = 0;
            for (t, seq, m) in &frames {
                n += encode(std::hint::black_box(m), *seq, *t, &mut ours_buf[n..]).unwrap();
            }
            n
        },
        || {
            let mut w: &mut [u8] = &mut mav_buf[..];
            let mut n = 0;
            for (i, m) in mav_msgs.iter().enumerate() {
                n += mavlink::write_v2_msg(&mut w, hdr(i), std::hint::black_box(m)).unwrap();
            }
            n
        },
    );

    // Decode throughput.
    let (ours_dec, mav_dec) = best_of_interleaved(
        reps,
        || {
            let mut d = FrameDecoder::new();
            let mut k = 0usize;
            for r in d.push_slice(std::hint::black_box(ours_bytes)) {
                if let Ok(f) = r {
                    std::hint::black_box(&f);
                    k += 1;
                }
            }
            assert_eq!(k, frames.len());
            k
        },
        || {
            let mut r = MavlinkReader::new(std::hint::black_box(&mav_bytes[..]));
            let mut k = 0usize;
            while let Ok((h, m)) = r.read_message::<mav::MavMessage>(MavlinkVersion::V2) {
                std::hint::black_box((&h, &m));
                k += 1;
            }
            assert_eq!(k, mav_msgs.len());
            k
        },
    );

    let rate = |count: usize, bytes: usize, s: f64| {
        format!(
            "{:.2} M msg/s, {:.0} MB/s",
            count as f64 / s / 1e6,
            bytes as f64 / s / 1e6
        )
    };
    row(
        "1a",
        "Link bytes/s, same telemetry at our default rates (square flight)",
        &format!(
            "{} B/s ({} frames/s)",
            thousands(ours_bps),
            thousands(frames.len() as f64 / secs)
        ),
        &format!(
            "MAVLink v2: {} B/s ({} msg/s)",
            thousands(mav_bps),
            thousands(mav_msgs.len() as f64 / secs)
        ),
        &format!("{byte_ratio:.2}"),
        "≤ 0.60× MAVLink's bytes",
        verdict(byte_ratio <= 0.6),
    );
    row(
        "1b",
        "Decode throughput, same telemetry (bytes → typed messages, CRC checked)",
        &rate(frames.len(), ours_bytes.len(), ours_dec),
        &format!(
            "mavlink crate: {}",
            rate(mav_msgs.len(), mav_bytes.len(), mav_dec)
        ),
        &format!("{:.2}× as fast", mav_dec / ours_dec),
        "≥ 2× MAVLink's decode throughput",
        verdict(mav_dec / ours_dec >= 2.0),
    );
    row(
        "1c",
        "Encode throughput, same telemetry (typed messages → bytes)",
        &rate(frames.len(), ours_bytes.len(), ours_enc),
        &format!(
            "mavlink crate: {}",
            rate(mav_msgs.len(), mav_bytes.len(), mav_enc)
        ),
        &format!("{:.2}× as fast", mav_enc / ours_enc),
        "— (no goal; for information)",
        "info",
    );
    note("1", &format!(
        "{:.0} s of the square flight: {} of our frames ({} B) vs {} MAVLink messages ({} B), the same content. Throughput ratios compare the wall time to process that same telemetry (MAVLink time ÷ ours), best of {reps} rounds, ours and MAVLink alternating in each; the msg/s figures count each side's own messages. Ours (link v6): COBS (decoded in place by hopping from code to code) + CRC-32C (the SSE4.2 `crc32` instruction here; slice-by-16 tables where a host lacks it) + postcard with fixed-point i16 fields where the resolution is known (IMU and magnetometer at the sensor's LSB, the navigation state's attitude, rates, velocity and accelerations: msg/src/fixed.rs), an 8 B header with the low 32 bits of the µs timestamp (12 B with all 64 on Hello and the 10 Hz Status), the home in one NavState a second. Mapping: {MAPPING}",
        secs,
        thousands(frames.len() as f64),
        thousands(ours_bytes.len() as f64),
        thousands(mav_msgs.len() as f64),
        thousands(mav_bytes.len() as f64),
    ));
}
