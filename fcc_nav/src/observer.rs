//! Luenberger linear-acceleration observer (paper A, eqs. 10–14).
//!
//! Model (per axis, heading frame): `a_x = k1·θ − k2·v_x` (eq. 11), so `ȧ_x = k1·θ̇ − k2·a_x`;
//! the attitude loop is modelled first order, `θ̇ = −a·θ + b·θ_cmd`. Observer:
//!
//! ```text
//! â̇ = k1·(−a·θ + b·θ_cmd) − k2·â + L·(a_meas − â)
//! ```
//!
//! `θ` is the tilt that accelerates the vehicle in +x (for the north/forward axis with FRD
//! and ZYX angles that is −pitch; the caller handles the sign).
//!
//! Discretisation: with the inputs held over the step the equation is linear first order in
//! `â`, `â̇ = f − (k2 + L)·â + L·a_meas`, and is integrated exactly (zero-order hold):
//! `â ← α·â + (1 − α)·(f + L·a_meas)/(k2 + L)`, `α = exp(−(k2 + L)·dt)`; forward Euler if
//! `k2 + L` is ~0.

use crate::math::expf;

/// Observer parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelObserverParams {
    /// Tilt-to-acceleration gain k1 \[m/s² per rad].
    pub k1_mps2_per_rad: f32,
    /// Linear drag coefficient k2 \[1/s].
    pub k2_per_s: f32,
    /// Attitude-loop pole a \[1/s] (`θ̇ = −a·θ + b·θ_cmd`).
    pub att_a_per_s: f32,
    /// Attitude-loop input gain b \[1/s].
    pub att_b_per_s: f32,
    /// Observer gain L \[1/s].
    pub gain_l_per_s: f32,
}

/// Luenberger observer of one axis of linear acceleration.
#[derive(Clone, Copy, Debug)]
pub struct AccelObserver {
    /// Parameters (may be changed on the fly).
    pub params: AccelObserverParams,
    accel_mps2: f32,
}

impl AccelObserver {
    /// New observer with estimate 0.
    pub fn new(p: AccelObserverParams) -> Self {
        Self {
            params: p,
            accel_mps2: 0.0,
        }
    }

    /// Set the acceleration estimate \[m/s²].
    pub fn reset(&mut self, a_mps2: f32) {
        self.accel_mps2 = a_mps2;
    }

    /// One step; returns the new estimate \[m/s²].
    pub fn update(
        &mut self,
        tilt_rad: f32,
        tilt_cmd_rad: f32,
        accel_meas_mps2: f32,
        dt_s: f32,
    ) -> f32 {
        let p = &self.params;
        let f = p.k1_mps2_per_rad * (-p.att_a_per_s * tilt_rad + p.att_b_per_s * tilt_cmd_rad);
        let lam = p.k2_per_s + p.gain_l_per_s;
        let drive = f + p.gain_l_per_s * accel_meas_mps2;
        if lam.abs() * dt_s < 1e-6 {
            self.accel_mps2 += (drive - lam * self.accel_mps2) * dt_s;
        } else {
            let alpha = expf(-lam * dt_s);
            self.accel_mps2 = alpha * self.accel_mps2 + (1.0 - alpha) * drive / lam;
        }
        self.accel_mps2
    }

    /// Current estimate \[m/s²].
    pub fn accel_mps2(&self) -> f32 {
        self.accel_mps2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Rng;

    const DT: f32 = 0.002;

    fn params() -> AccelObserverParams {
        AccelObserverParams {
            k1_mps2_per_rad: 9.0,
            k2_per_s: 0.3,
            att_a_per_s: 8.0,
            att_b_per_s: 8.0,
            gain_l_per_s: 10.0,
        }
    }

    /// Simulated plant: θ̇ = −aθ + bθ_cmd, v̇ = k1θ − k2v; returns (est err std, raw err std,
    /// final truth, final estimate).
    fn run(theta_cmd: impl Fn(f32) -> f32, noise: f32, secs: f32) -> (f32, f32, f32, f32) {
        let p = params();
        let mut rng = Rng::new(9);
        let mut obs = AccelObserver::new(p);
        let (mut th, mut v) = (0.0f32, 0.0f32);
        let (mut se, mut sr, mut n) = (0.0f64, 0.0f64, 0usize);
        let mut a_true = 0.0;
        for k in 0..(secs / DT) as usize {
            let t = k as f32 * DT;
            let cmd = theta_cmd(t);
            // sub-stepped truth
            for _ in 0..10 {
                let h = DT / 10.0;
                th += (-p.att_a_per_s * th + p.att_b_per_s * cmd) * h;
                v += (p.k1_mps2_per_rad * th - p.k2_per_s * v) * h;
            }
            a_true = p.k1_mps2_per_rad * th - p.k2_per_s * v;
            let meas = a_true + rng.normal(noise);
            let est = obs.update(th, cmd, meas, DT);
            if t > 1.0 {
                se += ((est - a_true) as f64).powi(2);
                sr += ((meas - a_true) as f64).powi(2);
                n += 1;
            }
        }
        (
            (se / n as f64).sqrt() as f32,
            (sr / n as f64).sqrt() as f32,
            a_true,
            obs.accel_mps2(),
        )
    }

    #[test]
    fn reduces_noise_vs_raw() {
        let cmd = |t: f32| {
            0.1 * crate::math::sinf(1.3 * t) + if (t as i32) % 4 < 2 { 0.05 } else { -0.05 }
        };
        let (est, raw, _, _) = run(cmd, 1.0, 30.0);
        assert!((raw - 1.0).abs() < 0.05, "raw {raw}");
        std::println!("observer: est err std {est}, raw {raw}");
        assert!(est < 0.3 * raw, "est {est} raw {raw}");
    }

    #[test]
    fn tracks_step_in_tilt_command() {
        let cmd = |t: f32| if t > 1.0 { 0.1 } else { 0.0 };
        // noiseless: estimate equals truth throughout (model is exact)
        let (est, _, truth, fin) = run(cmd, 0.0, 3.0);
        assert!(est < 0.02, "err std {est}");
        assert!((fin - truth).abs() < 0.01);
        // 2 s after the step the acceleration is still near k1·0.1 minus drag
        assert!(truth > 0.5);
    }

    #[test]
    fn converges_from_wrong_start_at_rate_k2_plus_l() {
        let mut obs = AccelObserver::new(params());
        obs.reset(5.0);
        let lam = params().k2_per_s + params().gain_l_per_s;
        let steps = (1.0 / lam / DT) as usize;
        for _ in 0..steps {
            obs.update(0.0, 0.0, 0.0, DT);
        }
        let want = 5.0 * (-(steps as f32) * DT * lam).exp();
        assert!(
            (obs.accel_mps2() - want).abs() < 1e-3,
            "{} vs {want}",
            obs.accel_mps2()
        );
    }

    #[test]
    fn sign_of_model_feedforward() {
        // commanding positive tilt from rest drives the estimate positive even with L = 0
        let mut p = params();
        p.gain_l_per_s = 0.0;
        let mut obs = AccelObserver::new(p);
        obs.update(0.0, 0.1, 0.0, DT);
        assert!(obs.accel_mps2() > 0.0);
    }
}
