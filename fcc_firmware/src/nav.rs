//! Navigation task: wires sensor samples into the `fcc_nav` filters at 500 Hz.
//!
//! Inputs: IMU (every tick), magnetometer, barometer, GPS (as they arrive). Outputs a
//! [`NavState`] in NED / FRD. Before arming, while still on the ground, it calibrates the gyro
//! bias and the barometric reference over `calibration_s`. The first valid GPS fix becomes the
//! local NED origin (home).

use crate::nav_health::{gps_gate_m, GpsInnovation, Innovations, NavHealth};
use crate::params::NavParams;
use crate::sensors::{BaroSample, GpsFix, ImuSample, SensorInputs};
use fcc_msgs::geodesy::{Lla, LocalNed};
use fcc_nav::attitude::{
    accel_tilt_rad, linear_accel_ned_mps2, mag_heading_rad, AttitudeEstimator, Euler,
};
use fcc_nav::ground_altitude::{GroundAltitude, GroundAltitudeFilter, GroundAltitudeParams};
use fcc_nav::horizontal::HorizontalEstimator;
use fcc_nav::lowpass::LowPass2;
use fcc_nav::range_aid::RangeAid;
use fcc_nav::tilt_kf::{GpsTiltKf, TiltCorrection};
use fcc_nav::vertical::{pressure_to_alt_m, VerticalEstimator};

/// Largest accelerometer bias the navigation filters may attribute (m/s²).
const ACCEL_BIAS_LIMIT_MPS2: f32 = 1.5;
/// The tilt innovation monitor runs on every this-many IMU samples.
const TILT_CHECK_EVERY: u8 = 10;
/// The GPS velocity stops correcting the tilt (and the GPS-differenced acceleration stops
/// compensating the accelerometer) when the last GPS velocity is older than this, s (1.5
/// periods of the 5 Hz u-blox solution). Held for the
/// whole GPS timeout (1 s), a stale gust acceleration was read as tilt, and that attitude error
/// is what the dead-reckoned velocity integrates after the loss (g·δ): `gps_loss.yaml` in still
/// air, seed 2, 2 s after the loss, 0.78° → 0.47° (0.5 s: 0.56°); campaign family `gps_loss`,
/// touchdown horizontal worst 0.83 → 0.61 m/s, every other family unchanged.
const GPS_ACCEL_MAX_AGE_S: f32 = 0.3;
/// [`GPS_ACCEL_MAX_AGE_S`] in µs: the per-step age checks compare integers (a u64 → f32
/// conversion is a library call on the Cortex-M4F).
pub const GPS_ACCEL_MAX_AGE_US: u64 = (GPS_ACCEL_MAX_AGE_S * 1e6) as u64;
/// Once the GPS-differenced acceleration is stale ([`GPS_ACCEL_MAX_AGE_S`] after the last GPS
/// velocity) in flight, the tilt is held on the gyro alone until the last GPS fix is this old,
/// s (a GPS-lost LAND from 8 m touches down within ≈ 8 s); then the accelerometer corrects it
/// again (a longer descent would otherwise integrate the gyro's residual bias). Campaign family
/// `gps_loss` (`fcc-campaign --per-family 72 --long`): touchdown horizontal worst 0.50 → 0.43
/// m/s, 8 → 5 landings above 0.3 m/s; the drift from the loss to contact p95 1.05 → 0.89 m.
const GYRO_ONLY_TILT_MAX_S: f32 = 20.0;
/// [`GYRO_ONLY_TILT_MAX_S`] in µs.
const GYRO_ONLY_TILT_MAX_US: u64 = (GYRO_ONLY_TILT_MAX_S * 1e6) as u64;
/// A fused ground height with a larger variance than this does not aid the height, m².
const AID_MAX_VAR_M2: f32 = 0.05;

/// The navigation solution, NED relative to home, body FRD.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NavState {
    pub t_us: u64,
    pub euler: Euler,
    /// Gyro rate after bias calibration, body FRD.
    pub rate_frd_radps: [f32; 3],
    pub pos_ned_m: [f32; 3],
    pub vel_ned_mps: [f32; 3],
    /// Gravity-compensated acceleration from the accelerometer, NED (raw, noisy).
    pub accel_ned_mps2: [f32; 3],
    /// Barometric altitude above the calibration point (m, up).
    pub baro_alt_m: f32,
    /// GPS currently feeding the horizontal filter.
    pub gps_ok: bool,
    /// Home (NED origin) known from GPS.
    pub home_set: bool,
    /// Gyro/baro calibration done.
    pub calibrated: bool,
    /// Height above the ground below from the laser + sonar Kalman fusion (paper B).
    pub ground: GroundAltitude,
    /// Rate of that height (m/s, up positive): `−v_down + r`, with `r` the filter's residual
    /// rate learnt from the rangefinders (corrects a biased vertical velocity near the ground).
    pub ground_rate_up_mps: f32,
    /// Latest raw rangefinder readings (m along the sensor axis; laser 99999 = no return).
    pub laser_m: Option<f32>,
    pub sonar_m: Option<f32>,
    /// Estimator faults ([`crate::nav_health`] bits; latched until the next arm).
    pub nav_faults: u8,
    /// Seconds the magnetometer has been rejected in a row (0 = fused).
    pub mag_disturbed_s: f32,
}

impl NavState {
    /// Horizontal speed over the ground, m/s.
    pub fn ground_speed_mps(&self) -> f32 {
        fcc_nav::math::hypotf(self.vel_ned_mps[0], self.vel_ned_mps[1])
    }
}

/// Why the navigation task is not ready to fly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NavNotReady {
    Calibrating,
    NoGpsHome,
}

pub struct Navigator {
    params: NavParams,
    att: AttitudeEstimator,
    horiz: HorizontalEstimator,
    vert: VerticalEstimator,
    home: Option<LocalNed>,
    gyro_bias_frd_radps: [f32; 3],
    cal_gyro_sum: [f32; 3],
    cal_accel_sum: [f32; 3],
    cal_baro_sum: f32,
    /// Magnetometer (offsets removed) summed over the calibration: the initial heading and the
    /// field reference come from the mean, not from one noisy sample.
    cal_mag_sum: [f32; 3],
    cal_mag_n: u32,
    cal_imu_n: u32,
    cal_baro_n: u32,
    cal_start_us: Option<u64>,
    calibrated: bool,
    p0_pa: f32,
    last_imu_us: Option<u64>,
    last_gps_us: Option<u64>,
    last_mag_frd: Option<[f32; 3]>,
    /// Accelerometer low-pass for the tilt correction only (vibration before asin/atan2).
    tilt_accel_lpf: [LowPass2; 3],
    /// Vehicle acceleration from successive GPS velocities (NED), smoothed: subtracted from
    /// the accelerometer's specific force so that manoeuvres are not mistaken for tilt (as
    /// ArduPilot's DCM does). Only while the GPS velocity corrects the tilt itself
    /// ([`Self::gps_tilt_aided`]), so it now shapes the tilt innovation monitor's reading,
    /// not the tilt.
    gps_accel_ned_mps2: [f32; 3],
    last_gps_vel: Option<(u64, [f32; 3])>,
    /// Roll/pitch and their rate biases from the GPS velocity's innovation (steady-state
    /// Kalman gains): the tilt's correction while GPS velocities arrive (see
    /// [`Self::gps_tilt_aided`]).
    tilt_kf: GpsTiltKf,
    /// The correction `tilt_kf` made in the last step, if any (for replaying the estimator).
    gps_tilt_applied: Option<TiltCorrection>,
    ground: GroundAltitudeFilter,
    /// Air temperature for the sonar's speed-of-sound correction: the barometer's sensor
    /// temperature (the MS5611 sits in the airflow on the paper's board), °C.
    air_temp_c: f32,
    /// Range-aided height: the vertical filter's measurement while the ground is in range.
    range_aid: RangeAid,
    /// Innovation monitors of every filter.
    health: NavHealth,
    tilt_check_tick: u8,
    vert_aided: bool,
    last_baro_us: Option<u64>,
    state: NavState,
}

impl Navigator {
    pub fn new(params: NavParams) -> Self {
        let mut horiz = HorizontalEstimator::new(params.horiz_gains());
        // The horizontal accelerometer bias is learnt from the GPS velocity (gps_update), not
        // from the position: the position crossover is far below the bias pole.
        horiz.n.set_bias_limit(ACCEL_BIAS_LIMIT_MPS2);
        horiz.e.set_bias_limit(ACCEL_BIAS_LIMIT_MPS2);
        let mut vert = VerticalEstimator::new(params.vert_gains());
        vert.down
            .set_bias_gain(params.vert_bias_pole_radps, ACCEL_BIAS_LIMIT_MPS2);
        Self {
            params,
            att: AttitudeEstimator::new(
                params.tilt_gains(),
                params.yaw_gains(),
                params.declination_deg.to_radians(),
            ),
            horiz,
            vert,
            home: None,
            gyro_bias_frd_radps: [0.0; 3],
            cal_gyro_sum: [0.0; 3],
            cal_accel_sum: [0.0; 3],
            cal_baro_sum: 0.0,
            cal_mag_sum: [0.0; 3],
            cal_mag_n: 0,
            cal_imu_n: 0,
            cal_baro_n: 0,
            cal_start_us: None,
            calibrated: false,
            p0_pa: 101_325.0,
            last_imu_us: None,
            last_gps_us: None,
            last_mag_frd: None,
            tilt_accel_lpf: [LowPass2::new(params.tilt_accel_lpf_hz, 500.0); 3],
            gps_accel_ned_mps2: [0.0; 3],
            last_gps_vel: None,
            tilt_kf: GpsTiltKf::new(),
            gps_tilt_applied: None,
            ground: GroundAltitudeFilter::new(GroundAltitudeParams::default()),
            air_temp_c: 15.0,
            range_aid: RangeAid::new(),
            health: NavHealth::new(),
            tilt_check_tick: 0,
            vert_aided: false,
            last_baro_us: None,
            state: NavState::default(),
        }
    }

    pub fn state(&self) -> &NavState {
        &self.state
    }

    /// Magnetometer health: whether readings are currently rejected by the attitude filter's
    /// innovation gate (a magnetic disturbance is suspected), and how many were rejected so far.
    pub fn mag_disturbance(&self) -> (bool, u32) {
        (self.att.mag_disturbed(), self.att.mag_rejects())
    }

    /// Whether the next IMU step's tilt is corrected by the GPS velocity ([`GpsTiltKf`], at
    /// each fix) instead of the accelerometer's gravity direction: while GPS velocities
    /// arrive (the last one at most [`GPS_ACCEL_MAX_AGE_S`] old) and the GPS is healthy, at
    /// every height.
    ///
    /// Until 2026-12-07 the accelerometer took over below 1 m of fused height, so that LAND's
    /// touchdown gate would see a gust's specific force in the estimated tilt at once. But the
    /// accelerometer's gravity direction in gusts is what the GPS-differenced acceleration only
    /// partly removes (it lags by the latency and its smoothing), and the hold at the gate
    /// then leaned on a tilt error that the horizontal velocity integrates: `hover_gale` 1016
    /// went from −0.05° to −0.4° of roll error below 1 m, and its velocity error from ≈ 0.02
    /// to 0.06 m/s. With the GPS velocity's correction at every height (40 seed sets of
    /// `fcc-campaign --per-family 72 --long`, S = 1000, 3000 … 79000, 23,040 flights), the
    /// estimate's horizontal velocity error at the gale's touchdowns: RMS 0.035 → 0.031 m/s,
    /// p99 0.080 → 0.071, worst 0.116 → 0.100; failed flights 10 → 9 (gale 7 → 5, GPS lost 3
    /// → 4 with a new one at 0.3004 m/s, the other five families 0 → 0).
    ///
    /// The accelerometer compared with a GPS-differenced acceleration mixes two times (that
    /// difference lags by the latency plus half an interval, and its 0.5 s smoothing more);
    /// the inertial velocity against the GPS's at the same (latency-aligned) instant does not.
    /// Attitude bench (`tests/benches/attitude_filter.rs`, 6 seeds each, RMS roll/pitch,
    /// offline re-run), with the velocity *change* over one fix interval as the tilt
    /// measurement (the aid before the Kalman gains): square 0.312/0.337° → 0.249/0.292°,
    /// manoeuvre 0.328/0.537° → 0.218/0.257°.
    pub fn gps_tilt_aided(&self) -> bool {
        self.state.gps_ok
            && self
                .last_gps_vel
                .is_some_and(|(t, _)| self.state.t_us.saturating_sub(t) <= GPS_ACCEL_MAX_AGE_US)
    }

    /// The tilt correction the GPS velocity made in the last step (see [`Self::gps_tilt_aided`]).
    pub fn gps_tilt_applied(&self) -> Option<TiltCorrection> {
        self.gps_tilt_applied
    }

    /// The manoeuvre acceleration (NED, m/s²) the next IMU step removes from the specific
    /// force it reads as a gravity direction: the smoothed GPS-differenced acceleration while
    /// GPS velocities arrive ([`Self::gps_tilt_aided`]: then that reading only feeds the tilt
    /// innovation monitor, the GPS velocity corrects the tilt), else zero (the tilt is held
    /// on the gyro first, then corrected from the accelerometer as it is).
    pub fn tilt_accel_comp_ned_mps2(&self) -> [f32; 3] {
        if self.gps_tilt_aided() {
            self.gps_accel_ned_mps2
        } else {
            [0.0; 3]
        }
    }

    /// Whether the tilt is held on the gyro alone: in flight, with the GPS-differenced
    /// acceleration no longer compensating the accelerometer (GPS lost, or its last velocity
    /// older than [`GPS_ACCEL_MAX_AGE_S`]), the last GPS fix younger than
    /// [`GYRO_ONLY_TILT_MAX_S`]. Without that compensation every gust acceleration the
    /// accelerometer reads would pull the tilt, and the dead-reckoned velocity integrates the
    /// tilt error (g·δ); the calibrated gyro drifts far less over a landing. From the stale
    /// compensation, not from the GPS timeout (1 s): in between the gusts pulled the tilt too
    /// (campaign family `gps_loss`, touchdowns beyond 0.3 m/s in seed sets 1000 / 3000 / 5000:
    /// 1 / 2 / 9 → 0 / 2 / 8).
    fn gyro_only_tilt(&self, now_us: u64, on_ground_disarmed: bool) -> bool {
        let age_us = |t: u64| now_us.saturating_sub(t);
        !on_ground_disarmed
            && (!self.state.gps_ok
                || self
                    .last_gps_vel
                    .is_some_and(|(t, _)| age_us(t) > GPS_ACCEL_MAX_AGE_US))
            && self
                .last_gps_us
                .is_some_and(|t| age_us(t) <= GYRO_ONLY_TILT_MAX_US)
    }

    pub fn home(&self) -> Option<Lla> {
        self.home.as_ref().map(|h| h.origin())
    }

    pub fn ready(&self) -> Result<(), NavNotReady> {
        if !self.calibrated {
            Err(NavNotReady::Calibrating)
        } else if self.home.is_none() {
            Err(NavNotReady::NoGpsHome)
        } else {
            Ok(())
        }
    }

    /// One 500 Hz step. `on_ground_disarmed`: calibration may run (vehicle still).
    pub fn step(&mut self, now_us: u64, s: &SensorInputs, on_ground_disarmed: bool) -> &NavState {
        let mut s = *s;
        if let Some(m) = s.mag.as_mut() {
            for i in 0..3 {
                m.mag_frd_ut[i] -= self.params.mag_offset_frd_ut[i];
            }
            self.last_mag_frd = Some(m.mag_frd_ut);
        }
        if let Some(imu) = s.imu.as_mut() {
            for i in 0..3 {
                imu.accel_frd_mps2[i] -= self.params.accel_offset_frd_mps2[i];
            }
        }
        let s = &s;
        if !self.calibrated {
            self.calibrate(now_us, s, on_ground_disarmed);
        }
        self.gps_tilt_applied = None;
        let mut imu_dt_s = 0.0;
        let mut innov = Innovations::default();
        if let Some(imu) = s.imu {
            let mag = s.mag.map(|m| m.mag_frd_ut);
            imu_dt_s = self.imu_update(imu, mag, on_ground_disarmed, &mut innov);
        }
        if let Some(b) = s.baro {
            self.baro_update(b, &mut innov);
        }
        if let Some(g) = s.gps {
            self.gps_update(now_us, g, &mut innov);
        }
        let faults = if self.calibrated {
            self.health.update(imu_dt_s, &innov)
        } else {
            0
        };
        let gps_ok = match self.last_gps_us {
            Some(t) => now_us.saturating_sub(t) as f32 * 1e-6 < self.params.gps_timeout_s,
            None => false,
        } && faults & crate::nav_health::FAULT_HORIZONTAL == 0;
        if !gps_ok && self.last_gps_us.is_some() {
            self.horiz.clear_gps();
        }
        if self.calibrated {
            self.ground_update(imu_dt_s, s);
        }
        let pn = self.horiz.pos_ne_m();
        let vn = self.horiz.vel_ne_mps();
        self.state.t_us = now_us;
        self.state.pos_ned_m = [pn[0], pn[1], -self.vert.alt_m()];
        self.state.vel_ned_mps = [vn[0], vn[1], self.vert.vel_down_mps()];
        self.state.gps_ok = gps_ok;
        self.state.nav_faults = faults;
        self.state.mag_disturbed_s = self.att.mag_disturbed_s();
        self.state.home_set = self.home.is_some();
        self.state.calibrated = self.calibrated;
        &self.state
    }

    /// IMU sample: attitude (gyro, the GPS-compensated accelerometer, the magnetometer), the
    /// tilt innovation (at 50 Hz), the NED acceleration into the horizontal and vertical
    /// filters. Returns the IMU period, s.
    fn imu_update(
        &mut self,
        imu: ImuSample,
        mag: Option<[f32; 3]>,
        on_ground_disarmed: bool,
        innov: &mut Innovations,
    ) -> f32 {
        let dt_s = match self.last_imu_us {
            Some(t) if imu.t_us > t => ((imu.t_us - t) as f32 * 1e-6).min(0.02),
            _ => 0.002,
        };
        self.last_imu_us = Some(imu.t_us);
        let gyro = [
            imu.gyro_frd_radps[0] - self.gyro_bias_frd_radps[0],
            imu.gyro_frd_radps[1] - self.gyro_bias_frd_radps[1],
            imu.gyro_frd_radps[2] - self.gyro_bias_frd_radps[2],
        ];
        let f = imu.accel_frd_mps2;
        let f_lp = [
            self.tilt_accel_lpf[0].update(f[0]),
            self.tilt_accel_lpf[1].update(f[1]),
            self.tilt_accel_lpf[2].update(f[2]),
        ];
        // Remove the manoeuvre acceleration (GPS-derived, NED → body) from the specific
        // force before it is read as a gravity direction (by the tilt monitor while the GPS
        // velocity corrects the tilt).
        let a = self.tilt_accel_comp_ned_mps2();
        self.att.mag_realign_allowed = on_ground_disarmed;
        self.att.accel_tilt = !self.gps_tilt_aided();
        let euler = if self.calibrated {
            let f_tilt_in = if self.gyro_only_tilt(imu.t_us, on_ground_disarmed) {
                // A zero specific force fails the estimator's gravity gate: no tilt correction.
                [0.0; 3]
            } else {
                f_lp
            };
            self.att.update_compensated(gyro, f_tilt_in, a, mag, dt_s)
        } else {
            self.att.euler()
        };
        // The compensated specific force of the estimator's latest tilt correction (100 Hz).
        let f_tilt = self.att.tilt_specific_force_frd_mps2();
        // The tilt monitor samples at 50 Hz (its hold time is seconds; asin/atan2 at 500 Hz
        // would cost the MCU ~10 % of a step).
        self.tilt_check_tick = (self.tilt_check_tick + 1) % TILT_CHECK_EVERY;
        let n_f = fcc_nav::math::sqrtf(
            f_tilt[0] * f_tilt[0] + f_tilt[1] * f_tilt[1] + f_tilt[2] * f_tilt[2],
        );
        if self.calibrated
            && self.tilt_check_tick == 0
            && fcc_nav::math::fabsf(n_f - fcc_nav::GRAVITY_MPS2) <= self.params.accel_gate_mps2
        {
            let (r_a, p_a) = accel_tilt_rad(f_tilt);
            let d = fcc_nav::math::hypotf(r_a - euler.roll_rad, p_a - euler.pitch_rad);
            innov.tilt_rad = Some(d);
        }
        let a_ned = linear_accel_ned_mps2(&euler, imu.accel_frd_mps2);
        if self.calibrated {
            self.tilt_kf.step([a_ned[0], a_ned[1]], dt_s);
            self.horiz.update([a_ned[0], a_ned[1]], dt_s);
            self.vert.update(a_ned[2], dt_s);
        }
        self.state.euler = euler;
        self.state.rate_frd_radps = gyro;
        self.state.accel_ned_mps2 = a_ned;
        dt_s
    }

    /// Barometer sample: altitude (with the rangefinder aid's offset) into the vertical filter,
    /// its innovation.
    fn baro_update(&mut self, b: BaroSample, innov: &mut Innovations) {
        if b.temperature_c.is_finite() {
            self.air_temp_c = b.temperature_c;
        }
        let alt = pressure_to_alt_m(b.pressure_pa, self.p0_pa);
        self.state.baro_alt_m = alt;
        let dt_s = self
            .last_baro_us
            .map_or(0.0, |t| b.t_us.saturating_sub(t) as f32 * 1e-6);
        self.last_baro_us = Some(b.t_us);
        if self.calibrated {
            let z = self.range_aid.measurement(
                dt_s,
                self.vert.alt_m(),
                alt,
                self.aid_height_m(),
                self.ground.reinit_count(),
                self.ground.rate_residual_mps(),
                self.state.ground_speed_mps(),
            );
            self.vert.baro_alt(z);
            // The range's crossover only while the measurement is the range altitude: the barometer
            // standing in (a suspect range altitude) at it dropped the height 0.58 m in 0.2 s
            // (campaign `landing` 5063, tests/tests/ground_altitude.rs).
            self.set_vert_aided(self.range_aid.range_measured());
            let baro_corr = alt - self.range_aid.baro_offset_m();
            innov.baro_alt_m = Some(fcc_nav::math::fabsf(baro_corr - self.vert.alt_m()));
        }
    }

    /// GPS fix: home on the first one after calibration, the differenced-velocity acceleration
    /// (attitude compensation), position and velocity into the horizontal filter unless it
    /// jumped; its innovation.
    fn gps_update(&mut self, now_us: u64, g: GpsFix, innov: &mut Innovations) {
        if g.fix_ok && g.lat_deg.is_finite() && g.lon_deg.is_finite() {
            let lla = Lla {
                lat_deg: g.lat_deg,
                lon_deg: g.lon_deg,
                alt_m: g.alt_m as f64,
            };
            if self.home.is_none() && self.calibrated {
                self.home = Some(LocalNed::new(lla));
                let p = self.state.pos_ned_m;
                self.horiz.reset([0.0, 0.0], [0.0, 0.0]);
                self.state.pos_ned_m = [0.0, 0.0, p[2]];
            }
            let mut fix_interval_s = 0.2;
            if let Some((t0, v0)) = self.last_gps_vel {
                let dt = now_us.saturating_sub(t0) as f32 * 1e-6;
                fix_interval_s = dt.clamp(0.05, 1.0);
                if dt > 0.05 && dt < 1.0 {
                    // First-order smoothing (~0.5 s) of the differenced GPS velocity.
                    let k = (dt / 0.5).min(1.0);
                    #[allow(clippy::needless_range_loop)] // one axis of three arrays
                    for i in 0..3 {
                        let a = (g.vel_ned_mps[i] - v0[i]) / dt;
                        self.gps_accel_ned_mps2[i] += k * (a - self.gps_accel_ned_mps2[i]);
                    }
                }
            }
            self.last_gps_vel = Some((now_us, g.vel_ned_mps));
            self.gps_tilt_update(g.vel_ned_mps);
            if let Some(home) = &self.home {
                let ned = home.lla_to_ned(&lla);
                let delay_steps = self.gps_delay_steps();
                let p = self.horiz.pos_ne_m();
                let d = fcc_nav::math::hypotf(ned[0] as f32 - p[0], ned[1] as f32 - p[1]);
                let gps = GpsInnovation {
                    distance_m: d,
                    gate_m: gps_gate_m(g.h_acc_m),
                };
                innov.gps = Some(gps);
                self.last_gps_us = Some(now_us);
                if !gps.acceptable() {
                    // A jump (multipath, spoofing): not fused; the monitor times it.
                    self.horiz.clear_gps();
                } else {
                    self.horiz.gps([ned[0] as f32, ned[1] as f32], delay_steps);
                    if g.vel_ned_mps.iter().all(|v| v.is_finite()) {
                        let k_v = self.params.gps_vel_gain;
                        self.horiz.gps_velocity(
                            [g.vel_ned_mps[0], g.vel_ned_mps[1]],
                            delay_steps,
                            k_v,
                            fcc_nav::complementary::bias_gain_per_fix(
                                self.params.horiz_bias_pole_radps,
                                k_v,
                                fix_interval_s,
                            ),
                        );
                    }
                }
            }
        }
    }

    /// The receiver's latency in IMU steps (500 Hz).
    fn gps_delay_steps(&self) -> usize {
        (self.params.gps_latency_s / 0.002 + 0.5) as usize
    }

    /// The GPS velocity's tilt correction ([`Self::gps_tilt_aided`]), while the GPS is healthy.
    fn gps_tilt_update(&mut self, vel_ned_mps: [f32; 3]) {
        if !self.calibrated || !self.state.gps_ok {
            self.tilt_kf.reset();
            return;
        }
        let delay_steps = self.gps_delay_steps();
        let v = [vel_ned_mps[0], vel_ned_mps[1]];
        let yaw = self.state.euler.yaw_rad;
        if let Some(c) = self.tilt_kf.gps_velocity(v, delay_steps, yaw) {
            if self.gps_tilt_aided() {
                self.att.apply_tilt_correction(&c);
                self.gps_tilt_applied = Some(c);
            }
        }
    }

    /// Ground altitude (paper B): predict with the vertical velocity (the process noise
    /// scaled with the speed over the ground), fuse the rangefinders.
    fn ground_update(&mut self, imu_dt_s: f32, s: &SensorInputs) {
        let e = self.state.euler;
        self.ground.set_ground_speed(self.state.ground_speed_mps());
        self.ground.predict(imu_dt_s, self.vert.vel_down_mps());
        if let Some(l) = s.laser {
            self.state.laser_m = Some(l.range_m);
            self.ground.update_laser(l.range_m, e.roll_rad, e.pitch_rad);
        }
        if let Some(r) = s.sonar {
            self.state.sonar_m = Some(r.range_m);
            self.ground
                .update_sonar(r.range_m, e.roll_rad, e.pitch_rad, self.air_temp_c);
        }
        self.state.ground = self.ground.output();
        self.state.ground_rate_up_mps = -self.vert.vel_down_mps() + self.ground.rate_residual_mps();
    }

    /// Paper B's fused height when it may aid the vertical filter: fused from a rangefinder
    /// recently, tight, and below `range_aid_max_m`.
    fn aid_height_m(&self) -> Option<f32> {
        use fcc_nav::ground_altitude::GroundSource;
        let g = &self.state.ground;
        let fused = !matches!(g.source, GroundSource::None | GroundSource::Predicted);
        (fused
            && g.variance_m2.is_finite()
            && g.variance_m2 < AID_MAX_VAR_M2
            && g.height_m < self.params.range_aid_max_m)
            .then_some(g.height_m)
    }

    /// The vertical filter's crossover follows the measurement's quality: the rangefinder's
    /// centimetres allow a high one (accelerometer errors then matter little), the
    /// barometer's prop-wash noise a low one.
    fn set_vert_aided(&mut self, aided: bool) {
        if aided == self.vert_aided {
            return;
        }
        self.vert_aided = aided;
        let g = if aided {
            self.params.vert_aided_gains()
        } else {
            self.params.vert_gains()
        };
        self.vert.down.set_gains(g);
        self.vert
            .down
            .set_bias_gain(self.params.vert_bias_pole_radps, ACCEL_BIAS_LIMIT_MPS2);
    }

    /// Forget latched estimator faults (at arming, on the ground).
    pub fn clear_faults(&mut self) {
        self.health.clear();
    }

    /// The innovation monitors (GPS fixes refused so far, fault bits).
    pub fn health(&self) -> &NavHealth {
        &self.health
    }

    /// The range aid (its baro offset, terrain reference, innovation).
    pub fn range_aid(&self) -> &RangeAid {
        &self.range_aid
    }

    fn calibrate(&mut self, now_us: u64, s: &SensorInputs, still: bool) {
        if !still {
            return;
        }
        let start = *self.cal_start_us.get_or_insert(now_us);
        if let Some(imu) = s.imu {
            for i in 0..3 {
                self.cal_gyro_sum[i] += imu.gyro_frd_radps[i];
                self.cal_accel_sum[i] += imu.accel_frd_mps2[i];
            }
            self.cal_imu_n += 1;
        }
        if let Some(b) = s.baro {
            self.cal_baro_sum += b.pressure_pa;
            self.cal_baro_n += 1;
        }
        if let Some(m) = s.mag {
            for i in 0..3 {
                self.cal_mag_sum[i] += m.mag_frd_ut[i];
            }
            self.cal_mag_n += 1;
        }
        let elapsed_s = now_us.saturating_sub(start) as f32 * 1e-6;
        if elapsed_s >= self.params.calibration_s && self.cal_imu_n > 100 && self.cal_baro_n > 5 {
            let n = self.cal_imu_n as f32;
            self.gyro_bias_frd_radps = [
                self.cal_gyro_sum[0] / n,
                self.cal_gyro_sum[1] / n,
                self.cal_gyro_sum[2] / n,
            ];
            let f = [
                self.cal_accel_sum[0] / n,
                self.cal_accel_sum[1] / n,
                self.cal_accel_sum[2] / n,
            ];
            self.p0_pa = self.cal_baro_sum / self.cal_baro_n as f32;
            let (roll, pitch) = accel_tilt_rad(f);
            let mag = if self.cal_mag_n > 0 {
                let n = self.cal_mag_n as f32;
                Some(self.cal_mag_sum.map(|x| x / n))
            } else {
                self.last_mag_frd
            };
            let yaw = match mag {
                Some(m) => {
                    self.att.set_mag_reference(m, roll, pitch);
                    mag_heading_rad(m, roll, pitch, self.params.declination_deg.to_radians())
                }
                None => 0.0,
            };
            self.att.reset(Euler {
                roll_rad: roll,
                pitch_rad: pitch,
                yaw_rad: yaw,
            });
            self.vert.reset(0.0, 0.0);
            // At rest the specific force must have magnitude g: the excess is the accelerometer
            // bias along gravity, i.e. the vertical channel's bias (NED down positive).
            let f_norm = fcc_nav::math::sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
            self.vert.down.set_bias(fcc_nav::GRAVITY_MPS2 - f_norm);
            self.horiz.reset([0.0, 0.0], [0.0, 0.0]);
            self.calibrated = true;
        }
    }
}
