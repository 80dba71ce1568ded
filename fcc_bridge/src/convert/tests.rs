use super::*;
use fcc_msgs as link;

fn cfg() -> Config {
    Config::default()
}

fn st() -> Time {
    Time {
        sec: 100,
        nanosec: 5,
    }
}

#[test]
fn imu_raw_is_flu_without_orientation() {
    let m = imu_raw(
        &link::ImuRaw {
            gyro_frd_radps: [0.1, 0.2, 0.3],
            accel_frd_mps2: [0.0, 0.0, -9.81],
        },
        st(),
        &cfg(),
    );
    assert_eq!(m.orientation_covariance[0], -1.0);
    assert_eq!(m.header.stamp, st());
    assert!((m.angular_velocity.y + 0.2).abs() < 1e-6 && (m.angular_velocity.z + 0.3).abs() < 1e-6);
    assert!((m.linear_acceleration.z - 9.81).abs() < 1e-5);
}

#[test]
fn mag_is_tesla() {
    let m = mag(
        &link::MagRaw {
            mag_frd_ut: [50.0, 0.0, 0.0],
        },
        st(),
        &cfg(),
    );
    assert!((m.magnetic_field.x - 50e-6).abs() < 1e-12);
}

#[test]
fn laser_sentinel_is_inf() {
    let (r, laser) = range(
        &link::RangeRaw {
            sensor: link::RangeSensor::Laser,
            range_m: 99_999.0,
        },
        st(),
        &cfg(),
    );
    assert!(laser && r.range == f32::INFINITY);
    let (r, laser) = range(
        &link::RangeRaw {
            sensor: link::RangeSensor::Sonar,
            range_m: 2.0,
        },
        st(),
        &cfg(),
    );
    assert!(!laser && r.range == 2.0 && r.radiation_type == Range::ULTRASOUND);
}

#[test]
fn nav_state_enu() {
    let m = link::NavState {
        q_body_to_ned: [1.0, 0.0, 0.0, 0.0],
        pos_ned_m: [1.0, 2.0, -3.0],
        vel_ned_mps: [4.0, 0.0, 0.0],
        ..Default::default()
    };
    let (odom, _imu, tf) = nav_state(&m, st(), &cfg());
    let p = odom.pose.pose.position;
    assert_eq!((p.x, p.y, p.z), (2.0, 1.0, 3.0));
    // Facing north, flying north: body forward 4.
    assert!((odom.twist.twist.linear.x - 4.0).abs() < 1e-6);
    // REP-105: the odometry and the body's transform hang under `odom`.
    assert_eq!(odom.header.frame_id, "odom");
    assert_eq!(odom.child_frame_id, "base_link");
    assert_eq!(tf.transforms.len(), 1);
    assert_eq!(tf.transforms[0].header.frame_id, "odom");
    assert_eq!(tf.transforms[0].child_frame_id, "base_link");
    assert_eq!(tf.transforms[0].transform.translation.z, 3.0);
}

/// The TF tree is map → odom → base_link → sensors: `map → odom` is the static identity.
#[test]
fn static_tree_map_odom_then_sensors() {
    let tf = static_transforms(st(), &cfg());
    let edges: Vec<(&str, &str)> = tf
        .transforms
        .iter()
        .map(|t| (t.header.frame_id.as_str(), t.child_frame_id.as_str()))
        .collect();
    assert_eq!(
        edges,
        [
            ("map", "odom"),
            ("base_link", "imu_link"),
            ("base_link", "gps_link"),
            ("base_link", "laser_link"),
            ("base_link", "sonar_link"),
        ]
    );
    let m = &tf.transforms[0].transform;
    assert_eq!(m.translation.to_array(), [0.0; 3]);
    assert_eq!(
        [m.rotation.w, m.rotation.x, m.rotation.y, m.rotation.z],
        [1.0, 0.0, 0.0, 0.0]
    );
    assert!(tf.transforms.iter().all(|t| t.header.stamp == st()));
    // odom_frame:=map (the same name): no self-loop.
    let same = Config {
        odom_frame: "map".into(),
        ..cfg()
    };
    assert!(static_transforms(st(), &same)
        .transforms
        .iter()
        .all(|t| t.header.frame_id == "base_link"));
}

/// `clock_source:=mcu`: `/tf_static` is stamped with the MCU clock like every other topic, at
/// the first telemetry of each connection; with `sync` the state machine emits none (the IO
/// layer publishes it at start-up).
#[test]
fn mcu_clock_stamps_tf_static() {
    use crate::state::{ClockSource, LinkState, Out};
    let mut enc = link::Encoder::new();
    let mut buf = [0u8; link::MAX_FRAME_LEN];
    let mut frame = |m: link::Message, t: u64| {
        let n = enc.encode(&m, t, &mut buf).unwrap();
        buf[..n].to_vec()
    };
    let hello = frame(link::Message::Hello(link::Hello::ours([0, 1, 0])), 1);
    let mut imu = |t| frame(link::Message::ImuRaw(link::ImuRaw::default()), t);
    let (imu_a, imu_b, imu_c) = (imu(7_000_000), imu(7_005_000), imu(42_000));
    let linux_ns = 1_700_000_000_000_000_000;
    let mut s = LinkState::new(cfg(), SetpointLimits::default(), ClockSource::Mcu);
    s.on_bytes(&hello, linux_ns).unwrap();
    let out = s.on_bytes(&imu_a, linux_ns).unwrap();
    match &out[..] {
        [Out::TfStatic(tf), Out::ImuRaw(m)] => {
            assert_eq!(m.header.stamp.to_nanos(), 7_000_000_000);
            assert!(tf
                .transforms
                .iter()
                .all(|t| t.header.stamp.to_nanos() == 7_000_000_000));
            assert_eq!(tf.transforms[0].child_frame_id, "odom");
        }
        other => panic!("expected /tf_static then the IMU: {other:?}"),
    }
    let out = s.on_bytes(&imu_b, linux_ns).unwrap();
    assert!(matches!(&out[..], [Out::ImuRaw(_)]), "once: {out:?}");
    // A restarted MCU (time from 0 again): restamped on the new connection.
    s.reconnect();
    s.on_bytes(&hello, linux_ns).unwrap();
    let out = s.on_bytes(&imu_c, linux_ns).unwrap();
    assert!(
        matches!(&out[..], [Out::TfStatic(tf), Out::ImuRaw(_)]
            if tf.transforms[0].header.stamp.to_nanos() == 42_000_000),
        "{out:?}"
    );
    let mut s = LinkState::new(cfg(), SetpointLimits::default(), ClockSource::Sync);
    s.on_bytes(&hello, linux_ns).unwrap();
    let out = s.on_bytes(&imu_a, linux_ns).unwrap();
    assert!(matches!(&out[..], [Out::ImuRaw(_)]), "sync: {out:?}");
}

#[test]
fn altitude_up_positive() {
    let (a, g) = altitude(
        &link::AltitudeFusion {
            vel_down_mps: -1.5,
            ground_height_m: 4.0,
            laser_m: 99_999.0,
            ..Default::default()
        },
        st(),
        &cfg(),
    );
    assert_eq!(a.vertical_speed_mps, 1.5);
    assert_eq!(a.laser_range_m, f32::INFINITY);
    assert_eq!(g.range, 4.0);
}

fn ts(frame: &str, v: [f64; 3], stamp: Time) -> TwistStamped {
    TwistStamped {
        header: Header::new(stamp, frame),
        twist: Twist {
            linear: Vector3::new(v),
            angular: Vector3::default(),
        },
    }
}

#[test]
fn setpoints() {
    let lim = SetpointLimits::default();
    let now = 1_000_000_000_000;
    let sp = setpoint(
        &ts("map", [1.0, 2.0, 0.5], Time::default()),
        now,
        None,
        None,
        &cfg(),
        &lim,
    )
    .unwrap();
    assert_eq!(sp.vel_ned_mps, [2.0, 1.0, -0.5]);
    assert_eq!(sp.ttl_ms, 300);
    assert_eq!(sp.yaw, link::YawSetpoint::Keep);
    let sp = setpoint(
        &ts("", [0.0, 1.0, 0.0], Time::default()),
        now,
        None,
        None,
        &cfg(),
        &lim,
    )
    .unwrap();
    assert_eq!(sp.vel_ned_mps, [1.0, 0.0, 0.0]);
    // base_link needs a heading.
    assert_eq!(
        setpoint(
            &ts("base_link", [1.0, 0.0, 0.0], Time::default()),
            now,
            None,
            None,
            &cfg(),
            &lim
        ),
        Err(SetpointReject::NoHeading)
    );
    let sp = setpoint(
        &ts("base_link", [1.0, 0.0, 0.0], Time::default()),
        now,
        Some(std::f64::consts::FRAC_PI_2),
        None,
        &cfg(),
        &lim,
    )
    .unwrap();
    assert!((sp.vel_ned_mps[1] - 1.0).abs() < 1e-6 && sp.vel_ned_mps[0].abs() < 1e-6);
    // Refusals.
    assert_eq!(
        setpoint(
            &ts("map", [f64::NAN, 0.0, 0.0], Time::default()),
            now,
            None,
            None,
            &cfg(),
            &lim
        ),
        Err(SetpointReject::NotFinite)
    );
    assert!(matches!(
        setpoint(
            &ts("map", [0.0, 0.0, 1e6], Time::default()),
            now,
            None,
            None,
            &cfg(),
            &lim
        ),
        Err(SetpointReject::TooLarge(_))
    ));
    assert!(matches!(
        setpoint(
            &ts("camera", [0.0; 3], Time::default()),
            now,
            None,
            None,
            &cfg(),
            &lim
        ),
        Err(SetpointReject::UnknownFrame(_))
    ));
    let old = Time::from_nanos(now - 2_000_000_000);
    assert!(matches!(
        setpoint(&ts("map", [0.0; 3], old), now, None, None, &cfg(), &lim),
        Err(SetpointReject::Stale { .. })
    ));
    let future = Time::from_nanos(now + 2_000_000_000);
    assert!(matches!(
        setpoint(&ts("map", [0.0; 3], future), now, None, None, &cfg(), &lim),
        Err(SetpointReject::Future { .. })
    ));
    let fresh = Time::from_nanos(now - 100_000_000);
    assert!(setpoint(&ts("map", [0.0; 3], fresh), now, None, None, &cfg(), &lim).is_ok());
}

fn ts_yaw(frame: &str, yaw_rate_z_up: f64) -> TwistStamped {
    let mut m = ts(frame, [1.0, 0.0, 0.0], Time::default());
    m.twist.angular = Vector3::new([0.0, 0.0, yaw_rate_z_up]);
    m
}

/// `angular.z` (z up, CCW) → a NED yaw-rate setpoint (−z), in the world and body frames; with
/// no rate, the latest heading or Keep; an absurd rate refused.
#[test]
fn setpoint_yaw_rate_and_heading() {
    let lim = SetpointLimits::default();
    let now = 1_000_000_000_000;
    let go =
        |m: &TwistStamped, heading: Option<f64>| setpoint(m, now, Some(0.0), heading, &cfg(), &lim);
    let rate = |r: f32| link::YawSetpoint::Rate {
        yaw_rate_ned_radps: r,
    };
    assert_eq!(go(&ts_yaw("map", 0.3), None).unwrap().yaw, rate(-0.3));
    assert_eq!(go(&ts_yaw("base_link", -0.5), None).unwrap().yaw, rate(0.5));
    // A rate wins over a heading; no rate carries the heading; nothing = keep.
    assert_eq!(go(&ts_yaw("map", 0.3), Some(1.0)).unwrap().yaw, rate(-0.3));
    assert_eq!(
        go(&ts_yaw("map", 0.0), Some(1.0)).unwrap().yaw,
        link::YawSetpoint::Heading { yaw_ned_rad: 1.0 }
    );
    assert_eq!(
        go(&ts_yaw("map", 0.0), None).unwrap().yaw,
        link::YawSetpoint::Keep
    );
    assert!(matches!(
        go(&ts_yaw("map", 7.0), None),
        Err(SetpointReject::YawRateTooLarge(_))
    ));
    assert_eq!(
        go(&ts_yaw("map", f64::INFINITY), None),
        Err(SetpointReject::NotFinite)
    );
}

fn qs(frame: &str, q_wxyz: [f64; 4]) -> QuaternionStamped {
    QuaternionStamped {
        header: Header::new(Time::default(), frame),
        quaternion: Quaternion::from_wxyz(q_wxyz),
    }
}

/// `setpoint/heading`: ENU orientation → NED yaw (REP-103 yaw 0 = east = NED 90°); bad input
/// refused with its reason.
#[test]
fn heading_from_quaternion() {
    let lim = SetpointLimits::default();
    let now = 1_000_000_000_000;
    let about_z = |deg: f64| {
        let h = 0.5 * deg.to_radians();
        [h.cos(), 0.0, 0.0, h.sin()]
    };
    let h = |m: &QuaternionStamped| heading(m, now, &cfg(), &lim);
    for (enu_deg, ned_deg, frame) in [
        (0.0, 90.0, "map"),
        (90.0, 0.0, "odom"),
        (180.0, -90.0, ""),
        (-45.0, 135.0, "/map"),
    ] {
        let y = h(&qs(frame, about_z(enu_deg))).unwrap();
        assert!(
            (fcc_ros::frames::wrap_pi(y - f64::to_radians(ned_deg))).abs() < 1e-9,
            "ENU {enu_deg}° → NED {}°",
            y.to_degrees()
        );
    }
    // Roll and pitch are ignored: only the yaw counts.
    let tilted = fcc_ros::frames::quat_mul(about_z(0.0), [0.98f64.sqrt(), 0.1, 0.1, 0.0]);
    assert!((h(&qs("map", tilted)).unwrap() - std::f64::consts::FRAC_PI_2).abs() < 0.05);
    assert_eq!(
        h(&qs("map", [f64::NAN, 0.0, 0.0, 1.0])),
        Err(SetpointReject::NotFinite)
    );
    assert!(matches!(
        h(&qs("map", [0.0, 0.0, 0.0, 0.0])),
        Err(SetpointReject::NotUnitQuaternion(n)) if n == 0.0
    ));
    assert!(matches!(
        h(&qs("map", [2.0, 0.0, 0.0, 0.0])),
        Err(SetpointReject::NotUnitQuaternion(_))
    ));
    assert!(matches!(
        h(&qs("base_link", about_z(0.0))),
        Err(SetpointReject::HeadingFrame(_))
    ));
    assert!(matches!(
        h(&qs("camera", about_z(0.0))),
        Err(SetpointReject::HeadingFrame(_))
    ));
    let mut old = qs("map", about_z(0.0));
    old.header.stamp = Time::from_nanos(now - 2_000_000_000);
    assert!(matches!(h(&old), Err(SetpointReject::Stale { .. })));
}

#[test]
fn commands() {
    assert_eq!(
        arm_command(&Bool { data: true }).command,
        link::CommandKind::Arm
    );
    assert_eq!(
        arm_command(&Bool { data: false }).command,
        link::CommandKind::Disarm
    );
    let m = |s: &str| mode_command(&StringMsg { data: s.into() }).map(|c| c.command);
    assert_eq!(m("HOLD"), Some(link::CommandKind::Hold));
    assert_eq!(m("land"), Some(link::CommandKind::Land));
    assert_eq!(m(" velocity "), Some(link::CommandKind::Velocity));
    assert_eq!(m("acro"), None);
}

/// The state machine: nothing is published before the Hello; a bad schema is fatal.
#[test]
fn state_handshake_and_publish() {
    use crate::state::{ClockSource, Fatal, LinkState, Out};
    let mut s = LinkState::new(cfg(), SetpointLimits::default(), ClockSource::Sync);
    let mut enc = link::Encoder::new();
    let mut buf = [0u8; link::MAX_FRAME_LEN];
    let mut frame = |m: link::Message, t: u64| {
        let n = enc.encode(&m, t, &mut buf).unwrap();
        buf[..n].to_vec()
    };
    let imu = frame(link::Message::ImuRaw(link::ImuRaw::default()), 10);
    assert!(s.on_bytes(&imu, 0).unwrap().is_empty());
    assert_eq!(s.counters.dropped, 1);
    let hello = frame(link::Message::Hello(link::Hello::ours([0, 1, 0])), 11);
    s.on_bytes(&hello, 0).unwrap();
    let imu = frame(link::Message::ImuRaw(link::ImuRaw::default()), 12);
    let out = s.on_bytes(&imu, 5_000).unwrap();
    // Not synced yet: stamped by arrival.
    assert!(matches!(&out[..], [Out::ImuRaw(m)] if m.header.stamp.to_nanos() == 5_000));
    // Synced: MCU 1000 µs ↔ Linux 1e9 ns.
    let pong = link::TimeSyncPong {
        linux_time_ns: 999_000_000,
        mcu_rx_time_us: 1000,
        mcu_tx_time_us: 1000,
    };
    s.on_bytes(
        &frame(link::Message::TimeSyncPong(pong), 1000),
        1_001_000_000,
    )
    .unwrap();
    let out = s
        .on_bytes(
            &frame(link::Message::ImuRaw(link::ImuRaw::default()), 2000),
            0,
        )
        .unwrap();
    assert!(matches!(&out[..], [Out::ImuRaw(m)] if m.header.stamp.to_nanos() == 1_001_000_000));
    // Garbage is counted, not fatal.
    s.on_bytes(&[1, 2, 3, 0], 0).unwrap();
    assert_eq!(s.link_totals().resyncs, 1);
    // Wrong schema → fatal.
    let bad = frame(
        link::Message::Hello(link::Hello {
            protocol_version: link::PROTOCOL_VERSION,
            schema_hash: 1,
            firmware_version: [0; 3],
        }),
        0,
    );
    assert!(matches!(s.on_bytes(&bad, 0), Err(Fatal::Handshake(_))));
}

/// Paper A Fig. 13 topics: observer (horizontal) and measured acceleration, NED → ENU in `map`.
#[test]
fn accels_enu_in_map() {
    let m = link::NavState {
        q_body_to_ned: [1.0, 0.0, 0.0, 0.0],
        accel_ned_mps2: [1.0, -2.0, 0.5],
        accel_obs_ne_mps2: [0.25, -0.75],
        ..Default::default()
    };
    let (obs, meas) = accels(&m, st(), &cfg());
    assert_eq!(obs.header.frame_id, "map");
    assert_eq!(meas.header.frame_id, "map");
    assert_eq!(obs.header.stamp, st());
    // Observer: x = east, y = north, z = 0.
    assert_eq!(obs.accel.linear.to_array(), [-0.75, 0.25, 0.0]);
    // Measured: east −2, north 1, up −0.5 (NED down +0.5).
    assert_eq!(meas.accel.linear.to_array(), [-2.0, 1.0, -0.5]);
    assert_eq!(meas.accel.angular.to_array(), [0.0; 3]);
}

/// The MCU's sensor health reaches `fcc_msgs/Status`.
#[test]
fn status_carries_sensor_health() {
    let m = link::Status {
        sensors: link::SensorHealth {
            gps_ok: false,
            mag_disturbed: true,
            mag_rejects: 42,
            laser_ok: false,
            sonar_ok: true,
            mag_disturbed_ds: 0,
            nav_faults: 0,
        },
        ..Default::default()
    };
    let s = status(&m, st(), &cfg());
    assert!(!s.gps_ok && s.mag_disturbed && !s.laser_ok && s.sonar_ok);
    assert_eq!(s.mag_rejects, 42);
}

#[test]
fn status_pilot_mode_and_reject() {
    let m = link::Status {
        mode: link::FlightMode::Pilot,
        last_reject: link::CommandResult::PilotOverride,
        ..Default::default()
    };
    let s = status(&m, st(), &cfg());
    assert_eq!(
        (s.mode, s.mode_name.as_str()),
        (Status::MODE_PILOT, "pilot")
    );
    assert_eq!(s.last_reject, "pilot_override");
}

/// Sensor-health rules and `/rosout` transitions: one WARN per episode (a flickering flag does
/// not repeat it), an INFO after 2 s healthy; rangefinders only count in the air within range.
#[test]
fn sensor_watch_transitions() {
    use crate::diag::sensors_status;
    use crate::health::{unhealthy, SensorWatch};
    let c = cfg();
    let mut s = link::Status {
        armed: true,
        landed: false,
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
    };
    let mut w = SensorWatch::default();
    assert!(w.update(&s, Some(5.0), &c, 1_000_000).is_empty());
    // GPS lost → one WARN.
    s.sensors.gps_ok = false;
    let e = w.update(&s, Some(5.0), &c, 1_100_000);
    assert_eq!(e.len(), 1);
    assert!(e[0].0 && e[0].1.contains("GPS lost"), "{e:?}");
    assert!(w.update(&s, Some(5.0), &c, 1_200_000).is_empty());
    let d = sensors_status(&s, Some(5.0), &c, "dev");
    assert_eq!(d.level, DiagnosticStatus::WARN);
    assert!(d.message.contains("GPS lost"));
    // Back: INFO only after 2 s healthy.
    s.sensors.gps_ok = true;
    assert!(w.update(&s, Some(5.0), &c, 2_000_000).is_empty());
    let e = w.update(&s, Some(5.0), &c, 3_300_000);
    assert_eq!(e.len(), 1);
    assert!(!e[0].0 && e[0].1.contains("GPS ok"), "{e:?}");
    assert_eq!(
        sensors_status(&s, Some(5.0), &c, "dev").level,
        DiagnosticStatus::OK
    );
    // A flickering magnetometer flag: one WARN.
    let mut warns = 0;
    for k in 0..40u64 {
        s.sensors.mag_disturbed = k % 3 != 0;
        warns += w
            .update(&s, Some(5.0), &c, 4_000_000 + k * 100_000)
            .iter()
            .filter(|e| e.0)
            .count();
    }
    assert_eq!(warns, 1);
    s.sensors.mag_disturbed = false;
    // Laser: not a fault on the ground or below its minimum range; a fault at 5 m in the air.
    s.sensors.laser_ok = false;
    s.landed = true;
    assert_eq!(unhealthy(&s, Some(0.3), &c), [false; 5]);
    s.landed = false;
    assert_eq!(unhealthy(&s, Some(0.3), &c), [false; 5]);
    assert_eq!(
        unhealthy(&s, Some(5.0), &c),
        [false, false, true, false, false]
    );
    // Sonar above its range (10.68 m): no fault; below: a fault.
    s.sensors.laser_ok = true;
    s.sensors.sonar_ok = false;
    assert_eq!(unhealthy(&s, Some(20.0), &c), [false; 5]);
    assert_eq!(
        unhealthy(&s, Some(5.0), &c),
        [false, false, false, true, false]
    );
    // Disarmed: rangefinders are not checked.
    s.armed = false;
    assert_eq!(unhealthy(&s, Some(5.0), &c), [false; 5]);
    // A diverged filter is a fault in any state, named in the text.
    s.sensors.nav_faults = 2;
    assert_eq!(
        unhealthy(&s, Some(5.0), &c),
        [false, false, false, false, true]
    );
    let d = crate::diag::sensors_status(&s, Some(5.0), &c, "fcc");
    assert_eq!(d.level, DiagnosticStatus::WARN);
    assert!(d
        .values
        .iter()
        .any(|kv| kv.key == "nav_faults" && kv.value == "horizontal"));
}

/// A rebooted MCU says Hello again with its sequence from 0: one sequence reset, not thousands
/// of lost frames; real gaps are still counted, and a reconnect starts the tracking afresh.
#[test]
fn state_new_mcu_session_is_not_loss() {
    use crate::state::{ClockSource, LinkState};
    let mut s = LinkState::new(cfg(), SetpointLimits::default(), ClockSource::Sync);
    let frame = |m: link::Message, seq: u16| {
        let mut buf = [0u8; link::MAX_FRAME_LEN];
        let n = link::encode(&m, seq, 1, &mut buf).unwrap();
        buf[..n].to_vec()
    };
    let hello = || link::Message::Hello(link::Hello::ours([0, 1, 0]));
    let imu = || link::Message::ImuRaw(link::ImuRaw::default());
    // First MCU session: seq 44530…, one real gap of 2 frames.
    let mut bytes = frame(hello(), 44_530);
    for seq in [44_531, 44_532, 44_535] {
        bytes.extend(frame(imu(), seq));
    }
    s.on_bytes(&bytes, 0).unwrap();
    let t = s.link_totals();
    assert_eq!((t.seq_gaps, t.frames_lost, t.seq_resets), (1, 2, 0));
    // The MCU reboots: Hello from seq 0 (20999 "missing" by the numbers), then one real loss.
    let mut bytes = frame(hello(), 0);
    for seq in [1, 3] {
        bytes.extend(frame(imu(), seq));
    }
    for b in &bytes {
        s.on_bytes(std::slice::from_ref(b), 0).unwrap();
    }
    let t = s.link_totals();
    assert_eq!(
        (t.seq_gaps, t.frames_lost, t.seq_resets),
        (2, 3, 1),
        "{t:?}"
    );
    assert_eq!(s.fill_status(Default::default()).frames_lost, 3);
    // Reconnect: totals kept, the new decoder starts with nothing forgiven.
    s.reconnect();
    let t2 = s.link_totals();
    assert_eq!((t2.seq_gaps, t2.frames_lost, t2.seq_resets), (2, 3, 1));
    let mut bytes = frame(hello(), 7);
    bytes.extend(frame(imu(), 9));
    s.on_bytes(&bytes, 0).unwrap();
    let t3 = s.link_totals();
    assert_eq!(
        (t3.seq_gaps, t3.frames_lost, t3.seq_resets),
        (3, 4, 1),
        "{t3:?}"
    );
}

/// Hostile setpoints: a 1 MB frame_id is refused with its size, never echoed whole; control
/// characters in an unknown frame are escaped; a NaN flood is counted in full while its warning
/// goes out once per second with the number suppressed.
#[test]
fn state_bounded_refusals_and_rate_limited_warnings() {
    use crate::bounded::{LOG_CHARS, MAX_FRAME_ID};
    use crate::state::{ClockSource, Handshake, LinkState};
    let mut s = LinkState::new(cfg(), SetpointLimits::default(), ClockSource::Sync);
    s.handshake = Handshake::Ok {
        firmware: [0, 1, 0],
    };
    let sp = |frame: &str, vx: f64| TwistStamped {
        header: Header {
            stamp: Time::default(),
            frame_id: frame.into(),
        },
        twist: Twist {
            linear: Vector3 {
                x: vx,
                y: 0.0,
                z: 0.0,
            },
            angular: Vector3::default(),
        },
    };
    let t0 = 1_000_000_000_000i64;
    assert!(s.on_setpoint(&sp("map", 1.0), t0).is_some());
    // 1 MB frame_id: refused by size (also without the arrival cut), the reason stays small.
    let big = "A".repeat(1 << 20);
    assert!(s.on_setpoint(&sp(&big, 1.0), t0).is_none());
    assert_eq!(
        s.counters.last_setpoint_reject,
        format!("frame_id too long (1048576 B > {MAX_FRAME_ID} B)")
    );
    // Unknown frame with terminal escapes and a newline: shown escaped and cut.
    let evil = format!("x\n\x1b[2J{}", "z".repeat(200));
    assert!(s.on_setpoint(&sp(&evil, 1.0), t0).is_none());
    let r = &s.counters.last_setpoint_reject;
    assert!(!r.contains(['\n', '\x1b']), "{r:?}");
    assert!(r.contains("x\\n\\u{1b}[2J"), "{r}");
    assert!(r.len() < 2 * LOG_CHARS + 100, "{} B: {r}", r.len());
    // NaN flood: 1000 setpoints over 2 s (every 2 ms).
    let before = s.counters.setpoint_rejects;
    for i in 0..1000 {
        assert!(s
            .on_setpoint(&sp("map", f64::NAN), t0 + i * 2_000_000)
            .is_none());
    }
    assert_eq!(s.counters.setpoint_rejects - before, 1000);
    // Logged at t0, t0 + 1 s; the 499 after the second one are waiting to be reported.
    assert_eq!(s.warn.pending("setpoint_not_finite"), 499);
    assert_eq!(
        s.warn.check("setpoint_not_finite", t0 + 3_000_000_000),
        Some(499)
    );
    // A long or odd mode text is no mode.
    let m = |t: &str| mode_command(&StringMsg { data: t.into() });
    assert!(m(&"hold ".repeat(1000)).is_none());
    assert!(s.on_command(None, "\u{1b}]0;pwned\u{7}").is_none());
    assert_eq!(s.counters.command_rejects, 1);
}

/// `cmd/kill` needs exactly `KILL`: anything else (a mode name, lower case, padding) is no kill.
#[test]
fn kill_needs_its_exact_text() {
    let s = |d: &str| StringMsg { data: d.into() };
    let k = kill_command(&s("KILL")).expect("KILL is the kill");
    assert_eq!(k.command, link::CommandKind::Kill);
    assert_eq!(k.confirm, link::KILL_CONFIRM);
    for bad in ["kill", " KILL", "KILL ", "disarm", "", "KILLKILL"] {
        assert!(kill_command(&s(bad)).is_none(), "{bad:?}");
    }
}

/// The status codes and names the bridge publishes are the `.msg` file's constants: every
/// failsafe cause and mode of the link maps to `FAILSAFE_<NAME>` / `MODE_<NAME>` with the same
/// value in `msg/msg/Status.msg` (the interface package other ROS nodes build against).
#[test]
fn status_codes_match_the_msg_constants() {
    use fcc_msgs::ros::RosMsg;
    let def = Status::DEFINITION;
    let constant = |name: &str| -> Option<u8> {
        def.lines().find_map(|l| {
            let l = l.split('#').next()?.trim();
            let rest = l.strip_prefix("uint8 ")?;
            let (n, v) = rest.split_once('=')?;
            (n.trim() == name).then(|| v.trim().parse().ok())?
        })
    };
    let causes = [
        link::FailsafeCause::None,
        link::FailsafeCause::SetpointStale,
        link::FailsafeCause::SetpointLost,
        link::FailsafeCause::Geofence,
        link::FailsafeCause::GpsLost,
        link::FailsafeCause::WindLimit,
        link::FailsafeCause::EstimatorFault,
        link::FailsafeCause::EmergencyKill,
    ];
    for c in causes {
        let (code, name) = failsafe_code(c);
        let key = format!("FAILSAFE_{}", name.to_ascii_uppercase());
        assert_eq!(constant(&key), Some(code), "{c:?}: {key}");
        assert!(def.contains(name), "failsafe_name comment lists {name}");
    }
    let modes = [
        link::FlightMode::Disarmed,
        link::FlightMode::Hold,
        link::FlightMode::Velocity,
        link::FlightMode::Land,
        link::FlightMode::Pilot,
    ];
    for m in modes {
        let (code, name) = mode_code(m);
        let key = format!("MODE_{}", name.to_ascii_uppercase());
        assert_eq!(constant(&key), Some(code), "{m:?}: {key}");
    }
}

/// The heading policy of the bridge: a `setpoint/heading` rides on the velocity setpoints that
/// follow; a yaw-rate setpoint wins and clears it; it is dropped after HEADING_MAX_AGE_NS; an
/// invalid heading is refused, counted and clears the kept one.
#[test]
fn state_heading_rides_on_setpoints_until_a_turn_or_its_age() {
    use crate::state::{ClockSource, Handshake, LinkState};
    let mut s = LinkState::new(cfg(), SetpointLimits::default(), ClockSource::Sync);
    s.handshake = Handshake::Ok {
        firmware: [0, 1, 0],
    };
    let mut t = 1_000_000_000_000i64;
    let mut yaw_of = |s: &mut LinkState, z: f64| {
        t += 20_000_000; // past the uplink's spacing: every setpoint goes at once
        match s.on_setpoint(&ts_yaw("map", z), t) {
            Some(link::Message::VelocitySetpoint(sp)) => (sp.yaw, t),
            other => panic!("{other:?}"),
        }
    };
    let (yaw, now) = yaw_of(&mut s, 0.0);
    assert_eq!(yaw, link::YawSetpoint::Keep);
    // East in ENU (identity) = NED 90°.
    s.on_heading(&qs("map", [1.0, 0.0, 0.0, 0.0]), now);
    let east = link::YawSetpoint::Heading {
        yaw_ned_rad: std::f32::consts::FRAC_PI_2,
    };
    assert_eq!(yaw_of(&mut s, 0.0).0, east);
    assert_eq!(yaw_of(&mut s, 0.0).0, east);
    // A turn: rate, and the heading is gone afterwards.
    assert_eq!(
        yaw_of(&mut s, 0.2).0,
        link::YawSetpoint::Rate {
            yaw_rate_ned_radps: -0.2
        }
    );
    assert_eq!(yaw_of(&mut s, 0.0).0, link::YawSetpoint::Keep);
    // Dropped after its age.
    let (_, now) = yaw_of(&mut s, 0.0);
    s.on_heading(&qs("map", [1.0, 0.0, 0.0, 0.0]), now);
    assert_eq!(yaw_of(&mut s, 0.0).0, east);
    for _ in 0..(HEADING_MAX_AGE_NS / 20_000_000) {
        yaw_of(&mut s, 0.0);
    }
    assert_eq!(yaw_of(&mut s, 0.0).0, link::YawSetpoint::Keep);
    assert_eq!(
        (
            s.counters.headings_received,
            s.counters.yaw_rate_setpoints,
            s.counters.setpoint_rejects
        ),
        (2, 1, 0)
    );
    // A bad heading: refused, counted, and the kept one dropped.
    let (_, now) = yaw_of(&mut s, 0.0);
    s.on_heading(&qs("map", [1.0, 0.0, 0.0, 0.0]), now);
    s.on_heading(&qs("map", [f64::NAN, 0.0, 0.0, 0.0]), now);
    assert_eq!(s.counters.setpoint_rejects, 1);
    assert!(
        s.counters.last_setpoint_reject.starts_with("heading: "),
        "{}",
        s.counters.last_setpoint_reject
    );
    assert_eq!(yaw_of(&mut s, 0.0).0, link::YawSetpoint::Keep);
}

/// `home` is published once the MCU sets home, again only when it moves (latched topic), in
/// `map`, with the MCU's latitude, longitude and altitude.
#[test]
fn home_published_when_set_and_when_moved() {
    use crate::state::{ClockSource, LinkState, Out};
    let mut s = LinkState::new(cfg(), SetpointLimits::default(), ClockSource::Mcu);
    let mut enc = link::Encoder::new();
    let mut buf = [0u8; link::MAX_FRAME_LEN];
    let mut frame = |m: link::Message, t: u64| {
        let n = enc.encode(&m, t, &mut buf).unwrap();
        buf[..n].to_vec()
    };
    s.on_bytes(
        &frame(link::Message::Hello(link::Hello::ours([0, 1, 0])), 1),
        0,
    )
    .unwrap();
    let nav = |home_set: bool, lat: f64| link::NavState {
        q_body_to_ned: [1.0, 0.0, 0.0, 0.0],
        home: Some(link::HomePosition {
            lat_deg: lat,
            lon_deg: 8.545_594,
            alt_m: 488.5,
        }),
        home_set,
        ..Default::default()
    };
    let mut homes = |m: link::NavState, t: u64| -> Vec<NavSatFix> {
        let out = s
            .on_bytes(&frame(link::Message::NavState(m), t), 0)
            .unwrap();
        out.into_iter()
            .filter_map(|o| match o {
                Out::Home(h) => Some(h),
                _ => None,
            })
            .collect()
    };
    assert!(homes(nav(false, 47.0), 10).is_empty(), "not set yet");
    let h = homes(nav(true, 47.397_742), 20);
    assert_eq!(h.len(), 1);
    assert_eq!(h[0].header.frame_id, "map");
    assert_eq!(
        (h[0].latitude, h[0].longitude, h[0].altitude),
        (47.397_742, 8.545_594, 488.5)
    );
    assert!(homes(nav(true, 47.397_742), 30).is_empty(), "unchanged");
    let without = link::NavState {
        home: None,
        ..nav(true, 47.4)
    };
    assert!(homes(without, 35).is_empty(), "this frame carries no home");
    assert_eq!(homes(nav(true, 47.4), 40).len(), 1, "moved");
}
