//! One run of the mission node, cycle by cycle: wait for the bridge → arm → fly the mission
//! (paused while the pilot flies) → the end ([`EndSequence`]) → landed and disarmed.
//!
//! Each cycle the node passes in its wall clock and what it last heard (the position and
//! velocity estimate in NED, the MCU's status, the ROS time); [`MissionRun::tick`] answers
//! with what to send (`cmd/arm`, `cmd/mode`, a velocity setpoint, `mission/status`), what to
//! log, and whether the run is over. The node does the I/O only: which topic, which message
//! type, which frame (ENU on ROS), so this sequencing is unit-tested here.
//!
//! Exit codes are the node's: every [`Outcome::Failed`] is a failure (1).

use crate::arming::{ArmAction, ArmRequests};
use crate::pilot_pause::{PauseEvent, PilotPause};
use crate::progress::{dist_to_go_m, phase_name, PhaseName, Progress};
use crate::status_report::{finished_json, ReportClock, StatusReport};
use crate::{EndPhase, EndSequence, McuMode, Mission, Phase, Request, WaypointFollower};

/// Wall time after the start before the node says what it is still waiting for, s.
pub const WAITING_NOTE_AFTER_S: f64 = 5.0;

/// The MCU's latest status, as the mission reads it (from `fcc_msgs/Status`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct McuStatus<'a> {
    pub armed: bool,
    pub landed: bool,
    /// The flight mode (when not `pilot`).
    pub mode: McuMode,
    /// The pilot flies (R/C override).
    pub pilot: bool,
    /// A failsafe cause is active.
    pub failsafe: bool,
    /// Names as on `status`, for the log and `mission/status`.
    pub mode_name: &'a str,
    pub failsafe_name: &'a str,
    /// The latest command rejection (`""` or `accepted` when none).
    pub last_reject: &'a str,
}

/// What the node knows at one cycle, once it has heard everything.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample<'a> {
    /// ROS time, ns.
    pub now_ns: i64,
    /// Position estimate, NED, m.
    pub pos_ned_m: [f32; 3],
    /// Velocity estimate, NED, m/s.
    pub vel_ned_mps: [f32; 3],
    pub mcu: McuStatus<'a>,
}

/// The input of one cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input<'a> {
    /// Something is missing: which of odometry, status and the ROS clock the node has.
    Waiting {
        odom: bool,
        status: bool,
        clock: bool,
    },
    Ready(Sample<'a>),
}

/// A log line's level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    Info,
    Warn,
}

/// How the run ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Every waypoint done, landed and disarmed (an action goal without landing: holding at
    /// the last waypoint, the MCU asked to HOLD).
    Complete,
    /// The mission failed (timeout, could not arm, disarmed in flight): the message.
    Failed(String),
    /// [`RunKind::ActionGoal`]: an MCU failsafe became active during the mission (the message).
    Failsafe(String),
    /// [`RunKind::ActionGoal`]: the R/C pilot took over (the message).
    PilotOverride(String),
}

/// What a run flies, and so how it starts and ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunKind {
    /// A mission file (`fcc-mission --mission FILE`): waypoints from the position at arming,
    /// always from the ground; a pilot override pauses it (resumed when the pilot lets go).
    MissionFile,
    /// An action goal: waypoints from the origin of `map` (home); in the air it starts from
    /// where the vehicle is (no takeoff); a pilot override or an MCU failsafe ends it; without
    /// landing it is complete at the last waypoint (then the MCU holds there).
    ActionGoal,
}

/// How far a run has come, for an action's feedback.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunProgress {
    /// `arming`, `takeoff`, `leg`, `hold`, `landing`, `done`, `hover`, `pilot`.
    pub phase: &'static str,
    /// The waypoint flown to (0-based; 0 before the first leg).
    pub waypoint: usize,
    /// Waypoints reached so far.
    pub reached: usize,
    /// Waypoints of the mission.
    pub waypoint_count: usize,
    /// To the current leg's end, m (0 without one).
    pub distance_to_go_m: f32,
    /// To the last waypoint at the cruise speed, with the holds, s.
    pub eta_s: f32,
    /// Horizontal distance from the current leg's line, m (0 off a leg).
    pub cross_track_m: f32,
}

/// What to do after one cycle, in this order: log, arm, mode commands, setpoint, status.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Step {
    pub logs: Vec<(Level, String)>,
    /// Send `cmd/arm` true.
    pub arm: bool,
    /// Send these on `cmd/mode`, in order.
    pub mode_commands: Vec<&'static str>,
    /// Send this velocity setpoint (NED, m/s).
    pub setpoint_ned_mps: Option<[f32; 3]>,
    /// With it, this heading to hold (NED yaw, rad; the mission's `yaw_deg`).
    pub heading_ned_rad: Option<f32>,
    /// Publish this on `mission/status`.
    pub status: Option<String>,
    /// The run is over (after the above).
    pub outcome: Option<Outcome>,
}

impl Step {
    fn info(&mut self, line: String) {
        self.logs.push((Level::Info, line));
    }
    fn warn(&mut self, line: String) {
        self.logs.push((Level::Warn, line));
    }
}

/// The node's settings that the sequencing uses.
#[derive(Debug, Clone)]
pub struct RunConfig {
    pub mission: Mission,
    /// Fail when the mission has not finished this long after the start, s (wall clock).
    pub timeout_s: f64,
    /// Give up arming after about this long, s (see [`ArmRequests`]).
    pub arm_timeout_s: f64,
    /// Seconds of ROS time in HOLD after the last waypoint (see [`EndSequence`]).
    pub hover_s: f64,
    pub kind: RunKind,
}

/// The mission node's sequencing: see the [module docs](self).
#[derive(Debug, Clone)]
pub struct MissionRun {
    mission: Mission,
    timeout_s: f64,
    arm_timeout_s: f64,
    arming: ArmRequests,
    /// Set at arming (ROS time, ns), with the follower (home = the position then).
    armed_at_ns: Option<i64>,
    follower: Option<WaypointFollower>,
    pause: PilotPause,
    end: EndSequence,
    progress: Progress,
    reports: ReportClock,
    last_reject: String,
    waiting_noted: bool,
    /// ROS time of the first complete sample, s (times in messages count from it).
    t_first_s: Option<f64>,
    setpoints: u64,
    kind: RunKind,
    progress_now: Option<RunProgress>,
}

impl MissionRun {
    pub fn new(c: RunConfig) -> Self {
        MissionRun {
            arming: ArmRequests::new(c.arm_timeout_s),
            end: EndSequence::new(c.hover_s),
            mission: c.mission,
            timeout_s: c.timeout_s,
            arm_timeout_s: c.arm_timeout_s,
            armed_at_ns: None,
            follower: None,
            pause: PilotPause::new(),
            progress: Progress::new(),
            reports: ReportClock::new(),
            last_reject: String::new(),
            waiting_noted: false,
            t_first_s: None,
            setpoints: 0,
            kind: c.kind,
            progress_now: None,
        }
    }

    /// The progress at the latest cycle (None before the first complete sample).
    pub fn progress(&self) -> Option<RunProgress> {
        self.progress_now
    }

    /// The mission flown.
    pub fn mission(&self) -> &Mission {
        &self.mission
    }

    /// Remarks on the settings, for the log at the start.
    pub fn notes(&self) -> Vec<(Level, String)> {
        let mut n = Vec::new();
        if self.end.hover_s() > 0.0 && !self.mission.land_at_end {
            n.push((
                Level::Warn,
                "hover_s is ignored: the mission does not land at the end (land_at_end: false)"
                    .into(),
            ));
        }
        n
    }

    /// The node published a setpoint of a [`Step`] (counted for the final log line).
    pub fn setpoint_published(&mut self) {
        self.setpoints += 1;
    }

    /// One cycle: `wall_s` the node's wall clock since its start (s, monotonic).
    pub fn tick(&mut self, wall_s: f64, input: Input<'_>) -> Step {
        let mut out = Step::default();
        if wall_s > self.timeout_s {
            out.outcome = Some(Outcome::Failed(format!(
                "timeout: mission not finished after {:.0} s (phase {:?})",
                self.timeout_s,
                self.progress.last_phase()
            )));
            return out;
        }
        match input {
            Input::Waiting {
                odom,
                status,
                clock,
            } => self.waiting(wall_s, [odom, status, clock], &mut out),
            Input::Ready(s) => self.step(wall_s, &s, &mut out),
        }
        out
    }

    /// Says once, after [`WAITING_NOTE_AFTER_S`], what is missing.
    fn waiting(&mut self, wall_s: f64, [odom, status, clock]: [bool; 3], out: &mut Step) {
        if self.waiting_noted || wall_s <= WAITING_NOTE_AFTER_S {
            return;
        }
        let have = |b: bool| if b { "ok" } else { "none yet" };
        out.info(format!(
            "waiting for the bridge: state/odom {}, status {}, clock {}",
            have(odom),
            have(status),
            if clock { "ok" } else { "no /clock yet" }
        ));
        self.waiting_noted = true;
    }

    fn step(&mut self, wall_s: f64, s: &Sample<'_>, out: &mut Step) {
        let t_s = s.now_ns as f64 * 1e-9;
        let tr_s = t_s - *self.t_first_s.get_or_insert(t_s);
        self.note_reject(s.mcu.last_reject, out);
        if self.armed_at_ns.is_none() {
            if !s.mcu.armed {
                return self.arm(wall_s, t_s, s, out);
            }
            self.on_armed(t_s, tr_s, s, out);
        }
        if !s.mcu.armed {
            return self.on_disarmed(s, out);
        }
        self.fly(wall_s, t_s, tr_s, s, out);
    }

    /// A new command rejection from the MCU or the bridge: a warning.
    fn note_reject(&mut self, reject: &str, out: &mut Step) {
        if reject == self.last_reject {
            return;
        }
        self.last_reject = reject.to_string();
        if !reject.is_empty() && reject != "accepted" {
            out.warn(format!("MCU/bridge reject: {reject}"));
        }
    }

    /// Before arming: the follower asks for Arm (its takeoff); the command is re-sent.
    fn arm(&mut self, wall_s: f64, t_s: f64, s: &Sample<'_>, out: &mut Step) {
        let mut probe = WaypointFollower::new(self.mission.clone());
        let g = probe.update(t_s, s.pos_ned_m, s.vel_ned_mps);
        match self.arming.update(wall_s, g.request == Some(Request::Arm)) {
            ArmAction::Wait => {}
            ArmAction::Send => out.arm = true,
            ArmAction::GiveUp => {
                out.outcome = Some(Outcome::Failed(format!(
                    "could not arm within {:.0} s (last reject: '{}')",
                    self.arm_timeout_s, s.mcu.last_reject
                )));
                return;
            }
        }
        self.set_progress("arming", 0, None);
        self.report(wall_s, s, ("arming", None), None, out);
    }

    /// Armed: home is the position now.
    fn on_armed(&mut self, t_s: f64, tr_s: f64, s: &Sample<'_>, out: &mut Step) {
        self.armed_at_ns = Some(s.now_ns);
        let mut f = match self.kind {
            RunKind::MissionFile => WaypointFollower::new(self.mission.clone()),
            RunKind::ActionGoal => {
                WaypointFollower::with_start(self.mission.clone(), Some([0.0; 3]), !s.mcu.landed)
            }
        };
        let _ = f.update(t_s, s.pos_ned_m, s.vel_ned_mps);
        self.follower = Some(f);
        let p = s.pos_ned_m;
        out.info(format!(
            "armed at t={tr_s:.2} s, home NED [{:.2}, {:.2}, {:.2}] m",
            p[0], p[1], p[2]
        ));
    }

    /// Disarmed after arming: the end of the run (complete when landing was asked and the MCU
    /// reports landed).
    fn on_disarmed(&mut self, s: &Sample<'_>, out: &mut Step) {
        let flight_s = (s.now_ns - self.armed_at_ns.unwrap_or(s.now_ns)) as f64 * 1e-9;
        let n = self.mission.waypoints.len();
        if self.end.land_requested() && s.mcu.landed {
            let track = self.progress.track();
            out.status = Some(finished_json(n));
            out.info(format!(
                "mission complete: {n}/{n} waypoints, {flight_s:.1} s armed, {} setpoints, cross-track (estimate, as seen on state/odom) RMS {:.3} m max {:.3} m; landed and disarmed",
                self.setpoints,
                track.rms_m(),
                track.max_m()
            ));
            out.outcome = Some(Outcome::Complete);
            return;
        }
        out.outcome = Some(Outcome::Failed(format!(
            "disarmed in flight after {flight_s:.1} s (phase {:?}, end {:?}, mode {}, failsafe {}, landed {})",
            self.progress.last_phase(),
            self.end.phase(),
            s.mcu.mode_name,
            s.mcu.failsafe_name,
            s.mcu.landed
        )));
    }

    /// Armed and flying: the pilot's pause, the follower, the end sequence, the setpoint.
    fn fly(&mut self, wall_s: f64, t_s: f64, tr_s: f64, s: &Sample<'_>, out: &mut Step) {
        if self.pilot(t_s, tr_s, s, out) {
            self.set_progress("pilot", 0, None);
            return self.report(wall_s, s, ("pilot", None), None, out);
        }
        // A stale setpoint (a late cycle on a loaded machine) is not an end: the MCU holds and
        // the next setpoint resumes velocity mode (it lands only once the setpoints are lost).
        let stale = s.mcu.failsafe_name == fcc_msgs::FailsafeCause::SetpointStale.name();
        if self.kind == RunKind::ActionGoal
            && s.mcu.failsafe
            && !stale
            && self.end.phase() == EndPhase::Mission
        {
            out.outcome = Some(Outcome::Failsafe(format!(
                "MCU failsafe {} (mode {})",
                s.mcu.failsafe_name, s.mcu.mode_name
            )));
            return;
        }
        let Some(f) = self.follower.as_mut() else {
            return;
        };
        let g = f.update(t_s, s.pos_ned_m, s.vel_ned_mps);
        let prog = progress_of(f, &g, s.pos_ned_m);
        self.progress_now = Some(prog);
        if self.kind == RunKind::ActionGoal && g.phase == Phase::Done && !self.mission.land_at_end {
            out.info(format!(
                "t={tr_s:.2} s goal reached: holding (cmd/mode hold)"
            ));
            out.mode_commands.push("hold");
            out.outcome = Some(Outcome::Complete);
            return;
        }
        if let Some((name, idx)) = self.progress.update(&g, s.pos_ned_m) {
            let idx = idx.map(|i| format!(" {i}")).unwrap_or_default();
            out.info(format!("t={tr_s:.2} s {name}{idx}"));
        }
        let dist = dist_to_go_m(&g, s.pos_ned_m);
        let mission_done = g.request == Some(Request::Land);
        let step = self
            .end
            .update(t_s, mission_done, s.mcu.mode, s.mcu.failsafe);
        if let Some(e) = &step.event {
            let line = format!("t={tr_s:.2} s {e}");
            out.logs.push((
                if e.is_warning() {
                    Level::Warn
                } else {
                    Level::Info
                },
                line,
            ));
        }
        out.mode_commands.extend(step.command.map(|c| c.as_str()));
        if !step.send_setpoints {
            let phase = match self.end.phase() {
                EndPhase::Hover => "hover",
                _ => "landing",
            };
            self.set_progress(phase, prog.waypoint, Some(prog.reached));
            return self.report(wall_s, s, (phase, None), None, out);
        }
        out.setpoint_ned_mps = Some(g.vel_ned_mps);
        out.heading_ned_rad = g.yaw_rad;
        self.report(wall_s, s, phase_name(g.phase), dist, out);
    }

    /// The pilot override: true while the pilot flies (nothing to send but the report).
    fn pilot(&mut self, t_s: f64, tr_s: f64, s: &Sample<'_>, out: &mut Step) -> bool {
        let p = self.pause.update(t_s, s.mcu.pilot, s.mcu.mode);
        match p.event {
            None => {}
            Some(PauseEvent::Paused) => out.warn(format!(
                "t={tr_s:.2} s pilot override: mission paused, no setpoints"
            )),
            Some(PauseEvent::Released) => out.info(format!(
                "t={tr_s:.2} s pilot released control (MCU {}): resuming with cmd/mode velocity",
                s.mcu.mode_name
            )),
            Some(PauseEvent::Resumed) => out.info(format!(
                "t={tr_s:.2} s pilot released control: mission resumed"
            )),
        }
        if p.send_resume {
            out.mode_commands.push("velocity");
        }
        if p.paused && self.kind == RunKind::ActionGoal {
            out.outcome = Some(Outcome::PilotOverride(format!(
                "t={tr_s:.2} s the R/C pilot took over (mode {})",
                s.mcu.mode_name
            )));
        }
        p.paused
    }

    /// Progress outside the follower's phases (arming, pilot, hover, landing).
    fn set_progress(&mut self, phase: &'static str, waypoint: usize, reached: Option<usize>) {
        let reached = reached.unwrap_or(self.progress_now.map_or(0, |p| p.reached));
        self.progress_now = Some(RunProgress {
            phase,
            waypoint,
            reached,
            waypoint_count: self.mission.waypoints.len(),
            distance_to_go_m: 0.0,
            eta_s: 0.0,
            cross_track_m: 0.0,
        });
    }

    /// `mission/status`, when one is due: `phase` (name, waypoint), the distance to go.
    fn report(
        &mut self,
        wall_s: f64,
        s: &Sample<'_>,
        (phase, waypoint): PhaseName,
        dist_to_go_m: Option<f32>,
        out: &mut Step,
    ) {
        if !self.reports.due(wall_s) {
            return;
        }
        let r = StatusReport {
            t_s: s.now_ns as f64 * 1e-9,
            phase,
            waypoint,
            of: self.mission.waypoints.len(),
            dist_to_go_m,
            armed: s.mcu.armed,
            mode: s.mcu.mode_name,
        };
        out.status = Some(r.json());
    }
}

/// The progress of a follower's guidance `g` at `pos_ned_m`: the waypoint, the distance to the
/// leg's end, the ETA to the last waypoint (the rest of this leg and the later legs at the
/// cruise speed, plus the holds) and the cross-track (horizontal, from the leg's line).
fn progress_of(f: &WaypointFollower, g: &crate::Guidance, pos_ned_m: [f32; 3]) -> RunProgress {
    let m = f.mission();
    let n = m.waypoints.len();
    let (phase, _) = phase_name(g.phase);
    let waypoint = match g.phase {
        Phase::Leg(i) | Phase::Hold(i) => i,
        Phase::Landing | Phase::Done => n.saturating_sub(1),
        _ => 0,
    };
    let reached = match g.phase {
        Phase::Leg(i) => i,
        Phase::Hold(i) => i + 1,
        Phase::Landing | Phase::Done => n,
        _ => 0,
    };
    let to_go = dist_to_go_m(g, pos_ned_m).unwrap_or(0.0);
    let later: f32 = (waypoint + 1..n)
        .map(|i| {
            let (a, b) = (m.waypoints[i - 1].ned_m(), m.waypoints[i].ned_m());
            ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt()
        })
        .sum();
    let holds = m.hold_s * (n - reached.min(n)) as f32;
    let eta_s = match g.phase {
        Phase::Landing | Phase::Done => 0.0,
        _ => (to_go + later) / m.speed_mps + holds,
    };
    let cross_track_m = match (g.phase, g.leg) {
        (Phase::Leg(_), Some(l)) => {
            let (dn, de) = (
                l.to_ned_m[0] - l.from_ned_m[0],
                l.to_ned_m[1] - l.from_ned_m[1],
            );
            let len = (dn * dn + de * de).sqrt();
            let (pn, pe) = (
                pos_ned_m[0] - l.from_ned_m[0],
                pos_ned_m[1] - l.from_ned_m[1],
            );
            if len < 1e-3 {
                0.0
            } else {
                (pn * de - pe * dn).abs() / len
            }
        }
        _ => 0.0,
    };
    RunProgress {
        phase,
        waypoint,
        reached,
        waypoint_count: n,
        distance_to_go_m: to_go,
        eta_s,
        cross_track_m,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::from_yaml_str;

    pub(crate) const MISSION: &str = "takeoff_alt_m: 2\nspeed_mps: 2\naccel_limit_mps2: 1\n\
        accept_radius_m: 0.3\nhold_s: 0.5\nwaypoints: [{north_m: 4, east_m: 0, alt_m: 2}]\n";
    /// ROS time at the first cycle, s (the node's messages count from it).
    const T0_S: f64 = 1000.0;
    pub(crate) const DT_S: f64 = 0.02;

    fn run(arm_timeout_s: f64, hover_s: f64) -> MissionRun {
        MissionRun::new(RunConfig {
            mission: from_yaml_str(MISSION).unwrap(),
            timeout_s: 600.0,
            arm_timeout_s,
            hover_s,
            kind: RunKind::MissionFile,
        })
    }

    /// A kinematic vehicle and its MCU: arms on `cmd/arm`, follows the setpoints exactly in
    /// velocity mode, stops in HOLD, descends at 1 m/s in land mode and disarms 1 s after
    /// touchdown. `pilot` makes it refuse everything (the pilot flies: it hovers).
    pub(crate) struct Vehicle {
        pub(crate) pos: [f32; 3],
        pub(crate) vel: [f32; 3],
        pub(crate) armed: bool,
        pub(crate) landed: bool,
        pub(crate) mode: McuMode,
        pub(crate) pilot: bool,
        refuse_arm: bool,
        on_ground_s: f64,
    }

    impl Vehicle {
        pub(crate) fn new() -> Self {
            Vehicle {
                pos: [3.0, -2.0, 0.0],
                vel: [0.0; 3],
                armed: false,
                landed: true,
                mode: McuMode::Disarmed,
                pilot: false,
                refuse_arm: false,
                on_ground_s: 0.0,
            }
        }

        fn mode_name(&self) -> &'static str {
            match (self.pilot, self.mode) {
                (true, _) | (_, McuMode::Pilot) => "pilot",
                (_, McuMode::Disarmed) => "disarmed",
                (_, McuMode::Hold) => "hold",
                (_, McuMode::Velocity) => "velocity",
                (_, McuMode::Land) => "land",
            }
        }

        pub(crate) fn sample(&self, t_s: f64) -> Sample<'static> {
            Sample {
                now_ns: ((T0_S + t_s) * 1e9).round() as i64,
                pos_ned_m: self.pos,
                vel_ned_mps: self.vel,
                mcu: McuStatus {
                    armed: self.armed,
                    landed: self.landed,
                    mode: self.mode,
                    pilot: self.pilot,
                    failsafe: false,
                    mode_name: self.mode_name(),
                    failsafe_name: "none",
                    last_reject: if self.refuse_arm { "not ready" } else { "" },
                },
            }
        }

        pub(crate) fn apply(&mut self, step: &Step) {
            if self.pilot {
                self.vel = [0.0; 3];
            } else {
                if step.arm && !self.refuse_arm && !self.armed {
                    (self.armed, self.mode) = (true, McuMode::Velocity);
                }
                for c in &step.mode_commands {
                    self.mode = match *c {
                        "hold" => McuMode::Hold,
                        "land" => McuMode::Land,
                        "velocity" => McuMode::Velocity,
                        other => panic!("unknown command {other}"),
                    };
                }
                // The firmware's rule: a fresh setpoint resumes velocity mode from HOLD.
                if self.mode == McuMode::Hold && step.setpoint_ned_mps.is_some() {
                    self.mode = McuMode::Velocity;
                }
                self.vel = match (self.mode, step.setpoint_ned_mps) {
                    (McuMode::Velocity, Some(v)) => v,
                    (McuMode::Land, _) => [0.0, 0.0, 1.0],
                    _ => [0.0; 3],
                };
            }
            for k in 0..3 {
                self.pos[k] += self.vel[k] * DT_S as f32;
            }
            if self.pos[2] >= 0.0 {
                (self.pos[2], self.vel[2]) = (0.0, self.vel[2].min(0.0));
            }
            self.landed = self.pos[2] >= -0.01 && self.vel[2] >= 0.0;
            self.on_ground_s = if self.landed {
                self.on_ground_s + DT_S
            } else {
                0.0
            };
            if self.armed && self.mode == McuMode::Land && self.on_ground_s >= 1.0 {
                (self.armed, self.mode) = (false, McuMode::Disarmed);
            }
        }
    }

    /// Flies until the outcome or `t_end_s`; `script(t, vehicle)` may change the vehicle first.
    /// Every cycle's step, with its time (s since the start).
    fn fly(
        r: &mut MissionRun,
        v: &mut Vehicle,
        t_end_s: f64,
        mut script: impl FnMut(f64, &mut Vehicle),
    ) -> Vec<(f64, Step)> {
        let mut out = Vec::new();
        for k in 0..(t_end_s / DT_S) as usize {
            let t = k as f64 * DT_S;
            script(t, v);
            let step = r.tick(t, Input::Ready(v.sample(t)));
            if step.setpoint_ned_mps.is_some() {
                r.setpoint_published();
            }
            v.apply(&step);
            let done = step.outcome.is_some();
            out.push((t, step));
            if done {
                break;
            }
        }
        out
    }

    fn lines(steps: &[(f64, Step)]) -> Vec<String> {
        steps
            .iter()
            .flat_map(|s| s.1.logs.iter().map(|l| l.1.clone()))
            .collect()
    }

    #[test]
    fn waits_for_the_bridge_then_says_once_what_is_missing() {
        let mut r = run(60.0, 0.0);
        let waiting = |odom, status, clock| Input::Waiting {
            odom,
            status,
            clock,
        };
        assert_eq!(r.tick(1.0, waiting(false, false, false)), Step::default());
        let s = r.tick(5.1, waiting(true, false, false));
        assert_eq!(
            s.logs,
            vec![(
                Level::Info,
                "waiting for the bridge: state/odom ok, status none yet, clock no /clock yet"
                    .to_string()
            )]
        );
        assert_eq!(s.status, None);
        assert_eq!(r.tick(8.0, waiting(true, true, false)), Step::default());
    }

    #[test]
    fn times_out_with_the_phase() {
        let mut r = run(60.0, 0.0);
        let s = r.tick(
            600.5,
            Input::Waiting {
                odom: true,
                status: true,
                clock: true,
            },
        );
        assert_eq!(
            s.outcome,
            Some(Outcome::Failed(
                "timeout: mission not finished after 600 s (phase None)".into()
            ))
        );
    }

    /// The mission's `yaw_deg` goes out with every setpoint (NED rad), none without it.
    #[test]
    fn heading_rides_with_every_setpoint() {
        let mut m = from_yaml_str(MISSION).unwrap();
        m.yaw_deg = Some(90.0);
        let mut r = MissionRun::new(RunConfig {
            mission: m,
            timeout_s: 600.0,
            arm_timeout_s: 60.0,
            hover_s: 0.0,
            kind: RunKind::MissionFile,
        });
        let steps = fly(&mut r, &mut Vehicle::new(), 120.0, |_, _| {});
        let with_sp: Vec<&Step> = steps
            .iter()
            .map(|s| &s.1)
            .filter(|s| s.setpoint_ned_mps.is_some())
            .collect();
        assert!(with_sp.len() > 100, "{}", with_sp.len());
        assert!(with_sp
            .iter()
            .all(|s| s.heading_ned_rad == Some(core::f32::consts::FRAC_PI_2)));
        let steps = fly(&mut run(60.0, 0.0), &mut Vehicle::new(), 120.0, |_, _| {});
        assert!(steps.iter().all(|s| s.1.heading_ned_rad.is_none()));
    }

    #[test]
    fn flies_the_mission_arms_lands_and_completes() {
        let (mut r, mut v) = (run(60.0, 0.0), Vehicle::new());
        let steps = fly(&mut r, &mut v, 120.0, |_, _| {});
        let (t_last, last) = steps.last().unwrap();
        assert_eq!(last.outcome, Some(Outcome::Complete), "{:?}", lines(&steps));
        assert_eq!(last.status.as_deref(), Some(finished_json(1).as_str()));
        // One arm command (taken at once), reported as arming before it.
        assert_eq!(steps.iter().filter(|s| s.1.arm).count(), 1);
        assert!(steps[0].1.arm);
        assert!(steps[0]
            .1
            .status
            .as_deref()
            .unwrap()
            .contains("\"phase\":\"arming\""));
        let l = lines(&steps);
        assert_eq!(
            l[0], "armed at t=0.02 s, home NED [3.00, -2.00, 0.00] m",
            "{l:?}"
        );
        let phases: Vec<&str> = l[1..l.len() - 1]
            .iter()
            .map(|x| x.split_once(" s ").unwrap().1)
            .collect();
        assert_eq!(
            phases,
            [
                "takeoff",
                "leg 0",
                "hold 0",
                "landing",
                "mission done, landing"
            ],
            "{l:?}"
        );
        let setpoints = steps
            .iter()
            .filter(|s| s.1.setpoint_ned_mps.is_some())
            .count();
        assert!(setpoints > 100, "{setpoints}");
        assert!(
            last.logs[0].1.starts_with(&format!(
                "mission complete: 1/1 waypoints, {:.1} s armed, {setpoints} setpoints, cross-track",
                t_last - 0.02
            )),
            "{:?}",
            last.logs
        );
        // The land command goes once (the MCU takes it); no setpoints after it.
        let lands: Vec<f64> = steps
            .iter()
            .filter(|s| s.1.mode_commands == ["land"])
            .map(|s| s.0)
            .collect();
        assert_eq!(lands.len(), 1, "{l:?}");
        assert!(steps
            .iter()
            .all(|s| s.0 < lands[0] || s.1.setpoint_ned_mps.is_none()));
        // mission/status at most twice a second (the final one is sent at once).
        let reports: Vec<f64> = steps[..steps.len() - 1]
            .iter()
            .filter(|s| s.1.status.is_some())
            .map(|s| s.0)
            .collect();
        assert!(
            reports.windows(2).all(|w| w[1] - w[0] >= 0.5 - 1e-9),
            "{reports:?}"
        );
        assert!(
            reports.len() as f64 >= t_last / 0.5 - 2.0,
            "{}",
            reports.len()
        );
    }

    #[test]
    fn hover_then_land() {
        let (mut r, mut v) = (run(60.0, 3.0), Vehicle::new());
        let steps = fly(&mut r, &mut v, 120.0, |_, _| {});
        assert_eq!(steps.last().unwrap().1.outcome, Some(Outcome::Complete));
        let cmds: Vec<(f64, &str)> = steps
            .iter()
            .flat_map(|s| s.1.mode_commands.iter().map(move |c| (s.0, *c)))
            .collect();
        assert_eq!(cmds.len(), 2, "{cmds:?}");
        assert_eq!((cmds[0].1, cmds[1].1), ("hold", "land"));
        assert!((cmds[1].0 - cmds[0].0 - 3.0).abs() < 0.05, "{cmds:?}");
        let hover_reports = steps
            .iter()
            .filter_map(|s| s.1.status.as_deref())
            .filter(|j| j.contains("\"phase\":\"hover\""))
            .count();
        assert!(hover_reports >= 5, "{hover_reports}");
    }

    #[test]
    fn a_pilot_override_pauses_the_mission_and_resumes_it() {
        let (mut r, mut v) = (run(60.0, 0.0), Vehicle::new());
        // The pilot takes over from 6 s to 9 s; the MCU then holds until the node resumes.
        let steps = fly(&mut r, &mut v, 120.0, |t, v| {
            if (6.0..9.0).contains(&t) {
                v.pilot = true;
            } else if v.pilot {
                (v.pilot, v.mode) = (false, McuMode::Hold);
            }
        });
        assert_eq!(steps.last().unwrap().1.outcome, Some(Outcome::Complete));
        let during: Vec<&Step> = steps
            .iter()
            .filter(|s| (6.0..9.0).contains(&s.0))
            .map(|s| &s.1)
            .collect();
        assert!(during
            .iter()
            .all(|s| s.setpoint_ned_mps.is_none() && s.mode_commands.is_empty() && !s.arm));
        assert!(during
            .iter()
            .filter_map(|s| s.status.as_deref())
            .all(|j| j.contains("\"phase\":\"pilot\"")));
        let l = lines(&steps);
        let at = |p: &str| {
            l.iter()
                .position(|x| x.contains(p))
                .unwrap_or_else(|| panic!("{p}: {l:?}"))
        };
        assert!(
            at("pilot override: mission paused, no setpoints")
                < at("pilot released control (MCU hold): resuming")
        );
        let resumes: Vec<f64> = steps
            .iter()
            .filter(|s| s.1.mode_commands == ["velocity"])
            .map(|s| s.0)
            .collect();
        assert_eq!(resumes.len(), 1, "the MCU takes it: {resumes:?}");
        assert!((resumes[0] - 9.0).abs() < 1e-6);
        assert!(at("mission resumed") > at("resuming"));
    }

    #[test]
    fn disarmed_in_flight_fails() {
        let (mut r, mut v) = (run(60.0, 0.0), Vehicle::new());
        let steps = fly(&mut r, &mut v, 60.0, |t, v| {
            if t >= 5.0 {
                (v.armed, v.mode) = (false, McuMode::Disarmed);
            }
        });
        let last = steps.last().unwrap();
        assert!((last.0 - 5.0).abs() < 1e-6);
        match &last.1.outcome {
            Some(Outcome::Failed(m)) => assert!(
                m.starts_with("disarmed in flight after 5.0 s (phase Some((\"leg\", Some(0))), end Mission, mode disarmed"),
                "{m}"
            ),
            o => panic!("{o:?}"),
        }
    }

    #[test]
    fn a_refused_arm_is_resent_each_second_then_given_up() {
        let (mut r, mut v) = (run(3.0, 0.0), Vehicle::new());
        v.refuse_arm = true;
        let steps = fly(&mut r, &mut v, 60.0, |_, _| {});
        let arms: Vec<f64> = steps.iter().filter(|s| s.1.arm).map(|s| s.0).collect();
        assert_eq!(arms.len(), 4, "{arms:?}");
        let last = steps.last().unwrap();
        assert!((last.0 - 4.0).abs() < 0.03, "{}", last.0);
        assert_eq!(
            last.1.outcome,
            Some(Outcome::Failed(
                "could not arm within 3 s (last reject: 'not ready')".into()
            ))
        );
        assert_eq!(
            lines(&steps),
            ["MCU/bridge reject: not ready"],
            "a reject is logged once"
        );
    }

    #[test]
    fn notes_on_the_settings() {
        assert!(run(60.0, 0.0).notes().is_empty());
        let mut m = from_yaml_str(MISSION).unwrap();
        m.yaw_deg = Some(90.0);
        m.land_at_end = false;
        let r = MissionRun::new(RunConfig {
            mission: m,
            timeout_s: 600.0,
            arm_timeout_s: 60.0,
            hover_s: 5.0,
            kind: RunKind::MissionFile,
        });
        let n = r.notes();
        assert_eq!(n.len(), 1);
        assert_eq!(n[0].0, Level::Warn);
        assert!(n[0].1.starts_with("hover_s is ignored"));
    }

    fn action_run(mission: &str) -> MissionRun {
        MissionRun::new(RunConfig {
            mission: from_yaml_str(mission).unwrap(),
            timeout_s: 600.0,
            arm_timeout_s: 60.0,
            hover_s: 0.0,
            kind: RunKind::ActionGoal,
        })
    }

    const HOLD_AT_END: &str = "takeoff_alt_m: 2\nspeed_mps: 2\naccept_radius_m: 0.3\n\
        land_at_end: false\nwaypoints: [{north_m: 4, east_m: 0, alt_m: 3}]\n";

    /// An action goal in the air: no arm, no takeoff, leg 0 from where the vehicle is, to the
    /// point in the map frame (not from the position at the start); complete at the point with
    /// a hold command; feedback progress along the way.
    #[test]
    fn an_action_goal_in_the_air_flies_from_here_and_holds_at_the_end() {
        let mut r = action_run(HOLD_AT_END);
        let mut v = Vehicle::new();
        (v.pos, v.armed, v.landed, v.mode) = ([-2.0, 1.0, -3.0], true, false, McuMode::Hold);
        let steps = fly(&mut r, &mut v, 60.0, |_, _| {});
        let (t, last) = steps.last().unwrap();
        assert_eq!(last.outcome, Some(Outcome::Complete), "{:?}", lines(&steps));
        assert_eq!(last.mode_commands, ["hold"]);
        assert!(steps.iter().all(|s| !s.1.arm));
        let l = lines(&steps);
        assert!(!l.iter().any(|x| x.contains("takeoff")), "{l:?}");
        assert!(*t < 10.0, "{t}");
        let d = ((v.pos[0] - 4.0).powi(2) + v.pos[1].powi(2) + (v.pos[2] + 3.0).powi(2)).sqrt();
        assert!(d < 0.4, "{:?}", v.pos);
        let p = r.progress().unwrap();
        assert_eq!((p.reached, p.waypoint_count), (1, 1));
    }

    #[test]
    fn an_action_goal_ends_on_a_pilot_override_and_on_a_failsafe() {
        let mut r = action_run(MISSION);
        let mut v = Vehicle::new();
        let steps = fly(&mut r, &mut v, 60.0, |t, v| v.pilot = t >= 4.0);
        match &steps.last().unwrap().1.outcome {
            Some(Outcome::PilotOverride(m)) => assert!(m.contains("pilot took over"), "{m}"),
            o => panic!("{o:?}"),
        }
        let mut r = action_run(MISSION);
        let mut v = Vehicle::new();
        let mut steps = Vec::new();
        for k in 0..1000 {
            let t = k as f64 * DT_S;
            let mut sample = v.sample(t);
            // A stale setpoint from 2 s to 3 s does not end it; the geofence from 4 s does.
            sample.mcu.failsafe = t >= 4.0 || (2.0..3.0).contains(&t);
            sample.mcu.failsafe_name = match t {
                t if t >= 4.0 => "geofence",
                t if (2.0..3.0).contains(&t) => "setpoint_stale",
                _ => "none",
            };
            let step = r.tick(t, Input::Ready(sample));
            v.apply(&step);
            let done = step.outcome.is_some();
            steps.push(step);
            if done {
                break;
            }
        }
        assert_eq!(
            steps.last().unwrap().outcome,
            Some(Outcome::Failsafe(
                "MCU failsafe geofence (mode velocity)".into()
            ))
        );
        // Ended at 4 s (the first geofence cycle), not at 2 s.
        assert_eq!(steps.len(), 201);
    }
}
