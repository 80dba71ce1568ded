//! Octorotor (X) motor mixing with saturation handling that keeps attitude authority.
//!
//! Allocation: the symmetric layout of [`crate::geometry`] makes the pseudo-inverse closed-form:
//! `T_i = F/8 − L·y_i/Σy² + M·x_i/Σx² − N·s_i/(8·c_q)`. Saturation priority:
//! roll/pitch first (scaled down only if they alone exceed the motor range), then collective
//! thrust is shifted to fit them, then yaw gets whatever headroom remains.
//! Thrust → ESC command: command ∝ rotor speed and thrust ∝ speed², so `cmd = √(T/T_max)`.

use crate::geometry::{motor_position_m, spin_cw, MOTOR_COUNT};

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MixerSaturation {
    /// Roll/pitch torques had to be scaled down (0 < scale < 1).
    pub attitude_scaled: bool,
    /// Collective thrust was moved: +1 it was lowered (hit the top), −1 raised (hit the bottom).
    pub thrust_shift_sign: f32,
    /// Fraction of the yaw torque that could be applied.
    pub yaw_scale: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mixer {
    pos_m: [(f32, f32); MOTOR_COUNT],
    sum_x2: f32,
    sum_y2: f32,
    torque_to_thrust_m: f32,
    pub max_thrust_n: f32,
    /// Lowest thrust a spinning motor gives (idle), N.
    pub min_thrust_n: f32,
}

impl Mixer {
    pub fn new(arm_m: f32, torque_to_thrust_m: f32, max_thrust_n: f32, idle_cmd: f32) -> Self {
        let mut pos_m = [(0.0, 0.0); MOTOR_COUNT];
        let (mut sx, mut sy) = (0.0, 0.0);
        for (i, p) in pos_m.iter_mut().enumerate() {
            *p = motor_position_m(i, arm_m);
            sx += p.0 * p.0;
            sy += p.1 * p.1;
        }
        Self {
            pos_m,
            sum_x2: sx,
            sum_y2: sy,
            torque_to_thrust_m,
            max_thrust_n,
            min_thrust_n: max_thrust_n * idle_cmd * idle_cmd,
        }
    }

    /// Per-motor thrusts (N) for a collective thrust (N) and body torques (N·m).
    pub fn mix_thrust(
        &self,
        thrust_n: f32,
        torque_nm: [f32; 3],
    ) -> ([f32; MOTOR_COUNT], MixerSaturation) {
        let n = MOTOR_COUNT as f32;
        let (lo, hi) = (self.min_thrust_n, self.max_thrust_n);
        let mut att = [0.0f32; MOTOR_COUNT];
        let mut yaw = [0.0f32; MOTOR_COUNT];
        for i in 0..MOTOR_COUNT {
            let (x, y) = self.pos_m[i];
            att[i] = -torque_nm[0] * y / self.sum_y2 + torque_nm[1] * x / self.sum_x2;
            yaw[i] = -torque_nm[2] * spin_cw(i) / (n * self.torque_to_thrust_m);
        }
        let mut sat = MixerSaturation {
            yaw_scale: 1.0,
            ..Default::default()
        };
        // 1. Roll/pitch alone must fit in the range.
        let (amin, amax) = min_max(&att);
        let spread = amax - amin;
        if spread > hi - lo {
            let s = (hi - lo) / spread;
            att.iter_mut().for_each(|a| *a *= s);
            sat.attitude_scaled = true;
        }
        let (amin, amax) = min_max(&att);
        // 2. Shift collective to fit roll/pitch.
        let mut c = thrust_n / n;
        if c + amax > hi {
            c = hi - amax;
            sat.thrust_shift_sign = 1.0;
        }
        if c + amin < lo {
            c = lo - amin;
            sat.thrust_shift_sign = -1.0;
        }
        // 3. Yaw gets the remaining headroom.
        let mut k = 1.0f32;
        for i in 0..MOTOR_COUNT {
            let base = c + att[i];
            if yaw[i] > 0.0 && base + yaw[i] > hi {
                k = k.min(((hi - base) / yaw[i]).max(0.0));
            } else if yaw[i] < 0.0 && base + yaw[i] < lo {
                k = k.min(((lo - base) / yaw[i]).max(0.0));
            }
        }
        sat.yaw_scale = k;
        let mut t = [0.0f32; MOTOR_COUNT];
        for i in 0..MOTOR_COUNT {
            t[i] = fcc_nav::math::clampf(c + att[i] + k * yaw[i], lo, hi);
        }
        (t, sat)
    }

    /// ESC commands (0..1) for a collective thrust and torques.
    pub fn mix(&self, thrust_n: f32, torque_nm: [f32; 3]) -> ([f32; MOTOR_COUNT], MixerSaturation) {
        let (t, sat) = self.mix_thrust(thrust_n, torque_nm);
        let mut cmd = [0.0f32; MOTOR_COUNT];
        for i in 0..MOTOR_COUNT {
            cmd[i] = fcc_nav::math::sqrtf((t[i] / self.max_thrust_n).max(0.0)).min(1.0);
        }
        (cmd, sat)
    }

    /// Forward model: collective thrust and torques produced by per-motor thrusts.
    pub fn wrench(&self, t: &[f32; MOTOR_COUNT]) -> (f32, [f32; 3]) {
        let mut f = 0.0;
        let mut tau = [0.0f32; 3];
        #[allow(clippy::needless_range_loop)] // i is also the motor's number for spin_cw
        for i in 0..MOTOR_COUNT {
            let (x, y) = self.pos_m[i];
            f += t[i];
            tau[0] += -y * t[i];
            tau[1] += x * t[i];
            tau[2] += -spin_cw(i) * self.torque_to_thrust_m * t[i];
        }
        (f, tau)
    }
}

fn min_max(v: &[f32; MOTOR_COUNT]) -> (f32, f32) {
    v.iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), &x| (lo.min(x), hi.max(x)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mixer() -> Mixer {
        Mixer::new(0.525, 0.016, 12.0, 0.1)
    }

    #[test]
    fn unsaturated_mix_reproduces_the_wrench() {
        let m = mixer();
        let (t, sat) = m.mix_thrust(44.0, [0.8, -0.5, 0.05]);
        let (f, tau) = m.wrench(&t);
        assert!((f - 44.0).abs() < 1e-3);
        for (a, b) in tau.iter().zip([0.8, -0.5, 0.05]) {
            assert!((a - b).abs() < 1e-4, "{tau:?}");
        }
        assert_eq!(sat.yaw_scale, 1.0);
        assert!(!sat.attitude_scaled);
    }

    #[test]
    fn positive_roll_torque_lowers_right_motors() {
        let m = mixer();
        let (t, _) = m.mix_thrust(44.0, [1.0, 0.0, 0.0]);
        for (i, t_i) in t.iter().enumerate() {
            let (_, y) = motor_position_m(i, 0.525);
            assert_eq!(y > 0.0, *t_i < 44.0 / 8.0, "motor {i}");
        }
    }

    #[test]
    fn yaw_gives_way_before_roll_pitch_at_full_thrust() {
        let m = mixer();
        let (t, sat) = m.mix_thrust(94.0, [1.5, 0.0, 1.0]);
        let (_, tau) = m.wrench(&t);
        assert!((tau[0] - 1.5).abs() < 1e-3, "roll kept: {tau:?}");
        assert!(sat.yaw_scale < 1.0);
        assert_eq!(sat.thrust_shift_sign, 1.0);
        assert!(t.iter().all(|&x| x <= 12.0 + 1e-6));
    }

    #[test]
    fn impossible_roll_is_scaled_not_clipped_per_motor() {
        let m = mixer();
        let (t, sat) = m.mix_thrust(44.0, [100.0, 50.0, 0.0]);
        let (_, tau) = m.wrench(&t);
        assert!(sat.attitude_scaled);
        // Direction of the torque preserved.
        assert!((tau[0] / tau[1] - 2.0).abs() < 1e-3, "{tau:?}");
    }

    #[test]
    fn command_is_sqrt_of_thrust_fraction() {
        let m = mixer();
        let (c, _) = m.mix(8.0 * 3.0, [0.0; 3]);
        assert!((c[0] - (3.0f32 / 12.0).sqrt()).abs() < 1e-5);
    }
}
