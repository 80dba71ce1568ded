//! The lockstep simulation: physics and sensor models around the unchanged flight core, with an
//! in-process stand-in for the Linux computer (the same waypoint logic `fcc_mission` uses).
//!
//! One call to [`Sim::tick`] advances 2 ms: four 0.5 ms physics substeps, the sensors sample the
//! true state, and the flight computer's tick ([`FlightComputer::tick`], the board's) polls
//! them; its motor commands go back to the physics on the next tick (one-tick actuation delay,
//! as on the board).

use super::linux::LinuxSide;
use super::log::{FlightLog, LogSample};
use super::physics::Octorotor;
use super::rangefinders::{LaserModel, SonarModel};
use super::scenario::{Fault, FlightPlan, Scenario};
use super::sensor_models::{BaroModel, BaroParams, BatteryModel, GpsModel, ImuModel, MagModel};
use super::terrain::Terrain;
use super::wind::Wind;
use fcc_firmware::commands::Mode;
use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::link::LinkEndpoint;
use fcc_firmware::params::{Params, RateParams};
use fcc_firmware::scheduler::{FlightComputer, TICK_US};
use fcc_firmware::sensors::{SensorBoard, SensorInputs};
use nalgebra::{UnitQuaternion, Vector3};

const PHYSICS_SUBSTEPS: u32 = 4;
/// Log every 10th tick (50 Hz).
const LOG_EVERY_TICKS: u64 = 10;

/// The simulated board: sensor models sampling the true state.
pub struct SimBoard {
    pub imu: ImuModel,
    pub mag: MagModel,
    pub baro: BaroModel,
    pub gps: GpsModel,
    pub battery: BatteryModel,
    pub laser: LaserModel,
    pub sonar: SonarModel,
    pub terrain: Terrain,
    pub air_temp_c: f64,
    /// Rangefinder samples handed to the core since the last log pass: (laser?, sample).
    polled_ranges: Vec<(bool, fcc_firmware::sensors::RangeSample)>,
    truth: Truth,
}

/// The true state the sensors see at the current tick.
#[derive(Clone, Copy, Debug)]
pub struct Truth {
    pub pos_ned_m: Vector3<f64>,
    pub vel_ned_mps: Vector3<f64>,
    pub accel_ned_mps2: Vector3<f64>,
    pub q_body_to_ned: UnitQuaternion<f64>,
    pub omega_frd_radps: Vector3<f64>,
    pub specific_force_frd_mps2: Vector3<f64>,
    pub rotor_speed_mean: f64,
    pub in_flight: bool,
    pub current_a: f64,
}

impl SensorBoard for SimBoard {
    fn poll(&mut self, now_us: u64) -> SensorInputs {
        let t = self.truth;
        let out = SensorInputs {
            imu: Some(self.imu.sample(
                now_us,
                t.omega_frd_radps,
                t.specific_force_frd_mps2,
                t.rotor_speed_mean,
            )),
            mag: self.mag.sample(now_us, &t.q_body_to_ned),
            baro: self.baro.sample(now_us, -t.pos_ned_m.z, t.in_flight),
            gps: self.gps.sample(now_us, t.pos_ned_m, t.vel_ned_mps),
            laser: self.laser.sample(
                now_us,
                t.pos_ned_m,
                &t.q_body_to_ned,
                &self.terrain,
                self.air_temp_c,
            ),
            sonar: self.sonar.sample(
                now_us,
                t.pos_ned_m,
                &t.q_body_to_ned,
                &self.terrain,
                self.air_temp_c,
            ),
            battery: self
                .battery
                .sample(now_us, t.current_a, TICK_US as f64 * 1e-6),
        };
        if let Some(l) = out.laser {
            self.polled_ranges.push((true, l));
        }
        if let Some(r) = out.sonar {
            self.polled_ranges.push((false, r));
        }
        out
    }
}

use fcc_firmware::sensors::MotorLatch;

/// Kinematic truth for scenarios where the vehicle is carried (elevator).
struct Carried {
    profile: Vec<[f64; 3]>,
    /// Fixed attitude of the rig (body to NED); `None` keeps the vehicle level.
    attitude: Option<UnitQuaternion<f64>>,
}

impl SimBoard {
    /// The scenario's sensor models (seeded with its seed), on the scenario's terrain and air.
    fn new(scenario: &Scenario) -> Self {
        let seed = scenario.seed;
        let s = &scenario.sensors;
        SimBoard {
            imu: ImuModel::new(s.imu.clone(), seed),
            mag: MagModel::new(s.mag.clone(), seed),
            // The barometer's atmosphere (and its thermometer) is the scenario's air.
            baro: BaroModel::new(
                BaroParams {
                    t0_c: scenario.air_temp_c,
                    ..s.baro.clone()
                },
                seed,
            ),
            gps: GpsModel::new(s.gps.clone(), seed),
            battery: BatteryModel::new(Default::default(), seed),
            laser: LaserModel::new(s.laser.clone(), seed),
            sonar: SonarModel::new(s.sonar.clone(), seed),
            terrain: scenario.terrain.clone(),
            air_temp_c: scenario.air_temp_c,
            polled_ranges: Vec::new(),
            truth: Truth {
                pos_ned_m: Vector3::zeros(),
                vel_ned_mps: Vector3::zeros(),
                accel_ned_mps2: Vector3::zeros(),
                q_body_to_ned: UnitQuaternion::identity(),
                omega_frd_radps: Vector3::zeros(),
                specific_force_frd_mps2: Vector3::new(0.0, 0.0, -fcc_nav::GRAVITY_MPS2 as f64),
                rotor_speed_mean: 0.0,
                in_flight: false,
                current_a: 0.5,
            },
        }
    }
}

impl Carried {
    /// The rig or the elevator of a carried plan; `None` when the vehicle flies.
    fn of(plan: &FlightPlan) -> Option<Self> {
        match plan {
            FlightPlan::Rig {
                height_m,
                roll_deg,
                pitch_deg,
            } => Some(Self {
                profile: vec![[*height_m as f64, 0.0, 0.0]],
                attitude: Some(UnitQuaternion::from_euler_angles(
                    (*roll_deg as f64).to_radians(),
                    (*pitch_deg as f64).to_radians(),
                    0.0,
                )),
            }),
            FlightPlan::Elevator {
                floors,
                floor_height_m,
                speed_mps,
                accel_mps2,
                dwell_s,
            } => Some(Self {
                profile: super::linux::elevator_profile(
                    floors,
                    *floor_height_m,
                    *speed_mps,
                    *accel_mps2,
                    *dwell_s,
                ),
                attitude: None,
            }),
            _ => None,
        }
    }
}

pub struct Sim {
    pub scenario: Scenario,
    pub t_us: u64,
    /// The MCU program under test (flight core + link endpoint), unchanged.
    pub fc: FlightComputer,
    pub body: Octorotor,
    pub board: SimBoard,
    wind: Wind,
    wind_ned: Vector3<f64>,
    motors: MotorLatch,
    linux: LinuxSide,
    /// The scripted R/C pilot's receiver (scenario `pilot:`).
    receiver: super::pilot::SimReceiver,
    carried: Option<Carried>,
    ticks: u64,
    /// The tick of the last 50 Hz sample ([`Self::finish`] records the last tick's own).
    last_record_tick: Option<u64>,
    pub log: FlightLog,
    /// Wall time spent inside the flight computer's tick (sensors polled + step, plus the link
    /// when served), for the benchmark.
    pub core_wall_ns: u128,
    /// The board's UART served on a pty (`--link-pty`): the Linux side is then a real process
    /// (bridge + mission node) and the in-process stand-in is off.
    link: Option<super::pty::PtyLink>,
    /// The bytes read from the pty in one tick.
    rx: Vec<u8>,
    /// The gear has been truly airborne since the last ground contact.
    airborne_since_contact: bool,
    /// The gear touched the ground in the last substep (a foot, or the whole gear).
    gear_touching: bool,
    /// A crash or tip-over ended the flight (truth).
    crashed: bool,
    /// The simulator's own events (crashes), merged into the log's at [`Self::finish`].
    sim_events: Vec<(f64, String)>,
    /// Samples and range readings go to this scratch file while the run lasts
    /// ([`Self::spill_log`]); read back into `log` at [`Self::finish`].
    spill: Option<super::log::Spill>,
    /// The scratch file failed to take a record: the rest stays in memory.
    spill_failed: bool,
}

impl Sim {
    pub fn new(scenario: Scenario) -> Result<Self, String> {
        let seed = scenario.seed;
        let gear = scenario.vehicle.gear_height_m;
        let start_down = scenario.terrain.ground_down_at(0.0, 0.0) - gear;
        let body = Octorotor::new(
            air_at(
                &scenario.vehicle,
                scenario.air_temp_c,
                scenario.sensors.baro.p0_pa,
            ),
            Vector3::new(0.0, 0.0, start_down),
            0.0,
        );
        let board = SimBoard::new(&scenario);
        let linux = LinuxSide::new(&scenario)?;
        let carried = Carried::of(&scenario.flight);
        let mut params = scenario.params;
        if scenario.sensors.calibration.enabled {
            calibrate(&mut params, &board, &scenario.sensors, seed);
        }
        Ok(Self {
            // Telemetry off until a link is served: the in-process mission computer reads the
            // core directly.
            fc: FlightComputer::new(Params {
                rates: RateParams::off(),
                ..params
            }),
            body,
            board,
            wind: Wind::new(scenario.wind.clone(), seed),
            wind_ned: Vector3::zeros(),
            motors: MotorLatch([0.0; MOTOR_COUNT]),
            linux,
            receiver: super::pilot::SimReceiver::new(&scenario.pilot),
            carried,
            t_us: 0,
            ticks: 0,
            last_record_tick: None,
            log: FlightLog {
                truth: super::truth::TruthCounters {
                    start_down_m: start_down,
                    ..Default::default()
                },
                commanded_alt_m: match &scenario.flight {
                    FlightPlan::Hover { alt_m, .. } | FlightPlan::Velocity { alt_m, .. } => {
                        Some(*alt_m as f64)
                    }
                    _ => None,
                },
                plan_kind: match &scenario.flight {
                    FlightPlan::Hover { .. } => "hover",
                    FlightPlan::Mission { .. } | FlightPlan::MissionInline { .. } => "mission",
                    FlightPlan::Velocity { .. } => "velocity",
                    FlightPlan::Elevator { .. } => "elevator",
                    FlightPlan::Rig { .. } => "rig",
                },
                ..Default::default()
            },
            core_wall_ns: 0,
            link: None,
            rx: Vec::new(),
            airborne_since_contact: false,
            gear_touching: true,
            crashed: false,
            sim_events: Vec::new(),
            spill: None,
            spill_failed: false,
            scenario,
        })
    }

    /// Serve the flight core's link on a pseudo-terminal instead of the in-process Linux side.
    /// Its telemetry starts at the scenario's `rates.*` parameters (the table's defaults unless
    /// the scenario sets them; settable over the link like any parameter).
    pub fn serve_link(
        &mut self,
        pty: super::pty::PtyLink,
    ) -> Result<(), fcc_firmware::params::ParamError> {
        let rates = self.scenario.params.stream_rates();
        self.fc.set_stream_rates(rates)?;
        self.fc.link = LinkEndpoint::new(rates);
        self.link = Some(pty);
        Ok(())
    }

    /// Keep the 50 Hz samples and the range readings in a scratch file in `dir` while the run
    /// lasts (flat memory for a long real-time run); [`Self::finish`] reads them back, so the
    /// log is the same. Should the file fail, the rest is kept in memory (an event says so).
    pub fn spill_log(&mut self, dir: &std::path::Path) -> Result<(), super::log::SpillError> {
        self.spill = Some(super::log::Spill::create(dir)?);
        Ok(())
    }

    fn spill_error(&mut self, e: super::log::SpillError) {
        self.spill_failed = true;
        let t = self.t_s();
        self.sim_events.push((
            t,
            format!("{e}; the flight log is kept in memory from here on"),
        ));
    }

    fn keep_sample(&mut self, s: LogSample) {
        if let (Some(sp), false) = (self.spill.as_mut(), self.spill_failed) {
            match sp.push_sample(&s) {
                Ok(()) => return,
                Err(e) => self.spill_error(e),
            }
        }
        self.log.samples.push(s);
    }

    fn keep_range(&mut self, r: super::log::RangeRecord) {
        if let (Some(sp), false) = (self.spill.as_mut(), self.spill_failed) {
            match sp.push_range(&r) {
                Ok(()) => return,
                Err(e) => self.spill_error(e),
            }
        }
        self.log.ranges.push(r);
    }

    /// The served link, if any: the MCU's endpoint and the pty.
    pub fn link(&self) -> Option<(&LinkEndpoint, &super::pty::PtyLink)> {
        self.link.as_ref().map(|pty| (&self.fc.link, pty))
    }

    /// The in-process mission computer (its refusal counters).
    pub fn linux(&self) -> &LinuxSide {
        &self.linux
    }

    /// 2 ms ticks run so far.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    pub fn t_s(&self) -> f64 {
        self.t_us as f64 * 1e-6
    }

    /// Whether the run is over (duration reached, or the plan finished and the vehicle is
    /// disarmed on the ground).
    pub fn finished(&self) -> bool {
        self.crashed
            || self.t_s() >= self.scenario.duration_s
            || (self.link.is_none() && self.linux.done())
    }

    /// A crash or tip-over ended the run.
    pub fn crashed(&self) -> bool {
        self.crashed
    }

    /// One physics substep, watching the gear: the first contact after true flight is scored
    /// ([`super::truth::classify_contact`]) — the whole gear on the ground, or before it the
    /// lowest foot of a leaning vehicle ([`super::truth::foot_clearance_m`]).
    fn physics_substep(&mut self, ground_down: f64, sub: f64) {
        let was_touching = self.gear_touching;
        let v = self.body.state.vel_ned_mps;
        let q = self.body.state.q_body_to_ned;
        self.body
            .step(&self.motors.0, self.wind_ned, ground_down, sub);
        let foot_m = super::truth::foot_clearance_m(
            ground_down - self.body.state.pos_ned_m.z,
            tilt_deg(&self.body.state.q_body_to_ned),
            self.body.params.gear_height_m,
        );
        if foot_m > super::truth::AIRBORNE_CLEARANCE_M {
            self.airborne_since_contact = true;
        }
        self.gear_touching = self.body.on_ground() || foot_m <= 0.0;
        if was_touching || !self.gear_touching || !self.airborne_since_contact {
            return;
        }
        self.airborne_since_contact = false;
        let tilt_deg = tilt_deg(&q);
        let mode = self.fc.core.mode();
        let (vz, vh) = (v.z, v.x.hypot(v.y));
        let outcome =
            super::truth::classify_contact(vz, vh, tilt_deg, self.body.params.gear_height_m);
        let t_s = self.t_s();
        self.log.contacts.push(super::truth::Contact {
            t_s,
            vz_down_mps: vz,
            v_horiz_mps: vh,
            tilt_deg,
            mode,
            planned: matches!(mode, Mode::Land | Mode::Pilot),
            outcome,
            gate_wait_s: self.fc.core.touchdown_gate().wait_s() as f64,
            gate_forced: self.fc.core.touchdown_gate().forced(),
        });
        if outcome != super::truth::ContactOutcome::Landed {
            self.crashed = true;
            self.sim_events.push((
                t_s,
                format!("{outcome:?}: touchdown at {vz:.2} m/s down, {vh:.2} m/s horizontal, tilt {tilt_deg:.1}° — run ended"),
            ));
        }
    }

    /// Truth counters of one tick.
    fn count_truth(&mut self) {
        let st = &self.body.state;
        let p = st.pos_ned_m;
        let ground = self.board.terrain.ground_down_at(p.x, p.y) - self.body.params.gear_height_m;
        if ground - p.z <= super::truth::AIRBORNE_CLEARANCE_M || self.carried.is_some() {
            return;
        }
        let c = &mut self.log.truth;
        let dt = TICK_US as f64 * 1e-6;
        if self.fc.core.armed() && !self.fc.core.telemetry().attitude_active {
            c.attitude_off_airborne_s += dt;
        }
        c.max_tilt_deg = c.max_tilt_deg.max(tilt_deg(&st.q_body_to_ned));
        c.max_speed_mps = c
            .max_speed_mps
            .max(st.vel_ned_mps.x.hypot(st.vel_ned_mps.y));
    }

    fn apply_faults(&mut self) -> bool {
        let t = self.t_s();
        let mut mag_field = Vector3::zeros();
        let mut gps_on = true;
        let mut gps_jump = Vector3::zeros();
        let mut linux_on = true;
        for f in &self.scenario.faults {
            let (a, b) = f.window();
            if t < a || t >= b {
                continue;
            }
            match f {
                Fault::MagDisturbance { field_ned_ut, .. } => {
                    mag_field += Vector3::new(field_ned_ut[0], field_ned_ut[1], field_ned_ut[2]);
                }
                Fault::GpsOutage { .. } => gps_on = false,
                Fault::GpsJump { offset_ned_m, .. } => {
                    gps_jump += Vector3::new(offset_ned_m[0], offset_ned_m[1], offset_ned_m[2]);
                }
                Fault::LinuxSilent { .. } => linux_on = false,
            }
        }
        self.board.mag.set_disturbance(mag_field);
        self.board.gps.set_available(gps_on);
        self.board.gps.set_jump(gps_jump);
        linux_on
    }

    /// Advance one 2 ms control tick: the airframe (or the carried rig), the truth the
    /// sensors read, the flight computer's tick, the rangefinder log.
    pub fn tick(&mut self) {
        let dt = TICK_US as f64 * 1e-6;
        let linux_on = self.apply_faults();
        let prev_vel = self.body.state.vel_ned_mps;
        let t_next_s = self.t_s() + dt;
        let carried = self.carried.as_ref();
        let carried = carried.map(|c| (sample_profile(&c.profile, t_next_s), c.attitude));
        match carried {
            Some(((z, v, a), attitude)) => self.carry(z, v, a, attitude),
            None => self.fly(dt, prev_vel),
        }
        self.t_us += TICK_US;
        self.ticks += 1;
        self.publish_truth();
        let t0 = std::time::Instant::now();
        self.run_flight_computer(linux_on);
        self.core_wall_ns += t0.elapsed().as_nanos();
        self.count_truth();
        self.keep_polled_ranges();
        if self.ticks % LOG_EVERY_TICKS == 0 {
            self.record();
        }
    }

    /// Paper B's rig: the vehicle carried along the profile (height `z_m` up, its rate and
    /// acceleration), at the rig's attitude if it has one; nothing flies.
    fn carry(
        &mut self,
        z_m: f64,
        v_up_mps: f64,
        a_up_mps2: f64,
        attitude: Option<UnitQuaternion<f64>>,
    ) {
        self.body.state.pos_ned_m = Vector3::new(0.0, 0.0, -z_m);
        self.body.state.vel_ned_mps = Vector3::new(0.0, 0.0, -v_up_mps);
        if let Some(q) = attitude {
            self.body.state.q_body_to_ned = q;
        }
        let g = fcc_nav::GRAVITY_MPS2 as f64;
        let a_ned = Vector3::new(0.0, 0.0, -a_up_mps2);
        let f_ned = a_ned - Vector3::new(0.0, 0.0, g);
        let f_body = self
            .body
            .state
            .q_body_to_ned
            .inverse_transform_vector(&f_ned);
        self.board.truth.specific_force_frd_mps2 = f_body;
        self.board.truth.accel_ned_mps2 = a_ned;
        self.board.truth.in_flight = false;
    }

    /// The airframe in the wind of its height over the terrain, [`PHYSICS_SUBSTEPS`] physics
    /// steps over `dt_s`; `prev_vel` is the velocity before them (the acceleration's truth).
    fn fly(&mut self, dt_s: f64, prev_vel: Vector3<f64>) {
        let p = self.body.state.pos_ned_m;
        let height = (self.board.terrain.ground_down_at(p.x, p.y) - p.z).max(0.0);
        self.wind_ned = self.wind.step(height, self.body.state.vel_ned_mps, dt_s);
        let sub = dt_s / PHYSICS_SUBSTEPS as f64;
        let ground_down =
            self.board.terrain.ground_down_at(p.x, p.y) - self.body.params.gear_height_m;
        for _ in 0..PHYSICS_SUBSTEPS {
            self.physics_substep(ground_down, sub);
        }
        self.board.truth.specific_force_frd_mps2 = self.body.specific_force_frd_mps2();
        self.board.truth.accel_ned_mps2 = (self.body.state.vel_ned_mps - prev_vel) / dt_s;
        self.board.truth.in_flight = !self.body.on_ground();
    }

    /// The body's state, as the simulated sensors read it.
    fn publish_truth(&mut self) {
        let st = &self.body.state;
        self.board.truth.pos_ned_m = st.pos_ned_m;
        self.board.truth.vel_ned_mps = st.vel_ned_mps;
        self.board.truth.q_body_to_ned = st.q_body_to_ned;
        self.board.truth.omega_frd_radps = st.omega_frd_radps;
        let mean_speed = st.rotor_speed_frac.iter().sum::<f64>() / MOTOR_COUNT as f64;
        self.board.truth.rotor_speed_mean = mean_speed;
        self.board.truth.current_a = self.body.electrical_power_w() / 18.5;
    }

    /// The flight computer's tick: the R/C frame, then the link bytes in (the pty, unless the
    /// wire is cut) or the in-process Linux computer, the tick, the link bytes out.
    fn run_flight_computer(&mut self, linux_on: bool) {
        // The R/C receiver's frame (50 Hz), before the tick that uses it.
        if let Some(p) = self.receiver.poll(self.t_us) {
            self.fc.core.pilot(self.t_us, &p);
        }
        if let Some(pty) = self.link.as_mut() {
            // The UART: whatever the Linux side wrote since the last tick (unless the wire is cut).
            let mut chunk = [0u8; 1024];
            self.rx.clear();
            loop {
                let n = pty.read_available(&mut chunk);
                if n == 0 {
                    break;
                }
                if linux_on {
                    self.rx.extend_from_slice(&chunk[..n]);
                }
            }
            let mut tx = [0u8; 1024];
            let n = self.fc.tick(
                self.t_us,
                &self.rx,
                &mut self.board,
                &mut self.motors,
                &mut tx,
            );
            if linux_on {
                pty.send_frames(&tx[..n]);
            }
        } else {
            // The in-process Linux computer runs at 20 Hz, before the MCU's tick at the same
            // instant; it talks to the core directly, so the link has no peer: what it sends
            // (its Hello once, then nothing with telemetry off) goes nowhere. Room for that
            // Hello keeps it from being encoded again every tick.
            if self.ticks % 25 == 0 && linux_on {
                self.linux.update(self.t_us, &mut self.fc.core);
            }
            let mut tx = [0u8; 64];
            self.fc
                .tick(self.t_us, &[], &mut self.board, &mut self.motors, &mut tx);
        }
    }

    /// The ranges the flight computer polled this tick, logged with the true height.
    fn keep_polled_ranges(&mut self) {
        let p = self.body.state.pos_ned_m;
        let agl = self.board.terrain.ground_down_at(p.x, p.y) - p.z;
        let mut polled = std::mem::take(&mut self.board.polled_ranges);
        for &(laser, r) in &polled {
            self.keep_range(super::log::RangeRecord {
                t_s: r.t_us as f64 * 1e-6,
                laser,
                range_m: r.range_m,
                true_agl_m: agl,
            });
        }
        polled.clear();
        self.board.polled_ranges = polled; // its capacity, reused
    }

    fn record(&mut self) {
        self.last_record_tick = Some(self.ticks);
        let st = &self.body.state;
        let (roll, pitch, yaw) = st.q_body_to_ned.euler_angles();
        let nav = *self.fc.core.nav();
        let tel = *self.fc.core.telemetry();
        let a = self.board.truth.accel_ned_mps2;
        let (sy, cy) = (
            nav.euler.yaw_rad.sin() as f64,
            nav.euler.yaw_rad.cos() as f64,
        );
        let accel_true_fr = [(cy * a.x + sy * a.y) as f32, (-sy * a.x + cy * a.y) as f32];
        self.keep_sample(LogSample {
            t_s: self.t_s(),
            mode: self.fc.core.mode(),
            failsafe: self.fc.core.failsafe(),
            armed: self.fc.core.armed(),
            landed: self.fc.core.landed(),
            plan: self.linux.status(),
            true_pos_ned_m: st.pos_ned_m.into(),
            true_vel_ned_mps: st.vel_ned_mps.into(),
            true_euler_rad: [roll, pitch, yaw],
            true_accel_ned_mps2: a.into(),
            wind_ned_mps: self.wind_ned.into(),
            nav,
            tel,
            accel_true_fr_mps2: accel_true_fr,
            true_agl_m: self
                .board
                .terrain
                .ground_down_at(st.pos_ned_m.x, st.pos_ned_m.y)
                - st.pos_ned_m.z,
            motors: *self.fc.core.motors(),
        });
    }

    /// Run to the end; returns the log.
    pub fn run(&mut self) -> &FlightLog {
        while !self.finished() {
            self.tick();
        }
        self.finish()
    }

    /// Close the log (events of the in-process mission computer) after a run driven by hand.
    pub fn finish(&mut self) -> &FlightLog {
        // The run ends on the tick that finished it (the mission computer saw the disarm, a
        // crash): its state closes the log even between two 50 Hz samples, so the log ends
        // the way the flight did (a square ended 10 ms after its last sample, still armed).
        if self.ticks > 0 && self.last_record_tick != Some(self.ticks) {
            self.record();
        }
        if let Some(sp) = self.spill.take() {
            // The file holds everything before any failure; memory the rest.
            let samples = std::mem::take(&mut self.log.samples);
            let ranges = std::mem::take(&mut self.log.ranges);
            if let Err(e) = sp.read_into(&mut self.log) {
                let t = self.t_s();
                self.sim_events
                    .push((t, format!("flight log incomplete: {e}")));
            }
            self.log.samples.extend(samples);
            self.log.ranges.extend(ranges);
        }
        let mut events = self.linux.events().to_vec();
        events.extend(self.sim_events.iter().cloned());
        events.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.log.events = events;
        &self.log
    }
}

/// The vehicle in the scenario's air: density `ρ = p0/(R_d·T)` from the air temperature (ISA
/// 15 °C → 1.225 kg/m³), and the rotors' thrust and drag, both ∝ ρ (`T = C_T·ρ·n²·D⁴`), scaled
/// from their sea-level figures: a hot day lifts less.
fn air_at(
    v: &super::physics::VehicleParams,
    air_temp_c: f64,
    p0_pa: f64,
) -> super::physics::VehicleParams {
    const R_DRY_AIR: f64 = 287.05;
    const RHO_ISA: f64 = 1.225;
    let rho = p0_pa / (R_DRY_AIR * (air_temp_c + 273.15));
    let k = rho / RHO_ISA;
    super::physics::VehicleParams {
        air_density_kgpm3: v.air_density_kgpm3 * k,
        max_thrust_per_motor_n: v.max_thrust_per_motor_n * k,
        rotor_drag_n_per_mps: v.rotor_drag_n_per_mps * k,
        ..v.clone()
    }
}

/// Tilt of the body z axis from the vertical, deg.
fn tilt_deg(q: &UnitQuaternion<f64>) -> f64 {
    q.transform_vector(&Vector3::z())
        .z
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// The operator's pre-flight calibrations: offsets measured with a residual error (see
/// [`super::scenario::CalibrationParams`]).
fn calibrate(
    params: &mut fcc_firmware::params::Params,
    board: &SimBoard,
    s: &super::scenario::SensorParams,
    seed: u64,
) {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0xCA11_B8A7);
    let (_, accel_bias) = board.imu.biases();
    let c = &s.calibration;
    let g = fcc_nav::GRAVITY_MPS2 as f64;
    for i in 0..3 {
        let r = super::sensor_models::normal(&mut rng, c.accel_residual_mg * 1e-3 * g);
        params.nav.accel_offset_frd_mps2[i] = (accel_bias[i] + r) as f32;
        let r = super::sensor_models::normal(&mut rng, c.mag_residual_ut);
        params.nav.mag_offset_frd_ut[i] = (s.mag.hard_iron_frd_ut[i] + r) as f32;
    }
}

/// Height (m, up), vertical speed (m/s, up) and acceleration of a carried profile at time `t`
/// (the profile holds analytic values every millisecond; the last point holds afterwards).
fn sample_profile(p: &[[f64; 3]], t: f64) -> (f64, f64, f64) {
    let i = ((t * 1e3).round() as usize).min(p.len().saturating_sub(1));
    p.get(i).map_or((0.0, 0.0, 0.0), |x| (x[0], x[1], x[2]))
}
