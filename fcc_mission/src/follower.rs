//! Waypoint follower: turns a [`Mission`] plus the vehicle's navigation
//! estimate into per-axis NED velocity commands for the flight MCU.
//!
//! Frames and units: NED (north, east, down), metres, m/s, seconds, radians.
//! Positions passed to [`WaypointFollower::update`] may be in any NED frame
//! (e.g. the MCU's local frame); the first valid position becomes *home*,
//! and mission coordinates (relative to home, altitude up) are converted to
//! that frame with `target = home + [north_m, east_m, -alt_m]`. [`LegInfo`]
//! is reported in the caller's frame as well, so it can be compared directly
//! with the positions passed in.
//!
//! The follower commands velocity along the straight leg only; cross-track
//! compensation is the MCU's job (paper A, eqs. 7–9). The commanded velocity
//! vector never changes faster than `accel_limit_mps2` (norm of the change
//! per update divided by the elapsed time), with one exception: invalid
//! (non-finite) mission parameters, which [`Mission::validate`] rejects.

use crate::mission::{Mission, MissionError};

/// Longest time step used for rate limiting and timers, s. Longer gaps
/// between updates are treated as this long (more conservative acceleration).
pub const MAX_DT_S: f64 = 0.1;
/// The stopping curve `sqrt(2·a_plan·remaining)` uses
/// `a_plan = BRAKE_PLAN_FRACTION · accel_limit_mps2`: the margin lets the rate
/// limit keep up although the vehicle's velocity lags the command (with the
/// full limit the command is rate-limited near the waypoint and overshoots).
pub const BRAKE_PLAN_FRACTION: f32 = 0.7;
/// While braking, the speed command falls by at least this fraction of the
/// acceleration limit, so braking always ends in bounded time.
pub const MIN_BRAKE_FRACTION: f32 = 0.25;
/// Landed detection: altitude above home at or below this, m.
pub const LANDED_ALT_M: f32 = 0.3;
/// Landed detection: |vertical velocity| at or below this, m/s.
pub const LANDED_VZ_MPS: f32 = 0.2;
/// Landed detection: both conditions held for this long, s.
pub const LANDED_CONFIRM_S: f64 = 1.0;

/// Mission phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Before the first (valid) update.
    Idle,
    /// Climbing vertically above home to `takeoff_alt_m`, then braking to zero.
    Takeoff,
    /// Flying the straight leg towards waypoint `i` (0-based).
    Leg(usize),
    /// Waypoint `i` reached: braking along the leg to zero, then zero
    /// velocity for `hold_s`.
    Hold(usize),
    /// Land requested from the MCU (its land mode descends); zero velocity.
    Landing,
    /// Finished: zero velocity (after landing, or hovering at the last
    /// waypoint when `land_at_end` is false).
    Done,
}

/// The straight segment currently flown, in the caller's NED frame, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegInfo {
    /// Start: home on the ground for takeoff, the takeoff point above home
    /// for leg 0, else waypoint `i-1`.
    pub from_ned_m: [f32; 3],
    /// End: the takeoff point above home for takeoff, else waypoint `i`.
    pub to_ned_m: [f32; 3],
}

/// A mode request for the vehicle. Requests are *levels*: repeated on every
/// update while they apply; the bridge should act when it changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Request {
    /// Arm (issued during [`Phase::Takeoff`]).
    Arm,
    /// Switch to the MCU's land mode (issued in [`Phase::Landing`] and in
    /// [`Phase::Done`] after a landing).
    Land,
}

/// Output of one [`WaypointFollower::update`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Guidance {
    /// Velocity command, NED, m/s.
    pub vel_ned_mps: [f32; 3],
    /// Heading command, rad clockwise from north in (-π, π]; `None` = keep
    /// current heading.
    pub yaw_rad: Option<f32>,
    /// Phase after this update.
    pub phase: Phase,
    /// Segment being flown (takeoff, leg or hold), caller's NED frame.
    pub leg: Option<LegInfo>,
    /// Mode request, see [`Request`].
    pub request: Option<Request>,
}

const UP: [f32; 3] = [0.0, 0.0, -1.0];

/// Station-keeping while holding at a waypoint: velocity per metre of error, 1/s.
pub const STATION_KEEP_GAIN_PER_S: f32 = 0.8;
/// Station-keeping velocity bound, m/s.
pub const STATION_KEEP_MAX_MPS: f32 = 0.5;
/// The hold timer starts once the vehicle is this close to the waypoint, m ...
pub const HOLD_SETTLE_M: f32 = 0.2;
/// ... or once it has tried for this long beyond the hold time, s.
pub const HOLD_SETTLE_TIMEOUT_S: f64 = 10.0;

/// Bounded proportional pull towards a point (`err` = target − position).
fn station_keep(err: [f32; 3]) -> [f32; 3] {
    let v = scale(err, STATION_KEEP_GAIN_PER_S);
    let n = norm(v);
    if n > STATION_KEEP_MAX_MPS {
        scale(v, STATION_KEEP_MAX_MPS / n)
    } else {
        v
    }
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: [f32; 3]) -> f32 {
    dot(a, a).sqrt()
}
fn scale(a: [f32; 3], k: f32) -> [f32; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}
fn finite3(a: [f32; 3]) -> bool {
    a.iter().all(|v| v.is_finite())
}

/// Runs a [`Mission`]: call [`update`](Self::update) at ≥ 20 Hz.
///
/// Phases: `Idle → Takeoff → Leg(0) → Hold(0) → … → Leg(n-1) → Hold(n-1) →
/// Landing → Done` (or `→ Done` directly when `land_at_end` is false).
///
/// The velocity command is always `speed · axis` with a scalar speed ≥ 0 and
/// a unit axis (up during takeoff, the leg direction during `Leg`/`Hold`);
/// the axis only changes while the speed is zero, so within a leg the
/// command is exactly along the leg and its changes respect the
/// acceleration limit.
#[derive(Debug, Clone)]
pub struct WaypointFollower {
    mission: Mission,
    phase: Phase,
    home: Option<[f32; 3]>,
    last_t: Option<f64>,
    /// Internal clock: sum of clamped time steps, s.
    clock: f64,
    speed: f32,
    axis: [f32; 3],
    takeoff_braking: bool,
    hold_since: Option<f64>,
    hold_entered: Option<f64>,
    correction: [f32; 3],
    landed_since: Option<f64>,
    landed: bool,
    /// See [`WaypointFollower::with_start`].
    origin: Option<[f32; 3]>,
    airborne: bool,
}

impl WaypointFollower {
    /// A follower for a mission whose waypoints are relative to `origin_ned_m` (the caller's
    /// frame, e.g. the origin of `map`) instead of home (the first position), and which, when
    /// `airborne`, starts with leg 0 from the first position (no takeoff: its `takeoff_alt_m`
    /// is not used). `with_start(m, None, false)` is [`WaypointFollower::new`].
    pub fn with_start(mission: Mission, origin_ned_m: Option<[f32; 3]>, airborne: bool) -> Self {
        WaypointFollower {
            origin: origin_ned_m,
            airborne,
            ..Self::new(mission)
        }
    }

    /// Creates a follower. The mission is not validated here (use
    /// [`try_new`](Self::try_new) or [`Mission::validate`] first); a mission
    /// without waypoints goes from takeoff straight to the end.
    pub fn new(mission: Mission) -> Self {
        WaypointFollower {
            mission,
            phase: Phase::Idle,
            home: None,
            last_t: None,
            clock: 0.0,
            speed: 0.0,
            axis: [0.0; 3],
            takeoff_braking: false,
            hold_since: None,
            hold_entered: None,
            correction: [0.0; 3],
            landed_since: None,
            landed: false,
            origin: None,
            airborne: false,
        }
    }

    /// Validates the mission, then creates the follower.
    pub fn try_new(mission: Mission) -> Result<Self, MissionError> {
        mission.validate()?;
        Ok(Self::new(mission))
    }

    /// The mission being flown.
    pub fn mission(&self) -> &Mission {
        &self.mission
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Home position (first valid position passed to `update`), caller's NED
    /// frame, m.
    pub fn home(&self) -> Option<[f32; 3]> {
        self.home
    }

    /// Takeoff point relative to home, NED m.
    fn takeoff_point(&self) -> [f32; 3] {
        [0.0, 0.0, -self.mission.takeoff_alt_m]
    }

    /// Leg `i` endpoints relative to home, NED m.
    fn leg_rel(&self, i: usize) -> ([f32; 3], [f32; 3]) {
        let from = if i == 0 {
            self.takeoff_point()
        } else {
            self.mission.waypoints[i - 1].ned_m()
        };
        (from, self.mission.waypoints[i].ned_m())
    }

    /// Unit direction of leg `i` (zero for a degenerate leg) and its length.
    fn leg_dir(&self, i: usize) -> ([f32; 3], f32) {
        let (from, to) = self.leg_rel(i);
        let d = sub(to, from);
        let len = norm(d);
        if len > 1e-6 {
            (scale(d, 1.0 / len), len)
        } else {
            ([0.0; 3], len)
        }
    }

    fn a(&self) -> f32 {
        self.mission.accel_limit_mps2
    }

    /// Stopping speed for `remaining_m` to go, m/s.
    fn stop_curve(&self, remaining_m: f32) -> f32 {
        (2.0 * BRAKE_PLAN_FRACTION * self.a() * remaining_m.max(0.0)).sqrt()
    }

    /// Speed-up/slow-down towards `target`, limited to `a·dt` either way.
    fn accelerate(&self, target: f32, dt: f32) -> f32 {
        let step = self.a() * dt;
        target.clamp(self.speed - step, self.speed + step).max(0.0)
    }

    /// Braking: never speeds up, follows the stopping curve when it is gentler than `a`, and slows by at
    /// least `MIN_BRAKE_FRACTION·a`.
    fn brake(&self, remaining_m: f32, dt: f32) -> f32 {
        let curve = self.stop_curve(remaining_m);
        let hi = self.speed - MIN_BRAKE_FRACTION * self.a() * dt;
        let lo = self.speed - self.a() * dt;
        curve.min(hi).max(lo).max(0.0)
    }

    /// Phase after the last waypoint.
    fn end_phase(&self) -> Phase {
        if self.mission.land_at_end {
            Phase::Landing
        } else {
            Phase::Done
        }
    }

    /// Phase after waypoint `i` (or after takeoff when `i` is `None`).
    fn after(&self, i: Option<usize>) -> Phase {
        let next = i.map_or(0, |i| i + 1);
        if next < self.mission.waypoints.len() {
            Phase::Leg(next)
        } else {
            self.end_phase()
        }
    }

    fn enter(&mut self, phase: Phase) {
        self.phase = phase;
        self.speed = 0.0;
        self.axis = match phase {
            Phase::Takeoff => UP,
            Phase::Leg(i) | Phase::Hold(i) => self.leg_dir(i).0,
            _ => [0.0; 3],
        };
        self.hold_since = None;
        self.hold_entered = None;
        self.landed_since = None;
        self.takeoff_braking = false;
    }

    /// One guidance step.
    ///
    /// Velocity commands are along the current leg; while holding at a waypoint (and
    /// horizontally while climbing) a small bounded station-keeping term
    /// (`STATION_KEEP_GAIN_PER_S`, at most `STATION_KEEP_MAX_MPS`) pulls the vehicle onto the
    /// point, so each straight leg starts where it should.
    ///
    /// * `t_s`: time, s (any epoch, monotonic; backward jumps count as zero
    ///   elapsed time, gaps over [`MAX_DT_S`] count as `MAX_DT_S`).
    /// * `pos_ned_m`: position estimate, NED m (any NED origin; see module docs).
    /// * `vel_ned_mps`: velocity estimate, NED m/s (used for landed detection).
    ///
    /// Non-finite inputs: the state machine does not advance and the command
    /// brakes towards zero at the acceleration limit (before home is known the
    /// follower stays `Idle`).
    pub fn update(&mut self, t_s: f64, pos_ned_m: [f32; 3], vel_ned_mps: [f32; 3]) -> Guidance {
        let dt = self.advance_clock(t_s);
        let prev_speed = self.speed;
        let prev_axis = self.axis;
        let inputs_ok = t_s.is_finite() && finite3(pos_ned_m) && finite3(vel_ned_mps);
        if self.home.is_none() {
            if !inputs_ok {
                return self.output();
            }
            self.start_at(pos_ned_m);
        }
        if !inputs_ok {
            self.speed = (self.speed - self.a() * dt).max(0.0);
            return self.output();
        }
        let rel = sub(pos_ned_m, self.home.unwrap_or([0.0; 3]));
        let want_corr = match self.phase {
            Phase::Idle => [0.0; 3],
            Phase::Takeoff => self.takeoff_step(rel, dt),
            Phase::Leg(i) => self.leg_step(i, rel, dt),
            Phase::Hold(i) => self.hold_step(i, rel, dt),
            Phase::Landing => self.landing_step(rel, vel_ned_mps),
            Phase::Done => self.done_step(rel),
        };
        self.slew(want_corr, prev_speed, prev_axis, dt);
        self.hold_timer(rel);
        self.output()
    }

    /// Home is `pos_ned_m`: re-expresses the waypoints from home when they are given from an
    /// origin, then takes off (or, airborne, starts the first leg from here).
    fn start_at(&mut self, pos_ned_m: [f32; 3]) {
        self.home = Some(pos_ned_m);
        if let Some(o) = self.origin {
            for w in &mut self.mission.waypoints {
                let ned = add(w.ned_m(), sub(o, pos_ned_m));
                (w.north_m, w.east_m, w.alt_m) = (ned[0], ned[1], -ned[2]);
            }
        }
        if self.airborne {
            self.mission.takeoff_alt_m = 0.0;
            let first = self.after(None);
            self.enter(first);
        } else {
            self.enter(Phase::Takeoff);
        }
    }

    /// The time step since the last update, s (0 for the first or a non-finite `t_s`, clamped
    /// to [0, `MAX_DT_S`]); advances the internal clock.
    fn advance_clock(&mut self, t_s: f64) -> f32 {
        let dt = match (self.last_t, t_s.is_finite()) {
            (Some(last), true) => (t_s - last).clamp(0.0, MAX_DT_S),
            _ => 0.0,
        };
        if t_s.is_finite() {
            self.last_t = Some(t_s);
        }
        self.clock += dt;
        dt as f32
    }

    /// Takeoff: climb to the takeoff altitude, brake, and go on once settled above home; the
    /// horizontal station-keeping wanted (`rel`: position from home, NED m).
    fn takeoff_step(&mut self, rel: [f32; 3], dt: f32) -> [f32; 3] {
        // Remaining climb, m (positive: below the takeoff altitude).
        let h_rem = self.mission.takeoff_alt_m + rel[2];
        if h_rem <= self.mission.accept_radius_m {
            self.takeoff_braking = true;
        }
        let horiz_err = {
            let e = sub(self.takeoff_point(), rel);
            norm([e[0], e[1], 0.0])
        };
        let waited = *self.hold_entered.get_or_insert(self.clock);
        if self.takeoff_braking {
            self.speed = self.brake(h_rem, dt);
            let settled =
                horiz_err <= HOLD_SETTLE_M || self.clock - waited >= HOLD_SETTLE_TIMEOUT_S + 30.0;
            if self.speed == 0.0 && settled {
                let next = self.after(None);
                self.enter(next);
            }
        } else {
            let target = self.mission.speed_mps.min(self.stop_curve(h_rem));
            self.speed = self.accelerate(target, dt);
        }
        // Keep above the take-off point horizontally while climbing.
        let c = station_keep(sub(self.takeoff_point(), rel));
        [c[0], c[1], 0.0]
    }

    /// Leg `i`: along the leg at the profile's speed until the waypoint is reached.
    fn leg_step(&mut self, i: usize, rel: [f32; 3], dt: f32) -> [f32; 3] {
        let (_, to) = self.leg_rel(i);
        let (u, len) = self.leg_dir(i);
        let to_go = sub(to, rel);
        let along = dot(to_go, u);
        // Reached: inside the acceptance sphere, or past the plane
        // through the waypoint normal to the leg (overshoot while
        // off track — never stall in front of the waypoint).
        if norm(to_go) <= self.mission.accept_radius_m || along <= 0.0 || len <= 1e-6 {
            self.phase = Phase::Hold(i);
            self.hold_since = None;
            self.speed = self.brake(along, dt);
        } else {
            let target = self.mission.speed_mps.min(self.stop_curve(along));
            self.speed = self.accelerate(target, dt);
        }
        [0.0; 3]
    }

    /// Hold at waypoint `i`: brake, then keep station on it.
    fn hold_step(&mut self, i: usize, rel: [f32; 3], dt: f32) -> [f32; 3] {
        let (_, to) = self.leg_rel(i);
        let along = dot(sub(to, rel), self.axis);
        self.speed = self.brake(along, dt);
        if self.speed == 0.0 {
            station_keep(sub(to, rel))
        } else {
            [0.0; 3]
        }
    }

    /// Landing (the MCU descends): done once on the ground for `LANDED_CONFIRM_S`.
    fn landing_step(&mut self, rel: [f32; 3], vel_ned_mps: [f32; 3]) -> [f32; 3] {
        self.speed = 0.0;
        let landed_now = -rel[2] <= LANDED_ALT_M && vel_ned_mps[2].abs() <= LANDED_VZ_MPS;
        if landed_now {
            let since = *self.landed_since.get_or_insert(self.clock);
            if self.clock - since >= LANDED_CONFIRM_S {
                self.enter(Phase::Done);
                self.landed = true;
            }
        } else {
            self.landed_since = None;
        }
        [0.0; 3]
    }

    /// Done: ended without landing, keep station on the last waypoint.
    fn done_step(&mut self, rel: [f32; 3]) -> [f32; 3] {
        self.speed = 0.0;
        match self.mission.waypoints.last() {
            Some(w) if !self.landed => station_keep(sub(w.ned_m(), rel)),
            _ => [0.0; 3],
        }
    }

    /// The station-keeping term slews first (so a leg starts without a sideways leftover);
    /// the along-leg speed gets what the acceleration limit leaves, so the total command
    /// never changes faster than `accel_limit_mps2`.
    fn slew(&mut self, want_corr: [f32; 3], prev_speed: f32, prev_axis: [f32; 3], dt: f32) {
        let budget = self.a() * dt;
        let d = sub(want_corr, self.correction);
        let dn = norm(d);
        let step = dn.min(budget);
        if dn > 0.0 {
            self.correction = add(self.correction, scale(d, step / dn));
        }
        let leg_budget = budget - step;
        if self.axis == prev_axis {
            self.speed = self
                .speed
                .clamp(prev_speed - leg_budget, prev_speed + leg_budget)
                .max(0.0);
        } else {
            self.speed = self.speed.min(leg_budget);
        }
    }

    /// Hold timer runs once the command has reached zero and the vehicle has settled on the
    /// waypoint (or has tried for HOLD_SETTLE_TIMEOUT_S), so the next leg starts on it.
    fn hold_timer(&mut self, rel: [f32; 3]) {
        let Phase::Hold(i) = self.phase else {
            return;
        };
        let (_, to) = self.leg_rel(i);
        let settled = norm(sub(to, rel)) <= HOLD_SETTLE_M;
        let entered = *self.hold_entered.get_or_insert(self.clock);
        let timed_out =
            self.clock - entered >= f64::from(self.mission.hold_s) + HOLD_SETTLE_TIMEOUT_S;
        if self.speed == 0.0 && !settled && !timed_out {
            // Drifted off the point: the hold restarts once back on it.
            self.hold_since = None;
        }
        if self.speed == 0.0 && (settled || timed_out) {
            let since = *self.hold_since.get_or_insert(self.clock);
            if self.clock - since >= f64::from(self.mission.hold_s) {
                let next = self.after(Some(i));
                self.enter(next);
            }
        }
    }

    fn output(&mut self) -> Guidance {
        let mut vel = add(scale(self.axis, self.speed), self.correction);
        if !finite3(vel) {
            // Only reachable with an invalid (non-finite) mission.
            self.speed = 0.0;
            vel = [0.0; 3];
        }
        let home = self.home.unwrap_or([0.0; 3]);
        let leg = match self.phase {
            Phase::Takeoff => Some(LegInfo {
                from_ned_m: home,
                to_ned_m: add(home, self.takeoff_point()),
            }),
            Phase::Leg(i) | Phase::Hold(i) => {
                let (from, to) = self.leg_rel(i);
                Some(LegInfo {
                    from_ned_m: add(home, from),
                    to_ned_m: add(home, to),
                })
            }
            _ => None,
        };
        let request = match self.phase {
            Phase::Takeoff => Some(Request::Arm),
            Phase::Landing => Some(Request::Land),
            Phase::Done if self.landed => Some(Request::Land),
            _ => None,
        };
        let yaw_rad = match self.phase {
            Phase::Idle => None,
            _ => self.mission.yaw_rad(),
        };
        Guidance {
            vel_ned_mps: vel,
            yaw_rad,
            phase: self.phase,
            leg,
            request,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mission::{from_yaml_str, Waypoint};

    fn square() -> Mission {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../launch_configs/missions/square.yaml"
        );
        from_yaml_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    }

    fn wp(n: f32, e: f32, alt: f32) -> Waypoint {
        Waypoint {
            north_m: n,
            east_m: e,
            alt_m: alt,
        }
    }

    /// Kinematic vehicle: velocity follows the command with a first-order
    /// lag; in land mode it descends at 0.5 m/s until the ground (home
    /// altitude).
    struct Sim {
        pos: [f32; 3],
        vel: [f32; 3],
        ground_d: f32,
        tau: f32,
    }

    impl Sim {
        fn step(&mut self, g: &Guidance, dt: f32) {
            let n = 10;
            let h = dt / n as f32;
            for _ in 0..n {
                if g.request == Some(Request::Land) {
                    self.vel = [0.0, 0.0, 0.5];
                    if self.pos[2] >= self.ground_d {
                        self.pos[2] = self.ground_d;
                        self.vel = [0.0; 3];
                    }
                } else {
                    for k in 0..3 {
                        self.vel[k] += (g.vel_ned_mps[k] - self.vel[k]) * h / self.tau;
                    }
                }
                for k in 0..3 {
                    self.pos[k] += self.vel[k] * h;
                }
            }
        }
    }

    struct Rec {
        t: f64,
        dt: f64,
        g: Guidance,
        pos: [f32; 3],
    }

    /// Flies `mission` from `home`; `dts` yields the update periods.
    fn fly(
        mission: Mission,
        home: [f32; 3],
        mut dts: impl FnMut(usize) -> f64,
        t_max: f64,
    ) -> Vec<Rec> {
        let mut f = WaypointFollower::new(mission);
        assert_eq!(f.phase(), Phase::Idle);
        let mut sim = Sim {
            pos: home,
            vel: [0.0; 3],
            ground_d: home[2],
            tau: 0.3,
        };
        let mut t = 12.5;
        let mut dt = 0.0;
        let mut out = Vec::new();
        let mut k = 0;
        while t < 12.5 + t_max {
            let g = f.update(t, sim.pos, sim.vel);
            out.push(Rec {
                t,
                dt,
                g,
                pos: sim.pos,
            });
            if g.phase == Phase::Done {
                break;
            }
            dt = dts(k);
            k += 1;
            sim.step(&g, dt as f32);
            t += dt;
        }
        out
    }

    fn phases(recs: &[Rec]) -> Vec<Phase> {
        let mut v: Vec<Phase> = Vec::new();
        for r in recs {
            if v.last() != Some(&r.g.phase) {
                v.push(r.g.phase);
            }
        }
        v
    }

    fn check_accel(recs: &[Rec], a: f32) {
        for w in recs.windows(2) {
            let dv = norm(sub(w[1].g.vel_ned_mps, w[0].g.vel_ned_mps));
            let dt = w[1].dt.min(MAX_DT_S) as f32;
            assert!(
                dv <= a * dt * (1.0 + 1e-4) + 1e-6,
                "accel {} > {a} at t={} ({:?} -> {:?})",
                dv / dt,
                w[1].t,
                w[0].g.phase,
                w[1].g.phase
            );
        }
    }

    #[test]
    fn square_mission_all_phases() {
        let m = square();
        let home = [100.0, -50.0, -2.0];
        let recs = fly(m.clone(), home, |_| 0.05, 200.0);
        let last = recs.last().unwrap();
        assert_eq!(last.g.phase, Phase::Done, "did not finish");
        assert!(last.t - 12.5 < 120.0, "took {} s", last.t - 12.5);
        assert_eq!(
            phases(&recs),
            vec![
                Phase::Takeoff,
                Phase::Leg(0),
                Phase::Hold(0),
                Phase::Leg(1),
                Phase::Hold(1),
                Phase::Leg(2),
                Phase::Hold(2),
                Phase::Leg(3),
                Phase::Hold(3),
                Phase::Landing,
                Phase::Done,
            ]
        );
        // Landed at home, with Land still requested.
        assert_eq!(last.g.request, Some(Request::Land));
        assert_eq!(last.g.vel_ned_mps, [0.0; 3]);
        assert!(norm(sub(last.pos, home)) < 0.5, "{:?}", last.pos);

        check_accel(&recs, m.accel_limit_mps2);

        let mut peak: f32 = 0.0;
        for (k, r) in recs.iter().enumerate() {
            let g = &r.g;
            let v = norm(g.vel_ned_mps);
            peak = peak.max(v);
            assert!(v <= m.speed_mps + 1e-4, "speed {v}");
            match g.phase {
                Phase::Takeoff => {
                    assert_eq!(g.request, Some(Request::Arm));
                    // Horizontal: only the bounded station-keeping over the take-off point.
                    assert!(
                        norm([g.vel_ned_mps[0], g.vel_ned_mps[1], 0.0])
                            <= STATION_KEEP_MAX_MPS + 1e-5
                    );
                    assert!(g.vel_ned_mps[2] <= 0.0);
                }
                Phase::Leg(i) | Phase::Hold(i) => {
                    assert_eq!(g.request, None);
                    let leg = g.leg.unwrap();
                    // LegInfo is in the caller's frame (home added).
                    let w = m.waypoints[i];
                    assert_eq!(leg.to_ned_m, add(home, w.ned_m()));
                    let d = sub(leg.to_ned_m, leg.from_ned_m);
                    let u = scale(d, 1.0 / norm(d));
                    // Along the leg, plus at most the bounded station-keeping term.
                    let along = dot(g.vel_ned_mps, u);
                    assert!(along >= -STATION_KEEP_MAX_MPS - 1e-5);
                    let perp = norm(sub(g.vel_ned_mps, scale(u, along)));
                    assert!(
                        perp <= STATION_KEEP_MAX_MPS + 1e-5,
                        "perp {perp} at t={}",
                        r.t
                    );
                    // Cross-track error of the (lagged, uncompensated) vehicle.
                    let e = sub(r.pos, leg.from_ned_m);
                    let xt = norm(sub(e, scale(u, dot(e, u))));
                    assert!(xt < 0.3, "cross-track {xt} at t={}", r.t);
                    if matches!(g.phase, Phase::Hold(_)) {
                        assert!(norm(sub(r.pos, leg.to_ned_m)) < m.accept_radius_m + 0.3);
                    }
                    // Leaving a hold: settled on the waypoint, held at least hold_s.
                    if g.phase == Phase::Hold(i)
                        && recs.get(k + 1).map(|n| n.g.phase) != Some(Phase::Hold(i))
                    {
                        assert!(
                            norm(sub(r.pos, leg.to_ned_m)) <= HOLD_SETTLE_M + 0.05,
                            "left hold at {:?}",
                            r.pos
                        );
                        let entered = recs[..=k]
                            .iter()
                            .rev()
                            .take_while(|q| q.g.phase == Phase::Hold(i))
                            .last()
                            .unwrap()
                            .t;
                        let left_at = recs[k + 1].t;
                        assert!(left_at - entered >= f64::from(m.hold_s) - 1e-6);
                    }
                }
                Phase::Landing => {
                    assert!(norm(g.vel_ned_mps) <= STATION_KEEP_MAX_MPS + 1e-5);
                    assert_eq!(g.request, Some(Request::Land));
                    assert_eq!(g.leg, None);
                }
                Phase::Idle | Phase::Done => {}
            }
            assert_eq!(g.yaw_rad, None);
        }
        assert!(peak > 0.98 * m.speed_mps, "peak {peak}");
        // Takeoff ended near the takeoff altitude.
        let first_leg = recs.iter().find(|r| r.g.phase == Phase::Leg(0)).unwrap();
        assert!((-(first_leg.pos[2] - home[2]) - m.takeoff_alt_m).abs() < m.accept_radius_m);
    }

    #[test]
    fn accel_limit_with_jittered_and_gappy_timing() {
        let mut m = square();
        m.hold_s = 0.0;
        m.accel_limit_mps2 = 2.0;
        m.speed_mps = 5.0;
        // Deterministic pseudo-random periods 20–60 ms plus occasional gaps.
        let mut s: u32 = 12345;
        let recs = fly(
            m.clone(),
            [0.0; 3],
            move |k| {
                s = s.wrapping_mul(1_103_515_245).wrapping_add(12345);
                let r = f64::from((s >> 8) % 1000) / 1000.0;
                if k % 97 == 50 {
                    0.4
                } else {
                    0.02 + 0.04 * r
                }
            },
            300.0,
        );
        assert_eq!(recs.last().unwrap().g.phase, Phase::Done);
        check_accel(&recs, m.accel_limit_mps2);
        assert_eq!(phases(&recs).len(), 11);
    }

    #[test]
    fn no_landing_ends_hovering_with_yaw() {
        let mut m = square();
        m.land_at_end = false;
        m.hold_s = 0.0;
        m.yaw_deg = Some(270.0);
        m.waypoints = vec![wp(10.0, 0.0, 8.0), wp(10.0, 0.0, 8.0), wp(10.0, 5.0, 8.0)];
        let recs = fly(m.clone(), [0.0; 3], |_| 0.05, 200.0);
        let last = recs.last().unwrap();
        assert_eq!(last.g.phase, Phase::Done);
        assert_eq!(last.g.request, None);
        // Only the bounded station-keeping term remains, and it is small on the waypoint.
        assert!(
            norm(last.g.vel_ned_mps) <= STATION_KEEP_MAX_MPS,
            "{:?}",
            last.g.vel_ned_mps
        );
        assert!(
            norm(sub(last.pos, [10.0, 5.0, -8.0])) < 0.6,
            "{:?}",
            last.pos
        );
        let ph = phases(&recs);
        // The repeated (zero-length) leg is passed through.
        assert!(
            ph.contains(&Phase::Leg(1)) && ph.contains(&Phase::Leg(2)),
            "{ph:?}"
        );
        assert!(!ph.contains(&Phase::Landing));
        let yaw = last.g.yaw_rad.unwrap();
        assert!((yaw + core::f32::consts::FRAC_PI_2).abs() < 1e-5, "{yaw}");
        check_accel(&recs, m.accel_limit_mps2);
    }

    #[test]
    fn first_update_sets_home_and_requests_arm() {
        let mut f = WaypointFollower::new(square());
        let g = f.update(1.0, [3.0, 4.0, -1.0], [0.0; 3]);
        assert_eq!(f.home(), Some([3.0, 4.0, -1.0]));
        assert_eq!(g.phase, Phase::Takeoff);
        assert_eq!(g.request, Some(Request::Arm));
        assert_eq!(g.vel_ned_mps, [0.0; 3]);
        assert_eq!(
            g.leg,
            Some(LegInfo {
                from_ned_m: [3.0, 4.0, -1.0],
                to_ned_m: [3.0, 4.0, -6.0]
            })
        );
        let g = f.update(1.05, [3.0, 4.0, -1.0], [0.0; 3]);
        assert!(
            (g.vel_ned_mps[2] + 0.05).abs() < 1e-6,
            "{:?}",
            g.vel_ned_mps
        );
    }

    #[test]
    fn non_finite_inputs_brake_and_freeze() {
        let mut f = WaypointFollower::new(square());
        let g = f.update(0.0, [f32::NAN, 0.0, 0.0], [0.0; 3]);
        assert_eq!(g.phase, Phase::Idle);
        assert_eq!(f.home(), None);
        assert_eq!(g.vel_ned_mps, [0.0; 3]);
        // Climb for a while.
        let mut t = 0.0;
        for _ in 0..20 {
            f.update(t, [0.0; 3], [0.0; 3]);
            t += 0.05;
        }
        let v0 = f.update(t, [0.0; 3], [0.0; 3]).vel_ned_mps[2];
        assert!(v0 < -0.5);
        t += 0.05;
        let g = f.update(t, [0.0, f32::INFINITY, 0.0], [0.0; 3]);
        assert_eq!(g.phase, Phase::Takeoff);
        assert!((g.vel_ned_mps[2] - (v0 + 0.05)).abs() < 1e-5);
        let g = f.update(f64::NAN, [0.0; 3], [0.0; 3]);
        assert_eq!(g.phase, Phase::Takeoff);
    }

    /// From an origin, airborne: no takeoff, leg 0 from where the vehicle is, the waypoints
    /// where the origin puts them (LegInfo in the caller's frame).
    #[test]
    fn airborne_start_from_an_origin() {
        let mut m = square();
        m.hold_s = 0.0;
        m.land_at_end = false;
        m.waypoints = vec![wp(10.0, 0.0, 5.0), wp(10.0, 10.0, 5.0)];
        let start = [3.0, -4.0, -6.0];
        let mut f = WaypointFollower::with_start(m, Some([0.0; 3]), true);
        let g = f.update(0.0, start, [0.0; 3]);
        assert_eq!(g.phase, Phase::Leg(0));
        assert_eq!(g.request, None);
        assert_eq!(
            g.leg,
            Some(LegInfo {
                from_ned_m: start,
                to_ned_m: [10.0, 0.0, -5.0]
            })
        );
        let recs = {
            let mut sim = Sim {
                pos: start,
                vel: [0.0; 3],
                ground_d: 0.0,
                tau: 0.3,
            };
            let mut t = 0.0;
            let mut last = g;
            while t < 120.0 && last.phase != Phase::Done {
                sim.step(&last, 0.05);
                t += 0.05;
                last = f.update(t, sim.pos, sim.vel);
            }
            (last, sim.pos)
        };
        assert_eq!(recs.0.phase, Phase::Done);
        assert!(norm(sub(recs.1, [10.0, 10.0, -5.0])) < 0.6, "{:?}", recs.1);
    }

    /// On the ground from an origin: takeoff above the first position, waypoints from the origin.
    #[test]
    fn ground_start_from_an_origin() {
        let mut f = WaypointFollower::with_start(square(), Some([1.0, 1.0, 0.0]), false);
        let g = f.update(0.0, [2.0, 2.0, 0.0], [0.0; 3]);
        assert_eq!(g.phase, Phase::Takeoff);
        assert_eq!(g.request, Some(Request::Arm));
        let w = square().waypoints[0].ned_m();
        assert_eq!(f.mission().waypoints[0].ned_m(), add(w, [-1.0, -1.0, 0.0]));
    }

    #[test]
    fn try_new_validates() {
        let mut m = square();
        m.speed_mps = -1.0;
        assert!(WaypointFollower::try_new(m).is_err());
        assert!(WaypointFollower::try_new(square()).is_ok());
    }
}
