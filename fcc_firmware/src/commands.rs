//! What the Linux computer sends the flight core: velocity setpoints with a time-to-live, and
//! mode commands. NED, m/s; times in MCU µs.

pub use fcc_msgs::YawSetpoint;

/// A velocity setpoint from the mission computer (paper A: per-axis velocity over UART).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocitySetpoint {
    pub vel_ned_mps: [f32; 3],
    /// Keep the held heading, hold a heading (rad, NED, from north towards east) or turn at a
    /// rate (rad/s, NED, clockwise seen from above): the link's vocabulary, one definition.
    pub yaw: YawSetpoint,
    /// The setpoint is valid for this long after it arrives; then the core holds position.
    pub ttl_ms: u16,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    Arm,
    Disarm,
    /// Position hold at the current point.
    Hold,
    /// Land here; disarm on touchdown.
    Land,
    /// Follow external velocity setpoints (entered automatically by the first setpoint when armed).
    Velocity,
    /// Emergency motor stop, in the air too (the only way to disarm while flying). Carries
    /// the confirmation [`KILL_CONFIRM`]; anything else is refused.
    Kill {
        confirm: u32,
    },
}

/// The confirmation an emergency kill must carry ("KILL" in ASCII), the link's own constant:
/// a kill is never the accident of a flipped bit or a mistyped mode.
pub use fcc_msgs::KILL_CONFIRM;

/// Why a command was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandError {
    /// Arm refused: gyro/baro calibration still running.
    NotCalibrated,
    /// Arm refused: no GPS home yet.
    NoHome,
    /// Arm or disarm refused: flying / not confirmed on the ground (land detector).
    NotLanded,
    /// The command needs the vehicle armed.
    Disarmed,
    /// Setpoint with NaN/inf or absurd values.
    InvalidSetpoint,
    /// The pilot's override switch is on: the R/C pilot has the vehicle ([`crate::pilot`]).
    PilotOverride,
    /// An emergency kill without the right confirmation.
    KillNotConfirmed,
}

impl core::fmt::Display for CommandError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            CommandError::NotCalibrated => "calibration still running",
            CommandError::NoHome => "no GPS home position yet",
            CommandError::NotLanded => "vehicle is not landed",
            CommandError::Disarmed => "vehicle is disarmed",
            CommandError::InvalidSetpoint => "setpoint is not finite or out of range",
            CommandError::PilotOverride => "the pilot's override switch is on",
            CommandError::KillNotConfirmed => "emergency kill without its confirmation",
        })
    }
}

/// Flight mode of the core and why it left the operator's mode: the link's vocabulary
/// (`fcc_msgs::vocab`, one definition with the ROS codes and names), not a mirror.
/// Failsafes: `SetpointStale` (setpoint older than its time-to-live → hold), `SetpointLost` (no
/// fresh setpoint for `setpoint_lost_land_s` → land), `Geofence` (→ hold at the fence),
/// `GpsLost` (→ altitude hold, then land), `WindLimit` (tilt at its limit, blown off → land
/// where it is), `EstimatorFault` ([`crate::nav_health`] → hold, then land), `EmergencyKill`.
pub use fcc_msgs::{FailsafeCause, FlightMode as Mode};
