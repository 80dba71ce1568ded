//! Attitude control: roll/pitch PID with the derivative taken on the gyro rate (the "angular-rate
//! feedback" summed into each channel in paper A Fig. 10), and yaw as P on the heading error →
//! yaw-rate command → feed-forward + PI with forgetting factor (eq. 18). Outputs body torques
//! (N·m, FRD: roll about x, pitch about y, yaw about z).

use super::pi::ForgettingPi;
use fcc_nav::complementary::wrap_pi;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TiltPid {
    pub kp_nm_per_rad: f32,
    pub kd_nm_per_radps: f32,
    pub pi: ForgettingPi,
}

impl TiltPid {
    pub fn new(kp: f32, ki: f32, kd: f32, i_limit_nm: f32) -> Self {
        Self {
            kp_nm_per_rad: kp,
            kd_nm_per_radps: kd,
            pi: ForgettingPi::new(0.0, ki, 1.0, i_limit_nm),
        }
    }

    pub fn reset(&mut self) {
        self.pi.reset();
    }

    /// Torque (N·m) from angle command/estimate (rad) and the body rate about the same axis.
    pub fn update(
        &mut self,
        dt_s: f32,
        angle_cmd_rad: f32,
        angle_rad: f32,
        rate_radps: f32,
        integrate: bool,
    ) -> f32 {
        let e = angle_cmd_rad - angle_rad;
        let i = if integrate {
            self.pi.update(e, dt_s, 0.0)
        } else {
            self.pi.integral_term()
        };
        self.kp_nm_per_rad * e + i - self.kd_nm_per_radps * rate_radps
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct YawController {
    pub heading_p_per_s: f32,
    pub rate_ff_nm_per_radps: f32,
    pub rate_limit_radps: f32,
    pub rate_pi: ForgettingPi,
}

impl YawController {
    pub fn new(
        heading_p: f32,
        ff: f32,
        kp: f32,
        ki: f32,
        forgetting: f32,
        rate_limit_radps: f32,
    ) -> Self {
        Self {
            heading_p_per_s: heading_p,
            rate_ff_nm_per_radps: ff,
            rate_limit_radps,
            rate_pi: ForgettingPi::new(kp, ki, forgetting, 0.5),
        }
    }

    pub fn reset(&mut self) {
        self.rate_pi.reset();
    }

    /// Yaw-rate command (rad/s) from the heading error, wrapped to ±π.
    pub fn rate_cmd_radps(&self, yaw_cmd_rad: f32, yaw_rad: f32) -> f32 {
        fcc_nav::math::clampf(
            self.heading_p_per_s * wrap_pi(yaw_cmd_rad - yaw_rad),
            -self.rate_limit_radps,
            self.rate_limit_radps,
        )
    }

    /// Yaw torque (N·m): `K_ff·r_cmd + Kp·e_r + Ki·I_r`.
    pub fn update(
        &mut self,
        dt_s: f32,
        yaw_cmd_rad: f32,
        yaw_rad: f32,
        yaw_rate_radps: f32,
        saturated_sign: f32,
    ) -> f32 {
        let r_cmd = self.rate_cmd_radps(yaw_cmd_rad, yaw_rad);
        self.rate_ff_nm_per_radps * r_cmd
            + self
                .rate_pi
                .update(r_cmd - yaw_rate_radps, dt_s, saturated_sign)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_takes_the_short_way() {
        assert!(
            (wrap_pi(3.0 * core::f32::consts::PI / 2.0) + core::f32::consts::PI / 2.0).abs() < 1e-5
        );
        let yc = YawController::new(1.0, 0.0, 1.0, 0.0, 1.0, 10.0);
        // From +170° to −170°: turn +20°, not −340°.
        let r = yc.rate_cmd_radps((-170.0f32).to_radians(), 170.0f32.to_radians());
        assert!((r - 20.0f32.to_radians()).abs() < 1e-4, "{r}");
    }

    #[test]
    fn tilt_pid_signs() {
        let mut pid = TiltPid::new(6.0, 0.0, 1.0, 0.5);
        assert!(pid.update(0.002, 0.1, 0.0, 0.0, true) > 0.0);
        assert!(
            pid.update(0.002, 0.0, 0.0, 1.0, true) < 0.0,
            "rate damping opposes motion"
        );
    }

    #[test]
    fn closes_loop_on_rigid_body() {
        let mut pid = TiltPid::new(6.0, 1.0, 1.4, 0.5);
        let (mut th, mut w) = (0.0f32, 0.0f32);
        let inertia = 0.13;
        for _ in 0..2000 {
            let tau = pid.update(0.002, 0.2, th, w, true) + 0.05; // constant disturbance torque
            w += tau / inertia * 0.002;
            th += w * 0.002;
        }
        assert!((th - 0.2).abs() < 0.01, "θ = {th}");
    }
}
