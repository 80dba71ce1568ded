//! Linux-side waypoint logic of the flight stack (paper A: the Linux
//! computer runs the mission and sends per-axis velocity commands to the
//! flight MCU over UART; the MCU does cross-track compensation and control).
//!
//! Pure logic: `std` only, no I/O besides parsing a YAML string. A ROS 2 node
//! or the simulator calls it in-process.
//!
//! # Layers and modules
//! * The mission and its guidance (the simulator uses these too): [`mission`] (the YAML
//!   file, validation), [`follower`] (the waypoint follower: phases, speed profile, velocity
//!   command).
//! * The mission node's goals, time passed in, no ROS types (the `fcc-mission` binary, feature
//!   `ros`, only wires them to topics and its `FollowWaypoints` action): [`goal`] (an action
//!   goal — local ENU or lat/lon points — as a mission in metres from home, or why it is
//!   refused: geofence, no home, bad fields), [`executive`] (one goal at a time: preemption,
//!   cancel = hold, feedback, results; the mission file is its first goal).
//! * The mission node's sequencing of one goal: [`run`] (one run, cycle by cycle: what to send
//!   and log), built from [`arming`] (arm command re-sends and timeout), [`pilot_pause`]
//!   (pause and resume around an R/C pilot override), [`progress`] (phase names, distance to
//!   go, cross-track on the legs), [`ending`] (hover in HOLD, then land; the MCU's modes) and
//!   [`status_report`] (the `mission/status` JSON and its rate); [`node_params`] (the node's
//!   ROS parameters: one table for the `-p` check, `--help`, the declared parameters and their
//!   descriptors).
//! * The launcher (`fcc-launch`, feature `ros`, does the process I/O): [`launch`] (its config,
//!   `${NAME}` variables, the supervision rules) and [`track`] (the cross-track report of a
//!   full-stack flight from the simulator's CSV).
//!
//! # Inputs
//! * A [`Mission`] (YAML via [`from_yaml_str`], validated by
//!   [`Mission::validate`]): takeoff altitude, speed, acceleration limit,
//!   acceptance radius, hold time, optional fixed yaw, land-at-end flag and
//!   waypoints in local metres relative to home (`north_m`, `east_m`,
//!   `alt_m` up positive).
//! * Each cycle (≥ 20 Hz), [`WaypointFollower::update`] gets time `t_s` (s),
//!   the position estimate `pos_ned_m` (NED, m) and the velocity estimate
//!   `vel_ned_mps` (NED, m/s). Home is the first valid position; mission
//!   targets are `home + [north_m, east_m, -alt_m]` in the caller's NED frame.
//!
//! # Outputs
//! A [`Guidance`] per update: the velocity command `vel_ned_mps` (NED, m/s)
//! for the MCU, an optional heading `yaw_rad` (rad from north, clockwise;
//! `None` = keep current), the [`Phase`], the current straight segment
//! [`LegInfo`] (caller's NED frame, m) and a mode [`Request`] (arm during
//! takeoff, land at the end).
//!
//! The command is along the current leg only, with a trapezoidal speed
//! profile: `v = min(speed_mps, sqrt(2·0.7·a·along_track_to_go), v_prev + a·dt)`
//! (never below `v_prev − a·dt`), so it arrives at each waypoint with ~zero
//! speed; its rate of change never exceeds `a = accel_limit_mps2`. The 0.7
//! ([`follower::BRAKE_PLAN_FRACTION`]) leaves margin for the vehicle's
//! velocity-tracking lag. Cross-track compensation is left to the MCU.
//!
//! # Example
//! ```
//! use fcc_mission::{from_yaml_str, Phase, Request, WaypointFollower};
//! let mission = from_yaml_str(
//!     "takeoff_alt_m: 5\nspeed_mps: 3\naccept_radius_m: 0.5\n\
//!      waypoints: [{north_m: 20, east_m: 0, alt_m: 5}]\n",
//! )?;
//! let mut follower = WaypointFollower::new(mission);
//! let g = follower.update(0.0, [0.0, 0.0, 0.0], [0.0; 3]);
//! assert_eq!(g.phase, Phase::Takeoff);
//! assert_eq!(g.request, Some(Request::Arm));
//! // send g.vel_ned_mps (and g.yaw_rad) to the MCU, call again in 50 ms ...
//! # Ok::<(), fcc_mission::MissionError>(())
//! ```
//!
//! Lat/lon waypoints: in action goals ([`goal`]); the YAML mission file still has local metres
//! only (a `lat_deg` key is rejected as an unknown field).

pub mod arming;
pub mod cli;
pub mod ending;
pub mod executive;
pub mod follower;
pub mod goal;
pub mod launch;
pub mod mission;
pub mod node_params;
pub mod pilot_pause;
pub mod progress;
pub mod run;
pub mod status_report;

pub use ending::{EndEvent, EndPhase, EndSequence, EndStep, McuMode, ModeCommand};
pub use follower::{Guidance, LegInfo, Phase, Request, WaypointFollower};
pub use mission::{from_yaml_str, Mission, MissionError, Waypoint};
pub use run::{MissionRun, RunConfig};
pub mod track;
