//! What a simulated flight leaves behind: a 50 Hz log of truth beside estimates and commands,
//! and the Linux side's events.

use fcc_firmware::commands::{FailsafeCause, Mode};
use fcc_firmware::flight::StepTelemetry;
use fcc_firmware::geometry::MOTOR_COUNT;
use fcc_firmware::nav::NavState;

/// What the in-process Linux computer is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
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

#[derive(Clone, Copy, Debug)]
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
#[derive(Clone, Copy, Debug)]
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
