//! Downward rangefinder models for paper B: the MDL ILM-150-R laser altimeter and the MaxBotix
//! XL-MaxSonar-WRLA1 (MB7076) ultrasonic rangefinder, over a [`Terrain`].
//!
//! Both produce the sensor's serial line and parse it back (the path a real driver takes), so
//! the flight core sees exactly what the wire can carry: 1 cm resolution, the laser's 99 999 m
//! no-return sentinel, the sonar's 20 cm floor and 10.68 m ceiling.
//!
//! Same conventions as [`super::sensor_models`]: a `ChaCha8Rng` seeded from `seed` XOR a
//! per-model constant, `Params` with `#[serde(default)]`, fixed-rate schedules on a grid.
//!
//! Sources of the default figures (paper B Tables 1–2 quote both):
//! - MDL ILM-150-R leaflet: 0.5–150 m reflectorless (650 m to a reflector), accuracy 5 cm,
//!   resolution 1 cm, 9 Hz, RS-232. Paper B: over a dark surface or at oblique incidence it
//!   gets no return and outputs 99 999 m (Figs. 2–4, 13). The leaflet's exact ASCII framing is
//!   not available here; the modelled line is an ASSUMPTION, see [`laser_line`].
//! - MaxBotix XL-MaxSonar-WR/WRL datasheet (MB7066/MB7076 are the 10 m, 1 cm models): range
//!   0–10.68 m with objects closer than 20 cm reported as 20 cm, 10 Hz, 1 cm resolution, RS-232
//!   serial (9600 8N1) "R" + **four** ASCII digits of range in cm + CR (e.g. "R0123\r"; 1068 cm
//!   when nothing is detected). The issue says `R###`: three digits is the 7.65 m XL-MaxSonar
//!   (MB12xx/MB70x0) format and cannot carry 1068; four digits are modelled and the parser
//!   accepts three or four. Accuracy: 2 cm (paper B Table 2). The sensor converts echo time with
//!   a fixed speed of sound (its internal temperature compensation is not modelled, as paper B
//!   assumes), so the reading is off by `c0/c(T)`, `c(T) = 331.5 + 0.60714·T` (paper B eq. 1).
//!   Beam: the nearest surface in a cone, half-angle 15° (ASSUMPTION: the WR/WRL beam plots
//!   narrow to roughly ±10–20° for large targets); noisier under tilt (paper B Fig. 7):
//!   σ·(1 + tilt/15°).

use nalgebra::{UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

use super::sensor_models::normal;
use super::terrain::Terrain;
use fcc_firmware::sensors::{RangeSample, LASER_NO_RETURN_M};

/// Speed of sound in air, m/s, at `t_c` °C (paper B eq. 1).
pub fn speed_of_sound_mps(t_c: f64) -> f64 {
    331.5 + 0.60714 * t_c
}

use super::sensor_models::{quantise, Schedule};

/// What both rangefinders share: the fixed-rate schedule, the noise stream and the last serial
/// line, which is parsed back as a driver would.
#[derive(Clone, Debug)]
struct SerialOutput {
    rng: ChaCha8Rng,
    schedule: Schedule,
    last_line: String,
}

impl SerialOutput {
    /// `salt` separates each model's noise stream from the others' for the same `seed`.
    fn new(rate_hz: f64, seed: u64, salt: u64) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed ^ salt),
            schedule: Schedule::new(rate_hz),
            last_line: String::new(),
        }
    }

    /// Emit `line` at `t_us` and read it back with `parse` (`fallback_m` if that fails).
    fn emit(
        &mut self,
        t_us: u64,
        line: String,
        parse: fn(&str) -> Option<f32>,
        fallback_m: f32,
    ) -> RangeSample {
        let range_m = parse(&line).unwrap_or(fallback_m);
        self.last_line = line;
        RangeSample { t_us, range_m }
    }
}

// ---------------------------------------------------------------------------------------------
// Laser altimeter
// ---------------------------------------------------------------------------------------------

/// MDL ILM-150-R laser altimeter.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LaserParams {
    /// Output rate, Hz (ILM-150-R: 9 Hz; paper B's Table 3 says 50 Hz, the leaflet 9 Hz).
    pub rate_hz: f64,
    /// Minimum range, m (0.5); closer gives no valid return (the sentinel).
    pub min_range_m: f64,
    /// Maximum reflectorless range, m (150).
    pub max_range_m: f64,
    /// Range noise 1σ, m (accuracy 5 cm, taken as 1σ).
    pub sigma_m: f64,
    /// Output resolution, m (1 cm).
    pub resolution_m: f64,
    /// Largest incidence angle (beam vs surface normal) that still returns, degrees
    /// (ASSUMPTION: 25°; paper B's roll test at 30° and 45° shows the laser failing).
    pub max_incidence_deg: f64,
    /// Sensor position in the body FRD frame, m (relative to the body origin).
    pub mount_offset_frd_m: [f64; 3],
}

impl Default for LaserParams {
    fn default() -> Self {
        Self {
            rate_hz: 9.0,
            min_range_m: 0.5,
            max_range_m: 150.0,
            sigma_m: 0.05,
            resolution_m: 0.01,
            max_incidence_deg: 25.0,
            mount_offset_frd_m: [0.0; 3],
        }
    }
}

/// The laser's serial line (ASSUMED framing): `"D "`, the range in metres as 8 characters with
/// two decimals and leading zeros, CR LF — e.g. `"D 00001.23\r\n"`; no return is
/// `"D 99999.00\r\n"`.
pub fn laser_line(range_m: f64) -> String {
    let r = range_m.clamp(0.0, LASER_NO_RETURN_M as f64);
    format!("D {r:08.2}\r\n")
}

/// Parse a [`laser_line`]; `None` if malformed.
pub fn parse_laser_line(line: &str) -> Option<f32> {
    let body = line.strip_suffix("\r\n")?.strip_prefix("D ")?;
    if body.len() != 8 || body.as_bytes()[5] != b'.' {
        return None;
    }
    if !body
        .bytes()
        .enumerate()
        .all(|(i, c)| i == 5 || c.is_ascii_digit())
    {
        return None;
    }
    body.parse::<f32>().ok()
}

#[derive(Clone, Debug)]
pub struct LaserModel {
    pub params: LaserParams,
    out: SerialOutput,
}

impl LaserModel {
    pub fn new(params: LaserParams, seed: u64) -> Self {
        let out = SerialOutput::new(params.rate_hz, seed, 0x1A5E_0006_0000_0006);
        Self { params, out }
    }

    /// The last serial line produced.
    pub fn last_line(&self) -> &str {
        &self.out.last_line
    }

    /// The noise-free range the sensor would report (m), or the sentinel: no return over a dark
    /// surface, beyond the incidence limit, or outside 0.5–150 m.
    pub fn true_reading_m(
        &self,
        t_us: u64,
        pos_ned_m: Vector3<f64>,
        q_body_to_ned: &UnitQuaternion<f64>,
        terrain: &Terrain,
    ) -> f64 {
        let p = &self.params;
        let origin = pos_ned_m + q_body_to_ned * Vector3::from(p.mount_offset_frd_m);
        let t_s = t_us as f64 * 1e-6;
        match terrain.range_body_down(origin, q_body_to_ned, p.max_range_m) {
            Some(hit)
                if hit.range_m >= p.min_range_m
                    && hit.incidence_rad <= p.max_incidence_deg.to_radians()
                    && !terrain.is_dark(hit.point_ned_m.x, hit.point_ned_m.y, t_s) =>
            {
                hit.range_m
            }
            _ => LASER_NO_RETURN_M as f64,
        }
    }

    /// A reading when one is due (9 Hz), else `None`. `air_temp_c` is unused (light).
    pub fn sample(
        &mut self,
        t_us: u64,
        pos_ned_m: Vector3<f64>,
        q_body_to_ned: &UnitQuaternion<f64>,
        terrain: &Terrain,
        _air_temp_c: f64,
    ) -> Option<RangeSample> {
        if !self.out.schedule.due(t_us) {
            return None;
        }
        let truth = self.true_reading_m(t_us, pos_ned_m, q_body_to_ned, terrain);
        let r = if truth >= LASER_NO_RETURN_M as f64 {
            truth
        } else {
            let n = normal(&mut self.out.rng, self.params.sigma_m);
            quantise((truth + n).max(0.0), self.params.resolution_m)
        };
        Some(
            self.out
                .emit(t_us, laser_line(r), parse_laser_line, LASER_NO_RETURN_M),
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Ultrasonic rangefinder
// ---------------------------------------------------------------------------------------------

/// MaxBotix XL-MaxSonar-WRLA1 (MB7076).
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SonarParams {
    /// Sensor position in the body FRD frame, m.
    pub mount_offset_frd_m: [f64; 3],
    /// Output rate, Hz (10).
    pub rate_hz: f64,
    /// Minimum reported range, m (objects closer than 20 cm are reported as 20 cm).
    pub min_report_m: f64,
    /// Maximum range, m (10.68; also reported when nothing is detected).
    pub max_range_m: f64,
    /// Noise 1σ when level, m (2 cm accuracy).
    pub sigma_m: f64,
    /// σ grows as σ·(1 + tilt/ref), ref in degrees (15°: ×3 at 30°, ×4 at 45°; paper B Fig. 7).
    pub sigma_tilt_ref_deg: f64,
    /// Output resolution, m (1 cm).
    pub resolution_m: f64,
    /// Beam half-angle, degrees (15°): the nearest surface within it is reported.
    pub beam_half_angle_deg: f64,
    /// Fixed speed of sound the sensor converts with, m/s (343.2, the usual 20 °C figure).
    pub c0_mps: f64,
}

impl Default for SonarParams {
    fn default() -> Self {
        Self {
            mount_offset_frd_m: [0.0; 3],
            rate_hz: 10.0,
            min_report_m: 0.20,
            max_range_m: 10.68,
            sigma_m: 0.02,
            sigma_tilt_ref_deg: 15.0,
            resolution_m: 0.01,
            beam_half_angle_deg: 15.0,
            c0_mps: 343.2,
        }
    }
}

/// The sonar's serial line: `"R"`, four ASCII digits of range in cm, CR (e.g. `"R0123\r"`).
pub fn sonar_line(range_m: f64) -> String {
    let cm = (range_m * 100.0).round().clamp(0.0, 9999.0) as u32;
    format!("R{cm:04}\r")
}

/// Parse an `R####\r` (or the 3-digit `R###\r`) line to metres; `None` if malformed.
pub fn parse_sonar_line(line: &str) -> Option<f32> {
    let digits = line.strip_suffix('\r')?.strip_prefix('R')?;
    if !(digits.len() == 3 || digits.len() == 4) || !digits.bytes().all(|c| c.is_ascii_digit()) {
        return None;
    }
    digits.parse::<u32>().ok().map(|cm| cm as f32 / 100.0)
}

#[derive(Clone, Debug)]
pub struct SonarModel {
    pub params: SonarParams,
    out: SerialOutput,
}

impl SonarModel {
    pub fn new(params: SonarParams, seed: u64) -> Self {
        let out = SerialOutput::new(params.rate_hz, seed, 0x50AA_0007_0000_0007);
        Self { params, out }
    }

    /// The last serial line produced.
    pub fn last_line(&self) -> &str {
        &self.out.last_line
    }

    /// Tilt of body-down from local vertical, rad.
    fn tilt_rad(q_body_to_ned: &UnitQuaternion<f64>) -> f64 {
        (q_body_to_ned * Vector3::z()).z.clamp(-1.0, 1.0).acos()
    }

    /// The noise-free reading, m: the nearest surface in the beam, scaled by `c0/c(T)`,
    /// limited to [20 cm, 10.68 m]; 10.68 m when nothing is in range.
    pub fn true_reading_m(
        &self,
        pos_ned_m: Vector3<f64>,
        q_body_to_ned: &UnitQuaternion<f64>,
        terrain: &Terrain,
        air_temp_c: f64,
    ) -> f64 {
        let p = &self.params;
        let origin = pos_ned_m + q_body_to_ned * Vector3::from(p.mount_offset_frd_m);
        let c = speed_of_sound_mps(air_temp_c);
        let scale = if c > 0.0 && air_temp_c.is_finite() {
            p.c0_mps / c
        } else {
            1.0
        };
        // The sensor's listening window is its max range at c0: geometric max = max·c/c0.
        let geo_max = p.max_range_m / scale;
        match terrain.range_cone(
            origin,
            q_body_to_ned,
            p.beam_half_angle_deg.to_radians(),
            geo_max,
        ) {
            Some(hit) => (hit.range_m * scale).clamp(p.min_report_m, p.max_range_m),
            None => p.max_range_m,
        }
    }

    /// A reading when one is due (10 Hz), else `None`.
    pub fn sample(
        &mut self,
        t_us: u64,
        pos_ned_m: Vector3<f64>,
        q_body_to_ned: &UnitQuaternion<f64>,
        terrain: &Terrain,
        air_temp_c: f64,
    ) -> Option<RangeSample> {
        if !self.out.schedule.due(t_us) {
            return None;
        }
        let p = self.params.clone();
        let truth = self.true_reading_m(pos_ned_m, q_body_to_ned, terrain, air_temp_c);
        let r = if truth >= p.max_range_m {
            p.max_range_m
        } else {
            let tilt_deg = Self::tilt_rad(q_body_to_ned).to_degrees();
            let sigma = if p.sigma_tilt_ref_deg > 0.0 {
                p.sigma_m * (1.0 + tilt_deg / p.sigma_tilt_ref_deg)
            } else {
                p.sigma_m
            };
            let n = normal(&mut self.out.rng, sigma);
            quantise(truth + n, p.resolution_m).clamp(p.min_report_m, p.max_range_m)
        };
        Some(
            self.out
                .emit(t_us, sonar_line(r), parse_sonar_line, p.max_range_m as f32),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::terrain::{DarkPatch, TerrainBox};
    use super::*;
    use fcc_nav::ground_altitude::GroundSource;

    fn mean_std(v: &[f64]) -> (f64, f64) {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (
            m,
            (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / v.len() as f64).sqrt(),
        )
    }

    fn dark_square() -> Terrain {
        Terrain {
            boxes: vec![],
            dark_patches: vec![DarkPatch {
                north_min_m: 10.0,
                north_max_m: 20.0,
                east_min_m: -5.0,
                east_max_m: 5.0,
                ..Default::default()
            }],
        }
    }

    #[test]
    fn laser_rate_noise_and_dark_patch() {
        let t = dark_square();
        let mut l = LaserModel::new(LaserParams::default(), 1);
        let level = UnitQuaternion::identity();
        let mut bright = vec![];
        let mut n = 0;
        for k in 0..5000u64 {
            // 10 s at 500 Hz, 3 m up, outside the patch.
            if let Some(s) = l.sample(k * 2000, Vector3::new(0.0, 0.0, -3.0), &level, &t, 20.0) {
                n += 1;
                bright.push(s.range_m as f64);
                // 1 cm resolution survives the f32 round trip.
                assert!(
                    ((s.range_m as f64 * 100.0) - (s.range_m as f64 * 100.0).round()).abs() < 1e-3
                );
            }
        }
        assert_eq!(n, 90, "9 Hz");
        let (m, s) = mean_std(&bright);
        assert!(
            (m - 3.0).abs() < 0.02 && (s / 0.05 - 1.0).abs() < 0.25,
            "{m} {s}"
        );
        // Over the dark patch: the sentinel, every time.
        for k in 0..500u64 {
            if let Some(s) = l.sample(
                20_000_000 + k * 2000,
                Vector3::new(15.0, 0.0, -3.0),
                &level,
                &t,
                20.0,
            ) {
                assert_eq!(s.range_m, LASER_NO_RETURN_M);
                assert_eq!(l.last_line(), "D 99999.00\r\n");
            }
        }
        // Paper B's time window: dark everywhere from 105 s to 184 s.
        let w: Terrain =
            serde_yaml::from_str("dark_patches: [{ from_s: 105, to_s: 184 }]").unwrap();
        let mut l = LaserModel::new(LaserParams::default(), 2);
        let at = |l: &mut LaserModel, s: f64| {
            (0..100u64)
                .find_map(|k| {
                    l.sample(
                        (s * 1e6) as u64 + k * 2000,
                        Vector3::new(0.0, 0.0, -1.0),
                        &level,
                        &w,
                        20.0,
                    )
                })
                .unwrap()
                .range_m
        };
        assert!(at(&mut l, 104.0) < 2.0);
        assert_eq!(at(&mut l, 105.5), LASER_NO_RETURN_M);
        assert_eq!(at(&mut l, 183.0), LASER_NO_RETURN_M);
        assert!(at(&mut l, 185.0) < 2.0);
        // Too close / too far.
        assert_eq!(
            l.true_reading_m(0, Vector3::new(0.0, 0.0, -0.3), &level, &Terrain::flat()),
            LASER_NO_RETURN_M as f64
        );
        assert_eq!(
            l.true_reading_m(0, Vector3::new(0.0, 0.0, -160.0), &level, &Terrain::flat()),
            LASER_NO_RETURN_M as f64
        );
    }

    #[test]
    fn laser_sentinel_at_high_tilt() {
        let l = LaserModel::new(LaserParams::default(), 3);
        let flat = Terrain::flat();
        let pos = Vector3::new(0.0, 0.0, -1.0);
        let q20 = UnitQuaternion::from_euler_angles(20f64.to_radians(), 0.0, 0.0);
        let r = l.true_reading_m(0, pos, &q20, &flat);
        assert!((r - 1.0 / 20f64.to_radians().cos()).abs() < 1e-9);
        for deg in [30.0f64, 45.0] {
            let q = UnitQuaternion::from_euler_angles(deg.to_radians(), 0.0, 0.0);
            assert_eq!(
                l.true_reading_m(0, pos, &q, &flat),
                LASER_NO_RETURN_M as f64
            );
            let q = UnitQuaternion::from_euler_angles(0.0, deg.to_radians(), 1.0);
            assert_eq!(
                l.true_reading_m(0, pos, &q, &flat),
                LASER_NO_RETURN_M as f64
            );
        }
    }

    #[test]
    fn sonar_rate_noise_tilt_and_dark_ok() {
        let t = dark_square();
        let p = SonarParams {
            c0_mps: speed_of_sound_mps(20.0),
            ..Default::default()
        };
        let mut s = SonarModel::new(p, 4);
        let mut level_r = vec![];
        let mut n = 0;
        let level = UnitQuaternion::identity();
        for k in 0..50_000u64 {
            // 100 s over the dark patch: the sonar does not care.
            if let Some(x) = s.sample(k * 2000, Vector3::new(15.0, 0.0, -1.0), &level, &t, 20.0) {
                n += 1;
                level_r.push(x.range_m as f64);
            }
        }
        assert_eq!(n, 1000, "10 Hz");
        let (m, sd) = mean_std(&level_r);
        assert!(
            (m - 1.0).abs() < 0.005 && (sd / 0.0208 - 1.0).abs() < 0.15,
            "{m} {sd}"
        );
        // At 45° roll: the cone edge (30° off vertical), 4× noisier.
        let q = UnitQuaternion::from_euler_angles(45f64.to_radians(), 0.0, 0.0);
        let mut v = vec![];
        for k in 0..20_000u64 {
            if let Some(x) = s.sample(
                200_000_000 + k * 2000,
                Vector3::new(0.0, 0.0, -1.0),
                &q,
                &t,
                20.0,
            ) {
                v.push(x.range_m as f64);
            }
        }
        let (m, sd) = mean_std(&v);
        assert!((m - 1.0 / 30f64.to_radians().cos()).abs() < 0.01, "{m}");
        assert!((sd / 0.08 - 1.0).abs() < 0.15, "{sd}");
        // Floor and ceiling.
        let flat = Terrain::flat();
        assert_eq!(
            s.true_reading_m(Vector3::new(0.0, 0.0, -0.05), &level, &flat, 20.0),
            0.20
        );
        assert_eq!(
            s.true_reading_m(Vector3::new(0.0, 0.0, -30.0), &level, &flat, 20.0),
            10.68
        );
        let x = (0..100u64)
            .find_map(|k| {
                s.sample(
                    400_000_000 + k * 2000,
                    Vector3::new(0.0, 0.0, -30.0),
                    &level,
                    &flat,
                    20.0,
                )
            })
            .unwrap();
        assert_eq!(x.range_m, 10.68);
        assert_eq!(s.last_line(), "R1068\r");
    }

    #[test]
    fn sonar_sees_nearest_surface() {
        let t = Terrain {
            boxes: vec![TerrainBox {
                north_min_m: 5.0,
                north_max_m: 8.0,
                east_min_m: -2.0,
                east_max_m: 2.0,
                height_m: 0.5,
            }],
            dark_patches: vec![],
        };
        let p = SonarParams {
            c0_mps: speed_of_sound_mps(20.0),
            ..Default::default()
        };
        let s = SonarModel::new(p, 5);
        let l = LaserModel::new(LaserParams::default(), 5);
        let level = UnitQuaternion::identity();
        let pos = Vector3::new(4.8, 0.0, -2.0);
        assert!((l.true_reading_m(0, pos, &level, &t) - 2.0).abs() < 1e-9);
        let r = s.true_reading_m(pos, &level, &t, 20.0);
        assert!((1.5..1.6).contains(&r), "{r}");
    }

    #[test]
    fn sonar_temperature_bias() {
        // Paper B's example: 2.5 m of air at 20 °C, converted with the 0 °C speed.
        let p = SonarParams {
            c0_mps: 331.5,
            sigma_m: 0.0,
            resolution_m: 0.0,
            ..Default::default()
        };
        let s = SonarModel::new(p, 6);
        let level = UnitQuaternion::identity();
        let flat = Terrain::flat();
        let r = s.true_reading_m(Vector3::new(0.0, 0.0, -2.5), &level, &flat, 20.0);
        println!("sonar, 2.5 m at 20 °C with c0 = 331.5: reads {r:.4} m, error {:.4} m (paper prints 2.389 / 0.111)", 2.5 - r);
        assert!((r - 2.5 * 331.5 / 343.6428).abs() < 1e-6);
        assert!(2.5 - r > 0.08 && 2.5 - r < 0.12);
        // The default sensor (c0 = 343.2 m/s) at −10 °C: sound is slower than assumed, the echo
        // is late and the range reads 5.5 % long (2.636 m).
        let s = SonarModel::new(SonarParams::default(), 7);
        let r = s.true_reading_m(Vector3::new(0.0, 0.0, -2.5), &level, &flat, -10.0);
        assert!((r - 2.5 * 343.2 / speed_of_sound_mps(-10.0)).abs() < 1e-9 && r > 2.6);
        // With the sensor's own c0 at the matching temperature the reading is unbiased.
        let t_match = (343.2 - 331.5) / 0.60714;
        let r = s.true_reading_m(Vector3::new(0.0, 0.0, -2.5), &level, &flat, t_match);
        assert!((r - 2.5).abs() < 1e-9);
    }

    #[test]
    fn serial_round_trip() {
        for r in [0.0, 0.5, 1.0, 1.23, 12.34, 99.99, 150.0, 99_999.0] {
            let line = laser_line(r);
            assert_eq!(line.len(), 12, "{line:?}");
            assert!(
                (parse_laser_line(&line).unwrap() as f64 - r).abs() < 0.005,
                "{line:?}"
            );
        }
        assert_eq!(laser_line(1.234), "D 00001.23\r\n");
        assert_eq!(parse_laser_line("D 00001.23\r\n"), Some(1.23));
        assert_eq!(parse_laser_line("D 00001.23"), None);
        assert_eq!(parse_laser_line("D 0001.234\r\n"), None);
        assert_eq!(parse_laser_line("X 00001.23\r\n"), None);
        for cm in [20u32, 99, 100, 123, 765, 1068] {
            let line = sonar_line(cm as f64 * 0.01);
            assert_eq!(line, format!("R{cm:04}\r"));
            assert!((parse_sonar_line(&line).unwrap() - cm as f32 * 0.01).abs() < 1e-6);
        }
        // The 3-digit R### form (7.65 m models, and the issue's notation) is accepted too.
        assert_eq!(parse_sonar_line("R123\r"), Some(1.23));
        assert_eq!(parse_sonar_line("R12\r"), None);
        assert_eq!(parse_sonar_line("R12a4\r"), None);
        assert_eq!(parse_sonar_line("R0123"), None);
        // Determinism.
        let t = Terrain::flat();
        let q = UnitQuaternion::from_euler_angles(0.1, -0.05, 0.3);
        let (mut a, mut b) = (
            SonarModel::new(SonarParams::default(), 9),
            SonarModel::new(SonarParams::default(), 9),
        );
        for k in 0..2000u64 {
            let pos = Vector3::new(0.0, 0.0, -3.0);
            assert_eq!(
                a.sample(k * 2000, pos, &q, &t, 15.0),
                b.sample(k * 2000, pos, &q, &t, 15.0)
            );
        }
    }

    /// The models feeding `fcc_nav`'s filter: paper B's ground test (1 m, dark 105–184 s) and
    /// roll test (30°, 45°), with the paper's switch filter alongside. A smoke test of the
    /// defaults; the acceptance tests live in `tests/`.
    #[test]
    fn models_feed_the_filter() {
        use fcc_nav::ground_altitude::{
            GroundAltitudeFilter, GroundAltitudeParams, PaperSwitchFilter, PaperSwitchParams,
        };
        let run = |roll_deg: f64, terrain: &Terrain, secs: u64, window: (f64, f64)| {
            let mut l = LaserModel::new(LaserParams::default(), 11);
            let mut s = SonarModel::new(SonarParams::default(), 11);
            let mut g = GroundAltitudeFilter::new(GroundAltitudeParams::default());
            let mut ps = PaperSwitchFilter::new(PaperSwitchParams::default());
            let mut rng = ChaCha8Rng::seed_from_u64(99);
            let q = UnitQuaternion::from_euler_angles(roll_deg.to_radians(), 0.0, 0.0);
            let pos = Vector3::new(0.0, 0.0, -1.0);
            let (mut last_l, mut last_s) = (1.0f32, 1.0f32);
            let (mut se, mut max, mut n, mut se_p) = (0.0f64, 0.0f64, 0usize, 0.0f64);
            for k in 0..secs * 500 {
                let t = k * 2000;
                g.predict(0.002, normal(&mut rng, 0.05) as f32);
                let mut new = false;
                if let Some(x) = l.sample(t, pos, &q, terrain, 20.0) {
                    g.update_laser(x.range_m, roll_deg.to_radians() as f32, 0.0);
                    last_l = x.range_m;
                    new = true;
                }
                if let Some(x) = s.sample(t, pos, &q, terrain, 20.0) {
                    g.update_sonar(x.range_m, roll_deg.to_radians() as f32, 0.0, 20.0);
                    last_s = x.range_m;
                    new = true;
                }
                if new {
                    ps.step(last_l, last_s);
                }
                let ts = t as f64 * 1e-6;
                if ts >= window.0 && ts < window.1 {
                    let e = g.output().height_m as f64 - 1.0;
                    se += e * e;
                    max = max.max(e.abs());
                    let ep = ps.output() as f64 - 1.0;
                    se_p += ep * ep;
                    n += 1;
                }
            }
            (
                (se / n as f64).sqrt(),
                max,
                (se_p / n as f64).sqrt(),
                g.output(),
            )
        };
        let dark: Terrain =
            serde_yaml::from_str("dark_patches: [{ from_s: 105, to_s: 184 }]").unwrap();
        let (rms, max, rms_p, o) = run(0.0, &dark, 200, (105.0, 184.0));
        println!("ground test, dark 105-184 s: ours rms {rms:.4} max {max:.4}; paper switch rms {rms_p:.4}");
        assert!(rms <= 0.03 && max <= 0.10, "{rms} {max}");
        assert_eq!(o.source, GroundSource::Both);
        for deg in [30.0, 45.0] {
            let (rms, max, rms_p, o) = run(deg, &Terrain::flat(), 60, (5.0, 60.0));
            println!("roll {deg}°: ours rms {rms:.4} max {max:.4}; paper switch rms {rms_p:.4}");
            assert!(rms <= 0.05, "{deg}: {rms}");
            assert_eq!(o.source, GroundSource::Sonar);
        }
    }
}
