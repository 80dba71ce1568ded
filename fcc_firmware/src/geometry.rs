//! Airframe geometry shared by the mixer and the simulator: the paper's octorotor in X layout.
//!
//! Motors are numbered clockwise seen from above, starting front-right. Motor `i` sits at
//! azimuth `22.5° + i·45°` from the body x (forward) axis towards body y (right), at `arm_m`
//! from the centre. Spin directions alternate; motor 0 spins clockwise seen from above.
//!
//! With thrust `T_i` along −z (FRD), motor `i` at `(x_i, y_i)` produces body torques
//! roll `−y_i·T_i`, pitch `x_i·T_i`, yaw `−s_i·c_q·T_i`, where `s_i = +1` for a clockwise rotor
//! (its reaction torque turns the body counter-clockwise, i.e. negative yaw in FRD) and `c_q` is
//! the rotor's torque-to-thrust ratio in metres.

pub const MOTOR_COUNT: usize = 8;

/// Azimuth of motor `i` in radians from body x towards body y.
pub fn motor_azimuth_rad(i: usize) -> f32 {
    (22.5 + 45.0 * i as f32) * core::f32::consts::PI / 180.0
}

/// Body FRD position (x, y) of motor `i`.
pub fn motor_position_m(i: usize, arm_m: f32) -> (f32, f32) {
    let a = motor_azimuth_rad(i);
    let (s, c) = fcc_nav::math::sincosf(a);
    (arm_m * c, arm_m * s)
}

/// +1 for a clockwise rotor (seen from above), −1 for counter-clockwise.
pub fn spin_cw(i: usize) -> f32 {
    if i % 2 == 0 {
        1.0
    } else {
        -1.0
    }
}
