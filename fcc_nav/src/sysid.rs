//! "3D curve fitting" (paper A, Fig. 12): streaming least-squares fit of the plane
//! `a = k1·θ − k2·v` (no intercept) to flight samples (tilt, velocity, acceleration).
//!
//! Only running sums are kept (in `f64`), so it is heap-free and O(1) per sample.

use libm::sqrt;

/// Result of a plane fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneFitResult {
    /// Tilt-to-acceleration gain k1 \[m/s² per rad].
    pub k1_mps2_per_rad: f32,
    /// Linear drag coefficient k2 \[1/s].
    pub k2_per_s: f32,
    /// RMS of the residuals \[m/s²].
    pub rms_residual_mps2: f32,
    /// Coefficient of determination (vs the mean of `a`), 1 = perfect.
    pub r_squared: f32,
}

/// Streaming least-squares accumulator.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlaneFit {
    n: u32,
    s_tt: f64,
    s_tv: f64,
    s_vv: f64,
    s_ta: f64,
    s_va: f64,
    s_aa: f64,
    s_a: f64,
}

impl PlaneFit {
    /// Empty accumulator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add one sample: tilt \[rad], velocity \[m/s], acceleration \[m/s²].
    pub fn add(&mut self, tilt_rad: f32, vel_mps: f32, accel_mps2: f32) {
        let (t, v, a) = (tilt_rad as f64, vel_mps as f64, accel_mps2 as f64);
        self.n = self.n.saturating_add(1);
        self.s_tt += t * t;
        self.s_tv += t * v;
        self.s_vv += v * v;
        self.s_ta += t * a;
        self.s_va += v * a;
        self.s_aa += a * a;
        self.s_a += a;
    }

    /// Number of samples added.
    pub fn count(&self) -> u32 {
        self.n
    }

    /// Solve the normal equations. `None` with fewer than 3 samples or when tilt and velocity
    /// are (nearly) collinear or constant zero (normalised determinant < 1e−6).
    pub fn solve(&self) -> Option<PlaneFitResult> {
        if self.n < 3 {
            return None;
        }
        let det = self.s_tt * self.s_vv - self.s_tv * self.s_tv;
        let scale = self.s_tt * self.s_vv;
        if scale.is_nan() || scale <= 0.0 || det <= 1e-6 * scale {
            return None;
        }
        // [s_tt s_tv; s_tv s_vv]·[k1; c] = [s_ta; s_va], c = −k2
        let k1 = (self.s_ta * self.s_vv - self.s_tv * self.s_va) / det;
        let c = (self.s_tt * self.s_va - self.s_tv * self.s_ta) / det;
        let n = self.n as f64;
        let ssr = (self.s_aa - k1 * self.s_ta - c * self.s_va).max(0.0);
        let sst = self.s_aa - self.s_a * self.s_a / n;
        let r2 = if sst > 0.0 { 1.0 - ssr / sst } else { 1.0 };
        Some(PlaneFitResult {
            k1_mps2_per_rad: k1 as f32,
            k2_per_s: -c as f32,
            rms_residual_mps2: sqrt(ssr / n) as f32,
            r_squared: r2 as f32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Rng;

    #[test]
    fn recovers_k1_k2_from_noisy_samples() {
        let mut rng = Rng::new(21);
        let mut fit = PlaneFit::new();
        let (k1, k2) = (9.5f32, 0.35f32);
        for _ in 0..5000 {
            let th = rng.normal(0.15);
            let v = rng.normal(4.0);
            fit.add(th, v, k1 * th - k2 * v + rng.normal(0.3));
        }
        assert_eq!(fit.count(), 5000);
        let r = fit.solve().unwrap();
        assert!((r.k1_mps2_per_rad - k1).abs() < 0.1, "{r:?}");
        assert!((r.k2_per_s - k2).abs() < 0.01, "{r:?}");
        assert!((r.rms_residual_mps2 - 0.3).abs() < 0.02, "{r:?}");
        assert!(r.r_squared > 0.9 && r.r_squared <= 1.0, "{r:?}");
    }

    #[test]
    fn exact_data_exact_fit() {
        let mut fit = PlaneFit::new();
        for i in 0..10 {
            let th = 0.01 * i as f32;
            let v = 0.5 * ((i * 7) % 5) as f32;
            fit.add(th, v, 8.0 * th - 0.2 * v);
        }
        let r = fit.solve().unwrap();
        assert!((r.k1_mps2_per_rad - 8.0).abs() < 1e-4);
        assert!((r.k2_per_s - 0.2).abs() < 1e-5);
        assert!(r.rms_residual_mps2 < 1e-4);
    }

    #[test]
    fn ill_conditioned_is_none() {
        let mut fit = PlaneFit::new();
        assert!(fit.solve().is_none());
        // v proportional to θ: collinear
        for i in 0..100 {
            let th = 0.01 * i as f32;
            fit.add(th, 3.0 * th, th);
        }
        assert!(fit.solve().is_none());
        // velocity always zero
        let mut fit = PlaneFit::new();
        for i in 0..100 {
            fit.add(0.01 * i as f32, 0.0, 0.1 * i as f32);
        }
        assert!(fit.solve().is_none());
    }
}
