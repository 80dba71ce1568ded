//! Paper A's flight tests in the simulator (issue: flight core acceptance). Each test flies a
//! scenario from `launch_configs/scenarios/` with its fixed seed, prints the figure the paper
//! reports, and checks the acceptance threshold.

mod common;

use fcc_sim::metrics;
use std::sync::OnceLock;

fn hover() -> &'static fcc_sim::log::FlightLog {
    static LOG: OnceLock<fcc_sim::log::FlightLog> = OnceLock::new();
    LOG.get_or_init(|| common::fly("hover"))
}

fn square() -> &'static fcc_sim::log::FlightLog {
    static LOG: OnceLock<fcc_sim::log::FlightLog> = OnceLock::new();
    LOG.get_or_init(|| common::fly("square"))
}

fn yaw_disturbance() -> &'static fcc_sim::log::FlightLog {
    static LOG: OnceLock<fcc_sim::log::FlightLog> = OnceLock::new();
    LOG.get_or_init(|| common::fly("yaw_disturbance"))
}

#[test]
fn hover_100s_stays_in_half_the_papers_box() {
    let h = metrics::hover_box(hover()).expect("the hover scenario must reach its hold");
    println!("{h}");
    assert!(h.duration_s >= 99.0, "hold lasted {:.1} s", h.duration_s);
    // Half of paper A's box (N 0.7, E 1.1, alt 0.3 m) on the estimated position.
    assert!(h.est_max_m[0] <= 0.35, "north {:.3} m", h.est_max_m[0]);
    assert!(h.est_max_m[1] <= 0.55, "east {:.3} m", h.est_max_m[1]);
    assert!(h.est_max_m[2] <= 0.15, "altitude {:.3} m", h.est_max_m[2]);
}

#[test]
fn square_legs_are_straight() {
    let legs = metrics::leg_tracks(square());
    for l in &legs {
        println!(
            "leg {}: cross-track est RMS {:.3} m max {:.3} m | true straightness RMS {:.3} m max {:.3} m",
            l.index, l.est_rms_m, l.est_max_m, l.true_rms_m, l.true_max_m
        );
    }
    assert_eq!(legs.len(), 4, "all four legs flown");
    let t = metrics::track_summary(&legs);
    println!(
        "square: cross-track est RMS {:.3} m max {:.3} m (true RMS {:.3} m max {:.3} m)",
        t.est_rms_m, t.est_max_m, t.true_rms_m, t.true_max_m
    );
    assert!(t.est_rms_m <= 0.3, "cross-track RMS {:.3} m", t.est_rms_m);
    assert!(t.est_max_m <= 0.8, "cross-track max {:.3} m", t.est_max_m);
    // The mission ends on the ground, disarmed.
    let last = square().samples.last().unwrap();
    assert!(!last.armed, "disarmed after landing");
}

#[test]
fn attitude_estimate_tracks_truth_during_the_square() {
    let a = metrics::attitude_error(square(), true);
    println!(
        "square: attitude RMS roll {:.3}° pitch {:.3}° yaw {:.3}° (max {:.2}° {:.2}° {:.2}°)",
        a.rms_deg[0], a.rms_deg[1], a.rms_deg[2], a.max_deg[0], a.max_deg[1], a.max_deg[2]
    );
    assert!(a.samples > 1000);
    assert!(
        a.rms_deg[0] <= 1.0 && a.rms_deg[1] <= 1.0,
        "{:?}",
        a.rms_deg
    );
    assert!(a.rms_deg[2] <= 3.0, "{:?}", a.rms_deg);
}

#[test]
fn yaw_rides_through_a_magnetic_disturbance() {
    let log = yaw_disturbance();
    let a = metrics::attitude_error(log, true);
    println!(
        "square with 15 µT disturbance: attitude RMS roll {:.3}° pitch {:.3}° yaw {:.3}° (max yaw {:.2}°)",
        a.rms_deg[0], a.rms_deg[1], a.rms_deg[2], a.max_deg[2]
    );
    assert!(
        a.rms_deg[0] <= 1.0 && a.rms_deg[1] <= 1.0,
        "{:?}",
        a.rms_deg
    );
    assert!(a.rms_deg[2] <= 3.0, "yaw RMS {:.3}°", a.rms_deg[2]);
    // The disturbance really was there and the legs were flown.
    assert_eq!(metrics::leg_tracks(log).len(), 4);
}

#[test]
fn elevator_vertical_filter_beats_the_barometer() {
    let log = common::fly("elevator");
    let v = metrics::vertical_error(&log, metrics::ELEVATOR_SETTLE_S);
    println!(
        "elevator: estimate error RMS {:.3} m (max {:.3}) | noise σ estimate {:.4} m vs barometer alone {:.4} m (RMS {:.3} m)",
        v.est_rms_m, v.est_max_m, v.est_noise_m, v.baro_noise_m, v.baro_rms_m
    );
    assert!(v.est_rms_m <= 0.3, "vertical RMS {:.3} m", v.est_rms_m);
    assert!(
        v.est_noise_m < 0.2 * v.baro_noise_m,
        "estimate noise {:.4} vs baro {:.4}",
        v.est_noise_m,
        v.baro_noise_m
    );
    // The ride really went up three floors.
    let top = log
        .samples
        .iter()
        .map(|s| -s.true_pos_ned_m[2])
        .fold(f64::MIN, f64::max);
    assert!((top - 10.5).abs() < 0.01, "top {top}");
}

#[test]
fn observer_is_much_less_noisy_than_the_accelerometer() {
    for (name, log) in [("hover", hover()), ("square", square())] {
        let o = metrics::observer_noise(log);
        println!(
            "{name}: observer std(est − truth) {:.3} m/s² vs raw accelerometer {:.3} m/s² (ratio {:.3})",
            o.observer_std_mps2,
            o.raw_std_mps2,
            o.observer_std_mps2 / o.raw_std_mps2
        );
        assert!(o.samples > 1000);
        assert!(o.observer_std_mps2 < 0.3 * o.raw_std_mps2, "{name}: {o:?}");
    }
}

#[test]
fn same_seed_same_flight_other_seed_other_flight() {
    let mut s = common::load("hover");
    s.duration_s = 20.0;
    let a = common::fly_scenario(s.clone());
    let b = common::fly_scenario(s.clone());
    s.seed += 1;
    let c = common::fly_scenario(s);
    let pos = |l: &fcc_sim::log::FlightLog| {
        l.samples
            .iter()
            .map(|x| x.true_pos_ned_m)
            .collect::<Vec<_>>()
    };
    assert_eq!(pos(&a), pos(&b));
    assert_ne!(pos(&a), pos(&c));
}
