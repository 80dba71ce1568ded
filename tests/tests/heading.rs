//! Heading setpoints reach the MCU and are held (issue 17, part 3), in the lockstep SITL: paper
//! A's square (20 m sides, 3 m/s, 3 m/s wind from the west) flown with `yaw_deg: 90` — the
//! mission follower's heading goes to the flight core as `YawSetpoint::Heading` with every
//! velocity setpoint — and the simulator's TRUE yaw (not the estimate) stays on east along each
//! leg. Without the heading reaching the MCU the vehicle keeps its take-off heading (north, 90°
//! off) and the test fails.

mod common;

use fcc_sim::log::PlanPhase;
use fcc_sim::scenario::FlightPlan;

/// Heading error of every leg sample: true yaw − 90°, wrapped, deg; per leg.
fn leg_heading_errors_deg(log: &fcc_sim::log::FlightLog) -> Vec<(usize, Vec<f64>)> {
    let mut legs: Vec<(usize, Vec<f64>)> = Vec::new();
    for s in &log.samples {
        if let PlanPhase::Leg { index, .. } = s.plan {
            let e = fcc_nav::complementary::wrap_pi_f64(s.true_euler_rad[2] - 90f64.to_radians());
            match legs.last_mut() {
                Some((i, v)) if *i == index => v.push(e.to_degrees()),
                _ => legs.push((index, vec![e.to_degrees()])),
            }
        }
    }
    legs
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

#[test]
fn square_with_heading_east_holds_90_deg_on_truth() {
    let mut s = common::load("square");
    let path = common::scenario_path("../missions/square");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut m = fcc_mission::from_yaml_str(&text).unwrap_or_else(|e| panic!("{e}"));
    m.yaw_deg = Some(90.0);
    s.flight = FlightPlan::MissionInline { mission: m };
    let log = common::fly_scenario(s);
    let legs = leg_heading_errors_deg(&log);
    let mut all = Vec::new();
    for (i, e) in &legs {
        let max = e.iter().fold(0f64, |m, x| m.max(x.abs()));
        println!(
            "leg {i}: true heading − 90° RMS {:.2}° max {max:.2}° ({} samples)",
            rms(e),
            e.len()
        );
        assert!(rms(e) <= 3.0, "leg {i}: heading RMS {:.2}° > 3°", rms(e));
        all.extend_from_slice(e);
    }
    println!(
        "square with yaw_deg 90: true heading − 90° RMS {:.2}° over {} leg samples",
        rms(&all),
        all.len()
    );
    assert_eq!(legs.len(), 4, "all four legs flown");
    assert!(!log.samples.last().unwrap().armed, "landed and disarmed");
}
