//! Linear-acceleration controller (paper A eqs. 15–17), one per heading-frame axis.
//!
//! Feed-forward from the fitted model `a = k1·θ − k2·v` solved for the tilt,
//! `θ_ff = (a_cmd + k2·v)/k1`, plus a PI with forgetting factor on `a_cmd − â`, where `â` is the
//! Luenberger observer's estimate (`fcc_nav::observer`). Output `θ_cmd = θ_ff + u_fb` is the tilt
//! that accelerates along +axis (forward: nose down; right: right wing down), radians.

use super::pi::ForgettingPi;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelController {
    pub k1_mps2_per_rad: f32,
    pub k2_per_s: f32,
    pub pi: ForgettingPi,
}

impl AccelController {
    pub fn new(
        k1_mps2_per_rad: f32,
        k2_per_s: f32,
        kp: f32,
        ki: f32,
        forgetting: f32,
        i_limit_rad: f32,
    ) -> Self {
        Self {
            k1_mps2_per_rad,
            k2_per_s,
            pi: ForgettingPi::new(kp, ki, forgetting, i_limit_rad),
        }
    }

    pub fn reset(&mut self) {
        self.pi.reset();
    }

    /// Feed-forward part alone (eq. 15).
    pub fn feed_forward_rad(&self, a_cmd_mps2: f32, vel_mps: f32) -> f32 {
        (a_cmd_mps2 + self.k2_per_s * vel_mps) / self.k1_mps2_per_rad
    }

    /// Tilt command (rad). `saturated_sign` is the side on which the tilt limit clipped last time.
    pub fn update(
        &mut self,
        dt_s: f32,
        a_cmd_mps2: f32,
        a_est_mps2: f32,
        vel_mps: f32,
        saturated_sign: f32,
    ) -> f32 {
        let ff = self.feed_forward_rad(a_cmd_mps2, vel_mps);
        let fb = self
            .pi
            .update(a_cmd_mps2 - a_est_mps2, dt_s, saturated_sign);
        ff + fb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feed_forward_inverts_the_model() {
        let c = AccelController::new(9.81, 0.25, 0.0, 0.0, 1.0, 1.0);
        let th = c.feed_forward_rad(1.0, 2.0);
        // model: a = k1·θ − k2·v
        assert!((9.81 * th - 0.25 * 2.0 - 1.0).abs() < 1e-5);
    }

    #[test]
    fn closes_loop_on_a_plant_with_wrong_model() {
        // True plant: a = 0.8·k1·θ − k2·v − 0.3 (a constant push, e.g. wind); the integral must
        // remove the model error. With λ < 1 a small residual error remains, bounded.
        for (lambda, tol) in [(1.0, 0.01), (0.9995, 0.1)] {
            let mut c = AccelController::new(9.81, 0.25, 0.03, 0.3, lambda, 0.3);
            let (mut v, mut a) = (0.0f32, 0.0f32);
            let dt = 0.002;
            for k in 0..10_000 {
                let a_cmd = if k < 2500 { 0.5 } else { 0.0 };
                let th = c.update(dt, a_cmd, a, v, 0.0);
                a = 0.8 * 9.81 * th - 0.25 * v - 0.3;
                v += a * dt;
            }
            assert!(a.abs() < tol, "λ {lambda}: a = {a}");
        }
    }
}
