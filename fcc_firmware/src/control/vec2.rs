//! Two small helpers on horizontal 2-vectors that the cascade and the mode logic share.

/// `v` scaled down to length `max` when longer (direction kept); unchanged otherwise.
pub fn clamp_norm(v: [f32; 2], max: f32) -> [f32; 2] {
    let n = fcc_nav::math::hypotf(v[0], v[1]);
    if n > max && n > 0.0 {
        [v[0] * max / n, v[1] * max / n]
    } else {
        v
    }
}

/// +1, −1 or 0 (for 0 and NaN): the side on which a limit is active, for anti-windup.
pub fn sign_or_zero(x: f32) -> f32 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_keeps_direction_and_short_vectors() {
        assert_eq!(clamp_norm([3.0, 4.0], 10.0), [3.0, 4.0]);
        let v = clamp_norm([3.0, 4.0], 1.0);
        assert!(
            (v[0] - 0.6).abs() < 1e-6 && (v[1] - 0.8).abs() < 1e-6,
            "{v:?}"
        );
        assert_eq!(clamp_norm([0.0, 0.0], 0.0), [0.0, 0.0]);
    }

    #[test]
    fn sign() {
        assert_eq!(sign_or_zero(2.0), 1.0);
        assert_eq!(sign_or_zero(-0.1), -1.0);
        assert_eq!(sign_or_zero(0.0), 0.0);
        assert_eq!(sign_or_zero(f32::NAN), 0.0);
    }
}
