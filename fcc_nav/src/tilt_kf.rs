//! GPS-velocity tilt filter: roll/pitch and their rate biases corrected from the GPS Doppler
//! velocity's innovation against an inertial velocity, with the steady-state Kalman gains of
//! the error model below (one per horizontal axis).
//!
//! ```text
//!   states   v (m/s, inertial velocity error), d (rad, the tilt error: v̇ = g·d), b (rad/s, ḋ = b)
//!   noise    accelerometer 300 µg/√Hz, gyro 0.01 °/s/√Hz, gyro bias random walk
//!            0.003 °/s/√s (MPU-9250 as simulated); GPS velocity 0.05 m/s at 5 Hz (u-blox M8)
//!   per fix  y = v_gps − v̂(t − L)            (innovation against the latency-delayed velocity)
//!            v̂ += K_V·y,   d̂ = K_D·y,   ḃ-correction = K_B·y
//! ```
//!
//! The gains are the steady state of the discrete Riccati recursion at the 0.2-s fix period
//! (`scripts/gps_loss_bound.py` computes them and the velocity error they leave after a GPS
//! loss). An attitude error δ (estimate = (I + [δ×])·truth, NED) makes the inertial
//! acceleration wrong by `(−g·δ_E, g·δ_N)`, so the north axis's `d` is `−δ_E` and the east
//! axis's is `δ_N`; the corrections are turned into roll/pitch (and their rate biases) with
//! the heading:
//!
//! ```text
//!   roll = δ_N·cos ψ + δ_E·sin ψ,   pitch = −δ_N·sin ψ + δ_E·cos ψ
//! ```
//!
//! It replaced a tilt aid that took the velocity *change* over one fix interval as a tilt
//! measurement (±2° of noise per fix from the 0.05 m/s velocities) through the attitude
//! filter's fixed 10-s crossover: the gyro bias's random walk lagged by ≈ 20 s there (a
//! GPS-lost landing of the campaign dead-reckoned on a 0.04 °/s bias error, 5σ of this
//! filter's), and a GPS loss dead-reckons on what the tilt and its rate are at that moment.
//! The gains hold for fixes every 0.2 s (5 Hz); for another rate, recompute them with the
//! script's `DT`.

use crate::math::sincosf;

/// Steps of the inertial velocity kept for the latency (0.254 s at 500 Hz).
pub const HIST: usize = 128;
/// Velocity gain per fix.
pub const K_VEL: f32 = 0.117_239;
/// Tilt correction per fix, rad per m/s of innovation.
pub const K_TILT_RAD_PER_MPS: f32 = 0.003_559_77;
/// Tilt-rate (gyro bias) correction per fix, rad/s per m/s of innovation.
pub const K_BIAS_RADPS_PER_MPS: f32 = 0.000_440_013;
/// Innovations larger than this (m/s) are not used (a GPS velocity glitch, or the filter just
/// started): the velocity is re-aligned to the GPS instead.
pub const REALIGN_MPS: f32 = 2.0;

/// Roll/pitch corrections to subtract (estimate minus truth), and to subtract from their rate
/// (the rate-bias estimates).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct TiltCorrection {
    /// Roll error \[rad].
    pub roll_rad: f32,
    /// Pitch error \[rad].
    pub pitch_rad: f32,
    /// Roll-rate error \[rad/s].
    pub roll_rate_radps: f32,
    /// Pitch-rate error \[rad/s].
    pub pitch_rate_radps: f32,
}

/// See the module documentation.
#[derive(Clone, Debug)]
pub struct GpsTiltKf {
    /// The accelerometer's integral (N, E), uncorrected; the filter's velocity is it plus
    /// `offset_ne_mps` (every correction moves the whole history alike).
    vel_ne_mps: [f32; 2],
    offset_ne_mps: [f32; 2],
    hist: [[f32; 2]; HIST],
    head: usize,
    filled: usize,
    aligned: bool,
}

impl Default for GpsTiltKf {
    fn default() -> Self {
        Self::new()
    }
}

impl GpsTiltKf {
    /// Not yet aligned: the first GPS velocity sets the inertial one.
    pub const fn new() -> Self {
        Self {
            vel_ne_mps: [0.0; 2],
            offset_ne_mps: [0.0; 2],
            hist: [[0.0; 2]; HIST],
            head: 0,
            filled: 0,
            aligned: false,
        }
    }

    /// One IMU step: integrate the gravity-compensated NED acceleration (N, E) over `dt_s`.
    #[inline]
    pub fn step(&mut self, accel_ne_mps2: [f32; 2], dt_s: f32) {
        self.vel_ne_mps[0] += accel_ne_mps2[0] * dt_s;
        self.vel_ne_mps[1] += accel_ne_mps2[1] * dt_s;
        self.head = (self.head + 1) % HIST;
        self.hist[self.head] = self.vel_ne_mps;
        if self.filled < HIST {
            self.filled += 1;
        }
    }

    /// Forget the alignment (GPS lost): the next GPS velocity re-aligns.
    pub fn reset(&mut self) {
        self.aligned = false;
    }

    /// A GPS velocity (N, E) measured `delay_steps` IMU steps ago; `yaw_rad` the heading.
    /// Returns the tilt correction, or `None` while (re-)aligning.
    pub fn gps_velocity(
        &mut self,
        vel_ne_mps: [f32; 2],
        delay_steps: usize,
        yaw_rad: f32,
    ) -> Option<TiltCorrection> {
        if delay_steps >= HIST || delay_steps >= self.filled {
            return None;
        }
        let then = self.hist[(self.head + HIST - delay_steps) % HIST];
        let y = [0, 1].map(|i| vel_ne_mps[i] - (then[i] + self.offset_ne_mps[i]));
        if !(y[0].is_finite() && y[1].is_finite()) {
            return None;
        }
        let realign = !self.aligned || crate::math::hypotf(y[0], y[1]) > REALIGN_MPS;
        let k = if realign { 1.0 } else { K_VEL };
        self.offset_ne_mps[0] += k * y[0];
        self.offset_ne_mps[1] += k * y[1];
        if realign {
            self.aligned = true;
            return None;
        }
        // North axis: d = −δ_E; east axis: d = δ_N.
        let d_e = K_TILT_RAD_PER_MPS * y[0];
        let d_n = -K_TILT_RAD_PER_MPS * y[1];
        let r_e = K_BIAS_RADPS_PER_MPS * y[0];
        let r_n = -K_BIAS_RADPS_PER_MPS * y[1];
        let (s, c) = sincosf(yaw_rad);
        Some(TiltCorrection {
            roll_rad: d_n * c + d_e * s,
            pitch_rad: -d_n * s + d_e * c,
            roll_rate_radps: r_n * c + r_e * s,
            pitch_rate_radps: -r_n * s + r_e * c,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{linear_accel_ned_mps2, AttitudeEstimator, Euler};
    use crate::complementary::CfGains;
    use crate::GRAVITY_MPS2;

    const DT: f32 = 0.002;
    const DELAY: usize = 60;

    /// A level vehicle at rest headed 40°, its attitude estimate started 1° off in roll and
    /// −0.5° in pitch, the gyro reading a roll and pitch rate bias of 0.05 and −0.03 °/s the
    /// estimator does not know; only the filter corrects the tilt (no accelerometer tilt).
    /// Returns the roll and pitch errors (deg) and their rates' errors (deg/s) at the end.
    fn fly(corrected: bool, seconds: f32) -> [f32; 4] {
        let yaw = 40f32.to_radians();
        let mut att = AttitudeEstimator::new(CfGains::new(0.1, 0.5), CfGains::new(0.1, 1.0), 0.0);
        att.accel_tilt = false;
        att.reset(Euler {
            roll_rad: 1f32.to_radians(),
            pitch_rad: -0.5f32.to_radians(),
            yaw_rad: yaw,
        });
        let bias = [0.05f32.to_radians(), -0.03f32.to_radians(), 0.0];
        let f_level = [0.0, 0.0, -GRAVITY_MPS2];
        let mut kf = GpsTiltKf::new();
        let steps = (seconds / DT) as usize;
        for i in 0..steps {
            let e = att.update(bias, Some(f_level), None, DT);
            let a = linear_accel_ned_mps2(&e, f_level);
            kf.step([a[0], a[1]], DT);
            if i % 100 == 99 {
                if let Some(c) = kf.gps_velocity([0.0, 0.0], DELAY, att.euler().yaw_rad) {
                    if corrected {
                        att.apply_tilt_correction(&c);
                    }
                }
            }
        }
        let e = att.euler();
        let rb = att.rate_bias_radps();
        [
            e.roll_rad.to_degrees(),
            e.pitch_rad.to_degrees(),
            (bias[0] + rb[0]).to_degrees(),
            (bias[1] + rb[1]).to_degrees(),
        ]
    }

    #[test]
    fn gps_velocities_remove_a_tilt_error_and_a_gyro_bias() {
        let [r, p, rr, pr] = fly(true, 120.0);
        assert!(
            r.abs() < 0.02 && p.abs() < 0.02,
            "tilt error {r:.4}° {p:.4}°"
        );
        assert!(
            rr.abs() < 0.002 && pr.abs() < 0.002,
            "rate error {rr:.5} {pr:.5} °/s"
        );
        // Without the corrections the bias integrates: 0.05 °/s for 120 s.
        let [r0, _, _, _] = fly(false, 120.0);
        assert!(r0 > 6.0, "uncorrected roll error {r0:.2}°");
    }

    #[test]
    fn a_velocity_glitch_realigns_instead_of_tilting() {
        let mut kf = GpsTiltKf::new();
        for _ in 0..200 {
            kf.step([0.0, 0.0], DT);
        }
        assert_eq!(
            kf.gps_velocity([0.0, 0.0], DELAY, 0.0),
            None,
            "first fix aligns"
        );
        assert!(kf.gps_velocity([0.1, 0.0], DELAY, 0.0).is_some());
        assert_eq!(
            kf.gps_velocity([5.0, 0.0], DELAY, 0.0),
            None,
            "a 5 m/s jump realigns"
        );
        let c = kf.gps_velocity([5.0, 0.0], DELAY, 0.0).unwrap();
        assert!(c.pitch_rad.abs() < 1e-6 && c.roll_rad.abs() < 1e-6);
    }
}
