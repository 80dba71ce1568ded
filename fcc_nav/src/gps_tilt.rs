//! GPS-velocity tilt aid: roll/pitch errors from the GPS velocity's change over a fix interval
//! against the inertial velocity's change over the same interval.
//!
//! The accelerometer alone reads gravity plus every manoeuvre and gust; subtracting a
//! GPS-differenced acceleration from it compares two things at different times (the difference
//! lags by the receiver's latency plus half an interval, and any smoothing on top). Here both
//! sides cover the same interval instead (ArduPilot's DCM drift correction compares the same
//! two velocity changes):
//!
//! ```text
//!   Δv_gps = v_gps(k) − v_gps(k−1)                   the receiver's, stamped at t_k − L
//!   Δv_ins = ∫ (R̂·f + g) dt   over [t_{k−1} − L, t_k − L]   (our attitude R̂, NE components)
//!   r      = (Δv_gps − Δv_ins) / (t_k − t_{k−1})        [m/s²]
//! ```
//!
//! An attitude error δ (a small rotation, NED, estimate = (I + [δ×])·truth) turns the measured
//! specific force `f ≈ (0, 0, −g)` into `R̂·f = R·f + δ × (0, 0, −g)`, so `r = (g·δ_E, −g·δ_N)`:
//!
//! ```text
//!   δ_N = −r_E / g,   δ_E = r_N / g
//!   roll error  = δ_N·cos ψ + δ_E·sin ψ     (about the body's forward axis)
//!   pitch error = −δ_N·sin ψ + δ_E·cos ψ    (about its right axis)
//! ```
//!
//! `L` is the receiver's latency, applied as a whole number of IMU steps to the history of the
//! integrated inertial velocity ([`HIST`] steps kept). The errors correct the roll/pitch filter
//! in place of the accelerometer's gravity direction while GPS velocities arrive
//! ([`crate::attitude::AttitudeEstimator::correct_tilt_error`]).

use crate::math::sincosf;
use crate::GRAVITY_MPS2;

/// IMU steps of integrated inertial velocity kept: the latency may be up to `HIST − 1` steps
/// (0.254 s at 500 Hz; the parameter check allows 0.25 s).
pub const HIST: usize = 128;

/// Shortest and longest interval between consecutive fixes, s (outside: the earlier fixes are
/// forgotten).
const INTERVAL_MIN_S: f32 = 0.05;
const INTERVAL_MAX_S: f32 = 1.0;

/// The velocity changes are compared over this many fix intervals (fewer until as many fixes
/// have arrived), the error applied at every fix.
pub const WINDOW_FIXES: usize = 1;

/// Roll and pitch errors (estimate minus truth) over a fix interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TiltError {
    /// Roll error \[rad].
    pub roll_rad: f32,
    /// Pitch error \[rad].
    pub pitch_rad: f32,
    /// The interval the errors were measured over \[s].
    pub interval_s: f32,
}

/// The previous fix: its time, velocity (N, E) and the delayed inertial velocity then.
#[derive(Clone, Copy, Debug)]
struct Fix {
    t_us: u64,
    vel_ne_mps: [f32; 2],
    ins_ne_mps: [f32; 2],
}

/// See the module documentation.
#[derive(Clone, Debug)]
pub struct GpsTiltAid {
    /// Integrated inertial velocity (N, E) after each of the last [`HIST`] steps.
    hist: [[f32; 2]; HIST],
    head: usize,
    /// Steps integrated so far (saturating at [`HIST`]).
    filled: usize,
    ins_ne_mps: [f32; 2],
    /// The last [`WINDOW_FIXES`] fixes (ring; `fixes_n` of them valid, newest at `fix_head`).
    fixes: [Fix; WINDOW_FIXES],
    fix_head: usize,
    fixes_n: usize,
}

impl Default for GpsTiltAid {
    fn default() -> Self {
        Self::new()
    }
}

impl GpsTiltAid {
    /// Empty history, no previous fix.
    pub const fn new() -> Self {
        Self {
            hist: [[0.0; 2]; HIST],
            head: 0,
            filled: 0,
            ins_ne_mps: [0.0; 2],
            fixes: [Fix {
                t_us: 0,
                vel_ne_mps: [0.0; 2],
                ins_ne_mps: [0.0; 2],
            }; WINDOW_FIXES],
            fix_head: 0,
            fixes_n: 0,
        }
    }

    /// One IMU step: integrate the gravity-compensated NED acceleration's north and east
    /// components (`R̂·f + g`, [`crate::attitude::linear_accel_ned_mps2`]) over `dt_s`.
    #[inline]
    pub fn step(&mut self, accel_ne_mps2: [f32; 2], dt_s: f32) {
        self.ins_ne_mps[0] += accel_ne_mps2[0] * dt_s;
        self.ins_ne_mps[1] += accel_ne_mps2[1] * dt_s;
        self.head = (self.head + 1) % HIST;
        self.hist[self.head] = self.ins_ne_mps;
        if self.filled < HIST {
            self.filled += 1;
        }
    }

    /// A GPS velocity (N, E) received at `t_us`, measured `delay_steps` IMU steps earlier;
    /// `yaw_rad` the current heading. The tilt error over the interval since the previous
    /// velocity, if that one is between 0.05 and 1 s old and the history reaches back far
    /// enough (`delay_steps < HIST`).
    pub fn gps_velocity(
        &mut self,
        t_us: u64,
        vel_ne_mps: [f32; 2],
        delay_steps: usize,
        yaw_rad: f32,
    ) -> Option<TiltError> {
        if delay_steps >= HIST || delay_steps >= self.filled {
            self.fixes_n = 0;
            return None;
        }
        let ins = self.hist[(self.head + HIST - delay_steps) % HIST];
        let fix = Fix {
            t_us,
            vel_ne_mps,
            ins_ne_mps: ins,
        };
        let last = self.fixes[self.fix_head];
        let interval_s = t_us.saturating_sub(last.t_us) as f32 * 1e-6;
        if self.fixes_n > 0 && !(INTERVAL_MIN_S..=INTERVAL_MAX_S).contains(&interval_s) {
            self.fixes_n = 0;
        }
        let n = self.fixes_n;
        let first = self.fixes[(self.fix_head + WINDOW_FIXES + 1 - n.max(1)) % WINDOW_FIXES];
        self.fix_head = (self.fix_head + 1) % WINDOW_FIXES;
        self.fixes[self.fix_head] = fix;
        self.fixes_n = (n + 1).min(WINDOW_FIXES);
        if n == 0 {
            return None;
        }
        let window_s = t_us.saturating_sub(first.t_us) as f32 * 1e-6;
        let r = [0, 1].map(|i| {
            ((vel_ne_mps[i] - first.vel_ne_mps[i]) - (ins[i] - first.ins_ne_mps[i])) / window_s
        });
        let d_n = -r[1] / GRAVITY_MPS2;
        let d_e = r[0] / GRAVITY_MPS2;
        let (s, c) = sincosf(yaw_rad);
        let e = TiltError {
            roll_rad: d_n * c + d_e * s,
            pitch_rad: -d_n * s + d_e * c,
            interval_s,
        };
        (e.roll_rad.is_finite() && e.pitch_rad.is_finite()).then_some(e)
    }

    /// Forget the previous fixes (the next velocity starts a new window).
    pub fn forget_fix(&mut self) {
        self.fixes_n = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{linear_accel_ned_mps2, rot_body_to_ned, Euler};

    const DT: f32 = 0.002;

    /// Fly a constant acceleration `a_ned` at heading `yaw` with the true tilt that produces
    /// it, the estimate off by `(d_roll, d_pitch)`; GPS at 5 Hz with `lat` steps of latency.
    fn measured(a_ne: [f32; 2], yaw: f32, d_roll: f32, d_pitch: f32, lat: usize) -> TiltError {
        let g = GRAVITY_MPS2;
        // Specific force in NED: a − g = (a_N, a_E, −g); in the body at the true attitude.
        let f_ned = [a_ne[0], a_ne[1], -g];
        let truth = Euler {
            roll_rad: 0.05,
            pitch_rad: -0.03,
            yaw_rad: yaw,
        };
        let r = rot_body_to_ned(&truth);
        let f_body =
            [0, 1, 2].map(|j| r[0][j] * f_ned[0] + r[1][j] * f_ned[1] + r[2][j] * f_ned[2]);
        let est = Euler {
            roll_rad: truth.roll_rad + d_roll,
            pitch_rad: truth.pitch_rad + d_pitch,
            yaw_rad: yaw,
        };
        let mut aid = GpsTiltAid::new();
        let mut out = None;
        let mut t_us = 0u64;
        for k in 1..=1000u32 {
            let a = linear_accel_ned_mps2(&est, f_body);
            aid.step([a[0], a[1]], DT);
            t_us += 2000;
            if k % 100 == 0 {
                // The receiver's velocity at the time it describes (lat steps ago).
                let t_meas = (k as usize - lat) as f32 * DT;
                let v = [a_ne[0] * t_meas, a_ne[1] * t_meas];
                if let Some(e) = aid.gps_velocity(t_us, v, lat, yaw) {
                    out = Some(e);
                }
            }
        }
        out.expect("an interval was measured")
    }

    #[test]
    fn measures_the_tilt_error_at_any_heading_and_acceleration() {
        for yaw in [0.0f32, 0.7, 1.6, -2.5] {
            for a in [[0.0f32, 0.0], [3.0, -2.0], [-1.0, 4.0]] {
                let (dr, dp) = (0.01f32, -0.02f32);
                let e = measured(a, yaw, dr, dp, 60);
                // The small-angle model: within 5e-4 rad of 0.01–0.02 rad (the manoeuvre's
                // acceleration and the true tilt's second-order terms).
                let tol = 5e-4;
                assert!((e.roll_rad - dr).abs() < tol, "yaw {yaw} a {a:?}: {e:?}");
                assert!((e.pitch_rad - dp).abs() < tol, "yaw {yaw} a {a:?}: {e:?}");
                assert!((e.interval_s - 0.2).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn no_error_when_the_attitude_is_right() {
        let e = measured([2.0, 1.0], 0.4, 0.0, 0.0, 60);
        assert!(e.roll_rad.abs() < 1e-4 && e.pitch_rad.abs() < 1e-4, "{e:?}");
    }

    #[test]
    fn the_latency_aligns_the_two_velocity_changes() {
        // An acceleration that starts mid-flight: with the latency ignored the GPS change
        // lags the inertial one and reads as tilt; with it, both cover the same interval.
        let lat = 60usize;
        let mut worst = [0.0f32; 2];
        for ignore_latency in [false, true] {
            let mut aid = GpsTiltAid::new();
            let mut v_true = std::vec::Vec::new();
            let mut v = 0.0f32;
            for k in 1..=2000usize {
                let a = if k > 700 && k < 1300 { 3.0 } else { 0.0 };
                v += a * DT;
                v_true.push(v);
                aid.step([a, 0.0], DT);
                if k % 100 == 0 {
                    let d = if ignore_latency { 0 } else { lat };
                    let e = aid.gps_velocity(k as u64 * 2000, [v_true[k - 1 - lat], 0.0], d, 0.0);
                    if let Some(e) = e {
                        let w = &mut worst[ignore_latency as usize];
                        *w = w.max(e.pitch_rad.abs());
                    }
                }
            }
        }
        assert!(worst[0] < 1e-4, "aligned: {worst:?}");
        // Misaligned by 0.12 s: 3 m/s² · 0.12 s over the 1 s window, / g ≈ 0.037 rad.
        assert!(worst[1] > 0.03, "not aligned: {worst:?}");
    }

    #[test]
    fn stale_or_too_close_fixes_start_a_new_interval() {
        let mut aid = GpsTiltAid::new();
        for _ in 0..200 {
            aid.step([0.0, 0.0], DT);
        }
        assert!(aid.gps_velocity(1_000_000, [0.0; 2], 10, 0.0).is_none());
        assert!(
            aid.gps_velocity(1_010_000, [0.0; 2], 10, 0.0).is_none(),
            "10 ms"
        );
        assert!(
            aid.gps_velocity(2_100_000, [0.0; 2], 10, 0.0).is_none(),
            "1.09 s"
        );
        assert!(aid.gps_velocity(2_300_000, [0.0; 2], 10, 0.0).is_some());
        aid.forget_fix();
        assert!(aid.gps_velocity(2_500_000, [0.0; 2], 10, 0.0).is_none());
        // A latency beyond the history: nothing, and no panic.
        assert!(aid.gps_velocity(2_700_000, [0.0; 2], HIST, 0.0).is_none());
        assert!(aid
            .gps_velocity(2_900_000, [f32::NAN; 2], 10, 0.0)
            .is_none());
    }
}
