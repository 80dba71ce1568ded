//! Airframe geometry shared by the mixer and the simulator: the paper's octorotor in X layout,
//! and the landing gear's lowest foot when leaning (the touchdown gate and the simulator's truth).
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

/// How much closer to the ground the lowest foot of the landing gear is when the body leans
/// `tilt_rad` than when level, m: the gear turns about the centre of mass, `height_m` above
/// the feet's plane, and the foot at `half_span_m` on the side of the lean comes down by
/// `r·sin φ − h·(1 − cos φ)` (feet taken in every direction: the worst case). Leaning 17°
/// into a gust with paper A's gear (r 0.3 m, h 0.25 m), 7.7 cm.
pub fn foot_drop_m(tilt_rad: f32, half_span_m: f32, height_m: f32) -> f32 {
    let (s, c) = fcc_nav::math::sincosf(tilt_rad.clamp(0.0, core::f32::consts::FRAC_PI_2));
    half_span_m * s - height_m * (1.0 - c)
}

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
    if i.is_multiple_of(2) {
        1.0
    } else {
        -1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_foot_on_the_side_of_the_lean_comes_down() {
        assert_eq!(foot_drop_m(0.0, 0.3, 0.25), 0.0);
        assert!((foot_drop_m(17f32.to_radians(), 0.3, 0.25) - 0.0767).abs() < 1e-3);
        // Negative tilt is the same lean seen the other way: clamped to level.
        assert_eq!(foot_drop_m(-0.1, 0.3, 0.25), 0.0);
        let mut prev = 0.0;
        for deg in 1..45 {
            let d = foot_drop_m((deg as f32).to_radians(), 0.3, 0.25);
            assert!(d > prev, "{deg}°");
            prev = d;
        }
    }
}
