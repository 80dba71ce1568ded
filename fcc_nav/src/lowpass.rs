//! Second-order Butterworth low-pass (biquad, bilinear transform with pre-warping), the filter
//! flight stacks put on the accelerometer before computing tilt angles: averaging ±g-scale
//! motor vibration *before* the non-linear `asin`/`atan2` of the tilt equations avoids the bias
//! those functions produce on noisy input (a few degrees at 3 m/s² RMS vibration).

use core::f32::consts::PI;

/// Second-order Butterworth low-pass biquad (state and coefficients).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LowPass2 {
    b: [f32; 3],
    a: [f32; 2],
    x: [f32; 2],
    y: [f32; 2],
    primed: bool,
}

impl LowPass2 {
    /// Cut-off `cutoff_hz` at sample rate `sample_hz` (cut-off clamped below Nyquist).
    pub fn new(cutoff_hz: f32, sample_hz: f32) -> Self {
        let fc = crate::math::clampf(cutoff_hz, 1e-3, 0.45 * sample_hz);
        let k = crate::math::tanf(PI * fc / sample_hz);
        let q = core::f32::consts::FRAC_1_SQRT_2;
        let norm = 1.0 / (1.0 + k / q + k * k);
        let b0 = k * k * norm;
        Self {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm],
            x: [0.0; 2],
            y: [0.0; 2],
            primed: false,
        }
    }

    /// Start from steady state at `v`.
    pub fn reset(&mut self, v: f32) {
        self.x = [v; 2];
        self.y = [v; 2];
        self.primed = true;
    }

    /// Filter one sample (the first sample primes the state to steady state).
    pub fn update(&mut self, x: f32) -> f32 {
        if !self.primed {
            self.reset(x);
        }
        let y = self.b[0] * x + self.b[1] * self.x[0] + self.b[2] * self.x[1]
            - self.a[0] * self.y[0]
            - self.a[1] * self.y[1];
        self.x = [x, self.x[0]];
        self.y = [y, self.y[0]];
        y
    }

    /// Last output.
    pub fn output(&self) -> f32 {
        self.y[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_dc_and_attenuates_vibration() {
        let mut f = LowPass2::new(10.0, 500.0);
        let mut peak: f32 = 0.0;
        for k in 0..5000 {
            let t = k as f32 * 0.002;
            let y = f.update(1.0 + 3.0 * crate::math::sinf(2.0 * PI * 100.0 * t));
            if k > 1000 {
                peak = peak.max((y - 1.0).abs());
            }
        }
        // 2nd order: (10/100)² → about 1 % of the 3.0 amplitude.
        assert!(peak < 0.05, "residual vibration {peak}");
        assert!((f.output() - 1.0).abs() < 0.05);
    }

    #[test]
    fn minus_3db_at_cutoff() {
        let mut f = LowPass2::new(20.0, 500.0);
        let mut peak: f32 = 0.0;
        for k in 0..20_000 {
            let y = f.update(crate::math::sinf(2.0 * PI * 20.0 * k as f32 * 0.002));
            if k > 10_000 {
                peak = peak.max(y.abs());
            }
        }
        assert!(
            (peak - core::f32::consts::FRAC_1_SQRT_2).abs() < 0.02,
            "{peak}"
        );
    }
}
