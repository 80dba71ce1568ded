//! Hard limits are enforced on the MCU whatever the mission computer asks for: speed, tilt,
//! geofence; and a GPS loss in flight ends in a landing on baro/accel.

mod common;

use fcc_firmware::commands::{FailsafeCause, Mode};
use fcc_sim::scenario::Fault;
use std::path::PathBuf;

fn mission_file(name: &str, text: &str) -> PathBuf {
    let p = std::env::temp_dir().join(format!("fcc-limits-{}-{name}.yaml", std::process::id()));
    std::fs::write(&p, text).unwrap();
    p
}

fn square_at(speed: f32) -> String {
    format!(
        "takeoff_alt_m: 5.0\nspeed_mps: {speed}\naccel_limit_mps2: 2.0\naccept_radius_m: 0.5\nhold_s: 1.0\nland_at_end: true\nwaypoints:\n  - {{north_m: 60.0, east_m: 0.0, alt_m: 5.0}}\n  - {{north_m: 0.0, east_m: 0.0, alt_m: 5.0}}\n"
    )
}

#[test]
fn speed_and_tilt_limits_hold_for_a_too_fast_mission() {
    let mut s = common::load("square");
    s.flight = fcc_sim::scenario::FlightPlan::Mission {
        mission_file: mission_file("fast", &square_at(12.0)),
    };
    s.params.limits.max_horiz_speed_mps = 5.0;
    s.params.limits.max_tilt_deg = 15.0;
    s.duration_s = 150.0;
    let log = common::fly_scenario(s);
    let vmax = log
        .samples
        .iter()
        .map(|x| x.true_vel_ned_mps[0].hypot(x.true_vel_ned_mps[1]))
        .fold(0.0, f64::max);
    let tilt_cmd_max = log
        .samples
        .iter()
        .map(|x| {
            (x.tel.roll_cmd_rad.powi(2) + x.tel.pitch_cmd_rad.powi(2))
                .sqrt()
                .to_degrees()
        })
        .fold(0.0f32, f32::max);
    println!("asked 12 m/s with a 5 m/s limit: fastest true ground speed {vmax:.2} m/s; largest tilt command {tilt_cmd_max:.1}° (limit 15°)");
    // 3 m/s of mean wind plus gusts can add to the airspeed-limited ground speed.
    assert!(vmax <= 5.0 + 1.0, "{vmax:.2} m/s");
    assert!(tilt_cmd_max <= 15.0 + 0.01);
    // The run ends at the disarm, so the last 50-Hz sample may still read armed: the event.
    let done_s = log
        .events
        .iter()
        .find(|(_, what)| what.starts_with("mission done"))
        .map(|(t, _)| *t);
    assert!(
        done_s.is_some_and(|d| log
            .events
            .iter()
            .any(|(t, what)| *t > d && what.starts_with("disarmed"))),
        "mission still completes and lands: {:?}",
        log.events
    );
}

#[test]
fn geofence_stops_the_vehicle_at_the_fence() {
    let mut s = common::load("square");
    s.flight = fcc_sim::scenario::FlightPlan::Mission {
        mission_file: mission_file("fence", &square_at(3.0)),
    };
    s.params.limits.fence_radius_m = 25.0;
    s.duration_s = 60.0;
    let log = common::fly_scenario(s);
    let rmax = log
        .samples
        .iter()
        .map(|x| x.nav.pos_ned_m[0].hypot(x.nav.pos_ned_m[1]))
        .fold(0.0f32, f32::max);
    let fenced = log
        .samples
        .iter()
        .any(|x| x.failsafe == FailsafeCause::Geofence);
    println!("waypoint 60 m out, fence 25 m: farthest estimated distance from home {rmax:.2} m, geofence reported: {fenced}");
    assert!(fenced);
    assert!(rmax <= 25.0 + 2.0, "{rmax:.2} m");
}

#[test]
fn gps_loss_in_flight_lands_on_baro_and_accel() {
    let mut s = common::load("hover");
    s.faults.push(Fault::GpsOutage {
        start_s: 40.0,
        end_s: 1e6,
    });
    let log = common::fly_scenario(s);
    let land = log
        .samples
        .iter()
        .find(|x| x.t_s > 40.0 && x.mode == Mode::Land)
        .expect("lands");
    let disarm = log
        .samples
        .iter()
        .find(|x| x.t_s > 40.0 && !x.armed)
        .expect("disarms");
    println!(
        "GPS lost at 40.0 s: land at {:.2} s ({:?}), disarmed at {:.2} s",
        land.t_s, land.failsafe, disarm.t_s
    );
    assert_eq!(land.failsafe, FailsafeCause::GpsLost);
    let timeout = fcc_firmware::params::NavParams::default().gps_timeout_s as f64;
    assert!(land.t_s - 40.0 <= timeout + 0.5);
    let gear = fcc_sim::physics::VehicleParams::default().gear_height_m;
    assert!((disarm.true_agl_m - gear).abs() < 0.06);
    // Altitude held on baro/accel while it descends under control: no hard impact.
    let contact = log
        .samples
        .iter()
        .filter(|x| x.t_s > land.t_s && x.t_s < disarm.t_s && x.true_agl_m - gear < 0.1)
        .map(|x| x.true_vel_ned_mps[2])
        .fold(0.0f64, f64::max);
    assert!(contact <= 0.5, "contact at {contact:.2} m/s");
    // On the simulator's truth: the dead-reckoned landing neither tips over nor strikes (it
    // did in 15 of 24 such hovers before LAND skipped the touchdown gate's wait without GPS).
    let t = fcc_sim::truth::report(&log);
    println!("truth: {:?}", t.contacts);
    assert!(!t.crashed, "crashed or tipped over: {:?}", t.contacts);
    assert_eq!(t.unplanned_contacts, 0, "{:?}", t.contacts);
}
