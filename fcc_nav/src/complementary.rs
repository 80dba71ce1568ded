//! Second-order complementary filters (paper A, eq. 1).
//!
//! The complementary pair is
//!
//! ```text
//! F_L(s) = (2ζωs + ω²) / (s² + 2ζωs + ω²),   F_H(s) = s² / (s² + 2ζωs + ω²),   F_L + F_H = 1
//! ```
//!
//! Both filters here are realised in error-feedback form with `k1 = 2ζω`, `k2 = ω²`:
//!
//! * [`AngleCf`]: `θ̂' = rate + b̂ + k1·e`, `b̂' = k2·e`, `e = meas − θ̂`, which equals
//!   `θ̂ = F_L·meas + F_H·(1/s)·rate`; `b̂` converges to minus the constant rate bias.
//! * [`PosVelCf`]: `x̂' = v̂ + k1·e`, `v̂' = u + k2·e`, `e = y − x̂`, which equals
//!   `x̂ = F_L·y + F_H·(1/s²)·u` (paper eq. 5). The paper's velocity (eq. 6),
//!   `F_L·s·y + F_H·(1/s)·u`, is `x̂' = v̂ + k1·e` ([`PosVelCf::pos_rate`]); the state `v̂`
//!   itself ([`PosVelCf::vel`]) is `(k2·s·y + (s + k1)·u)/(s² + k1·s + k2)`, also
//!   complementary but smoother (it does not pass measurement noise with gain `k1`).
//!
//! # Discretisation
//!
//! Each `update(…, dt_s)` is one predict/correct step (a fixed-gain, Kalman-like form):
//!
//! ```text
//! predict:  x⁻ = x + v·dt + ½·u·dt²,  v⁻ = v + u·dt        (exact for piecewise-constant u)
//! correct:  e = y − x⁻,   x = x⁻ + g1·e,   v = v⁻ + g2·e
//! ```
//!
//! (for [`AngleCf`]: `θ⁻ = θ + (rate + b̂)·dt`, `b̂⁻ = b̂`, same correction). The gains are
//! chosen so that the closed-loop discrete poles equal `z = exp(s·dt)` for the two continuous
//! poles `s` of `s² + 2ζωs + ω²` (pole matching). The closed-loop transition matrix is
//! `[[1−g1, (1−g1)·dt], [−g2, 1−g2·dt]]` with characteristic polynomial
//! `z² − (2 − g1 − g2·dt)·z + (1 − g1)`, hence
//!
//! ```text
//! g1 = 1 − exp(−2ζω·dt)
//! g2 = (1 + exp(−2ζω·dt) − (z1 + z2)) / dt,   z1 + z2 = 2·exp(−ζω·dt)·cos(ω·√(1−ζ²)·dt)
//! ```
//!
//! (`cosh(ω·√(ζ²−1)·dt)` for ζ > 1). For small `ω·dt`, `g1 ≈ k1·dt` and `g2 ≈ k2·dt`, i.e. the
//! scheme tends to forward Euler of the continuous filter. Because the prediction is exact when
//! the measurement is exactly the double integral of the input, the complementary property
//! (estimate = measurement) holds exactly in discrete time. The gains are computed in `f64`
//! (the `g2` expression is a difference of numbers close to 2) and cached per `dt_s`.
//!
//! # Delayed measurements ([`PosVelCf`])
//!
//! The filter keeps the last `HIST` *predicted* positions `x⁻` (one per `update`) in a fixed
//! ring buffer. A measurement set by [`PosVelCf::set_measurement`] is held (zero-order hold) and
//! applied on every `update` as `e = y_held − x⁻(now − delay_steps)`, until the next one arrives,
//! [`PosVelCf::clear_measurement`] is called, or it is older than `timeout_s`. Note that holding
//! a slow measurement (e.g. 5 Hz GPS) while the vehicle moves lags the `F_L` path by about half
//! the measurement period (≈ `v·T/2` position error at constant velocity `v`).

use libm::{cos, cosh, exp, sqrt};

/// Continuous-time tuning of a 2nd-order complementary pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CfGains {
    /// Crossover natural frequency ω \[rad/s].
    pub omega_radps: f32,
    /// Damping ratio ζ \[-].
    pub zeta: f32,
}

impl CfGains {
    /// Gains from natural frequency \[rad/s] and damping ratio.
    pub const fn new(omega_radps: f32, zeta: f32) -> Self {
        Self { omega_radps, zeta }
    }

    /// Proportional (first-state) feedback gain `k1 = 2ζω` \[1/s].
    pub fn k1(&self) -> f32 {
        2.0 * self.zeta * self.omega_radps
    }

    /// Integral (second-state) feedback gain `k2 = ω²` \[1/s²].
    pub fn k2(&self) -> f32 {
        self.omega_radps * self.omega_radps
    }

    /// Per-step discrete correction gains `(g1, g2)` for step `dt_s` (pole matching, see the
    /// module docs). `g1` is dimensionless, `g2` has units 1/s.
    pub fn discrete(&self, dt_s: f32) -> (f32, f32) {
        let w = self.omega_radps.max(0.0) as f64;
        let z = self.zeta.max(0.0) as f64;
        let dt = dt_s as f64;
        if dt <= 0.0 {
            return (0.0, 0.0);
        }
        let decay = exp(-z * w * dt);
        let det = decay * decay; // z1·z2 = exp(−2ζω·dt)
        let disc = z * z - 1.0;
        let sum = if disc.abs() < 1e-9 {
            2.0 * decay
        } else if disc < 0.0 {
            2.0 * decay * cos(w * sqrt(-disc) * dt)
        } else {
            2.0 * decay * cosh(w * sqrt(disc) * dt)
        };
        let g1 = 1.0 - det;
        let g2 = (1.0 + det - sum) / dt;
        (g1 as f32, g2 as f32)
    }
}

/// Cached discrete gains for the last `dt_s` used.
#[derive(Clone, Copy, Debug)]
struct GainCache {
    gains: CfGains,
    dt_s: f32,
    g1: f32,
    g2: f32,
}

impl GainCache {
    fn new(gains: CfGains) -> Self {
        Self {
            gains,
            dt_s: -1.0,
            g1: 0.0,
            g2: 0.0,
        }
    }

    fn get(&mut self, dt_s: f32) -> (f32, f32) {
        if dt_s != self.dt_s {
            let (g1, g2) = self.gains.discrete(dt_s);
            self.g1 = g1;
            self.g2 = g2;
            self.dt_s = dt_s;
        }
        (self.g1, self.g2)
    }
}

/// Per-fix bias gain `k_b` for [`PosVelCf::velocity_measurement_with_bias`]: with velocity gain
/// `k_v` per fix and fixes every `fix_interval_s`, the slow pole of `s² + K·s + K_b` lands at
/// `pole_radps` (`K = k_v/T`, `K_b = p·(K − p)`, `k_b = K_b·T = p·(k_v − p·T)`); 0 when `p` is 0
/// or not below `K`.
pub fn bias_gain_per_fix(pole_radps: f32, vel_gain: f32, fix_interval_s: f32) -> f32 {
    let p = pole_radps.max(0.0);
    let t = fix_interval_s.max(0.0);
    (p * (vel_gain - p * t)).max(0.0)
}

/// Wrap an angle to (−π, π].
#[inline]
pub fn wrap_pi(a_rad: f32) -> f32 {
    use core::f32::consts::PI;
    if a_rad > -PI && a_rad <= PI {
        return a_rad;
    }
    let two_pi = 2.0 * PI;
    let mut r = a_rad - two_pi * crate::math::floorf((a_rad + PI) / two_pi);
    // r in [−π, π); map −π (and rounding spill-over) into (−π, π].
    if r <= -PI {
        r += two_pi;
    }
    if r > PI {
        r -= two_pi;
    }
    r
}

/// Wrap an angle to (−π, π], f64: the one copy for the Linux side (the bridge's frames, the
/// simulator's metrics).
pub fn wrap_pi_f64(a_rad: f64) -> f64 {
    use core::f64::consts::PI;
    let mut a = a_rad % (2.0 * PI);
    if a > PI {
        a -= 2.0 * PI;
    } else if a <= -PI {
        a += 2.0 * PI;
    }
    a
}

/// Angle complementary filter with rate-bias estimation:
/// `θ̂ = F_L·meas + F_H·(1/s)·rate`.
#[derive(Clone, Copy, Debug)]
pub struct AngleCf {
    cache: GainCache,
    wrap: bool,
    angle_rad: f32,
    bias_radps: f32,
}

impl AngleCf {
    /// New filter at angle 0, bias 0. With `wrap_pi` the innovation and the angle are wrapped
    /// to (−π, π] (use for yaw).
    pub fn new(gains: CfGains, wrap_pi: bool) -> Self {
        Self {
            cache: GainCache::new(gains),
            wrap: wrap_pi,
            angle_rad: 0.0,
            bias_radps: 0.0,
        }
    }

    /// Set the angle; the bias estimate is zeroed.
    pub fn reset(&mut self, angle_rad: f32) {
        self.angle_rad = if self.wrap {
            wrap_pi(angle_rad)
        } else {
            angle_rad
        };
        self.bias_radps = 0.0;
    }

    /// Change the tuning (states kept).
    pub fn set_gains(&mut self, g: CfGains) {
        self.cache = GainCache::new(g);
    }

    /// One step: integrate `rate_radps` (plus the bias estimate) over `dt_s`, then correct
    /// with `meas_rad` if present. `None` = predict only (bias kept). Returns the angle.
    pub fn update(&mut self, rate_radps: f32, meas_rad: Option<f32>, dt_s: f32) -> f32 {
        self.predict(rate_radps, dt_s);
        match meas_rad {
            Some(m) => self.correct(m, dt_s),
            None => self.angle_rad,
        }
    }

    /// Propagation only: integrate `rate_radps` (plus the bias estimate) over `dt_s`.
    pub fn predict(&mut self, rate_radps: f32, dt_s: f32) -> f32 {
        let mut a = self.angle_rad + (rate_radps + self.bias_radps) * dt_s;
        if self.wrap {
            a = wrap_pi(a);
        }
        self.angle_rad = a;
        a
    }

    /// Correction only, with the gains of a step of `dt_s`: the time the predictions since the
    /// last correction covered (correcting every `n` predictions with the gains of `n·dt`
    /// keeps the filter's poles, sampled at `n·dt`). Returns the angle.
    pub fn correct(&mut self, meas_rad: f32, dt_s: f32) -> f32 {
        let mut a = self.angle_rad;
        let (g1, g2) = self.cache.get(dt_s);
        let mut e = meas_rad - a;
        if self.wrap {
            e = wrap_pi(e);
        }
        a += g1 * e;
        if self.wrap {
            a = wrap_pi(a);
        }
        self.bias_radps += g2 * e;
        self.angle_rad = a;
        a
    }

    /// Add `angle_rad` to the angle and `bias_radps` to the rate-bias estimate (a correction
    /// computed elsewhere, e.g. by [`crate::tilt_kf`]).
    pub fn nudge(&mut self, angle_rad: f32, bias_radps: f32) {
        let a = self.angle_rad + angle_rad;
        self.angle_rad = if self.wrap { wrap_pi(a) } else { a };
        self.bias_radps += bias_radps;
    }

    /// Current angle estimate \[rad].
    pub fn angle_rad(&self) -> f32 {
        self.angle_rad
    }

    /// Current rate-bias estimate \[rad/s] (added to the rate input; converges to −bias).
    pub fn bias_radps(&self) -> f32 {
        self.bias_radps
    }
}

/// Position/velocity complementary filter (double integrator) with delayed, held measurements:
/// `x̂ = F_L·y + F_H·(1/s²)·u`; velocity see [`Self::vel`] and [`Self::pos_rate`].
///
/// Delay convention: a measurement set before an `update` with `delay_steps = d` is the
/// position at the time reached `d` steps before the end of that update (`d = 0`: the time the
/// update advances to).
///
/// Units are the caller's (m, m/s, m/s² in this crate). `HIST` ≥ 1 is the length of the
/// predicted-position history (maximum usable delay is `HIST − 1` steps).
#[derive(Clone, Copy, Debug)]
pub struct PosVelCf<const HIST: usize> {
    cache: GainCache,
    pos: f32,
    vel: f32,
    innov_rate: f32,
    hist: [f32; HIST],
    /// Predicted velocities beside `hist`, for delayed velocity measurements.
    vhist: [f32; HIST],
    head: usize,
    meas: Option<f32>,
    delay_steps: usize,
    age_s: f32,
    /// A held measurement is dropped when older than this \[s] (default 1.0).
    pub timeout_s: f32,
    /// Input-bias estimate (subtracted from `accel`), see [`Self::set_bias_gain`].
    bias: f32,
    bias_k3: f32,
    bias_extra_k1: f32,
    bias_extra_k2: f32,
    bias_limit: f32,
}

impl<const HIST: usize> PosVelCf<HIST> {
    const HIST_OK: () = assert!(HIST >= 1, "PosVelCf needs HIST >= 1");

    /// New filter at rest at 0, no measurement.
    pub fn new(gains: CfGains) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::HIST_OK;
        Self {
            cache: GainCache::new(gains),
            pos: 0.0,
            vel: 0.0,
            innov_rate: 0.0,
            hist: [0.0; HIST],
            vhist: [0.0; HIST],
            head: 0,
            meas: None,
            delay_steps: 0,
            age_s: 0.0,
            timeout_s: 1.0,
            bias: 0.0,
            bias_k3: 0.0,
            bias_extra_k1: 0.0,
            bias_extra_k2: 0.0,
            bias_limit: 0.0,
        }
    }

    /// Optional slow estimate of a constant input (accelerometer) bias: `b̂' = −k3·e`, the input
    /// used being `u − b̂`. This adds a third pole at `p` (`k3 = p·ω²`), turning the paper's
    /// 2nd-order pair into the 3rd-order complementary filter ArduPilot's `AP_InertialNav` used
    /// for baro/GPS + accelerometer. With `p ≪ ω` the crossover is essentially unchanged; the
    /// gain is what removes the `b/ω²` position and `2ζb/ω` velocity errors an uncorrected
    /// accelerometer bias (or vibration rectification) leaves. `p = 0` (default) is the
    /// paper's filter. The estimate is clamped to `±limit`.
    pub fn set_bias_gain(&mut self, pole_radps: f32, limit: f32) {
        let g = self.cache.gains;
        let p = pole_radps.max(0.0);
        let w = g.omega_radps;
        // (s + p)(s² + 2ζωs + ω²) = s³ + (2ζω + p)s² + (ω² + 2ζωp)s + pω²: the first two
        // gains grow by p and 2ζωp so the three poles land where intended.
        self.bias_k3 = p * w * w;
        self.bias_extra_k1 = p;
        self.bias_extra_k2 = 2.0 * g.zeta * w * p;
        self.bias_limit = limit.abs();
    }

    /// Seed the input-bias estimate (e.g. from a static calibration on the ground).
    pub fn set_bias(&mut self, bias: f32) {
        self.bias = bias.max(-self.bias_limit).min(self.bias_limit);
    }

    /// Current input-bias estimate (same unit as `accel`).
    pub fn bias(&self) -> f32 {
        self.bias
    }

    /// Set the state; the history is filled with `pos` and any held measurement is dropped.
    pub fn reset(&mut self, pos: f32, vel: f32) {
        self.pos = pos;
        self.vel = vel;
        self.innov_rate = 0.0;
        self.hist = [pos; HIST];
        self.vhist = [vel; HIST];
        self.head = 0;
        self.meas = None;
        self.age_s = 0.0;
        self.bias = 0.0;
    }

    /// Change the tuning (states kept).
    pub fn set_gains(&mut self, g: CfGains) {
        self.cache = GainCache::new(g);
    }

    /// New measurement `pos`, valid `delay_steps` updates ago (clamped to `HIST − 1`). It is
    /// held and applied on every following `update` until replaced, cleared or timed out.
    pub fn set_measurement(&mut self, pos: f32, delay_steps: usize) {
        self.meas = Some(pos);
        self.delay_steps = delay_steps.min(HIST - 1);
        self.age_s = 0.0;
    }

    /// A velocity measurement `v` (e.g. GPS Doppler velocity), valid `delay_steps` updates ago,
    /// applied once: `v̂ ← v̂ + k_v·(v − v̂(t − d))` against the velocity predicted for its time
    /// (the history beside the positions). With `k_v` per fix at the fix rate `f`, the velocity
    /// error decays at ≈ `k_v·f` 1/s and the measurement noise is averaged over ≈ `2/k_v` fixes.
    pub fn velocity_measurement(&mut self, v: f32, delay_steps: usize, gain: f32) {
        self.velocity_measurement_with_bias(v, delay_steps, gain, 0.0);
    }

    /// [`Self::velocity_measurement`] that also learns the input (accelerometer) bias from the
    /// velocity innovation: `b̂ ← b̂ − k_b·(v − v̂(t − d))`, clamped to the limit of
    /// [`Self::set_bias_gain`] (a zero limit keeps `b̂` at 0). Per fix at rate `f` the velocity
    /// error `ṽ` and the bias error `β = b − b̂` obey `ṽ' = β − K·ṽ`, `β' = −K_b·ṽ` with
    /// `K = k_v·f`, `K_b = k_b·f`: poles at the roots of `s² + K·s + K_b`. [`bias_gain_per_fix`]
    /// places the slow one at `p` (`K_b = p·(K − p)`). With the bias learnt from the velocity,
    /// a constant bias leaves no steady velocity or position error even when the position
    /// crossover `ω` is far below `p` (a filter that trusts the Doppler velocity and follows
    /// the GPS position only slowly).
    pub fn velocity_measurement_with_bias(
        &mut self,
        v: f32,
        delay_steps: usize,
        gain: f32,
        bias_gain: f32,
    ) {
        let idx = (self.head + HIST - delay_steps.min(HIST - 1)) % HIST;
        let e = v - self.vhist[idx];
        let k = gain.clamp(0.0, 1.0);
        self.vel += k * e;
        for x in self.vhist.iter_mut() {
            *x += k * e;
        }
        if bias_gain > 0.0 {
            self.bias = (self.bias - bias_gain * e)
                .max(-self.bias_limit)
                .min(self.bias_limit);
        }
    }

    /// Set the input-bias limit alone (no position-driven bias gain): for a filter whose bias
    /// is learnt from velocity measurements ([`Self::velocity_measurement_with_bias`]).
    pub fn set_bias_limit(&mut self, limit: f32) {
        self.bias_limit = limit.abs();
    }

    /// Drop the held measurement (pure dead reckoning from now on).
    pub fn clear_measurement(&mut self) {
        self.meas = None;
    }

    /// Whether a measurement is currently held and applied.
    pub fn has_measurement(&self) -> bool {
        self.meas.is_some()
    }

    /// One step: predict with `accel` over `dt_s`, store the predicted position in the history,
    /// then correct with the held measurement (if any, and not timed out).
    pub fn update(&mut self, accel: f32, dt_s: f32) {
        let accel = accel - self.bias;
        let x_pred = self.pos + self.vel * dt_s + 0.5 * accel * dt_s * dt_s;
        let v_pred = self.vel + accel * dt_s;
        self.head = (self.head + 1) % HIST;
        self.hist[self.head] = x_pred;
        self.vhist[self.head] = v_pred;
        self.pos = x_pred;
        self.vel = v_pred;
        self.innov_rate = 0.0;
        if let Some(y) = self.meas {
            if self.age_s > self.timeout_s {
                self.meas = None;
                return;
            }
            let idx = (self.head + HIST - self.delay_steps) % HIST;
            let e = y - self.hist[idx];
            let (g1, g2) = self.cache.get(dt_s);
            let g1 = g1 + self.bias_extra_k1 * dt_s;
            let g2 = g2 + self.bias_extra_k2 * dt_s;
            self.pos += g1 * e;
            self.vel += g2 * e;
            if self.bias_k3 > 0.0 {
                self.bias = (self.bias - self.bias_k3 * e * dt_s)
                    .max(-self.bias_limit)
                    .min(self.bias_limit);
            }
            if dt_s > 0.0 {
                self.innov_rate = g1 * e / dt_s;
            }
            self.age_s += dt_s;
        }
    }

    /// Position estimate.
    pub fn pos(&self) -> f32 {
        self.pos
    }

    /// Velocity estimate: the filter's second state `v̂`.
    ///
    /// In transfer-function form `v̂ = (k2·s·y + (s + k1)·u)/(s² + k1·s + k2)`: complementary
    /// (exact when `y` and `u` agree) and rolling off measurement noise, but a constant input
    /// bias `b` leaves a steady velocity error `k1·b/ω² = 2ζ·b/ω`. See [`Self::pos_rate`] for
    /// the paper's eq. 6 split.
    pub fn vel(&self) -> f32 {
        self.vel
    }

    /// Rate of the position estimate, `x̂' = v̂ + k1·e` (discretely `v̂ + g1·e/dt` of the last
    /// step). This is exactly the paper's eq. 6, `F_L·s·y + F_H·(1/s)·u`: no steady error from
    /// an input bias, but measurement noise passes with high-frequency gain `k1`.
    pub fn pos_rate(&self) -> f32 {
        self.vel + self.innov_rate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Rng;
    use core::f32::consts::PI;

    const DT: f32 = 0.002;

    #[test]
    fn gains_k1_k2() {
        let g = CfGains::new(2.0, 0.5);
        assert_eq!(g.k1(), 2.0);
        assert_eq!(g.k2(), 4.0);
    }

    #[test]
    fn discrete_gains_tend_to_euler() {
        let g = CfGains::new(1.5, 0.7);
        let (g1, g2) = g.discrete(1e-4);
        assert!((g1 / 1e-4 - g.k1()).abs() < 1e-3 * g.k1());
        assert!((g2 - g.k2() * 1e-4).abs() < 1e-3 * g.k2() * 1e-4);
        // zero bandwidth = pure integration
        assert_eq!(CfGains::new(0.0, 0.7).discrete(DT), (0.0, 0.0));
        // over- and critically damped also fine
        for z in [1.0, 1.0 + 1e-12, 2.0] {
            let (a, b) = CfGains::new(1.0, z).discrete(1e-4);
            assert!((a / 1e-4 - 2.0 * z).abs() < 1e-2, "{z} {a}");
            assert!((b / 1e-4 - 1.0).abs() < 1e-2, "{z} {b}");
        }
    }

    #[test]
    fn discrete_poles_match_exp() {
        // Closed-loop matrix [[1-g1, (1-g1)dt], [-g2, 1-g2 dt]]; check trace/det vs exp(s dt).
        let g = CfGains::new(3.0, 0.4);
        let dt = 0.01f32;
        let (g1, g2) = g.discrete(dt);
        let tr = (1.0 - g1) + (1.0 - g2 * dt);
        let det = 1.0 - g1;
        let wd = 3.0 * (1.0f32 - 0.16).sqrt();
        let sigma = 0.4 * 3.0;
        let tr_want = 2.0 * (-sigma * dt).exp() * (wd * dt).cos();
        let det_want = (-2.0 * sigma * dt).exp();
        assert!((tr - tr_want).abs() < 1e-5);
        assert!((det - det_want).abs() < 1e-6);
    }

    #[test]
    fn wrap_pi_range() {
        assert!((wrap_pi(3.0 * PI) - PI).abs() < 1e-5);
        assert_eq!(wrap_pi(PI), PI);
        assert!((wrap_pi(-PI) - PI).abs() < 1e-6);
        assert!((wrap_pi(-3.5 * PI) - 0.5 * PI).abs() < 1e-5);
        assert_eq!(wrap_pi(0.3), 0.3);
        for i in -100..100 {
            let w = wrap_pi(i as f32 * 0.37);
            assert!(w > -PI && w <= PI);
        }
    }

    /// (a) complementary property: y = exact double integral of u ⇒ estimate = y.
    #[test]
    fn complementary_property_exact() {
        let mut f = PosVelCf::<8>::new(CfGains::new(2.0, 0.7));
        let (mut x, mut v) = (1.0f32, -0.5f32);
        f.reset(x, v);
        let mut max_err = 0.0f32;
        let mut max_verr = 0.0f32;
        for k in 0..5000 {
            let t = k as f32 * DT;
            let u = 2.0 * crate::math::sinf(3.0 * t) + 0.5;
            x += v * DT + 0.5 * u * DT * DT;
            v += u * DT;
            f.set_measurement(x, 0);
            f.update(u, DT);
            max_err = max_err.max((f.pos() - x).abs());
            max_verr = max_verr.max((f.vel() - v).abs());
        }
        assert!(max_err < 1e-4, "pos err {max_err}");
        assert!(max_verr < 5e-4, "vel err {max_verr}");
    }

    /// (b) constant accel bias b ⇒ steady-state position error b/ω².
    #[test]
    fn accel_bias_steady_state_is_b_over_omega_sq() {
        let g = CfGains::new(1.0, 0.7);
        let mut f = PosVelCf::<4>::new(g);
        f.reset(0.0, 0.0);
        f.timeout_s = f32::INFINITY;
        let b = 0.3f32;
        for _ in 0..(40.0 / DT) as usize {
            f.set_measurement(0.0, 0);
            f.update(b, DT);
        }
        let want = b / g.k2();
        assert!(
            (f.pos() - want).abs() < 0.01 * want,
            "{} vs {}",
            f.pos(),
            want
        );
        // the v̂ state carries k1·b/ω²; the position rate (paper eq. 6) has no bias
        assert!(
            (f.vel() - g.k1() * want).abs() < 0.01 * g.k1() * want,
            "{}",
            f.vel()
        );
        assert!(f.pos_rate().abs() < 1e-3, "{}", f.pos_rate());
        // doubling ω quarters the error
        let g2 = CfGains::new(2.0, 0.7);
        f.set_gains(g2);
        for _ in 0..(20.0 / DT) as usize {
            f.update(b, DT);
        }
        assert!((f.pos() - b / 4.0).abs() < 0.01 * b / 4.0);
    }

    /// Analytic F_L step response: 1 − e^{−ζωt}(cos ω_d t − (ζω/ω_d) sin ω_d t).
    fn fl_step(w: f32, z: f32, t: f32) -> f32 {
        let wd = w * (1.0 - z * z).sqrt();
        1.0 - (-z * w * t).exp() * ((wd * t).cos() - (z * w / wd) * (wd * t).sin())
    }

    fn step_peak(w: f32, z: f32) -> (f32, f32) {
        let mut f = PosVelCf::<4>::new(CfGains::new(w, z));
        f.reset(0.0, 0.0);
        f.timeout_s = f32::INFINITY;
        f.set_measurement(1.0, 0);
        let (mut peak, mut peak_ref, mut max_dev) = (0.0f32, 0.0f32, 0.0f32);
        for k in 1..(20.0 / DT) as usize {
            f.update(0.0, DT);
            let r = fl_step(w, z, k as f32 * DT);
            peak = peak.max(f.pos());
            peak_ref = peak_ref.max(r);
            max_dev = max_dev.max((f.pos() - r).abs());
        }
        assert!(max_dev < 0.01, "deviation from analytic {max_dev}");
        assert!((f.pos() - 1.0).abs() < 1e-3, "settles to 1");
        (peak, peak_ref)
    }

    /// (c) measurement step: overshoot matches the analytic F_L step for ζ, decreasing with ζ.
    #[test]
    fn measurement_step_overshoot_matches_zeta() {
        let (p05, r05) = step_peak(2.0, 0.5);
        let (p07, r07) = step_peak(2.0, 0.707);
        let (p09, r09) = step_peak(2.0, 0.9);
        assert!((p05 - r05).abs() < 0.005);
        assert!((p07 - r07).abs() < 0.005);
        assert!((p09 - r09).abs() < 0.005);
        // F_L has a zero, so overshoot is larger than the classic 2nd-order one.
        assert!(p05 > 1.25 && p05 < 1.35, "{p05}");
        assert!(p07 > 1.15 && p07 < 1.25, "{p07}");
        assert!(p05 > p07 && p07 > p09 && p09 > 1.0);
    }

    /// (d) constant gyro bias rejected; b̂ → −bias.
    #[test]
    fn angle_cf_rejects_gyro_bias() {
        let mut f = AngleCf::new(CfGains::new(1.0, 0.7), false);
        f.reset(0.0);
        let bias = 0.05f32;
        let mut t = 0.0f32;
        for _ in 0..(30.0 / DT) as usize {
            t += DT;
            let truth = 0.2 * crate::math::sinf(t);
            let rate = 0.2 * crate::math::cosf(t) + bias;
            f.update(rate, Some(truth), DT);
        }
        assert!((f.bias_radps() + bias).abs() < 1e-3, "{}", f.bias_radps());
        assert!((f.angle_rad() - 0.2 * crate::math::sinf(t)).abs() < 1e-3);
    }

    #[test]
    fn angle_cf_predict_only_keeps_bias_and_integrates() {
        let mut f = AngleCf::new(CfGains::new(1.0, 0.7), false);
        f.reset(0.0);
        for _ in 0..20000 {
            f.update(0.1, Some(0.0), DT);
        }
        let b = f.bias_radps();
        assert!((b + 0.1).abs() < 1e-3);
        for _ in 0..500 {
            f.update(0.1 + 1.0, None, DT);
        }
        assert_eq!(f.bias_radps(), b);
        assert!((f.angle_rad() - 1.0).abs() < 2e-3, "{}", f.angle_rad());
    }

    #[test]
    fn angle_cf_wraps_across_pi() {
        let mut f = AngleCf::new(CfGains::new(1.0, 0.7), true);
        f.reset(3.0);
        // measurement just across the wrap: should move the short way and stay in range
        for _ in 0..10000 {
            let a = f.update(0.0, Some(-3.0), DT);
            assert!(a > -PI && a <= PI);
        }
        assert!((f.angle_rad() + 3.0).abs() < 1e-3);
        // without wrap the same would be a 6 rad move; with wrap the bias stays small
        assert!(f.bias_radps().abs() < 1e-3);
    }

    /// (e) delayed measurement: matching delay ⇒ no bias on a constant-velocity ramp.
    #[test]
    fn delayed_measurement_ramp_no_bias() {
        let run = |delay_model: usize| -> f32 {
            let delay_true = 40usize;
            let mut f = PosVelCf::<64>::new(CfGains::new(1.0, 0.7));
            f.reset(5.0, 0.0);
            let v = 2.0f32;
            let mut err = 0.0;
            for k in 0..(30.0 / DT) as usize {
                // the update advances to step k + 1; the measurement is delay_true older
                let t_meas = (k + 1) as f32 - delay_true as f32;
                f.set_measurement(v * t_meas.max(0.0) * DT, delay_model);
                f.update(0.0, DT);
                err = f.pos() - v * (k + 1) as f32 * DT;
            }
            err
        };
        let e_ok = run(40);
        assert!(e_ok.abs() < 1e-3, "matched delay err {e_ok}");
        // unmatched delay lags by ≈ v·delay
        let e_bad = run(0);
        assert!((e_bad + 2.0 * 40.0 * DT).abs() < 0.02, "unmatched {e_bad}");
    }

    #[test]
    fn delay_clamped_and_timeout() {
        let mut f = PosVelCf::<8>::new(CfGains::new(1.0, 0.7));
        f.reset(0.0, 0.0);
        f.set_measurement(1.0, 1000); // clamped to 7, must not panic
        assert!(f.has_measurement());
        f.timeout_s = 0.1;
        for _ in 0..49 {
            f.update(0.0, DT);
        }
        assert!(f.has_measurement());
        for _ in 0..5 {
            f.update(0.0, DT);
        }
        assert!(!f.has_measurement());
        let p = f.pos();
        let v = f.vel();
        f.update(0.0, DT);
        assert!(
            (f.pos() - (p + v * DT)).abs() < 1e-6,
            "dead reckoning after timeout"
        );
        f.set_measurement(1.0, 0);
        f.clear_measurement();
        assert!(!f.has_measurement());
    }

    #[test]
    fn noise_is_attenuated() {
        let mut rng = Rng::new(7);
        let mut f = PosVelCf::<4>::new(CfGains::new(1.0, 0.7));
        f.reset(0.0, 0.0);
        let mut s2 = 0.0f64;
        let n = 20000;
        for k in 0..n {
            f.set_measurement(rng.normal(1.0), 0);
            f.update(rng.normal(0.5), DT);
            if k > 5000 {
                s2 += (f.pos() as f64).powi(2);
            }
        }
        let std = (s2 / (n - 5000) as f64).sqrt();
        assert!(std < 0.2, "std {std}");
    }

    #[test]
    fn bias_state_removes_the_accel_bias_error() {
        // Vehicle at rest (y = 0), accelerometer biased by +0.3: the paper's 2nd-order filter
        // settles at b/ω² and 2ζb/ω; with the bias state both errors vanish and b̂ → b.
        let g = CfGains::new(0.5, 0.8);
        let mut plain = PosVelCf::<8>::new(g);
        let mut biased = PosVelCf::<8>::new(g);
        biased.set_bias_gain(0.1, 2.0);
        for _ in 0..(400.0 / 0.002) as usize {
            plain.set_measurement(0.0, 0);
            biased.set_measurement(0.0, 0);
            plain.update(0.3, 0.002);
            biased.update(0.3, 0.002);
        }
        assert!(
            (plain.pos() - 0.3 / 0.25).abs() < 0.02,
            "plain pos {}",
            plain.pos()
        );
        assert!(biased.pos().abs() < 0.01, "pos {}", biased.pos());
        assert!(biased.vel().abs() < 0.01, "vel {}", biased.vel());
        assert!((biased.bias() - 0.3).abs() < 0.01, "bias {}", biased.bias());
    }
}
