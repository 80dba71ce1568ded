//! PI with a forgetting factor as anti-windup (paper A eqs. 16–17): `I_k = λ·I_{k−1} + e_k·Δt`,
//! `u = Kp·e + Ki·I`, with the integrator clamped to `±i_limit / Ki` and frozen while the output
//! is saturated in the direction of the error.

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForgettingPi {
    pub kp: f32,
    pub ki: f32,
    /// λ in (0, 1]; 1 = plain integrator.
    pub forgetting: f32,
    /// Bound on the integral term's contribution `|Ki·I|`.
    pub i_limit: f32,
    integral: f32,
}

impl ForgettingPi {
    pub const fn new(kp: f32, ki: f32, forgetting: f32, i_limit: f32) -> Self {
        Self {
            kp,
            ki,
            forgetting,
            i_limit,
            integral: 0.0,
        }
    }

    pub fn reset(&mut self) {
        self.integral = 0.0;
    }

    /// One step. `saturated_sign`: +1 if the downstream output is saturated high, −1 low, 0 not;
    /// the integral does not grow further in the saturated direction.
    pub fn update(&mut self, error: f32, dt_s: f32, saturated_sign: f32) -> f32 {
        if !error.is_finite() || !dt_s.is_finite() {
            return self.kp * 0.0 + self.ki * self.integral;
        }
        let growing = error * saturated_sign > 0.0;
        let mut i = self.forgetting * self.integral;
        if !growing {
            i += error * dt_s;
        }
        if self.ki > 0.0 {
            let lim = self.i_limit / self.ki;
            i = fcc_nav::math::clampf(i, -lim, lim);
        }
        self.integral = i;
        self.kp * error + self.ki * self.integral
    }

    /// The integral term's present contribution `Ki·I`.
    pub fn integral_term(&self) -> f32 {
        self.ki * self.integral
    }

    /// Preload the integral term (e.g. the hover thrust found on the ground).
    pub fn set_integral_term(&mut self, term: f32) {
        if self.ki > 0.0 {
            self.integral = term / self.ki;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forgetting_factor_bounds_integral_under_constant_error() {
        let mut pi = ForgettingPi::new(0.0, 1.0, 0.99, 1e9);
        for _ in 0..10_000 {
            pi.update(1.0, 0.01, 0.0);
        }
        // Steady state of I = λI + e·dt is e·dt/(1−λ) = 1.
        assert!(
            (pi.integral_term() - 1.0).abs() < 1e-3,
            "{}",
            pi.integral_term()
        );
    }

    #[test]
    fn plain_integrator_when_lambda_is_one() {
        let mut pi = ForgettingPi::new(2.0, 0.5, 1.0, 1e9);
        let mut u = 0.0;
        for _ in 0..100 {
            u = pi.update(1.0, 0.01, 0.0);
        }
        assert!((u - (2.0 + 0.5 * 1.0)).abs() < 1e-4, "{u}");
    }

    #[test]
    fn saturation_stops_windup_in_that_direction_only() {
        let mut pi = ForgettingPi::new(0.0, 1.0, 1.0, 1e9);
        pi.update(1.0, 1.0, 1.0);
        assert_eq!(pi.integral_term(), 0.0);
        pi.update(-1.0, 1.0, 1.0);
        assert_eq!(pi.integral_term(), -1.0);
    }
}
