//! Vertical channel: climb-rate PI → vertical acceleration → collective thrust (N).
//!
//! `thrust = m·(g + a_up_cmd) / (cos φ·cos θ)`; the integral absorbs the hover-thrust error
//! (battery sag, mass). Up is positive here; callers convert from NED down.

use super::pi::ForgettingPi;
use fcc_nav::GRAVITY_MPS2;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VerticalController {
    pub mass_kg: f32,
    pub pi: ForgettingPi,
}

impl VerticalController {
    pub fn new(mass_kg: f32, kp: f32, ki: f32, i_limit_mps2: f32) -> Self {
        Self {
            mass_kg,
            pi: ForgettingPi::new(kp, ki, 1.0, i_limit_mps2),
        }
    }

    pub fn reset(&mut self) {
        self.pi.reset();
    }

    /// Total thrust (N) for a climb-rate command. `tilt_cos` = cos φ·cos θ.
    pub fn update(
        &mut self,
        dt_s: f32,
        vz_up_cmd_mps: f32,
        vz_up_mps: f32,
        tilt_cos: f32,
        saturated_sign: f32,
    ) -> f32 {
        let a_up = self
            .pi
            .update(vz_up_cmd_mps - vz_up_mps, dt_s, saturated_sign);
        let c = fcc_nav::math::clampf(tilt_cos, 0.5, 1.0);
        self.mass_kg * (GRAVITY_MPS2 + a_up) / c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hovers_with_matched_rates_and_climbs_on_command() {
        let mut vc = VerticalController::new(4.5, 3.0, 1.0, 3.0);
        let t = vc.update(0.002, 0.0, 0.0, 1.0, 0.0);
        assert!((t - 4.5 * GRAVITY_MPS2).abs() < 1e-3);
        let t = vc.update(0.002, 1.0, 0.0, 1.0, 0.0);
        assert!(t > 4.5 * GRAVITY_MPS2 + 4.5 * 2.9);
        // Tilted: more thrust for the same vertical force.
        let t1 = vc.update(0.002, 0.0, 0.0, 0.9, 0.0);
        let t0 = vc.update(0.002, 0.0, 0.0, 1.0, 0.0);
        assert!(t1 > t0);
    }
}
