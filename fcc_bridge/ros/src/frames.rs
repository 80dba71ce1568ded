//! Every frame conversion between the link (NED / FRD, as in the firmware) and ROS (ENU / FLU,
//! REP-103 / REP-105) lives here, and only here.
//!
//! - Navigation frame: NED (x north, y east, z down) ↔ ENU (x east, y north, z up):
//!   `v_enu = [v_e, v_n, −v_d]`, an involution (the same map both ways).
//! - Body frame: FRD (x forward, y right, z down) ↔ FLU (x forward, y left, z up):
//!   `v_flu = [x, −y, −z]`, also an involution (180° about x).
//! - Attitude: the link's `q_body_to_ned` rotates FRD vectors into NED. ROS wants the rotation
//!   of FLU vectors into ENU: `q_enu_flu = q_ned_to_enu ⊗ q_frd_to_ned ⊗ q_flu_to_frd` with
//!   `q_flu_to_frd` = 180° about x and `q_ned_to_enu` = 180° about (x+y)/√2.
//! - Heading: NED yaw (from north towards east) ψ ↔ ENU yaw (from east towards north) π/2 − ψ.
//!   An ENU orientation's yaw (REP-103: 0 = facing east, counter-clockwise seen from above) is
//!   its ZYX Euler yaw ([`yaw_enu_of_q_enu`]).
//! - Yaw rate: FLU/ENU z-up rate (counter-clockwise seen from above, `twist.angular.z`) ↔ NED
//!   yaw rate (clockwise seen from above): `r_ned = −ω_z` ([`yaw_rate_enu_to_ned`]).
//!
//! Quaternions are `[w, x, y, z]`, Hamilton convention, f64.
//!
//! The TF tree (REP-105): `map → odom → base_link → sensor frames`.
//! - `map`: ENU, origin = the MCU's home (its GPS reference); world-fixed quantities
//!   (`accel/*`, `altitude`) are in it.
//! - `odom`: the frame of `state/odom` (`nav_msgs/Odometry`, child `base_link`) and the parent
//!   of `base_link` on `/tf`. `map → odom` is the identity, published once on `/tf_static`:
//!   the MCU runs one estimator, GPS-referenced, so there is no separate dead-reckoned
//!   estimate drifting away from `map` that a `map → odom` correction would absorb. `odom` is as
//!   continuous as that estimate: `fcc_nav::horizontal`'s complementary filter low-passes GPS
//!   (it moves smoothly towards each fix rather than jumping to it); only an estimator reset
//!   (start-up, a fault) moves it at once.
//! - `base_link`: FLU body; the sensor frames hang under it on `/tf_static`.

use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2};

pub type Vec3 = [f64; 3];
/// `[w, x, y, z]`.
pub type Quat = [f64; 4];

/// 180° about x: FLU → FRD (and FRD → FLU).
pub const Q_FLU_TO_FRD: Quat = [0.0, 1.0, 0.0, 0.0];
/// 180° about (1, 1, 0)/√2: NED → ENU (and ENU → NED).
pub const Q_NED_TO_ENU: Quat = [0.0, FRAC_1_SQRT_2, FRAC_1_SQRT_2, 0.0];

/// NED vector → ENU.
pub fn ned_to_enu(v: Vec3) -> Vec3 {
    [v[1], v[0], -v[2]]
}

/// ENU vector → NED.
pub fn enu_to_ned(v: Vec3) -> Vec3 {
    [v[1], v[0], -v[2]]
}

/// Horizontal NED vector (north, east) → ENU with z = 0.
pub fn ne_to_enu(v: [f64; 2]) -> Vec3 {
    [v[1], v[0], 0.0]
}

/// Body FRD vector → FLU.
pub fn frd_to_flu(v: Vec3) -> Vec3 {
    [v[0], -v[1], -v[2]]
}

/// Body FLU vector → FRD.
pub fn flu_to_frd(v: Vec3) -> Vec3 {
    [v[0], -v[1], -v[2]]
}

/// f32 triple → f64.
pub fn f64x3(v: [f32; 3]) -> Vec3 {
    [v[0] as f64, v[1] as f64, v[2] as f64]
}

/// Hamilton product `a ⊗ b`.
pub fn quat_mul(a: Quat, b: Quat) -> Quat {
    let [aw, ax, ay, az] = a;
    let [bw, bx, by, bz] = b;
    [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]
}

pub fn quat_conj(q: Quat) -> Quat {
    [q[0], -q[1], -q[2], -q[3]]
}

/// Unit quaternion (identity if the norm is 0 or not finite).
pub fn quat_normalize(q: Quat) -> Quat {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if !n.is_finite() || n < 1e-12 {
        return [1.0, 0.0, 0.0, 0.0];
    }
    let q = [q[0] / n, q[1] / n, q[2] / n, q[3] / n];
    // Canonical sign (w ≥ 0) so outputs are comparable.
    if q[0] < 0.0 {
        [-q[0], -q[1], -q[2], -q[3]]
    } else {
        q
    }
}

/// Rotate `v` by `q`: `q ⊗ (0, v) ⊗ q*`.
pub fn quat_rotate(q: Quat, v: Vec3) -> Vec3 {
    let p = quat_mul(quat_mul(q, [0.0, v[0], v[1], v[2]]), quat_conj(q));
    [p[1], p[2], p[3]]
}

/// The link's attitude (FRD → NED) as the ROS attitude (FLU → ENU).
pub fn q_frd_ned_to_q_flu_enu(q_frd_to_ned: Quat) -> Quat {
    let q = quat_normalize(q_frd_to_ned);
    quat_normalize(quat_mul(quat_mul(Q_NED_TO_ENU, q), Q_FLU_TO_FRD))
}

/// ROS attitude (FLU → ENU) as the link's (FRD → NED).
pub fn q_flu_enu_to_q_frd_ned(q_flu_to_enu: Quat) -> Quat {
    let q = quat_normalize(q_flu_to_enu);
    quat_normalize(quat_mul(quat_mul(Q_NED_TO_ENU, q), Q_FLU_TO_FRD))
}

/// Link quaternion `[w, x, y, z]` f32 → f64.
pub fn quat_f64(q: [f32; 4]) -> Quat {
    [q[0] as f64, q[1] as f64, q[2] as f64, q[3] as f64]
}

/// NED yaw (ZYX Euler ψ, from north towards east) of an FRD → NED attitude.
pub fn yaw_ned(q_frd_to_ned: Quat) -> f64 {
    let [w, x, y, z] = quat_normalize(q_frd_to_ned);
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// NED yaw → ENU yaw (from east towards north), wrapped to (−π, π].
pub fn yaw_ned_to_enu(yaw_ned: f64) -> f64 {
    wrap_pi(FRAC_PI_2 - yaw_ned)
}

/// ENU yaw → NED yaw, wrapped to (−π, π].
pub fn yaw_enu_to_ned(yaw_enu: f64) -> f64 {
    wrap_pi(FRAC_PI_2 - yaw_enu)
}

/// Yaw (ZYX Euler ψ about z-up, from east towards north) of an orientation in ENU, `[w, x, y, z]`
/// (normalised first).
pub fn yaw_enu_of_q_enu(q_enu: Quat) -> f64 {
    let [w, x, y, z] = quat_normalize(q_enu);
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// The orientation in ENU of a level vehicle with ENU yaw `yaw_enu` (a rotation about z),
/// `[w, x, y, z]`: what a heading is sent as (`setpoint/heading`).
pub fn q_enu_of_yaw_enu(yaw_enu: f64) -> Quat {
    let (s, c) = (0.5 * yaw_enu).sin_cos();
    [c, 0.0, 0.0, s]
}

/// A z-up yaw rate (FLU body or ENU, counter-clockwise seen from above, `twist.angular.z`) →
/// NED yaw rate (clockwise seen from above), rad/s.
pub fn yaw_rate_enu_to_ned(yaw_rate_z_up_radps: f64) -> f64 {
    -yaw_rate_z_up_radps
}

/// Wrap to (−π, π]: the one f64 copy, in `fcc_nav`.
pub use fcc_nav::complementary::wrap_pi_f64 as wrap_pi;

/// A velocity in the vehicle's body FLU frame, levelled (rotated by the heading only), → NED.
/// Used for `base_link` velocity setpoints: the tilt of the airframe does not leak into the
/// vertical speed.
pub fn flu_heading_to_ned(v_flu: Vec3, yaw_ned: f64) -> Vec3 {
    let [f, r, d] = flu_to_frd(v_flu);
    let (s, c) = yaw_ned.sin_cos();
    [c * f - s * r, s * f + c * r, d]
}

/// NED world vector → body FRD for an FRD → NED attitude.
pub fn ned_to_body_frd(q_frd_to_ned: Quat, v_ned: Vec3) -> Vec3 {
    quat_rotate(quat_conj(quat_normalize(q_frd_to_ned)), v_ned)
}

/// Upper-triangle-free 3×3 covariance: a diagonal one.
pub fn diag3(v: f64) -> [f64; 9] {
    [v, 0.0, 0.0, 0.0, v, 0.0, 0.0, 0.0, v]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const EPS: f64 = 1e-9;

    fn close(a: &[f64], b: &[f64], eps: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < eps)
    }

    /// ZYX Euler → FRD→NED quaternion (same formula as `fcc_nav::attitude::quat_from_euler`).
    fn euler_ned(roll: f64, pitch: f64, yaw: f64) -> Quat {
        let (sr, cr) = (0.5 * roll).sin_cos();
        let (sp, cp) = (0.5 * pitch).sin_cos();
        let (sy, cy) = (0.5 * yaw).sin_cos();
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    }

    #[test]
    fn vectors() {
        // North 1, east 2, down 3 → east 2, north 1, up −3.
        assert_eq!(ned_to_enu([1.0, 2.0, 3.0]), [2.0, 1.0, -3.0]);
        assert_eq!(enu_to_ned(ned_to_enu([1.0, 2.0, 3.0])), [1.0, 2.0, 3.0]);
        // Forward 1, right 2, down 3 → forward 1, left −2, up −3.
        assert_eq!(frd_to_flu([1.0, 2.0, 3.0]), [1.0, -2.0, -3.0]);
        // Level at rest: specific force FRD (0, 0, −g) → FLU (0, 0, +g) as ROS expects.
        assert_eq!(frd_to_flu([0.0, 0.0, -9.81]), [0.0, 0.0, 9.81]);
        assert_eq!(flu_to_frd(frd_to_flu([4.0, 5.0, 6.0])), [4.0, 5.0, 6.0]);
    }

    #[test]
    fn constant_quaternions_match_the_vector_maps() {
        for v in [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.3, -2.0, 5.0],
        ] {
            assert!(close(&quat_rotate(Q_NED_TO_ENU, v), &ned_to_enu(v), EPS));
            assert!(close(&quat_rotate(Q_FLU_TO_FRD, v), &flu_to_frd(v), EPS));
        }
    }

    #[test]
    fn level_facing_north_is_enu_yaw_90() {
        let q = q_frd_ned_to_q_flu_enu([1.0, 0.0, 0.0, 0.0]);
        let s = FRAC_1_SQRT_2;
        assert!(close(&q, &[s, 0.0, 0.0, s], EPS), "{q:?}");
        // Body forward (FLU x) points north = ENU +y; body left points west = ENU −x.
        assert!(close(
            &quat_rotate(q, [1.0, 0.0, 0.0]),
            &[0.0, 1.0, 0.0],
            EPS
        ));
        assert!(close(
            &quat_rotate(q, [0.0, 1.0, 0.0]),
            &[-1.0, 0.0, 0.0],
            EPS
        ));
        assert!(close(
            &quat_rotate(q, [0.0, 0.0, 1.0]),
            &[0.0, 0.0, 1.0],
            EPS
        ));
    }

    #[test]
    fn facing_east_is_enu_yaw_0() {
        let q = q_frd_ned_to_q_flu_enu(euler_ned(0.0, 0.0, FRAC_PI_2));
        assert!(close(&q, &[1.0, 0.0, 0.0, 0.0], EPS), "{q:?}");
    }

    /// The ROS attitude must rotate every body vector exactly as the link attitude does after
    /// converting both ends: R_enu_flu · v_flu = ned_to_enu(R_ned_frd · flu_to_frd(v_flu)).
    #[test]
    fn attitude_consistent_with_vector_maps() {
        for &(r, p, y) in &[
            (0.0, 0.0, 0.0),
            (0.3, -0.2, 1.0),
            (-0.5, 0.4, -2.5),
            (0.1, -0.17, 0.52),
            (1.2, 0.9, 3.0),
        ] {
            let q_ned = euler_ned(r, p, y);
            let q_enu = q_frd_ned_to_q_flu_enu(q_ned);
            for v in [
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.2, -0.7, 1.5],
            ] {
                let a = quat_rotate(q_enu, v);
                let b = ned_to_enu(quat_rotate(q_ned, flu_to_frd(v)));
                assert!(close(&a, &b, 1e-9), "rpy {r} {p} {y}: {a:?} vs {b:?}");
            }
            // Round trip.
            let back = q_flu_enu_to_q_frd_ned(q_enu);
            assert!(close(&back, &quat_normalize(q_ned), 1e-9));
            // Heading.
            let yaw_enu = {
                let [w, x, yy, z] = q_enu;
                (2.0 * (w * z + x * yy)).atan2(1.0 - 2.0 * (yy * yy + z * z))
            };
            assert!((wrap_pi(yaw_enu - yaw_ned_to_enu(y))).abs() < 1e-9);
            assert!((wrap_pi(yaw_ned(q_ned) - y)).abs() < 1e-9);
        }
    }

    /// Flying north, nose down 10°: velocity NED (5, 0, 0) → ENU (0, 5, 0); in the body FLU
    /// frame it is mostly forward with a positive (up) z part, because the body's up axis leans
    /// forward.
    #[test]
    fn flying_north_nose_down() {
        let pitch = -10f64.to_radians();
        let q = euler_ned(0.0, pitch, 0.0);
        let v_ned = [5.0, 0.0, 0.0];
        assert_eq!(ned_to_enu(v_ned), [0.0, 5.0, 0.0]);
        let v_flu = frd_to_flu(ned_to_body_frd(q, v_ned));
        assert!(close(
            &v_flu,
            &[5.0 * pitch.cos(), 0.0, 5.0 * (-pitch).sin()],
            1e-9
        ));
        assert!(v_flu[2] > 0.8);
        // The same through the ROS attitude.
        let q_enu = q_frd_ned_to_q_flu_enu(q);
        let v_flu2 = quat_rotate(quat_conj(q_enu), ned_to_enu(v_ned));
        assert!(close(&v_flu, &v_flu2, 1e-9));
        // Nose down in ENU/FLU is a positive pitch about body y (left): forward tilts to −z.
        let fwd = quat_rotate(q_enu, [1.0, 0.0, 0.0]);
        assert!(fwd[2] < 0.0 && fwd[1] > 0.9);
    }

    #[test]
    fn horizontal_ne_to_enu() {
        // North 1, east 2 → east 2, north 1, no vertical part.
        assert_eq!(ne_to_enu([1.0, 2.0]), [2.0, 1.0, 0.0]);
        // Consistent with the 3-D map of a horizontal vector.
        assert_eq!(ne_to_enu([-0.5, 0.25]), ned_to_enu([-0.5, 0.25, 0.0]));
    }

    #[test]
    fn rates_and_climb() {
        // Yawing clockwise seen from above (NED +r) is ENU/FLU −z.
        assert_eq!(frd_to_flu([0.0, 0.0, 0.5]), [0.0, 0.0, -0.5]);
        // Climbing: NED down −1 → ENU up +1.
        assert_eq!(ned_to_enu([0.0, 0.0, -1.0])[2], 1.0);
    }

    #[test]
    fn yaw_maps() {
        assert!((yaw_ned_to_enu(0.0) - FRAC_PI_2).abs() < EPS); // north
        assert!(yaw_ned_to_enu(FRAC_PI_2).abs() < EPS); // east
        assert!((yaw_ned_to_enu(PI).abs() - FRAC_PI_2).abs() < EPS); // south = −90°
        assert!((yaw_enu_to_ned(yaw_ned_to_enu(2.0)) - 2.0).abs() < EPS);
    }

    #[test]
    fn enu_orientation_yaw_and_rates() {
        // REP-103: yaw 0 faces east = NED 90°; 90° (CCW) faces north = NED 0.
        let about_z = |a: f64| [(0.5 * a).cos(), 0.0, 0.0, (0.5 * a).sin()];
        assert!(yaw_enu_of_q_enu(about_z(0.0)).abs() < EPS);
        assert!((yaw_enu_to_ned(yaw_enu_of_q_enu(about_z(0.0))) - FRAC_PI_2).abs() < EPS);
        assert!(yaw_enu_to_ned(yaw_enu_of_q_enu(about_z(FRAC_PI_2))).abs() < EPS);
        // West (ENU 180°) = NED −90°; a scaled quaternion gives the same yaw.
        let w = about_z(PI).map(|c| 3.0 * c);
        assert!((yaw_enu_to_ned(yaw_enu_of_q_enu(w)) + FRAC_PI_2).abs() < 1e-9);
        // The ENU orientation of a vehicle facing NED ψ has ENU yaw π/2 − ψ.
        for psi in [0.3, -2.0, 3.0] {
            let q = q_frd_ned_to_q_flu_enu(euler_ned(0.1, -0.2, psi));
            assert!((wrap_pi(yaw_enu_to_ned(yaw_enu_of_q_enu(q)) - psi)).abs() < 1e-9);
        }
        for psi in [0.0, 1.0, -3.0] {
            let q = q_enu_of_yaw_enu(yaw_ned_to_enu(psi));
            assert!((wrap_pi(yaw_enu_to_ned(yaw_enu_of_q_enu(q)) - psi)).abs() < 1e-12);
        }
        // Turning left (CCW, angular.z > 0) is a decreasing NED yaw.
        assert_eq!(yaw_rate_enu_to_ned(0.3), -0.3);
        assert_eq!(frd_to_flu([0.0, 0.0, yaw_rate_enu_to_ned(0.3)])[2], 0.3);
    }

    #[test]
    fn body_setpoints_rotate_by_heading() {
        // Forward 1 m/s while heading east (NED yaw 90°) → NED east 1.
        let v = flu_heading_to_ned([1.0, 0.0, 0.0], FRAC_PI_2);
        assert!(close(&v, &[0.0, 1.0, 0.0], EPS));
        // Left 1 m/s while heading north → west = NED y −1. Up 1 → NED down −1.
        let v = flu_heading_to_ned([0.0, 1.0, 1.0], 0.0);
        assert!(close(&v, &[0.0, -1.0, -1.0], EPS));
    }
}
