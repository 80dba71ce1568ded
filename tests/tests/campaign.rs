//! The Monte-Carlo flight-safety campaign, short form (issue 13): 6 seeds × 8 scenario
//! families (48 flights), every flight scored on the simulator's truth
//! (`fcc_sim::campaign`). The benchmark flies ≥ 500 (BENCHMARKS.md):
//!
//! ```text
//! cargo run --release -p fcc_sim --bin fcc-campaign -- --per-family 72 --long
//! ```
//!
//! Asserted on every flight: no crash or tip-over, no unplanned ground contact, the attitude
//! loops on whenever truly airborne, every flight landed and disarmed; hover true altitude
//! within ±0.3 m and the estimated box within half of paper A's; mission cross-track; yaw under
//! a 25 µT disturbance; paper B's rig at every height and air temperature; touchdown ≤ 0.5 m/s
//! down, ≤ 0.3 m/s horizontal, ≤ 5° tilt in every family but the GPS loss (the gale hover's
//! too, and its 2 m true excursion); with GPS lost, LAND within the GPS timeout + 0.5 s.
//! `campaign::OPEN_CHECKS` (the GPS loss's touchdown horizontal speed and tilt: the velocity
//! is dead-reckoned) are printed with their failures but not asserted: the vehicle does not
//! meet them on every seed (the issue stays open on them). One touchdown per landing
//! (`touchdowns`, no hop) is asserted in every family, and the touchdowns' vertical speed
//! within 0.02 m/s RMS of the touchdown speed (the committed descent on the inertial velocity),
//! and their horizontal speed within 0.085 m/s RMS (the committed descent's touchdown gain).

use fcc_sim::campaign;
use fcc_sim::scenario::FlightPlan;

#[test]
fn short_campaign_on_truth() {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let out = campaign::run(6, 1000, false, threads);
    println!("{}", campaign::table(&out));
    assert_eq!(out.len(), 6 * campaign::FAMILIES.len());
    let mut asserted = Vec::new();
    let mut open = 0;
    for o in &out {
        for (name, what) in &o.failures {
            if campaign::is_open(o.family, name) {
                open += 1;
            } else {
                asserted.push(format!("{} seed {} ({}): {what}", o.family, o.seed, o.what));
            }
        }
    }
    println!("open (not asserted) check failures: {open}");
    assert!(asserted.is_empty(), "{}", asserted.join("\n"));
    // The figures the assertions rest on were really measured.
    for fam in campaign::FAMILIES {
        let n = out
            .iter()
            .filter(|o| o.family == fam && !o.figures.is_empty())
            .count();
        assert_eq!(n, 6, "{fam}: every flight scored");
    }
    touchdowns_meet_the_ground_at_the_touchdown_speed(&out);
    touchdowns_do_not_slide(&out);
}

/// The committed descent's velocity loop flies the touchdown gain
/// (`control.vel_p_touchdown_per_s`, 5 /s against the flight's 3): a slide that builds on the
/// way down is leaned against before the gear meets the ground. The short campaign's 36
/// landings with GPS (the GPS-lost ones are dead-reckoned: `campaign::OPEN_CHECKS`): touchdown
/// horizontal speed RMS 0.0566 m/s (0.0618 while a lean during a gust's abort was allowed
/// before the descent had stopped; 0.0738 while the touchdown gate's abort speed widened from
/// 0.2 to 0.25 m/s with the wait; 0.0688 while the tilt was corrected from the
/// accelerometer below 1 m — these 36 landings' scatter: over 10 seed sets of the five families
/// with GPS (3,600 flights) and 20 of the gale (1,440), the same RMS went down in every family,
/// 0.0499–0.0590 → 0.0497–0.0575 m/s, the gale 0.108 → 0.106; 0.0735 before the committed
/// descent's acceleration loop
/// closed on the faster touchdown observer, `control.observer_touchdown_l_per_s`; 0.0747
/// before the touchdown gate extrapolated a slide
/// whose command the level limit clips, 0.0795 before the ground filter averaged the sonar at
/// rest); 0.1007 with the flight's gain. Short campaigns of seed sets 1000 … 8000 (before the
/// averaging): 0.061–0.087 against 0.082–0.100 (seed set 2000 beyond the bound: its gale 2004
/// slid at 0.33 m/s).
fn touchdowns_do_not_slide(out: &[campaign::Outcome]) {
    let horiz: Vec<f64> = out
        .iter()
        .filter(|o| o.family != "gps_loss")
        .filter_map(|o| o.figures.get("touchdown_horiz_mps").copied())
        .collect();
    let rms = rms(&horiz);
    println!(
        "touchdown horizontal speed with GPS: {} landings, RMS {rms:.4} m/s",
        horiz.len()
    );
    assert!(horiz.len() >= 30, "{} touchdowns scored", horiz.len());
    assert!(rms <= 0.085, "touchdown horizontal speed RMS {rms:.4} m/s");
}

/// The touchdown gate's committed descent closes its climb-rate loop on the inertial vertical
/// velocity: the gear meets the ground at `limits.land_touchdown_speed_mps`. Closed on the rate
/// over the ground (the rangefinder filter's residual rate kicked by each sonar reading), the
/// short campaign's 42 touchdowns scattered 0.027 m/s RMS about the commanded speed (gale
/// worst +0.06, −0.10 on 24 seeds); on the inertial velocity 0.0125 (0.0135 with the touchdown
/// gain, 0.0153 with the ground filter averaging the sonar at rest, 0.0168 with the gate
/// extrapolating a slide whose command the level limit clips, 0.0146 with the tilt from the
/// GPS velocity down to the ground, 0.0164 with the abort's speed 0.17 m/s unwidened, 0.0150
/// with the arrest after a gust's abort levelled — these 42 landings' scatter: over 40 seed
/// sets of the gale and 10 of the other five families the abort's speed left the same RMS at
/// 0.0246 → 0.0251 and 0.0129 → 0.0129 m/s, and over 40 sets of each the levelled arrest at
/// 0.0251 → 0.0251 and 0.0132 → 0.0131 m/s).
fn touchdowns_meet_the_ground_at_the_touchdown_speed(out: &[campaign::Outcome]) {
    let v_t = f64::from(
        fcc_firmware::params::Params::default()
            .limits
            .land_touchdown_speed_mps,
    );
    let dev: Vec<f64> = out
        .iter()
        .filter_map(|o| o.figures.get("touchdown_down_mps"))
        .map(|v| v - v_t)
        .collect();
    let rms = rms(&dev);
    let worst = dev.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    println!(
        "touchdown vertical speed about {v_t:.2} m/s: {} landings, RMS {rms:.4} m/s, worst {worst:.3}",
        dev.len()
    );
    assert!(dev.len() >= 40, "{} touchdowns scored", dev.len());
    assert!(
        rms <= 0.02,
        "touchdown vertical speed RMS {rms:.4} m/s about {v_t:.2}"
    );
}

/// Root mean square (0 for none).
fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// The velocity family's flights at the speed limit (commanded ≥ 7.8 of 8 m/s, in 3 m/s wind
/// with W20 15 kt gusts): the speed limit's feedback must not drive the velocity loop into a
/// limit cycle (`cruise_tilt_wobble_deg`, at its gain 2.0 3.8–3.9° on the long campaign's
/// fastest flights), and the true speed stays within the limit + 5 %. The short campaign's 6
/// seeds fly none this fast, so the first three such seeds are flown here.
#[test]
fn velocity_at_the_limit_holds_without_a_limit_cycle() {
    let fast: Vec<_> = (1000u64..)
        .map(|seed| campaign::generate("velocity", seed, false))
        .filter(|f| {
            matches!(f.scenario.flight, FlightPlan::Velocity { speed_mps, .. } if speed_mps >= 7.8)
        })
        .take(3)
        .collect();
    for f in &fast {
        let o = campaign::fly(f);
        let wobble = o.figures["cruise_tilt_wobble_deg"];
        let speed = o.figures["cruise_speed_over_limit"];
        println!(
            "velocity seed {} ({}): tilt wobble {wobble:.2}°, speed {speed:.3} × the limit",
            f.seed, f.what
        );
        assert!(o.failures.is_empty(), "seed {}: {:?}", f.seed, o.failures);
    }
}
