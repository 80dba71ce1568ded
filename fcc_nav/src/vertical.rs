//! Vertical position/velocity (paper A, eqs. 5–6):
//! `ĥ = F_L·h_baro + F_H·(1/s²)·a_z`, `v̂_z = F_L·s·h_baro + F_H·(1/s)·a_z`.
//!
//! Internally a [`PosVelCf`] on the NED **down** axis (position = −altitude), input the
//! gravity-compensated down acceleration (e.g. `linear_accel_ned_mps2(..)[2]`). The public
//! altitude is **up positive**. Baro altitudes are applied with no delay and held between
//! samples (timeout 1 s by default, see `PosVelCf::timeout_s`).

use crate::complementary::{CfGains, PosVelCf};
use crate::math::powf;

/// ISA barometric altitude \[m] above the reference pressure `p0_pa`:
/// `44330.77·(1 − (p/p0)^0.190263)`.
pub fn pressure_to_alt_m(pressure_pa: f32, p0_pa: f32) -> f32 {
    44330.77 * (1.0 - powf(pressure_pa / p0_pa, 0.190263))
}

/// Baro + accelerometer altitude estimator.
#[derive(Clone, Copy, Debug)]
pub struct VerticalEstimator {
    /// Down-axis filter (position = −altitude \[m], velocity = down \[m/s]).
    pub down: PosVelCf<64>,
}

impl VerticalEstimator {
    /// New estimator at altitude 0, at rest.
    pub fn new(g: CfGains) -> Self {
        Self {
            down: PosVelCf::new(g),
        }
    }

    /// Set altitude \[m, up] and vertical speed \[m/s, up].
    pub fn reset(&mut self, alt_m: f32, vel_up_mps: f32) {
        self.down.reset(-alt_m, -vel_up_mps);
    }

    /// New barometric altitude \[m, up], held until the next one.
    pub fn baro_alt(&mut self, alt_m: f32) {
        self.down.set_measurement(-alt_m, 0);
    }

    /// One step with gravity-compensated down acceleration \[m/s²].
    pub fn update(&mut self, accel_down_mps2: f32, dt_s: f32) {
        self.down.update(accel_down_mps2, dt_s);
    }

    /// Altitude estimate \[m, up].
    pub fn alt_m(&self) -> f32 {
        -self.down.pos()
    }

    /// Vertical velocity estimate \[m/s, down positive].
    pub fn vel_down_mps(&self) -> f32 {
        self.down.vel()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Rng;

    const DT: f32 = 0.002;

    #[test]
    fn isa_altitude() {
        assert_eq!(pressure_to_alt_m(101325.0, 101325.0), 0.0);
        // ISA: 1000 m ≈ 89874.6 Pa
        assert!((pressure_to_alt_m(89874.6, 101325.0) - 1000.0).abs() < 1.0);
        // lower pressure ⇒ higher; ~12 Pa per metre near sea level
        let d = pressure_to_alt_m(101313.0, 101325.0);
        assert!(d > 0.9 && d < 1.1, "{d}");
    }

    #[test]
    fn signs_up_vs_down() {
        let mut v = VerticalEstimator::new(CfGains::new(1.0, 0.7));
        v.reset(10.0, 1.0);
        assert_eq!(v.alt_m(), 10.0);
        assert_eq!(v.vel_down_mps(), -1.0);
        // accelerating upwards = negative down acceleration ⇒ altitude rises faster
        for _ in 0..500 {
            v.update(-1.0, DT);
        }
        assert!((v.alt_m() - 11.5).abs() < 1e-3, "{}", v.alt_m());
        assert!((v.vel_down_mps() + 2.0).abs() < 1e-4);
    }

    /// Elevator: 3rd → 6th → 4th → 3rd floor (3 m per floor), baro noise 0.5 m at 50 Hz.
    #[test]
    fn elevator_profile_noise_reduction() {
        let mut rng = Rng::new(5);
        let mut est = VerticalEstimator::new(CfGains::new(0.6, 0.8));
        let floor = 3.0f64;
        let mut alt = 2.0 * floor;
        let mut vel = 0.0f64;
        est.reset(alt as f32, 0.0);
        // legs: (start time, delta floors)
        let legs = [(10.0, 3.0), (40.0, -2.0), (70.0, -1.0)];
        let (mut sq, mut sqb, mut n, mut nb) = (0.0f64, 0.0f64, 0usize, 0usize);
        let steps = (100.0 / DT) as usize;
        for k in 0..steps {
            let t = k as f64 * DT as f64;
            // trapezoid-ish: accelerate 1 m/s² for 1 s, cruise, decelerate for 1 s
            let mut acc = 0.0f64;
            for &(t0, df) in &legs {
                let dist: f64 = df * floor;
                let cruise = dist.abs() - 1.0; // 1 m/s cruise, 0.5 m each for accel/decel
                let s = dist.signum();
                if t >= t0 && t < t0 + 1.0 {
                    acc = s;
                } else if t >= t0 + 1.0 + cruise && t < t0 + 2.0 + cruise {
                    acc = -s;
                }
            }
            if k % 10 == 0 {
                let b = alt as f32 + rng.normal(0.5);
                if t > 5.0 {
                    sqb += (b as f64 - alt).powi(2);
                    nb += 1;
                }
                est.baro_alt(b);
            }
            est.update(-(acc as f32) + rng.normal(0.3), DT);
            alt += vel * DT as f64 + 0.5 * acc * (DT * DT) as f64;
            vel += acc * DT as f64;
            if t > 5.0 {
                sq += (est.alt_m() as f64 - alt).powi(2);
                n += 1;
            }
        }
        assert!((alt - 2.0 * floor).abs() < 1e-6, "back at 3rd floor: {alt}");
        let std_est = (sq / n as f64).sqrt();
        let std_baro = (sqb / nb as f64).sqrt();
        std::println!("elevator: est err std {std_est} m, baro noise std {std_baro} m");
        assert!(std_est < 0.3 * std_baro, "est {std_est} baro {std_baro}");
    }
}
