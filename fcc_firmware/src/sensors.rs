//! Sensor samples as the flight core sees them, and the hardware traits that produce them.
//!
//! Frames: body FRD (x forward, y right, z down); NED for navigation. Times are MCU
//! microseconds since boot (`t_us`), passed in by the caller — the core never reads a clock.
//! A real board implements these traits with drivers; the SITL implements them with models.

/// One IMU sample (MPU-9250 class): angular rate and specific force in the body FRD frame.
/// At rest and level the accelerometer reads `[0, 0, -9.81]` (specific force = accel − gravity).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuSample {
    pub t_us: u64,
    pub gyro_frd_radps: [f32; 3],
    pub accel_frd_mps2: [f32; 3],
}

/// Magnetometer sample in the body FRD frame, microtesla.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MagSample {
    pub t_us: u64,
    pub mag_frd_ut: [f32; 3],
}

/// Barometer sample (MS5611 class).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BaroSample {
    pub t_us: u64,
    pub pressure_pa: f32,
    pub temperature_c: f32,
}

/// A GPS solution as delivered (arrival time `t_us`; the fix is older by the receiver latency).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpsFix {
    pub t_us: u64,
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Height above the WGS-84 ellipsoid.
    pub alt_m: f32,
    pub vel_ned_mps: [f32; 3],
    /// Receiver's horizontal accuracy estimate (1σ).
    pub h_acc_m: f32,
    pub num_sats: u8,
    /// 3-D fix valid.
    pub fix_ok: bool,
}

/// A downward rangefinder reading (laser altimeter or sonar), metres along the sensor axis.
/// The laser reports [`LASER_NO_RETURN_M`] when it gets no echo.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RangeSample {
    pub t_us: u64,
    pub range_m: f32,
}

/// What the ILM-150-R laser altimeter outputs when it receives no return (paper B).
pub use fcc_nav::ground_altitude::LASER_NO_RETURN_M;

/// Battery monitor sample (ADC on the board).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BatterySample {
    pub t_us: u64,
    pub voltage_v: f32,
    pub current_a: f32,
}

/// Everything the sensors delivered since the previous 500 Hz tick; `None` = no new sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SensorInputs {
    pub imu: Option<ImuSample>,
    pub mag: Option<MagSample>,
    pub baro: Option<BaroSample>,
    pub gps: Option<GpsFix>,
    pub laser: Option<RangeSample>,
    pub sonar: Option<RangeSample>,
    pub battery: Option<BatterySample>,
}

/// A sensor that may have a new sample at `now_us`.
pub trait Sensor {
    type Sample;
    fn poll(&mut self, now_us: u64) -> Option<Self::Sample>;
}

/// The board's sensors, polled once per tick by the scheduler.
pub trait SensorBoard {
    fn poll(&mut self, now_us: u64) -> SensorInputs;
}

/// ESC outputs: one normalised command per motor, 0 = stopped, 1 = full throttle.
pub trait MotorOutputs {
    fn write(&mut self, now_us: u64, cmd: &[f32; crate::geometry::MOTOR_COUNT]);
}

/// Motor outputs that keep the last command (what the ESCs would get): the simulator's, the
/// QEMU replay's and the recorder's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotorLatch(pub [f32; crate::geometry::MOTOR_COUNT]);

impl MotorOutputs for MotorLatch {
    fn write(&mut self, _now_us: u64, cmd: &[f32; crate::geometry::MOTOR_COUNT]) {
        self.0 = *cmd;
    }
}
