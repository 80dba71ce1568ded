//! u-blox UBX protocol parser (sans-IO) for NAV-PVT, plus a frame encoder for configuration.
//!
//! Source: u-blox 8 / u-blox M8 Receiver Description incl. Protocol Specification
//! (UBX-13003221), chapter "UBX Protocol". Frame structure: sync chars 0xB5 0x62, class, ID,
//! 2-byte little-endian payload length, payload, CK_A CK_B. Checksum: 8-bit Fletcher over
//! class, ID, length and payload (`CK_A += b; CK_B += CK_A`, modulo 256). UBX-NAV-PVT
//! (class 0x01, ID 0x07, 92 bytes): iTOW U4 @0, fixType U1 @20 (0 no fix, 1 dead reckoning,
//! 2 2D, 3 3D, 4 GNSS + DR, 5 time only), flags X1 @21 (bit 0 gnssFixOK), numSV U1 @23,
//! lon I4 @24 and lat I4 @28 (1e-7 deg), height I4 @32 (above the ellipsoid, mm), hMSL I4 @36
//! (mm), hAcc U4 @40, vAcc U4 @44 (mm), velN/velE/velD I4 @48/52/56 (mm/s), gSpeed I4 @60,
//! headMot I4 @64 (1e-5 deg), sAcc U4 @68 (mm/s), pDOP U2 @76 (0.01).
//! Also decoded: UBX-ACK-ACK (0x05 0x01) / ACK-NAK (0x05 0x00), 2 bytes: class and ID acked.
//!
//! Rejections are counted: bad checksum, a length above [`MAX_LEN`] (taken as a corrupted
//! header, the parser resynchronises at the next byte), a known message with the wrong
//! length, and well-formed messages this parser does not decode ("unknown", skipped without
//! buffering when longer than the buffer).

use fcc_firmware::sensors::GpsFix;

pub const SYNC1: u8 = 0xB5;
pub const SYNC2: u8 = 0x62;
pub const CLASS_NAV: u8 = 0x01;
pub const ID_NAV_PVT: u8 = 0x07;
pub const CLASS_ACK: u8 = 0x05;
pub const ID_ACK_ACK: u8 = 0x01;
pub const ID_ACK_NAK: u8 = 0x00;
pub const NAV_PVT_LEN: usize = 92;
/// Payloads kept in the buffer (NAV-PVT is the largest we decode).
pub const BUF_LEN: usize = 100;
/// Longest payload accepted at all; longer lengths are treated as a corrupted header. u-blox
/// M8 messages stay well below this (NAV-SAT with 60 satellites: 728 bytes).
pub const MAX_LEN: u16 = 1024;

/// UBX-NAV-PVT, the fields the flight stack uses (units as on the wire).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NavPvt {
    pub itow_ms: u32,
    pub fix_type: u8,
    pub flags: u8,
    pub num_sv: u8,
    pub lon_e7: i32,
    pub lat_e7: i32,
    pub height_mm: i32,
    pub hmsl_mm: i32,
    pub h_acc_mm: u32,
    pub v_acc_mm: u32,
    /// velN, velE, velD (offsets 48, 52, 56).
    pub vel_ned_mm_s: [i32; 3],
    pub g_speed_mm_s: i32,
    pub head_mot_e5: i32,
    pub s_acc_mm_s: u32,
    pub p_dop_e2: u16,
    /// flags3 @78 (protocol ≥ 27, u-blox F9; reserved = 0 on M8): bit 0 invalidLlh.
    pub flags3: u8,
}

impl NavPvt {
    /// Decode a 92-byte payload.
    pub fn from_payload(p: &[u8]) -> Option<NavPvt> {
        if p.len() != NAV_PVT_LEN {
            return None;
        }
        let u4 = |o: usize| -> u32 {
            p.get(o..o + 4)
                .and_then(|s| <[u8; 4]>::try_from(s).ok())
                .map(u32::from_le_bytes)
                .unwrap_or(0)
        };
        let i4 = |o: usize| u4(o) as i32;
        let u1 = |o: usize| p.get(o).copied().unwrap_or(0);
        Some(NavPvt {
            itow_ms: u4(0),
            fix_type: u1(20),
            flags: u1(21),
            num_sv: u1(23),
            lon_e7: i4(24),
            lat_e7: i4(28),
            height_mm: i4(32),
            hmsl_mm: i4(36),
            h_acc_mm: u4(40),
            v_acc_mm: u4(44),
            vel_ned_mm_s: [i4(48), i4(52), i4(56)],
            g_speed_mm_s: i4(60),
            head_mot_e5: i4(64),
            s_acc_mm_s: u4(68),
            p_dop_e2: u16::from_le_bytes([u1(76), u1(77)]),
            flags3: u1(78),
        })
    }

    pub fn lat_deg(&self) -> f64 {
        self.lat_e7 as f64 * 1e-7
    }
    pub fn lon_deg(&self) -> f64 {
        self.lon_e7 as f64 * 1e-7
    }
    /// flags bit 0: a valid fix (within the DOP and accuracy masks).
    pub fn gnss_fix_ok(&self) -> bool {
        self.flags & 0x01 != 0
    }
    /// flags3 bit 0 (newer receivers): lon, lat, height and hMSL are invalid.
    pub fn invalid_llh(&self) -> bool {
        self.flags3 & 0x01 != 0
    }
    /// A 3-D fix the navigation may use: gnssFixOK, fixType 3 (3D) or 4 (GNSS + DR), and the
    /// position not marked invalid.
    pub fn fix_3d_ok(&self) -> bool {
        self.gnss_fix_ok() && (self.fix_type == 3 || self.fix_type == 4) && !self.invalid_llh()
    }

    /// As the flight core's [`GpsFix`] (arrival time `now_us`; height above the ellipsoid, as
    /// `GpsFix::alt_m` is defined).
    pub fn to_gps_fix(&self, now_us: u64) -> GpsFix {
        GpsFix {
            t_us: now_us,
            lat_deg: self.lat_deg(),
            lon_deg: self.lon_deg(),
            alt_m: self.height_mm as f32 / 1000.0,
            vel_ned_mps: self.vel_ned_mm_s.map(|v| v as f32 / 1000.0),
            h_acc_m: self.h_acc_mm as f32 / 1000.0,
            num_sats: self.num_sv,
            fix_ok: self.fix_3d_ok(),
        }
    }
}

/// What the parser hands out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UbxMessage {
    NavPvt(NavPvt),
    Ack { class: u8, id: u8 },
    Nak { class: u8, id: u8 },
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UbxStats {
    pub messages: u32,
    pub bad_checksum: u32,
    /// Length field above [`MAX_LEN`].
    pub oversize: u32,
    /// A decoded class/ID with the wrong payload length.
    pub bad_length: u32,
    /// Valid frames of messages not decoded here.
    pub unknown: u32,
    /// Bytes dropped while hunting for the sync characters.
    pub skipped_bytes: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum St {
    Sync1,
    Sync2,
    Class,
    Id,
    Len1,
    Len2,
    Payload,
    CkA,
    CkB,
}

/// Byte-at-a-time UBX parser.
#[derive(Clone, Debug)]
pub struct UbxParser {
    st: St,
    class: u8,
    id: u8,
    len: u16,
    pos: u16,
    ck_a: u8,
    ck_b: u8,
    rx_ck_a: u8,
    buf: [u8; BUF_LEN],
    pub stats: UbxStats,
}

impl Default for UbxParser {
    fn default() -> Self {
        Self::new()
    }
}

impl UbxParser {
    pub fn new() -> Self {
        Self {
            st: St::Sync1,
            class: 0,
            id: 0,
            len: 0,
            pos: 0,
            ck_a: 0,
            ck_b: 0,
            rx_ck_a: 0,
            buf: [0; BUF_LEN],
            stats: UbxStats::default(),
        }
    }

    fn ck(&mut self, b: u8) {
        self.ck_a = self.ck_a.wrapping_add(b);
        self.ck_b = self.ck_b.wrapping_add(self.ck_a);
    }

    pub fn push(&mut self, b: u8) -> Option<UbxMessage> {
        match self.st {
            St::Sync1 => {
                if b == SYNC1 {
                    self.st = St::Sync2;
                } else {
                    self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(1);
                }
            }
            St::Sync2 => {
                if b == SYNC2 {
                    self.st = St::Class;
                    self.ck_a = 0;
                    self.ck_b = 0;
                } else if b == SYNC1 {
                    self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(1);
                } else {
                    self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(2);
                    self.st = St::Sync1;
                }
            }
            St::Class => {
                self.class = b;
                self.ck(b);
                self.st = St::Id;
            }
            St::Id => {
                self.id = b;
                self.ck(b);
                self.st = St::Len1;
            }
            St::Len1 => {
                self.len = b as u16;
                self.ck(b);
                self.st = St::Len2;
            }
            St::Len2 => {
                self.len |= (b as u16) << 8;
                self.ck(b);
                self.pos = 0;
                if self.len > MAX_LEN {
                    self.stats.oversize = self.stats.oversize.wrapping_add(1);
                    self.st = if b == SYNC1 { St::Sync2 } else { St::Sync1 };
                } else if self.len == 0 {
                    self.st = St::CkA;
                } else {
                    self.st = St::Payload;
                }
            }
            St::Payload => {
                self.ck(b);
                if let Some(slot) = self.buf.get_mut(self.pos as usize) {
                    *slot = b;
                }
                self.pos = self.pos.saturating_add(1);
                if self.pos >= self.len {
                    self.st = St::CkA;
                }
            }
            St::CkA => {
                self.rx_ck_a = b;
                self.st = St::CkB;
            }
            St::CkB => {
                self.st = St::Sync1;
                if self.rx_ck_a != self.ck_a || b != self.ck_b {
                    self.stats.bad_checksum = self.stats.bad_checksum.wrapping_add(1);
                    return None;
                }
                return self.finish();
            }
        }
        None
    }

    fn finish(&mut self) -> Option<UbxMessage> {
        let len = self.len as usize;
        let payload = if len <= BUF_LEN {
            self.buf.get(..len)
        } else {
            None
        };
        let msg = match (self.class, self.id) {
            (CLASS_NAV, ID_NAV_PVT) => match payload.and_then(NavPvt::from_payload) {
                Some(p) => Some(UbxMessage::NavPvt(p)),
                None => {
                    self.stats.bad_length = self.stats.bad_length.wrapping_add(1);
                    return None;
                }
            },
            (CLASS_ACK, ID_ACK_ACK) | (CLASS_ACK, ID_ACK_NAK) => match payload {
                Some(&[class, id]) => Some(if self.id == ID_ACK_ACK {
                    UbxMessage::Ack { class, id }
                } else {
                    UbxMessage::Nak { class, id }
                }),
                _ => {
                    self.stats.bad_length = self.stats.bad_length.wrapping_add(1);
                    return None;
                }
            },
            _ => None,
        };
        match msg {
            Some(_) => self.stats.messages = self.stats.messages.wrapping_add(1),
            None => self.stats.unknown = self.stats.unknown.wrapping_add(1),
        }
        msg
    }
}

/// Fletcher-8 checksum of class, ID, length and payload ("UBX checksum").
pub fn checksum(bytes: &[u8]) -> (u8, u8) {
    bytes.iter().fold((0u8, 0u8), |(a, b), &x| {
        let a = a.wrapping_add(x);
        (a, b.wrapping_add(a))
    })
}

/// Write a UBX frame into `out`; returns its length, `None` if `out` is too small or the
/// payload longer than 65535 bytes. Use it for configuration (CFG-RATE, CFG-MSG, CFG-VALSET…).
pub fn encode(class: u8, id: u8, payload: &[u8], out: &mut [u8]) -> Option<usize> {
    let len = u16::try_from(payload.len()).ok()?;
    let total = payload.len() + 8;
    let frame = out.get_mut(..total)?;
    let [l0, l1] = len.to_le_bytes();
    let (head, rest) = frame.split_at_mut(6);
    head.copy_from_slice(&[SYNC1, SYNC2, class, id, l0, l1]);
    let (body, ck) = rest.split_at_mut(payload.len());
    body.copy_from_slice(payload);
    let (a, b) = checksum(&[class, id, l0, l1]);
    let (a, b) = payload.iter().fold((a, b), |(a, b), &x| {
        let a = a.wrapping_add(x);
        (a, b.wrapping_add(a))
    });
    ck.copy_from_slice(&[a, b]);
    Some(total)
}

/// Configuration messages for a u-blox M8 on its UART1 (UBX-13003221, UBX-CFG messages). Each
/// writes a complete frame into `out` and returns its length (`None` if `out` is too small);
/// send them at the receiver's current baud rate and wait for the [`UbxMessage::Ack`].
pub mod config {
    use super::encode;

    /// UBX-CFG-PRT (0x06 0x00, 20 bytes) for UART1: 8N1 (mode 0x000008D0), `baud`, UBX + NMEA
    /// in, UBX only out.
    pub fn cfg_prt_uart1(baud: u32, out: &mut [u8]) -> Option<usize> {
        let mut p = [0u8; 20];
        p[0] = 1; // portID UART1
        p[4..8].copy_from_slice(&0x0000_08D0u32.to_le_bytes());
        p[8..12].copy_from_slice(&baud.to_le_bytes());
        p[12..14].copy_from_slice(&0x0003u16.to_le_bytes()); // inProtoMask UBX | NMEA
        p[14..16].copy_from_slice(&0x0001u16.to_le_bytes()); // outProtoMask UBX
        encode(0x06, 0x00, &p, out)
    }

    /// UBX-CFG-RATE (0x06 0x08, 6 bytes): measurement period, one solution per measurement,
    /// GPS time reference.
    pub fn cfg_rate(meas_period_ms: u16, out: &mut [u8]) -> Option<usize> {
        let [a, b] = meas_period_ms.to_le_bytes();
        encode(0x06, 0x08, &[a, b, 0x01, 0x00, 0x01, 0x00], out)
    }

    /// UBX-CFG-MSG (0x06 0x01, 3 bytes): output rate of a message on the current port
    /// (1 = every solution, 0 = off).
    pub fn cfg_msg(class: u8, id: u8, rate: u8, out: &mut [u8]) -> Option<usize> {
        encode(0x06, 0x01, &[class, id, rate], out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::testutil::Rng;

    fn feed(p: &mut UbxParser, s: &[u8]) -> Vec<UbxMessage> {
        s.iter().filter_map(|&b| p.push(b)).collect()
    }

    /// A NAV-PVT payload laid out by hand at the offsets of UBX-13003221 (UBX-NAV-PVT).
    fn pvt_payload() -> [u8; 92] {
        let mut p = [0u8; 92];
        let put = |p: &mut [u8; 92], o: usize, b: &[u8]| p[o..o + b.len()].copy_from_slice(b);
        put(&mut p, 0, &123_456_000u32.to_le_bytes()); // iTOW
        put(&mut p, 4, &2026u16.to_le_bytes());
        p[20] = 3; // fixType 3D
        p[21] = 0x01; // gnssFixOK
        p[23] = 14; // numSV
        put(&mut p, 24, &1_269_780_000i32.to_le_bytes()); // lon 126.978°
        put(&mut p, 28, &375_665_000i32.to_le_bytes()); // lat 37.5665°
        put(&mut p, 32, &(-12_345i32).to_le_bytes()); // height −12.345 m
        put(&mut p, 36, &25_000i32.to_le_bytes()); // hMSL 25 m
        put(&mut p, 40, &1_500u32.to_le_bytes()); // hAcc 1.5 m
        put(&mut p, 44, &2_500u32.to_le_bytes());
        put(&mut p, 48, &1_000i32.to_le_bytes()); // velN 1 m/s
        put(&mut p, 52, &(-2_000i32).to_le_bytes()); // velE −2 m/s
        put(&mut p, 56, &300i32.to_le_bytes()); // velD 0.3 m/s
        put(&mut p, 76, &125u16.to_le_bytes()); // pDOP 1.25
        p
    }

    #[test]
    fn protocol_spec_checksum_examples() {
        // UBX-ACK-ACK for CFG-RATE as printed in u-blox documents: B5 62 05 01 02 00 06 08 16 3F.
        let ack = [0xB5, 0x62, 0x05, 0x01, 0x02, 0x00, 0x06, 0x08, 0x16, 0x3F];
        assert_eq!(checksum(&ack[2..8]), (0x16, 0x3F));
        let mut p = UbxParser::new();
        assert_eq!(
            feed(&mut p, &ack),
            vec![UbxMessage::Ack {
                class: 0x06,
                id: 0x08
            }]
        );
        // CFG-RATE 200 ms, navRate 1, timeRef GPS: B5 62 06 08 06 00 C8 00 01 00 01 00 DE 6A.
        let mut out = [0u8; 32];
        let n = encode(0x06, 0x08, &[0xC8, 0x00, 0x01, 0x00, 0x01, 0x00], &mut out).unwrap();
        assert_eq!(
            &out[..n],
            &[0xB5, 0x62, 0x06, 0x08, 0x06, 0x00, 0xC8, 0x00, 0x01, 0x00, 0x01, 0x00, 0xDE, 0x6A]
        );
        // A NAK.
        let n = encode(0x05, 0x00, &[0x06, 0x01], &mut out).unwrap();
        assert_eq!(
            feed(&mut p, &out[..n]),
            vec![UbxMessage::Nak {
                class: 0x06,
                id: 0x01
            }]
        );
    }

    #[test]
    fn nav_pvt_fields_and_gps_fix() {
        let mut out = [0u8; 128];
        let n = encode(0x01, 0x07, &pvt_payload(), &mut out).unwrap();
        assert_eq!(n, 100);
        let mut p = UbxParser::new();
        let m = feed(&mut p, &out[..n]);
        let UbxMessage::NavPvt(pvt) = m[0] else {
            panic!("{m:?}")
        };
        assert_eq!(pvt.itow_ms, 123_456_000);
        assert_eq!((pvt.fix_type, pvt.num_sv, pvt.p_dop_e2), (3, 14, 125));
        assert!(pvt.fix_3d_ok());
        let f = pvt.to_gps_fix(77);
        assert_eq!(f.t_us, 77);
        assert!((f.lat_deg - 37.5665).abs() < 1e-9 && (f.lon_deg - 126.978).abs() < 1e-9);
        assert!((f.alt_m + 12.345).abs() < 1e-4);
        assert_eq!(pvt.hmsl_mm, 25_000);
        assert_eq!(f.vel_ned_mps, [1.0, -2.0, 0.3]);
        assert_eq!(f.h_acc_m, 1.5);
        assert_eq!(f.num_sats, 14);
        assert!(f.fix_ok);
        // Not a usable fix: gnssFixOK clear, or a 2D fix.
        let mut q = pvt_payload();
        q[21] = 0;
        let n = encode(0x01, 0x07, &q, &mut out).unwrap();
        let UbxMessage::NavPvt(x) = feed(&mut p, &out[..n])[0] else {
            panic!()
        };
        assert!(!x.to_gps_fix(0).fix_ok);
        q[21] = 1;
        q[20] = 2;
        let n = encode(0x01, 0x07, &q, &mut out).unwrap();
        let UbxMessage::NavPvt(x) = feed(&mut p, &out[..n])[0] else {
            panic!()
        };
        assert!(!x.fix_3d_ok());
        // Negative lat/lon (southern / western hemisphere).
        q[24..28].copy_from_slice(&(-1_234_567_890i32).to_le_bytes());
        q[28..32].copy_from_slice(&(-900_000_000i32).to_le_bytes());
        let n = encode(0x01, 0x07, &q, &mut out).unwrap();
        let UbxMessage::NavPvt(x) = feed(&mut p, &out[..n])[0] else {
            panic!()
        };
        assert!((x.lon_deg() + 123.456789).abs() < 1e-9 && (x.lat_deg() + 90.0).abs() < 1e-12);
    }

    #[test]
    fn rejections_are_counted() {
        let mut out = [0u8; 128];
        let mut p = UbxParser::new();
        // Bad checksum.
        let n = encode(0x01, 0x07, &pvt_payload(), &mut out).unwrap();
        let mut bad = out;
        bad[50] ^= 0x40;
        assert!(feed(&mut p, &bad[..n]).is_empty());
        assert_eq!(p.stats.bad_checksum, 1);
        // Oversize length: resync, and the good frame right after is still found.
        let mut s = vec![0xB5, 0x62, 0x01, 0x07, 0xFF, 0xFF];
        s.extend_from_slice(&out[..n]);
        assert_eq!(feed(&mut p, &s).len(), 1);
        assert_eq!(p.stats.oversize, 1);
        // NAV-PVT with a wrong length (a truncated payload, valid checksum).
        let n2 = encode(0x01, 0x07, &pvt_payload()[..84], &mut out).unwrap();
        assert!(feed(&mut p, &out[..n2]).is_empty());
        assert_eq!(p.stats.bad_length, 1);
        // Unknown messages, short and longer than the buffer (NAV-SAT-like, 500 bytes).
        let n3 = encode(0x01, 0x03, &[0u8; 16], &mut out).unwrap();
        assert!(feed(&mut p, &out[..n3]).is_empty());
        let mut big = [0u8; 600];
        let n4 = encode(0x01, 0x35, &[0x5A; 500], &mut big).unwrap();
        assert!(feed(&mut p, &big[..n4]).is_empty());
        assert_eq!(p.stats.unknown, 2);
        // Noise between frames, and a B5 B5 62 sequence.
        let n = encode(0x01, 0x07, &pvt_payload(), &mut out).unwrap();
        let mut s = vec![0x00, 0xB5, 0x13, 0xB5];
        s.extend_from_slice(&out[..n]);
        assert_eq!(feed(&mut p, &s).len(), 1);
        assert_eq!(p.stats.messages, 2);
    }

    #[test]
    fn config_frames() {
        let mut out = [0u8; 32];
        // CFG-MSG enabling NAV-PVT as commonly printed: B5 62 06 01 03 00 01 07 01 13 51.
        let n = config::cfg_msg(0x01, 0x07, 1, &mut out).unwrap();
        assert_eq!(
            &out[..n],
            &[0xB5, 0x62, 0x06, 0x01, 0x03, 0x00, 0x01, 0x07, 0x01, 0x13, 0x51]
        );
        let n = config::cfg_rate(200, &mut out).unwrap();
        assert_eq!(&out[6..8], &[0xC8, 0x00]);
        assert_eq!(n, 14);
        let n = config::cfg_prt_uart1(115_200, &mut out).unwrap();
        assert_eq!(n, 28);
        assert_eq!(&out[14..18], &115_200u32.to_le_bytes());
        assert_eq!(checksum(&out[2..26]), (out[26], out[27]));
        assert_eq!(config::cfg_prt_uart1(9600, &mut [0u8; 27]), None);
    }

    #[test]
    fn invalid_llh_flag_clears_the_fix() {
        let mut q = pvt_payload();
        q[78] = 0x01;
        let p = NavPvt::from_payload(&q).unwrap();
        assert!(p.gnss_fix_ok() && p.invalid_llh() && !p.fix_3d_ok());
    }

    #[test]
    fn encode_refuses_small_buffer() {
        let mut out = [0u8; 9];
        assert_eq!(encode(1, 7, &[0, 0], &mut out), None);
        assert_eq!(encode(1, 7, &[0], &mut out), Some(9));
    }

    #[test]
    fn any_bytes_never_panic() {
        let mut rng = Rng(0xB562);
        let mut p = UbxParser::new();
        for _ in 0..300_000 {
            let _ = p.push(rng.biased(&[0xB5, 0x62, 0x01, 0x07, 0x05, 0x5C, 0x00]));
        }
        // Random frames with valid checksums and random payloads of every length up to 120.
        let mut out = [0u8; 200];
        for _ in 0..5_000 {
            let len = (rng.next_u64() % 120) as usize;
            let mut pl = [0u8; 120];
            pl.iter_mut().for_each(|b| *b = rng.byte());
            let class = if rng.byte() & 1 == 0 { 0x01 } else { 0x05 };
            let id = [0x07, 0x00, 0x01][(rng.next_u64() % 3) as usize];
            let n = encode(class, id, &pl[..len], &mut out).unwrap();
            for &b in &out[..n] {
                let _ = p.push(b);
            }
        }
        assert!(p.stats.bad_checksum > 0 && p.stats.bad_length > 0);
    }
}
