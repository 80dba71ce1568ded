//! Monte-Carlo campaign: many seeds × scenario families, every flight scored on the
//! simulator's truth ([`super::truth`]) against the flight-safety acceptance, then a table of
//! percentiles and the worst case of every figure, with the failures listed.
//!
//! | family | what varies (per seed) | checked (truth unless noted) |
//! |---|---|---|
//! | `hover` | 100 s at 5 m, 3 m/s wind from any direction, W20 15 kt | alt ±0.3 m; estimated box ≤ N 0.35 / E 0.55 / alt 0.15 m |
//! | `hover_gale` | 8 m/s + W20 30 kt from any direction | horizontal excursion ≤ 2 m |
//! | `gps_loss` | GPS lost for good 30–60 s into a hover at 3–8 m, 0–5 m/s wind from any direction, W20 ≤ 15 kt | LAND (`GpsLost`) within the GPS timeout + 0.5 s; time to contact, true drift |
//! | `mission` | 3–6 waypoints, legs 8–40 m, turns up to 170°, climbs, 1–5 m/s, wind 0–8 m/s, W20 ≤ 30 kt | est. cross-track RMS ≤ 0.3 m, max ≤ 0.8 m |
//! | `velocity` | circle at 2–8 m/s (the limit), zero climb | alt ±0.5 m; speed ≤ limit + 5 %; tilt ≤ limit + 2°; tilt wobble (about its 2-s mean) RMS ≤ 3° |
//! | `landing` | a 0.3–1.5 m step on the way, landing on a dark patch | touchdown figures |
//! | `mag` | square with 25 µT for 10–30 s | yaw RMS ≤ 3°, max ≤ 8° |
//! | `rig` | paper B's rig at 0.3–10 m, −10…40 °C | fused height RMS ≤ 3 cm, max ≤ 10 cm |
//!
//! Every flying family also checks: no crash or tip-over, no unplanned ground contact, no
//! flyaway, one touchdown per landing (no hop off the ground), touchdown ≤ 0.5 m/s down,
//! ≤ 0.3 m/s horizontal, ≤ 5° tilt, and no time truly
//! airborne with the attitude loops off; and measures how long LAND's touchdown gate waited
//! for a lull (`touchdown_gate_wait_s`) and whether its timeout committed the touchdown
//! (`touchdown_gate_forced`: its last chance, or GPS lost).

use super::log::{FlightLog, LogSample};
use super::metrics;
use super::scenario::Scenario;
use super::sim::Sim;
use super::truth::{self, TruthReport};
use rand::{Rng, SeedableRng};
use std::collections::BTreeMap;
use std::fmt::Write;

/// The touchdown gate's longest wait for a lull, s: a flight's duration leaves room for it
/// after the landing starts (a flight still waiting at the end would count as never landed).
const GATE_LAST_S: f64 = fcc_firmware::touchdown_gate::LAST_CHANCE_S as f64;

/// The scenario families, in table order.
pub const FAMILIES: [&str; 8] = [
    "hover",
    "hover_gale",
    "gps_loss",
    "mission",
    "velocity",
    "landing",
    "mag",
    "rig",
];

/// One generated flight.
#[derive(Clone, Debug)]
pub struct Flight {
    pub family: &'static str,
    pub seed: u64,
    pub what: String,
    pub scenario: Scenario,
}

/// One flown and scored flight.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub family: &'static str,
    pub seed: u64,
    pub what: String,
    /// Named figures (units in the names).
    pub figures: BTreeMap<&'static str, f64>,
    /// (check name, what failed).
    pub failures: Vec<(&'static str, String)>,
}

/// The checks the vehicle does **not** meet yet, per family: measured, printed and listed as
/// failures by `fcc-campaign`, but not asserted by the test command's short campaign; every
/// other check of every family is asserted.
///
/// - `gps_loss` (GPS lost in a hover; the vehicle lands on baro, accelerometer and rangefinders
///   alone): without GPS nothing this airframe carries observes the velocity over the ground (a
///   slow acceleration and a tilt error look alike to the accelerometer), and the dead-reckoned
///   velocity's error grows ≈ 0.03–0.1 m/s per second from the loss — the attitude error of the
///   moment (≈ 0.1–0.5°, the complementary filter having read gust accelerations as tilt; after
///   the loss the tilt is held on the gyro, `fcc_firmware::nav`) read as an acceleration. The landing is made as short as is safe (`fcc_firmware::flight`: down at the
///   descent limit, the slow part from 0.6 m, no wait at the touchdown gate), which bounds the
///   slide at contact but not to 0.3 m/s. With the tilt and the gyro bias corrected by the
///   steady-state Kalman gains of the sensors' error model (`fcc_nav::tilt_kf`), 20 seed sets
///   (1,000 … 39,000, 1,440 GPS-lost landings): 13 → 7 touchdowns beyond 0.3 m/s, the gale's
///   flights in the same sets 16 → 16 failed. What no estimator can remove on these sensors
///   (`scripts/gps_loss_bound.py`, the optimal filter's dead-reckoned velocity error): σ 0.070
///   m/s per axis 5.5 s after the last fix (the median time to contact), 0.089 m/s at 6.8 s
///   (p95), so P(|v| > 0.3 m/s) ≈ 1e-4 … 4e-3 per landing from the estimate alone, and a gust
///   at a blind touchdown adds to it (seed 5051: no mean wind, W20 15 kt, the estimate 0.16 m/s
///   off, slid 0.46 m/s with the level tilt limit clipping). Waiting at the gate for a lull
///   with GPS lost (1.5 s at most, the tilt demand alone judged) added drift: 6 → 20 of 720.
///
/// `hover_gale` (8 m/s + W20 30 kt: its touchdown speed and tilt, its 2 m true excursion) was
/// here until 2026-12-06: near the ground the gusts keep σ_u ≈ 3 m/s while the mean drops, and
/// the lull the touchdown gate (`fcc_firmware::touchdown_gate`) waits for came late or did not
/// last through the last 0.12 m (seed set 1000, fifteenth session: 4 of 72 slid beyond 0.3
/// m/s), and the excursion was the GPS's (`hold_nav_drift_m`, p50 2.2 m before the Doppler-led
/// horizontal filter). Now asserted: over 20 seed sets (1000, 3000 … 39000; 1,440 gale
/// flights) one touchdown at 0.306 m/s, tilt worst 4.83°, excursion worst 1.30 m, scored on
/// the gear's plane; on the first foot to touch (`truth::foot_clearance_m`), 6 of 1,440 (5
/// at 0.31–0.39 m/s, one at 5.26° after a 52-s wait), and 9 of 2,880 over 40 seed sets (to
/// 79000; `scripts/bench_history.md`, 2026-12-07, the gate extrapolating a slide whose command
/// the level limit clips), 2 since the arrest after a gust's abort is levelled (2026-12-08:
/// `hover_gale` 19001 at 0.315 m/s, 41068 at 5.24°). Asserted
/// on the short campaign's seeds as a regression check; the issue stays open on them.
pub const OPEN_CHECKS: [(&str, &[&str]); 1] =
    [("gps_loss", &["touchdown_horiz_mps", "touchdown_tilt_deg"])];

/// Checks of every flying family printed with their failures but not asserted yet: none.
/// `touchdowns` (one touchdown per landing, added on 2026-12-02) was here while landings hopped:
/// 28 of the 576 flights of seed set 1000 touched down twice — the touchdown's own jolt read
/// as a gust by the touchdown gate, which climbed back to its hold height; with the gate
/// feeling the ground (`fcc_firmware::touchdown_gate::TouchdownGate::feel_ground`) 43 of
/// 5,760 over ten seed sets, a gust's abort 1–3 cm above the ground; with a contact just after
/// such an abort taken as the touchdown (`touchdown_gate::REFEEL_S`) none, and it is asserted.
pub const OPEN_IN_EVERY_FAMILY: [&str; 0] = [];

/// The family named `name` (one of [`FAMILIES`]).
pub fn family(name: &str) -> Option<&'static str> {
    FAMILIES.iter().copied().find(|f| *f == name)
}

/// Is `check` of a flight of `family` one the vehicle does not meet yet (not asserted)?
pub fn is_open(family: &str, check: &str) -> bool {
    OPEN_IN_EVERY_FAMILY.contains(&check)
        || OPEN_CHECKS
            .iter()
            .any(|(f, checks)| *f == family && checks.contains(&check))
}

fn wind_yaml(speed: f64, dir: f64, w20: f64) -> String {
    format!(
        "wind: {{mean_speed_mps: {speed:.2}, from_direction_deg: {dir:.1}, w20_kt: {w20:.1}}}\n"
    )
}

/// Generate the flight of `family` for `seed`. `long`: the benchmark's full durations (the
/// velocity cruise 5 min instead of 1).
pub fn generate(family: &'static str, seed: u64, long: bool) -> Flight {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ fnv(family));
    let dir: f64 = rng.gen_range(0.0..360.0);
    let (what, yaml) = match family {
        "hover" => (
            format!("3 m/s from {dir:.0}°"),
            format!("name: hover\nduration_s: {:.0}\n{}flight: {{kind: hover, alt_m: 5.0, hold_s: 100.0}}\n", 120.0 + GATE_LAST_S, wind_yaml(3.0, dir, 15.0)),
        ),
        "hover_gale" => {
            let v = rng.gen_range(6.0..8.0);
            let hold_s = if long { 100.0 } else { 60.0 };
            (
                format!("{v:.1} m/s + W20 30 kt from {dir:.0}°"),
                format!("name: hover_gale\nduration_s: {:.0}\n{}flight: {{kind: hover, alt_m: 5.0, hold_s: {}}}\n", hold_s + 30.0 + GATE_LAST_S, wind_yaml(v, dir, 30.0), hold_s),
            )
        }
        "gps_loss" => {
            let wind = rng.gen_range(0.0..5.0);
            let w20 = rng.gen_range(0.0..15.0);
            let alt = rng.gen_range(3.0..8.0);
            let t_loss = rng.gen_range(30.0..60.0);
            (
                format!("GPS lost at {t_loss:.0} s, hover at {alt:.1} m, {wind:.1} m/s W20 {w20:.0} kt"),
                format!("name: gps_loss\nduration_s: 120\n{}flight: {{kind: hover, alt_m: {alt:.2}, hold_s: 100.0}}\nfaults: [{{kind: gps_outage, start_s: {t_loss:.2}, end_s: 1.0e6}}]\n", wind_yaml(wind, dir, w20)),
            )
        }
        "mission" => mission(&mut rng, dir),
        "velocity" => {
            let v = rng.gen_range(2.0..=8.0f64).min(8.0);
            let cruise = if long { 300.0 } else { 60.0 };
            (
                format!("{v:.1} m/s circle for {cruise} s, 3 m/s wind"),
                format!("name: velocity\nduration_s: {}\n{}flight: {{kind: velocity, alt_m: 5.0, speed_mps: {v:.2}, radius_m: {:.1}, cruise_s: {cruise}}}\n", cruise + 30.0 + GATE_LAST_S, wind_yaml(3.0, dir, 15.0), (v * 8.0).max(15.0)),
            )
        }
        "landing" => {
            let step = rng.gen_range(0.3..1.5);
            let dist = rng.gen_range(15.0..30.0);
            let wind = rng.gen_range(0.0..6.0);
            (
                format!("{step:.1} m step, land on a dark patch {dist:.0} m away, {wind:.1} m/s"),
                format!("name: landing\nduration_s: 150\nair_temp_c: {:.0}\n{}flight: {{kind: mission_inline, mission: {{takeoff_alt_m: 5.0, speed_mps: 2.0, accel_limit_mps2: 1.0, accept_radius_m: 0.5, hold_s: 2.0, land_at_end: true, waypoints: [{{north_m: {:.1}, east_m: 0.0, alt_m: 5.0}}, {{north_m: {dist:.1}, east_m: 0.0, alt_m: 3.0}}]}}}}\nterrain:\n  boxes: [{{north_min_m: {:.1}, north_max_m: {:.1}, east_min_m: -5, east_max_m: 5, height_m: {step:.2}}}]\n  dark_patches: [{{center_north_m: {dist:.1}, center_east_m: 0, radius_m: 4}}]\n",
                    rng.gen_range(-10.0..40.0), wind_yaml(wind, dir, 15.0), dist * 0.5, dist * 0.3, dist * 0.55),
            )
        }
        "mag" => {
            let dur = rng.gen_range(10.0..30.0);
            let a: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
            (
                format!("25 µT for {dur:.0} s"),
                format!("name: mag\nduration_s: 200\n{}flight: {{kind: mission_inline, mission: {{takeoff_alt_m: 5.0, speed_mps: 3.0, accel_limit_mps2: 1.0, accept_radius_m: 0.5, hold_s: 2.0, land_at_end: true, waypoints: [{{north_m: 20, east_m: 0, alt_m: 5}}, {{north_m: 20, east_m: 20, alt_m: 5}}, {{north_m: 0, east_m: 20, alt_m: 5}}, {{north_m: 0, east_m: 0, alt_m: 5}}]}}}}\nfaults: [{{kind: mag_disturbance, start_s: 20, end_s: {:.1}, field_ned_ut: [{:.2}, {:.2}, 0.0]}}]\n",
                    wind_yaml(3.0, dir, 15.0), 20.0 + dur, 25.0 * a.cos(), 25.0 * a.sin()),
            )
        }
        _ => {
            let h = rng.gen_range(0.3..10.0);
            let temp = rng.gen_range(-10.0..40.0);
            (
                format!("rig at {h:.2} m, {temp:.0} °C"),
                format!("name: rig\nduration_s: 60\nair_temp_c: {temp:.1}\nflight: {{kind: rig, height_m: {h:.3}, roll_deg: 0, pitch_deg: 0}}\n"),
            )
        }
    };
    let mut scenario = Scenario::from_yaml_str(&yaml)
        .unwrap_or_else(|(f, r)| panic!("campaign {family}: generated scenario: {f}: {r}"));
    scenario.seed = seed;
    Flight {
        family,
        seed,
        what,
        scenario,
    }
}

/// A random polygon mission: 3–6 waypoints, legs 8–40 m, any turn, altitudes 3–8 m.
fn mission(rng: &mut rand_chacha::ChaCha8Rng, dir: f64) -> (String, String) {
    let n = rng.gen_range(3..=6);
    let speed = rng.gen_range(1.0..=5.0f64).min(5.0);
    let wind = rng.gen_range(0.0..=8.0f64).min(8.0);
    let w20 = rng.gen_range(0.0..=30.0f64).min(30.0);
    let (mut p, mut heading) = ([0.0f64, 0.0], rng.gen_range(0.0..std::f64::consts::TAU));
    let mut wps = String::new();
    let mut max_turn = 0.0f64;
    for i in 0..n {
        if i > 0 {
            let turn = rng.gen_range(-170.0f64..170.0).to_radians();
            max_turn = max_turn.max(turn.abs());
            heading += turn;
        }
        let len = rng.gen_range(8.0..40.0);
        p = [p[0] + len * heading.cos(), p[1] + len * heading.sin()];
        let alt = rng.gen_range(3.0..8.0);
        write!(
            wps,
            "{{north_m: {:.1}, east_m: {:.1}, alt_m: {alt:.1}}}, ",
            p[0], p[1]
        )
        .ok();
    }
    (
        format!("{n} waypoints at {speed:.1} m/s, turns ≤ {:.0}°, wind {wind:.1} m/s W20 {w20:.0} kt", max_turn.to_degrees()),
        format!("name: mission\nduration_s: 600\n{}flight: {{kind: mission_inline, mission: {{takeoff_alt_m: 5.0, speed_mps: {speed:.2}, accel_limit_mps2: 1.0, accept_radius_m: 0.5, hold_s: 2.0, land_at_end: true, waypoints: [{wps}]}}}}\n", wind_yaml(wind, dir, w20)),
    )
}

fn fnv(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

/// Fly one flight and score it.
pub fn fly(f: &Flight) -> Outcome {
    fly_logged(f).0
}

/// Fly one flight; its score and its log (for a CSV of the flight that failed).
pub fn fly_logged(f: &Flight) -> (Outcome, FlightLog) {
    let mut sim = Sim::new(f.scenario.clone()).unwrap_or_else(|e| panic!("{e}"));
    sim.run();
    let still_armed = sim.fc.core.armed();
    sim.finish();
    let log = std::mem::take(&mut sim.log);
    (score(f, &log, still_armed), log)
}

/// Score a flown flight against the checks of its family (module doc).
fn score(f: &Flight, log: &FlightLog, still_armed: bool) -> Outcome {
    let mut o = Outcome {
        family: f.family,
        seed: f.seed,
        what: f.what.clone(),
        figures: BTreeMap::new(),
        failures: Vec::new(),
    };
    if f.family == "rig" {
        score_rig(&mut o, log);
        return o;
    }
    let t: TruthReport = truth::report(log);
    let v_t = f.scenario.params.limits.land_touchdown_speed_mps as f64;
    let floor_s = fcc_firmware::touchdown_gate::ABORT_ABOVE_M as f64 / v_t;
    score_safety(&mut o, log, &t, still_armed, floor_s);
    match f.family {
        "hover" | "hover_gale" => score_hover(&mut o, log, &t, f.family == "hover_gale"),
        "mission" | "landing" | "mag" => score_mission(&mut o, log, &t, f.family == "mag"),
        "velocity" => score_velocity(&mut o, log, f),
        "gps_loss" => score_gps_loss(&mut o, log, &t, f),
        _ => {}
    }
    o
}

/// Record figure `name` = `v`, and a failure when a `limit` is given and `v` is not within it
/// (NaN fails).
fn figure(o: &mut Outcome, name: &'static str, v: f64, limit: Option<f64>) {
    o.figures.insert(name, v);
    if let Some(l) = limit {
        if !(v <= l) {
            o.failures.push((name, format!("{name} {v:.3} > {l}")));
        }
    }
}

/// The ground rig: the fused height above ground against truth.
fn score_rig(o: &mut Outcome, log: &FlightLog) {
    let g = metrics::ground_comparison(log);
    let ours = g.last().map(|x| x.1).unwrap_or_default();
    figure(o, "ground_rms_m", ours.rms_m, Some(0.03));
    figure(o, "ground_max_m", ours.max_m, Some(0.10));
}

/// The checks of every flying family: no crash, unplanned contact or flyaway, attitude loops
/// on while airborne, a gentle touchdown, disarmed at the end, no estimator fault.
/// `floor_s`: the committed descent's time under the abort floor ([`late_gain_mps`]).
fn score_safety(
    o: &mut Outcome,
    log: &FlightLog,
    t: &TruthReport,
    still_armed: bool,
    floor_s: f64,
) {
    figure(o, "crashes", t.crashed as u8 as f64, Some(0.0));
    figure(
        o,
        "unplanned_contacts",
        t.unplanned_contacts as f64,
        Some(0.0),
    );
    figure(o, "flyaways", t.flyaway as u8 as f64, Some(0.0));
    figure(
        o,
        "attitude_off_airborne_s",
        t.attitude_off_airborne_s,
        Some(0.0),
    );
    match t.worst_touchdown() {
        Some(w) => {
            figure(o, "touchdown_down_mps", w[0], Some(0.5));
            figure(o, "touchdown_horiz_mps", w[1], Some(0.3));
            figure(o, "touchdown_tilt_deg", w[2], Some(5.0));
            let planned = || t.contacts.iter().filter(|c| c.planned);
            // A landing touches down once: a second planned contact is a hop (the gear
            // touched, the vehicle climbed off the ground again and came down).
            figure(o, "touchdowns", planned().count() as f64, Some(1.0));
            let wait_s = planned().map(|c| c.gate_wait_s).fold(0.0, f64::max);
            figure(o, "touchdown_gate_wait_s", wait_s, None);
            let forced = planned().any(|c| c.gate_forced);
            figure(o, "touchdown_gate_forced", forced as u8 as f64, None);
            let first = planned().next();
            touchdown_estimate(o, log, first);
            let gain = first.map_or(f64::NAN, |c| late_gain_mps(log, c.t_s, floor_s));
            figure(o, "touchdown_late_gain_mps", gain, None);
        }
        None => o.failures.push(("landed", "never landed".into())),
    }
    if still_armed {
        o.failures
            .push(("disarmed", "still armed at the end of the run".into()));
    }
    let failsafe = |c: fcc_firmware::commands::FailsafeCause| {
        log.samples.iter().any(|s| s.failsafe == c) as u8 as f64
    };
    figure(
        o,
        "wind_limit_landings",
        failsafe(fcc_firmware::commands::FailsafeCause::WindLimit),
        None,
    );
    figure(
        o,
        "estimator_faults",
        failsafe(fcc_firmware::commands::FailsafeCause::EstimatorFault),
        Some(0.0),
    );
    figure(o, "max_tilt_deg", t.max_tilt_deg, None);
    figure(o, "max_speed_mps", t.max_speed_mps, None);
}

/// GPS lost: the failsafe's landing must begin within the GPS timeout + 0.5 s of the loss;
/// measured: the time from the loss to the first contact, the true horizontal distance
/// travelled in it and the dead-reckoned velocity's error at the contact.
fn score_gps_loss(o: &mut Outcome, log: &FlightLog, t: &TruthReport, f: &Flight) {
    use fcc_firmware::commands::FailsafeCause;
    let t_loss = f
        .scenario
        .faults
        .iter()
        .find_map(|x| match x {
            crate::scenario::Fault::GpsOutage { start_s, .. } => Some(*start_s),
            _ => None,
        })
        .unwrap_or(f64::NAN);
    let timeout = fcc_firmware::params::NavParams::default().gps_timeout_s as f64;
    let land = log
        .samples
        .iter()
        .find(|s| s.t_s >= t_loss && s.failsafe == FailsafeCause::GpsLost);
    figure(
        o,
        "gps_loss_to_land_s",
        land.map_or(f64::NAN, |s| s.t_s - t_loss),
        Some(timeout + 0.5),
    );
    let contact = t.contacts.iter().find(|c| c.t_s >= t_loss);
    let at = |time: f64| log.samples.iter().find(|s| s.t_s >= time);
    let drift = match (at(t_loss), contact.and_then(|c| at(c.t_s))) {
        (Some(a), Some(b)) => (b.true_pos_ned_m[0] - a.true_pos_ned_m[0])
            .hypot(b.true_pos_ned_m[1] - a.true_pos_ned_m[1]),
        _ => f64::NAN,
    };
    figure(
        o,
        "gps_loss_to_contact_s",
        contact.map_or(f64::NAN, |c| c.t_s - t_loss),
        None,
    );
    figure(o, "gps_loss_drift_m", drift, None);
    // The dead-reckoned velocity's error at the contact (truth − estimate, horizontal, the
    // last sample before it): a slide no loop can see, with nothing on board observing the
    // ground speed. `scripts/gps_loss_bound.py` has the optimal estimator's error for these
    // sensors.
    let before = contact.and_then(|c| sample_before(log, c.t_s));
    let vel_err = before.map_or(f64::NAN, horiz_vel_err_mps);
    figure(o, "gps_loss_vel_err_mps", vel_err, None);
}

/// The last logged sample before `t_s`.
fn sample_before(log: &FlightLog, t_s: f64) -> Option<&LogSample> {
    log.samples.iter().rev().find(|s| s.t_s < t_s)
}

/// The horizontal velocity estimate's error against the truth, m/s.
fn horiz_vel_err_mps(s: &LogSample) -> f64 {
    let v = s.nav.vel_ned_mps;
    (s.true_vel_ned_mps[0] - v[0] as f64).hypot(s.true_vel_ned_mps[1] - v[1] as f64)
}

/// The estimate at the first landing's contact (the last sample before it): the horizontal
/// ground speed the vehicle believed it had, and that belief's error against the truth — how
/// much of a touchdown's slide the loops could not see.
fn touchdown_estimate(o: &mut Outcome, log: &FlightLog, first: Option<&truth::Contact>) {
    let before = first.and_then(|c| sample_before(log, c.t_s));
    let est = before.map_or(f64::NAN, |s| {
        let v = s.nav.vel_ned_mps;
        (v[0] as f64).hypot(v[1] as f64)
    });
    figure(o, "touchdown_est_horiz_mps", est, None);
    figure(
        o,
        "touchdown_vel_err_mps",
        before.map_or(f64::NAN, horiz_vel_err_mps),
        None,
    );
    // The tilt the vehicle believed it had at the contact, less the true one, deg.
    let tilt_err = before.map_or(f64::NAN, |s| {
        let e = s.nav.euler;
        let est = fcc_nav::ground_altitude::tilt_angle_rad(e.roll_rad, e.pitch_rad) as f64;
        let tr = fcc_nav::ground_altitude::tilt_angle_rad(
            s.true_euler_rad[0] as f32,
            s.true_euler_rad[1] as f32,
        ) as f64;
        (est - tr).to_degrees()
    });
    figure(o, "touchdown_tilt_err_deg", tilt_err, None);
}

/// The true horizontal speed a landing gained in its last `floor_s` before its contact at
/// `contact_t_s` (the committed descent under the touchdown gate's abort floor,
/// `touchdown_gate::ABORT_ABOVE_M` at the touchdown speed: there no gust sends it back, since
/// a climb that low would touch and lift off again), m/s. Its part of a slide is one no abort
/// could have answered.
fn late_gain_mps(log: &FlightLog, contact_t_s: f64, floor_s: f64) -> f64 {
    let speed = |s: &LogSample| s.true_vel_ned_mps[0].hypot(s.true_vel_ned_mps[1]);
    match (
        sample_before(log, contact_t_s),
        sample_before(log, contact_t_s - floor_s),
    ) {
        (Some(at), Some(before)) => speed(at) - speed(before),
        _ => f64::NAN,
    }
}

/// Hover: the hold's true altitude error and excursion, and the estimate's box (the gale's
/// box and altitude error are measured, not checked).
fn score_hover(o: &mut Outcome, log: &FlightLog, t: &TruthReport, gale: bool) {
    let Some(h) = metrics::hover_box(log) else {
        o.failures.push(("hold", "never reached the hold".into()));
        return;
    };
    figure(
        o,
        "hold_alt_err_m",
        t.hold_alt_err_m.unwrap_or(f64::NAN),
        (!gale).then_some(0.3),
    );
    figure(
        o,
        "hold_excursion_m",
        t.hold_excursion_m.unwrap_or(f64::NAN),
        gale.then_some(2.0),
    );
    figure(
        o,
        "hold_nav_drift_m",
        t.hold_nav_drift_m.unwrap_or(f64::NAN),
        None,
    );
    let (bn, be, ba) = if gale {
        (None, None, None)
    } else {
        (Some(0.35), Some(0.55), Some(0.15))
    };
    figure(o, "est_box_n_m", h.est_max_m[0], bn);
    figure(o, "est_box_e_m", h.est_max_m[1], be);
    figure(o, "est_box_alt_m", h.est_max_m[2], ba);
    figure(o, "true_box_n_m", h.true_max_m[0], None);
    figure(o, "true_box_e_m", h.true_max_m[1], None);
}

/// Missions (and the landing and magnetometer families): cross-track of the estimate, the true
/// line and altitude on the legs; with `mag`, the yaw error.
fn score_mission(o: &mut Outcome, log: &FlightLog, t: &TruthReport, mag: bool) {
    let legs = metrics::leg_tracks(log);
    let s = metrics::track_summary(&legs);
    if legs.is_empty() {
        o.failures.push(("legs", "no leg flown".into()));
    } else {
        figure(o, "xtrack_est_rms_m", s.est_rms_m, Some(0.3));
        figure(o, "xtrack_est_max_m", s.est_max_m, Some(0.8));
        figure(
            o,
            "line_true_max_m",
            t.leg_line_max_m.unwrap_or(f64::NAN),
            None,
        );
        figure(
            o,
            "leg_alt_err_m",
            t.leg_alt_err_m.unwrap_or(f64::NAN),
            None,
        );
    }
    if mag {
        let a = metrics::attitude_error(log, true);
        figure(o, "yaw_rms_deg", a.rms_deg[2], Some(3.0));
        figure(o, "yaw_max_deg", a.max_deg[2], Some(8.0));
    }
}

/// Velocity cruise: true altitude error, speed and tilt against the MCU's limits.
fn score_velocity(o: &mut Outcome, log: &FlightLog, f: &Flight) {
    let limits = f.scenario.params.limits;
    let c = velocity_truth(log);
    figure(o, "cruise_alt_err_m", c[0], Some(0.5));
    figure(
        o,
        "cruise_speed_over_limit",
        c[1] / limits.max_horiz_speed_mps as f64,
        Some(1.05),
    );
    figure(
        o,
        "cruise_tilt_over_limit_deg",
        c[2] - limits.max_tilt_deg as f64,
        Some(2.0),
    );
    figure(
        o,
        "cruise_tilt_wobble_deg",
        cruise_tilt_wobble_deg(log),
        Some(CRUISE_WOBBLE_MAX_DEG),
    );
}

/// Velocity cruise: the largest RMS tilt wobble about its 2-s moving mean, deg. The gusts'
/// buffeting alone gives 1.3° median, 1.6–1.7° p95 over the family (W20 15 kt); a limit cycle
/// adds more (the speed limit's feedback at gain 2: 3.8–3.9° at 7.9 of 8 m/s).
const CRUISE_WOBBLE_MAX_DEG: f64 = 3.0;

/// Velocity cruise, truth: RMS of the tilt about its own centred 2-s moving mean, deg — the
/// attitude's fast swings (a limit cycle, or the turbulence's buffeting), not the slow lean
/// into the wind around the circle.
fn cruise_tilt_wobble_deg(log: &FlightLog) -> f64 {
    let pts: Vec<(f64, f64)> = cruise_samples(log)
        .map(|s| (s.t_s, true_tilt_deg(s)))
        .collect();
    if pts.is_empty() {
        return f64::NAN;
    }
    // Prefix sums for the moving mean over [t − 1 s, t + 1 s].
    let mut prefix = vec![0.0f64; pts.len() + 1];
    for (i, (_, v)) in pts.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
    }
    let (mut lo, mut hi, mut sum_sq) = (0usize, 0usize, 0.0f64);
    for &(t, v) in &pts {
        while pts[lo].0 < t - 1.0 {
            lo += 1;
        }
        while hi < pts.len() && pts[hi].0 <= t + 1.0 {
            hi += 1;
        }
        let mean = (prefix[hi] - prefix[lo]) / (hi - lo) as f64;
        sum_sq += (v - mean) * (v - mean);
    }
    (sum_sq / pts.len() as f64).sqrt()
}

/// The armed samples of the velocity plan's cruise.
fn cruise_samples(log: &FlightLog) -> impl Iterator<Item = &super::log::LogSample> {
    use super::log::PlanPhase;
    log.samples
        .iter()
        .filter(|s| matches!(s.plan, PlanPhase::Cruise { .. }) && s.armed)
}

/// The true tilt (angle of the body z axis from the vertical), deg.
fn true_tilt_deg(s: &super::log::LogSample) -> f64 {
    let (r, p) = (s.true_euler_rad[0], s.true_euler_rad[1]);
    (r.cos() * p.cos()).clamp(-1.0, 1.0).acos().to_degrees()
}

/// Velocity cruise, truth: max |alt − commanded|, max horizontal speed, max tilt (deg).
fn velocity_truth(log: &FlightLog) -> [f64; 3] {
    let mut m = [0.0f64; 3];
    let start = log.truth.start_down_m;
    let cmd = log.commanded_alt_m.unwrap_or(0.0);
    for s in cruise_samples(log) {
        m[0] = m[0].max((start - s.true_pos_ned_m[2] - cmd).abs());
        m[1] = m[1].max(s.true_vel_ned_mps[0].hypot(s.true_vel_ned_mps[1]));
        m[2] = m[2].max(true_tilt_deg(s));
    }
    m
}

/// Fly `per_family` seeds of each family on `threads` threads (seeds `first_seed..`).
pub fn run(per_family: usize, first_seed: u64, long: bool, threads: usize) -> Vec<Outcome> {
    run_families(&FAMILIES, per_family, first_seed, long, threads)
}

/// [`run`] over the given families only.
pub fn run_families(
    families: &[&'static str],
    per_family: usize,
    first_seed: u64,
    long: bool,
    threads: usize,
) -> Vec<Outcome> {
    let flights: Vec<Flight> = families
        .iter()
        .copied()
        .flat_map(|f| (0..per_family as u64).map(move |i| generate(f, first_seed + i, long)))
        .collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let out = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|sc| {
        for _ in 0..threads.max(1) {
            sc.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(f) = flights.get(i) else { break };
                let o = fly(f);
                out.lock().unwrap_or_else(|e| e.into_inner()).push((i, o));
            });
        }
    });
    let mut v = out.into_inner().unwrap_or_else(|e| e.into_inner());
    v.sort_by_key(|x| x.0);
    v.into_iter().map(|x| x.1).collect()
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// The campaign table: per family and figure, p50 / p95 / worst and the worst seed; then every
/// failure.
pub fn table(outcomes: &[Outcome]) -> String {
    let mut s = String::new();
    writeln!(
        s,
        "| family | figure | flights | p50 | p95 | worst | worst seed |"
    )
    .ok();
    writeln!(s, "|---|---|---|---|---|---|---|").ok();
    for fam in FAMILIES {
        let of: Vec<&Outcome> = outcomes.iter().filter(|o| o.family == fam).collect();
        let names: std::collections::BTreeSet<&str> =
            of.iter().flat_map(|o| o.figures.keys().copied()).collect();
        for name in names {
            let mut v: Vec<(f64, u64)> = of
                .iter()
                .filter_map(|o| o.figures.get(name).map(|x| (*x, o.seed)))
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            let vals: Vec<f64> = v.iter().map(|x| x.0).collect();
            let worst = v.last().copied().unwrap_or((f64::NAN, 0));
            writeln!(
                s,
                "| {fam} | {name} | {} | {:.3} | {:.3} | {:.3} | {} |",
                vals.len(),
                percentile(&vals, 0.5),
                percentile(&vals, 0.95),
                worst.0,
                worst.1
            )
            .ok();
        }
    }
    let failed: Vec<&Outcome> = outcomes.iter().filter(|o| !o.failures.is_empty()).collect();
    writeln!(s, "\n{} flights, {} failed", outcomes.len(), failed.len()).ok();
    for o in failed {
        let what: Vec<&str> = o.failures.iter().map(|f| f.1.as_str()).collect();
        writeln!(
            s,
            "FAIL {} seed {} ({}): {}",
            o.family,
            o.seed,
            o.what,
            what.join("; ")
        )
        .ok();
    }
    s
}
