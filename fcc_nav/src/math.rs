//! Single-precision elementary functions for the flight core: every `f32` function the no_std
//! navigation and control code calls goes through this module.
//!
//! Why not `libm` directly: the TM4C129x's Cortex-M4F has a single-precision FPU only, so any
//! `f64` operation becomes a call into the software double routines (`__aeabi_dmul`, …). The
//! `libm` crate's `sinf`/`cosf`/`tanf` evaluate their kernels and argument reduction in `f64`,
//! `asinf` and `hypotf` use an `f64` square root or sum, and its `sqrtf` is a bit-by-bit integer
//! loop on targets without an architecture override (ARM has none). On the MCU that cost about
//! 30k instructions per 500 Hz step (QEMU replay); with this module, 4.2k. Here:
//!
//! | function | implementation | max error (host test against `f64` std, see the tests) |
//! |---|---|---|
//! | [`sqrtf`] | `VSQRT.F32` on the bare-metal ARM build (`core::f32::math::sqrt`), `libm::sqrtf` elsewhere; both correctly rounded, so bit-identical | 0.5 ulp |
//! | [`sinf`], [`cosf`], [`sincosf`], [`tanf`] | Cody–Waite reduction by π/2 (3-part constant) for \|x\| < 64, Payne–Hanek in integer arithmetic (96-bit window of 2/π) above; Cephes single-precision minimax polynomials on \[−π/4, π/4] | sin/cos ≤ 1.5 ulp, tan ≤ 3.5 ulp (all finite x) |
//! | [`asinf`], [`acosf`] | `atan2f(x, √((1−x)(1+x)))` and `atan2f(√((1−x)(1+x)), x)` | ≤ 2.5 ulp |
//! | [`hypotf`] | `√(a²+b²)` with power-of-two rescaling near overflow / underflow | ≤ 1.25 ulp |
//! | [`atan2f`], [`atanf`], [`expf`], [`powf`], [`floorf`], [`fmodf`] | `libm`'s, which are already `f32`-only (FreeBSD msun ports; checked in the MCU disassembly by `scripts/build-mcu.sh`) | expf ≤ 1 ulp, atan2f ≤ 1.5 ulp (measured here too) |
//!
//! No function here uses `f64`, `mul_add` or any platform math, so the host build and the MCU
//! build of the flight core compute bit-identical results (`scripts/test-mcu.sh` checks this on
//! a recorded flight). The stated bounds are the largest errors the tests in this file found
//! over dense sweeps (see `tests`), rounded up, not proofs.

/// Square root, correctly rounded; `NaN` for `x < 0`.
#[inline(always)]
pub fn sqrtf(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_os = "none"))]
    {
        // Lowers to llvm.sqrt.f32: VSQRT.F32 on an FPU (14 cycles on the M4F).
        core::f32::math::sqrt(x)
    }
    #[cfg(not(all(target_arch = "arm", target_os = "none")))]
    {
        libm::sqrtf(x)
    }
}

/// `x` limited to `[lo, hi]`, like `f32::clamp` (NaN stays NaN), but without `clamp`'s panic
/// on `lo > hi` or NaN bounds, so the MCU image has no panic path here (bounds come from
/// range-checked parameters; an inverted pair gives `lo` below it and `hi` above it).
#[inline]
pub fn clampf(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

/// `|x|`.
#[inline(always)]
pub fn fabsf(x: f32) -> f32 {
    x.abs()
}

/// Largest integer not greater than `x` (libm: integer bit manipulation only).
#[inline]
pub fn floorf(x: f32) -> f32 {
    libm::floorf(x)
}

/// Remainder of `x / y` with the sign of `x` (libm: integer bit manipulation only).
#[inline]
pub fn fmodf(x: f32, y: f32) -> f32 {
    libm::fmodf(x, y)
}

/// Four-quadrant arctangent of `y/x` in \[−π, π] (libm: `f32` only).
#[inline]
pub fn atan2f(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// Arctangent in \[−π/2, π/2] (libm: `f32` only).
#[inline]
pub fn atanf(x: f32) -> f32 {
    libm::atanf(x)
}

/// `eˣ` (libm: `f32` only).
#[inline]
pub fn expf(x: f32) -> f32 {
    libm::expf(x)
}

/// `xʸ` (libm: `f32` only).
#[inline]
pub fn powf(x: f32, y: f32) -> f32 {
    libm::powf(x, y)
}

/// Arcsine in \[−π/2, π/2]; `NaN` outside \[−1, 1].
#[inline]
pub fn asinf(x: f32) -> f32 {
    // 1 − x is exact for x in [0.5, 1] (Sterbenz), so the cosine leg stays accurate near ±1.
    atan2f(x, sqrtf((1.0 - x) * (1.0 + x)))
}

/// Arccosine in \[0, π]; `NaN` outside \[−1, 1].
#[inline]
pub fn acosf(x: f32) -> f32 {
    atan2f(sqrtf((1.0 - x) * (1.0 + x)), x)
}

/// `√(x² + y²)` without overflow or underflow in the intermediate squares.
#[inline]
pub fn hypotf(x: f32, y: f32) -> f32 {
    let (a, b) = (x.abs(), y.abs());
    let (hi, lo) = if a >= b { (a, b) } else { (b, a) };
    const TWO_P60: f32 = f32::from_bits(0x5d80_0000); // 2^60
    const TWO_M60: f32 = f32::from_bits(0x2180_0000); // 2^-60
    if (TWO_M60..TWO_P60).contains(&hi) {
        // lo² may underflow here only when it is below hi²·2^-66: negligible.
        return sqrtf(hi * hi + lo * lo);
    }
    if hi == f32::INFINITY || lo == f32::INFINITY {
        return f32::INFINITY; // IEEE: hypot(±∞, NaN) = +∞
    }
    if hi.is_nan() || lo.is_nan() {
        return f32::NAN;
    }
    if hi == 0.0 {
        return 0.0;
    }
    // Rescale by an exact power of two, then undo it.
    let (s, unscale) = if hi >= TWO_P60 {
        (f32::from_bits(0x1280_0000), f32::from_bits(0x6c80_0000)) // 2^-90, 2^90
    } else {
        (f32::from_bits(0x6c80_0000), f32::from_bits(0x1280_0000))
    };
    let (h, l) = (hi * s, lo * s);
    sqrtf(h * h + l * l) * unscale
}

/// Sine (radians).
#[inline]
pub fn sinf(x: f32) -> f32 {
    sincosf(x).0
}

/// Cosine (radians).
#[inline]
pub fn cosf(x: f32) -> f32 {
    sincosf(x).1
}

/// Tangent (radians), as `sin/cos` of one reduction.
#[inline]
pub fn tanf(x: f32) -> f32 {
    let (s, c) = sincosf(x);
    s / c
}

/// π/2 split for Cody–Waite reduction: `P1` has 8 significant bits and `P2` 11, so `k·P1` and
/// `k·P2` are exact for |k| < 2¹³; `P1 + P2 + P3` = π/2 to 1.7e−15.
const PIO2_1: f32 = 1.570_312_5;
// The split's exact decimal values as published (more digits than an f32 holds, on purpose).
#[allow(clippy::excessive_precision)]
const PIO2_2: f32 = 4.837_512_969_970_703_125e-4;
#[allow(clippy::excessive_precision)]
const PIO2_3: f32 = 7.549_790_126_404_332e-8;
const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
/// Above this |x| the reduction switches to [`reduce_large`] (Cody–Waite's residual error
/// `k·1.7e−15` would otherwise show near multiples of π/2).
const CW_MAX: f32 = 64.0;

/// `(sin x, cos x)` from one argument reduction. `NaN` for non-finite `x`.
#[inline]
pub fn sincosf(x: f32) -> (f32, f32) {
    let ax = x.abs();
    if ax < f32::from_bits(0x3980_0000) {
        // |x| < 2^-12: sin x = x and cos x = 1 correctly rounded (keeps the sign of ±0).
        return (x, 1.0);
    }
    let (z, q) = if ax < CW_MAX {
        // Nearest quadrant: k = round(x·2/π) (ties away from zero; any nearby k works).
        let k = (x * FRAC_2_PI + if x < 0.0 { -0.5 } else { 0.5 }) as i32;
        let kf = k as f32;
        (((x - kf * PIO2_1) - kf * PIO2_2) - kf * PIO2_3, k as u32)
    } else if x.is_finite() {
        reduce_large(x)
    } else {
        return (f32::NAN, f32::NAN); // NaN, ±∞ → NaN
    };
    let zz = z * z;
    // Cephes sinf/cosf polynomials on [−π/4, π/4] (single-precision minimax).
    #[allow(clippy::excessive_precision)] // the coefficients as Cephes publishes them
    let s =
        ((-1.951_529_589_1e-4 * zz + 8.332_160_873_6e-3) * zz - 1.666_665_461_1e-1) * zz * z + z;
    #[allow(clippy::excessive_precision)]
    let c = ((2.443_315_711_809_948e-5 * zz - 1.388_731_625_493_765e-3) * zz
        + 4.166_664_568_298_827e-2)
        * zz
        * zz
        - 0.5 * zz
        + 1.0;
    match q & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Bits of 2/π, preceded by one zero word (the integer part): bit `j` of this big-endian string
/// has weight 2^(31−j). 2/π = 0.A2F9836E 4E441529 FC2757D1 … (hex).
const TWO_OVER_PI: [u32; 8] = [
    0x0000_0000,
    0xA2F9_836E,
    0x4E44_1529,
    0xFC27_57D1,
    0xF534_DDC0,
    0xDB62_9599,
    0x3C43_9041,
    0xFE51_63AB,
];

/// Payne–Hanek reduction for finite |x| ≥ 64 (any larger x too): `x = (q + f)·π/2` with
/// `f` in \[−½, ½), in integer arithmetic (no `f64`). Returns `(f·π/2, q mod 4)`.
#[cold]
#[inline(never)]
fn reduce_large(x: f32) -> (f32, u32) {
    let bits = x.to_bits();
    let neg = bits >> 31 != 0;
    let exp = ((bits >> 23) & 0xff) as i32;
    let m = ((bits & 0x7f_ffff) | 0x80_0000) as u128; // |x| = m·2^e, e = exp − 150
    let e = exp - 150;
    // Bits of 2/π with weight ≥ 2^-(e−2) give multiples of 4 (dropped); take the 96 bits with
    // weights 2^-(e−1) … 2^-(e+94), i.e. starting at string bit j0 = (e − 1) + 31 ≥ 0.
    let j0 = (e + 30) as usize;
    // e ≤ 104, so w ≤ 4 (the min() only tells the compiler: no bounds-check panic path).
    let (w, o) = ((j0 / 32).min(4), (j0 % 32) as u32);
    let hi: u128 = ((TWO_OVER_PI[w] as u128) << 96)
        | ((TWO_OVER_PI[w + 1] as u128) << 64)
        | ((TWO_OVER_PI[w + 2] as u128) << 32)
        | TWO_OVER_PI[w + 3] as u128;
    // String bits o … o+95 of those four words (o ≤ 31, so the zeros shifted in drop out).
    let window = (hi << o) >> 32;
    // The window's top bit has weight 2^-(e−1), so x·2/π ≡ m·window·2^-94 (mod 4); the
    // truncated tail of 2/π adds less than m·2^-94 < 2^-70.
    let p = m * window; // < 2^120
    let mut q = (p >> 94) as u32 & 3;
    let mut frac = (p & ((1u128 << 94) - 1)) as i128;
    if frac >= 1i128 << 93 {
        frac -= 1i128 << 94;
        q = q.wrapping_add(1);
    }
    // z = frac·2^-94·π/2 with π/2 in 64-bit fixed point and a single rounding to f32.
    let a = frac.unsigned_abs();
    let z = if a == 0 {
        0.0
    } else {
        let lz = a.leading_zeros() as i32; // ≥ 35
        let t = ((a << lz) >> 64) as u64; // top 64 significant bits of |frac|
        const PIO2_Q63: u128 = 0xC90F_DAA2_2168_C235; // round(π/2·2^63)
                                                      // |z| = t·PIO2_Q63·2^(−93−lz); the product is < 2^128 and ≥ 2^126, so its f32 is
                                                      // normal, and the scalings by powers of two are exact.
        let v = ((t as u128) * PIO2_Q63) as f32 * pow2(-64);
        let k = -29 - lz;
        v * pow2(k / 2) * pow2(k - k / 2)
    };
    let z = if frac < 0 { -z } else { z };
    if neg {
        (-z, q.wrapping_neg() & 3)
    } else {
        (z, q & 3)
    }
}

/// 2^k for k in \[−126, 127].
#[inline(always)]
fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::println;

    /// Error of `y` against the exact value `r` in units of the f32 ulp at `r`.
    fn ulps(y: f32, r: f64) -> f64 {
        if y.is_nan() && r.is_nan() {
            return 0.0;
        }
        let ra = r.abs();
        let e = if ra < f32::MIN_POSITIVE as f64 {
            -149
        } else {
            (ra as f32).to_bits() as i32 >> 23 & 0xff
        };
        let ulp = if e == -149 {
            2f64.powi(-149)
        } else {
            // ulp of the f32 binade containing r (r rounded to f32 may step up a binade: use
            // the smaller, i.e. stricter, one)
            let b = f64::from(f32::from_bits(((e as u32) << 23) & 0x7f80_0000));
            b * 2f64.powi(-23)
        };
        ((y as f64) - r).abs() / ulp
    }

    /// Every `stride`-th f32 between `lo` and `hi` (both ≥ 0), and their negatives.
    fn sweep(lo: f32, hi: f32, stride: u32, mut f: impl FnMut(f32)) {
        let mut b = lo.to_bits();
        while b <= hi.to_bits() {
            let x = f32::from_bits(b);
            f(x);
            f(-x);
            b += stride;
        }
    }

    fn max_err(
        lo: f32,
        hi: f32,
        stride: u32,
        ours: impl Fn(f32) -> f32,
        exact: impl Fn(f64) -> f64,
    ) -> (f64, f32) {
        let mut worst = (0.0, 0.0);
        sweep(lo, hi, stride, |x| {
            let e = ulps(ours(x), exact(x as f64));
            if e > worst.0 {
                worst = (e, x);
            }
        });
        worst
    }

    // Small strides under --release; debug builds (plain `cargo test`) sweep more coarsely.
    const fn stride(release: u32) -> u32 {
        if cfg!(debug_assertions) {
            release * 16
        } else {
            release
        }
    }

    #[test]
    fn sin_cos_within_1_5_ulp() {
        for (lo, hi, st) in [
            (0.0, 8.0, stride(97)),       // the flight core's range (|angle| ≤ π), dense
            (8.0, 64.0, stride(31)),      // rest of the Cody–Waite range
            (64.0, 1.0e6, stride(1_009)), // Payne–Hanek
            (1.0e6, f32::MAX, stride(65_537)), // Payne–Hanek, up to the largest f32
        ] {
            let (es, xs) = max_err(lo, hi, st, sinf, f64::sin);
            let (ec, xc) = max_err(lo, hi, st, cosf, f64::cos);
            println!(
                "sinf [{lo:e}, {hi:e}]: max {es:.3} ulp at {xs:e}; cosf: max {ec:.3} ulp at {xc:e}"
            );
            assert!(
                es <= 1.5 && ec <= 1.5,
                "sin {es} at {xs:e}, cos {ec} at {xc:e}"
            );
        }
        // Uniform grid over one turn and a bit.
        let mut worst: f64 = 0.0;
        for i in 0..=2_000_000 {
            let x = -7.0 + 14.0 * i as f32 / 2.0e6;
            let (s, c) = sincosf(x);
            worst = worst
                .max(ulps(s, (x as f64).sin()))
                .max(ulps(c, (x as f64).cos()));
            assert!(s.abs() <= 1.0 && c.abs() <= 1.0);
        }
        println!("sincosf on a uniform grid over [-7, 7]: max {worst:.3} ulp");
        assert!(worst <= 1.5);
        // Exact special values.
        assert_eq!(sinf(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(sinf(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(cosf(0.0), 1.0);
        assert!(
            sinf(f32::NAN).is_nan()
                && cosf(f32::INFINITY).is_nan()
                && sinf(f32::NEG_INFINITY).is_nan()
        );
    }

    #[test]
    fn tan_within_3_5_ulp() {
        for (lo, hi, st) in [
            (0.0, 8.0, stride(97)),
            (8.0, 1.0e6, stride(1_009)),
            (1.0e6, f32::MAX, stride(65_537)),
        ] {
            let (e, x) = max_err(lo, hi, st, tanf, f64::tan);
            println!("tanf [{lo:e}, {hi:e}]: max {e:.3} ulp at {x:e}");
            assert!(e <= 3.5, "tan {e} at {x:e}");
        }
    }

    #[test]
    fn asin_acos_within_2_5_ulp() {
        let (ea, xa) = max_err(0.0, 1.0, stride(23), asinf, f64::asin);
        let (ec, xc) = max_err(0.0, 1.0, stride(23), acosf, f64::acos);
        println!("asinf [-1, 1]: max {ea:.3} ulp at {xa:e}; acosf: max {ec:.3} ulp at {xc:e}");
        assert!(ea <= 2.5 && ec <= 2.5);
        assert!(asinf(1.5).is_nan() && acosf(-1.0001).is_nan());
        assert_eq!(asinf(1.0), core::f32::consts::FRAC_PI_2);
        assert_eq!(acosf(1.0), 0.0);
        assert_eq!(acosf(-1.0), core::f32::consts::PI);
    }

    #[test]
    fn hypot_within_1_25_ulp() {
        let mut worst = (0.0f64, 0.0f32, 0.0f32);
        let mut check = |x: f32, y: f32| {
            let e = ulps(hypotf(x, y), (x as f64).hypot(y as f64));
            if e > worst.0 {
                worst = (e, x, y);
            }
        };
        // A log-spaced grid of magnitudes (1e-40 … 3e38) crossed with ratios.
        let mut a = 1.0e-40f32;
        while a < 3.0e38 {
            let mut r = 1.0e-9f32;
            while r <= 1.0 {
                check(a, a * r);
                check(-a * r, a);
                r *= 1.37;
            }
            a *= 1.9;
        }
        for i in 0..1_000_000u32 {
            let x = (i as f32 * 0.618_034).sin() * 100.0;
            let y = (i as f32 * 0.414_213_5).cos() * 30.0;
            check(x, y);
        }
        println!(
            "hypotf: max {:.3} ulp at ({:e}, {:e})",
            worst.0, worst.1, worst.2
        );
        assert!(worst.0 <= 1.25);
        assert_eq!(hypotf(f32::INFINITY, f32::NAN), f32::INFINITY);
        assert!(hypotf(f32::NAN, 1.0).is_nan());
        assert_eq!(hypotf(0.0, -0.0), 0.0);
        assert_eq!(hypotf(3.0e38, 3.0e38), 3.0e38 * core::f32::consts::SQRT_2);
    }

    #[test]
    fn libm_exp_within_1_atan2_within_1_5_ulp() {
        let (ee, xe) = max_err(0.0, 88.0, stride(97), expf, f64::exp);
        let mut worst = (0.0f64, 0.0f32, 0.0f32);
        for i in 0..=600u32 {
            for j in 0..=600u32 {
                let (y, x) = (-3.0 + i as f32 * 0.01, -3.0 + j as f32 * 0.01);
                let e = ulps(atan2f(y, x), (y as f64).atan2(x as f64));
                if e > worst.0 {
                    worst = (e, y, x);
                }
            }
        }
        println!(
            "expf [-88, 88]: max {ee:.3} ulp at {xe:e}; atan2f grid: max {:.3} ulp at ({:e}, {:e})",
            worst.0, worst.1, worst.2
        );
        assert!(ee <= 1.0 && worst.0 <= 1.5);
    }

    #[test]
    fn sqrt_correctly_rounded() {
        let (e, x) = max_err(0.0, f32::MAX, stride(4_099), sqrtf, f64::sqrt);
        println!("sqrtf: max {e:.3} ulp at {x:e}");
        assert!(e <= 0.5);
    }
}
