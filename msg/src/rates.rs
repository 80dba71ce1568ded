//! Per-stream telemetry rates (MCU → Linux) and the link budget they imply.

use crate::frame::{header_len, CRC_LEN};
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
    /// Defaults: the `rates.*` rows of the parameter table ([`crate::for_each_mcu_param!`]);
    /// worst case ≈ 30 % of 921600 baud (see the test `default_rates_fit_budget`).
    pub const DEFAULT: StreamRates = {
        use crate::param_default as d;
        StreamRates {
            imu_raw_hz: d::RATES_IMU_HZ as u16,
            mag_raw_hz: d::RATES_MAG_HZ as u16,
            baro_raw_hz: d::RATES_BARO_HZ as u16,
            gps_raw_hz: d::RATES_GPS_HZ as u16,
            laser_raw_hz: d::RATES_LASER_HZ as u16,
            sonar_raw_hz: d::RATES_SONAR_HZ as u16,
            battery_hz: d::RATES_BATTERY_HZ as u16,
            nav_state_hz: d::RATES_NAV_STATE_HZ as u16,
            altitude_hz: d::RATES_ALTITUDE_HZ as u16,
            status_hz: d::RATES_STATUS_HZ as u16,
        }
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

    /// The rate of one stream.
    pub const fn hz(&self, s: Stream) -> u16 {
        match s {
            Stream::Status => self.status_hz,
            Stream::NavState => self.nav_state_hz,
            Stream::Altitude => self.altitude_hz,
            Stream::ImuRaw => self.imu_raw_hz,
            Stream::MagRaw => self.mag_raw_hz,
            Stream::BaroRaw => self.baro_raw_hz,
            Stream::GpsRaw => self.gps_raw_hz,
            Stream::LaserRaw => self.laser_raw_hz,
            Stream::SonarRaw => self.sonar_raw_hz,
            Stream::Battery => self.battery_hz,
        }
    }

    /// The rate of one stream changed to `hz`.
    pub fn set_hz(&mut self, s: Stream, hz: u16) {
        let f = match s {
            Stream::Status => &mut self.status_hz,
            Stream::NavState => &mut self.nav_state_hz,
            Stream::Altitude => &mut self.altitude_hz,
            Stream::ImuRaw => &mut self.imu_raw_hz,
            Stream::MagRaw => &mut self.mag_raw_hz,
            Stream::BaroRaw => &mut self.baro_raw_hz,
            Stream::GpsRaw => &mut self.gps_raw_hz,
            Stream::LaserRaw => &mut self.laser_raw_hz,
            Stream::SonarRaw => &mut self.sonar_raw_hz,
            Stream::Battery => &mut self.battery_hz,
        };
        *f = hz;
    }

    /// The rates read from parameter values (`param(id)` for each stream's
    /// [`Stream::param_id`]; a missing, negative or NaN value is 0 = off, fractions round down).
    pub fn from_params(param: impl Fn(u16) -> Option<f32>) -> StreamRates {
        let mut r = StreamRates::OFF;
        for s in Stream::ALL {
            let hz = param(s.param_id()).unwrap_or(0.0);
            // `as` saturates: NaN → 0, negative → 0, above u16::MAX → u16::MAX.
            r.set_hz(s, hz as u16);
        }
        r
    }

    /// Share of a link of `bytes_per_s` the worst case at these rates takes (1.0 = all of it).
    pub fn worst_case_share(&self, bytes_per_s: u32) -> f64 {
        self.worst_case_bytes_per_s() as f64 / bytes_per_s.max(1) as f64
    }

    /// (message id, rate) per stream, in [`Stream::ALL`] order.
    pub const fn streams(&self) -> [(u8, u16); Stream::COUNT] {
        let mut out = [(0u8, 0u16); Stream::COUNT];
        let mut i = 0;
        while i < Stream::COUNT {
            let s = Stream::ALL[i];
            out[i] = (s.msg_id(), self.hz(s));
            i += 1;
        }
        out
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
        Some(p) => cobs::max_encoding_length(header_len(msg_id) + p + CRC_LEN) + 1,
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

/// One telemetry stream of the MCU, in the order an endpoint sends them when several are due at
/// once (state first). `Stream as usize` indexes per-stream arrays ([`Stream::index`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    Status,
    NavState,
    Altitude,
    ImuRaw,
    MagRaw,
    BaroRaw,
    GpsRaw,
    /// `RangeRaw` from the laser.
    LaserRaw,
    /// `RangeRaw` from the sonar.
    SonarRaw,
    Battery,
}

impl Stream {
    pub const COUNT: usize = 10;
    /// Every stream, in send order.
    pub const ALL: [Stream; Stream::COUNT] = [
        Stream::Status,
        Stream::NavState,
        Stream::Altitude,
        Stream::ImuRaw,
        Stream::MagRaw,
        Stream::BaroRaw,
        Stream::GpsRaw,
        Stream::LaserRaw,
        Stream::SonarRaw,
        Stream::Battery,
    ];

    /// Position in [`Stream::ALL`] (for per-stream arrays).
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Its rate parameter (`rates.*` in the parameter table, [`crate::param_id`]).
    pub const fn param_id(self) -> u16 {
        use crate::param_id as p;
        match self {
            Stream::Status => p::RATES_STATUS_HZ,
            Stream::NavState => p::RATES_NAV_STATE_HZ,
            Stream::Altitude => p::RATES_ALTITUDE_HZ,
            Stream::ImuRaw => p::RATES_IMU_HZ,
            Stream::MagRaw => p::RATES_MAG_HZ,
            Stream::BaroRaw => p::RATES_BARO_HZ,
            Stream::GpsRaw => p::RATES_GPS_HZ,
            Stream::LaserRaw => p::RATES_LASER_HZ,
            Stream::SonarRaw => p::RATES_SONAR_HZ,
            Stream::Battery => p::RATES_BATTERY_HZ,
        }
    }

    /// The stream whose rate parameter is `id`.
    pub fn by_param_id(id: u16) -> Option<Stream> {
        Stream::ALL.into_iter().find(|s| s.param_id() == id)
    }

    /// The message id the stream sends.
    pub const fn msg_id(self) -> u8 {
        match self {
            Stream::Status => id::STATUS,
            Stream::NavState => id::NAV_STATE,
            Stream::Altitude => id::ALTITUDE_FUSION,
            Stream::ImuRaw => id::IMU_RAW,
            Stream::MagRaw => id::MAG_RAW,
            Stream::BaroRaw => id::BARO_RAW,
            Stream::GpsRaw => id::GPS_RAW,
            Stream::LaserRaw | Stream::SonarRaw => id::RANGE_RAW,
            Stream::Battery => id::BATTERY,
        }
    }
}

#[cfg(test)]
mod stream_tests {
    use super::*;

    #[test]
    fn all_is_in_index_order() {
        for (i, s) in Stream::ALL.iter().enumerate() {
            assert_eq!(s.index(), i);
        }
        let r = StreamRates::DEFAULT;
        assert_eq!(
            r.streams()[Stream::LaserRaw.index()],
            (id::RANGE_RAW, r.laser_raw_hz)
        );
        assert_eq!(r.streams()[0], (id::STATUS, r.status_hz));
    }

    #[test]
    fn rates_follow_the_parameter_table() {
        let table = |id: u16| crate::params::by_id(id).map(|p| p.default);
        assert_eq!(StreamRates::from_params(table), StreamRates::DEFAULT);
        for s in Stream::ALL {
            assert_eq!(Stream::by_param_id(s.param_id()), Some(s));
            let p = crate::params::by_id(s.param_id()).unwrap();
            assert!(
                p.name.starts_with("rates.") && p.name.ends_with("_hz"),
                "{}",
                p.name
            );
            assert_eq!(p.min, 0.0);
        }
        let mut r = StreamRates::DEFAULT;
        r.set_hz(Stream::ImuRaw, 7);
        assert_eq!(r.hz(Stream::ImuRaw), 7);
        assert_eq!(
            StreamRates::from_params(|_| Some(f32::NAN)),
            StreamRates::OFF
        );
        assert_eq!(StreamRates::from_params(|_| Some(-3.0)), StreamRates::OFF);
        assert_eq!(Stream::by_param_id(crate::param_id::MAX_TILT_DEG), None);
    }
}
