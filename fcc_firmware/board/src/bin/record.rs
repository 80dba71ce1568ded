//! Host tool: fly the SITL's octorotor (physics + sensor models of `fcc_sim`) in closed
//! loop with the host build of the flight core, and record every tick's sensor inputs, the
//! operator's commands and setpoints, and the motor outputs.
//!
//!   record [SECONDS] [OUT_DIR]   (defaults: 16 s, ./data)
//!
//! Writes `OUT_DIR/inputs.bin` (replayed on the MCU / QEMU) and `OUT_DIR/expected.bin` (the host
//! build's outputs). The flight: 2 s calibration on the ground, arm, climb to 3 m, fly north at
//! 2 m/s then east, land. The replay of the recording on the host must give the same outputs
//! bit for bit (checked here), so the recording captures everything the core depends on.

use fcc_board::replay::{encode, Event};
use fcc_firmware::commands::{Command, VelocitySetpoint, YawSetpoint};
use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::scheduler::{FlightComputer, TICK_US};
use fcc_firmware::sensors::{SensorBoard, SensorInputs};
use fcc_sim::scenario::Scenario;
use fcc_sim::sim::Sim;
use nalgebra::Vector3;

const SCENARIO: &str = "
name: mcu-record
seed: 7
duration_s: 60
flight:
  kind: hover
  alt_m: 3.0
  hold_s: 1.0
";

use fcc_firmware::sensors::MotorLatch as Latch;

/// The sensors sampled from the physics' true state (what `Sim::tick` does, minus wind).
struct Board<'a> {
    sim: &'a mut Sim,
    prev_vel: Vector3<f64>,
    /// What the last poll handed the core (recorded).
    polled: SensorInputs,
}

impl SensorBoard for Board<'_> {
    fn poll(&mut self, now_us: u64) -> SensorInputs {
        let s = &mut *self.sim;
        let st = s.body.state.clone();
        let f = s.body.specific_force_frd_mps2();
        let mean = st.rotor_speed_frac.iter().sum::<f64>() / MOTOR_COUNT as f64;
        let in_flight = !s.body.on_ground();
        let current = s.body.electrical_power_w() / 18.5;
        let b = &mut s.board;
        let _ = self.prev_vel;
        self.polled = SensorInputs {
            imu: Some(b.imu.sample(now_us, st.omega_frd_radps, f, mean)),
            mag: b.mag.sample(now_us, &st.q_body_to_ned),
            baro: b.baro.sample(now_us, -st.pos_ned_m.z, in_flight),
            gps: b.gps.sample(now_us, st.pos_ned_m, st.vel_ned_mps),
            laser: b.laser.sample(now_us, st.pos_ned_m, &st.q_body_to_ned, &b.terrain, b.air_temp_c),
            sonar: b.sonar.sample(now_us, st.pos_ned_m, &st.q_body_to_ned, &b.terrain, b.air_temp_c),
            battery: b.battery.sample(now_us, current, TICK_US as f64 * 1e-6),
        };
        self.polled
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seconds: f64 = args.get(1).map_or(16.0, |s| s.parse().expect("SECONDS"));
    let out_dir = std::path::PathBuf::from(args.get(2).map_or("data", |s| s.as_str()));
    let scenario = Scenario::from_yaml_str(SCENARIO).unwrap_or_else(|e| panic!("scenario: {e:?}"));
    let params = scenario.params;
    assert!(params == fcc_firmware::params::Params::default(), "the replay images use Params::default()");
    // The Sim supplies the physics and the sensor models; its own core and Linux stand-in are
    // not used (this loop is the lockstep tick, so the inputs can be recorded).
    let mut sim = Sim::new(scenario).expect("sim");
    // The flight computer's tick as the replay runs it (no link traffic: the mission computer
    // below talks to the core directly and is recorded as events).
    let mut fc = FlightComputer::new(params);
    let mut tx = [0u8; fcc_board::replay::TX_BYTES];

    let mut w = encode::InputWriter::new();
    let mut outputs: Vec<[f32; MOTOR_COUNT]> = Vec::new();
    let mut motors = Latch([0.0; MOTOR_COUNT]);
    let ticks = (seconds * 1e6 / TICK_US as f64) as u64;
    let mut t_us = 0u64;
    let mut armed_at: Option<u64> = None;
    let mut land_sent = false;
    for k in 1..=ticks {
        // Physics: four 0.5 ms substeps on the previous tick's motor commands.
        let dt = TICK_US as f64 * 1e-6;
        let p = sim.body.state.pos_ned_m;
        let ground_down = sim.board.terrain.ground_down_at(p.x, p.y) - sim.body.params.gear_height_m;
        for _ in 0..4 {
            sim.body.step(&motors.0, Vector3::zeros(), ground_down, dt / 4.0);
        }
        t_us += TICK_US;

        // The mission computer at 20 Hz: arm when ready, climb, fly a leg north then east, land.
        let mut events: Vec<Event> = Vec::new();
        if k % 25 == 0 {
            let sp = |v: [f32; 3]| VelocitySetpoint { vel_ned_mps: v, yaw: YawSetpoint::Keep, ttl_ms: 300 };
            match armed_at {
                None => {
                    if fc.core.navigator().ready().is_ok() {
                        events.push(Event::Command(Command::Arm));
                        armed_at = Some(t_us);
                    }
                }
                Some(t0) => {
                    let since = (t_us - t0) as f64 * 1e-6;
                    let alt = -fc.core.nav().pos_ned_m[2];
                    if since < 4.0 {
                        events.push(Event::Setpoint(sp([0.0, 0.0, -(0.8 * (3.0 - alt)).clamp(-1.0, 1.5)])));
                    } else if since < 7.0 {
                        events.push(Event::Setpoint(sp([2.0, 0.0, 0.0])));
                    } else if since < 9.0 {
                        events.push(Event::Setpoint(sp([0.0, 1.5, 0.0])));
                    } else if !land_sent {
                        events.push(Event::Command(Command::Land));
                        land_sent = true;
                    }
                }
            }
        }
        for e in &events {
            let _ = match *e {
                Event::Command(c) => fc.core.command(t_us, c),
                Event::Setpoint(s) => fc.core.setpoint(t_us, s),
            };
        }
        let mut board = Board { sim: &mut sim, prev_vel: Vector3::zeros(), polled: SensorInputs::default() };
        fc.tick(t_us, &[], &mut board, &mut motors, &mut tx);
        w.tick(t_us, &board.polled, &events);
        outputs.push(motors.0);
    }
    let inputs = w.finish();
    let expected = encode::outputs(&outputs);

    // The recording must be complete: replaying it on a fresh core gives the same outputs.
    let mut mismatches = 0u32;
    let n = fcc_board::replay::replay(params, &inputs, |i, m| {
        if outputs[i as usize] != *m {
            mismatches += 1;
        }
    })
    .expect("decode");
    assert_eq!(n as usize, outputs.len());
    assert_eq!(mismatches, 0, "host replay differs from the closed-loop run");

    let st = &sim.body.state;
    let max_cmd = outputs.iter().flat_map(|m| m.iter()).fold(0.0f32, |a, &b| a.max(b));
    std::fs::create_dir_all(&out_dir).expect("mkdir");
    std::fs::write(out_dir.join("inputs.bin"), &inputs).expect("write inputs");
    std::fs::write(out_dir.join("expected.bin"), &expected).expect("write expected");
    println!(
        "recorded {n} ticks ({seconds} s): inputs {} B, expected {} B; end: pos NED {:.2?} m, mode {:?}, \
         armed {}, max motor cmd {max_cmd:.3}; host replay identical",
        inputs.len(),
        expected.len(),
        [st.pos_ned_m.x, st.pos_ned_m.y, st.pos_ned_m.z],
        fc.core.mode(),
        fc.core.armed(),
    );
}
