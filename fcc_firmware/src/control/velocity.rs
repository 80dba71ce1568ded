//! Horizontal velocity tracking with cross-track compensation (paper A eqs. 7–9, Fig. 11) and the
//! PI velocity controller that turns the compensated command into an acceleration command.
//!
//! Each cycle an expected position advances along the commanded direction `u` at the vehicle's
//! along-track speed, `p_exp ← p_exp + (v·u)·u·Δt`; the part of `p_exp − p` perpendicular to `u`
//! is the cross-track error `e_ct`, and `v_cmd' = v_cmd + K_ct·e_ct`. All vectors are NED north/
//! east, metres and m/s.

use super::pi::ForgettingPi;

/// Below this commanded speed the direction is undefined: no cross-track compensation.
const MIN_TRACK_SPEED_MPS: f32 = 0.05;
/// A change of commanded direction larger than this starts a new track (cos of ~5°).
const NEW_TRACK_COS: f32 = 0.996;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrossTrack {
    pub k_per_s: f32,
    expected_ne_m: Option<[f32; 2]>,
    dir_ne: [f32; 2],
    last_error_m: f32,
}

impl CrossTrack {
    pub const fn new(k_per_s: f32) -> Self {
        Self {
            k_per_s,
            expected_ne_m: None,
            dir_ne: [1.0, 0.0],
            last_error_m: 0.0,
        }
    }

    pub fn reset(&mut self) {
        self.expected_ne_m = None;
        self.last_error_m = 0.0;
    }

    /// Signed cross-track error of the last update (m, positive = vehicle right of track).
    pub fn error_m(&self) -> f32 {
        self.last_error_m
    }

    /// Returns the compensated command `v_cmd + K_ct·e_ct`.
    pub fn update(
        &mut self,
        dt_s: f32,
        v_cmd_ne: [f32; 2],
        pos_ne_m: [f32; 2],
        vel_ne_mps: [f32; 2],
    ) -> [f32; 2] {
        let speed = fcc_nav::math::hypotf(v_cmd_ne[0], v_cmd_ne[1]);
        if speed < MIN_TRACK_SPEED_MPS {
            self.reset();
            return v_cmd_ne;
        }
        let u = [v_cmd_ne[0] / speed, v_cmd_ne[1] / speed];
        let same_track = u[0] * self.dir_ne[0] + u[1] * self.dir_ne[1] > NEW_TRACK_COS;
        let mut p_exp = match self.expected_ne_m {
            Some(p) if same_track => p,
            _ => pos_ne_m,
        };
        self.dir_ne = u;
        // eq. 7: advance the expected position by the along-track component of the velocity.
        let v_along = vel_ne_mps[0] * u[0] + vel_ne_mps[1] * u[1];
        p_exp[0] += v_along * u[0] * dt_s;
        p_exp[1] += v_along * u[1] * dt_s;
        // eq. 8: cross-track error = component of (p_exp − p) perpendicular to u.
        let d = [p_exp[0] - pos_ne_m[0], p_exp[1] - pos_ne_m[1]];
        let along = d[0] * u[0] + d[1] * u[1];
        let e_ct = [d[0] - along * u[0], d[1] - along * u[1]];
        // Keep the expected point abeam of the vehicle so along-track error never builds up.
        p_exp = [pos_ne_m[0] + e_ct[0], pos_ne_m[1] + e_ct[1]];
        self.expected_ne_m = Some(p_exp);
        // Right of track: the track lies to the left, i.e. e_ct points left (−right vector).
        let right = [-u[1], u[0]];
        self.last_error_m = -(e_ct[0] * right[0] + e_ct[1] * right[1]);
        // eq. 9
        [
            v_cmd_ne[0] + self.k_per_s * e_ct[0],
            v_cmd_ne[1] + self.k_per_s * e_ct[1],
        ]
    }
}

/// PI velocity controller per horizontal axis → acceleration command (NED, m/s²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocityController {
    pub pi: [ForgettingPi; 2],
    pub accel_limit_mps2: f32,
}

impl VelocityController {
    pub fn new(kp: f32, ki: f32, i_limit: f32, accel_limit_mps2: f32) -> Self {
        let pi = ForgettingPi::new(kp, ki, 1.0, i_limit);
        Self {
            pi: [pi, pi],
            accel_limit_mps2,
        }
    }

    pub fn reset(&mut self) {
        self.pi[0].reset();
        self.pi[1].reset();
    }

    /// The proportional gain from now on (1/s), the integral kept: LAND's committed descent
    /// flies a stiffer loop than the rest of the flight (`control.vel_p_touchdown_per_s`).
    pub fn set_p(&mut self, kp_per_s: f32) {
        self.pi[0].kp = kp_per_s;
        self.pi[1].kp = kp_per_s;
    }

    /// `saturated`: per axis, the sign in which the downstream tilt limit is active.
    pub fn update(
        &mut self,
        dt_s: f32,
        v_cmd_ne: [f32; 2],
        vel_ne_mps: [f32; 2],
        saturated: [f32; 2],
    ) -> [f32; 2] {
        let mut a = [0.0; 2];
        for i in 0..2 {
            a[i] = self.pi[i].update(v_cmd_ne[i] - vel_ne_mps[i], dt_s, saturated[i]);
        }
        // Limit the magnitude, keeping direction.
        let n = fcc_nav::math::hypotf(a[0], a[1]);
        if n > self.accel_limit_mps2 {
            let s = self.accel_limit_mps2 / n;
            a = [a[0] * s, a[1] * s];
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vehicle_right_of_track_is_pushed_left() {
        // Flying north; the vehicle drifts east (right) of the line it started on.
        let mut ct = CrossTrack::new(1.0);
        let dt = 0.002;
        let mut p = [0.0f32, 0.0];
        ct.update(dt, [3.0, 0.0], p, [3.0, 0.0]);
        for _ in 0..500 {
            p[0] += 3.0 * dt;
            p[1] += 0.5 * dt; // drifting east
            ct.update(dt, [3.0, 0.0], p, [3.0, 0.5]);
        }
        let v = ct.update(dt, [3.0, 0.0], p, [3.0, 0.5]);
        assert!(ct.error_m() > 0.45, "right-of-track error {}", ct.error_m());
        assert!(v[1] < -0.45, "command must push west: {:?}", v);
        assert!(
            (v[0] - 3.0).abs() < 1e-3,
            "along-track command unchanged: {:?}",
            v
        );
    }

    #[test]
    fn on_track_no_correction_and_new_direction_restarts() {
        let mut ct = CrossTrack::new(1.0);
        let mut p = [0.0f32, 0.0];
        for _ in 0..100 {
            p[1] += 3.0 * 0.01;
            let v = ct.update(0.01, [0.0, 3.0], p, [0.0, 3.0]);
            assert!(v[0].abs() < 1e-4);
        }
        // Turning south: starts a new track from where the vehicle is.
        let v = ct.update(0.01, [-3.0, 0.0], [5.0, 5.0], [0.0, 3.0]);
        assert!(v[1].abs() < 1e-4 && ct.error_m().abs() < 1e-4);
    }

    #[test]
    fn velocity_pi_limits_acceleration_magnitude() {
        let mut vc = VelocityController::new(2.0, 0.0, 1.0, 3.0);
        let a = vc.update(0.01, [10.0, 10.0], [0.0, 0.0], [0.0, 0.0]);
        assert!((fcc_nav::math::hypotf(a[0], a[1]) - 3.0).abs() < 1e-4);
        assert!((a[0] - a[1]).abs() < 1e-5);
    }
}
