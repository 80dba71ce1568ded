//! Mean wind plus Dryden turbulence (MIL-F-8785C low-altitude model, h < 1000 ft).
//!
//! Turbulence intensities and scale lengths (h in ft, W20 = mean wind speed at 20 ft):
//! - `L_w = h`, `L_u = L_v = h / (0.177 + 0.000823·h)^1.2`
//! - `σ_w = 0.1·W20`, `σ_u = σ_v = σ_w / (0.177 + 0.000823·h)^0.4`
//! - light turbulence: W20 = 15 kt (moderate 30 kt, severe 45 kt).
//!
//! Forming filters (temporal, airspeed V, driven by unit-intensity white noise):
//! - `H_u(s) = σ_u·√(2L_u/(πV)) / (1 + (L_u/V)·s)`
//! - `H_v(s) = σ_v·√(L_v/(πV))·(1 + √3·(L_v/V)·s) / (1 + (L_v/V)·s)²`, and `H_w` likewise
//!   with `L_w`, `σ_w`.
//!
//! The spectra are the spec's one-sided spectra over ω ∈ [0, ∞) in rad/s; with that convention
//! "unit white noise" has intensity π (two-sided, per rad/s… i.e. E[n(t)n(t+τ)] = π·δ(τ)),
//! which makes each filter output's variance exactly σ². Each filter is discretised exactly at
//! the caller's `dt` (zero-order hold on the state transition, Van Loan for the noise
//! covariance), so the variance is right whatever `dt` and V are. Coefficients are recomputed
//! when V, h or dt change by more than 0.5 %.
//!
//! Height: the low-altitude model is specified for h below 1000 ft (above that the spec's
//! medium/high-altitude model applies, with L = 1750 ft); we clamp h to 1000 ft. As h → 0 the
//! scale lengths vanish and the filters become singular, so h is also clamped to ≥ 3 ft (a floor
//! chosen for the simulator — a multirotor sitting on the ground is outside the model's range
//! anyway).
//!
//! Convection speed: `V` is the vehicle's speed through the frozen turbulence field, i.e.
//! relative to the **mean** air at its own height, `V = max(|v − w_mean(h)|, 1 m/s)` (Taylor's
//! frozen-turbulence hypothesis: the field moves with the local mean wind; in hover it sweeps
//! past at the mean wind speed, as rotorcraft turbulence models convect it — the 1 m/s floor
//! keeps the time constants finite in calm hover). The gusts are not part of `V` (the spec's
//! `V` is the mean airspeed the spatial spectrum is converted with), and the mean is the
//! shear law's at `h`, not the 20-ft value: near the ground the air, and with it the gust
//! pattern, moves slower (at 0.4 m about 0.44× the 20-ft wind), so a hovering vehicle's gusts
//! there last longer, not shorter. Until 2026-11-28 `V` was `max(airspeed, 20-ft mean, 1)`,
//! which swept the ground-level field past at the 20-ft speed plus the gust itself.
//!
//! Axes: u along the mean-wind direction (the way the air moves), v horizontal and 90° to the
//! right of u (seen from above), w down; rotated into NED. With no mean wind, u points along
//! the configured direction anyway.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;

const FT_PER_M: f64 = 1.0 / 0.3048;
const MPS_PER_KT: f64 = 1852.0 / 3600.0;
/// Lower clamp of the height used in the Dryden formulas, ft.
pub const DRYDEN_MIN_HEIGHT_FT: f64 = 3.0;
/// Upper end of the MIL-F-8785C low-altitude model, ft.
pub const DRYDEN_MAX_HEIGHT_FT: f64 = 1000.0;
/// Light turbulence W20, kt.
pub const W20_LIGHT_KT: f64 = 15.0;
/// Moderate turbulence W20, kt.
pub const W20_MODERATE_KT: f64 = 30.0;

/// Wind configuration. Default: calm, no turbulence.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WindParams {
    /// Mean horizontal wind speed, m/s.
    pub mean_speed_mps: f64,
    /// Meteorological direction: where the wind blows FROM, degrees clockwise from north.
    pub from_direction_deg: f64,
    /// Wind speed at 20 ft that sets the turbulence intensity, knots (0 = no turbulence;
    /// 15 = light, 30 = moderate, 45 = severe).
    pub w20_kt: f64,
    /// Roughness length of the MIL-F-8785C wind-shear law, m: the mean wind at height `h` is
    /// `mean_speed_mps·ln(h/z0)/ln(20 ft/z0)` (`mean_speed_mps` is the wind at 20 ft, the
    /// spec's W20 height); `z0` = 0.15 ft (0.046 m) for category C flight phases (terminal:
    /// take-off, approach, landing), the spec's value for flight near the ground. 0 = no
    /// shear (the same mean wind at every height).
    pub shear_z0_m: f64,
}

impl Default for WindParams {
    /// Calm, no turbulence, the category C shear law.
    fn default() -> Self {
        Self {
            mean_speed_mps: 0.0,
            from_direction_deg: 0.0,
            w20_kt: 0.0,
            shear_z0_m: SHEAR_Z0_CAT_C_M,
        }
    }
}

/// MIL-F-8785C wind-shear roughness length for category C flight phases: 0.15 ft, in m.
pub const SHEAR_Z0_CAT_C_M: f64 = 0.15 * 0.3048;
/// The shear law's reference height (20 ft), m.
const SHEAR_REF_M: f64 = 20.0 * 0.3048;

/// Mean-wind factor of the shear law at `height_m` (1 at 20 ft; 0 at or below `z0`).
pub fn shear_factor(height_m: f64, z0_m: f64) -> f64 {
    if z0_m <= 0.0 {
        return 1.0;
    }
    let h = height_m.min(DRYDEN_MAX_HEIGHT_FT / FT_PER_M);
    if h <= z0_m {
        return 0.0;
    }
    (h / z0_m).ln() / (SHEAR_REF_M / z0_m).ln()
}

/// Intensities (σ_u, σ_v, σ_w) in m/s and scale lengths (L_u, L_v, L_w) in m at `height_m`.
pub fn dryden_low_altitude(height_m: f64, w20_kt: f64) -> ([f64; 3], [f64; 3]) {
    let h_ft = (height_m * FT_PER_M).clamp(DRYDEN_MIN_HEIGHT_FT, DRYDEN_MAX_HEIGHT_FT);
    let k = 0.177 + 0.000823 * h_ft;
    let l_w_ft = h_ft;
    let l_uv_ft = h_ft / k.powf(1.2);
    let sigma_w = 0.1 * w20_kt.max(0.0) * MPS_PER_KT;
    let sigma_uv = sigma_w / k.powf(0.4);
    let l_uv = l_uv_ft / FT_PER_M;
    let l_w = l_w_ft / FT_PER_M;
    ([sigma_uv, sigma_uv, sigma_w], [l_uv, l_uv, l_w])
}

#[derive(Clone, Debug)]
struct Coeffs {
    key: (f64, f64, f64), // (V, h, dt) they were computed for
    sigma: [f64; 3],
    /// Per-step decay exp(−dt·V/L) for u, v, w.
    phi: [f64; 3],
}

/// Mean wind plus Dryden turbulence, deterministic from a seed.
#[derive(Clone, Debug)]
pub struct Wind {
    pub params: WindParams,
    rng: ChaCha8Rng,
    /// Unit-gain-normalised u state (its value is the u turbulence, m/s).
    u: f64,
    /// v and w: a unit-variance first-order Gauss–Markov state `g` (time constant T = L/V) and
    /// its first-order low-pass `z`; the Dryden form (1 + √3·Ts)/(1 + Ts)² is then
    /// `√3·g + (1 − √3)·z`, scaled to σ. Both states keep their physical scale when V or h
    /// change (a canonical-form realisation does not, and blows up when T shrinks).
    gz: [[f64; 2]; 2],
    coeffs: Option<Coeffs>,
    last_turbulence_uvw: Vector3<f64>,
}

impl Wind {
    pub fn new(p: WindParams, seed: u64) -> Self {
        Self {
            params: p,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x5749_4E44_0000_0001),
            u: 0.0,
            gz: [[0.0; 2]; 2],
            coeffs: None,
            last_turbulence_uvw: Vector3::zeros(),
        }
    }

    /// Mean wind velocity, NED, m/s (the direction the air moves).
    pub fn mean_ned_mps(&self) -> Vector3<f64> {
        let d = self.params.from_direction_deg.to_radians();
        -self.params.mean_speed_mps * Vector3::new(d.cos(), d.sin(), 0.0)
    }

    /// Turbulence of the last step in (u along-wind, v lateral-right, w down), m/s.
    pub fn last_turbulence_uvw_mps(&self) -> Vector3<f64> {
        self.last_turbulence_uvw
    }

    fn coeffs_for(&mut self, v: f64, h: f64, dt: f64) -> Coeffs {
        if let Some(c) = &self.coeffs {
            let close = |a: f64, b: f64| (a - b).abs() <= 0.005 * b.abs().max(1e-9);
            if close(v, c.key.0) && close(h, c.key.1) && close(dt, c.key.2) {
                return c.clone();
            }
        }
        let (sigma, l) = dryden_low_altitude(h, self.params.w20_kt);
        let phi = [
            (-v / l[0] * dt).exp(),
            (-v / l[1] * dt).exp(),
            (-v / l[2] * dt).exp(),
        ];
        let c = Coeffs {
            key: (v, h, dt),
            sigma,
            phi,
        };
        self.coeffs = Some(c.clone());
        c
    }

    /// Advance by `dt_s` and return the wind velocity (mean + turbulence), NED, m/s.
    /// `height_m` is height above ground, `vel_ned_mps` the vehicle's velocity over the ground.
    pub fn step(&mut self, height_m: f64, vel_ned_mps: Vector3<f64>, dt_s: f64) -> Vector3<f64> {
        let mean = self.mean_ned_mps() * shear_factor(height_m, self.params.shear_z0_m);
        if self.params.w20_kt <= 0.0 || dt_s.is_nan() || dt_s <= 0.0 {
            self.last_turbulence_uvw = Vector3::zeros();
            return mean;
        }
        // Speed through the frozen field: relative to the mean air at this height.
        let v = (vel_ned_mps - mean).norm().max(1.0);
        let h_m = height_m.max(DRYDEN_MIN_HEIGHT_FT / FT_PER_M);
        let c = self.coeffs_for(v, h_m, dt_s);

        // u: first-order Gauss–Markov, exact: u' = φu + σ√(1−φ²)·n.
        let n: f64 = StandardNormal.sample(&mut self.rng);
        let pu = c.phi[0];
        self.u = pu * self.u + c.sigma[0] * (1.0 - pu * pu).max(0.0).sqrt() * n;

        // v, w: H = σ·√(L/(πV))·(1 + √3·Ts)/(1 + Ts)². With g a unit-variance Gauss–Markov
        // process of time constant T, (1 + √3·Ts)/(1 + Ts)·g = √3·g + (1 − √3)·LP_T(g) has
        // variance 2 (g is white of PSD 2T through 1/(1 + Ts): ∫(1+3x²)/(1+x²)² dx/π = 2),
        // hence the σ/√2 scale.
        let mut out = [0.0; 2];
        for k in 0..2 {
            let ph = c.phi[k + 1];
            let n: f64 = StandardNormal.sample(&mut self.rng);
            let [g, z] = &mut self.gz[k];
            *g = ph * *g + (1.0 - ph * ph).max(0.0).sqrt() * n;
            *z = ph * *z + (1.0 - ph) * *g;
            out[k] = c.sigma[k + 1] / 2f64.sqrt() * (3f64.sqrt() * *g + (1.0 - 3f64.sqrt()) * *z);
        }
        let uvw = Vector3::new(self.u, out[0], out[1]);
        self.last_turbulence_uvw = uvw;

        // Rotate: u along the direction the wind blows to, v 90° clockwise from it, w down.
        let to = (self.params.from_direction_deg + 180.0).to_radians();
        let (s, co) = to.sin_cos();
        let n_comp = uvw.x * co - uvw.y * s;
        let e_comp = uvw.x * s + uvw.y * co;
        mean + Vector3::new(n_comp, e_comp, uvw.z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn std_of(v: &[f64]) -> f64 {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / v.len() as f64).sqrt()
    }

    #[test]
    fn calm_and_mean_direction() {
        let mut w = Wind::new(
            WindParams {
                mean_speed_mps: 5.0,
                from_direction_deg: 0.0,
                w20_kt: 0.0,
                shear_z0_m: 0.0,
            },
            1,
        );
        for _ in 0..100 {
            let v = w.step(10.0, Vector3::zeros(), 0.002);
            assert_eq!(v, Vector3::new(-5.0, 0.0, 0.0)); // from north → towards south
        }
        let mut w = Wind::new(
            WindParams {
                mean_speed_mps: 4.0,
                from_direction_deg: 270.0,
                w20_kt: 0.0,
                shear_z0_m: 0.0,
            },
            1,
        );
        let v = w.step(10.0, Vector3::zeros(), 0.002);
        assert!((v - Vector3::new(0.0, 4.0, 0.0)).norm() < 1e-9, "{v:?}"); // from west → east
    }

    #[test]
    fn dryden_figures() {
        // h = 1000 ft: k = 1.0 → L_u = L_w = 1000 ft, σ_u = σ_w.
        let (s, l) = dryden_low_altitude(1000.0 * 0.3048, 15.0);
        assert!((l[0] - 304.8).abs() < 1e-6 && (l[2] - 304.8).abs() < 1e-6);
        assert!((s[2] - 1.5 * MPS_PER_KT).abs() < 1e-12 && (s[0] - s[2]).abs() < 1e-9);
        // Low altitude: σ_u > σ_w, L_u > L_w.
        let (s, l) = dryden_low_altitude(10.0, 15.0);
        assert!(s[0] > s[2] && l[0] > l[2]);
    }

    #[test]
    fn turbulence_std_matches_sigma() {
        let p = WindParams {
            mean_speed_mps: 3.0,
            from_direction_deg: 30.0,
            w20_kt: W20_LIGHT_KT,
            shear_z0_m: 0.0,
        };
        let mut w = Wind::new(p.clone(), 42);
        let (h, v, dt) = (10.0, Vector3::new(15.0, 0.0, 0.0), 0.01);
        let (sigma, l) = dryden_low_altitude(h, p.w20_kt);
        let n = 400_000; // 4000 s ≈ 900 correlation times of u
        let mut us = Vec::with_capacity(n);
        let mut vs = Vec::with_capacity(n);
        let mut ws = Vec::with_capacity(n);
        for _ in 0..n {
            w.step(h, v, dt);
            let t = w.last_turbulence_uvw_mps();
            us.push(t.x);
            vs.push(t.y);
            ws.push(t.z);
        }
        let (su, sv, sw) = (std_of(&us), std_of(&vs), std_of(&ws));
        assert!(
            (su / sigma[0] - 1.0).abs() < 0.15,
            "σu {su} vs {} (L {})",
            sigma[0],
            l[0]
        );
        assert!(
            (sv / sigma[1] - 1.0).abs() < 0.15,
            "σv {sv} vs {}",
            sigma[1]
        );
        assert!(
            (sw / sigma[2] - 1.0).abs() < 0.15,
            "σw {sw} vs {}",
            sigma[2]
        );
    }

    /// Near the ground a hovering vehicle's gusts decorrelate at the local mean wind's pace
    /// (the frozen field moves with the sheared mean), not the 20-ft wind's: the u
    /// autocorrelation at lag τ is exp(−τ·V/L_u) with V = the mean at that height.
    #[test]
    fn gusts_near_the_ground_move_with_the_local_mean_wind() {
        let p = WindParams {
            mean_speed_mps: 7.0,
            from_direction_deg: 0.0,
            w20_kt: W20_MODERATE_KT,
            shear_z0_m: SHEAR_Z0_CAT_C_M,
        };
        let (h, dt, lag_s) = (0.5, 0.01, 0.5);
        let mut w = Wind::new(p.clone(), 3);
        let us: Vec<f64> = (0..600_000)
            .map(|_| {
                w.step(h, Vector3::zeros(), dt);
                w.last_turbulence_uvw_mps().x
            })
            .collect();
        let k = (lag_s / dt) as usize;
        let m = us.iter().sum::<f64>() / us.len() as f64;
        let var = us.iter().map(|u| (u - m) * (u - m)).sum::<f64>();
        let cov = us
            .windows(k + 1)
            .map(|x| (x[0] - m) * (x[k] - m))
            .sum::<f64>();
        let rho = cov / var;
        let (_, l) = dryden_low_altitude(h, p.w20_kt);
        let v_local = p.mean_speed_mps * shear_factor(h, p.shear_z0_m);
        let expect = (-lag_s * v_local / l[0]).exp();
        let at_20ft_speed = (-lag_s * p.mean_speed_mps / l[0]).exp();
        assert!((rho - expect).abs() < 0.05, "ρ {rho} vs {expect}");
        assert!(
            rho - at_20ft_speed > 0.1,
            "ρ {rho} vs 20-ft {at_20ft_speed}"
        );
    }

    #[test]
    fn deterministic_and_rotated() {
        let p = WindParams {
            mean_speed_mps: 2.0,
            from_direction_deg: 90.0,
            w20_kt: 15.0,
            shear_z0_m: 0.0,
        };
        let mut a = Wind::new(p.clone(), 7);
        let mut b = Wind::new(p.clone(), 7);
        let mut c = Wind::new(p, 8);
        let mut diff = 0.0;
        for _ in 0..1000 {
            let x = a.step(5.0, Vector3::zeros(), 0.002);
            assert_eq!(x, b.step(5.0, Vector3::zeros(), 0.002));
            diff += (x - c.step(5.0, Vector3::zeros(), 0.002)).norm();
            // from east → u towards west (−E); v to the right of west = north.
            let t = a.last_turbulence_uvw_mps();
            let m = Vector3::new(0.0, -2.0, 0.0);
            assert!((x - m - Vector3::new(t.y, -t.x, t.z)).norm() < 1e-9);
        }
        assert!(diff > 0.0);
    }
}
