//! Fixed-point wire encodings: an `f32` field whose resolution is known travels as
//! little-endian `i16` counts of that resolution (2 bytes, fixed layout: no varint) instead of
//! a 4-byte float. The structs keep `f32` in SI units; only the wire changes.
//!
//! `count = round(v / lsb)`, saturated to ±32767; NaN travels as −32768 and comes back as
//! NaN; decoding gives `count · lsb`. A value that was a multiple of `lsb` (a sensor's output)
//! round-trips exactly up to `f32` rounding; anything else is rounded to the nearest count.
//!
//! | encoding | LSB | range | source of the resolution |
//! |---|---|---|---|
//! | [`gyro`] | 2000 °/s / 32768 = 1.065·10⁻³ rad/s | ±34.9 rad/s | MPU-9250 at ±2000 °/s, 16.4 LSB/(°/s) (PS-MPU-9250A-01 §3.1, the board's setting) |
//! | [`accel`] | 16 g / 32768 = 4.788·10⁻³ m/s² | ±156.9 m/s² | MPU-9250 at ±16 g, 2048 LSB/g (PS §3.2, the board's setting) |
//! | [`mag`] | 0.15 µT | ±4915 µT | AK8963 (the MPU-9250's magnetometer) at 16-bit output, 0.15 µT/LSB |
//! | [`unit`] | 1/32767 | ±1 | a unit quaternion's components (≤ 0.0035° of attitude) |
//! | [`vel`] | 2 mm/s | ±65.5 m/s | estimated velocity: 15× below the GPS's 0.03 m/s noise |
//! | [`accel_est`] | 5 mm/s² | ±163.8 m/s² | estimated accelerations (noise ≈ 0.05 m/s²) |
//! | [`temp`] | 0.01 °C | ±327 °C | MS5611-01BA03 `TEMP`, 0.01 °C resolution |
//!
//! The simulator's IMU is configured finer (±8 g, ±1000 °/s); the link then rounds it to the
//! board's resolution, 0.03 °/s and 2.4 mm/s² at most — a tenth of the sensor noise.

use serde::de::{self, SeqAccess, Visitor};
use serde::ser::SerializeTuple;
use serde::{Deserializer, Serializer};

/// The count that stands for NaN.
pub const NAN_COUNT: i16 = i16::MIN;

/// `v` as a count of `lsb`: rounded half away from zero, saturated to ±32767, NaN → −32768.
pub fn to_count(v: f32, lsb: f32) -> i16 {
    if v.is_nan() {
        return NAN_COUNT;
    }
    let c = v / lsb;
    let r = if c >= 0.0 { c + 0.5 } else { c - 0.5 };
    // `as` saturates; the clamp keeps −32768 for NaN alone.
    (r.clamp(-32767.0, 32767.0)) as i16
}

/// A count of `lsb` as a value (−32768 → NaN).
pub fn from_count(c: i16, lsb: f32) -> f32 {
    if c == NAN_COUNT {
        f32::NAN
    } else {
        f32::from(c) * lsb
    }
}

/// Serialise `N` values as `N` little-endian `i16` counts (a tuple of `2N` bytes: postcard
/// writes them as they are).
pub fn serialize_array<S: Serializer, const N: usize>(
    v: &[f32; N],
    lsb: f32,
    s: S,
) -> Result<S::Ok, S::Error> {
    let mut t = s.serialize_tuple(2 * N)?;
    for x in v {
        let [lo, hi] = to_count(*x, lsb).to_le_bytes();
        t.serialize_element(&lo)?;
        t.serialize_element(&hi)?;
    }
    t.end()
}

/// The inverse of [`serialize_array`].
pub fn deserialize_array<'de, D: Deserializer<'de>, const N: usize>(
    d: D,
    lsb: f32,
) -> Result<[f32; N], D::Error> {
    struct Counts<const N: usize>(f32);
    impl<'de, const N: usize> Visitor<'de> for Counts<N> {
        type Value = [f32; N];
        fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
            write!(f, "{} little-endian i16 counts", N)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> Result<[f32; N], A::Error> {
            let mut out = [0.0f32; N];
            for (i, o) in out.iter_mut().enumerate() {
                let lo: u8 = a
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(2 * i, &self))?;
                let hi: u8 = a
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(2 * i + 1, &self))?;
                *o = from_count(i16::from_le_bytes([lo, hi]), self.0);
            }
            Ok(out)
        }
    }
    d.deserialize_tuple(2 * N, Counts::<N>(lsb))
}

/// One `f32` as one count (a tuple of one element: the same bytes as `[f32; 1]`'s).
pub fn serialize_scalar<S: Serializer>(v: &f32, lsb: f32, s: S) -> Result<S::Ok, S::Error> {
    serialize_array(core::array::from_ref(v), lsb, s)
}

/// The inverse of [`serialize_scalar`].
pub fn deserialize_scalar<'de, D: Deserializer<'de>>(d: D, lsb: f32) -> Result<f32, D::Error> {
    deserialize_array::<D, 1>(d, lsb).map(|[v]| v)
}

/// One encoding: `serialize`/`deserialize` for `#[serde(with = "…")]` on `[f32; N]` fields, and
/// the same in its `scalar` module for `f32` fields.
macro_rules! encoding {
    ($(#[$doc:meta])* $name:ident, $lsb:expr) => {
        $(#[$doc])*
        pub mod $name {
            /// The resolution, in the field's unit.
            pub const LSB: f32 = $lsb;
            pub fn serialize<S: serde::Serializer, const N: usize>(
                v: &[f32; N],
                s: S,
            ) -> Result<S::Ok, S::Error> {
                super::serialize_array(v, LSB, s)
            }
            pub fn deserialize<'de, D: serde::Deserializer<'de>, const N: usize>(
                d: D,
            ) -> Result<[f32; N], D::Error> {
                super::deserialize_array(d, LSB)
            }
            /// The same for one `f32`.
            pub mod scalar {
                pub fn serialize<S: serde::Serializer>(v: &f32, s: S) -> Result<S::Ok, S::Error> {
                    super::super::serialize_scalar(v, super::LSB, s)
                }
                pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
                    super::super::deserialize_scalar(d, super::LSB)
                }
            }
        }
    };
}

encoding!(
    /// Angular rate, rad/s: the MPU-9250's LSB at ±2000 °/s.
    gyro,
    2000.0 / 32768.0 * (core::f32::consts::PI / 180.0)
);
encoding!(
    /// Specific force, m/s²: the MPU-9250's LSB at ±16 g (g = 9.80665 m/s²).
    accel,
    16.0 * 9.80665 / 32768.0
);
encoding!(
    /// Magnetic field, µT: the AK8963's 16-bit LSB.
    mag,
    0.15
);
encoding!(
    /// Unit-quaternion components.
    unit,
    1.0 / 32767.0
);
encoding!(
    /// Estimated velocity, m/s.
    vel,
    0.002
);
encoding!(
    /// Estimated acceleration, m/s².
    accel_est,
    0.005
);
encoding!(
    /// Temperature, °C: the MS5611's 0.01 °C (its `TEMP` output).
    temp,
    0.01
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_round_saturate_and_keep_nan() {
        assert_eq!(to_count(0.0, 0.1), 0);
        assert_eq!(to_count(0.149, 0.1), 1);
        assert_eq!(to_count(-0.151, 0.1), -2);
        assert_eq!(to_count(1e9, 0.1), 32767);
        assert_eq!(to_count(-1e9, 0.1), -32767);
        assert_eq!(to_count(f32::INFINITY, 0.1), 32767);
        assert_eq!(to_count(f32::NEG_INFINITY, 0.1), -32767);
        assert_eq!(to_count(f32::NAN, 0.1), NAN_COUNT);
        assert!(from_count(NAN_COUNT, 0.1).is_nan());
        assert_eq!(from_count(-32767, 0.5), -16383.5);
    }

    /// A sensor's output (a multiple of its LSB) crosses exactly; any value within the range
    /// comes back within half an LSB.
    #[test]
    fn sensor_values_cross_exactly_others_within_half_an_lsb() {
        for lsb in [
            gyro::LSB,
            accel::LSB,
            mag::LSB,
            unit::LSB,
            vel::LSB,
            accel_est::LSB,
        ] {
            for c in [-32767i16, -1000, -1, 0, 1, 77, 32767] {
                let v = f32::from(c) * lsb;
                assert_eq!(from_count(to_count(v, lsb), lsb), v, "lsb {lsb} count {c}");
            }
            let mut x = 0.123_f32;
            for _ in 0..1000 {
                x = (x * 7.31 + 0.17) % 1.0;
                let v = (x - 0.5) * 60000.0 * lsb;
                let back = from_count(to_count(v, lsb), lsb);
                assert!(
                    (back - v).abs() <= 0.5 * lsb * 1.001,
                    "lsb {lsb}: {v} -> {back}"
                );
            }
        }
    }
}
