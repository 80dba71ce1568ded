//! Navigation task: wires sensor samples into the `fcc_nav` filters at 500 Hz.
//!
//! Inputs: IMU (every tick), magnetometer, barometer, GPS (as they arrive). Outputs a
//! [`NavState`] in NED / FRD. Before arming, while still on the ground, it calibrates the gyro
//! bias and the barometric reference over `calibration_s`. The first valid GPS fix becomes the
//! local NED origin (home).

use crate::nav_health::{Innovations, NavHealth};
use crate::params::NavParams;
use crate::sensors::{BaroSample, GpsFix, ImuSample, SensorInputs};
use fcc_nav::attitude::{
    accel_tilt_rad, linear_accel_ned_mps2, mag_heading_rad, rot_body_to_ned, AttitudeEstimator,
    Euler,
};
use fcc_nav::geodesy::{Lla, LocalNed};
use fcc_nav::ground_altitude::{GroundAltitude, GroundAltitudeFilter, GroundAltitudeParams};
use fcc_nav::horizontal::HorizontalEstimator;
use fcc_nav::lowpass::LowPass2;
use fcc_nav::range_aid::RangeAid;
use fcc_nav::vertical::{pressure_to_alt_m, VerticalEstimator};

/// Largest accelerometer bias the navigation filters may attribute (m/s²).
const ACCEL_BIAS_LIMIT_MPS2: f32 = 1.5;
/// The tilt innovation monitor runs on every this-many IMU samples.
const TILT_CHECK_EVERY: u8 = 10;
/// A fused ground height with a larger variance than this does not aid the height, m².
const AID_MAX_VAR_M2: f32 = 0.05;

/// The navigation solution, NED relative to home, body FRD.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
    /// Vehicle acceleration from successive GPS velocities (NED), smoothed, and when it was
    /// last updated: subtracted from the accelerometer before the tilt correction so that
    /// manoeuvres are not mistaken for tilt (as ArduPilot's DCM does).
    gps_accel_ned_mps2: [f32; 3],
    last_gps_vel: Option<(u64, [f32; 3])>,
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
        horiz
            .n
            .set_bias_gain(params.horiz_bias_pole_radps, ACCEL_BIAS_LIMIT_MPS2);
        horiz
            .e
            .set_bias_gain(params.horiz_bias_pole_radps, ACCEL_BIAS_LIMIT_MPS2);
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
        let s = &self.remove_sensor_offsets(s);
        if !self.calibrated {
            self.calibrate(now_us, s, on_ground_disarmed);
        }
        let mut imu_dt_s = 0.0;
        let mut innov = Innovations::default();
        if let Some(imu) = s.imu {
            let mag_frd_ut = s.mag.map(|m| m.mag_frd_ut);
            imu_dt_s = self.fuse_imu(&imu, mag_frd_ut, on_ground_disarmed, &mut innov);
        }
        if let Some(b) = s.baro {
            self.fuse_baro(&b, &mut innov);
        }
        if let Some(g) = s.gps {
            self.fuse_gps(now_us, &g, &mut innov);
        }
        let faults = if self.calibrated {
            self.health.update(imu_dt_s, &innov)
        } else {
            0
        };
        let gps_ok = self.gps_fresh_and_healthy(now_us, faults);
        if !gps_ok && self.last_gps_us.is_some() {
            self.horiz.clear_gps();
        }
        if self.calibrated {
            self.update_ground(imu_dt_s, s);
        }
        self.publish_state(now_us, gps_ok, faults)
    }

    /// The samples with the configured magnetometer and accelerometer offsets removed (and the
    /// corrected magnetometer kept for the heading at the end of calibration).
    #[inline]
    fn remove_sensor_offsets(&mut self, s: &SensorInputs) -> SensorInputs {
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
        s
    }

    /// IMU sample: attitude propagated with the bias-corrected gyro and corrected by the
    /// tilt-filtered accelerometer and the magnetometer (once calibrated), the tilt innovation
    /// sampled, the NED acceleration fed to the horizontal and vertical filters. Returns the
    /// IMU interval, s.
    #[inline]
    fn fuse_imu(
        &mut self,
        imu: &ImuSample,
        mag_frd_ut: Option<[f32; 3]>,
        on_ground_disarmed: bool,
        innov: &mut Innovations,
    ) -> f32 {
        let dt_s = self.imu_interval_s(imu.t_us);
        let gyro = [
            imu.gyro_frd_radps[0] - self.gyro_bias_frd_radps[0],
            imu.gyro_frd_radps[1] - self.gyro_bias_frd_radps[1],
            imu.gyro_frd_radps[2] - self.gyro_bias_frd_radps[2],
        ];
        let f_tilt = self.tilt_specific_force_frd_mps2(imu.accel_frd_mps2);
        self.att.mag_realign_allowed = on_ground_disarmed;
        let euler = if self.calibrated {
            self.att.update(gyro, Some(f_tilt), mag_frd_ut, dt_s)
        } else {
            self.att.euler()
        };
        self.monitor_tilt(f_tilt, &euler, innov);
        let a_ned = linear_accel_ned_mps2(&euler, imu.accel_frd_mps2);
        if self.calibrated {
            self.horiz.update([a_ned[0], a_ned[1]], dt_s);
            self.vert.update(a_ned[2], dt_s);
        }
        self.state.euler = euler;
        self.state.rate_frd_radps = gyro;
        self.state.accel_ned_mps2 = a_ned;
        dt_s
    }

    /// Time since the previous IMU sample, s (2 ms for the first or an out-of-order one,
    /// at most 20 ms).
    #[inline]
    fn imu_interval_s(&mut self, imu_t_us: u64) -> f32 {
        let dt_s = match self.last_imu_us {
            Some(t) if imu_t_us > t => ((imu_t_us - t) as f32 * 1e-6).min(0.02),
            _ => 0.002,
        };
        self.last_imu_us = Some(imu_t_us);
        dt_s
    }

    /// The low-passed specific force with the manoeuvre acceleration (GPS-derived, NED → body)
    /// removed, before it is read as a gravity direction, body FRD, m/s².
    #[inline]
    fn tilt_specific_force_frd_mps2(&mut self, accel_frd_mps2: [f32; 3]) -> [f32; 3] {
        let f = accel_frd_mps2;
        let f_lp = [
            self.tilt_accel_lpf[0].update(f[0]),
            self.tilt_accel_lpf[1].update(f[1]),
            self.tilt_accel_lpf[2].update(f[2]),
        ];
        let r = rot_body_to_ned(&self.att.euler());
        let a = if self.state.gps_ok {
            self.gps_accel_ned_mps2
        } else {
            [0.0; 3]
        };
        let mut f_tilt = f_lp;
        for (i, ft) in f_tilt.iter_mut().enumerate() {
            *ft -= r[0][i] * a[0] + r[1][i] * a[1] + r[2][i] * a[2];
        }
        f_tilt
    }

    /// The tilt innovation (accelerometer tilt against the estimate) when the specific force
    /// is close to g. The monitor samples at 50 Hz (its hold time is seconds; asin/atan2 at
    /// 500 Hz would cost the MCU ~10 % of a step).
    #[inline]
    fn monitor_tilt(&mut self, f_tilt: [f32; 3], euler: &Euler, innov: &mut Innovations) {
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
    }

    /// Barometer sample: air temperature for the sonar, barometric altitude, and (once
    /// calibrated) the range-aided height measurement of the vertical filter.
    #[inline]
    fn fuse_baro(&mut self, b: &BaroSample, innov: &mut Innovations) {
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
            );
            self.vert.baro_alt(z);
            self.set_vert_aided(self.range_aid.aiding());
            let baro_corr = alt - self.range_aid.baro_offset_m();
            innov.baro_alt_m = Some(fcc_nav::math::fabsf(baro_corr - self.vert.alt_m()));
        }
    }

    /// GPS fix: the first valid one (once calibrated) becomes home; every valid one updates
    /// the manoeuvre acceleration and, with a home, is gated and fused.
    #[inline]
    fn fuse_gps(&mut self, now_us: u64, g: &GpsFix, innov: &mut Innovations) {
        if !(g.fix_ok && g.lat_deg.is_finite() && g.lon_deg.is_finite()) {
            return;
        }
        let lla = Lla {
            lat_deg: g.lat_deg,
            lon_deg: g.lon_deg,
            alt_m: g.alt_m as f64,
        };
        if self.home.is_none() && self.calibrated {
            self.set_home(lla);
        }
        self.update_gps_accel_ned_mps2(now_us, g.vel_ned_mps);
        let ned_m = match &self.home {
            Some(home) => home.lla_to_ned(&lla),
            None => return,
        };
        self.fuse_gps_ned(now_us, ned_m, g.vel_ned_mps, innov);
    }

    /// Make `lla` the NED origin; the horizontal filter restarts there, the height is kept.
    #[inline]
    fn set_home(&mut self, lla: Lla) {
        self.home = Some(LocalNed::new(lla));
        let p = self.state.pos_ned_m;
        self.horiz.reset([0.0, 0.0], [0.0, 0.0]);
        self.state.pos_ned_m = [0.0, 0.0, p[2]];
    }

    /// Vehicle acceleration from successive GPS velocities: first-order smoothing (~0.5 s) of
    /// the differenced velocity, for fixes 50 ms to 1 s apart.
    #[inline]
    fn update_gps_accel_ned_mps2(&mut self, now_us: u64, vel_ned_mps: [f32; 3]) {
        if let Some((t0, v0)) = self.last_gps_vel {
            let dt = now_us.saturating_sub(t0) as f32 * 1e-6;
            if dt > 0.05 && dt < 1.0 {
                let k = (dt / 0.5).min(1.0);
                for i in 0..3 {
                    let a = (vel_ned_mps[i] - v0[i]) / dt;
                    self.gps_accel_ned_mps2[i] += k * (a - self.gps_accel_ned_mps2[i]);
                }
            }
        }
        self.last_gps_vel = Some((now_us, vel_ned_mps));
    }

    /// A fix relative to home (NED, m): its innovation recorded; fused (position, and the
    /// velocity when finite) with the receiver latency unless it jumped away from the estimate.
    #[inline]
    fn fuse_gps_ned(
        &mut self,
        now_us: u64,
        ned_m: [f64; 3],
        vel_ned_mps: [f32; 3],
        innov: &mut Innovations,
    ) {
        let delay_steps = (self.params.gps_latency_s / 0.002 + 0.5) as usize;
        let p = self.horiz.pos_ne_m();
        let d = fcc_nav::math::hypotf(ned_m[0] as f32 - p[0], ned_m[1] as f32 - p[1]);
        innov.gps_m = Some(d);
        self.last_gps_us = Some(now_us);
        if !NavHealth::gps_acceptable(d) {
            // A jump (multipath, spoofing): not fused; the monitor times it.
            self.horiz.clear_gps();
        } else {
            self.horiz
                .gps([ned_m[0] as f32, ned_m[1] as f32], delay_steps);
            if vel_ned_mps.iter().all(|v| v.is_finite()) {
                self.horiz.gps_velocity(
                    [vel_ned_mps[0], vel_ned_mps[1]],
                    delay_steps,
                    self.params.gps_vel_gain,
                );
            }
        }
    }

    /// GPS fused within `gps_timeout_s` and the horizontal filter not faulted.
    #[inline]
    fn gps_fresh_and_healthy(&self, now_us: u64, faults: u8) -> bool {
        (match self.last_gps_us {
            Some(t) => now_us.saturating_sub(t) as f32 * 1e-6 < self.params.gps_timeout_s,
            None => false,
        }) && faults & crate::nav_health::FAULT_HORIZONTAL == 0
    }

    /// Ground altitude (paper B): predict with the vertical velocity, fuse the rangefinders.
    #[inline]
    fn update_ground(&mut self, imu_dt_s: f32, s: &SensorInputs) {
        let e = self.state.euler;
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

    /// Copy the filters' outputs and the flags into the published state.
    #[inline]
    fn publish_state(&mut self, now_us: u64, gps_ok: bool, faults: u8) -> &NavState {
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
            let yaw = match self.last_mag_frd {
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
