//! Test-only helpers: a small deterministic Gaussian noise source (no external crates).

/// xorshift64* generator with Box–Muller normal samples.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    /// Uniform in (0, 1].
    pub fn uniform(&mut self) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        let r = x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11;
        (r as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// Zero-mean normal sample with standard deviation `std`.
    pub fn normal(&mut self, std: f32) -> f32 {
        let u1 = self.uniform();
        let u2 = self.uniform();
        let n = libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(2.0 * core::f64::consts::PI * u2);
        (n as f32) * std
    }
}
