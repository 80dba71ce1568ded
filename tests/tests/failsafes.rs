//! Honest failsafes in the simulator: the mission computer falls silent in mid-leg; the MCU
//! holds within the setpoint time-to-live, then lands and disarms, and says why.

mod common;

use fcc_firmware::commands::{FailsafeCause, Mode};
use fcc_sim::scenario::Fault;

#[test]
fn silent_mission_computer_hold_then_land() {
    let mut s = common::load("square");
    let silent_from_s = 12.0; // on the first leg, at cruise speed
    s.faults.push(Fault::LinuxSilent {
        start_s: silent_from_s,
        end_s: 1e6,
    });
    let log = common::fly_scenario(s);
    let after: Vec<_> = log
        .samples
        .iter()
        .filter(|x| x.t_s >= silent_from_s)
        .collect();
    assert!(
        after[0].mode == Mode::Velocity,
        "flying the leg when the link goes silent"
    );
    let ttl_s = fcc_sim::linux::SETPOINT_TTL_MS as f64 * 1e-3;
    let hold = after.iter().find(|x| x.mode == Mode::Hold).expect("holds");
    let land = after.iter().find(|x| x.mode == Mode::Land).expect("lands");
    let disarm = after.iter().find(|x| !x.armed).expect("disarms");
    println!(
        "link silent at {silent_from_s:.2} s: hold at {:.2} s ({:?}), land at {:.2} s ({:?}), disarmed at {:.2} s",
        hold.t_s, hold.failsafe, land.t_s, land.failsafe, disarm.t_s
    );
    assert_eq!(hold.failsafe, FailsafeCause::SetpointStale);
    assert!(
        hold.t_s - silent_from_s <= ttl_s + 0.1,
        "held {:.2} s after the last setpoint",
        hold.t_s - silent_from_s
    );
    assert_eq!(land.failsafe, FailsafeCause::SetpointLost);
    let lost_s = fcc_firmware::params::LimitParams::default().setpoint_lost_land_s as f64;
    assert!(
        (land.t_s - silent_from_s - lost_s).abs() <= 0.3,
        "land after {:.2} s",
        land.t_s - silent_from_s
    );
    // Touchdown: on the ground, slow, then disarmed.
    let gear = fcc_sim::physics::VehicleParams::default().gear_height_m;
    assert!(
        (disarm.true_agl_m - gear).abs() < 0.06,
        "on the ground: {:.3} m",
        disarm.true_agl_m
    );
    let touchdown_speed = log
        .samples
        .iter()
        .filter(|x| x.t_s > land.t_s && x.t_s < disarm.t_s && x.true_agl_m - gear < 0.3)
        .map(|x| x.true_vel_ned_mps[2])
        .fold(0.0f64, f64::max);
    println!("vertical speed near touchdown ≤ {touchdown_speed:.2} m/s");
    assert!(touchdown_speed <= 0.5);
    // While holding it brakes from cruise speed and stays near the hold point: the overshoot
    // is bounded by the braking distance, and it is stopped by the time it starts landing.
    let p0 = hold.nav.pos_ned_m;
    let excursion = after
        .iter()
        .filter(|x| x.t_s >= hold.t_s && x.t_s < land.t_s)
        .map(|x| {
            ((x.nav.pos_ned_m[0] - p0[0]).powi(2) + (x.nav.pos_ned_m[1] - p0[1]).powi(2)).sqrt()
        })
        .fold(0.0f32, f32::max);
    // It came to a stop while holding (braking from cruise, then settling on the point).
    let min_speed = after
        .iter()
        .filter(|x| x.t_s >= hold.t_s && x.t_s < land.t_s)
        .map(|x| (x.true_vel_ned_mps[0].powi(2) + x.true_vel_ned_mps[1].powi(2)).sqrt())
        .fold(f64::MAX, f64::min);
    println!("hold: excursion from the hold point {excursion:.2} m, slowest {min_speed:.2} m/s");
    assert!(excursion < 2.0, "hold excursion {excursion:.2} m");
    assert!(min_speed < 0.3, "never stopped: {min_speed:.2} m/s");
}
