//! Shared by the peer benchmarks (`scripts/bench.sh`): one simulated flight, captured tick by
//! tick, and the machine-readable result lines the script turns into BENCHMARKS.md.
//!
//! ## How the sensor samples are captured (no change to `fcc_firmware` needed)
//! `Sim::tick` polls `SimBoard` internally and does not keep the `SensorInputs` it handed the
//! flight core. The sensor models are deterministic (seeded `ChaCha8Rng` inside each model) and
//! `Clone`, so before every tick this module clones the board's seven models ("shadow models"),
//! and after the tick samples the clones with the same true state the board saw (read back from
//! `sim.body`, computed exactly as `Sim::tick` computes it). That reproduces the samples bit for
//! bit. Proof, checked on every tick: a *twin* `FlightCore` (same calibrated `Params`), fed the
//! shadow samples and driven by its own in-process mission computer (`LinuxSide`, same schedule
//! as `Sim`), must output exactly the motor commands of the simulator's core. If a sample
//! differed in a single bit the twin would diverge and the bench would abort.
//!
//! The twin also gives the cost of `FlightCore::step` alone (the simulator's own counter,
//! `core_wall_ns`, also contains the sensor models and the mission computer).

#![allow(dead_code)]

use fcc_firmware::flight::FlightCore;
use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::link::LinkEndpoint;
use fcc_firmware::params::Params;
use fcc_firmware::scheduler::TICK_US;
use fcc_firmware::sensors::SensorInputs;
use fcc_msgs::StreamRates;
use fcc_nav::tilt_kf::TiltCorrection;
use fcc_sim::linux::LinuxSide;
use fcc_sim::scenario::Scenario;
use fcc_sim::sim::Sim;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Scenario file `launch_configs/scenarios/<name>.yaml`.
pub fn scenario_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../launch_configs/scenarios")
        .join(format!("{name}.yaml"))
}

pub fn load_scenario(name: &str) -> Scenario {
    Scenario::load(&scenario_path(name)).unwrap_or_else(|e| panic!("scenario {name}: {e}"))
}

/// One 2 ms tick of the captured flight.
#[derive(Clone, Copy, Debug)]
pub struct Tick {
    pub t_us: u64,
    /// Exactly what the flight core received this tick.
    pub inputs: SensorInputs,
    /// True attitude (ZYX roll, pitch, yaw, rad) after the tick, from the physics.
    pub true_euler_rad: [f64; 3],
    /// The vehicle is off the ground.
    pub airborne: bool,
    /// The core's navigation has finished its ground calibration.
    pub calibrated: bool,
    /// The core's own attitude estimate (roll, pitch, yaw, rad).
    pub core_euler_rad: [f32; 3],
    /// The manoeuvre acceleration (NED, m/s²) the core's *next* attitude step removes from the
    /// specific force (`Navigator::tilt_accel_comp_ned_mps2` after this tick).
    pub tilt_comp_next_ned_mps2: [f32; 3],
    /// The core's *next* attitude step corrects the tilt from the GPS velocity, not the
    /// accelerometer (`Navigator::gps_tilt_aided` after this tick).
    pub gps_tilt_aided_next: bool,
    /// The tilt correction the GPS velocity made in this tick, after the attitude step
    /// (`Navigator::gps_tilt_applied`).
    pub gps_tilt: Option<TiltCorrection>,
}

pub struct Capture {
    pub scenario: String,
    /// The seed the scenario was flown with.
    pub seed: u64,
    /// The calibrated parameters the simulator's core runs with.
    pub params: Params,
    pub ticks: Vec<Tick>,
    /// Wall ns of each twin `FlightCore::step` call (timer overhead subtracted).
    pub step_ns: Vec<f64>,
    /// Estimated cost of one `Instant::now()` pair, subtracted above.
    pub timer_overhead_ns: f64,
    /// The MCU's real link output at `StreamRates::DEFAULT` (`LinkEndpoint::poll_tx`), if asked.
    pub telemetry: Vec<u8>,
    /// Telemetry frames the endpoint dropped (buffer full); must be 0.
    pub telemetry_dropped: u32,
    pub sim_s: f64,
}

struct Shadow {
    imu: fcc_sim::sensor_models::ImuModel,
    mag: fcc_sim::sensor_models::MagModel,
    baro: fcc_sim::sensor_models::BaroModel,
    gps: fcc_sim::sensor_models::GpsModel,
    battery: fcc_sim::sensor_models::BatteryModel,
    laser: fcc_sim::rangefinders::LaserModel,
    sonar: fcc_sim::rangefinders::SonarModel,
}

fn timer_overhead_ns() -> f64 {
    let n = 200_000;
    let mut best = f64::MAX;
    for _ in 0..3 {
        let mut sum = 0u128;
        for _ in 0..n {
            let t0 = Instant::now();
            sum += std::hint::black_box(t0.elapsed()).as_nanos();
        }
        best = best.min(sum as f64 / n as f64);
    }
    best
}

/// Fly scenario `name` (flown, not carried; no faults) in lockstep and capture every tick.
pub fn capture(name: &str, with_link: bool) -> Capture {
    capture_seeded(name, 0, with_link)
}

/// [`capture`] with `seed_add` added to the scenario's seed (0: the scenario as written).
pub fn capture_seeded(name: &str, seed_add: u64, with_link: bool) -> Capture {
    let mut s = load_scenario(name);
    s.seed += seed_add;
    assert!(
        s.faults.is_empty(),
        "capture replays the sensor models without fault injection: pick a scenario without faults"
    );
    let mut sim = Sim::new(s.clone()).expect("sim");
    assert!(
        matches!(sim.log.plan_kind, "hover" | "mission"),
        "capture needs a flown scenario (the carried ones set the specific force differently)"
    );
    let params = *sim.fc.core.params();
    let mut twin = FlightCore::new(params);
    let mut twin_linux = LinuxSide::new(&s).expect("mission computer");
    let mut link = LinkEndpoint::new(StreamRates::DEFAULT);
    let mut tx = [0u8; 1024];
    let overhead = timer_overhead_ns();
    let mut ticks = Vec::new();
    let mut step_ns = Vec::new();
    let mut telemetry = Vec::new();
    while !sim.finished() {
        let b = &sim.board;
        let mut sh = Shadow {
            imu: b.imu.clone(),
            mag: b.mag.clone(),
            baro: b.baro.clone(),
            gps: b.gps.clone(),
            battery: b.battery.clone(),
            laser: b.laser.clone(),
            sonar: b.sonar.clone(),
        };
        sim.tick();
        // The true state the board sampled inside the tick (as `Sim::tick` computes it).
        let t = sim.t_us;
        let body = &sim.body;
        let st = &body.state;
        let b = &sim.board;
        let rotor_mean = st.rotor_speed_frac.iter().sum::<f64>() / MOTOR_COUNT as f64;
        let inputs = SensorInputs {
            imu: Some(sh.imu.sample(
                t,
                st.omega_frd_radps,
                body.specific_force_frd_mps2(),
                rotor_mean,
            )),
            mag: sh.mag.sample(t, &st.q_body_to_ned),
            baro: sh.baro.sample(t, -st.pos_ned_m.z, !body.on_ground()),
            gps: sh.gps.sample(t, st.pos_ned_m, st.vel_ned_mps),
            laser: sh
                .laser
                .sample(t, st.pos_ned_m, &st.q_body_to_ned, &b.terrain, b.air_temp_c),
            sonar: sh
                .sonar
                .sample(t, st.pos_ned_m, &st.q_body_to_ned, &b.terrain, b.air_temp_c),
            battery: sh
                .battery
                .sample(t, body.electrical_power_w() / 18.5, TICK_US as f64 * 1e-6),
        };
        // The twin: same schedule as `Sim::tick` (mission computer at 20 Hz, before the step).
        if sim.ticks() % 25 == 0 {
            twin_linux.update(t, &mut twin);
        }
        let t0 = Instant::now();
        let motors = twin.step(t, &inputs);
        let ns = t0.elapsed().as_nanos() as f64;
        step_ns.push((ns - overhead).max(0.0));
        assert_eq!(
            &motors,
            sim.fc.core.motors(),
            "twin core diverged at t = {t} µs: the captured samples are not the ones the simulator's core saw"
        );
        if with_link {
            let n = link.poll_tx(t, &sim.fc.core, &inputs, &mut tx);
            telemetry.extend_from_slice(&tx[..n]);
        }
        let (roll, pitch, yaw) = st.q_body_to_ned.euler_angles();
        let e = sim.fc.core.nav().euler;
        ticks.push(Tick {
            t_us: t,
            inputs,
            true_euler_rad: [roll, pitch, yaw],
            airborne: !body.on_ground(),
            calibrated: sim.fc.core.nav().calibrated,
            core_euler_rad: [e.roll_rad, e.pitch_rad, e.yaw_rad],
            tilt_comp_next_ned_mps2: sim.fc.core.navigator().tilt_accel_comp_ned_mps2(),
            gps_tilt_aided_next: sim.fc.core.navigator().gps_tilt_aided(),
            gps_tilt: sim.fc.core.navigator().gps_tilt_applied(),
        });
    }
    Capture {
        scenario: name.to_string(),
        seed: s.seed,
        params,
        ticks,
        step_ns,
        timer_overhead_ns: overhead,
        telemetry,
        telemetry_dropped: link.stats().tx_dropped,
        sim_s: sim.t_s(),
    }
}

/// Best (lowest) wall time of `reps` runs of `f`, in seconds; `f` returns a value kept alive.
pub fn best_of<T>(reps: usize, mut f: impl FnMut() -> T) -> f64 {
    let mut best = f64::MAX;
    for _ in 0..reps {
        let t0 = Instant::now();
        std::hint::black_box(f());
        best = best.min(t0.elapsed().as_secs_f64());
    }
    best
}

/// Best wall time of `a` and of `b` over `reps` rounds, the two run alternately in each round
/// so that both see the same machine (a shared, noisy host drifts between two back-to-back
/// series more than within one round).
pub fn best_of_interleaved<T, U>(
    reps: usize,
    mut a: impl FnMut() -> T,
    mut b: impl FnMut() -> U,
) -> (f64, f64) {
    let (mut best_a, mut best_b) = (f64::MAX, f64::MAX);
    for _ in 0..reps {
        let t0 = Instant::now();
        std::hint::black_box(a());
        best_a = best_a.min(t0.elapsed().as_secs_f64());
        let t0 = Instant::now();
        std::hint::black_box(b());
        best_b = best_b.min(t0.elapsed().as_secs_f64());
    }
    (best_a, best_b)
}

/// One table row for `scripts/bench.sh`:
/// `ROW|id|what|ours|peer|ratio|goal|verdict`. No `|` inside the fields.
pub fn row(id: &str, what: &str, ours: &str, peer: &str, ratio: &str, goal: &str, verdict: &str) {
    for f in [id, what, ours, peer, ratio, goal, verdict] {
        assert!(!f.contains('|') && !f.contains('\n'), "field {f:?}");
    }
    println!("ROW|{id}|{what}|{ours}|{peer}|{ratio}|{goal}|{verdict}");
}

/// A note printed under the table (`NOTE|id|text`).
pub fn note(id: &str, text: &str) {
    assert!(!text.contains('\n'));
    println!("NOTE|{id}|{text}");
}

pub fn verdict(met: bool) -> &'static str {
    if met {
        "met"
    } else {
        "**missed**"
    }
}

/// Thousands separators for readability: 1234567 → "1,234,567".
pub fn thousands(x: f64) -> String {
    let n = x.round() as i64;
    let s = n.abs().to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    if n < 0 {
        format!("-{out}")
    } else {
        out
    }
}
