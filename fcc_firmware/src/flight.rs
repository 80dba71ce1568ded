//! The 500 Hz flight step: sensors → navigation → mode logic → control cascade → mixer.
//!
//! This is the thin task (PX4's module wrapper) around the control cascade
//! ([`crate::control::cascade::Cascade`], the math as a plain struct): it owns the modes,
//! failsafes, guidance, limits, land detection and the touchdown gate, turns the navigation
//! solution and the Linux computer's setpoints into a [`Demand`] each step, and calls the
//! cascade for the motor commands. Time is always an argument (`now_us`, MCU µs).

use crate::commands::{
    Command, CommandError, FailsafeCause, Mode, VelocitySetpoint, YawSetpoint, KILL_CONFIRM,
};
use crate::control::cascade::{Cascade, Demand};
use crate::control::heading::Heading;
use crate::control::vec2::clamp_norm;
use crate::geometry::MOTOR_COUNT;
use crate::land_detector::{LandDetector, LandInputs, LandState};
use crate::nav::{NavNotReady, NavState, Navigator};
use crate::params::{ParamError, ParamFault, Params};
use crate::pilot::{PilotInput, PilotReceiver};
use crate::sensors::SensorInputs;
use crate::touchdown_gate::{GateAction, TouchdownGate, GATE_CLEARANCE_M};
use fcc_nav::complementary::wrap_pi;
use fcc_nav::ground_altitude::GroundSource;
use fcc_nav::GRAVITY_MPS2;

/// A fused ground height with a larger variance than this is not trusted for landing (m²).
const GROUND_MAX_VAR_M2: f32 = 0.25;
/// Wind limit: tilt at its limit with the velocity command missed by more than
/// [`WIND_VEL_ERR_MPS`] for this long (net of [`WIND_LEAK`]), s.
const WIND_LIMIT_S: f32 = 2.5;
/// Wind limit: the saturation count decays at this fraction of real time while not saturated.
const WIND_LEAK: f32 = 0.5;
/// Wind limit: velocity error that counts as "blown off", m/s.
const WIND_VEL_ERR_MPS: f32 = 1.0;
/// Estimator fault (not horizontal): hold this long before landing, s.
const FAULT_HOLD_S: f32 = 2.0;
/// LAND, descent committed by the touchdown gate: below this height of the gear over the
/// ground the tilt is limited to [`LAND_LEVEL_TILT_DEG`], m.
const LAND_LEVEL_HEIGHT_M: f32 = 0.15;
/// LAND: the level limit applies only while slower than this over the ground: a gust that
/// drives the vehicle sideways near the ground is braked with the full tilt (sliding into the
/// ground tips a vehicle over sooner than a tilted gear does), m/s.
const LAND_LEVEL_MAX_SPEED_MPS: f32 = 0.4;
/// LAND's committed last [`LAND_LEVEL_HEIGHT_M`] when not levelled (sliding faster than
/// [`LAND_LEVEL_MAX_SPEED_MPS`], or the gate's unlevel touchdown): the tilt limit, deg. A gear
/// meeting the ground at the full tilt limit (45°) while still sliding tips over (`hover` in
/// 16 m/s + W20 30 kt, `tests/tests/safety.rs`: 0.84 m/s at 35.5°); the tip-over margin at 25°
/// still holds to ≈ 0.85 m/s (`fcc_sim::truth`).
const LAND_BRAKE_TILT_DEG: f32 = 25.0;
/// LAND with GPS lost and the ground in the rangefinders' view: the final descent starts
/// this high (sensor height above the ground, m; the gear stands at 0.25 m). Measured on
/// `launch_configs/scenarios/gps_loss.yaml` (24 flights, 4 wind directions): 2.0 m (the usual
/// `limits.land_slow_alt_m`) → median horizontal touchdown 0.73 m/s, max 1.28; 1.0 m → 0.50,
/// 0.86; 0.6 m → 0.40, 0.81; vertical at most 0.35 m/s in all three.
const GPS_LOST_SLOW_ALT_M: f32 = 0.6;
/// LAND: the tilt limit just before touchdown, deg.
const LAND_LEVEL_TILT_DEG: f32 = crate::touchdown_gate::LEVEL_TILT_DEG;
/// Velocity mode: command reduction per m/s of estimated speed over the limit. The term raises
/// the velocity loop's gain along the velocity above the limit: at 2.0 a cruise commanded at
/// 7.9 of 8 m/s in gusts fell into a limit cycle (the tilt swinging 4° ↔ 36° every 0.7 s;
/// campaign family `velocity`, `cruise_tilt_wobble_deg` worst 3.8–3.9° against 1.3° median);
/// with the command tracked at the limit (no [`SPEED_LIMIT_MARGIN`]) 1.0 still cycled in 4 of
/// 720 cruises. With the margin and the GPS-velocity tilt aid, over the ten seed sets 1000 …
/// 19000 (`fcc-campaign --per-family 72 --long --family velocity`): gain 1.0 → speed over the
/// limit worst 5.1 % (one cruise failed), wobble worst 1.99°; 0.5 → 4.3 %, 1.90°; 0 → 4.2 %,
/// 1.90°. Kept at 0.5: it still pulls a gust's overspeed back, and costs nothing measurable.
const SPEED_LIMIT_GAIN: f32 = 0.5;
/// Velocity mode: the tracked command stays this fraction below the speed limit
/// (`limits.max_horiz_speed_mps`), so the velocity loop's tracking error and the gusts have room
/// below the limit instead of the speed-limit feedback switching in and out around it. Asked
/// for the limit, the vehicle cruises at 97 % of it. Campaign family `velocity` (10 seed sets
/// 1000 … 19000, 720 circles at 2–8 m/s for 300 s in 3 m/s wind + W20 15 kt): without it 4
/// cruises failed (true speed up to 6.5 % over the limit, tilt wobble up to 3.4° RMS, every
/// one at 7.9–8.0 m/s), with it none (worst 4.4 %, 1.87°; before the tilt aid, at gain 1.0),
/// every other family's figures unchanged.
const SPEED_LIMIT_MARGIN: f32 = 0.03;
/// Velocity mode: largest rate of change of the horizontal velocity command, m/s².
const VEL_SLEW_MPS2: f32 = 2.0;
/// Velocity mode: the integrated target height stays within this of the estimate, m.
const VEL_ALT_LEAD_M: f32 = 1.0;
/// A velocity-mode descent faster than this is the operator's own (the terrain floor lets it
/// through), m/s.
const FLOOR_DESCENT_MPS: f32 = 0.1;
/// Deceleration planned for stopping at the geofence, m/s².
const FENCE_BRAKE_MPS2: f32 = 1.0;
/// Closer to the fence than this while being held back by it → reported as a geofence event.
const FENCE_REPORT_M: f32 = 2.0;
/// Largest velocity component a setpoint may carry before it is refused as absurd.
const SETPOINT_ABS_LIMIT_MPS: f32 = 50.0;
/// Pilot mode, sticks centred: brake (zero velocity) until slower than this, then hold the
/// position reached (PX4 Position mode's brake-then-lock), m/s.
const PILOT_LOCK_SPEED_MPS: f32 = 0.5;
/// Pilot mode and velocity-mode yaw-rate setpoints: the heading command, advanced at the
/// commanded yaw rate, leads the heading by at most this much, rad (so a vehicle that cannot
/// turn as fast does not wind up a command far ahead of it).
pub const YAW_LEAD_RAD: f32 = 0.5;

pub use crate::control::cascade::StepTelemetry;

pub struct FlightCore {
    params: Params,
    nav: Navigator,
    mode: Mode,
    failsafe: FailsafeCause,
    setpoint: Option<(VelocitySetpoint, u64)>,
    last_setpoint_us: Option<u64>,
    hold_ne_m: [f32; 2],
    hold_alt_m: f32,
    /// Velocity mode: the height the commanded climb rate integrates to (m, up); `None` until
    /// the first velocity-mode step.
    vel_alt_m: Option<f32>,
    /// Velocity mode: the slew-limited horizontal command (NED north, east), m/s.
    vel_slew_ne: Option<[f32; 2]>,
    /// Truly above the terrain floor since take-off (the floor then applies).
    above_floor: bool,
    /// Time the tilt has been at its limit while the velocity command is not followed, s.
    wind_sat_s: f32,
    /// When an estimator fault was first seen in this flight (MCU µs); cleared at arming.
    fault_since_us: Option<u64>,
    yaw_hold_rad: f32,
    takeoff_alt_m: f32,
    /// On the ground or in the air ([`crate::land_detector`]).
    land: LandDetector,
    touchdown_gate: TouchdownGate,
    /// Last step's tilt demand of the horizontal loops (`|θ_cmd|` before the tilt limit), rad:
    /// the touchdown gate's measure of the gust.
    tilt_demand_rad: f32,
    /// The control cascade ([`crate::control::cascade`]): velocity → acceleration → attitude
    /// → vertical → mixer.
    cascade: Cascade,
    last_step_us: Option<u64>,
    motors: [f32; MOTOR_COUNT],
    telemetry: StepTelemetry,
    /// The R/C receiver ([`crate::pilot`]).
    pilot: PilotReceiver,
    /// The pilot handed the vehicle back: hold until the Linux side commands velocity mode
    /// (a setpoint alone does not resume).
    pilot_released: bool,
}

impl FlightCore {
    pub fn new(params: Params) -> Self {
        Self {
            params,
            nav: Navigator::new(params.nav),
            mode: Mode::Disarmed,
            failsafe: FailsafeCause::None,
            setpoint: None,
            last_setpoint_us: None,
            hold_ne_m: [0.0; 2],
            hold_alt_m: 0.0,
            vel_alt_m: None,
            vel_slew_ne: None,
            above_floor: false,
            wind_sat_s: 0.0,
            fault_since_us: None,
            yaw_hold_rad: 0.0,
            takeoff_alt_m: 0.0,
            land: LandDetector::new(),
            touchdown_gate: TouchdownGate::new(),
            tilt_demand_rad: 0.0,
            cascade: Cascade::from_params(&params),
            last_step_us: None,
            motors: [0.0; MOTOR_COUNT],
            telemetry: StepTelemetry::default(),
            pilot: PilotReceiver::new(),
            pilot_released: false,
        }
    }

    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Change one tunable parameter (ids: `fcc_msgs::param_id`, the one table in
    /// `fcc_msgs::params`) in flight: set on a copy, checked with [`Params::validate`] (the
    /// table's range and the cross-checks), then applied; the cascade rebuilds the controllers
    /// whose parameters changed ([`Cascade::set_params`]: their integrators restart).
    pub fn set_param(&mut self, id: u16, value: f32) -> Result<(), ParamError> {
        let mut p = self.params;
        let field = p.link_param_mut(id).ok_or(ParamError {
            field: "id",
            reason: ParamFault::UnknownId,
        })?;
        *field = value;
        self.set_params(p)
    }

    /// Replace every parameter at once: checked with [`Params::validate`], then applied as
    /// [`Self::set_param`] applies one.
    pub fn set_params(&mut self, p: Params) -> Result<(), ParamError> {
        p.validate()?;
        self.params = p;
        self.cascade.set_params(&p);
        Ok(())
    }

    /// LAND's touchdown gate ([`crate::touchdown_gate`]): how long the landing waited for a
    /// lull, whether it was committed by the timeout.
    pub fn touchdown_gate(&self) -> &TouchdownGate {
        &self.touchdown_gate
    }

    /// Current value of a tunable parameter (ids: `fcc_msgs::param_id`).
    pub fn param(&self, id: u16) -> Option<f32> {
        self.params.link_param(id)
    }
    pub fn mode(&self) -> Mode {
        self.mode
    }
    pub fn failsafe(&self) -> FailsafeCause {
        self.failsafe
    }
    pub fn armed(&self) -> bool {
        self.mode != Mode::Disarmed
    }
    pub fn landed(&self) -> bool {
        self.land.landed()
    }
    pub fn nav(&self) -> &NavState {
        self.nav.state()
    }
    pub fn navigator(&self) -> &Navigator {
        &self.nav
    }
    pub fn telemetry(&self) -> &StepTelemetry {
        &self.telemetry
    }
    pub fn motors(&self) -> &[f32; MOTOR_COUNT] {
        &self.motors
    }
    pub fn pilot_receiver(&self) -> &PilotReceiver {
        &self.pilot
    }

    /// A frame from the R/C receiver (the board's S.BUS, ~every 10–14 ms). Takes effect at the
    /// next [`Self::step`]: switch on and armed → [`Mode::Pilot`]; switch off, receiver
    /// failsafe or no frame for [`crate::pilot::RX_TIMEOUT_US`] → hold.
    pub fn pilot(&mut self, now_us: u64, p: &PilotInput) {
        let _ = now_us;
        self.pilot.input(p);
    }

    /// Apply an operator command.
    pub fn command(&mut self, now_us: u64, cmd: Command) -> Result<(), CommandError> {
        let nav = *self.nav.state();
        if let Command::Kill { confirm } = cmd {
            // Before the pilot check: the kill stops the motors whoever flies.
            if confirm != KILL_CONFIRM {
                return Err(CommandError::KillNotConfirmed);
            }
            self.mode = Mode::Disarmed;
            self.failsafe = FailsafeCause::EmergencyKill;
            self.setpoint = None;
            self.motors = [0.0; MOTOR_COUNT];
            return Ok(());
        }
        if self.mode == Mode::Pilot {
            match cmd {
                Command::Arm => return Ok(()),
                // On the ground the Linux side may still disarm.
                Command::Disarm if self.land.landed() => {}
                _ => return Err(CommandError::PilotOverride),
            }
        }
        match cmd {
            Command::Arm => {
                if self.armed() {
                    return Ok(());
                }
                match self.nav.ready() {
                    Err(NavNotReady::Calibrating) => return Err(CommandError::NotCalibrated),
                    Err(NavNotReady::NoGpsHome) => return Err(CommandError::NoHome),
                    Ok(()) => {}
                }
                if !self.land.landed() {
                    return Err(CommandError::NotLanded);
                }
                self.cascade.reset();
                self.nav.clear_faults();
                self.fault_since_us = None;
                self.takeoff_alt_m = -nav.pos_ned_m[2];
                self.enter_hold(&nav);
                self.failsafe = FailsafeCause::None;
                self.last_setpoint_us = Some(now_us);
                self.pilot_released = false;
            }
            Command::Disarm => {
                // Never in the air: cutting the motors there is a free fall.
                if !self.land.landed() {
                    return Err(CommandError::NotLanded);
                }
                self.mode = Mode::Disarmed;
                self.setpoint = None;
            }
            Command::Hold => {
                if !self.armed() {
                    return Err(CommandError::Disarmed);
                }
                self.enter_hold(&nav);
                self.failsafe = FailsafeCause::None;
            }
            Command::Land => {
                if !self.armed() {
                    return Err(CommandError::Disarmed);
                }
                self.enter_land(&nav);
            }
            Command::Kill { .. } => {}
            Command::Velocity => {
                if !self.armed() {
                    return Err(CommandError::Disarmed);
                }
                self.mode = Mode::Velocity;
                self.failsafe = FailsafeCause::None;
                self.last_setpoint_us = Some(now_us);
                self.pilot_released = false;
            }
        }
        Ok(())
    }

    /// Accept a velocity setpoint from the mission computer. Out-of-limit speeds are clamped to
    /// the MCU's limits; non-finite or absurd values are refused.
    pub fn setpoint(&mut self, now_us: u64, sp: VelocitySetpoint) -> Result<(), CommandError> {
        let finite = sp
            .vel_ned_mps
            .iter()
            .all(|v| v.is_finite() && v.abs() <= SETPOINT_ABS_LIMIT_MPS)
            && match sp.yaw {
                YawSetpoint::Keep => true,
                YawSetpoint::Heading { yaw_ned_rad } => yaw_ned_rad.is_finite(),
                YawSetpoint::Rate {
                    yaw_rate_ned_radps: r,
                } => r.is_finite() && r.abs() <= fcc_msgs::SETPOINT_YAW_RATE_ABS_MAX_RADPS,
            };
        // The time-to-live is the stale-setpoint failsafe: bounded to a few seconds.
        let ttl_ok =
            (fcc_msgs::SETPOINT_TTL_MS_MIN..=fcc_msgs::SETPOINT_TTL_MS_MAX).contains(&sp.ttl_ms);
        if !finite || !ttl_ok {
            return Err(CommandError::InvalidSetpoint);
        }
        if !self.armed() {
            return Err(CommandError::Disarmed);
        }
        if self.mode == Mode::Pilot {
            return Err(CommandError::PilotOverride);
        }
        let l = &self.params.limits;
        let mut v = sp.vel_ned_mps;
        let h = fcc_nav::math::hypotf(v[0], v[1]);
        if h > l.max_horiz_speed_mps {
            v[0] *= l.max_horiz_speed_mps / h;
            v[1] *= l.max_horiz_speed_mps / h;
        }
        // max/min, not clamp: clamp panics on inverted bounds; the limits are range-checked
        // (params.rs) but the MCU image must have no panic path reachable from link bytes.
        v[2] = v[2].max(-l.max_climb_mps).min(l.max_descent_mps);
        // Headings wrapped once here, rates clamped to the fastest turn the heading loop
        // follows: its rate limit, and its gain times the lead the held heading may take
        // (`advance_yaw_hold`; 1.5/s · 0.5 rad = 0.75 rad/s with the defaults) — a faster
        // setpoint would turn the vehicle slower than asked.
        let c = &self.params.control;
        let r_max = c.yaw_rate_limit_radps.min(c.yaw_p_per_s * YAW_LEAD_RAD);
        let yaw = match sp.yaw {
            YawSetpoint::Keep => YawSetpoint::Keep,
            YawSetpoint::Heading { yaw_ned_rad } => YawSetpoint::Heading {
                yaw_ned_rad: wrap_pi(yaw_ned_rad),
            },
            YawSetpoint::Rate { yaw_rate_ned_radps } => YawSetpoint::Rate {
                yaw_rate_ned_radps: yaw_rate_ned_radps.max(-r_max).min(r_max),
            },
        };
        self.setpoint = Some((
            VelocitySetpoint {
                vel_ned_mps: v,
                yaw,
                ..sp
            },
            now_us,
        ));
        self.last_setpoint_us = Some(now_us);
        // A fresh setpoint resumes velocity mode from hold (but never overrides a landing).
        if self.mode == Mode::Hold && !self.pilot_released {
            self.mode = Mode::Velocity;
            self.failsafe = FailsafeCause::None;
        }
        Ok(())
    }

    fn enter_hold(&mut self, nav: &NavState) {
        self.vel_alt_m = None;
        self.vel_slew_ne = None;
        self.mode = Mode::Hold;
        self.hold_ne_m = [nav.pos_ned_m[0], nav.pos_ned_m[1]];
        self.hold_alt_m = -nav.pos_ned_m[2];
        self.yaw_hold_rad = nav.euler.yaw_rad;
        self.cascade.reset_track();
    }

    fn enter_land(&mut self, nav: &NavState) {
        self.vel_alt_m = None;
        self.vel_slew_ne = None;
        self.mode = Mode::Land;
        self.touchdown_gate.reset();
        self.hold_ne_m = [nav.pos_ned_m[0], nav.pos_ned_m[1]];
        self.yaw_hold_rad = nav.euler.yaw_rad;
        self.cascade.reset_track();
    }

    /// One 500 Hz step; returns the ESC commands (0..1).
    pub fn step(&mut self, now_us: u64, inputs: &SensorInputs) -> [f32; MOTOR_COUNT] {
        let dt_s = match self.last_step_us {
            Some(t) if now_us > t => ((now_us - t) as f32 * 1e-6).min(0.02),
            _ => 0.002,
        };
        self.last_step_us = Some(now_us);
        let still = self.mode == Mode::Disarmed && self.land.landed();
        let nav = *self.nav.step(now_us, inputs, still);
        self.telemetry = StepTelemetry {
            t_us: now_us,
            ..Default::default()
        };
        if self.mode == Mode::Disarmed {
            if !self.land.landed() {
                // Disarmed in the air (an emergency kill): landed once at rest.
                self.detect_touchdown(dt_s, &nav, 1.0);
            }
            self.motors = [0.0; MOTOR_COUNT];
            return self.motors;
        }
        self.update_mode(now_us, &nav);
        if self.mode == Mode::Disarmed {
            self.motors = [0.0; MOTOR_COUNT];
            return self.motors;
        }
        let (v_cmd_ne, vz_cmd_down, yaw_cmd) = self.guidance(dt_s, &nav);
        self.control(dt_s, &nav, v_cmd_ne, vz_cmd_down, yaw_cmd);
        self.detect_touchdown(dt_s, &nav, vz_cmd_down);
        self.motors
    }

    fn update_mode(&mut self, now_us: u64, nav: &NavState) {
        let l = self.params.limits;
        let since_sp_s = self
            .last_setpoint_us
            .map_or(f32::MAX, |t| now_us.saturating_sub(t) as f32 * 1e-6);
        // The pilot's switch wins over the Linux side's modes (not over a GPS-loss landing:
        // the assisted mode needs the horizontal estimate).
        let pilot_on = self.pilot.active(now_us);
        if pilot_on && self.mode != Mode::Pilot && self.failsafe != FailsafeCause::GpsLost {
            self.enter_hold(nav);
            self.mode = Mode::Pilot;
            self.failsafe = FailsafeCause::None;
            self.setpoint = None;
        } else if !pilot_on && self.mode == Mode::Pilot {
            // Switch off or receiver failsafe: hold here until the Linux side re-commands.
            self.enter_hold(nav);
            self.failsafe = FailsafeCause::None;
            self.pilot_released = true;
        }
        match self.mode {
            Mode::Velocity => {
                let stale = match self.setpoint {
                    Some((sp, t)) => now_us.saturating_sub(t) > sp.ttl_ms as u64 * 1000,
                    None => true,
                };
                if stale {
                    self.enter_hold(nav);
                    self.failsafe = FailsafeCause::SetpointStale;
                }
            }
            Mode::Hold
                if self.failsafe == FailsafeCause::SetpointStale
                    && since_sp_s > l.setpoint_lost_land_s =>
            {
                self.enter_land(nav);
                self.failsafe = FailsafeCause::SetpointLost;
            }
            _ => {}
        }
        self.estimator_failsafe(now_us, nav);
        // Wind beyond authority: the tilt at its limit and still blown off → land here
        // (the wind weakens towards the ground).
        if self.wind_sat_s >= WIND_LIMIT_S && self.mode != Mode::Land && !self.land.landed() {
            self.enter_land(nav);
            self.failsafe = FailsafeCause::WindLimit;
        }
        // GPS lost in flight: the horizontal estimate will drift → land on baro/accel.
        if nav.home_set
            && !nav.gps_ok
            && !self.land.landed()
            && self.mode != Mode::Land
            && self.failsafe != FailsafeCause::EstimatorFault
        {
            self.enter_land(nav);
            self.failsafe = FailsafeCause::GpsLost;
        }
    }

    /// A diverged navigation filter ([`crate::nav_health`]): a horizontal fault lands at once
    /// (holding needs the position), any other holds for [`FAULT_HOLD_S`] and then lands.
    fn estimator_failsafe(&mut self, now_us: u64, nav: &NavState) {
        if nav.nav_faults == 0 || self.land.landed() || self.mode == Mode::Land {
            return;
        }
        // The clock runs from the first detection: an operator's velocity or hold command
        // cannot restart it (the fault bits stay latched until the next arming).
        let since_us = *self.fault_since_us.get_or_insert(now_us);
        let held_s = now_us.saturating_sub(since_us) as f32 * 1e-6;
        let horizontal = nav.nav_faults & crate::nav_health::FAULT_HORIZONTAL != 0;
        if horizontal || held_s >= FAULT_HOLD_S {
            self.enter_land(nav);
        } else if self.mode != Mode::Hold {
            self.enter_hold(nav);
        }
        self.failsafe = FailsafeCause::EstimatorFault;
    }

    /// Advance the held heading at `yaw_rate_radps` (NED, rad/s) over `dt_s`, at most
    /// [`YAW_LEAD_RAD`] ahead of (or behind) the heading estimate `yaw_rad`: the pilot's yaw
    /// stick and a velocity setpoint's yaw rate.
    fn advance_yaw_hold(&mut self, yaw_rate_radps: f32, dt_s: f32, yaw_rad: f32) {
        let lead = fcc_nav::math::clampf(
            wrap_pi(self.yaw_hold_rad + yaw_rate_radps * dt_s - yaw_rad),
            -YAW_LEAD_RAD,
            YAW_LEAD_RAD,
        );
        self.yaw_hold_rad = wrap_pi(yaw_rad + lead);
    }

    /// Velocity command (NED north/east, down) and heading command for the current mode, then
    /// the geofence and the terrain floor.
    fn guidance(&mut self, dt_s: f32, nav: &NavState) -> ([f32; 2], f32, f32) {
        let alt = -nav.pos_ned_m[2];
        let (v_ne, vz_down, yaw) = match self.mode {
            Mode::Hold => {
                let vz = self.height_loop(0.0, self.hold_alt_m, alt);
                (self.hold_velocity_ne(nav), vz, self.yaw_hold_rad)
            }
            Mode::Velocity => self.velocity_guidance(dt_s, nav),
            Mode::Land => self.land_guidance(dt_s, nav),
            Mode::Pilot => self.pilot_guidance(dt_s, nav),
            Mode::Disarmed => ([0.0; 2], 0.0, nav.euler.yaw_rad),
        };
        let v_ne = self.fence_horizontal(nav, v_ne);
        let mut vz_down = self.terrain_floor(nav, vz_down);
        if alt - self.takeoff_alt_m > self.params.limits.fence_alt_m && vz_down < 0.0 {
            vz_down = 0.3;
            self.failsafe = FailsafeCause::Geofence;
        }
        (v_ne, vz_down, yaw)
    }

    /// Back to the hold point (NED north, east, m/s): `pos_p·(p_hold − p)`, at most
    /// `limits.hold_max_speed_mps`.
    fn hold_velocity_ne(&self, nav: &NavState) -> [f32; 2] {
        let e = [
            self.hold_ne_m[0] - nav.pos_ned_m[0],
            self.hold_ne_m[1] - nav.pos_ned_m[1],
        ];
        let k = self.params.control.pos_p_per_s;
        clamp_norm([k * e[0], k * e[1]], self.params.limits.hold_max_speed_mps)
    }

    /// VELOCITY: the setpoint's velocity (slewed) and climb, its heading or yaw rate; without
    /// a setpoint, hold.
    fn velocity_guidance(&mut self, dt_s: f32, nav: &NavState) -> ([f32; 2], f32, f32) {
        let Some((sp, _)) = self.setpoint else {
            return (self.hold_velocity_ne(nav), 0.0, self.yaw_hold_rad);
        };
        match sp.yaw {
            YawSetpoint::Keep => {}
            YawSetpoint::Heading { yaw_ned_rad } => self.yaw_hold_rad = yaw_ned_rad,
            YawSetpoint::Rate { yaw_rate_ned_radps } => {
                self.advance_yaw_hold(yaw_rate_ned_radps, dt_s, nav.euler.yaw_rad)
            }
        }
        let vz = self.velocity_climb(dt_s, sp.vel_ned_mps[2], -nav.pos_ned_m[2]);
        let target = [sp.vel_ned_mps[0], sp.vel_ned_mps[1]];
        let v = self.slew_velocity(dt_s, target, nav);
        (v, vz, self.yaw_hold_rad)
    }

    /// LAND: down at the landing speed holding the point, then the final descent.
    fn land_guidance(&mut self, dt_s: f32, nav: &NavState) -> ([f32; 2], f32, f32) {
        let l = self.params.limits;
        // GPS lost: every second adds to the dead-reckoning drift, so the descent is
        // fast and its slow part short — where the rangefinders see the ground (on the
        // barometer's metre of error it keeps the usual margin).
        let gps_lost = !nav.gps_ok && self.ground_usable(nav);
        let slow_alt_m = if gps_lost {
            l.land_slow_alt_m.min(GPS_LOST_SLOW_ALT_M)
        } else {
            l.land_slow_alt_m
        };
        if self.height_above_ground_m(nav) > slow_alt_m {
            // Dead-reckoned (GPS lost), the position drifts ever faster: no position
            // hold, zero velocity (while that estimate is still good), and down at the
            // descent limit.
            let (v, down) = if nav.gps_ok {
                (self.hold_velocity_ne(nav), l.land_speed_mps)
            } else {
                ([0.0; 2], l.max_descent_mps.max(l.land_speed_mps))
            };
            (v, down, self.yaw_hold_rad)
        } else {
            // Final descent: zero horizontal velocity (no position corrections that
            // would slide the gear at touchdown); where it is becomes the hold point.
            self.hold_ne_m = [nav.pos_ned_m[0], nav.pos_ned_m[1]];
            ([0.0; 2], self.final_descent(dt_s, nav), self.yaw_hold_rad)
        }
    }

    /// PILOT: the sticks' velocity, climb and yaw rate; a centred stick holds (once slower
    /// than [`PILOT_LOCK_SPEED_MPS`], where it is).
    fn pilot_guidance(&mut self, dt_s: f32, nav: &NavState) -> ([f32; 2], f32, f32) {
        let l = self.params.limits;
        let alt = -nav.pos_ned_m[2];
        let d = self
            .pilot
            .demand(l.max_horiz_speed_mps, l.max_climb_mps, l.max_descent_mps);
        let pos = [nav.pos_ned_m[0], nav.pos_ned_m[1]];
        let speed = nav.ground_speed_mps();
        let v = match d.vel_fr_mps {
            Some(v) => {
                self.hold_ne_m = pos;
                Heading::new(nav.euler.yaw_rad).to_ne(v)
            }
            None if speed > PILOT_LOCK_SPEED_MPS => {
                self.hold_ne_m = pos;
                [0.0; 2]
            }
            None => self.hold_velocity_ne(nav),
        };
        let vz = match d.climb_mps {
            Some(up) => {
                self.hold_alt_m = alt;
                -up
            }
            None => self.height_loop(0.0, self.hold_alt_m, alt),
        };
        self.advance_yaw_hold(d.yaw_rate_radps, dt_s, nav.euler.yaw_rad);
        (v, vz, self.yaw_hold_rad)
    }

    /// Geofence: the outward velocity is limited so the vehicle can brake to a stop at the
    /// fence (v ≤ √(2·a·d)); outside it, it is pulled back in.
    fn fence_horizontal(&mut self, nav: &NavState, v_ne: [f32; 2]) -> [f32; 2] {
        let r = fcc_nav::math::hypotf(nav.pos_ned_m[0], nav.pos_ned_m[1]);
        if r <= 1e-3 {
            return v_ne;
        }
        let out = [nav.pos_ned_m[0] / r, nav.pos_ned_m[1] / r];
        let v_out = v_ne[0] * out[0] + v_ne[1] * out[1];
        let to_fence = self.params.limits.fence_radius_m - r;
        let v_out_max = if to_fence > 0.0 {
            fcc_nav::math::sqrtf(2.0 * FENCE_BRAKE_MPS2 * to_fence)
        } else {
            -0.5 * (-to_fence).min(2.0)
        };
        if v_out <= v_out_max {
            return v_ne;
        }
        if to_fence < FENCE_REPORT_M {
            self.failsafe = FailsafeCause::Geofence;
        }
        let remove = v_out - v_out_max;
        [v_ne[0] - remove * out[0], v_ne[1] - remove * out[1]]
    }

    /// LAND's final descent (NED down, m/s): the gear waits at the touchdown gate's clearance
    /// for a lull ([`crate::touchdown_gate`]), then descends at the touchdown speed `v_t`
    /// (`limits.land_touchdown_speed_mps`).
    /// The gate judges the tilt demand `d = max(tilt, |θ_cmd|)`, `θ_cmd` last step's tilt
    /// command before the limit (the lean the wind of the moment asks for), and the estimated
    /// ground speed (on the way down, extrapolated to the contact at `v_t`). Waiting (and
    /// approaching), the height loop holds the gate clearance, never descending faster than the
    /// final speed `v_f`. Committed: `v = max(v_t − (v_down − v_t)⁺, v_t/2)`, with `v_down` the
    /// inertial descent rate — a brake on the overshoot of the step from the hold. From the
    /// gate on (holding at it, and committed) the climb-rate loop closes on the inertial
    /// vertical velocity ([`Self::control`]); the height over the ground enters through the
    /// height loop on the clearance.
    /// The contact's vertical speed is the vehicle's own (the ground does not move); the rate
    /// over the ground adds the rangefinder filter's residual rate, which each 10-Hz sonar
    /// reading (σ 2 cm) kicks: closing on it, the 0.4-s descent from the gate met the ground at
    /// 0.38–0.46 m/s true while the loop read 0.25–0.32 (`hover_gale`, 20 seed sets: touchdown
    /// vertical p99 0.384, worst 0.424 m/s at `v_f` 0.3; on the inertial velocity 0.347 and
    /// 0.369). The tighter touchdown speed buys a faster last descent: the shorter the time a
    /// gust has to slide the levelled vehicle, the slower the slide (see `v_t`'s measurement
    /// in README.md and BENCHMARKS.md). Holding at the gate on the inertial velocity too, the
    /// hold no longer bobs with the residual rate's kicks: 20 seed sets, the gale's holds put
    /// no foot down (`hover_gale` 37051 did, at 20°), and the touchdowns' tilt worst is 4.66°.
    fn final_descent(&mut self, dt_s: f32, nav: &NavState) -> f32 {
        let l = self.params.limits;
        if !self.ground_usable(nav) {
            return l.land_final_speed_mps;
        }
        // The lowest foot's clearance: leaning into a gust at the gate brings a foot down by
        // several centimetres.
        let a = self.params.airframe;
        let lean_rad =
            fcc_nav::ground_altitude::tilt_angle_rad(nav.euler.roll_rad, nav.euler.pitch_rad);
        let clearance_m = self.height_above_ground_m(nav)
            - a.sensor_height_on_ground_m
            - crate::geometry::foot_drop_m(
                lean_rad,
                a.gear_half_span_m,
                a.sensor_height_on_ground_m,
            );
        let tilt_rad = lean_rad.max(self.tilt_demand_rad);
        let speed_mps = nav.ground_speed_mps();
        if !nav.gps_ok {
            self.touchdown_gate.commit_blind();
        }
        self.touchdown_gate.feel_ground(
            dt_s,
            clearance_m,
            nav.vel_ned_mps[2],
            nav.accel_ned_mps2[2],
        );
        let v_t = l.land_touchdown_speed_mps;
        match self
            .touchdown_gate
            .update(dt_s, clearance_m, tilt_rad, speed_mps, v_t)
        {
            GateAction::Descend => {
                let over = (nav.vel_ned_mps[2] - v_t).max(0.0);
                (v_t - over).max(0.5 * v_t)
            }
            // The height loop on the gear's clearance, never descending faster than the final
            // speed.
            GateAction::Hold => self
                .height_loop(0.0, GATE_CLEARANCE_M, clearance_m)
                .min(l.land_final_speed_mps),
        }
    }

    /// Velocity mode: the horizontal command moves towards the setpoint at no more than
    /// [`VEL_SLEW_MPS2`] (a step from hover to the speed limit would otherwise saturate the
    /// tilt and overshoot the speed); it starts from the estimated velocity, never faster than
    /// the setpoint (the slew limits how fast the command rises; a vehicle resuming faster than
    /// it is asked to fly — a gust, or the overshoot of the hold it comes from — is not
    /// commanded to keep that speed: `robust_stack.py`'s noisy link resumed after a stale
    /// setpoint at 3.14 m/s estimated and commanded 3.11 m/s against the mission's 3).
    fn slew_velocity(&mut self, dt_s: f32, target_ne: [f32; 2], nav: &NavState) -> [f32; 2] {
        let cruise_max_mps = self.params.limits.max_horiz_speed_mps * (1.0 - SPEED_LIMIT_MARGIN);
        let target_ne = clamp_norm(target_ne, cruise_max_mps);
        let v = self.vel_slew_ne.get_or_insert_with(|| {
            let target_mps = fcc_nav::math::hypotf(target_ne[0], target_ne[1]);
            clamp_norm([nav.vel_ned_mps[0], nav.vel_ned_mps[1]], target_mps)
        });
        let d = [target_ne[0] - v[0], target_ne[1] - v[1]];
        let step = clamp_norm(d, VEL_SLEW_MPS2 * dt_s);
        *v = [v[0] + step[0], v[1] + step[1]];
        // Speed limit as a feedback, not only a clamp of the command: a gust that pushes the
        // estimated speed over the limit pulls the command back along the velocity.
        let u = [nav.vel_ned_mps[0], nav.vel_ned_mps[1]];
        let speed = fcc_nav::math::hypotf(u[0], u[1]);
        let excess = speed - self.params.limits.max_horiz_speed_mps;
        if excess > 0.0 && speed > 0.0 {
            let k = SPEED_LIMIT_GAIN * excess / speed;
            return [v[0] - k * u[0], v[1] - k * u[1]];
        }
        *v
    }

    /// Velocity mode's vertical channel: the commanded climb rate integrates into a target
    /// height `h_t` that the height loop holds, so a zero climb rate holds the height instead
    /// of drifting with the velocity estimate (PX4's position lock under velocity setpoints):
    /// `h_t ← h_t − v_z,cmd·dt` (kept within [`VEL_ALT_LEAD_M`] of ĥ),
    /// `v_z = v_z,cmd − k_alt·(h_t − ĥ)`, limited to the climb/descent limits (NED down).
    fn velocity_climb(&mut self, dt_s: f32, vz_cmd_down: f32, alt_m: f32) -> f32 {
        let t = self.vel_alt_m.get_or_insert(alt_m);
        *t = fcc_nav::math::clampf(
            *t - vz_cmd_down * dt_s,
            alt_m - VEL_ALT_LEAD_M,
            alt_m + VEL_ALT_LEAD_M,
        );
        let target_m = *t;
        self.height_loop(vz_cmd_down, target_m, alt_m)
    }

    /// The height loop of every mode that holds a height: `v_z = v_ff − k_alt·(h_t − ĥ)`
    /// (NED down), limited to the climb and descent limits.
    fn height_loop(&self, vz_ff_down: f32, target_alt_m: f32, alt_m: f32) -> f32 {
        let l = self.params.limits;
        fcc_nav::math::clampf(
            vz_ff_down - self.params.control.alt_p_per_s * (target_alt_m - alt_m),
            -l.max_climb_mps,
            l.max_descent_mps,
        )
    }

    /// Terrain floor: outside LAND, once the vehicle has been above `limits.min_agl_m`, a
    /// level or climbing command never lets it sink below that height over the ground the
    /// rangefinders see (a descent the operator commands is still obeyed).
    fn terrain_floor(&mut self, nav: &NavState, vz_down: f32) -> f32 {
        let floor_m = self.params.limits.min_agl_m;
        if !self.ground_usable(nav) || floor_m <= 0.0 {
            return vz_down;
        }
        let h = nav.ground.height_m - self.params.airframe.sensor_height_on_ground_m;
        if self.land.landed() || self.mode == Mode::Land {
            self.above_floor = false;
            return vz_down;
        }
        if h > floor_m {
            self.above_floor = true;
        }
        let commanded_down = match (self.mode, self.setpoint) {
            (Mode::Velocity, Some((sp, _))) => sp.vel_ned_mps[2] > FLOOR_DESCENT_MPS,
            (Mode::Pilot, _) => true,
            _ => false,
        };
        if !self.above_floor || commanded_down || h >= floor_m {
            return vz_down;
        }
        let climb = self.params.control.alt_p_per_s * (floor_m - h);
        vz_down.min(-fcc_nav::math::clampf(
            climb,
            0.0,
            self.params.limits.max_climb_mps,
        ))
    }

    /// The tilt limit: `limits.max_tilt_deg`, and in LAND's last [`LAND_LEVEL_HEIGHT_M`] above
    /// the gear no more than [`LAND_LEVEL_TILT_DEG`] while slower than
    /// [`LAND_LEVEL_MAX_SPEED_MPS`] (touch down level: a tilted gear catches a foot) — once
    /// the touchdown gate has committed — while a gust's abort arrests the committed descent
    /// ([`TouchdownGate::arresting`]), and on the gear (ground contact) whatever the speed.
    /// Waiting at the gate the vehicle leans as far as the wind needs to stay put (the level
    /// limit there let every gust slide it, and at 0.15 m the limit switched on and off with
    /// the height noise); a commit whose command the level limit clips goes back to the gate.
    fn tilt_limit_rad(&self, nav: &NavState) -> f32 {
        let on_ground_m = self.params.airframe.sensor_height_on_ground_m;
        let speed = nav.ground_speed_mps();
        // The speed exception needs a speed over the ground: dead-reckoned (GPS lost), the
        // estimate drifts, and braking a slide it only imagines leans the vehicle over.
        let slow = speed < LAND_LEVEL_MAX_SPEED_MPS || !nav.gps_ok;
        // The committed descent's last LAND_LEVEL_HEIGHT_M.
        let near_ground = self.mode == Mode::Land
            && self.touchdown_gate.committed()
            && self.ground_usable(nav)
            && nav.ground.height_m < on_ground_m + LAND_LEVEL_HEIGHT_M;
        let level = self.mode == Mode::Land
            && ((near_ground && !self.touchdown_gate.unlevel() && slow)
                // Sent back by a gust and still going down: no lean until the descent has
                // stopped (a lean during the arrest puts a foot down).
                || self.touchdown_gate.arresting(nav.vel_ned_mps[2])
                // On the gear: a lean there tips the vehicle over (PX4 levels the thrust on
                // ground contact).
                || self.land.state() != LandState::Airborne);
        let l = self.params.limits;
        if level {
            l.max_tilt_deg.min(LAND_LEVEL_TILT_DEG).to_radians()
        } else if near_ground {
            l.max_tilt_deg.min(LAND_BRAKE_TILT_DEG).to_radians()
        } else {
            l.max_tilt_deg.to_radians()
        }
    }

    /// The control cascade for this step's velocity, climb-rate and heading commands: the mode
    /// logic's part (take-off, the tilt limit, which climb rate to close the loop on, the wind
    /// limit's count) around [`Cascade::update`].
    fn control(
        &mut self,
        dt_s: f32,
        nav: &NavState,
        v_cmd_ne: [f32; 2],
        vz_cmd_down: f32,
        yaw_cmd: f32,
    ) {
        if self.land.landed() && vz_cmd_down < -0.2 {
            self.land.take_off();
        }
        // Every loop flies until the land detector confirms touchdown (never the estimated
        // altitude alone: it can be off by more than the gear height).
        let airborne = !self.land.landed();
        // Final descent: the rangefinders see the ground, so the climb rate relative to it is
        // what the height over it is about (paper B's fused height, issue: use in flight) —
        // until the touchdown gate: holding there and touching down, the climb-rate loop closes
        // on the inertial vertical velocity (final_descent).
        let climb_over_ground = self.mode == Mode::Land
            && self.ground_usable(nav)
            && nav.ground.height_m < self.params.limits.land_slow_alt_m
            && !self.touchdown_gate.at_gate();
        let demand = Demand {
            vel_ne_mps: v_cmd_ne,
            vz_down_mps: vz_cmd_down,
            yaw_rad: yaw_cmd,
            tilt_limit_rad: self.tilt_limit_rad(nav),
            cross_track: self.mode == Mode::Velocity,
            climb_over_ground,
            touchdown: self.mode == Mode::Land && self.touchdown_gate.committed(),
            airborne,
        };
        let out = self.cascade.update(dt_s, nav, &demand);
        self.count_wind_saturation(dt_s, airborne, out.tilt_limited, out.vel_err_mps);
        self.motors = out.motors;
        self.telemetry = out.telemetry;
        self.tilt_demand_rad = out.tilt_demand_rad;
        self.touchdown_gate.command_limited(dt_s, out.tilt_limited);
    }

    /// The wind limit's count: time at the tilt limit with the velocity command missed by
    /// more than [`WIND_VEL_ERR_MPS`] (not in LAND). Leaky: gust lulls pause the count instead
    /// of restarting it.
    fn count_wind_saturation(
        &mut self,
        dt_s: f32,
        airborne: bool,
        tilt_limited: bool,
        vel_err_mps: f32,
    ) {
        if airborne && tilt_limited && vel_err_mps > WIND_VEL_ERR_MPS && self.mode != Mode::Land {
            self.wind_sat_s += dt_s;
        } else {
            self.wind_sat_s = (self.wind_sat_s - WIND_LEAK * dt_s).max(0.0);
        }
    }

    /// Height of the rangefinders above the ground, for landing: the rangefinder fusion when
    /// it has a usable estimate (paper B), else barometric height above the take-off point
    /// plus the sensors' height when standing on the gear.
    pub fn height_above_ground_m(&self, nav: &NavState) -> f32 {
        let g = &nav.ground;
        if self.ground_usable(nav) {
            g.height_m
        } else {
            -nav.pos_ned_m[2] - self.takeoff_alt_m + self.params.airframe.sensor_height_on_ground_m
        }
    }

    /// The fused ground height is fresh and tight enough to land on.
    fn ground_usable(&self, nav: &NavState) -> bool {
        let g = &nav.ground;
        !matches!(g.source, GroundSource::None | GroundSource::Predicted)
            && g.variance_m2.is_finite()
            && g.variance_m2 < GROUND_MAX_VAR_M2
    }

    /// Run the land detector (every armed mode); in LAND, a confirmed touchdown disarms.
    fn detect_touchdown(&mut self, dt_s: f32, nav: &NavState, vz_cmd_down: f32) {
        if self.land.landed() {
            if self.mode == Mode::Land {
                self.disarm_landed();
            }
            return;
        }
        let on_ground_m = self.params.airframe.sensor_height_on_ground_m;
        let height_m = self.height_above_ground_m(nav);
        let near_ground = height_m < on_ground_m + crate::land_detector::CONTACT_MARGIN_M;
        let climb_rate_mps = if near_ground && self.ground_usable(nav) {
            nav.ground_rate_up_mps
        } else {
            -nav.vel_ned_mps[2]
        };
        let r = nav.rate_frd_radps;
        let x = LandInputs {
            thrust_n: self.telemetry.thrust_n,
            hover_thrust_n: self.params.airframe.mass_kg * GRAVITY_MPS2,
            climb_rate_mps,
            height_agl_m: height_m,
            height_on_ground_m: on_ground_m,
            rate_norm_radps: fcc_nav::math::sqrtf(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]),
            descending: vz_cmd_down > 0.0 || self.mode == Mode::Land,
        };
        if self.land.update(dt_s, &x, self.params.limits.touchdown_s) == LandState::Landed {
            self.setpoint = None;
            if self.mode == Mode::Land {
                self.disarm_landed();
            } else {
                self.motors = [self.params.airframe.idle_cmd; MOTOR_COUNT];
            }
        }
    }

    fn disarm_landed(&mut self) {
        self.mode = Mode::Disarmed;
        self.setpoint = None;
        self.motors = [0.0; MOTOR_COUNT];
    }
}
