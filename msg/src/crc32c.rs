//! CRC-32C of the frames (Castagnoli, the iSCSI polynomial 0x1EDC6F41, reflected,
//! init/xorout 0xFFFFFFFF), computed by the fastest means the target offers:
//!
//! | target | means | cost |
//! |---|---|---|
//! | x86-64 with SSE4.2 (std) | the `crc32` instruction, 8 bytes at a time | ≈ 1 cycle per 8 B |
//! | AArch64 with the CRC extension (std) | `crc32cx`, 8 bytes at a time | ≈ 1 cycle per 8 B |
//! | other hosts | slice-by-16 tables (16 KiB) | ≈ 1 cycle per B |
//! | the MCU (`target_os = "none"`) | one 256-entry table (1 KiB of flash) | bytewise |
//!
//! Every means gives the same value ([`CRC32C`], the `crc` crate's `CRC_32_ISCSI`, is the
//! reference; the tests compare them). The instructions compute exactly this CRC: SSE4.2's
//! `crc32` and ARMv8's `crc32c*` use the Castagnoli polynomial, reflected, without the
//! init/xorout, which [`crc32c`] applies.

use crc::{Crc, Table, CRC_32_ISCSI};

/// The table-driven CRC-32C (the reference, and the fallback where no instruction exists).
pub static CRC32C: Crc<u32, CrcTable> = Crc::<u32, CrcTable>::new(&CRC_32_ISCSI);
#[cfg(not(target_os = "none"))]
type CrcTable = Table<16>;
#[cfg(target_os = "none")]
type CrcTable = Table<1>;

/// CRC-32C of `bytes`.
pub fn crc32c(bytes: &[u8]) -> u32 {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if std::is_x86_feature_detected!("sse4.2") {
        // SAFETY: the CPU has SSE4.2, checked just above.
        return unsafe { sse42(bytes) };
    }
    #[cfg(all(feature = "std", target_arch = "aarch64"))]
    if std::arch::is_aarch64_feature_detected!("crc") {
        // SAFETY: the CPU has the CRC extension, checked just above.
        return unsafe { armv8(bytes) };
    }
    CRC32C.checksum(bytes)
}

/// The instruction paths' common walk, given the instruction for 8, 4, 2 and 1 bytes: 8-byte
/// words, then the 0..7 bytes left in at most three dependent steps (4, 2, 1), not seven; init
/// and xorout applied here. Inlined into each `#[target_feature]` caller.
#[cfg(all(feature = "std", any(target_arch = "x86_64", target_arch = "aarch64")))]
#[inline(always)]
fn by_words(
    bytes: &[u8],
    d: impl Fn(u32, u64) -> u32,
    w: impl Fn(u32, u32) -> u32,
    h: impl Fn(u32, u16) -> u32,
    b: impl Fn(u32, u8) -> u32,
) -> u32 {
    let mut crc = u32::MAX;
    let mut words = bytes.chunks_exact(8);
    for x in &mut words {
        let mut le = [0u8; 8];
        le.copy_from_slice(x);
        crc = d(crc, u64::from_le_bytes(le));
    }
    let mut rest = words.remainder();
    if let Some((x, r)) = rest.split_first_chunk::<4>() {
        crc = w(crc, u32::from_le_bytes(*x));
        rest = r;
    }
    if let Some((x, r)) = rest.split_first_chunk::<2>() {
        crc = h(crc, u16::from_le_bytes(*x));
        rest = r;
    }
    if let Some(&x) = rest.first() {
        crc = b(crc, x);
    }
    !crc
}

#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[target_feature(enable = "sse4.2")]
unsafe fn sse42(bytes: &[u8]) -> u32 {
    use core::arch::x86_64::{_mm_crc32_u16, _mm_crc32_u32, _mm_crc32_u64, _mm_crc32_u8};
    by_words(
        bytes,
        |c, x| _mm_crc32_u64(u64::from(c), x) as u32,
        |c, x| _mm_crc32_u32(c, x),
        |c, x| _mm_crc32_u16(c, x),
        |c, x| _mm_crc32_u8(c, x),
    )
}

#[cfg(all(feature = "std", target_arch = "aarch64"))]
#[target_feature(enable = "crc")]
unsafe fn armv8(bytes: &[u8]) -> u32 {
    use core::arch::aarch64::{__crc32cb, __crc32cd, __crc32ch, __crc32cw};
    by_words(
        bytes,
        |c, x| __crc32cd(c, x),
        |c, x| __crc32cw(c, x),
        |c, x| __crc32ch(c, x),
        |c, x| __crc32cb(c, x),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The check value of CRC-32C ("123456789" → 0xE3069283, the catalogue's `check`), and
    /// every length 0..=130 of a pseudo-random buffer at every start offset 0..8 (the
    /// instruction paths' 8-byte words and remainders), against the table reference.
    #[test]
    fn every_means_gives_the_reference_value() {
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
        assert_eq!(CRC32C.checksum(b"123456789"), 0xE306_9283);
        let mut x = 0x1234_5678u32;
        let buf: Vec<u8> = (0..140)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                x as u8
            })
            .collect();
        for start in 0..8 {
            for len in 0..=130 {
                let s = &buf[start..start + len];
                let reference = Crc::<u32>::new(&CRC_32_ISCSI).checksum(s);
                assert_eq!(crc32c(s), reference, "start {start} len {len}");
                assert_eq!(CRC32C.checksum(s), reference, "start {start} len {len}");
            }
        }
    }
}
