//! What a simulated flight leaves behind: a 50 Hz log of truth beside estimates and commands,
//! and the Linux side's events. A long real-time run (`fcc-sitl --link-pty`) spills the samples
//! and rangefinder readings to an unlinked scratch file as they come ([`Spill`]) and reads them
//! back when the run is closed: flat memory while it flies, the same log afterwards.

use fcc_firmware::commands::{FailsafeCause, Mode};
use fcc_firmware::flight::StepTelemetry;
use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::nav::NavState;

/// What the in-process Linux computer is doing.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum PlanPhase {
    Waiting,
    Climbing,
    /// Hover hold window (paper A Fig. 16): the hold point (estimated NED).
    Holding {
        hold_ned_m: [f32; 3],
    },
    /// Flying the straight leg from → to (estimated NED) towards waypoint `index`.
    Leg {
        index: usize,
        from_ned_m: [f32; 3],
        to_ned_m: [f32; 3],
    },
    HoldAtWaypoint(usize),
    /// Velocity-mode cruise (scenario `velocity`): commanded horizontal speed, zero climb.
    Cruise {
        speed_mps: f32,
    },
    Landing,
    Done,
    /// Carried (elevator): no flight.
    Carried,
}

#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct LogSample {
    pub t_s: f64,
    pub mode: Mode,
    pub failsafe: FailsafeCause,
    pub armed: bool,
    pub landed: bool,
    pub plan: PlanPhase,
    pub true_pos_ned_m: [f64; 3],
    pub true_vel_ned_mps: [f64; 3],
    /// Roll, pitch, yaw (ZYX), rad.
    pub true_euler_rad: [f64; 3],
    pub true_accel_ned_mps2: [f64; 3],
    pub wind_ned_mps: [f64; 3],
    pub nav: NavState,
    pub tel: StepTelemetry,
    /// True horizontal acceleration in the estimated heading frame (forward, right).
    pub accel_true_fr_mps2: [f32; 2],
    /// True height of the body origin above the terrain right below it, m.
    pub true_agl_m: f64,
    pub motors: [f32; MOTOR_COUNT],
}

/// One rangefinder reading as the core received it, with the truth at that moment.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct RangeRecord {
    pub t_s: f64,
    /// Laser altimeter (else sonar).
    pub laser: bool,
    /// Reading along the sensor axis (laser 99999 = no return).
    pub range_m: f32,
    /// True vertical height above the terrain below, m.
    pub true_agl_m: f64,
}

#[derive(Clone, Debug, Default)]
pub struct FlightLog {
    pub samples: Vec<LogSample>,
    /// (time s, what happened)
    pub events: Vec<(f64, String)>,
    /// Every rangefinder reading, at its own rate.
    pub ranges: Vec<RangeRecord>,
    /// The scenario's flight plan kind: "hover", "mission", "velocity", "elevator" or "rig".
    pub plan_kind: &'static str,
    /// Every ground contact after flight, with its speeds, tilt and outcome (truth).
    pub contacts: Vec<super::truth::Contact>,
    /// Truth counters accumulated every tick.
    pub truth: super::truth::TruthCounters,
    /// The height the plan commands (hover: its `alt_m` above take-off), m.
    pub commanded_alt_m: Option<f64>,
}

/// Where [`Spill`] fails.
#[derive(Debug)]
pub enum SpillError {
    Io(std::io::Error),
    /// A record did not encode or decode (postcard).
    Codec(postcard::Error),
    /// The file ends inside a record.
    Truncated,
    /// A record with an unknown tag.
    BadTag(u8),
}

impl std::fmt::Display for SpillError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SpillError::Io(e) => write!(f, "flight-log scratch file: {e}"),
            SpillError::Codec(e) => write!(f, "flight-log scratch record: {e}"),
            SpillError::Truncated => f.write_str("flight-log scratch file ends inside a record"),
            SpillError::BadTag(t) => write!(f, "flight-log scratch record with unknown tag {t}"),
        }
    }
}

impl From<std::io::Error> for SpillError {
    fn from(e: std::io::Error) -> Self {
        SpillError::Io(e)
    }
}

/// Largest encoded record (a [`LogSample`] is ≈ 330 bytes in postcard).
const SPILL_RECORD_MAX: usize = 1024;
const TAG_SAMPLE: u8 = 0;
const TAG_RANGE: u8 = 1;

/// The log's samples and range readings on disk, in the order they came: each record is a tag
/// byte, a u16 LE length and the postcard encoding (f32/f64 bit-exact). The file is unlinked as
/// soon as it is open, so it vanishes with the process whatever ends it.
pub struct Spill {
    file: std::io::BufWriter<std::fs::File>,
    records: u64,
}

impl Spill {
    /// A scratch file in `dir` (e.g. `std::env::temp_dir()`).
    pub fn create(dir: &std::path::Path) -> Result<Self, SpillError> {
        let name = format!(
            ".fcc-sitl-log-{}-{:x}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos())
        );
        let path = dir.join(name);
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)?;
        std::fs::remove_file(&path)?;
        Ok(Self {
            file: std::io::BufWriter::with_capacity(64 * 1024, file),
            records: 0,
        })
    }

    /// One record in one `write_all`: the buffer takes it whole or not at all, so after a
    /// failed write (disk full) the file plus the unwritten buffer are still whole records.
    fn put<T: serde::Serialize>(&mut self, tag: u8, v: &T) -> Result<(), SpillError> {
        use std::io::Write;
        let mut buf = [0u8; 3 + SPILL_RECORD_MAX];
        let n = postcard::to_slice(v, &mut buf[3..])
            .map_err(SpillError::Codec)?
            .len();
        buf[0] = tag;
        buf[1..3].copy_from_slice(&(n as u16).to_le_bytes());
        self.file.write_all(&buf[..3 + n])?;
        self.records += 1;
        Ok(())
    }

    pub fn push_sample(&mut self, s: &LogSample) -> Result<(), SpillError> {
        self.put(TAG_SAMPLE, s)
    }

    pub fn push_range(&mut self, r: &RangeRecord) -> Result<(), SpillError> {
        self.put(TAG_RANGE, r)
    }

    /// Records written so far.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Read everything back, appending to `log.samples` and `log.ranges` in the order written:
    /// the file, then what its buffer could not write (nothing is flushed again).
    pub fn read_into(self, log: &mut FlightLog) -> Result<(), SpillError> {
        use std::io::{Read, Seek};
        let (mut file, pending) = self.file.into_parts();
        let pending = pending.unwrap_or_else(|p| p.into_inner());
        file.seek(std::io::SeekFrom::Start(0))?;
        let mut r = std::io::BufReader::with_capacity(64 * 1024, file).chain(&pending[..]);
        let mut head = [0u8; 3];
        let mut buf = [0u8; SPILL_RECORD_MAX];
        loop {
            match r.read_exact(&mut head[..1]) {
                Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
                other => other?,
            }
            r.read_exact(&mut head[1..])
                .map_err(|_| SpillError::Truncated)?;
            let n = u16::from_le_bytes([head[1], head[2]]) as usize;
            let body = buf.get_mut(..n).ok_or(SpillError::Truncated)?;
            r.read_exact(body).map_err(|_| SpillError::Truncated)?;
            match head[0] {
                TAG_SAMPLE => log
                    .samples
                    .push(postcard::from_bytes(body).map_err(SpillError::Codec)?),
                TAG_RANGE => log
                    .ranges
                    .push(postcard::from_bytes(body).map_err(SpillError::Codec)?),
                t => return Err(SpillError::BadTag(t)),
            }
        }
    }
}

/// Write the log as CSV (one row per 50 Hz sample) for plotting elsewhere.
pub fn write_csv(log: &FlightLog, path: &std::path::Path) -> std::io::Result<()> {
    use std::io::Write;
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(
        f,
        "t_s,mode,armed,true_n_m,true_e_m,true_d_m,est_n_m,est_e_m,est_d_m,true_vn_mps,true_ve_mps,true_vd_mps,est_vn_mps,est_ve_mps,est_vd_mps,true_roll_rad,true_pitch_rad,true_yaw_rad,est_roll_rad,est_pitch_rad,est_yaw_rad,baro_alt_m,accel_est_fwd_mps2,accel_meas_fwd_mps2,accel_true_fwd_mps2,cross_track_m,vel_cmd_n_mps,vel_cmd_e_mps,vel_cmd_d_mps,thrust_n,roll_cmd_rad,pitch_cmd_rad,failsafe,true_agl_m,ground_m,ground_var_m2,ground_source,ground_rate_up_mps,laser_m,sonar_m"
    )?;
    for s in &log.samples {
        let n = &s.nav;
        writeln!(
            f,
            "{:.3},{:?},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.4},{:.4},{:.4},{:.4},{:.4},{:.3},{:.3},{:.3},{:.2},{:.4},{:.4},{:?},{:.3},{:.3},{:.5},{:?},{:.3},{:?},{:?}",
            s.t_s, s.mode, s.armed as u8,
            s.true_pos_ned_m[0], s.true_pos_ned_m[1], s.true_pos_ned_m[2],
            n.pos_ned_m[0], n.pos_ned_m[1], n.pos_ned_m[2],
            s.true_vel_ned_mps[0], s.true_vel_ned_mps[1], s.true_vel_ned_mps[2],
            n.vel_ned_mps[0], n.vel_ned_mps[1], n.vel_ned_mps[2],
            s.true_euler_rad[0], s.true_euler_rad[1], s.true_euler_rad[2],
            n.euler.roll_rad, n.euler.pitch_rad, n.euler.yaw_rad,
            n.baro_alt_m, s.tel.accel_est_fr_mps2[0], s.tel.accel_meas_fr_mps2[0], s.accel_true_fr_mps2[0], s.tel.cross_track_m,
            s.tel.vel_cmd_ned_mps[0], s.tel.vel_cmd_ned_mps[1], s.tel.vel_cmd_ned_mps[2], s.tel.thrust_n, s.tel.roll_cmd_rad, s.tel.pitch_cmd_rad, s.failsafe,
            s.true_agl_m, n.ground.height_m, n.ground.variance_m2, n.ground.source, n.ground_rate_up_mps, n.laser_m.unwrap_or(f32::NAN), n.sonar_m.unwrap_or(f32::NAN)
        )?;
    }
    f.flush()
}
