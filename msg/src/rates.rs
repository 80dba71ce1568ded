//! Per-stream telemetry rates (MCU → Linux) and the link budget they imply.

use crate::frame::{CRC_LEN, HEADER_LEN};
use crate::messages::{id, max_payload_len};

/// 921600 baud, 8N1: 10 bits per byte.
pub const BAUD_921600_BYTES_PER_S: u32 = 921_600 / 10;

/// Telemetry rates in Hz; 0 turns a stream off. A raw sensor stream sends the newest sample at
/// most at its rate and never repeats a sample, so a rate above the sensor's own rate means
/// "every sample".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamRates {
    pub imu_raw_hz: u16,
    pub mag_raw_hz: u16,
    pub baro_raw_hz: u16,
    pub gps_raw_hz: u16,
    pub laser_raw_hz: u16,
    pub sonar_raw_hz: u16,
    pub battery_hz: u16,
    pub nav_state_hz: u16,
    pub altitude_hz: u16,
    pub status_hz: u16,
}

impl Default for StreamRates {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl StreamRates {
    /// Defaults: worst case ≈ 30 % of 921600 baud (see the test `default_rates_fit_budget`).
    pub const DEFAULT: StreamRates = StreamRates {
        imu_raw_hz: 200,
        mag_raw_hz: 50,
        baro_raw_hz: 50,
        gps_raw_hz: 10,
        laser_raw_hz: 10,
        sonar_raw_hz: 10,
        battery_hz: 5,
        nav_state_hz: 100,
        altitude_hz: 50,
        status_hz: 10,
    };

    /// Every stream off.
    pub const OFF: StreamRates = StreamRates {
        imu_raw_hz: 0,
        mag_raw_hz: 0,
        baro_raw_hz: 0,
        gps_raw_hz: 0,
        laser_raw_hz: 0,
        sonar_raw_hz: 0,
        battery_hz: 0,
        nav_state_hz: 0,
        altitude_hz: 0,
        status_hz: 0,
    };

    /// (message id, rate) per stream, in the order an endpoint should send them when several
    /// are due at once (state first).
    pub const fn streams(&self) -> [(u8, u16); 10] {
        [
            (id::STATUS, self.status_hz),
            (id::NAV_STATE, self.nav_state_hz),
            (id::ALTITUDE_FUSION, self.altitude_hz),
            (id::IMU_RAW, self.imu_raw_hz),
            (id::MAG_RAW, self.mag_raw_hz),
            (id::BARO_RAW, self.baro_raw_hz),
            (id::GPS_RAW, self.gps_raw_hz),
            (id::RANGE_RAW, self.laser_raw_hz),
            (id::RANGE_RAW, self.sonar_raw_hz),
            (id::BATTERY, self.battery_hz),
        ]
    }

    /// Upper bound of the telemetry bytes/s at these rates (every frame at its largest size).
    pub const fn worst_case_bytes_per_s(&self) -> u32 {
        let s = self.streams();
        let mut total = 0u32;
        let mut i = 0;
        while i < s.len() {
            total += s[i].1 as u32 * max_frame_len(s[i].0) as u32;
            i += 1;
        }
        total
    }
}

/// Largest encoded frame (COBS + delimiter) of a message id; 0 for an unknown id.
pub const fn max_frame_len(msg_id: u8) -> usize {
    match max_payload_len(msg_id) {
        Some(p) => cobs::max_encoding_length(HEADER_LEN + p + CRC_LEN) + 1,
        None => 0,
    }
}

/// Period in µs for a rate in Hz (`None` = off).
pub const fn period_us(hz: u16) -> Option<u64> {
    if hz == 0 {
        None
    } else {
        Some(1_000_000 / hz as u64)
    }
}
