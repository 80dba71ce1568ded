//! Attitude estimation (paper A, eqs. 2–4) and body→NED rotations.
//!
//! Roll and pitch: accelerometer tilt through `F_L`, integrated Euler-angle rates (from the
//! gyro via the ZYX kinematics) through `F_H`. Yaw: tilt-compensated magnetometer heading plus
//! declination through `F_L`, integrated `ψ̇` through `F_H`. Each angle is an [`AngleCf`], so a
//! constant gyro bias (in Euler-rate space) is estimated and rejected.
//!
//! Frames: body FRD, navigation NED, ZYX Euler angles, `R = Rz(ψ)·Ry(θ)·Rx(φ)` maps body
//! vectors into NED. Specific-force convention: level at rest the accelerometer reads
//! `[0, 0, −g]`; at rest with roll φ and pitch θ it reads `g·(sin θ, −sin φ cos θ, −cos φ cos θ)`.

use crate::complementary::{wrap_pi, AngleCf, CfGains};
use crate::math::fabsf;
use crate::math::{asinf, atan2f, sincosf, sqrtf};
use crate::GRAVITY_MPS2;

/// ZYX Euler angles \[rad].
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Euler {
    /// Roll φ, positive right wing down.
    pub roll_rad: f32,
    /// Pitch θ, positive nose up.
    pub pitch_rad: f32,
    /// Yaw ψ (true heading), positive clockwise from north, in (−π, π].
    pub yaw_rad: f32,
}

/// Roll and pitch `(φ, θ)` \[rad] from a specific-force sample in FRD, assuming no linear
/// acceleration: `θ = asin(f_x/|f|)`, `φ = atan2(−f_y, −f_z)`. Returns `(0, 0)` for `f = 0`.
pub fn accel_tilt_rad(f_frd_mps2: [f32; 3]) -> (f32, f32) {
    let [fx, fy, fz] = f_frd_mps2;
    accel_tilt_norm_rad(f_frd_mps2, sqrtf(fx * fx + fy * fy + fz * fz))
}

/// [`accel_tilt_rad`] with the norm `|f|` already computed.
#[inline]
fn accel_tilt_norm_rad(f_frd_mps2: [f32; 3], norm: f32) -> (f32, f32) {
    let [fx, fy, fz] = f_frd_mps2;
    if norm < 1e-6 {
        return (0.0, 0.0);
    }
    let pitch = asinf(crate::math::clampf(fx / norm, -1.0, 1.0));
    let roll = atan2f(-fy, -fz);
    (roll, pitch)
}

/// Tilt-compensated magnetic heading plus declination → true heading \[rad] in (−π, π].
///
/// `m_frd` in any unit (µT typical). `declination_rad` is east-positive
/// (true = magnetic + declination).
pub fn mag_heading_rad(
    m_frd: [f32; 3],
    roll_rad: f32,
    pitch_rad: f32,
    declination_rad: f32,
) -> f32 {
    let (mx_h, my_h) = mag_horizontal(m_frd, sincosf(roll_rad), sincosf(pitch_rad));
    wrap_pi(atan2f(-my_h, mx_h) + declination_rad)
}

/// The field's horizontal components `(north-ish, east-ish)` in the heading frame, from the
/// `(sin, cos)` of roll and pitch.
#[inline]
fn mag_horizontal(m_frd: [f32; 3], roll: (f32, f32), pitch: (f32, f32)) -> (f32, f32) {
    let [mx, my, mz] = m_frd;
    let ((sp, cp), (st, ct)) = (roll, pitch);
    let mx_h = mx * ct + my * sp * st + mz * cp * st;
    let my_h = my * cp - mz * sp;
    (mx_h, my_h)
}

/// Magnitude \[µT] and dip (inclination, down positive) \[rad] of a body-frame field at the
/// given roll and pitch.
pub fn mag_norm_dip(m_frd: [f32; 3], roll_rad: f32, pitch_rad: f32) -> (f32, f32) {
    let (roll, pitch) = (sincosf(roll_rad), sincosf(pitch_rad));
    mag_norm_dip_h(m_frd, roll, pitch, mag_horizontal(m_frd, roll, pitch))
}

/// [`mag_norm_dip`] from the trigonometry and the horizontal components already computed.
#[inline]
fn mag_norm_dip_h(
    m_frd: [f32; 3],
    roll: (f32, f32),
    pitch: (f32, f32),
    (mx_h, my_h): (f32, f32),
) -> (f32, f32) {
    let [mx, my, mz] = m_frd;
    let ((sp, cp), (st, ct)) = (roll, pitch);
    let mz_v = -mx * st + my * sp * ct + mz * cp * ct;
    let h = sqrtf(mx_h * mx_h + my_h * my_h);
    (sqrtf(h * h + mz_v * mz_v), atan2f(mz_v, h))
}

/// Euler-angle rates `[φ̇, θ̇, ψ̇]` \[rad/s] from body rates `[p, q, r]` \[rad/s] (FRD).
/// `cos θ` is limited to ±1e−3 near ±90° pitch (gimbal lock).
pub fn euler_rates(gyro_frd_radps: [f32; 3], roll_rad: f32, pitch_rad: f32) -> [f32; 3] {
    let (sp, cp) = sincosf(roll_rad);
    let (st, ct) = sincosf(pitch_rad);
    euler_rates_trig(gyro_frd_radps, (sp, cp), (st, ct))
}

/// [`euler_rates`] from the sines and cosines of roll and pitch.
fn euler_rates_trig(gyro_frd_radps: [f32; 3], roll: (f32, f32), pitch: (f32, f32)) -> [f32; 3] {
    let [p, q, r] = gyro_frd_radps;
    let (sp, cp) = roll;
    let (st, mut ct) = pitch;
    const MIN_COS: f32 = 1e-3;
    if ct.abs() < MIN_COS {
        ct = if ct < 0.0 { -MIN_COS } else { MIN_COS };
    }
    let qr = q * sp + r * cp;
    [p + qr * st / ct, q * cp - r * sp, qr / ct]
}

/// Rotation matrix body (FRD) → NED, `R = Rz(ψ)·Ry(θ)·Rx(φ)`, row-major.
pub fn rot_body_to_ned(e: &Euler) -> [[f32; 3]; 3] {
    let roll = sincosf(e.roll_rad);
    let pitch = sincosf(e.pitch_rad);
    rot_trig(roll, pitch, sincosf(e.yaw_rad))
}

/// [`rot_body_to_ned`] from the sines and cosines `(sin, cos)` of roll, pitch and yaw.
fn rot_trig(roll: (f32, f32), pitch: (f32, f32), yaw: (f32, f32)) -> [[f32; 3]; 3] {
    let ((sp, cp), (st, ct), (ss, cs)) = (roll, pitch, yaw);
    [
        [ct * cs, sp * st * cs - cp * ss, cp * st * cs + sp * ss],
        [ct * ss, sp * st * ss + cp * cs, cp * st * ss - sp * cs],
        [-st, sp * ct, cp * ct],
    ]
}

/// Rotate a body (FRD) vector into NED.
pub fn body_to_ned(e: &Euler, v_frd: [f32; 3]) -> [f32; 3] {
    let r = rot_body_to_ned(e);
    let mut out = [0.0; 3];
    for (o, row) in out.iter_mut().zip(r.iter()) {
        *o = row[0] * v_frd[0] + row[1] * v_frd[1] + row[2] * v_frd[2];
    }
    out
}

/// Gravity-compensated linear acceleration in NED \[m/s²]: `R·f + [0, 0, g]` (zero at rest).
pub fn linear_accel_ned_mps2(e: &Euler, f_frd: [f32; 3]) -> [f32; 3] {
    let mut a = body_to_ned(e, f_frd);
    a[2] += GRAVITY_MPS2;
    a
}

/// Quaternion `[w, x, y, z]` rotating body FRD into NED for ZYX Euler angles (yaw, pitch, roll).
pub fn quat_from_euler(roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> [f32; 4] {
    let (sr, cr) = crate::math::sincosf(0.5 * roll_rad);
    let (sp, cp) = crate::math::sincosf(0.5 * pitch_rad);
    let (sy, cy) = crate::math::sincosf(0.5 * yaw_rad);
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

/// Complementary-filter attitude estimator (roll, pitch, yaw).
#[derive(Clone, Copy, Debug)]
pub struct AttitudeEstimator {
    roll: AngleCf,
    pitch: AngleCf,
    yaw: AngleCf,
    /// Magnetic declination \[rad], east positive.
    pub declination_rad: f32,
    /// Accelerometer correction is skipped when `| |f| − g | >` this \[m/s²] (default 2.0).
    pub accel_gate_mps2: f32,
    /// Roll and pitch are corrected from the accelerometer on every this-many steps (default
    /// 5: 100 Hz at 500 Hz), with the gains of the time since the last correction; the gyro
    /// propagates every step. The (low-passed, 5 Hz) specific force carries nothing faster, and
    /// the tilt measurement (norm, asin, atan2, the compensation's rotation) is most of a
    /// step's cost.
    pub tilt_every: u8,
    /// Roll and pitch are corrected from the accelerometer's gravity direction (default true).
    /// False while another tilt measurement corrects them ([`Self::apply_tilt_correction`]): the
    /// compensated specific force is still formed ([`Self::tilt_specific_force_frd_mps2`]),
    /// the tilt read from it (asin, atan2) is not.
    pub accel_tilt: bool,
    tilt_tick: u8,
    tilt_dt_s: f32,
    /// Magnetometer innovation gate \[rad]: a heading that disagrees with the gyro-propagated
    /// yaw by more than this is treated as a magnetic disturbance and not fused (default 10°).
    pub mag_gate_rad: f32,
    /// Field-consistency gates against the reference taken on the ground
    /// ([`Self::set_mag_reference`]): a field whose magnitude differs by more than
    /// `mag_norm_gate_ut` \[µT] or whose dip differs by more than `mag_dip_gate_rad` is
    /// disturbed, whatever heading it gives (defaults 4 µT, 4°).
    pub mag_norm_gate_ut: f32,
    /// See `mag_norm_gate_ut`.
    pub mag_dip_gate_rad: f32,
    /// There is **no timeout** that accepts a disturbed field in flight: while disturbed, the
    /// heading is held on the gyro (a horizontal disturbance can keep the field's magnitude
    /// and dip and still turn its heading by tens of degrees). Only while
    /// `mag_realign_allowed` (the caller: on the ground, disarmed and still) does a field that
    /// matches the reference's magnitude and dip but disagrees with the gyro heading for
    /// `mag_realign_s` \[s] re-align the heading to it (a heading change the gyro missed
    /// before take-off must not lock the magnetometer out; default 10).
    pub mag_realign_s: f32,
    /// See `mag_realign_s` (default false).
    pub mag_realign_allowed: bool,
    mag_ref: Option<(f32, f32)>,
    mag_consistent_s: f32,
    /// The last reading's field matched the reference (magnitude, dip).
    mag_field_ok: bool,
    mag_realigns: u32,
    mag_rejected_s: f32,
    mag_rejects: u32,
    /// The specific force the last tilt correction of [`Self::update_compensated`] read
    /// (compensated).
    tilt_f_frd_mps2: [f32; 3],
    /// `(sin, cos)` of the current roll and pitch when a magnetometer step already computed
    /// them (the next step's propagation reuses them); `None` otherwise.
    trig: Option<((f32, f32), (f32, f32))>,
}

impl AttitudeEstimator {
    /// New estimator: `tilt` gains for roll/pitch, `yaw` gains for heading.
    pub fn new(tilt: CfGains, yaw: CfGains, declination_rad: f32) -> Self {
        Self {
            roll: AngleCf::new(tilt, true),
            pitch: AngleCf::new(tilt, false),
            yaw: AngleCf::new(yaw, true),
            declination_rad,
            accel_gate_mps2: 2.0,
            tilt_every: 5,
            tilt_tick: 0,
            tilt_dt_s: 0.0,
            mag_gate_rad: 10.0 * core::f32::consts::PI / 180.0,
            mag_norm_gate_ut: 4.0,
            mag_dip_gate_rad: 4.0 * core::f32::consts::PI / 180.0,
            mag_realign_s: 10.0,
            mag_realign_allowed: false,
            mag_ref: None,
            mag_consistent_s: 0.0,
            mag_field_ok: true,
            mag_realigns: 0,
            mag_rejected_s: 0.0,
            mag_rejects: 0,
            tilt_f_frd_mps2: [0.0; 3],
            trig: None,
            accel_tilt: true,
        }
    }

    /// Magnetometer readings rejected by the innovation gate so far.
    pub fn mag_rejects(&self) -> u32 {
        self.mag_rejects
    }

    /// Heading re-alignments to a consistent field after `mag_realign_s` of disagreement.
    pub fn mag_realigns(&self) -> u32 {
        self.mag_realigns
    }

    /// Take the undisturbed field's magnitude and dip from a reading at the given attitude
    /// (on the ground, at calibration).
    pub fn set_mag_reference(&mut self, m_frd_ut: [f32; 3], roll_rad: f32, pitch_rad: f32) {
        self.mag_ref = Some(mag_norm_dip(m_frd_ut, roll_rad, pitch_rad));
    }

    /// Seconds the magnetometer has been rejected in a row (0 when fused).
    pub fn mag_disturbed_s(&self) -> f32 {
        self.mag_rejected_s
    }

    /// Whether the magnetometer is currently being rejected (disturbance suspected).
    pub fn mag_disturbed(&self) -> bool {
        self.mag_rejected_s > 0.0
    }

    /// Set the attitude (rate-bias estimates zeroed).
    pub fn reset(&mut self, e: Euler) {
        self.trig = None;
        self.tilt_tick = 0;
        self.tilt_dt_s = 0.0;
        self.roll.reset(e.roll_rad);
        self.pitch.reset(e.pitch_rad);
        self.yaw.reset(e.yaw_rad);
    }

    /// One step: propagate with the gyro, correct roll/pitch with the accelerometer (if given
    /// and within the gate) and yaw with the magnetometer (if given).
    pub fn update(
        &mut self,
        gyro_frd_radps: [f32; 3],
        accel_frd_mps2: Option<[f32; 3]>,
        mag_frd_ut: Option<[f32; 3]>,
        dt_s: f32,
    ) -> Euler {
        let (roll, pitch) = self.roll_pitch_trig();
        let rates = euler_rates_trig(gyro_frd_radps, roll, pitch);
        self.correct(rates, accel_frd_mps2, mag_frd_ut, dt_s)
    }

    /// [`Self::update`] with the vehicle's manoeuvre acceleration `accel_ned_mps2` (NED, e.g.
    /// from differenced GPS velocities) first removed from the specific force `f_frd_mps2`,
    /// rotated into the body with the current estimate, so that it is not read as tilt. The
    /// same result as `update(gyro, Some(f − Rᵀ·a), mag, dt)` with `R` =
    /// [`rot_body_to_ned`] of [`Self::euler`], sharing the roll and pitch trigonometry with the
    /// propagation (and skipping the rotation when `a` is zero).
    pub fn update_compensated(
        &mut self,
        gyro_frd_radps: [f32; 3],
        f_frd_mps2: [f32; 3],
        accel_ned_mps2: [f32; 3],
        mag_frd_ut: Option<[f32; 3]>,
        dt_s: f32,
    ) -> Euler {
        let (roll, pitch) = self.roll_pitch_trig();
        let rates = euler_rates_trig(gyro_frd_radps, roll, pitch);
        let mut f = None;
        if self.tilt_due() {
            let mut fc = f_frd_mps2;
            let a = accel_ned_mps2;
            if a != [0.0; 3] {
                let r = rot_trig(roll, pitch, sincosf(self.yaw.angle_rad()));
                for (i, fi) in fc.iter_mut().enumerate() {
                    *fi -= r[0][i] * a[0] + r[1][i] * a[1] + r[2][i] * a[2];
                }
            }
            self.tilt_f_frd_mps2 = fc;
            f = Some(fc);
        }
        self.correct(rates, f, mag_frd_ut, dt_s)
    }

    /// Whether this step (the next call of `correct`) corrects the tilt.
    #[inline]
    fn tilt_due(&self) -> bool {
        self.tilt_tick.saturating_add(1) >= self.tilt_every
    }

    /// The compensated specific force the last tilt correction used (FRD, m/s²).
    pub fn tilt_specific_force_frd_mps2(&self) -> [f32; 3] {
        self.tilt_f_frd_mps2
    }

    /// `(sin, cos)` of the current roll and pitch (reused from the last magnetometer step).
    #[inline]
    fn roll_pitch_trig(&mut self) -> ((f32, f32), (f32, f32)) {
        match self.trig.take() {
            Some(t) => t,
            None => (
                sincosf(self.roll.angle_rad()),
                sincosf(self.pitch.angle_rad()),
            ),
        }
    }

    /// The correction half of a step, from the Euler rates.
    fn correct(
        &mut self,
        rates: [f32; 3],
        accel_frd_mps2: Option<[f32; 3]>,
        mag_frd_ut: Option<[f32; 3]>,
        dt_s: f32,
    ) -> Euler {
        let mut roll = self.roll.predict(rates[0], dt_s);
        let mut pitch = self.pitch.predict(rates[1], dt_s);
        self.tilt_dt_s += dt_s;
        if self.tilt_due() {
            let f = accel_frd_mps2.filter(|_| self.accel_tilt);
            let tilt = f.and_then(|f| {
                let n = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
                if (n - GRAVITY_MPS2).abs() <= self.accel_gate_mps2 {
                    Some(accel_tilt_norm_rad(f, n))
                } else {
                    None
                }
            });
            if let Some((r, p)) = tilt {
                roll = self.roll.correct(r, self.tilt_dt_s);
                pitch = self.pitch.correct(p, self.tilt_dt_s);
            }
            self.tilt_tick = 0;
            self.tilt_dt_s = 0.0;
        } else {
            self.tilt_tick += 1;
        }
        let mut heading = None;
        if let Some(m) = mag_frd_ut {
            let trig = (sincosf(roll), sincosf(pitch));
            self.trig = Some(trig);
            let horiz = mag_horizontal(m, trig.0, trig.1);
            let h = wrap_pi(atan2f(-horiz.1, horiz.0) + self.declination_rad);
            heading = Some(h);
            let innov = crate::complementary::wrap_pi(h - self.yaw.angle_rad());
            let field_ok = match self.mag_ref {
                None => true,
                Some((n0, d0)) => {
                    let (n, d) = mag_norm_dip_h(m, trig.0, trig.1, horiz);
                    fabsf(n - n0) <= self.mag_norm_gate_ut && fabsf(d - d0) <= self.mag_dip_gate_rad
                }
            };
            if field_ok && fabsf(innov) <= self.mag_gate_rad {
                self.mag_consistent_s = 0.0;
            } else if field_ok
                && self.mag_realign_allowed
                && self.mag_consistent_s >= self.mag_realign_s
            {
                // An Earth-like field disagreeing for that long: the gyro heading was wrong.
                self.yaw.reset(h);
                self.mag_realigns = self.mag_realigns.wrapping_add(1);
                self.mag_consistent_s = 0.0;
            } else {
                heading = None;
                self.mag_rejects = self.mag_rejects.wrapping_add(1);
            }
            self.mag_field_ok = field_ok;
        }
        if mag_frd_ut.is_some() {
            if heading.is_none() {
                self.mag_rejected_s += dt_s;
            } else {
                self.mag_rejected_s = 0.0;
            }
        } else if self.mag_rejected_s > 0.0 {
            self.mag_rejected_s += dt_s;
        }
        // Time (every step, not per reading) the field has looked Earth-like while refused.
        self.mag_consistent_s = if self.mag_rejected_s > 0.0 && self.mag_field_ok {
            self.mag_consistent_s + dt_s
        } else {
            0.0
        };
        self.yaw.update(rates[2], heading, dt_s);
        self.euler()
    }

    /// Remove a tilt error and its rate ([`crate::tilt_kf::GpsTiltKf`]) from roll and pitch
    /// and their rate-bias estimates.
    pub fn apply_tilt_correction(&mut self, c: &crate::tilt_kf::TiltCorrection) {
        self.roll.nudge(-c.roll_rad, -c.roll_rate_radps);
        self.pitch.nudge(-c.pitch_rad, -c.pitch_rate_radps);
        self.trig = None;
    }

    /// Current estimate.
    pub fn euler(&self) -> Euler {
        Euler {
            roll_rad: self.roll.angle_rad(),
            pitch_rad: self.pitch.angle_rad(),
            yaw_rad: self.yaw.angle_rad(),
        }
    }

    /// Euler-rate bias estimates `[φ̇, θ̇, ψ̇]` \[rad/s] (converge to minus the rate bias).
    pub fn rate_bias_radps(&self) -> [f32; 3] {
        [
            self.roll.bias_radps(),
            self.pitch.bias_radps(),
            self.yaw.bias_radps(),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Rng;
    use core::f32::consts::{FRAC_PI_2, PI};

    const G: f32 = GRAVITY_MPS2;
    const DT: f32 = 0.002;
    /// Earth field in NED (Korea-like, µT): north, east, down.
    const M_NED: [f32; 3] = [30.0, 0.0, 40.0];

    fn ned_to_body(e: &Euler, v: [f32; 3]) -> [f32; 3] {
        let r = rot_body_to_ned(e);
        [0, 1, 2].map(|j| r[0][j] * v[0] + r[1][j] * v[1] + r[2][j] * v[2])
    }

    fn accel_at_rest(e: &Euler) -> [f32; 3] {
        ned_to_body(e, [0.0, 0.0, -G])
    }

    fn e(r: f32, p: f32, y: f32) -> Euler {
        Euler {
            roll_rad: r,
            pitch_rad: p,
            yaw_rad: y,
        }
    }

    #[test]
    fn accel_at_rest_matches_documented_formula() {
        let (r, p) = (0.3f32, -0.2f32);
        let f = accel_at_rest(&e(r, p, 1.0));
        let want = [G * p.sin(), -G * r.sin() * p.cos(), -G * r.cos() * p.cos()];
        for i in 0..3 {
            assert!((f[i] - want[i]).abs() < 1e-5);
        }
        let lvl = accel_at_rest(&Euler::default());
        assert!((lvl[2] + G).abs() < 1e-6);
    }

    #[test]
    fn tilt_signs() {
        // nose up ⇒ +pitch: forward axis points up, accel x reads +g sinθ
        let (r, p) = accel_tilt_rad(accel_at_rest(&e(0.0, 0.3, 0.0)));
        assert!((p - 0.3).abs() < 1e-5 && r.abs() < 1e-5);
        // right wing down ⇒ +roll
        let (r, p) = accel_tilt_rad(accel_at_rest(&e(0.4, 0.0, 0.0)));
        assert!((r - 0.4).abs() < 1e-5 && p.abs() < 1e-5);
        // combined; |f| normalisation makes it scale free
        let f = accel_at_rest(&e(-0.5, 0.6, 2.0)).map(|x| 1.3 * x);
        let (r, p) = accel_tilt_rad(f);
        assert!((r + 0.5).abs() < 1e-5 && (p - 0.6).abs() < 1e-5);
        // clamp: no NaN
        let (r, p) = accel_tilt_rad([20.0, 0.0, 0.0]);
        assert!((p - FRAC_PI_2).abs() < 1e-3 && !r.is_nan());
        assert_eq!(accel_tilt_rad([0.0; 3]), (0.0, 0.0));
    }

    #[test]
    fn heading_north_east_and_declination() {
        let h = mag_heading_rad(ned_to_body(&e(0.0, 0.0, 0.0), M_NED), 0.0, 0.0, 0.0);
        assert!(h.abs() < 1e-5);
        let h = mag_heading_rad(ned_to_body(&e(0.0, 0.0, FRAC_PI_2), M_NED), 0.0, 0.0, 0.0);
        assert!((h - FRAC_PI_2).abs() < 1e-5, "east {h}");
        let h = mag_heading_rad(ned_to_body(&e(0.0, 0.0, -2.5), M_NED), 0.0, 0.0, 0.0);
        assert!((h + 2.5).abs() < 1e-5, "{h}");
        // east declination: magnetic north points 8° east of true north
        let d = 8f32.to_radians();
        // vehicle pointing at true heading 30°, so magnetic heading is 22°
        let m_ned_decl = [M_NED[0] * d.cos(), M_NED[0] * d.sin(), M_NED[2]];
        let yaw = 30f32.to_radians();
        let h = mag_heading_rad(ned_to_body(&e(0.0, 0.0, yaw), m_ned_decl), 0.0, 0.0, d);
        assert!((h - yaw).abs() < 1e-5, "{h}");
        // wraps
        let h = mag_heading_rad(ned_to_body(&e(0.0, 0.0, 3.1), M_NED), 0.0, 0.0, 0.1);
        assert!(h > -PI && h <= PI && (h - (3.2 - 2.0 * PI)).abs() < 1e-4);
    }

    #[test]
    fn heading_with_tilt() {
        for &(r, p, y) in &[(0.3, 0.2, 1.0), (-0.5, 0.4, -2.0), (0.2, -0.6, 3.0)] {
            let m = ned_to_body(&e(r, p, y), M_NED);
            let h = mag_heading_rad(m, r, p, 0.0);
            assert!((h - y).abs() < 1e-4, "{r} {p} {y} -> {h}");
            // without compensation the heading would be wrong
            assert!((mag_heading_rad(m, 0.0, 0.0, 0.0) - y).abs() > 1e-2);
        }
    }

    #[test]
    fn euler_rates_kinematics() {
        // level: Euler rates = body rates
        let r = euler_rates([0.1, 0.2, 0.3], 0.0, 0.0);
        assert!(
            (r[0] - 0.1).abs() < 1e-6 && (r[1] - 0.2).abs() < 1e-6 && (r[2] - 0.3).abs() < 1e-6
        );
        // rolled 90°: body q maps to yaw rate, r to −pitch rate
        let r = euler_rates([0.0, 0.2, 0.3], FRAC_PI_2, 0.0);
        assert!((r[1] + 0.3).abs() < 1e-5 && (r[2] - 0.2).abs() < 1e-5);
        // gimbal lock guard: finite
        let r = euler_rates([0.0, 0.1, 0.1], 0.1, FRAC_PI_2);
        assert!(r.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn rotation_and_linear_accel() {
        let att = e(0.3, -0.4, 1.2);
        let m = rot_body_to_ned(&att);
        // orthonormal
        for i in 0..3 {
            for j in 0..3 {
                let d: f32 = (0..3).map(|k| m[i][k] * m[j][k]).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-5);
            }
        }
        // yaw 90°: body forward = east
        let v = body_to_ned(&e(0.0, 0.0, FRAC_PI_2), [1.0, 0.0, 0.0]);
        assert!(v[0].abs() < 1e-6 && (v[1] - 1.0).abs() < 1e-6);
        // pitch up: forward has negative down component
        let v = body_to_ned(&e(0.0, 0.3, 0.0), [1.0, 0.0, 0.0]);
        assert!(v[2] < 0.0);
        // at rest → zero
        let a = linear_accel_ned_mps2(&att, accel_at_rest(&att));
        assert!(a.iter().all(|x| x.abs() < 1e-5), "{a:?}");
        // accelerating north at 1 m/s² while level: f = a − g = [1, 0, −g]
        let a = linear_accel_ned_mps2(&Euler::default(), [1.0, 0.0, -G]);
        assert!((a[0] - 1.0).abs() < 1e-6 && a[2].abs() < 1e-6);
    }

    fn sim(est: &mut AttitudeEstimator, truth: Euler, gyro: [f32; 3], secs: f32, rng: &mut Rng) {
        for _ in 0..(secs / DT) as usize {
            let f = accel_at_rest(&truth).map(|x| x + rng.normal(0.3));
            let m = ned_to_body(&truth, M_NED).map(|x| x + rng.normal(0.5));
            est.update(gyro, Some(f), Some(m), DT);
        }
    }

    #[test]
    fn estimator_converges_after_rotation() {
        let mut rng = Rng::new(3);
        let mut est = AttitudeEstimator::new(CfGains::new(1.0, 0.7), CfGains::new(0.5, 0.7), 0.0);
        // the vehicle was rotated to `target` while the estimator still believes it is level
        // and north (e.g. rotated before the gyro integration started): it must converge
        let target = e(0.2, -0.15, 1.0);
        est.reset(e(0.0, 0.0, 0.0));
        // (the 57° heading error is first taken for a disturbance; the field matches the
        // Earth's, so after `mag_realign_s` the heading is re-aligned to it)
        est.mag_realign_allowed = true;
        sim(&mut est, target, [0.0; 3], 25.0, &mut rng);
        assert_eq!(est.mag_realigns(), 1);
        let got = est.euler();
        assert!((got.roll_rad - 0.2).abs() < 0.01, "{got:?}");
        assert!((got.pitch_rad + 0.15).abs() < 0.01, "{got:?}");
        assert!((got.yaw_rad - 1.0).abs() < 0.02, "{got:?}");
    }

    #[test]
    fn estimator_tracks_yaw_rotation_with_gyro() {
        let mut est = AttitudeEstimator::new(CfGains::new(1.0, 0.7), CfGains::new(0.5, 0.7), 0.0);
        est.reset(Euler::default());
        // 90° yaw in 1 s at 90°/s, level: Euler yaw rate = r
        let r = FRAC_PI_2;
        let mut yaw = 0.0f32;
        for _ in 0..500 {
            yaw += r * DT;
            let t = e(0.0, 0.0, yaw);
            est.update(
                [0.0, 0.0, r],
                Some(accel_at_rest(&t)),
                Some(ned_to_body(&t, M_NED)),
                DT,
            );
        }
        assert!(
            (est.euler().yaw_rad - FRAC_PI_2).abs() < 1e-3,
            "{:?}",
            est.euler()
        );
    }

    #[test]
    fn estimator_rejects_gyro_bias() {
        let mut rng = Rng::new(11);
        let mut est = AttitudeEstimator::new(CfGains::new(1.0, 0.7), CfGains::new(0.5, 0.7), 0.0);
        let truth = e(0.1, 0.05, -0.7);
        est.reset(truth);
        let bias = [0.02, -0.03, 0.01];
        sim(&mut est, truth, bias, 40.0, &mut rng);
        let got = est.euler();
        assert!((got.roll_rad - truth.roll_rad).abs() < 0.01, "{got:?}");
        assert!((got.pitch_rad - truth.pitch_rad).abs() < 0.01, "{got:?}");
        assert!((got.yaw_rad - truth.yaw_rad).abs() < 0.02, "{got:?}");
        let b = est.rate_bias_radps();
        let want = euler_rates(bias, truth.roll_rad, truth.pitch_rad);
        for i in 0..3 {
            assert!((b[i] + want[i]).abs() < 3e-3, "{b:?} vs {want:?}");
        }
    }

    #[test]
    fn compensated_update_equals_update_of_the_compensated_force() {
        let mut rng = Rng::new(21);
        let gains = (CfGains::new(1.0, 0.7), CfGains::new(0.5, 0.7));
        let mut a_est = AttitudeEstimator::new(gains.0, gains.1, 0.1);
        a_est.reset(e(0.2, -0.1, 2.5));
        let mut b_est = a_est;
        for k in 0..2000 {
            let gyro = [rng.normal(0.2), rng.normal(0.2), rng.normal(0.3)];
            let f = [rng.normal(1.0), rng.normal(1.0), -G + rng.normal(1.0)];
            // Zero (no GPS) half of the time: then no rotation at all.
            let a = if k % 2 == 0 {
                [rng.normal(1.0), rng.normal(1.0), rng.normal(0.3)]
            } else {
                [0.0; 3]
            };
            let m = (k % 5 == 0).then(|| M_NED.map(|x| x + rng.normal(0.5)));
            let r = rot_body_to_ned(&b_est.euler());
            let f_c: [f32; 3] =
                core::array::from_fn(|i| f[i] - (r[0][i] * a[0] + r[1][i] * a[1] + r[2][i] * a[2]));
            let got = a_est.update_compensated(gyro, f, a, m, DT);
            let want = b_est.update(gyro, Some(f_c), m, DT);
            assert_eq!(got, want, "step {k}");
            if k % 5 == 4 {
                // A tilt-correction step (every 5th): the compensated force it read.
                assert_eq!(a_est.tilt_specific_force_frd_mps2(), f_c);
            }
        }
    }

    #[test]
    fn accel_gate_skips_large_specific_force() {
        let mut est = AttitudeEstimator::new(CfGains::new(1.0, 0.7), CfGains::new(0.5, 0.7), 0.0);
        est.reset(Euler::default());
        // 3 g forward: would read as a large pitch; gated out
        for _ in 0..1000 {
            est.update([0.0; 3], Some([3.0 * G, 0.0, -G]), None, DT);
        }
        assert_eq!(est.euler().pitch_rad, 0.0);
        est.accel_gate_mps2 = 100.0;
        for _ in 0..1000 {
            est.update([0.0; 3], Some([3.0 * G, 0.0, -G]), None, DT);
        }
        assert!(est.euler().pitch_rad > 0.5);
    }

    #[test]
    fn short_magnetic_disturbance_is_gated_out() {
        let mut rng = Rng::new(5);
        let mut est = AttitudeEstimator::new(CfGains::new(0.5, 0.7), CfGains::new(0.1, 1.0), 0.0);
        let truth = e(0.0, 0.0, 0.5);
        est.reset(truth);
        sim(&mut est, truth, [0.0; 3], 5.0, &mut rng);
        // 8 s of an extra 15 µT towards east: the magnetometer heading is off by ~20°.
        for _ in 0..(8.0 / DT) as usize {
            let f = accel_at_rest(&truth);
            let m_ned = [M_NED[0], M_NED[1] + 15.0, M_NED[2]];
            est.update([0.0; 3], Some(f), Some(ned_to_body(&truth, m_ned)), DT);
            assert!(
                (est.euler().yaw_rad - 0.5).abs() < 2f32.to_radians(),
                "{:?}",
                est.euler()
            );
        }
        assert!(est.mag_rejects() > 0 && est.mag_disturbed());
        sim(&mut est, truth, [0.0; 3], 1.0, &mut rng);
        assert!(!est.mag_disturbed());
    }

    #[test]
    fn a_long_disturbance_is_never_accepted() {
        let mut rng = Rng::new(6);
        let mut est = AttitudeEstimator::new(CfGains::new(0.5, 0.7), CfGains::new(0.1, 1.0), 0.0);
        let truth = e(0.0, 0.0, 0.5);
        est.reset(truth);
        est.set_mag_reference(ned_to_body(&truth, M_NED), 0.0, 0.0);
        sim(&mut est, truth, [0.0; 3], 5.0, &mut rng);
        // 120 s of an extra 25 µT that keeps the field's magnitude (50.2 vs 50 µT) and dip
        // but turns its heading by 49°: rejected throughout in flight, yaw held on the gyro.
        for _ in 0..(120.0 / DT) as usize {
            let f = accel_at_rest(&truth);
            let m_ned = [M_NED[0] - 10.0, M_NED[1] + 22.9, M_NED[2]];
            est.update([0.0; 3], Some(f), Some(ned_to_body(&truth, m_ned)), DT);
        }
        assert!(
            (est.euler().yaw_rad - 0.5).abs() < 1f32.to_radians(),
            "{:?}",
            est.euler()
        );
        assert!(est.mag_disturbed_s() > 119.0 && est.mag_realigns() == 0);
        // Over: fused again at once.
        sim(&mut est, truth, [0.0; 3], 1.0, &mut rng);
        assert!(!est.mag_disturbed());
    }
}
