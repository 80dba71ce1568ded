//! Futaba S.BUS receiver frames: sans-IO decoder and the pilot-override helper.
//!
//! Format (Futaba publishes no public specification; this is the de-facto description shared
//! by the open implementations — e.g. the mbed "FutabaSBUS" library, PX4 `sbus.cpp`, and the
//! `uf-sbus` crate's README — and it matches what receivers send):
//! - UART 100 000 baud, 8 data bits, **even parity, 2 stop bits**, **inverted** levels (idle
//!   low): the TM4C UART needs an external inverter; parity/framing errors from the UART should
//!   simply drop the byte (the decoder resynchronises).
//! - A frame every 14 ms (7 ms in "high speed" mode), 25 bytes:
//!   `[0] = 0x0F` header; `[1..=22]` = 16 channels × 11 bits, packed little-endian (channel 1
//!   is bits 0..10 of the 176-bit little-endian number formed by bytes 1–22); `[23]` = flags:
//!   bit 0 digital channel 17, bit 1 digital channel 18, bit 2 frame lost, bit 3 failsafe;
//!   `[24] = 0x00` footer (S.BUS2 receivers use 0x04, 0x14, 0x24, 0x34 for the telemetry slot
//!   that follows; accepted too).
//! - Values: 11-bit 0..2047. Typical transmitter range 172..1811 with 992 at centre
//!   (FrSky/OpenTX ±100 %; Futaba ≈ 368..1680 centre 1024): see [`to_unit`].
//!
//! Why not a crate: the crates.io candidates (checked November 2026) are `sbus` 0.2.2 (last
//! release 2020), `uf-sbus` 0.1.0 and `sbus-rs` 0.1.3 (AeroRust; fuzz-tested, embedded-io
//! based) — all pre-1.0, for ~80 lines of decoding. It is written here, sans-IO like the other
//! parsers, and tested against the per-channel formulas of the common C decoders and a random
//! byte stream; `sbus-rs` is the one to switch to if a dependency is preferred.

/// Frame length, bytes.
pub const FRAME_LEN: usize = 25;
pub const HEADER: u8 = 0x0F;
pub const FLAG_CH17: u8 = 0x01;
pub const FLAG_CH18: u8 = 0x02;
pub const FLAG_FRAME_LOST: u8 = 0x04;
pub const FLAG_FAILSAFE: u8 = 0x08;

/// Raw value at −100 %, 0 and +100 % (OpenTX/FrSky convention).
pub const RAW_MIN: u16 = 172;
pub const RAW_MID: u16 = 992;
pub const RAW_MAX: u16 = 1811;

/// One decoded frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SbusFrame {
    /// Channels 1..16, raw 11-bit values.
    pub channels: [u16; 16],
    pub ch17: bool,
    pub ch18: bool,
    /// The receiver missed a frame from the transmitter (channels hold their last values).
    pub frame_lost: bool,
    /// The receiver is in failsafe (link lost for a while): do not trust the channels.
    pub failsafe: bool,
}

impl SbusFrame {
    /// Channel `n` (1-based, 1..=16) raw value, `None` outside.
    pub fn channel(&self, n: usize) -> Option<u16> {
        n.checked_sub(1).and_then(|i| self.channels.get(i).copied())
    }
}

fn footer_ok(b: u8) -> bool {
    b == 0x00 || b & 0x0F == 0x04
}

/// Decode a complete 25-byte frame; `None` if header or footer is wrong.
pub fn decode_frame(f: &[u8; FRAME_LEN]) -> Option<SbusFrame> {
    if f[0] != HEADER || !footer_ok(f[24]) {
        return None;
    }
    let mut channels = [0u16; 16];
    let mut acc: u32 = 0;
    let mut nbits = 0u32;
    let mut ch = channels.iter_mut();
    for &byte in &f[1..23] {
        acc |= (byte as u32) << nbits;
        nbits += 8;
        while nbits >= 11 {
            if let Some(c) = ch.next() {
                *c = (acc & 0x07FF) as u16;
            }
            acc >>= 11;
            nbits -= 11;
        }
    }
    let flags = f[23];
    Some(SbusFrame {
        channels,
        ch17: flags & FLAG_CH17 != 0,
        ch18: flags & FLAG_CH18 != 0,
        frame_lost: flags & FLAG_FRAME_LOST != 0,
        failsafe: flags & FLAG_FAILSAFE != 0,
    })
}

/// Encode a frame (for tests and for an S.BUS output).
pub fn encode_frame(fr: &SbusFrame) -> [u8; FRAME_LEN] {
    let mut out = [0u8; FRAME_LEN];
    out[0] = HEADER;
    let mut acc: u32 = 0;
    let mut nbits = 0u32;
    let mut slots = out[1..23].iter_mut();
    for &c in &fr.channels {
        acc |= ((c & 0x07FF) as u32) << nbits;
        nbits += 11;
        while nbits >= 8 {
            if let Some(s) = slots.next() {
                *s = acc as u8;
            }
            acc >>= 8;
            nbits -= 8;
        }
    }
    out[23] = (fr.ch17 as u8)
        | (fr.ch18 as u8) << 1
        | (fr.frame_lost as u8) << 2
        | (fr.failsafe as u8) << 3;
    out
}

/// Raw value → −1..1 (172 → −1, 992 → 0, 1811 → +1), clamped.
pub fn to_unit(raw: u16) -> f32 {
    let v = (raw as f32 - RAW_MID as f32) / ((RAW_MAX - RAW_MID) as f32);
    v.clamp(-1.0, 1.0)
}

/// The pilot takes over when the switch on `channel` (1-based) is above `threshold_raw`, and
/// the receiver is not in failsafe (a failsafe frame's channels are the receiver's preset, not
/// the pilot's hand). `None` frame (no recent S.BUS) → no override.
pub fn pilot_override(frame: Option<&SbusFrame>, channel: usize, threshold_raw: u16) -> bool {
    match frame {
        Some(f) if !f.failsafe => f.channel(channel).is_some_and(|v| v > threshold_raw),
        _ => false,
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SbusStats {
    pub frames: u32,
    /// 25 bytes after a header without a valid footer (lost sync, noise).
    pub bad_frames: u32,
    /// Bytes skipped while looking for a header.
    pub skipped_bytes: u32,
    /// Frames flagged frame-lost / failsafe by the receiver.
    pub frame_lost: u32,
    pub failsafe: u32,
    /// Partial frames dropped by [`SbusDecoder::idle`].
    pub truncated: u32,
}

/// Byte-at-a-time decoder. On a bad footer it rescans the buffered bytes for the next 0x0F, so
/// it locks onto the stream within a frame or two even without UART idle detection; calling
/// [`SbusDecoder::idle`] on the inter-frame gap (≥ 3 ms of silence) makes sync immediate.
#[derive(Clone, Debug)]
pub struct SbusDecoder {
    buf: [u8; FRAME_LEN],
    len: usize,
    pub stats: SbusStats,
}

impl Default for SbusDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl SbusDecoder {
    pub fn new() -> Self {
        Self {
            buf: [0; FRAME_LEN],
            len: 0,
            stats: SbusStats::default(),
        }
    }

    /// The line went idle: whatever partial frame is buffered is dropped.
    pub fn idle(&mut self) {
        if self.len > 0 {
            self.stats.truncated = self.stats.truncated.wrapping_add(1);
        }
        self.len = 0;
    }

    pub fn push(&mut self, byte: u8) -> Option<SbusFrame> {
        if self.len == 0 && byte != HEADER {
            self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(1);
            return None;
        }
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = byte;
            self.len += 1;
        }
        if self.len < FRAME_LEN {
            return None;
        }
        self.len = 0;
        match decode_frame(&self.buf) {
            Some(f) => {
                self.stats.frames = self.stats.frames.wrapping_add(1);
                if f.frame_lost {
                    self.stats.frame_lost = self.stats.frame_lost.wrapping_add(1);
                }
                if f.failsafe {
                    self.stats.failsafe = self.stats.failsafe.wrapping_add(1);
                }
                Some(f)
            }
            None => {
                self.stats.bad_frames = self.stats.bad_frames.wrapping_add(1);
                // Resync: restart at the next header among the buffered bytes.
                if let Some(pos) = self.buf.iter().skip(1).position(|&b| b == HEADER) {
                    let start = pos + 1;
                    self.buf.copy_within(start.., 0);
                    self.len = FRAME_LEN - start;
                }
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::testutil::Rng;

    /// Reference: the explicit per-channel formula of the common C decoders (mbed FutabaSBUS,
    /// PX4), channel 1 = (b1 | b2<<8) & 0x7FF, channel 2 = (b2>>3 | b3<<5) & 0x7FF, …
    fn reference(b: &[u8; 25]) -> [u16; 16] {
        let b: Vec<u32> = b.iter().map(|&x| x as u32).collect();
        let m = 0x07FF;
        [
            (b[1] | b[2] << 8) & m,
            (b[2] >> 3 | b[3] << 5) & m,
            (b[3] >> 6 | b[4] << 2 | b[5] << 10) & m,
            (b[5] >> 1 | b[6] << 7) & m,
            (b[6] >> 4 | b[7] << 4) & m,
            (b[7] >> 7 | b[8] << 1 | b[9] << 9) & m,
            (b[9] >> 2 | b[10] << 6) & m,
            (b[10] >> 5 | b[11] << 3) & m,
            (b[12] | b[13] << 8) & m,
            (b[13] >> 3 | b[14] << 5) & m,
            (b[14] >> 6 | b[15] << 2 | b[16] << 10) & m,
            (b[16] >> 1 | b[17] << 7) & m,
            (b[17] >> 4 | b[18] << 4) & m,
            (b[18] >> 7 | b[19] << 1 | b[20] << 9) & m,
            (b[20] >> 2 | b[21] << 6) & m,
            (b[21] >> 5 | b[22] << 3) & m,
        ]
        .map(|v| v as u16)
    }

    #[test]
    fn known_bytes() {
        // Channel 1 = 0x7FF, the rest 0: bytes 1–2 = FF 07.
        let mut f = [0u8; 25];
        f[0] = 0x0F;
        f[1] = 0xFF;
        f[2] = 0x07;
        let d = decode_frame(&f).unwrap();
        assert_eq!(d.channels[0], 0x7FF);
        assert!(d.channels[1..].iter().all(|&c| c == 0));
        // All channels at centre 992 (0x3E0), flags failsafe + frame lost + ch17.
        let fr = SbusFrame {
            channels: [992; 16],
            ch17: true,
            frame_lost: true,
            failsafe: true,
            ..Default::default()
        };
        let bytes = encode_frame(&fr);
        assert_eq!(&bytes[..4], &[0x0F, 0xE0, 0x03, 0x1F]);
        assert_eq!(bytes[23], 0x0D);
        assert_eq!(decode_frame(&bytes), Some(fr));
        assert_eq!(reference(&bytes), [992; 16]);
    }

    #[test]
    fn matches_reference_decoder_on_random_frames() {
        let mut rng = Rng(25);
        for _ in 0..2000 {
            let mut f = [0u8; 25];
            f.iter_mut().for_each(|b| *b = rng.byte());
            f[0] = 0x0F;
            f[24] = 0x00;
            let d = decode_frame(&f).unwrap();
            assert_eq!(d.channels, reference(&f));
            assert_eq!(
                decode_frame(&encode_frame(&d)).unwrap().channels,
                d.channels
            );
        }
    }

    #[test]
    fn stream_sync_footers_and_flags() {
        let mut dec = SbusDecoder::new();
        let mut fr = SbusFrame::default();
        for (i, c) in fr.channels.iter_mut().enumerate() {
            *c = 172 + 100 * i as u16;
        }
        let good = encode_frame(&fr);
        let mut stream = vec![0x00, 0x55, 0x0F, 0x12]; // noise incl. a false header
        for footer in [0x00u8, 0x04, 0x14, 0x24, 0x34] {
            let mut g = good;
            g[24] = footer;
            stream.extend_from_slice(&g);
        }
        let mut g = good;
        g[24] = 0x99; // bad footer
        stream.extend_from_slice(&g);
        stream.extend_from_slice(&good);
        let out: Vec<SbusFrame> = stream.iter().filter_map(|&b| dec.push(b)).collect();
        assert!(out.len() >= 5, "{}", out.len());
        assert!(out.iter().all(|f| *f == fr));
        assert!(dec.stats.bad_frames >= 1);
        // Flags.
        let mut lost = fr;
        lost.frame_lost = true;
        lost.failsafe = true;
        dec.idle();
        let o: Vec<_> = encode_frame(&lost)
            .iter()
            .filter_map(|&b| dec.push(b))
            .collect();
        assert_eq!(o, vec![lost]);
        assert_eq!((dec.stats.frame_lost, dec.stats.failsafe), (1, 1));
    }

    #[test]
    fn override_switch() {
        let mut fr = SbusFrame::default();
        fr.channels[4] = 1811; // channel 5 high
        assert!(pilot_override(Some(&fr), 5, 1500));
        assert!(!pilot_override(Some(&fr), 6, 1500));
        assert!(!pilot_override(Some(&fr), 0, 1500));
        assert!(!pilot_override(Some(&fr), 17, 1500));
        assert!(!pilot_override(None, 5, 1500));
        fr.failsafe = true;
        assert!(!pilot_override(Some(&fr), 5, 1500));
        assert_eq!(to_unit(172), -1.0);
        assert_eq!(to_unit(992), 0.0);
        assert_eq!(to_unit(1811), 1.0);
        assert_eq!(to_unit(2047), 1.0);
    }

    #[test]
    fn any_bytes_never_panic() {
        let mut rng = Rng(100_000);
        let mut dec = SbusDecoder::new();
        for i in 0..300_000u32 {
            if i % 997 == 0 {
                dec.idle();
            }
            if let Some(f) = dec.push(rng.biased(&[0x0F, 0x00, 0x04])) {
                assert!(f.channels.iter().all(|&c| c <= 0x7FF));
            }
        }
        assert!(dec.stats.frames > 0 && dec.stats.bad_frames > 0);
    }
}
