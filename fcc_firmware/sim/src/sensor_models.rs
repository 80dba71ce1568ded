//! Sensor models for the SITL: turn the true state into the samples the flight core sees
//! ([`fcc_firmware::sensors`]), with datasheet noise figures, biases, vibration, quantisation, rates
//! and latency.
//!
//! Every model owns a `ChaCha8Rng` seeded from the `seed` given to `new`, XOR a per-model
//! constant, so models are independent of each other and everything is reproducible.
//! Every `Params` struct deserialises with `#[serde(default)]`: a config file only names what it
//! changes.
//!
//! Sources of the default figures:
//! - InvenSense MPU-9250 Product Specification PS-MPU-9250A-01 rev 1.1: gyro rate noise
//!   spectral density 0.01 °/s/√Hz, initial ZRO tolerance ±5 °/s, full scale ±250…±2000 °/s,
//!   16-bit; accel noise power spectral density 300 µg/√Hz, initial zero-g offset ±60 mg (x/y),
//!   ±80 mg (z), ±2…±16 g, 16-bit. AK8963 (inside the MPU-9250): 0.6 µT/LSB at 14-bit,
//!   0.15 µT/LSB at 16-bit output.
//! - MEAS MS5611-01BA03 datasheet: resolution 0.012 mbar (1.2 Pa) at OSR 4096; in flight the
//!   reading is dominated by prop wash and dynamic pressure: tens of Pa.
//! - u-blox M8 (NEO-M8N) data sheet: 2.5 m CEP horizontal, 0.05 m/s velocity accuracy.
//! - PX4 SITL Gazebo GPS plugin (`gazebo_gps_plugin`): 5 Hz, 120 ms delay, position error as a
//!   Gauss–Markov random walk with a 60 s correlation time that settles near 1 m horizontally.

use std::collections::VecDeque;

use nalgebra::{UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;

use fcc_firmware::sensors::{BaroSample, BatterySample, GpsFix, ImuSample, MagSample};

/// Standard gravity, m/s² (used to convert g / mg / µg figures).
pub const G0: f64 = 9.80665;

/// A zero-mean normal draw with standard deviation `sigma` (0 if `sigma <= 0`).
/// Corner of the high-pass applied to the broadband vibration (Hz).
const VIB_HP_HZ: f64 = 30.0;

pub fn normal(rng: &mut ChaCha8Rng, sigma: f64) -> f64 {
    if sigma > 0.0 {
        let n: f64 = StandardNormal.sample(rng);
        n * sigma
    } else {
        0.0
    }
}

fn normal3(rng: &mut ChaCha8Rng, sigma: f64) -> Vector3<f64> {
    Vector3::new(normal(rng, sigma), normal(rng, sigma), normal(rng, sigma))
}

/// Round to the nearest multiple of `lsb` (no-op if `lsb <= 0`).
pub(crate) fn quantise(x: f64, lsb: f64) -> f64 {
    if lsb > 0.0 {
        (x / lsb).round() * lsb
    } else {
        x
    }
}

/// Fixed-rate scheduler: due at the first call, then every `period_us`.
#[derive(Clone, Debug)]
pub(crate) struct Schedule {
    period_us: u64,
    next_us: Option<u64>,
}

impl Schedule {
    pub(crate) fn new(rate_hz: f64) -> Self {
        let period_us = if rate_hz > 0.0 {
            (1e6 / rate_hz).round().max(1.0) as u64
        } else {
            u64::MAX
        };
        Self {
            period_us,
            next_us: None,
        }
    }
    pub(crate) fn due(&mut self, t_us: u64) -> bool {
        match self.next_us {
            None => {
                self.next_us = Some(t_us.saturating_add(self.period_us));
                true
            }
            Some(n) if t_us >= n => {
                // Keep the grid; skip missed slots rather than bursting.
                let mut next = n.saturating_add(self.period_us);
                while next <= t_us {
                    next = next.saturating_add(self.period_us);
                }
                self.next_us = Some(next);
                true
            }
            _ => false,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// IMU
// ---------------------------------------------------------------------------------------------

/// MPU-9250 gyro + accelerometer model.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImuParams {
    /// Gyro rate noise spectral density, °/s/√Hz (datasheet: 0.01).
    pub gyro_noise_density_dps_rthz: f64,
    /// Accel noise spectral density, µg/√Hz (datasheet: 300).
    pub accel_noise_density_ug_rthz: f64,
    /// Noise-equivalent bandwidth, Hz: 184 Hz = the gyro DLPF setting DLPF_CFG = 1
    /// (184 Hz bandwidth, 2.9 ms delay). The same figure is used for the accelerometer (its
    /// nearest setting, A_DLPF_CFG = 1, is 218 Hz). White noise σ = density·√bandwidth:
    /// gyro 0.136 °/s, accel 4.1 mg (0.040 m/s²).
    pub bandwidth_hz: f64,
    /// 1σ of the turn-on gyro bias, °/s. The datasheet's ±5 °/s is the worst-case initial ZRO
    /// tolerance; 1 °/s is taken as a typical 1σ part.
    pub gyro_bias_sigma_dps: f64,
    /// 1σ of the turn-on accel bias, mg (datasheet zero-g offset ±60 mg x/y, ±80 mg z worst
    /// case; 30 mg taken as 1σ).
    pub accel_bias_sigma_mg: f64,
    /// Gyro bias random walk, °/s per √s (in-run drift; 0.003 → 0.03 °/s after 100 s).
    pub gyro_bias_rw_dps_rts: f64,
    /// Accel bias random walk, m/s² per √s (0.0005 → 5 mm/s² ≈ 0.5 mg after 100 s).
    pub accel_bias_rw_mps2_rts: f64,
    /// Rotor speed at full command, rpm (650 Kv × 18.5 V ≈ 12 000 unloaded, ~9 000 loaded).
    pub rotor_max_rpm: f64,
    /// Mean rotor-speed fraction at hover (the physics default gives √(4.5·9.81/96) ≈ 0.68).
    pub hover_rotor_speed_frac: f64,
    /// Accelerometer vibration RMS per axis at hover, m/s² (ASSUMPTION: paper A Fig. 7 shows a
    /// very noisy in-flight accelerometer but gives no figure; 3 m/s² is typical of a soft-
    /// mounted FCC on a carbon octorotor). Split: 50 % of the power at the rotor frequency,
    /// 25 % at twice it, 25 % broadband. Amplitude scales with (rotor speed / hover)².
    pub accel_vib_rms_hover_mps2: f64,
    /// Gyro vibration RMS per axis at hover, °/s (smaller: same split and scaling).
    pub gyro_vib_rms_hover_dps: f64,
    /// Accel full scale, g (±8 g, 16-bit → 4096 LSB/g).
    pub accel_full_scale_g: f64,
    /// Gyro full scale, °/s (±1000 °/s, 16-bit → 32.8 LSB/(°/s)).
    pub gyro_full_scale_dps: f64,
}

impl Default for ImuParams {
    fn default() -> Self {
        Self {
            gyro_noise_density_dps_rthz: 0.01,
            accel_noise_density_ug_rthz: 300.0,
            bandwidth_hz: 184.0,
            gyro_bias_sigma_dps: 1.0,
            accel_bias_sigma_mg: 30.0,
            gyro_bias_rw_dps_rts: 0.003,
            accel_bias_rw_mps2_rts: 0.0005,
            rotor_max_rpm: 9000.0,
            hover_rotor_speed_frac: 0.68,
            accel_vib_rms_hover_mps2: 3.0,
            gyro_vib_rms_hover_dps: 0.5,
            accel_full_scale_g: 8.0,
            gyro_full_scale_dps: 1000.0,
        }
    }
}

/// MPU-9250 gyro/accel model, sampled at 500 Hz by the caller (every 2 ms).
#[derive(Clone, Debug)]
pub struct ImuModel {
    pub params: ImuParams,
    rng: ChaCha8Rng,
    gyro_bias_radps: Vector3<f64>,
    accel_bias_mps2: Vector3<f64>,
    /// Phase of the rotor fundamental, rad (integrated from the rotor frequency).
    rotor_phase_rad: f64,
    /// Per-axis phase offsets of the 1× and 2× components, accel then gyro.
    phase_offsets: [[f64; 2]; 6],
    /// One-pole low-pass state per channel, subtracted from the broadband vibration so it is
    /// structural (above ~30 Hz) and carries no power near DC.
    vib_lp: [f64; 6],
    last_t_us: Option<u64>,
}

impl ImuModel {
    pub fn new(params: ImuParams, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x1A7E_0001_0000_0001);
        let gyro_bias_radps = normal3(&mut rng, params.gyro_bias_sigma_dps.to_radians());
        let accel_bias_mps2 = normal3(&mut rng, params.accel_bias_sigma_mg * 1e-3 * G0);
        let mut phase_offsets = [[0.0; 2]; 6];
        for p in phase_offsets.iter_mut() {
            for x in p.iter_mut() {
                *x = rand::Rng::gen_range(&mut rng, 0.0..core::f64::consts::TAU);
            }
        }
        Self {
            params,
            rng,
            gyro_bias_radps,
            accel_bias_mps2,
            rotor_phase_rad: 0.0,
            phase_offsets,
            vib_lp: [0.0; 6],
            last_t_us: None,
        }
    }

    /// Current true biases (gyro rad/s, accel m/s²) — for tests and logging.
    pub fn biases(&self) -> (Vector3<f64>, Vector3<f64>) {
        (self.gyro_bias_radps, self.accel_bias_mps2)
    }

    /// White-noise σ of (gyro rad/s, accel m/s²).
    pub fn white_sigmas(&self) -> (f64, f64) {
        let bw = self.params.bandwidth_hz.max(0.0).sqrt();
        (
            (self.params.gyro_noise_density_dps_rthz * bw).to_radians(),
            self.params.accel_noise_density_ug_rthz * 1e-6 * G0 * bw,
        )
    }

    /// One IMU sample at `t_us` from the true body rate and specific force (FRD) and the mean
    /// rotor-speed fraction (0..1) that drives the vibration.
    pub fn sample(
        &mut self,
        t_us: u64,
        omega_frd_radps: Vector3<f64>,
        specific_force_frd_mps2: Vector3<f64>,
        rotor_speed_frac_mean: f64,
    ) -> ImuSample {
        let p = self.params.clone();
        let dt = match self.last_t_us {
            Some(t0) if t_us > t0 => (t_us - t0) as f64 * 1e-6,
            _ => 0.0,
        };
        self.last_t_us = Some(t_us);

        // Bias random walk.
        if dt > 0.0 {
            let sg = p.gyro_bias_rw_dps_rts.to_radians() * dt.sqrt();
            let sa = p.accel_bias_rw_mps2_rts * dt.sqrt();
            self.gyro_bias_radps += normal3(&mut self.rng, sg);
            self.accel_bias_mps2 += normal3(&mut self.rng, sa);
        }

        // Motor vibration: the fundamental at the rotor frequency and its 2nd harmonic, sampled
        // at the call instants (so a 2× component above 250 Hz aliases as on the real board),
        // plus broadband noise. Power split 50/25/25 %.
        let w = rotor_speed_frac_mean.clamp(0.0, 1.5);
        let f_rotor_hz = w * p.rotor_max_rpm / 60.0;
        self.rotor_phase_rad = (self.rotor_phase_rad + core::f64::consts::TAU * f_rotor_hz * dt)
            % core::f64::consts::TAU;
        let hover = p.hover_rotor_speed_frac.max(1e-3);
        let scale = (w / hover).powi(2);
        let mut vib = [0.0; 6];
        for (k, v) in vib.iter_mut().enumerate() {
            let rms = if k < 3 {
                p.accel_vib_rms_hover_mps2
            } else {
                p.gyro_vib_rms_hover_dps.to_radians()
            } * scale;
            if rms <= 0.0 {
                continue;
            }
            // Sinusoid RMS = A/√2: A1 = rms·√(2·0.5) = rms, A2 = rms·√(2·0.25).
            let a1 = rms;
            let a2 = rms * 0.5f64.sqrt();
            let ph = self.phase_offsets[k];
            // Broadband part: white noise high-passed at VIB_HP_HZ. Frame vibration is a
            // structural, high-frequency phenomenon; a white floor reaching DC would be a
            // velocity random walk hundreds of times the datasheet's, which no real IMU shows.
            let white = normal(&mut self.rng, rms * 0.5);
            let alpha = 1.0 - (-core::f64::consts::TAU * VIB_HP_HZ * dt).exp();
            self.vib_lp[k] += alpha * (white - self.vib_lp[k]);
            *v = a1 * (self.rotor_phase_rad + ph[0]).sin()
                + a2 * (2.0 * self.rotor_phase_rad + ph[1]).sin()
                + (white - self.vib_lp[k]);
        }

        let (sg, sa) = self.white_sigmas();
        let gyro = omega_frd_radps
            + self.gyro_bias_radps
            + normal3(&mut self.rng, sg)
            + Vector3::new(vib[3], vib[4], vib[5]);
        let accel = specific_force_frd_mps2
            + self.accel_bias_mps2
            + normal3(&mut self.rng, sa)
            + Vector3::new(vib[0], vib[1], vib[2]);

        let a_fs = p.accel_full_scale_g * G0;
        let a_lsb = a_fs / 32768.0;
        let g_fs = p.gyro_full_scale_dps.to_radians();
        let g_lsb = g_fs / 32768.0;
        let q = |x: f64, fs: f64, lsb: f64| quantise(x.clamp(-fs, fs - lsb), lsb) as f32;
        ImuSample {
            t_us,
            gyro_frd_radps: [
                q(gyro.x, g_fs, g_lsb),
                q(gyro.y, g_fs, g_lsb),
                q(gyro.z, g_fs, g_lsb),
            ],
            accel_frd_mps2: [
                q(accel.x, a_fs, a_lsb),
                q(accel.y, a_fs, a_lsb),
                q(accel.z, a_fs, a_lsb),
            ],
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Magnetometer
// ---------------------------------------------------------------------------------------------

/// AK8963 magnetometer model and the local Earth field.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MagParams {
    /// Output rate, Hz (AK8963 continuous mode 2: 100 Hz).
    pub rate_hz: f64,
    /// Total field intensity, µT (Seoul, ~37.5° N: ≈ 50 µT, WMM).
    pub field_total_ut: f64,
    /// Inclination (dip), degrees, positive down (≈ 53° at Seoul).
    pub inclination_deg: f64,
    /// Declination, degrees, positive east (≈ −8°, i.e. 8° W in Korea, as paper A says).
    pub declination_deg: f64,
    /// White noise σ, µT.
    pub noise_sigma_ut: f64,
    /// Residual hard-iron bias after calibration, body FRD, µT.
    pub hard_iron_frd_ut: [f64; 3],
    /// Output resolution, µT/LSB (0.15 at 16-bit output).
    pub resolution_ut: f64,
}

impl Default for MagParams {
    fn default() -> Self {
        Self {
            rate_hz: 100.0,
            field_total_ut: 50.0,
            inclination_deg: 53.0,
            declination_deg: -8.0,
            noise_sigma_ut: 0.3,
            hard_iron_frd_ut: [1.0, -0.5, 1.5],
            resolution_ut: 0.15,
        }
    }
}

impl MagParams {
    /// The Earth field in NED, µT.
    pub fn earth_field_ned_ut(&self) -> Vector3<f64> {
        let i = self.inclination_deg.to_radians();
        let d = self.declination_deg.to_radians();
        let h = self.field_total_ut * i.cos();
        Vector3::new(h * d.cos(), h * d.sin(), self.field_total_ut * i.sin())
    }
}

#[derive(Clone, Debug)]
pub struct MagModel {
    pub params: MagParams,
    rng: ChaCha8Rng,
    schedule: Schedule,
    disturbance_ned_ut: Vector3<f64>,
}

impl MagModel {
    pub fn new(params: MagParams, seed: u64) -> Self {
        let schedule = Schedule::new(params.rate_hz);
        Self {
            params,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x3A6_0002_0000_0002),
            schedule,
            disturbance_ned_ut: Vector3::zeros(),
        }
    }

    /// An extra field added to the Earth's (NED, µT), e.g. near a steel structure; zero clears it.
    pub fn set_disturbance(&mut self, field_ned_ut: Vector3<f64>) {
        self.disturbance_ned_ut = field_ned_ut;
    }

    pub fn sample(&mut self, t_us: u64, q_body_to_ned: &UnitQuaternion<f64>) -> Option<MagSample> {
        if !self.schedule.due(t_us) {
            return None;
        }
        let b_ned = self.params.earth_field_ned_ut() + self.disturbance_ned_ut;
        let b = q_body_to_ned.inverse_transform_vector(&b_ned)
            + Vector3::from(self.params.hard_iron_frd_ut)
            + normal3(&mut self.rng, self.params.noise_sigma_ut);
        let r = self.params.resolution_ut;
        Some(MagSample {
            t_us,
            mag_frd_ut: [
                quantise(b.x, r) as f32,
                quantise(b.y, r) as f32,
                quantise(b.z, r) as f32,
            ],
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Barometer
// ---------------------------------------------------------------------------------------------

/// MS5611 barometer model over the ISA troposphere.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BaroParams {
    /// Output rate, Hz.
    pub rate_hz: f64,
    /// Pressure at altitude 0 (sea-level-like reference), Pa.
    pub p0_pa: f64,
    /// Temperature at altitude 0, °C (the simulator sets it to the scenario's `air_temp_c`).
    pub t0_c: f64,
    /// Temperature lapse rate, K/m (ISA 0.0065).
    pub lapse_k_per_m: f64,
    /// White noise σ at rest, Pa.
    pub static_noise_pa: f64,
    /// In-flight white noise σ, Pa (prop wash).
    pub flight_white_noise_pa: f64,
    /// In-flight coloured (low-passed) noise σ, Pa; total in flight ≈ √(10² + 11²) ≈ 15 Pa.
    pub flight_colored_noise_pa: f64,
    /// Correlation time of the coloured part, s.
    pub flight_colored_tau_s: f64,
    /// Slow drift random walk, Pa/√s (0.2 → 2 Pa ≈ 0.17 m after 100 s).
    pub drift_rw_pa_rts: f64,
    /// Output resolution, Pa (0.012 mbar at OSR 4096).
    pub resolution_pa: f64,
    /// Sensor temperature above the air (self-heating), °C. The MS5611 converts at OSR 4096
    /// drawing 12.5 µA per sample per second (datasheet, supply current at 1 sample/s): at
    /// 50 Hz ≈ 0.6 mA × 3 V ≈ 2 mW; with the ~150 K/W of a small QFN on a board that is
    /// ≈ 0.3 °C (an estimate from the datasheet's current, not a datasheet figure).
    pub temperature_offset_c: f64,
}

impl Default for BaroParams {
    fn default() -> Self {
        Self {
            rate_hz: 50.0,
            p0_pa: 101_325.0,
            t0_c: 15.0,
            lapse_k_per_m: 0.0065,
            static_noise_pa: 1.2,
            flight_white_noise_pa: 10.0,
            flight_colored_noise_pa: 11.0,
            flight_colored_tau_s: 1.0,
            drift_rw_pa_rts: 0.2,
            resolution_pa: 1.2,
            temperature_offset_c: 0.3,
        }
    }
}

impl BaroParams {
    /// ISA pressure at `alt_m`, Pa.
    pub fn pressure_at(&self, alt_m: f64) -> f64 {
        const M: f64 = 0.028_964_4; // kg/mol
        const R: f64 = 8.314_462_618; // J/(mol·K)
        let t0 = self.t0_c + 273.15;
        if self.lapse_k_per_m.abs() < 1e-9 {
            self.p0_pa * (-G0 * M * alt_m / (R * t0)).exp()
        } else {
            let ratio = (1.0 - self.lapse_k_per_m * alt_m / t0).max(1e-6);
            self.p0_pa * ratio.powf(G0 * M / (R * self.lapse_k_per_m))
        }
    }
}

#[derive(Clone, Debug)]
pub struct BaroModel {
    pub params: BaroParams,
    rng: ChaCha8Rng,
    schedule: Schedule,
    colored_pa: f64,
    drift_pa: f64,
    last_t_us: Option<u64>,
}

impl BaroModel {
    pub fn new(params: BaroParams, seed: u64) -> Self {
        let schedule = Schedule::new(params.rate_hz);
        Self {
            params,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0xBA20_0003_0000_0003),
            schedule,
            colored_pa: 0.0,
            drift_pa: 0.0,
            last_t_us: None,
        }
    }

    /// `alt_m`: altitude above the reference of `p0_pa` (e.g. origin altitude − NED down);
    /// `in_flight`: rotors running / airborne (selects the prop-wash noise).
    pub fn sample(&mut self, t_us: u64, alt_m: f64, in_flight: bool) -> Option<BaroSample> {
        if !self.schedule.due(t_us) {
            return None;
        }
        let p = self.params.clone();
        let dt = match self.last_t_us {
            Some(t0) if t_us > t0 => (t_us - t0) as f64 * 1e-6,
            _ => 0.0,
        };
        self.last_t_us = Some(t_us);
        if dt > 0.0 {
            self.drift_pa += normal(&mut self.rng, p.drift_rw_pa_rts * dt.sqrt());
            let phi = if p.flight_colored_tau_s > 0.0 {
                (-dt / p.flight_colored_tau_s).exp()
            } else {
                0.0
            };
            self.colored_pa =
                phi * self.colored_pa + normal(&mut self.rng, (1.0 - phi * phi).sqrt());
        } else {
            self.colored_pa = normal(&mut self.rng, 1.0); // stationary start (unit variance)
        }
        let noise = if in_flight {
            normal(&mut self.rng, p.flight_white_noise_pa)
                + p.flight_colored_noise_pa * self.colored_pa
        } else {
            normal(&mut self.rng, p.static_noise_pa)
        };
        let pressure = p.pressure_at(alt_m) + self.drift_pa + noise;
        let temperature = p.t0_c - p.lapse_k_per_m * alt_m + p.temperature_offset_c;
        Some(BaroSample {
            t_us,
            pressure_pa: quantise(pressure, p.resolution_pa) as f32,
            temperature_c: (quantise(temperature, 0.01)) as f32,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// GPS
// ---------------------------------------------------------------------------------------------

/// u-blox M8-class receiver, error model after PX4's Gazebo GPS plugin.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GpsParams {
    /// Solution rate, Hz.
    pub rate_hz: f64,
    /// Delivery latency: the fix delivered at t was measured at t − latency, ms.
    pub latency_ms: f64,
    /// Horizontal error σ per axis (N, E), m — a first-order Gauss–Markov process.
    pub h_sigma_m: f64,
    /// Correlation time of the horizontal error, s.
    pub h_tau_s: f64,
    /// Vertical error σ, m.
    pub v_sigma_m: f64,
    /// Correlation time of the vertical error, s.
    pub v_tau_s: f64,
    /// Velocity white noise σ per axis, m/s.
    pub vel_sigma_mps: f64,
    /// Reference origin of the simulation's NED frame (Seoul City Hall by default).
    pub origin_lat_deg: f64,
    pub origin_lon_deg: f64,
    /// Ellipsoid height of the origin, m.
    pub origin_alt_m: f64,
    /// Satellites reported with a fix.
    pub num_sats: u8,
}

impl Default for GpsParams {
    fn default() -> Self {
        Self {
            rate_hz: 5.0,
            latency_ms: 120.0,
            h_sigma_m: 1.0,
            h_tau_s: 60.0,
            v_sigma_m: 1.5,
            v_tau_s: 60.0,
            vel_sigma_mps: 0.05,
            origin_lat_deg: 37.5665,
            origin_lon_deg: 126.9780,
            origin_alt_m: 40.0,
            num_sats: 12,
        }
    }
}

impl GpsParams {
    /// Local NED (m) → (lat °, lon °, ellipsoid height m) about the origin.
    ///
    /// Local tangent-plane conversion with the WGS-84 radii of curvature at the origin
    /// (meridian `M`, prime vertical `N`): Δlat = north/(M + h), Δlon = east/((N + h)·cos lat).
    /// The error against the exact ECEF route grows as (distance²/R): below 1 cm within 1 km
    /// of the origin, plenty for the simulator's flights.
    pub fn ned_to_lla(&self, ned_m: Vector3<f64>) -> (f64, f64, f64) {
        const A: f64 = 6_378_137.0;
        const E2: f64 = 6.694_379_990_14e-3;
        let lat0 = self.origin_lat_deg.to_radians();
        let s = lat0.sin();
        let w = (1.0 - E2 * s * s).sqrt();
        let n = A / w;
        let m = A * (1.0 - E2) / (w * w * w);
        let h0 = self.origin_alt_m;
        let lat = self.origin_lat_deg + (ned_m.x / (m + h0)).to_degrees();
        let lon = self.origin_lon_deg + (ned_m.y / ((n + h0) * lat0.cos())).to_degrees();
        (lat, lon, h0 - ned_m.z)
    }
}

#[derive(Clone, Debug)]
pub struct GpsModel {
    pub params: GpsParams,
    rng: ChaCha8Rng,
    schedule: Schedule,
    available: bool,
    jump_ned_m: Vector3<f64>,
    err_ned_m: Vector3<f64>,
    last_meas_us: Option<u64>,
    /// Measured fixes waiting for delivery: (delivery time, fix with measurement time).
    queue: VecDeque<(u64, GpsFix)>,
}

impl GpsModel {
    pub fn new(params: GpsParams, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6950_0004_0000_0004);
        // Start the Gauss–Markov errors from their stationary distribution.
        let err_ned_m = Vector3::new(
            normal(&mut rng, params.h_sigma_m),
            normal(&mut rng, params.h_sigma_m),
            normal(&mut rng, params.v_sigma_m),
        );
        let schedule = Schedule::new(params.rate_hz);
        Self {
            params,
            rng,
            schedule,
            available: true,
            jump_ned_m: Vector3::zeros(),
            err_ned_m,
            last_meas_us: None,
            queue: VecDeque::new(),
        }
    }

    /// GPS outage: while off, fixes measured are reported with `fix_ok = false`.
    /// A position error added to every fix (a jump: multipath, spoofing), NED m.
    pub fn set_jump(&mut self, offset_ned_m: Vector3<f64>) {
        self.jump_ned_m = offset_ned_m;
    }

    pub fn set_available(&mut self, on: bool) {
        self.available = on;
    }

    pub fn available(&self) -> bool {
        self.available
    }

    /// The current true position error (NED, m).
    pub fn error_ned_m(&self) -> Vector3<f64> {
        self.err_ned_m
    }

    fn latency_us(&self) -> u64 {
        (self.params.latency_ms.max(0.0) * 1000.0).round() as u64
    }

    /// Call every tick with the true position/velocity. When a measurement is due it is
    /// taken now and queued; a fix is returned once `latency_ms` has passed since its
    /// measurement (its `t_us` is the delivery time, i.e. measurement time + latency when the
    /// caller's tick divides the latency).
    pub fn sample(
        &mut self,
        t_us: u64,
        pos_ned_m: Vector3<f64>,
        vel_ned_mps: Vector3<f64>,
    ) -> Option<GpsFix> {
        if self.schedule.due(t_us) {
            let p = self.params.clone();
            let dt = match self.last_meas_us {
                Some(t0) if t_us > t0 => (t_us - t0) as f64 * 1e-6,
                _ => 0.0,
            };
            self.last_meas_us = Some(t_us);
            if dt > 0.0 {
                let step = |e: f64, sigma: f64, tau: f64, rng: &mut ChaCha8Rng| {
                    let phi = if tau > 0.0 { (-dt / tau).exp() } else { 0.0 };
                    phi * e + normal(rng, sigma * (1.0 - phi * phi).max(0.0).sqrt())
                };
                self.err_ned_m.x = step(self.err_ned_m.x, p.h_sigma_m, p.h_tau_s, &mut self.rng);
                self.err_ned_m.y = step(self.err_ned_m.y, p.h_sigma_m, p.h_tau_s, &mut self.rng);
                self.err_ned_m.z = step(self.err_ned_m.z, p.v_sigma_m, p.v_tau_s, &mut self.rng);
            }
            let fix = if self.available {
                let (lat, lon, alt) = p.ned_to_lla(pos_ned_m + self.err_ned_m + self.jump_ned_m);
                let v = vel_ned_mps + normal3(&mut self.rng, p.vel_sigma_mps);
                GpsFix {
                    t_us,
                    lat_deg: lat,
                    lon_deg: lon,
                    alt_m: alt as f32,
                    vel_ned_mps: [v.x as f32, v.y as f32, v.z as f32],
                    // Receiver's estimate: the 1σ horizontal radius √2·σ, rounded like a receiver.
                    h_acc_m: ((2f64.sqrt() * p.h_sigma_m * 10.0).round() / 10.0) as f32,
                    num_sats: p.num_sats,
                    fix_ok: true,
                }
            } else {
                // No solution: a receiver still reports, with no valid position.
                GpsFix {
                    t_us,
                    lat_deg: 0.0,
                    lon_deg: 0.0,
                    alt_m: 0.0,
                    vel_ned_mps: [0.0; 3],
                    h_acc_m: 9999.0,
                    num_sats: 0,
                    fix_ok: false,
                }
            };
            let deliver = t_us.saturating_add(self.latency_us());
            self.queue.push_back((deliver, fix));
        }
        match self.queue.front() {
            Some(&(deliver, _)) if deliver <= t_us => {
                let (_, mut fix) = self.queue.pop_front().unwrap();
                // Drop anything older that is also due (the caller skipped ticks): newest wins.
                while let Some(&(d, _)) = self.queue.front() {
                    if d <= t_us {
                        fix = self.queue.pop_front().unwrap().1;
                    } else {
                        break;
                    }
                }
                fix.t_us = t_us;
                Some(fix)
            }
            _ => None,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Battery
// ---------------------------------------------------------------------------------------------

/// 5S LiPo pack with an open-circuit-voltage curve and internal resistance.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BatteryParams {
    /// Series cells (5S).
    pub cells: u32,
    /// Capacity, mAh (5200).
    pub capacity_mah: f64,
    /// Total internal resistance of the pack, Ω (~20 mΩ for a 30C 5200 mAh 5S).
    pub internal_resistance_ohm: f64,
    /// Initial state of charge, 0..1.
    pub initial_soc: f64,
    /// Monitor rate, Hz.
    pub rate_hz: f64,
    /// ADC noise σ on the voltage, V.
    pub voltage_noise_v: f64,
    /// Current-sensor noise σ, A.
    pub current_noise_a: f64,
}

impl Default for BatteryParams {
    fn default() -> Self {
        Self {
            cells: 5,
            capacity_mah: 5200.0,
            internal_resistance_ohm: 0.020,
            initial_soc: 1.0,
            rate_hz: 10.0,
            voltage_noise_v: 0.02,
            current_noise_a: 0.2,
        }
    }
}

/// Open-circuit voltage of one LiPo cell vs state of charge (0..1): 3.5 V empty → 4.2 V full,
/// piecewise linear through a typical discharge curve.
pub fn lipo_cell_ocv_v(soc: f64) -> f64 {
    const TABLE: [(f64, f64); 12] = [
        (0.00, 3.50),
        (0.05, 3.60),
        (0.10, 3.68),
        (0.20, 3.73),
        (0.30, 3.77),
        (0.40, 3.80),
        (0.50, 3.84),
        (0.60, 3.87),
        (0.70, 3.92),
        (0.80, 3.98),
        (0.90, 4.07),
        (1.00, 4.20),
    ];
    let s = soc.clamp(0.0, 1.0);
    for w in TABLE.windows(2) {
        let (s0, v0) = w[0];
        let (s1, v1) = w[1];
        if s <= s1 {
            return v0 + (v1 - v0) * (s - s0) / (s1 - s0);
        }
    }
    TABLE[TABLE.len() - 1].1
}

#[derive(Clone, Debug)]
pub struct BatteryModel {
    pub params: BatteryParams,
    rng: ChaCha8Rng,
    schedule: Schedule,
    soc: f64,
    last_current_a: f64,
}

impl BatteryModel {
    pub fn new(params: BatteryParams, seed: u64) -> Self {
        let schedule = Schedule::new(params.rate_hz);
        let soc = params.initial_soc.clamp(0.0, 1.0);
        Self {
            params,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0xBA77_0005_0000_0005),
            schedule,
            soc,
            last_current_a: 0.0,
        }
    }

    /// State of charge, 0..1.
    pub fn soc(&self) -> f64 {
        self.soc
    }

    /// True terminal voltage at the last current, V.
    pub fn voltage_v(&self) -> f64 {
        self.params.cells as f64 * lipo_cell_ocv_v(self.soc)
            - self.last_current_a * self.params.internal_resistance_ohm
    }

    /// Call every step with the current drawn over the last `dt_s`; returns a monitor sample
    /// at `rate_hz`.
    pub fn sample(&mut self, t_us: u64, current_a: f64, dt_s: f64) -> Option<BatterySample> {
        let i = current_a.max(0.0);
        if dt_s > 0.0 && self.params.capacity_mah > 0.0 {
            self.soc = (self.soc - i * dt_s / (self.params.capacity_mah * 3.6)).max(0.0);
        }
        self.last_current_a = i;
        if !self.schedule.due(t_us) {
            return None;
        }
        let v = self.voltage_v() + normal(&mut self.rng, self.params.voltage_noise_v);
        let c = i + normal(&mut self.rng, self.params.current_noise_a);
        Some(BatterySample {
            t_us,
            voltage_v: v as f32,
            current_a: c.max(0.0) as f32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean_std(v: &[f64]) -> (f64, f64) {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (
            m,
            (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / v.len() as f64).sqrt(),
        )
    }

    fn quiet_imu() -> ImuParams {
        ImuParams {
            gyro_bias_rw_dps_rts: 0.0,
            accel_bias_rw_mps2_rts: 0.0,
            ..Default::default()
        }
    }

    #[test]
    fn imu_white_noise_matches_density() {
        let mut imu = ImuModel::new(quiet_imu(), 3);
        let (sg, sa) = imu.white_sigmas();
        assert!((sg.to_degrees() - 0.1356).abs() < 1e-3);
        assert!((sa - 0.0399).abs() < 1e-3);
        let (bg, ba) = imu.biases();
        let mut gx = vec![];
        let mut az = vec![];
        for k in 0..50_000u64 {
            let s = imu.sample(k * 2000, Vector3::zeros(), Vector3::new(0.0, 0.0, -G0), 0.0);
            gx.push(s.gyro_frd_radps[0] as f64);
            az.push(s.accel_frd_mps2[2] as f64);
        }
        let (mg, stdg) = mean_std(&gx);
        let (ma, stda) = mean_std(&az);
        // Quantisation adds lsb²/12 (gyro lsb 0.0305 °/s, accel 2.4 mm/s²): negligible.
        assert!((stdg / sg - 1.0).abs() < 0.1, "{stdg} vs {sg}");
        assert!((stda / sa - 1.0).abs() < 0.1, "{stda} vs {sa}");
        assert!((mg - bg.x).abs() < 3e-4);
        assert!((ma - (-G0 + ba.z)).abs() < 3e-3);
    }

    #[test]
    fn imu_vibration_at_hover() {
        let mut imu = ImuModel::new(quiet_imu(), 4);
        let mut ax = vec![];
        let mut gx = vec![];
        for k in 0..20_000u64 {
            let s = imu.sample(
                k * 2000,
                Vector3::zeros(),
                Vector3::new(0.0, 0.0, -G0),
                0.68,
            );
            ax.push(s.accel_frd_mps2[0] as f64);
            gx.push(s.gyro_frd_radps[0] as f64);
        }
        let (_, s) = mean_std(&ax);
        assert!(s > 2.0 && s < 4.0, "accel vib RMS {s}");
        let (_, sgy) = mean_std(&gx);
        assert!(
            sgy.to_degrees() > 0.3 && sgy.to_degrees() < 1.0,
            "gyro vib {sgy}"
        );
        // Motors off: no vibration.
        let mut imu = ImuModel::new(quiet_imu(), 4);
        let s = imu.sample(0, Vector3::zeros(), Vector3::zeros(), 0.0);
        assert!((s.accel_frd_mps2[0] as f64).abs() < 0.5);
    }

    #[test]
    fn imu_bias_drawn_per_seed_and_deterministic() {
        let a = ImuModel::new(ImuParams::default(), 1);
        let b = ImuModel::new(ImuParams::default(), 2);
        assert_ne!(a.biases(), b.biases());
        let mut a = ImuModel::new(ImuParams::default(), 9);
        let mut b = ImuModel::new(ImuParams::default(), 9);
        for k in 0..1000u64 {
            let w = Vector3::new(0.1, -0.2, 0.3);
            let f = Vector3::new(0.5, 0.1, -9.7);
            assert_eq!(a.sample(k * 2000, w, f, 0.7), b.sample(k * 2000, w, f, 0.7));
        }
    }

    #[test]
    fn imu_saturates() {
        let mut imu = ImuModel::new(quiet_imu(), 5);
        let s = imu.sample(
            0,
            Vector3::new(100.0, 0.0, 0.0),
            Vector3::new(0.0, 0.0, -200.0),
            0.0,
        );
        assert!((s.gyro_frd_radps[0] as f64 - 1000f64.to_radians()).abs() < 1e-3);
        assert!((s.accel_frd_mps2[2] as f64 + 8.0 * G0).abs() < 1e-3);
    }

    #[test]
    fn mag_field_rate_heading_and_disturbance() {
        let p = MagParams {
            hard_iron_frd_ut: [0.0; 3],
            ..Default::default()
        };
        let mut m = MagModel::new(p.clone(), 1);
        let yaw = 0.7f64;
        let q = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
        let mut n = 0;
        let mut hs = vec![];
        let mut xs = vec![];
        for k in 0..5000u64 {
            if let Some(s) = m.sample(k * 2000, &q) {
                n += 1;
                let (mx, my) = (s.mag_frd_ut[0] as f64, s.mag_frd_ut[1] as f64);
                hs.push((-my).atan2(mx) + p.declination_deg.to_radians());
                xs.push(s.mag_frd_ut[2] as f64);
            }
        }
        assert_eq!(n, 1000); // 10 s at 100 Hz
        let (mh, _) = mean_std(&hs);
        assert!((mh - yaw).abs() < 0.01, "{mh}");
        let (mz, sz) = mean_std(&xs);
        assert!((mz - 50.0 * 53f64.to_radians().sin()).abs() < 0.05);
        assert!((sz / 0.3 - 1.0).abs() < 0.15, "{sz}");
        let b = p.earth_field_ned_ut();
        assert!(b.y < 0.0 && (b.norm() - 50.0).abs() < 1e-9);
        m.set_disturbance(Vector3::new(0.0, 0.0, 30.0));
        let s = (10_000_000..10_020_000)
            .step_by(2000)
            .find_map(|t| m.sample(t, &q))
            .unwrap();
        assert!((s.mag_frd_ut[2] as f64 - (mz + 30.0)).abs() < 1.5);
    }

    #[test]
    fn baro_noise_rest_and_flight() {
        let mut b = BaroModel::new(
            BaroParams {
                drift_rw_pa_rts: 0.0,
                ..Default::default()
            },
            2,
        );
        let p0 = b.params.pressure_at(100.0);
        let (mut rest, mut flight) = (vec![], vec![]);
        for k in 0..200_000u64 {
            let t = k * 2000;
            if let Some(s) = b.sample(t, 100.0, k >= 100_000) {
                if k < 100_000 { &mut rest } else { &mut flight }.push(s.pressure_pa as f64 - p0);
            }
        }
        assert_eq!(rest.len(), 10_000); // 200 s at 50 Hz
        let (mr, sr) = mean_std(&rest);
        // f32 pressure near 1e5 Pa has 0.008 Pa resolution; quantisation 1.2 Pa adds 0.35 Pa rms.
        let expect_rest = (1.2f64.powi(2) + 1.2f64.powi(2) / 12.0).sqrt();
        assert!(
            mr.abs() < 0.1 && (sr / expect_rest - 1.0).abs() < 0.1,
            "{mr} {sr}"
        );
        let (_, sf) = mean_std(&flight);
        assert!(sf > 12.0 && sf < 18.0, "{sf}");
        // ISA: ~12 Pa per metre near sea level, 1013.25 hPa at 0.
        assert!((b.params.pressure_at(0.0) - 101_325.0).abs() < 1e-9);
        let dpdh = b.params.pressure_at(0.0) - b.params.pressure_at(1.0);
        assert!((dpdh - 12.0).abs() < 0.2, "{dpdh}");
        assert!((b.params.pressure_at(1000.0) - 89_875.0).abs() < 20.0);
    }

    #[test]
    fn gps_latency_is_exact_and_rate() {
        let p = GpsParams {
            h_sigma_m: 0.0,
            v_sigma_m: 0.0,
            vel_sigma_mps: 0.0,
            ..Default::default()
        };
        let mut g = GpsModel::new(p.clone(), 5);
        let speed = 3.0; // north, m/s
        let mut fixes = vec![];
        for k in 0..5000u64 {
            let t = k * 2000;
            let pos = Vector3::new(speed * t as f64 * 1e-6, 0.0, -10.0);
            if let Some(f) = g.sample(t, pos, Vector3::new(speed, 0.0, 0.0)) {
                fixes.push(f);
            }
        }
        assert_eq!(fixes.len(), 50); // 10 s at 5 Hz (the first arrives at 120 ms)
        assert_eq!(fixes[0].t_us, 120_000);
        for (i, f) in fixes.iter().enumerate() {
            assert_eq!(f.t_us, 120_000 + i as u64 * 200_000);
            // Position corresponds to the truth at t − 120 ms.
            let t_meas = (f.t_us - 120_000) as f64 * 1e-6;
            let (lat, _, alt) = p.ned_to_lla(Vector3::new(speed * t_meas, 0.0, -10.0));
            assert!((f.lat_deg - lat).abs() < 1e-10, "fix {i}");
            assert!((f.alt_m as f64 - alt).abs() < 1e-3);
            assert!(f.fix_ok);
        }
        // 1 m north ≈ 1/111 km in latitude.
        let (lat1, lon1, _) = p.ned_to_lla(Vector3::new(1000.0, 1000.0, 0.0));
        assert!(((lat1 - p.origin_lat_deg) * 110_990.0 - 1000.0).abs() < 2.0);
        assert!(
            ((lon1 - p.origin_lon_deg) * 111_320.0 * p.origin_lat_deg.to_radians().cos() - 1000.0)
                .abs()
                < 3.0
        );
    }

    #[test]
    fn gps_error_statistics_outage_and_determinism() {
        let p = GpsParams {
            h_tau_s: 10.0,
            v_tau_s: 10.0,
            ..Default::default()
        };
        let mut g = GpsModel::new(p.clone(), 11);
        let mut en = vec![];
        let mut vn = vec![];
        for k in 0..(2000 * 500u64) {
            // 2000 s at 500 Hz
            if let Some(f) = g.sample(k * 2000, Vector3::zeros(), Vector3::zeros()) {
                en.push((f.lat_deg - p.origin_lat_deg) * 110_990.0);
                vn.push(f.vel_ned_mps[0] as f64);
            }
        }
        let (_, s) = mean_std(&en);
        assert!((s - 1.0).abs() < 0.2, "{s}");
        let (_, sv) = mean_std(&vn);
        assert!((sv / 0.05 - 1.0).abs() < 0.1, "{sv}");

        let mut a = GpsModel::new(GpsParams::default(), 3);
        let mut b = GpsModel::new(GpsParams::default(), 3);
        let mut got_none = false;
        for k in 0..3000u64 {
            if k == 1000 {
                a.set_available(false);
                b.set_available(false);
            }
            let t = k * 2000;
            let fa = a.sample(t, Vector3::new(1.0, 2.0, -3.0), Vector3::zeros());
            assert_eq!(
                fa,
                b.sample(t, Vector3::new(1.0, 2.0, -3.0), Vector3::zeros())
            );
            if let Some(f) = fa {
                // Fixes measured after the outage began (t ≥ 2 s + latency) are invalid.
                if t >= 2_000_000 + 120_000 + 2000 {
                    assert!(!f.fix_ok);
                    got_none = true;
                } else if t < 2_000_000 {
                    assert!(f.fix_ok);
                }
            }
        }
        assert!(got_none);
    }

    #[test]
    fn battery_voltage_and_discharge() {
        let mut b = BatteryModel::new(
            BatteryParams {
                voltage_noise_v: 0.0,
                current_noise_a: 0.0,
                ..Default::default()
            },
            1,
        );
        let s = b.sample(0, 0.0, 0.0).unwrap();
        assert!((s.voltage_v - 21.0).abs() < 1e-4);
        let s = b.sample(100_000, 40.0, 0.1).unwrap();
        assert!(
            (s.voltage_v as f64 - (21.0 - 0.8)).abs() < 0.01,
            "{}",
            s.voltage_v
        );
        assert!(b.sample(150_000, 40.0, 0.05).is_none());
        // 5.2 Ah at 52 A = 6 min to empty.
        let mut t = 150_000u64;
        for _ in 0..(360 * 100 - 15) {
            t += 10_000;
            b.sample(t, 52.0, 0.01);
        }
        assert!(b.soc() < 1e-3, "{}", b.soc());
        assert!(
            (lipo_cell_ocv_v(0.0) - 3.5).abs() < 1e-12
                && (lipo_cell_ocv_v(0.5) - 3.84).abs() < 1e-12
        );
    }
}
