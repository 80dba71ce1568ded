//! Paper B in flight (issue: ground altitude): the laser + sonar Kalman fusion on paper B's
//! ground and roll tests, side by side with each sensor alone and the paper's fixed 2 m switch,
//! and a landing over a terrain step onto a surface that is dark to the laser.

mod common;

use fcc_sim::log::FlightLog;
use fcc_sim::metrics::{self, GroundStats};

fn table(name: &str, rows: &[(&'static str, GroundStats)]) {
    println!("{name}: height above ground vs truth");
    println!(
        "  {:<28} {:>10} {:>10} {:>11}",
        "method", "RMS m", "max m", "diverged s"
    );
    for (m, g) in rows {
        println!(
            "  {:<28} {:>10.3} {:>10.3} {:>11.1}",
            m, g.rms_m, g.max_m, g.diverged_s
        );
    }
}

fn ours(rows: &[(&'static str, GroundStats)]) -> GroundStats {
    rows.iter().find(|r| r.0.starts_with("ours")).unwrap().1
}

/// Errors of our fused height (50 Hz log) in a time window, against truth.
fn fused_errors(log: &FlightLog, from_s: f64, to_s: f64) -> Vec<f64> {
    log.samples
        .iter()
        .filter(|s| s.t_s >= from_s && s.t_s < to_s && s.nav.calibrated)
        .map(|s| s.nav.ground.height_m as f64 - s.true_agl_m)
        .collect()
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

#[test]
fn ground_test_rides_through_the_dark_surface() {
    let log = common::fly("ground_test");
    let rows = metrics::ground_comparison(&log);
    table("ground test (1 m, dark 105–184 s)", &rows);
    // The laser really reported 99999 m over the dark surface, and only there.
    let dark: Vec<_> = log
        .ranges
        .iter()
        .filter(|r| r.laser && r.t_s >= 105.2 && r.t_s < 183.8)
        .collect();
    assert!(dark.len() > 600 && dark.iter().all(|r| r.range_m == 99_999.0));
    assert!(log
        .ranges
        .iter()
        .filter(|r| r.laser && (r.t_s < 104.8 || r.t_s > 184.2) && r.t_s > 5.0)
        .all(|r| r.range_m < 2.0));
    let o = ours(&rows);
    assert!(o.rms_m <= 0.03, "RMS {:.3} m", o.rms_m);
    assert!(o.max_m <= 0.10, "max {:.3} m", o.max_m);
    assert_eq!(o.diverged_s, 0.0, "never diverges");
    // Outside the dark window: no worse than the better sensor alone (same samples).
    let mut inside_laser = Vec::new();
    let mut inside_sonar = Vec::new();
    for r in log.ranges.iter().filter(|r| r.t_s > 10.0 && r.t_s < 100.0) {
        let e = r.range_m as f64 - r.true_agl_m;
        if r.laser {
            inside_laser.push(e);
        } else {
            inside_sonar.push(e);
        }
    }
    let better = rms(&inside_laser).min(rms(&inside_sonar));
    let fused = rms(&fused_errors(&log, 10.0, 100.0));
    println!("before the dark patch: fused RMS {fused:.4} m vs better sensor alone {better:.4} m");
    assert!(
        fused <= better,
        "fused {fused:.4} vs better sensor {better:.4}"
    );
}

#[test]
fn roll_tests_at_30_and_45_degrees() {
    for name in ["roll_30", "roll_45"] {
        let log = common::fly(name);
        let rows = metrics::ground_comparison(&log);
        table(name, &rows);
        let o = ours(&rows);
        assert!(o.rms_m <= 0.05, "{name}: RMS {:.3} m", o.rms_m);
        assert_eq!(o.diverged_s, 0.0, "{name}");
    }
}

#[test]
fn landing_over_a_step_onto_a_dark_patch() {
    let log = common::fly("landing_dark");
    table(
        "landing approach (1 m step, dark landing spot)",
        &metrics::ground_comparison(&log),
    );
    let gear = fcc_sim::physics::VehicleParams::default().gear_height_m;
    // The run ends at the disarm (the mission computer is done), possibly before the next 50 Hz
    // sample: the disarm is the event, the vehicle's state the last sample up to it.
    let disarm_t_s = log
        .events
        .iter()
        .find(|(t, what)| *t > 10.0 && what.starts_with("disarmed"))
        .expect("disarmed after landing")
        .0;
    let disarm = log
        .samples
        .iter()
        .rev()
        .find(|s| s.t_s <= disarm_t_s)
        .expect("a sample before the disarm");
    let land = log
        .samples
        .iter()
        .find(|s| s.mode == fcc_firmware::commands::Mode::Land)
        .expect("landed");
    // Touched down on the dark patch (centre N 25, E 0, radius 4 m) and stands on its gear.
    let p = disarm.true_pos_ned_m;
    assert!(
        ((p[0] - 25.0).powi(2) + p[1].powi(2)).sqrt() < 4.0,
        "landed at {p:?}"
    );
    assert!(
        (disarm.true_agl_m - gear).abs() < 0.06,
        "on the gear: {:.3}",
        disarm.true_agl_m
    );
    // The laser was blind there: the descent rested on the sonar.
    let final_descent: Vec<_> = log
        .samples
        .iter()
        .filter(|s| s.t_s > land.t_s && s.t_s <= disarm_t_s)
        .collect();
    assert!(final_descent
        .iter()
        .any(|s| s.nav.laser_m == Some(99_999.0)));
    let contact_speed = final_descent
        .iter()
        .filter(|s| s.true_agl_m - gear < 0.1)
        .map(|s| s.true_vel_ned_mps[2])
        .fold(0.0f64, f64::max);
    println!("landing: land mode from {:.1} s, vertical speed at contact {contact_speed:.2} m/s, disarmed at {disarm_t_s:.1} s", land.t_s);
    assert!(contact_speed <= 0.5, "contact at {contact_speed:.2} m/s");
}

/// The campaign's `landing` flight 5063 (`fcc-campaign --only landing:5063 --long`): a 0.5-m
/// step down, then the laser back over the far side of the dark patch. While the range
/// altitude is suspect the barometer stands in, and it must do so at the barometer's own
/// crossover: at the range's (fast) one the height followed the barometer's error, dropped
/// 0.58 m in 0.2 s when the laser came back, was re-anchored there, and the vehicle climbed to
/// 1.77 m above its commanded height (true) and stayed 1.6–1.9 m off its estimate. With the
/// faster attitude loop (2026-12-06) the same flight left the box's far edge on a different
/// beat: the sonar's cone turned the 0.5-m edge into a 0.6-s ramp, the ground filter followed it
/// with its residual rate (no re-acquisition), and the height followed the terrain down by 0.75 m
/// — the range aid now bridges such a ramp with the barometer (`fcc_nav::range_aid`).
#[test]
fn a_step_and_the_laser_back_do_not_move_the_height() {
    let f = fcc_sim::campaign::generate("landing", 5063, true);
    let (o, log) = fcc_sim::campaign::fly_logged(&f);
    let t = fcc_sim::truth::report(&log);
    let err = t.leg_alt_err_m.expect("legs flown");
    println!(
        "{}: true altitude error max {err:.3} m; {:?}",
        f.what, o.failures
    );
    assert!(err < 0.5, "true altitude error over the step {err:.3} m");
    assert!(o.failures.is_empty(), "{:?}", o.failures);
}
