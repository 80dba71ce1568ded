//! Framing: header, CRC-32C, COBS, the encoder and the byte-at-a-time decoder.

use crate::crc32c::crc32c;
pub use crate::crc32c::CRC32C;
use crate::messages::{Message, PayloadError, MAX_PAYLOAD_LEN};
use crate::{LinkCounters, PROTOCOL_VERSION};

/// Header length of most frames: version (1) | msg_id (1) | seq (2, LE) | t_us low 32 bits
/// (4, LE).
pub const HEADER_LEN: usize = 8;
/// Header length of the frames that carry the whole 64-bit `t_us` ([`long_header`]: the
/// handshake's, frozen across versions, and `Status`, ten a second): version (1) | msg_id (1) |
/// seq (2, LE) | t_us (8, LE).
pub const LONG_HEADER_LEN: usize = 12;
/// Trailer length: CRC-32C (4, LE).
pub const CRC_LEN: usize = 4;
/// Largest unencoded frame (header + payload + CRC).
pub const MAX_RAW_FRAME_LEN: usize = LONG_HEADER_LEN + MAX_PAYLOAD_LEN + CRC_LEN;
/// Largest frame on the wire: COBS of the raw frame plus the 0x00 delimiter.
pub const MAX_FRAME_LEN: usize = cobs::max_encoding_length(MAX_RAW_FRAME_LEN) + 1;
// Frames stay small: a decoder costs one buffer of this size, a 2 ms tick carries 184 B.
const _: () = assert!(MAX_FRAME_LEN <= 128);

/// Whether frames of `msg_id` carry the 64-bit time (else its low 32 bits, which the decoder
/// extends from the frames before: [`FrameDecoder`]).
pub const fn long_header(msg_id: u8) -> bool {
    matches!(
        msg_id,
        crate::id::HELLO | crate::id::HELLO_REQUEST | crate::id::STATUS
    )
}

/// Header length of frames of `msg_id`.
pub const fn header_len(msg_id: u8) -> usize {
    if long_header(msg_id) {
        LONG_HEADER_LEN
    } else {
        HEADER_LEN
    }
}

/// The frame header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    pub version: u8,
    pub msg_id: u8,
    /// Per-direction sequence number, wrapping.
    pub seq: u16,
    /// Sender's clock in µs: MCU µs since boot on MCU → Linux frames (the time the payload
    /// refers to); the Linux side's monotonic µs on Linux → MCU frames (informational). Whole
    /// in long headers; extended from the low 32 bits in the others ([`FrameDecoder`]).
    pub t_us: u64,
}

impl Header {
    /// Write the header for `msg_id`'s length into `out` (at least [`LONG_HEADER_LEN`]);
    /// returns its length.
    fn write(&self, out: &mut [u8; LONG_HEADER_LEN]) -> usize {
        out[0] = self.version;
        out[1] = self.msg_id;
        out[2..4].copy_from_slice(&self.seq.to_le_bytes());
        out[4..12].copy_from_slice(&self.t_us.to_le_bytes());
        header_len(self.msg_id)
    }
}

/// One decoded frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub header: Header,
    pub message: Message,
}

/// Why [`encode`] failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EncodeError {
    /// `out` is shorter than the worst-case encoded frame for this message.
    BufferTooSmall { needed: usize, available: usize },
    /// postcard refused the payload (cannot happen for the types of this crate).
    Serialize,
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EncodeError::BufferTooSmall { needed, available } => {
                write!(
                    f,
                    "output buffer too small: {needed} B needed, {available} B available"
                )
            }
            EncodeError::Serialize => f.write_str("payload serialisation failed"),
        }
    }
}

/// Encode `msg` as one complete frame (COBS + trailing 0x00) into `out`; returns its length.
///
/// `out` must hold the worst-case encoding of the message
/// (`cobs::max_encoding_length(header_len(id) + len + CRC_LEN) + 1`); [`MAX_FRAME_LEN`] always
/// does.
pub fn encode(msg: &Message, seq: u16, t_us: u64, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut raw = [0u8; MAX_RAW_FRAME_LEN];
    let header = Header {
        version: PROTOCOL_VERSION,
        msg_id: msg.id(),
        seq,
        t_us,
    };
    let mut h = [0u8; LONG_HEADER_LEN];
    let h_len = header.write(&mut h);
    // Slices by `get`, not indexing: no panic path in the MCU image (scripts/build-mcu.sh
    // lists them); the lengths are constants, so these never fail.
    raw.get_mut(..LONG_HEADER_LEN)
        .ok_or(EncodeError::Serialize)?
        .copy_from_slice(&h);
    // The payload follows the header (over a short header's unused high time bytes).
    let payload = raw
        .get_mut(h_len..h_len + MAX_PAYLOAD_LEN)
        .ok_or(EncodeError::Serialize)?;
    let n = msg
        .serialize_payload(payload)
        .map_err(|_| EncodeError::Serialize)?;
    let crc_at = h_len + n;
    let crc = crc32c(raw.get(..crc_at).ok_or(EncodeError::Serialize)?);
    raw.get_mut(crc_at..crc_at + CRC_LEN)
        .ok_or(EncodeError::Serialize)?
        .copy_from_slice(&crc.to_le_bytes());
    let raw_len = crc_at + CRC_LEN;
    let needed = cobs::max_encoding_length(raw_len) + 1;
    let too_small = EncodeError::BufferTooSmall {
        needed,
        available: out.len(),
    };
    if out.len() < needed {
        return Err(too_small);
    }
    let src = raw.get(..raw_len).ok_or(EncodeError::Serialize)?;
    let len = cobs::try_encode(src, out).map_err(|_| too_small)?;
    *out.get_mut(len).ok_or(too_small)? = 0;
    Ok(len + 1)
}

/// Convenience: an encoder that numbers its frames (one per direction).
#[derive(Clone, Debug, Default)]
pub struct Encoder {
    next_seq: u16,
}

impl Encoder {
    pub const fn new() -> Self {
        Self { next_seq: 0 }
    }
    /// Sequence number the next frame will carry.
    pub fn next_seq(&self) -> u16 {
        self.next_seq
    }
    /// Encode with the next sequence number; the number is used up only on success.
    pub fn encode(
        &mut self,
        msg: &Message,
        t_us: u64,
        out: &mut [u8],
    ) -> Result<usize, EncodeError> {
        let n = encode(msg, self.next_seq, t_us, out)?;
        self.next_seq = self.next_seq.wrapping_add(1);
        Ok(n)
    }
}

/// Why a frame candidate was rejected. Every error is also counted in [`LinkCounters`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DecodeError {
    /// Not valid COBS, or too short for header + CRC.
    Framing,
    /// CRC-32C mismatch.
    Crc,
    /// More bytes than the longest frame before a 0x00; discarded up to the next 0x00.
    Overrun,
    /// The frame is intact but from another protocol version (only `Hello` and `HelloRequest`
    /// are decoded across versions so that the handshake can report it).
    VersionMismatch { ours: u8, theirs: u8 },
    /// The frame is intact but its message id is unknown.
    UnknownId { msg_id: u8 },
    /// The payload did not decode as the message the id names.
    Payload { msg_id: u8 },
    /// The payload decoded but `extra` bytes were left over.
    TrailingBytes { msg_id: u8, extra: usize },
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DecodeError::Framing => f.write_str("invalid COBS framing or frame too short"),
            DecodeError::Crc => f.write_str("CRC-32C mismatch"),
            DecodeError::Overrun => f.write_str("frame longer than the maximum; resynchronising"),
            DecodeError::VersionMismatch { ours, theirs } => {
                write!(f, "protocol version mismatch: ours {ours}, theirs {theirs}")
            }
            DecodeError::UnknownId { msg_id } => write!(f, "unknown message id 0x{msg_id:02x}"),
            DecodeError::Payload { msg_id } => {
                write!(f, "payload of message 0x{msg_id:02x} does not decode")
            }
            DecodeError::TrailingBytes { msg_id, extra } => {
                write!(
                    f,
                    "payload of message 0x{msg_id:02x} has {extra} trailing bytes"
                )
            }
        }
    }
}

/// Incremental frame decoder: feed bytes in any chunks; a frame ends at each 0x00.
///
/// After any error the decoder waits for the next 0x00 and starts afresh, so garbage costs at
/// most the frame it hits. Empty frames (consecutive 0x00) are ignored, so a sender may send a
/// 0x00 first to flush a half frame at the receiver.
///
/// Short headers carry the low 32 bits of the time; the decoder extends them from the previous
/// frame's time ([`extend_time`]), which a long header (`Status`, ten a second) sets whole. A
/// sequence restart (the sender rebooted) forgets the time, as [`Self::reset`] does.
pub struct FrameDecoder {
    buf: [u8; MAX_FRAME_LEN],
    len: usize,
    /// Overran: drop bytes until the next 0x00.
    discarding: bool,
    last_seq: Option<u16>,
    /// The last frame's full time (µs), which extends the next short header's.
    last_t_us: Option<u64>,
    counters: LinkCounters,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameDecoder {
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_FRAME_LEN],
            len: 0,
            discarding: false,
            last_seq: None,
            last_t_us: None,
            counters: LinkCounters {
                rx_bytes: 0,
                rx_frames: 0,
                crc_errors: 0,
                framing_errors: 0,
                overruns: 0,
                resyncs: 0,
                decode_errors: 0,
                unknown_ids: 0,
                version_errors: 0,
                seq_gaps: 0,
                frames_lost: 0,
                seq_resets: 0,
            },
        }
    }

    pub fn counters(&self) -> &LinkCounters {
        &self.counters
    }

    /// Forget a half-received frame and the sequence history (e.g. after reopening the port).
    pub fn reset(&mut self) {
        self.len = 0;
        self.discarding = false;
        self.last_seq = None;
        self.last_t_us = None;
    }

    /// Feed one byte; returns a frame (or the reason a candidate was rejected) when a 0x00
    /// completes one, or when an overrun is detected.
    pub fn push(&mut self, byte: u8) -> Option<Result<Frame, DecodeError>> {
        if byte != 0 {
            return self.absorb(&[byte]);
        }
        // Delimiter.
        let c = &mut self.counters;
        c.rx_bytes = c.rx_bytes.wrapping_add(1);
        let len = core::mem::replace(&mut self.len, 0);
        if core::mem::replace(&mut self.discarding, false) || len == 0 {
            return None;
        }
        Some(self.finish(len))
    }

    /// Feed a run of non-zero bytes (no delimiter): one copy. A run that does not fit is an
    /// overrun, reported once; the bytes up to the next 0x00 are then dropped.
    fn absorb(&mut self, run: &[u8]) -> Option<Result<Frame, DecodeError>> {
        let c = &mut self.counters;
        c.rx_bytes = c.rx_bytes.wrapping_add(run.len() as u32);
        if self.discarding || run.is_empty() {
            return None;
        }
        let end = self.len + run.len();
        match self.buf.get_mut(self.len..end) {
            Some(slot) => {
                slot.copy_from_slice(run);
                self.len = end;
                None
            }
            None => {
                self.discarding = true;
                self.len = 0;
                c.overruns = c.overruns.wrapping_add(1);
                c.resyncs = c.resyncs.wrapping_add(1);
                Some(Err(DecodeError::Overrun))
            }
        }
    }

    /// Take bytes from the front of `bytes` until a frame (or the reason a candidate was
    /// rejected) completes, and return it; `None` once `bytes` is used up (it is then empty).
    /// Bytes are taken a run at a time: everything up to the next 0x00 is copied in one piece
    /// (byte-at-a-time [`Self::push`] gives the same frames, errors and counters).
    pub fn next_from(&mut self, bytes: &mut &[u8]) -> Option<Result<Frame, DecodeError>> {
        while !bytes.is_empty() {
            let (run, rest) = bytes.split_at(find_zero(bytes).unwrap_or(bytes.len()));
            *bytes = rest;
            if let Some(r) = self.absorb(run) {
                return Some(r);
            }
            if let Some((_, rest)) = bytes.split_first() {
                *bytes = rest;
                if let Some(r) = self.push(0) {
                    return Some(r);
                }
            }
        }
        None
    }

    /// Feed a chunk; iterate over the frames (and errors) it completes. Bytes after the last
    /// item taken stay unconsumed if the iterator is dropped early, so drain it.
    pub fn push_slice<'a, 'b>(&'a mut self, bytes: &'b [u8]) -> PushSlice<'a, 'b> {
        PushSlice {
            decoder: self,
            bytes,
        }
    }

    fn finish(&mut self, len: usize) -> Result<Frame, DecodeError> {
        let r = self.check(len);
        let c = &mut self.counters;
        let counter = match r {
            Ok(_) => &mut c.rx_frames,
            Err(DecodeError::Framing) => &mut c.framing_errors,
            Err(DecodeError::Crc) => &mut c.crc_errors,
            Err(DecodeError::Overrun) => &mut c.overruns,
            Err(DecodeError::VersionMismatch { .. }) => &mut c.version_errors,
            Err(DecodeError::UnknownId { .. }) => &mut c.unknown_ids,
            Err(DecodeError::Payload { .. } | DecodeError::TrailingBytes { .. }) => {
                &mut c.decode_errors
            }
        };
        *counter = counter.wrapping_add(1);
        if matches!(r, Err(DecodeError::Framing | DecodeError::Crc)) {
            c.resyncs = c.resyncs.wrapping_add(1);
        }
        r
    }

    fn check(&mut self, len: usize) -> Result<Frame, DecodeError> {
        let candidate = self.buf.get_mut(..len).ok_or(DecodeError::Overrun)?;
        let raw_len = cobs_decode_in_place(candidate).ok_or(DecodeError::Framing)?;
        if raw_len < HEADER_LEN + CRC_LEN {
            return Err(DecodeError::Framing);
        }
        let Self {
            buf,
            last_seq,
            last_t_us,
            counters,
            ..
        } = self;
        // The decoded frame is buf[1..1 + raw_len]: body, then the CRC. Ranges by `get` and
        // `try_from`, which cannot panic (an MCU image without panic paths: build-mcu.sh).
        let crc_at = 1 + raw_len.checked_sub(CRC_LEN).ok_or(DecodeError::Framing)?;
        let body = buf.get(1..crc_at).ok_or(DecodeError::Framing)?;
        let crc_bytes = buf.get(crc_at..1 + raw_len).ok_or(DecodeError::Framing)?;
        let crc = <[u8; CRC_LEN]>::try_from(crc_bytes).map_err(|_| DecodeError::Framing)?;
        if crc32c(body) != u32::from_le_bytes(crc) {
            return Err(DecodeError::Crc);
        }
        let msg_id = body.get(1).copied().ok_or(DecodeError::Framing)?;
        let h_len = header_len(msg_id);
        let head = body.get(..h_len).ok_or(DecodeError::Framing)?;
        let mut seq = [0u8; 2];
        seq.copy_from_slice(head.get(2..4).ok_or(DecodeError::Framing)?);
        let seq = u16::from_le_bytes(seq);
        if track_seq(last_seq, counters, seq) {
            // The sender restarted: its clock did too.
            *last_t_us = None;
        }
        let mut t = [0u8; 8];
        let t_bytes = head.get(4..).ok_or(DecodeError::Framing)?;
        t.get_mut(..t_bytes.len())
            .ok_or(DecodeError::Framing)?
            .copy_from_slice(t_bytes);
        let t_us = if h_len == LONG_HEADER_LEN {
            u64::from_le_bytes(t)
        } else {
            extend_time(*last_t_us, u64::from_le_bytes(t) as u32)
        };
        *last_t_us = Some(t_us);
        let header = Header {
            version: body.first().copied().ok_or(DecodeError::Framing)?,
            msg_id,
            seq,
            t_us,
        };
        let frozen = msg_id == crate::id::HELLO || msg_id == crate::id::HELLO_REQUEST;
        if header.version != PROTOCOL_VERSION && !frozen {
            return Err(DecodeError::VersionMismatch {
                ours: PROTOCOL_VERSION,
                theirs: header.version,
            });
        }
        let payload = body.get(h_len..).ok_or(DecodeError::Framing)?;
        let message = Message::deserialize_payload(msg_id, payload).map_err(|e| match e {
            PayloadError::UnknownId => DecodeError::UnknownId { msg_id },
            PayloadError::Invalid => DecodeError::Payload { msg_id },
            PayloadError::TrailingBytes(extra) => DecodeError::TrailingBytes { msg_id, extra },
        })?;
        Ok(Frame { header, message })
    }
}

/// The full time of a short header from its low 32 bits: the value closest to the previous
/// frame's time `last_us` (±35.8 min), or the low bits alone when there is none (the first
/// 71.6 min after the sender's start, as after a restart). Never before 0.
pub fn extend_time(last_us: Option<u64>, low_us: u32) -> u64 {
    let Some(last) = last_us else {
        return u64::from(low_us);
    };
    let d = i64::from(low_us.wrapping_sub(last as u32) as i32);
    let t = (last as i64).saturating_add(d);
    if t < 0 {
        u64::from(low_us)
    } else {
        t as u64
    }
}

/// Count a gap or a restart; true when the sequence restarted.
fn track_seq(last_seq: &mut Option<u16>, c: &mut LinkCounters, seq: u16) -> bool {
    let mut restarted = false;
    {
        if let Some(last) = *last_seq {
            let gap = seq.wrapping_sub(last.wrapping_add(1));
            if gap != 0 {
                if gap < 0x8000 {
                    c.seq_gaps = c.seq_gaps.wrapping_add(1);
                    c.frames_lost = c.frames_lost.wrapping_add(gap as u32);
                } else {
                    c.seq_resets = c.seq_resets.wrapping_add(1);
                    restarted = true;
                }
            }
        }
        *last_seq = Some(seq);
    }
    restarted
}

/// Iterator returned by [`FrameDecoder::push_slice`].
pub struct PushSlice<'a, 'b> {
    decoder: &'a mut FrameDecoder,
    bytes: &'b [u8],
}

impl Iterator for PushSlice<'_, '_> {
    type Item = Result<Frame, DecodeError>;
    fn next(&mut self) -> Option<Self::Item> {
        self.decoder.next_from(&mut self.bytes)
    }
}

/// Index of the first 0x00 in `bytes`, 8 bytes per step: a word `x` holds a 0x00 iff
/// `(x − 0x01…01) & !x & 0x80…80 ≠ 0`, and its lowest set bit marks the first one (a borrow
/// can only flag bytes above a real 0x00).
fn find_zero(bytes: &[u8]) -> Option<usize> {
    const LO: u64 = 0x0101_0101_0101_0101;
    const HI: u64 = 0x8080_8080_8080_8080;
    let mut words = bytes.chunks_exact(8);
    let mut at = 0;
    for w in &mut words {
        let mut b = [0u8; 8];
        b.copy_from_slice(w);
        let x = u64::from_le_bytes(b);
        let z = x.wrapping_sub(LO) & !x & HI;
        if z != 0 {
            return Some(at + (z.trailing_zeros() / 8) as usize);
        }
        at += 8;
    }
    words
        .remainder()
        .iter()
        .position(|&b| b == 0)
        .map(|p| at + p)
}

/// COBS-decode `buf` in place (it holds no 0x00: the delimiters split frames); the decoded
/// bytes are `buf[1..1 + len]`, `None` for a code that runs past the end.
///
/// Each code byte stands for the 0x00 that ends its block (except a 0xFF block's and the last
/// block's), and sits exactly where that 0x00 belongs one byte later: so the decoding is a hop
/// from code to code writing 0x00 over each, the data never moving. Only after a 0xFF block
/// (254 data bytes, no 0x00: never in our frames, which are shorter) does the rest shift down
/// by one, a byte at a time. The `cobs` crate's decoding, without its per-byte copy.
pub(crate) fn cobs_decode_in_place(buf: &mut [u8]) -> Option<usize> {
    let n = buf.len();
    // The current block's code byte is at `r`; its data goes to `w` (= r + 1 until a 0xFF
    // block shifts the rest, then w <= r).
    let (mut r, mut w) = (0usize, 1usize);
    let mut code = usize::from(*buf.first()?);
    loop {
        if code == 0 || r + code > n {
            return None;
        }
        if w != r + 1 {
            for i in 1..code {
                let b = *buf.get(r + i)?;
                *buf.get_mut(w + i - 1)? = b;
            }
        }
        w += code - 1;
        r += code;
        if r >= n {
            return Some(w - 1);
        }
        // Read the next code before its place may take this block's 0x00.
        let next = usize::from(*buf.get(r)?);
        if code != 0xFF {
            *buf.get_mut(w)? = 0;
            w += 1;
        }
        code = next;
    }
}
