//! The heading frame the horizontal loops work in: NED's north/east rotated by the yaw ψ, axes
//! forward and right (level, so roll and pitch do not enter). The one place the rotation is
//! written: `fr = R(−ψ)·ne`, `ne = R(ψ)·fr`.

/// The rotation by one heading (its sine and cosine, computed once).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Heading {
    sin: f32,
    cos: f32,
}

impl Heading {
    pub fn new(yaw_rad: f32) -> Self {
        let (sin, cos) = fcc_nav::math::sincosf(yaw_rad);
        Self { sin, cos }
    }

    /// NED (north, east) → heading frame (forward, right).
    pub fn to_fr(&self, ne: [f32; 2]) -> [f32; 2] {
        let (s, c) = (self.sin, self.cos);
        [c * ne[0] + s * ne[1], -s * ne[0] + c * ne[1]]
    }

    /// Heading frame (forward, right) → NED (north, east).
    pub fn to_ne(&self, fr: [f32; 2]) -> [f32; 2] {
        let (s, c) = (self.sin, self.cos);
        [c * fr[0] - s * fr[1], s * fr[0] + c * fr[1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heading_east_turns_north_into_left() {
        let h = Heading::new(core::f32::consts::FRAC_PI_2);
        let fr = h.to_fr([1.0, 0.0]);
        assert!((fr[0]).abs() < 1e-6 && (fr[1] + 1.0).abs() < 1e-6, "{fr:?}");
        let ne = h.to_ne([1.0, 0.0]);
        assert!((ne[0]).abs() < 1e-6 && (ne[1] - 1.0).abs() < 1e-6, "{ne:?}");
    }

    #[test]
    fn round_trip() {
        for k in 0..16 {
            let h = Heading::new(k as f32 * 0.4 - 3.0);
            let v = [1.5, -0.7];
            let back = h.to_ne(h.to_fr(v));
            assert!((back[0] - v[0]).abs() < 1e-6 && (back[1] - v[1]).abs() < 1e-6);
        }
    }
}
