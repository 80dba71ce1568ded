//! An in-process stand-in for the Linux computer of paper A: it reads the MCU's navigation state,
//! runs the plan (hover, a waypoint mission through `fcc_mission`, or nothing when carried) and
//! sends velocity setpoints and commands at 20 Hz — what the bridge and mission node do over the
//! UART in the full stack.

use super::log::PlanPhase;
use super::scenario::{FlightPlan, Scenario};
use fcc_firmware::commands::{Command, Mode, VelocitySetpoint, YawSetpoint};
use fcc_firmware::flight::FlightCore;
use fcc_mission::{Guidance, Mission, Phase, Request, WaypointFollower};

/// Setpoint time-to-live sent with every velocity setpoint (ms): several 20 Hz periods.
pub const SETPOINT_TTL_MS: u16 = 300;

enum Plan {
    Hover {
        alt_m: f32,
        hold_s: f32,
        hold_start_s: Option<f64>,
        settle_s: f64,
        landing: bool,
    },
    Mission {
        follower: WaypointFollower,
        land_sent: bool,
    },
    Velocity {
        alt_m: f32,
        speed_mps: f32,
        radius_m: f32,
        cruise_s: f32,
        cruise_start_s: Option<f64>,
        landing: bool,
    },
    Carried,
}

pub struct LinuxSide {
    plan: Plan,
    phase: PlanPhase,
    armed_once: bool,
    done: bool,
    events: Vec<(f64, String)>,
    /// Setpoints the MCU refused, and of those, refused because the pilot had the vehicle.
    pub setpoint_rejects: u32,
    pub pilot_rejects: u32,
}

impl LinuxSide {
    pub fn new(s: &Scenario) -> Result<Self, String> {
        let plan = match &s.flight {
            FlightPlan::Hover { alt_m, hold_s } => Plan::Hover {
                alt_m: *alt_m,
                hold_s: *hold_s,
                hold_start_s: None,
                settle_s: 0.0,
                landing: false,
            },
            FlightPlan::Mission { mission_file } => {
                let text = std::fs::read_to_string(mission_file)
                    .map_err(|e| format!("{}: {e}", mission_file.display()))?;
                let m: Mission = fcc_mission::from_yaml_str(&text)
                    .map_err(|e| format!("{}: {e}", mission_file.display()))?;
                Plan::Mission {
                    follower: WaypointFollower::new(m),
                    land_sent: false,
                }
            }
            FlightPlan::MissionInline { mission } => Plan::Mission {
                follower: WaypointFollower::new(mission.clone()),
                land_sent: false,
            },
            FlightPlan::Velocity {
                alt_m,
                speed_mps,
                radius_m,
                cruise_s,
            } => Plan::Velocity {
                alt_m: *alt_m,
                speed_mps: *speed_mps,
                radius_m: *radius_m,
                cruise_s: *cruise_s,
                cruise_start_s: None,
                landing: false,
            },
            FlightPlan::Elevator { .. } | FlightPlan::Rig { .. } => Plan::Carried,
        };
        let phase = if matches!(plan, Plan::Carried) {
            PlanPhase::Carried
        } else {
            PlanPhase::Waiting
        };
        Ok(Self {
            plan,
            phase,
            armed_once: false,
            done: false,
            events: Vec::new(),
            setpoint_rejects: 0,
            pilot_rejects: 0,
        })
    }

    pub fn status(&self) -> PlanPhase {
        self.phase
    }
    pub fn done(&self) -> bool {
        self.done
    }
    pub fn events(&self) -> &[(f64, String)] {
        &self.events
    }

    fn event(&mut self, t_s: f64, what: String) {
        self.events.push((t_s, what));
    }

    fn try_arm(
        armed_once: &mut bool,
        events: &mut Vec<(f64, String)>,
        t_us: u64,
        core: &mut FlightCore,
    ) -> bool {
        if core.armed() {
            return true;
        }
        if *armed_once {
            // Disarmed after having flown: the flight is over.
            return false;
        }
        if core.command(t_us, Command::Arm).is_ok() {
            *armed_once = true;
            events.push((t_us as f64 * 1e-6, "armed".into()));
            true
        } else {
            false
        }
    }

    pub fn update(&mut self, t_us: u64, core: &mut FlightCore) {
        let t_s = t_us as f64 * 1e-6;
        if self.armed_once && !core.armed() && !self.done {
            self.done = true;
            self.phase = PlanPhase::Done;
            self.event(t_s, format!("disarmed ({:?})", core.failsafe()));
            return;
        }
        // The plan is taken out while it runs so that its step may use the rest of `self`.
        let mut plan = std::mem::replace(&mut self.plan, Plan::Carried);
        match &mut plan {
            Plan::Carried => {}
            Plan::Hover {
                alt_m,
                hold_s,
                hold_start_s,
                settle_s,
                landing,
            } => self.update_hover(
                t_us,
                core,
                (*alt_m, *hold_s),
                hold_start_s,
                settle_s,
                landing,
            ),
            Plan::Velocity {
                alt_m,
                speed_mps,
                radius_m,
                cruise_s,
                cruise_start_s,
                landing,
            } => self.update_velocity(
                t_us,
                core,
                (*alt_m, *speed_mps, *radius_m, *cruise_s),
                cruise_start_s,
                landing,
            ),
            Plan::Mission {
                follower,
                land_sent,
            } => self.update_mission(t_us, core, follower, land_sent),
        }
        self.plan = plan;
    }

    /// A velocity setpoint with the link's time-to-live; with a heading to hold (NED, rad) if
    /// `yaw_rad` is given, else keeping the held heading.
    fn setpoint(vel_ned_mps: [f32; 3], yaw_rad: Option<f32>) -> VelocitySetpoint {
        VelocitySetpoint {
            vel_ned_mps,
            yaw: match yaw_rad {
                Some(yaw_ned_rad) => YawSetpoint::Heading { yaw_ned_rad },
                None => YawSetpoint::Keep,
            },
            ttl_ms: SETPOINT_TTL_MS,
        }
    }

    /// Send a setpoint, counting a refusal.
    fn send_setpoint(&mut self, t_us: u64, core: &mut FlightCore, sp: VelocitySetpoint) {
        let r = core.setpoint(t_us, sp);
        count(&mut self.setpoint_rejects, &mut self.pilot_rejects, r);
    }

    /// Hover plan: arm, climb to `alt_m` (`(alt_m, hold_s)`), settle 2 s, HOLD for `hold_s`,
    /// then LAND.
    fn update_hover(
        &mut self,
        t_us: u64,
        core: &mut FlightCore,
        (alt_m, hold_s): (f32, f32),
        hold_start_s: &mut Option<f64>,
        settle_s: &mut f64,
        landing: &mut bool,
    ) {
        let t_s = t_us as f64 * 1e-6;
        if *landing {
            return;
        }
        if let Some(start) = *hold_start_s {
            if t_s - start >= hold_s as f64 {
                *landing = true;
                let _ = core.command(t_us, Command::Land);
                self.phase = PlanPhase::Landing;
                self.events.push((t_s, "hold done, landing".into()));
            }
            return;
        }
        if !Self::try_arm(&mut self.armed_once, &mut self.events, t_us, core) {
            return;
        }
        let nav = *core.nav();
        let alt = -nav.pos_ned_m[2];
        let err = alt_m - alt;
        let vz_up = (0.8 * err).clamp(-1.0, 1.5);
        self.send_setpoint(t_us, core, Self::setpoint([0.0, 0.0, -vz_up], None));
        self.phase = PlanPhase::Climbing;
        if err.abs() < 0.3 && nav.vel_ned_mps[2].abs() < 0.3 {
            *settle_s += 0.05;
        } else {
            *settle_s = 0.0;
        }
        if *settle_s >= 2.0 && core.command(t_us, Command::Hold).is_ok() {
            *hold_start_s = Some(t_s);
            let hold = [nav.pos_ned_m[0], nav.pos_ned_m[1], nav.pos_ned_m[2]];
            self.phase = PlanPhase::Holding { hold_ned_m: hold };
            self.events
                .push((t_s, format!("holding at {:.2?} for {hold_s} s", hold)));
        }
    }

    /// Velocity plan: arm, climb to `alt_m`, cruise on a circle of `radius_m` at `speed_mps`
    /// for `cruise_s` (`(alt_m, speed_mps, radius_m, cruise_s)`), then LAND.
    fn update_velocity(
        &mut self,
        t_us: u64,
        core: &mut FlightCore,
        (alt_m, speed_mps, radius_m, cruise_s): (f32, f32, f32, f32),
        cruise_start_s: &mut Option<f64>,
        landing: &mut bool,
    ) {
        let t_s = t_us as f64 * 1e-6;
        if *landing {
            return;
        }
        if let Some(start) = *cruise_start_s {
            if t_s - start >= cruise_s as f64 {
                *landing = true;
                let _ = core.command(t_us, Command::Land);
                self.phase = PlanPhase::Landing;
                self.events.push((t_s, "cruise done, landing".into()));
                return;
            }
            // Tangent to the circle through the start point (counter-clockwise seen
            // from above), zero climb: the MCU holds the height.
            let w = speed_mps / radius_m;
            let a = w * (t_s - start) as f32;
            let (s_a, c_a) = (a.sin(), a.cos());
            let v = [-speed_mps * s_a, speed_mps * c_a, 0.0];
            self.send_setpoint(t_us, core, Self::setpoint(v, None));
            return;
        }
        if !Self::try_arm(&mut self.armed_once, &mut self.events, t_us, core) {
            return;
        }
        let nav = *core.nav();
        let err = alt_m + nav.pos_ned_m[2];
        let vz_up = (0.8 * err).clamp(-1.0, 1.5);
        self.send_setpoint(t_us, core, Self::setpoint([0.0, 0.0, -vz_up], None));
        self.phase = PlanPhase::Climbing;
        if err.abs() < 0.1 && nav.vel_ned_mps[2].abs() < 0.2 {
            *cruise_start_s = Some(t_s);
            self.phase = PlanPhase::Cruise { speed_mps };
            self.events
                .push((t_s, format!("cruise at {speed_mps} m/s for {cruise_s} s")));
        }
    }

    /// Mission plan: once the MCU is ready, follow `fcc_mission`'s guidance (arm, legs,
    /// holds), LAND when it asks to, and report its phase.
    fn update_mission(
        &mut self,
        t_us: u64,
        core: &mut FlightCore,
        follower: &mut WaypointFollower,
        land_sent: &mut bool,
    ) {
        let t_s = t_us as f64 * 1e-6;
        if core.mode() == Mode::Disarmed && !self.armed_once && core.navigator().ready().is_err() {
            return; // wait for calibration and a GPS home before starting the mission
        }
        let nav = *core.nav();
        let g = follower.update(t_s, nav.pos_ned_m, nav.vel_ned_mps);
        match g.request {
            Some(Request::Arm) => {
                if !Self::try_arm(&mut self.armed_once, &mut self.events, t_us, core) {
                    return;
                }
            }
            Some(Request::Land) if !*land_sent => {
                *land_sent = true;
                let _ = core.command(t_us, Command::Land);
                self.phase = PlanPhase::Landing;
                self.events.push((t_s, "mission done, landing".into()));
                return;
            }
            _ => {}
        }
        if *land_sent {
            return;
        }
        let phase = Self::mission_plan_phase(&g);
        if phase != self.phase {
            let what = format!("{phase:?}");
            self.phase = phase;
            self.events.push((t_s, what));
        }
        if core.armed() {
            self.send_setpoint(t_us, core, Self::setpoint(g.vel_ned_mps, g.yaw_rad));
        }
    }

    /// The logged plan phase of the mission follower's guidance.
    fn mission_plan_phase(g: &Guidance) -> PlanPhase {
        match (g.phase, g.leg) {
            (Phase::Leg(i), Some(leg)) => PlanPhase::Leg {
                index: i,
                from_ned_m: leg.from_ned_m,
                to_ned_m: leg.to_ned_m,
            },
            (Phase::Hold(i), _) => PlanPhase::HoldAtWaypoint(i),
            (Phase::Takeoff, _) => PlanPhase::Climbing,
            (Phase::Landing, _) => PlanPhase::Landing,
            (Phase::Done, _) => PlanPhase::Done,
            _ => PlanPhase::Waiting,
        }
    }
}

/// Count a refused setpoint (and whether the pilot's override refused it).
fn count(all: &mut u32, pilot: &mut u32, r: Result<(), fcc_firmware::commands::CommandError>) {
    if let Err(e) = r {
        *all += 1;
        if e == fcc_firmware::commands::CommandError::PilotOverride {
            *pilot += 1;
        }
    }
}

/// The elevator ride (paper A Figs. 8–9): floors visited in order with a trapezoidal speed
/// profile, dwelling `dwell_s` at each (and before the first move). Returns analytic
/// [height m, vertical speed m/s, acceleration m/s²] every millisecond, heights relative to
/// the first floor.
pub fn elevator_profile(
    floors: &[i32],
    floor_height_m: f32,
    speed_mps: f32,
    accel_mps2: f32,
    dwell_s: f32,
) -> Vec<[f64; 3]> {
    let (vmax, a) = (speed_mps as f64, accel_mps2 as f64);
    let dt = 1e-3;
    let mut out = Vec::new();
    let hold = |out: &mut Vec<[f64; 3]>, h: f64, secs: f64| {
        for _ in 0..(secs / dt).round() as usize {
            out.push([h, 0.0, 0.0]);
        }
    };
    let base = floors[0] as f64 * floor_height_m as f64;
    let mut h = 0.0;
    hold(&mut out, h, dwell_s as f64);
    for w in floors.windows(2) {
        let d = (w[1] - w[0]) as f64 * floor_height_m as f64;
        let dist = d.abs();
        let sgn = d.signum();
        // Trapezoid (or triangle if too short).
        let v = vmax.min((a * dist).sqrt());
        let t_acc = v / a;
        let d_acc = 0.5 * a * t_acc * t_acc;
        let t_cruise = (dist - 2.0 * d_acc).max(0.0) / v;
        let total = 2.0 * t_acc + t_cruise;
        let n = (total / dt).round() as usize;
        for k in 0..n {
            let t = k as f64 * dt;
            let (s, vel, acc) = if t < t_acc {
                (0.5 * a * t * t, a * t, a)
            } else if t < t_acc + t_cruise {
                (d_acc + v * (t - t_acc), v, 0.0)
            } else {
                let td = t - t_acc - t_cruise;
                (
                    d_acc + v * t_cruise + v * td - 0.5 * a * td * td,
                    v - a * td,
                    -a,
                )
            };
            out.push([h + sgn * s, sgn * vel, sgn * acc]);
        }
        h += d;
        hold(&mut out, h, dwell_s as f64);
    }
    let _ = base;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elevator_profile_reaches_each_floor() {
        let p = elevator_profile(&[3, 6, 4, 3], 3.5, 1.0, 0.5, 10.0);
        let last = p.last().unwrap();
        assert!(last[0].abs() < 1e-6 && last[1].abs() < 1e-9);
        let max = p.iter().map(|x| x[0]).fold(f64::MIN, f64::max);
        assert!((max - 10.5).abs() < 1e-3, "{max}");
        // Integrating v reproduces h.
        let mut h = 0.0;
        for x in &p {
            h += x[1] * 1e-3;
        }
        assert!(h.abs() < 0.02, "{h}");
    }
}
