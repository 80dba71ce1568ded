//! The end of a mission, as the mission node sequences it with the flight MCU's modes.
//!
//! When the [`WaypointFollower`](crate::WaypointFollower) asks to land after the last waypoint:
//! * `hover_s == 0`: land right away — send the MCU's land mode, re-sent every
//!   [`LAND_RESEND_S`] until the MCU reports it (commands travel best-effort);
//! * `hover_s > 0`: hover first (paper A Fig. 16: the flight core's hover test, HOLD at the
//!   current estimate) — send the MCU's hold mode and stop sending velocity setpoints (a fresh
//!   one would resume velocity mode); re-send hold every [`HOLD_RESEND_S`] until the MCU
//!   reports HOLD without a failsafe (a HOLD entered because the setpoints went stale is a
//!   failsafe that lands after a few seconds, not the hover asked for); after `hover_s` in HOLD
//!   (counted from the hold command the MCU acted on), land as above.
//!
//! The hover is abandoned for landing when the MCU leaves HOLD by itself (a failsafe, another
//! node) or does not confirm HOLD within [`HOLD_CONFIRM_TIMEOUT_S`]; it never re-sends hold
//! over an MCU that is landing.
//!
//! Pure logic, time passed in (seconds of ROS time: simulated time with `use_sim_time`), so
//! the node's wiring stays thin and the sequencing is unit-tested here.

/// Re-send the hold command after this long without the MCU in HOLD, s.
pub const HOLD_RESEND_S: f64 = 1.0;
/// Give up on the hover (and land) if the MCU has not confirmed HOLD after this long, s.
pub const HOLD_CONFIRM_TIMEOUT_S: f64 = 10.0;
/// Re-send the land command after this long without the MCU in land mode, s.
pub const LAND_RESEND_S: f64 = 0.5;

/// The MCU's flight mode as reported on `status`: the link's vocabulary (`fcc_msgs::vocab`:
/// `McuMode::from_code(Status.mode)`, `McuMode::from_name(Status.mode_name)`), not a mirror.
pub use fcc_msgs::FlightMode as McuMode;

/// A mode command for the MCU (`cmd/mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModeCommand {
    Hold,
    Land,
}

impl ModeCommand {
    /// The `cmd/mode` string.
    pub fn as_str(self) -> &'static str {
        match self {
            ModeCommand::Hold => "hold",
            ModeCommand::Land => "land",
        }
    }
}

/// Something worth a log line, emitted once when it happens.
#[derive(Debug, Clone, PartialEq)]
pub enum EndEvent {
    /// The mission is done; hovering `hover_s` in HOLD first.
    HoverRequested { hover_s: f64 },
    /// The MCU reports HOLD (commanded, no failsafe); `latency_s` after the first hold command.
    HoverConfirmed { latency_s: f64 },
    /// Hovered `hovered_s` in HOLD; landing.
    HoverDone { hovered_s: f64 },
    /// The MCU left HOLD during the hover (mode, failsafe active); landing. A warning.
    HoverInterrupted {
        mode: McuMode,
        failsafe: bool,
        hovered_s: f64,
    },
    /// The MCU did not confirm HOLD in time, or is landing already; landing. A warning.
    HoverAbandoned {
        mode: McuMode,
        failsafe: bool,
        waited_s: f64,
    },
    /// The mission is done; landing (no hover).
    Landing,
}

impl EndEvent {
    /// True for the events that deserve a warning.
    pub fn is_warning(&self) -> bool {
        matches!(
            self,
            EndEvent::HoverInterrupted { .. } | EndEvent::HoverAbandoned { .. }
        )
    }
}

impl std::fmt::Display for EndEvent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = |m: &McuMode, fs: &bool| {
            format!(
                "{}{}",
                format!("{m:?}").to_lowercase(),
                if *fs { " (failsafe)" } else { "" }
            )
        };
        match self {
            EndEvent::HoverRequested { hover_s } => {
                write!(f, "mission done, hovering {hover_s} s in HOLD (cmd/mode hold, no setpoints)")
            }
            EndEvent::HoverConfirmed { latency_s } => {
                write!(f, "MCU in HOLD ({:.0} ms after the first hold command)", latency_s * 1e3)
            }
            EndEvent::HoverDone { hovered_s } => {
                write!(f, "hovered {hovered_s:.1} s in HOLD, landing")
            }
            EndEvent::HoverInterrupted { mode, failsafe, hovered_s } => write!(
                f,
                "hover interrupted after {hovered_s:.1} s: the MCU left HOLD (mode {}), landing",
                m(mode, failsafe)
            ),
            EndEvent::HoverAbandoned { mode, failsafe, waited_s } => write!(
                f,
                "hover abandoned: the MCU is not in a commanded HOLD after {waited_s:.1} s (mode {}), landing",
                m(mode, failsafe)
            ),
            EndEvent::Landing => write!(f, "mission done, landing"),
        }
    }
}

/// The output of one [`EndSequence::update`].
#[derive(Debug, Clone, PartialEq)]
pub struct EndStep {
    /// Keep sending the follower's velocity setpoints (only while the mission runs).
    pub send_setpoints: bool,
    /// Publish this on `cmd/mode` now.
    pub command: Option<ModeCommand>,
    /// Log this.
    pub event: Option<EndEvent>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum State {
    Mission,
    /// Hold sent (first at `requested`, last at `sent`), not yet confirmed.
    HoldRequested {
        requested: f64,
        sent: f64,
    },
    /// The MCU holds since the hold command sent at `since`.
    Hovering {
        since: f64,
    },
    /// Land requested; last command sent at `sent`.
    Landing {
        sent: f64,
    },
}

/// Where the end of the mission stands, see the [module docs](self).
#[derive(Debug, Clone, PartialEq)]
pub enum EndPhase {
    /// The mission is running (setpoints flow).
    Mission,
    /// Hold requested or hovering in HOLD.
    Hover,
    /// Land requested.
    Landing,
}

/// Sequences the end of the mission: see the [module docs](self).
#[derive(Debug, Clone)]
pub struct EndSequence {
    hover_s: f64,
    state: State,
}

impl EndSequence {
    /// `hover_s`: seconds (of the caller's clock) in HOLD after the last waypoint; 0 = land
    /// right away. Negative or non-finite values are treated as 0 (validate before).
    pub fn new(hover_s: f64) -> Self {
        EndSequence {
            hover_s: if hover_s.is_finite() && hover_s > 0.0 {
                hover_s
            } else {
                0.0
            },
            state: State::Mission,
        }
    }

    /// The hover time asked for, s.
    pub fn hover_s(&self) -> f64 {
        self.hover_s
    }

    /// True once landing has been requested (the mission succeeds when the vehicle then
    /// disarms on the ground).
    pub fn land_requested(&self) -> bool {
        matches!(self.state, State::Landing { .. })
    }

    /// Where the sequence stands.
    pub fn phase(&self) -> EndPhase {
        match self.state {
            State::Mission => EndPhase::Mission,
            State::HoldRequested { .. } | State::Hovering { .. } => EndPhase::Hover,
            State::Landing { .. } => EndPhase::Landing,
        }
    }

    fn land(&mut self, t_s: f64, event: EndEvent) -> EndStep {
        self.state = State::Landing { sent: t_s };
        EndStep {
            send_setpoints: false,
            command: Some(ModeCommand::Land),
            event: Some(event),
        }
    }

    /// One step, at every cycle of the node.
    /// * `t_s`: now, s (ROS time; monotonic — a backward jump counts as no time elapsed);
    /// * `mission_done`: the follower asks to land (the last waypoint is done);
    /// * `mode`, `failsafe`: the MCU's latest status (mode; a failsafe cause is active).
    pub fn update(
        &mut self,
        t_s: f64,
        mission_done: bool,
        mode: McuMode,
        failsafe: bool,
    ) -> EndStep {
        let idle = EndStep {
            send_setpoints: false,
            command: None,
            event: None,
        };
        match self.state {
            State::Mission => {
                if !mission_done {
                    return EndStep {
                        send_setpoints: true,
                        ..idle
                    };
                }
                if self.hover_s > 0.0 {
                    self.state = State::HoldRequested {
                        requested: t_s,
                        sent: t_s,
                    };
                    EndStep {
                        command: Some(ModeCommand::Hold),
                        event: Some(EndEvent::HoverRequested {
                            hover_s: self.hover_s,
                        }),
                        ..idle
                    }
                } else {
                    self.land(t_s, EndEvent::Landing)
                }
            }
            State::HoldRequested { requested, sent } => {
                let waited = (t_s - requested).max(0.0);
                if mode == McuMode::Hold && !failsafe {
                    // The hover counts from the hold command the MCU acted on.
                    self.state = State::Hovering { since: sent };
                    return EndStep {
                        event: Some(EndEvent::HoverConfirmed { latency_s: waited }),
                        ..idle
                    };
                }
                if mode == McuMode::Land || waited >= HOLD_CONFIRM_TIMEOUT_S {
                    // Never fight an MCU that lands (a failsafe); never wait forever.
                    return self.land(
                        t_s,
                        EndEvent::HoverAbandoned {
                            mode,
                            failsafe,
                            waited_s: waited,
                        },
                    );
                }
                if t_s - sent >= HOLD_RESEND_S {
                    self.state = State::HoldRequested {
                        requested,
                        sent: t_s,
                    };
                    return EndStep {
                        command: Some(ModeCommand::Hold),
                        ..idle
                    };
                }
                idle
            }
            State::Hovering { since } => {
                let hovered = (t_s - since).max(0.0);
                if mode != McuMode::Hold {
                    return self.land(
                        t_s,
                        EndEvent::HoverInterrupted {
                            mode,
                            failsafe,
                            hovered_s: hovered,
                        },
                    );
                }
                if hovered >= self.hover_s {
                    return self.land(t_s, EndEvent::HoverDone { hovered_s: hovered });
                }
                idle
            }
            State::Landing { sent } => {
                if mode != McuMode::Land && t_s - sent >= LAND_RESEND_S {
                    self.state = State::Landing { sent: t_s };
                    return EndStep {
                        command: Some(ModeCommand::Land),
                        ..idle
                    };
                }
                idle
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use McuMode::*;

    /// Runs the sequence at `dt` from `t0` for `n` steps with the MCU's mode from `mcu(t)`;
    /// returns (t, step) for every step with a command or an event.
    fn run(
        s: &mut EndSequence,
        t0: f64,
        dt: f64,
        n: usize,
        done: bool,
        mcu: impl Fn(f64) -> (McuMode, bool),
    ) -> Vec<(f64, EndStep)> {
        let mut out = Vec::new();
        for k in 0..n {
            let t = t0 + k as f64 * dt;
            let (m, f) = mcu(t);
            let st = s.update(t, done, m, f);
            if st.command.is_some() || st.event.is_some() {
                out.push((t, st));
            }
        }
        out
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    #[test]
    fn mission_running_sends_setpoints_and_nothing_else() {
        let mut s = EndSequence::new(30.0);
        for k in 0..100 {
            let st = s.update(k as f64 * 0.02, false, Velocity, false);
            assert_eq!(
                st,
                EndStep {
                    send_setpoints: true,
                    command: None,
                    event: None
                }
            );
        }
        assert_eq!(s.phase(), EndPhase::Mission);
        assert!(!s.land_requested());
    }

    #[test]
    fn hover_zero_lands_right_after_the_last_waypoint_as_before() {
        for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let mut s = EndSequence::new(h);
            assert_eq!(s.hover_s(), 0.0);
            let st = s.update(10.0, true, Velocity, false);
            assert!(!st.send_setpoints);
            assert_eq!(st.command, Some(ModeCommand::Land));
            assert_eq!(st.event, Some(EndEvent::Landing));
            assert!(s.land_requested());
            // Re-sent every 0.5 s until the MCU reports land, then silence.
            let ev = run(&mut s, 10.02, 0.02, 100, true, |t| {
                (if t < 11.2 { Velocity } else { Land }, false)
            });
            let sends: Vec<f64> = ev.iter().map(|e| e.0).collect();
            assert_eq!(sends.len(), 2, "{sends:?}");
            assert!(close(sends[0], 10.5) && close(sends[1], 11.0), "{sends:?}");
            assert!(ev
                .iter()
                .all(|e| e.1.command == Some(ModeCommand::Land) && !e.1.send_setpoints));
        }
    }

    #[test]
    fn hover_holds_for_hover_s_of_the_given_clock_then_lands() {
        let mut s = EndSequence::new(30.0);
        // The mission runs until t = 100 s.
        for k in 0..50 {
            assert!(
                s.update(99.0 + k as f64 * 0.02, false, Velocity, false)
                    .send_setpoints
            );
        }
        let st = s.update(100.0, true, Velocity, false);
        assert_eq!(st.command, Some(ModeCommand::Hold));
        assert_eq!(st.event, Some(EndEvent::HoverRequested { hover_s: 30.0 }));
        assert!(!st.send_setpoints);
        assert_eq!(s.phase(), EndPhase::Hover);
        // The MCU reports HOLD 0.1 s later (status at 10 Hz); no setpoints from here on.
        let mcu = |t: f64| {
            if t < 100.1 - 1e-9 {
                (Velocity, false)
            } else if t < 130.05 {
                (Hold, false)
            } else {
                (Land, false)
            }
        };
        let mut events = Vec::new();
        let mut commands = Vec::new();
        for k in 1..3000 {
            let t = 100.0 + k as f64 * 0.02;
            let (m, f) = mcu(t);
            let st = s.update(t, true, m, f);
            assert!(!st.send_setpoints, "setpoint at {t}");
            if let Some(e) = st.event {
                events.push((t, e));
            }
            if let Some(c) = st.command {
                commands.push((t, c));
            }
        }
        assert_eq!(events.len(), 2, "{events:?}");
        assert!(
            matches!(events[0].1, EndEvent::HoverConfirmed { latency_s } if close(latency_s, 0.1))
        );
        // Land exactly hover_s after the hold command (first step at or past it).
        assert!(close(events[1].0, 130.0), "{events:?}");
        assert!(matches!(events[1].1, EndEvent::HoverDone { hovered_s } if close(hovered_s, 30.0)));
        // One land command: the MCU reports land 0.05 s later; no hold re-sent.
        assert_eq!(commands, vec![(events[1].0, ModeCommand::Land)]);
        assert!(s.land_requested());
    }

    #[test]
    fn hold_is_resent_each_second_until_confirmed_and_the_hover_counts_from_the_confirmed_one() {
        let mut s = EndSequence::new(20.0);
        assert_eq!(
            s.update(50.0, true, Velocity, false).command,
            Some(ModeCommand::Hold)
        );
        // First command lost: the setpoints went stale → the MCU holds as a failsafe (which
        // lands after a few seconds) — not the hover asked for; the third command takes.
        let ev = run(&mut s, 50.02, 0.02, 2000, true, |t| {
            if t < 50.3 {
                (Velocity, false)
            } else if t < 52.05 {
                (Hold, true)
            } else if t < 72.05 {
                (Hold, false)
            } else {
                (Land, false)
            }
        });
        let holds: Vec<f64> = ev
            .iter()
            .filter(|e| e.1.command == Some(ModeCommand::Hold))
            .map(|e| e.0)
            .collect();
        assert_eq!(holds.len(), 2, "{ev:?}");
        assert!(close(holds[0], 51.0) && close(holds[1], 52.0), "{holds:?}");
        let land: Vec<&(f64, EndStep)> = ev
            .iter()
            .filter(|e| e.1.command == Some(ModeCommand::Land))
            .collect();
        assert_eq!(land.len(), 1, "{ev:?}");
        // 20 s from the hold command sent at 52.0 s.
        assert!(close(land[0].0, 72.0), "{land:?}");
        assert!(matches!(land[0].1.event, Some(EndEvent::HoverDone { .. })));
    }

    #[test]
    fn hover_is_measured_in_the_callers_clock_not_in_steps() {
        // Sim time at 2× (the node steps every 10 ms of sim time) or with gaps: the same 30 s.
        for dt in [0.01, 0.04, 0.3] {
            let mut s = EndSequence::new(30.0);
            s.update(0.0, true, Velocity, false);
            let ev = run(&mut s, dt, dt, (40.0 / dt) as usize, true, |t| {
                (if t < 0.2 { Velocity } else { Hold }, false)
            });
            let land = ev
                .iter()
                .find(|e| e.1.command == Some(ModeCommand::Land))
                .expect("land");
            assert!(
                land.0 >= 30.0 - 1e-9 && land.0 < 30.0 + dt + 1e-9,
                "dt {dt}: {}",
                land.0
            );
        }
    }

    #[test]
    fn an_mcu_that_leaves_hold_ends_the_hover_and_is_never_fought() {
        // GPS lost during the hover: the MCU lands by itself → land (harmless), no hold re-sent.
        let mut s = EndSequence::new(30.0);
        s.update(0.0, true, Velocity, false);
        let ev = run(&mut s, 0.02, 0.02, 1000, true, |t| {
            if t < 0.1 {
                (Velocity, false)
            } else if t < 12.0 {
                (Hold, false)
            } else {
                (Land, true)
            }
        });
        assert!(
            ev.iter().all(|e| e.1.command != Some(ModeCommand::Hold)),
            "{ev:?}"
        );
        let i = ev
            .iter()
            .position(|e| matches!(e.1.event, Some(EndEvent::HoverInterrupted { .. })))
            .expect("interrupted");
        assert!(close(ev[i].0, 12.0));
        assert!(ev[i].1.event.as_ref().unwrap().is_warning());
        assert_eq!(ev[i].1.command, Some(ModeCommand::Land));
        assert_eq!(ev.len(), i + 1, "nothing after: the MCU is in land");

        // Landing before HOLD was ever confirmed: abandon at once, never send hold over it.
        let mut s = EndSequence::new(30.0);
        s.update(0.0, true, Velocity, false);
        let ev = run(&mut s, 0.02, 0.02, 500, true, |t| {
            (if t < 0.5 { Velocity } else { Land }, t >= 0.5)
        });
        assert!(
            ev.iter().all(|e| e.1.command != Some(ModeCommand::Hold)),
            "{ev:?}"
        );
        assert!(matches!(
            ev[0].1.event,
            Some(EndEvent::HoverAbandoned { mode: Land, .. })
        ));
        assert!(close(ev[0].0, 0.5));
    }

    #[test]
    fn no_confirmation_gives_up_and_lands() {
        let mut s = EndSequence::new(30.0);
        s.update(0.0, true, Velocity, false);
        let ev = run(&mut s, 0.05, 0.05, 400, true, |_| (Velocity, false));
        let holds = ev
            .iter()
            .filter(|e| e.1.command == Some(ModeCommand::Hold))
            .count();
        assert_eq!(holds, 9, "re-sent at 1..9 s: {ev:?}");
        let a = ev
            .iter()
            .find(|e| matches!(e.1.event, Some(EndEvent::HoverAbandoned { .. })))
            .expect("abandoned");
        assert!(close(a.0, HOLD_CONFIRM_TIMEOUT_S), "{}", a.0);
        assert_eq!(a.1.command, Some(ModeCommand::Land));
        assert!(s.land_requested());
    }

    #[test]
    fn clock_going_backwards_counts_as_no_time() {
        let mut s = EndSequence::new(5.0);
        s.update(10.0, true, Velocity, false);
        assert!(s.update(10.1, true, Hold, false).event.is_some()); // confirmed, since 10.0
                                                                    // A backward jump (e.g. a restarted /clock) neither ends the hover nor underflows.
        let st = s.update(3.0, true, Hold, false);
        assert_eq!(st.command, None);
        assert_eq!(s.phase(), EndPhase::Hover);
        assert_eq!(
            s.update(15.0, true, Hold, false).command,
            Some(ModeCommand::Land)
        );
    }

    #[test]
    fn mode_names_and_commands() {
        assert_eq!(McuMode::from_name("hold"), Some(Hold));
        assert_eq!(McuMode::from_name("land"), Some(Land));
        assert_eq!(McuMode::from_name("velocity"), Some(Velocity));
        assert_eq!(McuMode::from_name("disarmed"), Some(Disarmed));
        assert_eq!(McuMode::from_name("loiter"), None);
        assert_eq!(ModeCommand::Hold.as_str(), "hold");
        assert_eq!(ModeCommand::Land.as_str(), "land");
    }
}
