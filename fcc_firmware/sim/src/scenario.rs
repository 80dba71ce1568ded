//! Scenario files (YAML, `launch_configs/scenarios/*.yaml`): what to fly, in which weather, with
//! which faults. A bad file gives one line naming the file, the field and the reason.

use super::physics::VehicleParams;
use super::rangefinders::{LaserParams, SonarParams};
use super::sensor_models::{BaroParams, GpsParams, ImuParams, MagParams};
use super::terrain::Terrain;
use super::wind::WindParams;
use fcc_firmware::params::Params;
use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub name: String,
    /// Every random process in the run derives from this seed: same seed, same flight.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Stop the run after this much simulated time even if the flight is not over.
    pub duration_s: f64,
    #[serde(default)]
    pub wind: WindParams,
    pub flight: FlightPlan,
    #[serde(default)]
    pub faults: Vec<Fault>,
    /// A scripted R/C pilot: timed switch/stick/receiver events, fed to the core through a
    /// simulated S.BUS receiver ([`super::pilot`]). Empty → no receiver.
    #[serde(default)]
    pub pilot: Vec<super::pilot::PilotEvent>,
    /// Overrides of the flight core's parameters (any subset).
    #[serde(default)]
    pub params: Params,
    #[serde(default)]
    pub vehicle: VehicleParams,
    #[serde(default)]
    pub sensors: SensorParams,
    /// Ground under the flight: flat plus boxes/steps, and where it is dark to the laser.
    #[serde(default)]
    pub terrain: Terrain,
    /// Air temperature (°C): the true speed of sound for the sonar follows it.
    #[serde(default = "default_air_temp_c")]
    pub air_temp_c: f64,
}

fn default_air_temp_c() -> f64 {
    15.0
}

fn default_seed() -> u64 {
    1
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorParams {
    pub calibration: CalibrationParams,
    pub imu: ImuParams,
    pub mag: MagParams,
    pub baro: BaroParams,
    pub gps: GpsParams,
    pub laser: LaserParams,
    pub sonar: SonarParams,
}

/// The pre-flight sensor calibrations every operator runs (accelerometer 6-orientation, compass
/// rotation), emulated: the firmware receives the true offsets plus a residual error of this
/// size (1σ per axis). A 6-orientation accelerometer calibration leaves a few mg (temperature
/// drift of the MPU-9250's zero-g offset is ±1.5 mg/°C, datasheet PS-MPU-9250A-01 §3.2);
/// compass calibration leaves a fraction of a µT of hard iron.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CalibrationParams {
    pub enabled: bool,
    pub accel_residual_mg: f64,
    pub mag_residual_ut: f64,
}

impl Default for CalibrationParams {
    fn default() -> Self {
        Self {
            enabled: true,
            accel_residual_mg: 5.0,
            mag_residual_ut: 0.3,
        }
    }
}

/// What the (simulated) Linux computer does.
#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum FlightPlan {
    /// Take off to `alt_m`, hold position for `hold_s` (paper A Fig. 16), land.
    Hover { alt_m: f32, hold_s: f32 },
    /// Fly a mission file with the Linux-side waypoint logic (`fcc_mission`), path relative to
    /// the scenario file.
    Mission { mission_file: PathBuf },
    /// The same, with the mission written inline (generated scenarios: the campaign).
    MissionInline { mission: fcc_mission::Mission },
    /// Velocity mode: take off to `alt_m`, then command `speed_mps` tangent to a circle of
    /// `radius_m` around home (zero vertical speed) for `cruise_s`, then land.
    Velocity {
        alt_m: f32,
        speed_mps: f32,
        radius_m: f32,
        cruise_s: f32,
    },
    /// The vehicle is carried in an elevator (motors off, no GPS): floors visited in order,
    /// paper A Figs. 8–9.
    /// A static test rig (paper B's ground and roll tests): the vehicle held at `height_m`
    /// above the ground with the given attitude, motors off.
    Rig {
        height_m: f32,
        roll_deg: f32,
        pitch_deg: f32,
    },
    Elevator {
        floors: Vec<i32>,
        floor_height_m: f32,
        speed_mps: f32,
        accel_mps2: f32,
        dwell_s: f32,
    },
}

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Fault {
    /// An extra magnetic field (e.g. a steel structure) between `start_s` and `end_s`.
    MagDisturbance {
        start_s: f64,
        end_s: f64,
        field_ned_ut: [f64; 3],
    },
    /// No GPS fixes between `start_s` and `end_s`.
    GpsOutage { start_s: f64, end_s: f64 },
    /// Every GPS fix between `start_s` and `end_s` is off by `offset_ned_m` (a jump:
    /// multipath, spoofing) — the horizontal filter's innovation monitor must catch it.
    GpsJump {
        start_s: f64,
        end_s: f64,
        offset_ned_m: [f64; 3],
    },
    /// The mission computer falls silent (killed, link cut): no setpoints or commands reach the
    /// MCU between `start_s` and `end_s`.
    LinuxSilent { start_s: f64, end_s: f64 },
}

impl Fault {
    pub fn window(&self) -> (f64, f64) {
        match *self {
            Fault::MagDisturbance { start_s, end_s, .. }
            | Fault::GpsOutage { start_s, end_s }
            | Fault::GpsJump { start_s, end_s, .. }
            | Fault::LinuxSilent { start_s, end_s } => (start_s, end_s),
        }
    }
}

/// A scenario that could not be loaded: file, field path and reason.
#[derive(Debug)]
pub struct ScenarioError {
    pub file: PathBuf,
    pub field: String,
    pub reason: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}: {}", self.file.display(), self.reason)
        } else {
            write!(
                f,
                "{}: {}: {}",
                self.file.display(),
                self.field,
                self.reason
            )
        }
    }
}

impl std::error::Error for ScenarioError {}

impl Scenario {
    pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
        let err = |field: &str, reason: String| ScenarioError {
            file: path.to_path_buf(),
            field: field.into(),
            reason,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err("", e.to_string()))?;
        let mut s = Self::from_yaml_str(&text).map_err(|(field, reason)| err(&field, reason))?;
        if let FlightPlan::Mission { mission_file } = &mut s.flight {
            if mission_file.is_relative() {
                let base = path.parent().unwrap_or(Path::new("."));
                *mission_file = base.join(&*mission_file);
            }
        }
        Ok(s)
    }

    /// Parse and validate; the error is (field path, reason).
    pub fn from_yaml_str(text: &str) -> Result<Scenario, (String, String)> {
        let de = serde_yaml::Deserializer::from_str(text);
        let s: Scenario = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner().to_string();
            (if path == "." { String::new() } else { path }, inner)
        })?;
        s.validate()?;
        Ok(s)
    }

    fn validate(&self) -> Result<(), (String, String)> {
        let bad = |f: &str, r: &str| Err((f.to_string(), r.to_string()));
        if !(self.duration_s.is_finite() && self.duration_s > 0.0 && self.duration_s <= 7200.0) {
            return bad("duration_s", "must be in (0, 7200] s");
        }
        if !(self.wind.mean_speed_mps.is_finite()
            && (0.0..=25.0).contains(&self.wind.mean_speed_mps))
        {
            return bad("wind.mean_speed_mps", "must be in [0, 25] m/s");
        }
        if !(self.wind.w20_kt.is_finite() && (0.0..=60.0).contains(&self.wind.w20_kt)) {
            return bad("wind.w20_kt", "must be in [0, 60] kt");
        }
        if !self.wind.from_direction_deg.is_finite() {
            return bad("wind.from_direction_deg", "not finite");
        }
        match &self.flight {
            FlightPlan::Hover { alt_m, hold_s } => {
                if !(alt_m.is_finite() && (1.0..=100.0).contains(alt_m)) {
                    return bad("flight.alt_m", "must be in [1, 100] m");
                }
                if !(hold_s.is_finite() && *hold_s > 0.0) {
                    return bad("flight.hold_s", "must be positive");
                }
            }
            FlightPlan::Mission { .. } | FlightPlan::MissionInline { .. } => {}
            FlightPlan::Velocity {
                alt_m,
                speed_mps,
                radius_m,
                cruise_s,
            } => {
                if !(alt_m.is_finite() && (1.0..=100.0).contains(alt_m)) {
                    return bad("flight.alt_m", "must be in [1, 100] m");
                }
                if !(speed_mps.is_finite() && (0.0..=20.0).contains(speed_mps)) {
                    return bad("flight.speed_mps", "must be in [0, 20] m/s");
                }
                if !(radius_m.is_finite() && *radius_m >= 5.0) {
                    return bad("flight.radius_m", "must be ≥ 5 m");
                }
                if !(cruise_s.is_finite() && *cruise_s > 0.0) {
                    return bad("flight.cruise_s", "must be positive");
                }
            }
            FlightPlan::Rig {
                height_m,
                roll_deg,
                pitch_deg,
            } => {
                if !(height_m.is_finite() && (0.1..=100.0).contains(height_m)) {
                    return bad("flight.height_m", "must be in [0.1, 100] m");
                }
                if !(roll_deg.is_finite() && roll_deg.abs() <= 80.0) {
                    return bad("flight.roll_deg", "must be within ±80°");
                }
                if !(pitch_deg.is_finite() && pitch_deg.abs() <= 80.0) {
                    return bad("flight.pitch_deg", "must be within ±80°");
                }
            }
            FlightPlan::Elevator {
                floors,
                floor_height_m,
                speed_mps,
                accel_mps2,
                dwell_s,
            } => {
                if floors.is_empty() {
                    return bad("flight.floors", "needs at least one floor");
                }
                if !(floor_height_m.is_finite() && *floor_height_m > 0.5 && *floor_height_m < 20.0)
                {
                    return bad("flight.floor_height_m", "must be in (0.5, 20) m");
                }
                if !(speed_mps.is_finite() && *speed_mps > 0.0 && *speed_mps < 20.0) {
                    return bad("flight.speed_mps", "must be in (0, 20) m/s");
                }
                if !(accel_mps2.is_finite() && *accel_mps2 > 0.0 && *accel_mps2 < 10.0) {
                    return bad("flight.accel_mps2", "must be in (0, 10) m/s²");
                }
                if !(dwell_s.is_finite() && *dwell_s >= 0.0) {
                    return bad("flight.dwell_s", "must be ≥ 0 s");
                }
            }
        }
        if !(self.air_temp_c.is_finite() && (-40.0..=60.0).contains(&self.air_temp_c)) {
            return bad("air_temp_c", "must be in [-40, 60] °C");
        }
        for (i, f) in self.faults.iter().enumerate() {
            let (a, b) = f.window();
            if !(a.is_finite() && b.is_finite() && a >= 0.0 && b > a) {
                return Err((format!("faults[{i}]"), "needs 0 ≤ start_s < end_s".into()));
            }
        }
        super::pilot::validate(&self.pilot)?;
        self.params
            .validate()
            .map_err(|e| (format!("params.{}", e.field), e.reason.to_string()))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_field_is_named() {
        let y = "name: x\nduration_s: 10\nflight: {kind: hover, alt_m: 5, hold_s: 10}\nwind: {mean_speed_mps: 3, gust: 2}\n";
        let (field, reason) = Scenario::from_yaml_str(y).unwrap_err();
        assert_eq!(field, "wind.gust");
        assert!(reason.contains("gust"), "{reason}");
    }

    #[test]
    fn out_of_range_is_named() {
        let y = "name: x\nduration_s: 10\nflight: {kind: hover, alt_m: 500, hold_s: 10}\n";
        assert_eq!(Scenario::from_yaml_str(y).unwrap_err().0, "flight.alt_m");
        let y = "name: x\nduration_s: 10\nflight: {kind: hover, alt_m: 5, hold_s: 10}\nparams: {limits: {max_tilt_deg: 90}}\n";
        assert_eq!(
            Scenario::from_yaml_str(y).unwrap_err().0,
            "params.limits.max_tilt_deg"
        );
        let y = "name: x\nduration_s: ten\nflight: {kind: hover, alt_m: 5, hold_s: 10}\n";
        assert_eq!(Scenario::from_yaml_str(y).unwrap_err().0, "duration_s");
        let y = "name: x\nduration_s: 10\nflight: {kind: hover, alt_m: 5, hold_s: 10}\npilot: [{at_s: 2, override_on: true, sticks: [0, 2, 0, 0]}]\n";
        assert_eq!(
            Scenario::from_yaml_str(y).unwrap_err().0,
            "pilot[0].sticks[1]"
        );
        let y = "name: x\nduration_s: 10\nflight: {kind: hover, alt_m: 5, hold_s: 10}\npilot: [{at_s: 2, receiver: lost}]\n";
        assert_eq!(
            Scenario::from_yaml_str(y).unwrap_err().0,
            "pilot[0].receiver"
        );
    }

    #[test]
    fn repo_scenarios_load() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch_configs/scenarios");
        let mut n = 0;
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "yaml") {
                Scenario::load(&p).unwrap_or_else(|e| panic!("{e}"));
                n += 1;
            }
        }
        assert!(n >= 4);
    }
}
